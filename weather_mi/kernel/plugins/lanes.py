"""Persistent lanes: a pass of path tracing as one kernel launch in which every lane, when its path ends,
takes the next sample from a shared atomic counter.

In a Dr.Jit LLVM kernel a SIMD packet loops until its longest path ends, and path lengths in cloud are
heavy-tailed, so a pass launches one LLVM block of lanes per thread and refills lanes as their paths end.
Each sample re-seeds its lane's PCG32 from (the pass's seed, the sample's number), so the image does not
depend on which lane ran which sample; each sample's radiance goes to its own slot, and the slots are
summed in sample order: deterministic. :func:`render_passes` renders several passes in one launch (a
launch still ends when its longest path ends). Measurements: ``docs/reference-estimator.md``.
"""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

from . import wavelengths

MAX_JOBS_PER_LAUNCH = 1 << 22  # persistent lanes: samples per kernel launch (12 bytes of radiance each)
CUDA_LANES = 1 << 20           # lanes of a launch off LLVM: a GPU wants ~10^5-10^6 threads in flight
STRATIFIED_WAVELENGTHS = True  # spectral: a pixel's samples in a pass stratified in wavelength (.wavelengths)

_JOB_SAMPLERS: dict = {}
_PCG_MULT = 0x5851F42D4C957F2D


def _splitmix64(x: int) -> int:
    """SplitMix64 of ``x``: a well-mixed 64-bit key for a pass seed."""
    z = (x + 0x9E3779B97F4A7C15) & 0xFFFFFFFFFFFFFFFF
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & 0xFFFFFFFFFFFFFFFF
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & 0xFFFFFFFFFFFFFFFF
    return z ^ (z >> 31)


def _seed_pcg(rng, initstate, initseq, active):
    """PCG32's seeding (``PCG32.seed``: stream ``initseq``, offset ``initstate``) in the lanes ``active``."""
    inc = (initseq << 1) | 1
    state = inc + initstate          # state = 0; step; state += initstate
    state = state * _PCG_MULT + inc  # step
    rng.state = dr.select(active, state, rng.state)
    rng.inc = dr.select(active, inc, rng.inc)


def job_sampler_class():
    """The sampler of the persistent lanes (one per variant): ``next_1d`` / ``next_2d`` from a PCG32 that
    is re-seeded for every sample (a Mitsuba sampler cannot be re-seeded per lane inside a kernel)."""
    key = mi.variant()
    if key not in _JOB_SAMPLERS:
        class JobSampler:
            DRJIT_STRUCT = {"rng": mi.PCG32}

            def __init__(self):
                self.rng = mi.PCG32()

            def next_1d(self, active=True):
                return self.rng.next_float32(mi.Bool(active))

            def next_2d(self, active=True):
                a = mi.Bool(active)
                u = self.rng.next_float32(a)
                return mi.Point2f(u, self.rng.next_float32(a))
        _JOB_SAMPLERS[key] = JobSampler
    return _JOB_SAMPLERS[key]


def default_lanes() -> int:
    """Lanes of a persistent-lane launch: one LLVM block per worker thread (each thread's first packet
    then takes samples until none are left), at least 64. Not critical: 512, 2048, 8192 and 32768 lanes
    took the same time (0.19-0.20 s per spp, demo side view, 160 x 120, two rounds). Persistent lanes are
    meant for LLVM (``passes._persistent`` never picks them elsewhere); called on another variant (a direct
    ``render_pass``) this reads no LLVM setting and gives CUDA_LANES, enough lanes to fill a GPU."""
    if not mi.variant().startswith("llvm"):
        return CUDA_LANES
    from ..jit_settings import llvm_block_size
    return max(64, int(dr.thread_count()) * int(llvm_block_size() or 1024))


def _film_pixels(film, pixels, name: str):
    """(width, height, the selected flat pixel indices (None: all), the same as a UInt32 array)."""
    width, height = (int(v) for v in film.crop_size())
    if any(int(v) != 0 for v in film.crop_offset()):
        raise ValueError(f"{name}: render_pass needs a film without a crop offset")
    n_all = width * height
    if pixels is None:
        return width, height, None, None
    pix = np.unique(np.asarray(pixels, np.int64).ravel())
    if pix.size == 0 or pix[0] < 0 or pix[-1] >= n_all:
        raise ValueError(f"{name}: pixels must be flat indices in [0, {n_all}), got {pix.size} "
                         f"indices in [{pix.min() if pix.size else 0}, {pix.max() if pix.size else 0}]")
    return width, height, pix, mi.UInt32(pix.astype(np.uint32))


class _Launch:
    """What the kernel of one launch reads: the film, the pixels, the layers (one sample of every
    selected pixel) of all passes in order: its pass's key (the PCG32 state; its high bits | the
    sample's number make the stream) and its sample number in the pass."""

    def __init__(self, sensor, medium, path_loop, width, height, pix_list, n_pix, layer_number, layer_key,
                 layer_inv_spp=None):
        self.sensor, self.medium, self.loop = sensor, medium, path_loop
        self.pix_list, self.layer_number, self.layer_key = pix_list, layer_number, layer_key
        self.layer_inv_spp = layer_inv_spp  # spectral: 1 / its pass's spp, for the stratified wavelengths
        self.size = [dr.opaque(mi.UInt32, v) for v in (width, height)]
        self.n_sel = dr.opaque(mi.UInt32, n_pix)
        self.n_all = dr.opaque(mi.UInt32, width * height)
        self.inv_size = mi.Point2f(dr.opaque(mi.Float, 1.0 / width), dr.opaque(mi.Float, 1.0 / height))

    def run(self, job_sampler, n_lanes: int, n: int, layer0: int) -> np.ndarray:
        """Samples [0, n) of the layers from ``layer0`` on, with ``n_lanes`` lanes: their radiance, (n, 3)."""
        sensor, medium, loop = self.sensor, self.medium, self.loop
        counter = dr.zeros(mi.UInt32, 1)
        slots = dr.zeros(mi.Float, 3 * n)
        n_jobs, first = dr.opaque(mi.UInt32, n), dr.opaque(mi.UInt32, layer0)
        sampler = job_sampler()
        sampler.rng = mi.PCG32(n_lanes)
        path = loop.initial(dr.zeros(mi.Ray3f, n_lanes), medium, dr.full(mi.Bool, False, n_lanes))
        start_state = (dr.full(mi.UInt32, 0xFFFFFFFF, n_lanes), dr.full(mi.Bool, True, n_lanes),
                       dr.zeros(mi.Spectrum, n_lanes), sampler, path)

        def pcond(job, alive, weight, sampler, path):
            return alive

        def pbody(job, alive, weight, sampler, path):
            sampler, path = loop.body(sampler, path)
            done = alive & ~path.active
            # the finished sample's radiance into its slot
            finished = done & (job < n_jobs)
            value = path.result * weight
            if mi.is_spectral:  # the sample's CIE XYZ, as the film adds it (a unit spectrum has Y = 1)
                value = mi.spectrum_to_xyz(value, path.ray.wavelengths, finished)
            for c in range(3):
                dr.scatter(slots, value[c], job * 3 + c, finished)
            # the next sample, from the shared counter
            nxt = dr.scatter_inc(counter, mi.UInt32(0), done)
            start = done & (nxt < n_jobs)
            job = dr.select(done, nxt, job)
            alive = (alive & path.active) | start
            # the sample's number in its pass: its layer there x all pixels + its pixel (a pass over
            # some pixels gives them the values of the pass over all)
            k = job % self.n_sel
            layer = first + job // self.n_sel
            pixel = k if self.pix_list is None else dr.gather(mi.UInt32, self.pix_list, k, start)
            number = dr.gather(mi.UInt32, self.layer_number, layer, start) * self.n_all + pixel
            key = dr.gather(mi.UInt64, self.layer_key, layer, start)
            _seed_pcg(sampler.rng, key, ((key >> 32) << 32) | mi.UInt64(number), start)
            pos = mi.Point2f(mi.Float(pixel % self.size[0]), mi.Float(pixel // self.size[0])) + sampler.next_2d(start)
            u_wavelength = sampler.next_1d(start)
            ray, ray_weight = sensor.sample_ray(sensor.shutter_open(), u_wavelength, pos * self.inv_size,
                                                mi.Point2f(0.5, 0.5), start)
            if mi.is_spectral:  # the path's wavelengths drawn for colour (.wavelengths), stratified in the pass
                if self.layer_inv_spp is not None:
                    inv_spp = dr.gather(mi.Float, self.layer_inv_spp, layer, start)
                    u_wavelength = wavelengths.stratified(key, pixel, dr.gather(mi.UInt32, self.layer_number, layer,
                                                                                 start), inv_spp)
                ray, ray_weight = wavelengths.redrawn(ray, ray_weight, u_wavelength, start)
            new = loop.initial(ray, medium, start)
            for name in type(path).DRJIT_STRUCT:  # the new samples' paths in the lanes that start one
                setattr(path, name, dr.select(start, getattr(new, name), getattr(path, name)))
            weight = dr.select(start, mi.Spectrum(ray_weight), weight)
            return job, alive, weight, sampler, path

        dr.while_loop(state=start_state, cond=pcond, body=pbody, label="majorant_volpath: persistent lanes")
        return slots.numpy().reshape(n, 3)


def render_passes(integrator, scene, passes, lanes: int | None = None, max_jobs: int = MAX_JOBS_PER_LAUNCH,
                  pixels=None, name: str = "majorant_volpath") -> list:
    """Passes of a path-tracing integrator rendered together with persistent lanes.

    Parameters
    ----------
    integrator
        An integrator with ``_path_loop(scene, medium)``: an object with ``initial(ray, medium, active)``
        (the path state, its ``active`` and ``result`` fields read here) and ``body(sampler, state)``
        (``majorant_volpath``).
    scene : mi.Scene
        Rendered through its first sensor (box filter: a pixel is the mean of the samples whose film
        position falls in it, as ``mi.render`` renders it).
    passes : list of (int, int)
        ``[(spp, seed), ...]``: samples per pixel and seed of each pass.
    lanes : int, optional
        Lanes per launch (default :func:`default_lanes`).
    max_jobs : int
        Samples per launch at most (a launch ends when its longest path ends).
    pixels : array of int, optional
        Flat pixel indices (row-major) to render; the others are 0. A sample is numbered by its layer and
        pixel in the whole film, so the selected pixels get the values of the pass over all.
    name : str
        Prefix of error messages.

    Returns
    -------
    list of numpy.ndarray
        One (H, W, 3) float32 image per pass, each as a pass rendered alone. Deterministic: a sample's
        random numbers depend on (its pass's seed, its number in the pass) only, and a pass's slots are
        summed layer by layer in order.
    """
    sensor = scene.sensors()[0]
    width, height, pix, pix_list = _film_pixels(sensor.film(), pixels, name)
    spps = [int(spp) for spp, _ in passes]
    if not spps or min(spps) < 1:
        raise ValueError(f"{name}: every pass needs spp >= 1, got {spps}")
    n_all = width * height
    n_pix = n_all if pix is None else int(pix.size)
    layer_pass = np.repeat(np.arange(len(spps)), spps)
    layer_number = mi.UInt32(np.concatenate([np.arange(n) for n in spps]).astype(np.uint32))
    layer_key = mi.UInt64(np.array([_splitmix64(int(seed)) for _, seed in passes], np.uint64)[layer_pass])
    medium = sensor.get_medium()
    inv_spp = mi.Float((1.0 / np.asarray(spps, np.float64))[layer_pass].astype(np.float32)) \
        if mi.is_spectral and STRATIFIED_WAVELENGTHS else None
    launch = _Launch(sensor, medium, integrator._path_loop(scene, medium), width, height, pix_list, n_pix,
                     layer_number, layer_key, inv_spp)
    job_sampler = job_sampler_class()
    lanes = int(lanes) if lanes is not None else default_lanes()
    total = len(layer_pass)
    layers = max(1, min(total, int(max_jobs) // n_pix))   # layers per launch
    acc = np.zeros((len(spps), n_pix, 3), np.float64)
    for layer0 in range(0, total, layers):
        n_layers = min(layers, total - layer0)
        n = n_layers * n_pix
        values = launch.run(job_sampler, max(1, min(lanes, n)), n, layer0).reshape(n_layers, n_pix, 3)
        for j in range(n_layers):  # layer by layer, in order: the sums do not depend on the launches
            acc[layer_pass[layer0 + j]] += values[j]
    images = []
    for a, spp in zip(acc, spps):
        out = np.zeros((n_all, 3), np.float32)
        out[slice(None) if pix is None else pix] = a / spp
        images.append(out.reshape(height, width, 3))
    return images
