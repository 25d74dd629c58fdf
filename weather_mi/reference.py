"""Ground truth: path-traced rendering of an OpticalVolume in Mitsuba 3, in passes, with a per-pixel
standard error, checkpoints after every pass and resume.

The estimate is the mean of P independent passes (consecutive seeds, k samples per pixel each); its
standard error is the sample standard deviation of the pass means over sqrt(P) (Welford updates).
A render to a target (``target_rse``) adds passes over its cloud pixels only, so there P is larger
than elsewhere. Passes rendered in this process share launches (``render_passes``); each keeps its
own seed and values, so the image does not depend on how they were grouped (nor on Dask).
"""
from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import WeatherDataError
from .forward_peak import DEFAULT_CONE_DEG, check_cone_deg, delta_scaled
from .imageio import Image
from .optics import OpticalVolume
from .scene import SceneSpec

INTEGRATORS = ("majorant", "volpath")
MAX_LANES_PER_PASS = 1 << 22
MIN_PASSES = 16          # default number of passes (batches) of a render with spp >= 16
CLOUD_TAU = np.log(2.0)  # cloud pixels: eye-ray transmittance below 1/2
MAX_TARGET_PASSES = 1 << 14
BATCH_SAMPLES = 1 << 20  # passes rendered together up to this many samples (render_passes; 0: one by one) ...
MAX_BATCH_PASSES = 16    # ... and this many passes
DEFAULT_AUREOLE_NEE = 0.0  # probability of the aureole estimator (majorant_volpath): 1.8x the time for a 1.5-2x lower RMS noise, off
DEFAULT_SUN_GUIDING = 0.0  # guiding adds noise on five of the six issue-10 views (plugins/majorant_volpath.py): off


def _check_inputs(spec: SceneSpec, vol: OpticalVolume, spp: int, normalize, integrator: str, variant):
    if not isinstance(spp, (int, np.integer)) or spp < 1:
        raise ValueError(f"spp must be a positive integer, got {spp!r}")
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator must be one of {INTEGRATORS}, got {integrator!r}")
    if normalize not in (None, "reflectance"):
        raise ValueError(f"normalize must be None or 'reflectance', got {normalize!r}")
    if normalize == "reflectance" and min(spec.sun.irradiance) <= 0:
        raise ValueError(f"normalize='reflectance' divides by the sun's irradiance: every channel must be > 0, "
                         f"got {spec.sun.irradiance}")
    if variant is not None:
        import mitsuba as mi
        if variant not in mi.variants():
            raise ValueError(f"unknown Mitsuba variant {variant!r}; expected one of {sorted(mi.variants())}")
        if integrator == "majorant" and variant.startswith("scalar"):
            raise ValueError(f"integrator 'majorant' (majorant_volpath) runs on JIT variants (llvm_ad_rgb, "
                             f"cuda_ad_rgb), not {variant!r}: use integrator='volpath' there")
    src = str(vol.attrs.get("source", "OpticalVolume"))
    for name in ("beta_total", "albedo", "weights"):
        a = getattr(vol, name)
        if not np.all(np.isfinite(a)):
            raise WeatherDataError(src, name, "finite values in the optical volume", "NaN or infinite values")
    if np.any(vol.beta_total < 0):
        raise WeatherDataError(src, "beta_total", "extinction >= 0 (1/m)")


def pass_seed(seed: int, i: int) -> int:
    """Mitsuba seed of pass ``i`` of a render with scene seed ``seed`` (distinct per pass and seed)."""
    return (int(seed) * 1_000_003 + int(i)) % (1 << 32)


def _passes(spec: SceneSpec, spp: int, passes: int | None) -> list[int]:
    """Samples per pixel of each pass: MIN_PASSES passes (batch means) when spp allows, so that the
    standard error estimated from their spread is itself stable (its relative error is about
    1 / sqrt(2 (P - 1)): 18% with 16 passes, 41% with 4), and at most MAX_LANES_PER_PASS paths per pass
    (memory)."""
    if passes is None:
        per = max(1, min(spp // MIN_PASSES, MAX_LANES_PER_PASS // (spec.width * spec.height)))
        passes = -(-spp // per)
    passes = max(1, min(int(passes), spp))
    base, extra = divmod(spp, passes)
    return [base + (1 if i < extra else 0) for i in range(passes)]


def integrator_dict(vol: OpticalVolume, integrator: str, max_depth: int, rr_depth: int | None = None,
                    cell: int | None = None, sun=None, sun_guiding: float = 0.0, legacy: bool = False,
                    aureole_nee: float = 0.0) -> dict:
    """Mitsuba integrator dict: stock ``volpath`` or ``majorant_volpath`` with a majorant grid of
    ``cell``^3 voxels per coarse cell (None: the plugin's ``DEFAULT_CELL``). ``rr_depth``: depth at which
    Russian roulette starts (None: the integrators' default, 5; a huge value turns it off). ``sun``: a
    ``Sun`` that ``majorant_volpath`` samples itself at every vertex (a disk with MIS, or a point), with
    ``sun_guiding`` (see ``render_reference``); None: the sun is a scene emitter."""
    if integrator == "volpath":
        d = {"type": "volpath", "max_depth": int(max_depth)}
    else:
        import mitsuba as mi
        from .plugins.hydrometeor_mixture import bbox_transform
        from .plugins.majorant_volpath import DEFAULT_CELL, majorant_grid
        from .variant import ensure_registered
        ensure_registered()
        cell = DEFAULT_CELL if cell is None else cell
        d = {"type": "majorant_volpath", "max_depth": int(max_depth), "cell": int(cell),
             "majorant": mi.TensorXf(majorant_grid(vol.beta_total, cell=int(cell))),
             "to_world": bbox_transform(vol.bbox)}
        if sun is not None:
            from .mitsuba_scene import integrator_sun
            d.update(integrator_sun(sun, sun_guiding, aureole_nee))
        if legacy:  # the estimator before issue 10 (see render_reference)
            d.update({"rr_mode": "volpath", "phase_channels": "mean", "emitter_nee": 1.0, "tracking_grid": "coarse",
                      "transmittance": "ratio", "persistent_lanes": False})
    if rr_depth is not None:
        d["rr_depth"] = int(rr_depth)
    return d


@dataclass(frozen=True)
class PassScene:
    """What a pass renders: the scene, the volume and the estimator options of a ``render_reference`` call
    (``key``: its fingerprint). Built into a Mitsuba scene in the current variant by ``build``, here or in
    a Dask worker (the same scene, hence the same pass images)."""

    spec: SceneSpec
    vol: OpticalVolume
    options: dict
    key: str

    def pixels_of(self, i: int):
        """The pixels (flat indices) pass ``i`` renders: None (all) for the planned passes, the cloud
        pixels for the passes a render to a target adds (``options["target_pixels"]``)."""
        pixels = self.options.get("target_pixels")
        if pixels is None:
            return None
        return None if i < self.options["planned"] else pixels

    def build(self):
        import mitsuba as mi
        from .mitsuba_scene import recentred, scene_dict
        o = self.options
        spec_k, vol_k, _ = recentred(self.spec, self.vol)  # kernel-side coordinates: bbox centred on the origin
        vol_render = delta_scaled(vol_k, o["forward_peak_deg"])
        integ = integrator_dict(vol_render, o["integrator"], o["max_depth"], o["rr_depth"], o["cell"],
                                sun=self.spec.sun if o["own_sun"] else None, sun_guiding=o["sun_guiding"],
                                aureole_nee=o["aureole_nee"], legacy=o["legacy"] and o["integrator"] == "majorant")
        return mi.load_dict(scene_dict(spec_k, vol_render, integ))


def _persistent(scene, persistent: bool | None) -> bool:
    """Whether passes of ``scene`` run with persistent lanes: as asked, or (None) wherever they apply:
    ``majorant_volpath`` on an LLVM variant, unless its ``persistent_lanes`` is false."""
    import mitsuba as mi
    if persistent is not None:
        return persistent
    integrator = scene.integrator()
    return (mi.variant().startswith("llvm") and hasattr(integrator, "render_passes")
            and getattr(integrator, "persistent", False))


def render_pass(scene, spp: int, seed: int, persistent: bool | None = None, pixels=None) -> np.ndarray:
    """One pass of ``spp`` samples per pixel with seed ``seed``: the film's (H, W, C) float32 array.

    ``persistent`` (None: wherever it applies): ``majorant_volpath`` on an LLVM variant renders the pass
    with persistent lanes (its ``render_pass``), otherwise ``mi.render``. Both estimate the same image;
    their random numbers differ. ``pixels`` (flat indices, row-major): with persistent lanes only these
    pixels are rendered (the others are 0), with the values they have in the pass over every pixel;
    ``mi.render`` renders every pixel anyway."""
    import mitsuba as mi
    if _persistent(scene, persistent):
        return scene.integrator().render_pass(scene, int(spp), int(seed), pixels=pixels)
    return np.array(mi.render(scene, spp=int(spp), seed=int(seed)), dtype=np.float32)


def render_passes(scene, passes, persistent: bool | None = None, pixels=None) -> list:
    """Several passes ``[(spp, seed), ...]``: as ``render_pass`` renders each (one pass: through it), but
    with persistent lanes in shared launches (``majorant_volpath.render_passes``: one tail of long paths
    per launch instead of one per pass)."""
    if len(passes) > 1 and _persistent(scene, persistent):
        return scene.integrator().render_passes(scene, [(int(spp), int(seed)) for spp, seed in passes],
                                                pixels=pixels)
    return [render_pass(scene, spp, seed, persistent=persistent, pixels=pixels) for spp, seed in passes]


def pass_stderr(m2: np.ndarray, n) -> np.ndarray:
    """Standard error of the mean over ``n`` passes from Welford's M2 (NaN below two passes); ``n`` a
    number or per-pixel counts that broadcast against ``m2``."""
    n = np.asarray(n, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(n > 1, np.sqrt(m2 / np.maximum(n - 1, 1) / n), np.nan)


def welford_update(mean: np.ndarray, m2: np.ndarray, img: np.ndarray, n: int, where=None) -> None:
    """Add pass ``n`` (1-based) of image ``img`` to the per-pixel running mean and M2 (in place); with
    ``where`` (a boolean (H, W) mask) only to those pixels, for which it is their pass ``n``."""
    if where is not None:
        sub_mean, sub_m2 = mean[where], m2[where]
        welford_update(sub_mean, sub_m2, img[where], n)
        mean[where], m2[where] = sub_mean, sub_m2
        return
    delta = img - mean
    mean += delta / n
    m2 += delta * (img - mean)


def pass_counts(n: int, planned: int, target: np.ndarray | None) -> np.ndarray:
    """(H, W, 1) passes per pixel after ``n`` passes of a render whose passes past the ``planned`` ones
    cover only the ``target`` pixels (render to a target: its cloud pixels), or (1, 1, 1) of n."""
    if target is None or n <= planned:
        return np.full((1, 1, 1), n)
    return np.where(target, n, planned)[..., None]


def _local_passes(scene, seed: int, per_pass, more, start: int, pixels_of=lambda i: None,
                  n_pixels: int = 1, planned: int | None = None, limit: int | None = None):
    """Passes rendered in this process: (index, image, seconds) while ``more(index)``; pass i renders
    the pixels ``pixels_of(i)`` (None: all ``n_pixels``). Consecutive passes over the same pixels are
    rendered together (``render_passes``), up to BATCH_SAMPLES samples, MAX_BATCH_PASSES passes, the end of
    the ``planned`` ones and ``limit`` (no pass from there on is wanted); ``more`` is asked for each pass after the previous one was handed over, so the passes handed
    over do not depend on the batches (a render to a target may render up to a batch it then drops).
    A pass's seconds: its batch's over its size."""
    i = start
    while more(i):
        pix = pixels_of(i)
        per_sample = max(1, n_pixels if pix is None else len(pix))
        batch, samples = [i], per_pass(i) * per_sample
        while (len(batch) < MAX_BATCH_PASSES and samples < BATCH_SAMPLES
               and (planned is None or (batch[-1] + 1 < planned) == (i < planned))
               and (limit is None or batch[-1] + 1 < limit)):
            batch.append(batch[-1] + 1)
            samples += per_pass(batch[-1]) * per_sample
        t0 = time.perf_counter()
        images = render_passes(scene, [(per_pass(j), pass_seed(seed, j)) for j in batch], pixels=pix)
        dt = (time.perf_counter() - t0) / len(batch)
        for j, raw in zip(batch, images):
            if j > i and not more(j):
                return
            yield j, raw, dt
        i = batch[-1] + 1


def _fingerprint(spec: SceneSpec, vol: OpticalVolume, spp_list, *options) -> str:
    h = hashlib.sha256()
    h.update(json.dumps([spec.to_dict(), spp_list, *options], sort_keys=True, default=str).encode())
    for a in (vol.beta_total, vol.albedo, vol.weights):
        h.update(np.ascontiguousarray(a).tobytes())
    for t in vol.require_phase_tables():  # the phase functions are part of the scene too
        h.update(np.ascontiguousarray(t.theta, np.float64).tobytes())
        h.update(np.ascontiguousarray(t.values, np.float64).tobytes())
    h.update(json.dumps([list(map(float, p)) for p in vol.bbox]).encode())
    return h.hexdigest()


def _save_checkpoint(path: Path, state: dict) -> None:
    from .output_paths import written_atomically
    path.parent.mkdir(parents=True, exist_ok=True)
    with written_atomically(path) as tmp:
        np.savez(tmp, **state)


def _load_checkpoint(path: Path, key: str, spp_list) -> tuple:
    """(mean, m2, passes done, seconds, spp done) from a checkpoint of this render (``key``); ValueError
    naming the file when it is unreadable or belongs to another render."""
    import zipfile
    try:
        with np.load(path) as state:
            stored = str(state["key"])
            if stored == key:
                done = int(state["done"])
                spp_done = int(state["spp_done"]) if "spp_done" in state else sum(spp_list[:done])
                return state["mean"], state["m2"], done, float(state["seconds"]), spp_done
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        raise ValueError(f"checkpoint {path} cannot be read ({type(exc).__name__}: {exc}); delete it to "
                         "render afresh (without resume / --resume)") from exc
    raise ValueError(f"checkpoint {path} belongs to a different scene, volume or sample plan")


def _keep_aside(path: Path) -> None:
    """A checkpoint found where a fresh render will write its own: renamed to <stem>.previous.npz, with a
    warning (it is never discarded silently)."""
    import warnings
    aside = path.with_name(f"{path.name[:-len('.npz')] if path.name.endswith('.npz') else path.name}.previous.npz")
    os.replace(path, aside)
    warnings.warn(f"checkpoint {path} exists and resume was not asked for: kept aside as {aside} (pass "
                  "resume=True to continue a render from a checkpoint)", UserWarning, stacklevel=3)


def noise_stats(radiance: np.ndarray, stderr: np.ndarray, cloud: np.ndarray) -> dict:
    """How converged an image is over its cloud pixels (``cloud``: a boolean (H, W) mask), from the
    channel means of radiance and standard error:

    rse_mean        mean over cloud pixels of se / radiance (``Image.relative_stderr``)
    rms_se_over_mean  RMS of se over cloud pixels / mean cloud radiance
    worst_se_over_mean  largest se of a cloud pixel / mean cloud radiance
    cloud_pixels    number of cloud pixels"""
    lum = np.asarray(radiance, np.float64).mean(axis=2)
    se = np.asarray(stderr, np.float64).mean(axis=2)
    ok = np.asarray(cloud, bool) & (lum > 0) & np.isfinite(se)
    if not np.any(ok):
        return {"cloud_pixels": 0, "rse_mean": float("nan"), "rms_se_over_mean": float("nan"),
                "worst_se_over_mean": float("nan")}
    m = float(lum[ok].mean())
    return {"cloud_pixels": int(ok.sum()), "rse_mean": float(np.mean(se[ok] / lum[ok])),
            "rms_se_over_mean": float(np.sqrt(np.mean(se[ok] ** 2)) / m),
            "worst_se_over_mean": float(se[ok].max() / m)}


def cloud_mask(spec: SceneSpec, vol: OpticalVolume) -> np.ndarray:
    """Cloud pixels (H, W) of a view: eye-ray optical depth > ln 2 (transmittance below 1/2), as the
    noise figures of ``render_reference`` count them (deterministic, no rendering)."""
    import mitsuba as mi
    from .mitsuba_scene import recentred, sensor_dict
    from .variant import set_variant
    set_variant(_current_or_default())
    spec_k, vol_k, _ = recentred(spec, vol)
    return eye_optical_depth(mi.load_dict(sensor_dict(spec_k)), vol_k, spec_k) > CLOUD_TAU


def eye_optical_depth(sensor, vol_k: OpticalVolume, spec: SceneSpec, steps: int = 512) -> np.ndarray:
    """Optical depth (H, W) of the medium along each pixel's central camera ray, by the midpoint rule
    over ``steps`` steps of the ray's segment in the volume's box (deterministic; the scene's own
    ``sensor``, so the same rays as the render). ``vol_k``: the volume in the sensor's coordinates."""
    import drjit as dr
    import mitsuba as mi
    from .jitarrays import aligned_float
    h, w = spec.height, spec.width
    jj, ii = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    pos = mi.Point2f(aligned_float(mi, ((ii + 0.5) / w).ravel()), aligned_float(mi, ((jj + 0.5) / h).ravel()))
    ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
    lo, hi = (np.asarray(p, np.float64) for p in vol_k.bbox)
    ext = hi - lo
    o = [(ray.o[k] - float(lo[k])) / float(ext[k]) for k in range(3)]
    d = [ray.d[k] / float(ext[k]) for k in range(3)]
    t0, t1 = mi.Float(0.0), mi.Float(dr.inf)
    for k in range(3):
        inv = dr.rcp(dr.select(dr.abs(d[k]) < 1e-30, 1e-30, d[k]))
        ta, tb = -o[k] * inv, (1.0 - o[k]) * inv
        t0, t1 = dr.maximum(t0, dr.minimum(ta, tb)), dr.minimum(t1, dr.maximum(ta, tb))
    seg = dr.maximum(t1 - t0, 0.0)
    tex = mi.Texture3f(mi.TensorXf(np.ascontiguousarray(vol_k.beta_total, np.float32)[..., None]),
                       wrap_mode=dr.WrapMode.Clamp)
    n_steps = dr.opaque(mi.UInt32, steps)

    def body(i, tau):  # one small symbolic loop: an unrolled march compiles for a minute
        t = t0 + seg * ((mi.Float(i) + 0.5) / mi.Float(n_steps))
        tau += tex.eval(mi.Point3f(*(o[k] + d[k] * t for k in range(3))))[0]
        return i + 1, tau

    _, tau = dr.while_loop(state=(mi.UInt32(0), dr.zeros(mi.Float, h * w)), cond=lambda i, tau: i < n_steps,
                           body=body, label="eye optical depth")
    return np.asarray(tau * seg / steps, np.float64).reshape(h, w)


def render_reference(spec: SceneSpec, vol: OpticalVolume, spp: int = 256, max_depth: int = -1, *,
                     integrator: str = "majorant", passes: int | None = None, normalize: str | None = None,
                     checkpoint=None, resume=None, progress: bool = True, variant: str | None = None,
                     rr_depth: int | None = None, cell: int | None = None, target_rse: float | None = None,
                     max_seconds: float | None = None, sun_guiding: float | None = None,
                     forward_peak_deg: float | None = None, aureole_nee: float | None = None,
                     legacy: bool = False, client=None, worker_variant=None, on_pass=None) -> Image:
    """Path-trace ``vol`` as seen by ``spec`` (Mitsuba ``volpath`` or our local-majorant tracker).

    spp        : samples per pixel in total, split into passes (``passes``, default MIN_PASSES = 16
                 batches when spp >= 16). With ``target_rse``: the samples of the first estimate; passes of
                 the same size are then added until the target is met.
    integrator : "majorant" (delta tracking over a coarse majorant grid; default) or "volpath"
                 (Mitsuba's own, one global majorant: the reference's reference; point sun only).
    normalize  : None (radiance) or "reflectance" (pi L / (mu0 E) per channel).
    rr_depth   : depth at which Russian roulette starts (None: the integrators' default, 5).
    cell       : fine voxels per coarse cell of the majorant grid ("majorant" only; None: the default).
    target_rse : keep adding passes until the mean relative standard error over cloud pixels (eye-ray
                 transmittance < 1/2) is at most this, or ``max_seconds`` of rendering have passed. The
                 added passes render the cloud pixels only (with persistent lanes; ``mi.render`` renders
                 every pixel and the others' values are dropped): the other pixels keep the planned passes
                 (metadata ``spp_background``). On the side-lit supercell at 256 x 256 its 6% of cloud
                 pixels take 60% of a full pass's time.
    sun_guiding: probability of drawing a scattering direction from the phase function centred on the
                 sun ("majorant" only; None: DEFAULT_SUN_GUIDING).
    forward_peak_deg : scattering by less than this many degrees (the diffraction peaks of rain, snow
                 and graupel) counted as unscattered light, delta-M scaling (``weather_mi.forward_peak``;
                 None: DEFAULT_CONE_DEG = 3 deg, 0 with ``legacy``; 0: the tables as they are, which
                 reads low at practical spp, see ``validation/forward_peak_slabs.py``).
    aureole_nee: probability of the aureole estimator at a scattering vertex ("majorant" only; sun light
                 through one more, forward, scattering sampled about the sun; None: DEFAULT_AUREOLE_NEE,
                 0 where sun guiding is asked for: the two are exclusive).
    legacy     : the estimator before issue 10, for benchmarks: the sun one of the scene's emitters
                 (point sun only), Russian roulette as Mitsuba's volpath, phase sampling by channel mean.
    checkpoint : a .npz path written after every pass; ``resume`` (a path, or True to use
                 ``checkpoint``) continues a render from it; the scene must be identical.
    client     : None (render in this process), a ``dask.distributed.Client`` or a scheduler address
                 ("tcp://host:8786"): the passes become Dask tasks (``weather_mi.dask_passes``), merged here
                 in pass order, so the image is bit-identical to the in-process one.
    worker_variant : with ``client``: the Mitsuba variant of the workers (None: this process's; "auto": each
                 worker's default, cuda_ad_rgb where it has a GPU; a name; or {worker address: name}).
    on_pass    : None, or a callable invoked after every merged pass (after its checkpoint is written)
                 with an ``Image`` of the estimate so far: mean radiance and standard error (float32; NaN
                 while fewer than 2 passes), and the metadata of the final image for the passes so far
                 (``passes``, ``spp``, ``seconds``, ``noise``: ``noise_stats`` over the cloud pixels or
                 None while fewer than 2 passes, ``target_rse``, ...). The arrays are the callback's own
                 copies. An exception it raises propagates out of ``render_reference`` (queued Dask passes
                 are cancelled and the checkpoint stays valid, as with Ctrl-C): a way to stop a render.

    The metadata records ``noise_stats`` over the cloud pixels (also shown by the progress bar).
    """
    from .variant import set_variant
    _check_inputs(spec, vol, spp, normalize, integrator, variant)
    sun_guiding = DEFAULT_SUN_GUIDING if sun_guiding is None else sun_guiding
    if aureole_nee is None:  # the two are exclusive: sun guiding given, no aureole estimator
        aureole_nee = DEFAULT_AUREOLE_NEE if sun_guiding == 0 and not legacy else 0.0
    _check_sun_options(spec, integrator, target_rse, max_seconds, sun_guiding, legacy)
    forward_peak_deg = check_cone_deg((0.0 if legacy else DEFAULT_CONE_DEG) if forward_peak_deg is None
                                      else forward_peak_deg)
    set_variant(variant) if variant is not None else set_variant(_current_or_default())

    from .variant import path_tracing_width
    with path_tracing_width():  # the scene is built and its passes rendered at the path tracer's SIMD width
        import mitsuba as mi
        from tqdm.auto import tqdm

        spp_list = _passes(spec, int(spp), passes)
        own_sun = integrator == "majorant" and not legacy
        options = [integrator, max_depth, normalize, mi.variant(), rr_depth]
        if forward_peak_deg > 0:
            options.append(["forward peak", forward_peak_deg])
        if own_sun:
            options.append(["integrator sun", sun_guiding] + ([aureole_nee] if aureole_nee else []))
        if client is not None and worker_variant is not None:  # other variants: the same image within noise only
            options.append(["worker variant", worker_variant])
        plan = ["target", spp_list[0], "cloud passes"] if target_rse is not None else spp_list
        key = _fingerprint(spec, vol, plan, *options)  # cell: speed only
        ckpt = Path(checkpoint) if checkpoint is not None else None
        resume_path = ckpt if resume is True else (Path(resume) if resume else None)
        h, w = spec.height, spec.width
        mean = np.zeros((h, w, 3))
        m2 = np.zeros((h, w, 3))
        done, seconds, spp_done = 0, 0.0, 0
        if resume_path is not None and resume_path.is_file():
            mean, m2, done, seconds, spp_done = _load_checkpoint(resume_path, key, spp_list)
            ckpt = ckpt or resume_path
        elif resume_path is None and ckpt is not None and ckpt.is_file():
            _keep_aside(ckpt)

        if mi.variant().startswith("scalar"):  # the ray march is vectorised: every pixel counts there
            cloud = np.ones((spec.height, spec.width), bool)
        else:  # the full extinction (not delta-scaled), the scene's sensor
            cloud = cloud_mask(spec, vol)
        planned = len(spp_list)
        # render to a target: the passes past the planned ones cover the cloud pixels only
        target = cloud if target_rse is not None else None
        job = PassScene(spec, vol, dict(integrator=integrator, max_depth=max_depth, rr_depth=rr_depth, cell=cell,
                                        own_sun=own_sun, sun_guiding=sun_guiding, aureole_nee=aureole_nee,
                                        legacy=legacy, forward_peak_deg=forward_peak_deg,
                                        target_pixels=None if target is None else np.flatnonzero(target.ravel()),
                                        planned=planned), key)
        scene = job.build() if client is None else None
        scale = 1.0
        if normalize == "reflectance":
            scale = np.pi / (spec.sun.mu0 * np.asarray(spec.sun.irradiance))

        def stats(n):
            if n < 2:
                return None
            return noise_stats(mean, pass_stderr(m2, pass_counts(n, planned, target)), cloud)

        def more(i):
            if target_rse is None:
                return i < len(spp_list)
            if i < planned:
                return True
            if not cloud.any():  # no cloud pixel in view: nothing to converge
                return False
            st = stats(i)
            if st is not None and st["cloud_pixels"] and st["rse_mean"] <= target_rse:
                return False
            return i < MAX_TARGET_PASSES and (max_seconds is None or seconds < max_seconds)

        def per_pass(i):
            return spp_list[i] if i < len(spp_list) else spp_list[0]

        def metadata(n, spp_done, seconds, noise):
            background = sum(spp_list[:min(n, planned)]) if target is not None else spp_done
            return {"renderer": "reference", "integrator": integrator, "variant": mi.variant(), "spp": int(spp_done),
                    "spp_background": int(background),
                    "passes": n, "max_depth": int(max_depth), "rr_depth": rr_depth, "seconds": seconds,
                    "normalize": normalize, "scene": spec.to_dict(), "species_preset": vol.attrs.get("species_preset"),
                    "source": vol.attrs.get("source"), "time": vol.attrs.get("time"),
                    "phase_mode": vol.phase_mode, "sun": ("scene emitter" if not own_sun else
                                                          ("disk" if spec.sun.angular_diameter_deg > 0 else "point")),
                    "sun_guiding": sun_guiding if own_sun else None, "target_rse": target_rse,
                    "forward_peak_deg": forward_peak_deg, "aureole_nee": aureole_nee if own_sun else None,
                    "noise": noise}

        total = len(spp_list) if target_rse is None else None
        bar = tqdm(total=total, initial=done, desc="reference", unit="pass", disable=not progress)
        if client is None:
            passes_in = _local_passes(scene, spec.seed, per_pass, more, done, job.pixels_of,
                                      n_pixels=spec.width * spec.height, planned=planned,
                                      limit=planned if target_rse is None else MAX_TARGET_PASSES)
        else:
            from .dask_passes import RemotePasses
            remote = RemotePasses(client, job, per_pass, more, done, len(spp_list), target_rse is not None,
                                  worker_variant=worker_variant)
            passes_in = iter(remote)
        i = done
        try:
            for i, raw, dt in passes_in:  # pass i's image, in pass order; dt: its seconds (wall-clock over Dask)
                per = per_pass(i)
                img = raw.astype(np.float64)[..., :3] * scale
                seconds += dt
                n = i + 1
                welford_update(mean, m2, img, n, where=None if i < planned else target)
                spp_done += per
                i = n
                if ckpt is not None:
                    _save_checkpoint(ckpt, {"key": key, "mean": mean, "m2": m2, "done": n, "seconds": seconds,
                                            "spp_done": spp_done})
                bar.update(1)
                # noise over the cloud pixels: for the progress bar and on_pass only
                st = stats(n) if progress or on_pass is not None else None
                if progress and st is not None:
                    bar.set_postfix_str(f"cloud RSE {st['rse_mean']:.3f} worst se/mean {st['worst_se_over_mean']:.2f}")
                if on_pass is not None:
                    on_pass(Image(mean.astype(np.float32), pass_stderr(m2, pass_counts(n, planned, target)).astype(np.float32),
                                  metadata(n, spp_done, seconds, st)))
        finally:  # over Dask: cancels the passes still queued (target met, Ctrl-C, error); the checkpoint stays valid
            passes_in.close()
            bar.close()
        n = i
        stderr = pass_stderr(m2, pass_counts(n, planned, target))
        meta = metadata(n, spp_done, seconds, noise_stats(mean, stderr, cloud) if n > 1 else None)
        if client is not None:
            meta["dask"] = remote.summary
        return Image(mean.astype(np.float32), stderr.astype(np.float32), meta)



def _check_sun_options(spec, integrator, target_rse, max_seconds, sun_guiding, legacy):
    disk = spec.sun.angular_diameter_deg > 0
    if disk and (integrator == "volpath" or legacy):
        what = "integrator='volpath'" if integrator == "volpath" else "legacy=True"
        raise ValueError(f"{what} renders the sun as a point (Mitsuba's 'directional' emitter): give "
                         f"Sun(..., angular_diameter_deg=0), or use integrator='majorant' for a sun disk "
                         f"of {spec.sun.angular_diameter_deg} deg")
    if target_rse is not None and not (isinstance(target_rse, (int, float)) and 0 < target_rse < 1):
        raise ValueError(f"target_rse must be a relative standard error in (0, 1), got {target_rse!r}")
    if max_seconds is not None and not (isinstance(max_seconds, (int, float)) and max_seconds > 0):
        raise ValueError(f"max_seconds must be a positive number of seconds, got {max_seconds!r}")
    if not (isinstance(sun_guiding, (int, float)) and 0.0 <= sun_guiding < 1.0):
        raise ValueError(f"sun_guiding must be a probability in [0, 1), got {sun_guiding!r}")


def render_transmittance(spec: SceneSpec, vol: OpticalVolume, spp: int = 32, **kw) -> np.ndarray:
    """Eye-ray transmittance (H, W) through ``vol`` from the path tracer: the volume made purely
    absorbing, seen against a uniform sky of radiance 1 with no sun light and no ground, so that the
    rendered radiance is the transmittance (unbiased delta-tracking estimate, ``spp`` samples)."""
    from dataclasses import replace
    from .scene import Sky, Sun
    absorbing = replace(vol, albedo=np.zeros_like(vol.albedo))
    t_spec = replace(spec, sun=Sun(spec.sun.azimuth, spec.sun.elevation, irradiance=0.0, angular_diameter_deg=0.0),
                     sky=Sky("constant", radiance=1.0), ground=None)
    kw.setdefault("progress", False)
    return render_reference(t_spec, absorbing, spp=spp, **kw).radiance.mean(axis=2)


def _current_or_default() -> str:
    import mitsuba as mi
    from .variant import default_variant
    return mi.variant() or default_variant()
