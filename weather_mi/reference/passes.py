"""The passes of a reference render: their seeds and sample plan, the estimator options they share
(``PassOptions``), the scene they render (``PassScene``, built here or in a Dask worker) and the
rendering of one pass or several in shared launches, in this process.

A pass is ``spp`` samples per pixel with its own Mitsuba seed (``pass_seed``); a render's image is the
mean of its passes (``weather_mi.reference.estimates``), merged in pass order by ``render_reference``.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..optics.forward_peak import delta_scaled
from ..kernel.scene_dict import integrator_dict, recentred, scene_dict
from ..optics.volume import OpticalVolume
from ..scene.spec import SceneSpec

MAX_LANES_PER_PASS = 1 << 22
MIN_PASSES = 16          # default number of passes (batches) of a render with spp >= 16
BATCH_SAMPLES = 1 << 20  # passes rendered together up to this many samples (render_passes; 0: one by one) ...
MAX_BATCH_PASSES = 16    # ... and this many passes
# probability of the aureole estimator (majorant_volpath): 1.8x the time for a 1.5-2x lower RMS noise, off
DEFAULT_AUREOLE_NEE = 0.0
# probability of a multiple-vertex NEE chain (weather_mi/kernel/plugins/mvnee.py): 1.6-1.8x the CPU time for a 1.25-1.6x lower
# variance, 0.7-1.0x the efficiency on the six demo views (docs/reference-estimator.md): off
DEFAULT_MVNEE = 0.0
DEFAULT_SUN_GUIDING = 0.0  # guiding adds noise on five of the six issue-10 views (weather_mi/kernel/plugins/majorant_volpath.py): off


def pass_seed(seed: int, i: int) -> int:
    """Mitsuba seed of pass ``i`` of a render with scene seed ``seed`` (distinct per pass and seed)."""
    return (int(seed) * 1_000_003 + int(i)) % (1 << 32)


def plan_passes(spec: SceneSpec, spp: int, passes: int | None) -> list[int]:
    """Samples per pixel of each pass: MIN_PASSES passes (batch means) when spp allows, so that the
    standard error estimated from their spread is itself stable (its relative error is about
    1 / sqrt(2 (P - 1)): 18% with 16 passes, 41% with 4), and at most MAX_LANES_PER_PASS paths per pass
    (memory).

    Parameters
    ----------
    spec : SceneSpec
        The view (its width x height pixels).
    spp : int
        Samples per pixel in total.
    passes : int or None
        Number of passes asked for (at most ``spp``); None: as above.

    Returns
    -------
    list of int
        Samples per pixel of each pass, summing to ``spp``.
    """
    if passes is None:
        per = max(1, min(spp // MIN_PASSES, MAX_LANES_PER_PASS // (spec.width * spec.height)))
        passes = -(-spp // per)
    passes = max(1, min(int(passes), spp))
    base, extra = divmod(spp, passes)
    return [base + (1 if i < extra else 0) for i in range(passes)]


def current_or_default_variant() -> str:
    """The Mitsuba variant selected in this process, or the default one (``variant.default_variant``)."""
    import mitsuba as mi
    from ..kernel.variant import default_variant
    return mi.variant() or default_variant()


@dataclass(frozen=True)
class PassOptions:
    """The estimator options every pass of a ``render_reference`` call shares.

    Attributes
    ----------
    estimator : ReferenceOptions
        The call's estimator options, resolved (``ReferenceOptions.resolved``: no None left where
        ``render_reference`` has a default); ``PassScene.build`` hands the kernel's to ``integrator_dict``.
    planned : int
        Number of planned passes (over every pixel).
    target_pixels : ndarray of int or None
        Flat (row-major) indices of the pixels the passes past the planned ones render (a render to a
        target: its cloud pixels); None: there are no such passes.
    """

    estimator: ReferenceOptions  # noqa: F821 (weather_mi.reference.options, which imports this module)
    planned: int
    target_pixels: np.ndarray | None = None


@dataclass(frozen=True)
class PassScene:
    """What a pass renders: the scene, the volume and the estimator options of a ``render_reference`` call
    (``key``: its fingerprint). Built into a Mitsuba scene in the current variant by ``build``, here or in
    a Dask worker (the same scene, hence the same pass images); pickles to the workers."""

    spec: SceneSpec
    vol: OpticalVolume
    options: PassOptions
    key: str

    def pixels_of(self, i: int):
        """The pixels (flat indices) pass ``i`` renders: None (all) for the planned passes, the cloud
        pixels for the passes a render to a target adds (``options.target_pixels``)."""
        pixels = self.options.target_pixels
        if pixels is None:
            return None
        return None if i < self.options.planned else pixels

    def build(self, release: bool = False):
        """The Mitsuba scene (current variant) in kernel-side coordinates: the bbox centred on the origin.
        ``release``: ``vol``'s grids are released as the kernel's are made from them (``OpticalVolume.release``:
        the extinction and albedo once delta-scaled, the weights once packed), so the peak holds one set."""
        import mitsuba as mi
        o = self.options.estimator
        spec_k, vol_k, _ = recentred(self.spec, self.vol)
        vol_render = delta_scaled(vol_k, o.forward_peak_deg, species_extinction=False,  # the kernel reads no beta_s
                                  deferred_weights=True)  # the weights scaled as they are packed (kernel.medium)
        if release and vol_render is not vol_k:  # its own extinction and albedo now (views of beta_ext stay)
            for v in (self.vol, vol_k):
                v.release("beta_ext", "beta_total", "albedo")
        integ = integrator_dict(vol_render, sun=self.spec.sun if o.own_sun else None, atmosphere=self.spec.atmosphere,
                                **o.kernel_options())
        d = scene_dict(spec_k, vol_render, integ)
        if release:
            for v in (self.vol, vol_k):
                v.release("beta_ext", "beta_total", "albedo", "weights")
        del vol_k, vol_render, integ  # the grids the kernel does not hold in place (the delta-scaled beta_ext,
        return mi.load_dict(d)        # weights) go before it builds its own (llvm: TensorXf(numpy) shares memory)


def _persistent(scene, persistent: bool | None) -> bool:
    """Whether passes of ``scene`` run with persistent lanes: as asked, or (None) wherever they apply:
    ``majorant_volpath`` on an LLVM variant, unless its ``persistent_lanes`` is false.

    Never on other variants, even when asked: persistent lanes refill the lanes of a CPU SIMD packet whose
    longest path holds it (sized in LLVM blocks per CPU thread); on CUDA a launch is many warps of 32 lanes
    that the hardware schedules as slots free up, and the lane count is an LLVM setting, so ``mi.render``
    renders the pass there (skipped, not an error: the same image in expectation, other random numbers)."""
    from ..kernel.variant import is_llvm
    if not is_llvm():
        return False
    if persistent is not None:
        return persistent
    integrator = scene.integrator()
    return hasattr(integrator, "render_passes") and getattr(integrator, "persistent", False)


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


def local_passes(scene, seed: int, per_pass, more, start: int, pixels_of=lambda i: None,
                 n_pixels: int = 1, planned: int | None = None, limit: int | None = None):
    """Passes rendered in this process: (index, image, seconds) while ``more(index)``; pass i renders
    the pixels ``pixels_of(i)`` (None: all ``n_pixels``). Consecutive passes over the same pixels are
    rendered together (``render_passes``), up to BATCH_SAMPLES samples, MAX_BATCH_PASSES passes, the end of
    the ``planned`` ones and ``limit`` (no pass from there on is wanted); ``more`` is asked for each pass
    after the previous one was handed over, so the passes handed over do not depend on the batches (a
    render to a target may render up to a batch it then drops). A pass's seconds: its batch's over its size."""
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
