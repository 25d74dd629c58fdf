"""Ground truth: ``render_reference`` path-traces an OpticalVolume in Mitsuba 3, in passes, with a
per-pixel standard error, a checkpoint after every pass and resume.

The estimate is the mean of P independent passes (consecutive seeds, k samples per pixel each); its
standard error is the sample standard deviation of the pass means over sqrt(P) (Welford updates).
A render to a target (``target_rse``) adds passes over its cloud pixels only, so there P is larger
than elsewhere. Passes rendered in this process share launches (``passes.render_passes``); each keeps
its own seed and values, so the image does not depend on how they were grouped (nor on Dask).

The steps live beside it: the passes and the scene they render in ``passes``, the running estimate and
the cloud pixels in ``estimates``, checkpoints in ``checkpoints``, Dask in ``dask_passes``.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import checkpoints
from .dask_passes import RemotePasses
from ..errors import WeatherDataError
from .estimates import CLOUD_TAU, noise_stats, pass_counts, pass_stderr, view_optical_depth, welford_update
from .estimates import cloud_mask  # noqa: F401  (re-exported: wm.reference.render.cloud_mask, the README's name)
from ..io.image import Image
from ..optics.volume import OpticalVolume
from .passes import PassOptions, PassScene, current_or_default_variant, local_passes, plan_passes
from .options import INTEGRATORS, ReferenceOptions, takes_options  # noqa: F401 (INTEGRATORS re-exported)
from ..scene.spec import SceneSpec

MAX_TARGET_PASSES = 1 << 14


@takes_options
def render_reference(spec: SceneSpec, vol: OpticalVolume, *args, options: ReferenceOptions | None = None,
                     checkpoint=None, resume=None, progress: bool = True, variant: str | None = None,
                     client=None, worker_variant=None, on_pass=None, release_volume: bool = False,
                     **estimator) -> Image:
    """Path-trace ``vol`` as seen by ``spec`` (Mitsuba ``volpath`` or our local-majorant tracker).

    Parameters
    ----------
    spec : SceneSpec
        Camera, sun, sky, ground, image size (pixels) and seed.
    vol : OpticalVolume
        Extinction (1/m), albedo and phase functions on the grid, its bbox in m.
    <ReferenceOptions fields>
    options : ReferenceOptions, optional
        The estimator options above as one object (``weather_mi.reference.options``); the ones also given
        by position or keyword replace its fields.
    checkpoint : path, optional
        A .npz written after every pass (a file already there is kept aside, unless resumed from).
    resume : path or True, optional
        Continue a render from this checkpoint (True: ``checkpoint``); the scene must be identical.
    progress : bool
        Show a progress bar (with the noise over the cloud pixels).
    variant : str, optional
        Mitsuba variant (None: the one selected, or the default).
    client : Client or str, optional
        None (render in this process), a ``dask.distributed.Client`` or a scheduler address
        ("tcp://host:8786"): the passes become Dask tasks (``weather_mi.reference.dask_passes``), merged here in
        pass order, so the image is bit-identical to the in-process one.
    worker_variant : str or dict, optional
        With ``client``: the Mitsuba variant of the workers (None: this process's; "auto": each
        worker's default, cuda_ad_rgb where a CUDA test kernel runs there, else llvm_ad_rgb; a name; or
        {worker address: name}). The metadata then records ``variant`` (or "mixed"),
        ``passes_by_variant`` and ``agreement`` (``cluster.pass_variants``).
    on_pass : callable, optional
        Invoked after every merged pass (after its checkpoint is written) with an ``Image`` of the
        estimate so far: mean radiance and standard error (float32; NaN while fewer than 2 passes), and
        the metadata of the final image for the passes so far (``passes``, ``spp``, ``seconds``,
        ``noise``: ``noise_stats`` over the cloud pixels or None while fewer than 2 passes,
        ``target_rse``, ...). The arrays are the callback's own copies. An exception it raises
        propagates out of ``render_reference`` (queued Dask passes are cancelled and the checkpoint
        stays valid, as with Ctrl-C): a way to stop a render.
    release_volume : bool, default False
        In this process (no ``client``): ``vol``'s grids are released (``OpticalVolume.release``) as the
        kernel's own grids are built from them, so that the two are not held together at the peak; reading
        them afterwards raises. For a caller that needs them no more (the command line).

    Returns
    -------
    Image
        Radiance (or reflectance) and standard error, (H, W, 3) float32; ``transmittance``: the (H, W)
        eye-ray transmittance of the volume (None on scalar variants), whose pixels below 1/2 are the
        cloud pixels; the metadata records the render and ``noise_stats`` over the cloud pixels (also
        shown by the progress bar).

    Raises
    ------
    OutputWriteError
        When the checkpoint cannot be written (a full disk): the checkpoint of the previous pass is kept
        whole, and resuming from it continues the render.
    """
    from ..kernel.variant import path_tracing_width, set_variant
    o = ReferenceOptions.of_call(options, args, estimator).resolved(spec)  # defaults filled in, checked
    _check_inputs(spec, vol, o.integrator, variant)
    from ..optics.air.inside import scene_air
    vol = scene_air(vol, spec.atmosphere)  # the atmosphere's air in the box too (none where vol has it already)
    set_variant(variant if variant is not None else current_or_default_variant())
    with path_tracing_width():  # the scene is built and its passes rendered at the path tracer's SIMD width
        spp_list = plan_passes(spec, o.spp, o.passes)
        cloud, transmittance = _cloud_pixels(spec, vol)
        # render to a target: the passes past the planned ones cover the cloud pixels only, or every pixel (None)
        target = _target(o, cloud)
        pass_options = PassOptions(o, planned=len(spp_list),
                                   target_pixels=None if target is None else np.flatnonzero(target.ravel()))
        key = _render_key(spec, vol, spp_list, o, worker_variant if client is not None else None)
        run = _Run(PassScene(spec, vol, pass_options, key), spp_list, cloud, transmittance, _scale(spec, o.normalize),
                   mean=np.zeros((spec.height, spec.width, 3)), m2=np.zeros((spec.height, spec.width, 3)))
        run.release_volume = bool(release_volume) and client is None
        _open_checkpoint(run, checkpoint, resume)
        remote = _merge_passes(run, client, worker_variant, progress, on_pass)
        image = run.image(run.done, run.stats(run.done))
        if remote is not None:  # which variant each pass used (workers may differ: "auto")
            from .cluster import pass_variants
            image.metadata["dask"] = remote.summary
            image.metadata.update(pass_variants(remote.summary["passes_by_variant"], image.metadata["variant"]))
        return image


@dataclass
class _Run:
    """One ``render_reference`` call under way: what its passes render (``job``), their samples per pixel
    (``spp_list``: the planned ones), its cloud pixels and where it checkpoints; the estimate so far: the
    per-pixel mean and Welford M2 (float64, (H, W, 3)) of the passes merged, their number, their seconds
    and samples per pixel."""

    job: PassScene
    spp_list: list
    cloud: np.ndarray
    transmittance: np.ndarray | None
    scale: object           # 1.0, or the (3,) reflectance factors pi / (mu0 E)
    mean: np.ndarray
    m2: np.ndarray
    ckpt: Path | None = None
    done: int = 0
    seconds: float = 0.0
    spp_done: int = 0
    release_volume: bool = False  # the job's volume released as its scene is built (``render_reference``)

    @property
    def xyz_film(self) -> bool:
        """Whether the passes are CIE XYZ (spectral variants: ``kernel.scene_dict.sensor_dict``)."""
        import mitsuba as mi
        return bool(mi.is_spectral)

    @property
    def planned(self) -> int:
        return self.job.options.planned

    @property
    def target_rse(self) -> float | None:
        return self.job.options.estimator.target_rse

    @property
    def max_seconds(self) -> float | None:
        return self.job.options.estimator.max_seconds

    @property
    def target(self) -> np.ndarray | None:
        """The pixels the passes past the planned ones render (a render to a target with ``target_pixels="cloud"``:
        the cloud pixels), or None (every pixel: no target, or ``target_pixels="all"``)."""
        return _target(self.job.options.estimator, self.cloud)

    def per_pass(self, i: int) -> int:
        return self.spp_list[i] if i < len(self.spp_list) else self.spp_list[0]

    def stderr(self, n: int) -> np.ndarray:
        return pass_stderr(self.m2, pass_counts(n, self.planned, self.target))

    def stats(self, n: int) -> dict | None:
        """``noise_stats`` over the cloud pixels after ``n`` passes (None below two)."""
        if n < 2:
            return None
        return noise_stats(self.mean, self.stderr(n), self.cloud)

    def more(self, i: int) -> bool:
        """Whether pass ``i`` is wanted: every planned one; past them (a render to a target) until the
        target is met, MAX_TARGET_PASSES or ``max_seconds``."""
        if self.target_rse is None:
            return i < len(self.spp_list)
        if i < self.planned:
            return True
        if not self.cloud.any():  # no cloud pixel in view: nothing to converge
            return False
        st = self.stats(i)
        if st is not None and st["cloud_pixels"] and st["rse_mean"] <= self.target_rse:
            return False
        return i < MAX_TARGET_PASSES and (self.max_seconds is None or self.seconds < self.max_seconds)

    def merge(self, i: int, raw: np.ndarray, dt: float) -> int:
        """Add pass ``i``'s image ``raw`` (its seconds ``dt``) to the estimate and checkpoint it; the
        number of passes merged."""
        img = raw.astype(np.float64)[..., :3] * self.scale
        if self.xyz_film:  # spectral variants: the film's CIE XYZ as linear sRGB (D65) through colour-science
            from ..optics.spectrum import linear_srgb
            img = linear_srgb(img)
        self.seconds += dt
        n = i + 1
        welford_update(self.mean, self.m2, img, n, where=None if i < self.planned else self.target)
        self.spp_done += self.per_pass(i)
        self.done = n
        if self.ckpt is not None:
            checkpoints.save_checkpoint(self.ckpt, {"key": self.job.key, "mean": self.mean, "m2": self.m2, "done": n,
                                                    "seconds": self.seconds, "spp_done": self.spp_done})
        return n

    def image(self, n: int, noise: dict | None) -> Image:
        """The estimate after ``n`` passes as an ``Image`` (its own arrays) with its metadata."""
        import mitsuba as mi
        transmittance = None if self.transmittance is None else self.transmittance.copy()
        xyz = None
        if mi.is_spectral:  # the passes were merged as linear sRGB (``merge``); X, Y, Z back from their mean
            from ..optics.spectrum import xyz_of_linear_srgb
            xyz = xyz_of_linear_srgb(self.mean)
        return Image(self.mean.astype(np.float32), self.stderr(n).astype(np.float32), self.metadata(n, noise),
                     transmittance, xyz=xyz)

    def metadata(self, n: int, noise: dict | None) -> dict:
        import mitsuba as mi
        o, spec, vol = self.job.options.estimator, self.job.spec, self.job.vol
        target = self.target
        background = sum(self.spp_list[:min(n, self.planned)]) if target is not None and not target.all() else self.spp_done
        # the estimator options (None where unused), then this render's figures: spp and passes done
        return {"renderer": "reference", "variant": mi.variant(), **o.metadata(),
                "spp": int(self.spp_done), "spp_background": int(background),
                "passes": n, "seconds": self.seconds,
                "scene": spec.to_dict(), "species_preset": vol.attrs.get("species_preset"),
                "source": vol.attrs.get("source"), "time": vol.attrs.get("time"),
                "phase_mode": vol.phase_mode, "sun": ("scene emitter" if not o.own_sun else
                                                      ("disk" if spec.sun.angular_diameter_deg > 0 else "point")),
                "noise": noise}


def _target(o: ReferenceOptions, cloud: np.ndarray) -> np.ndarray | None:
    """The pixels (H, W) the passes of a render to a target add render when they are fewer than all: the ``cloud``
    pixels with ``o.target_pixels == "cloud"``; None (every pixel) without a target or with ``"all"``."""
    if o.target_rse is None or o.target_pixels != "cloud":
        return None
    return cloud


def _cloud_pixels(spec: SceneSpec, vol: OpticalVolume):
    """(cloud pixels (H, W) bool, eye-ray transmittance (H, W) float32 or None) of the view: the full
    extinction (not delta-scaled) along the scene's sensor rays; every pixel on a scalar variant."""
    import mitsuba as mi
    if mi.variant().startswith("scalar"):  # the ray march is vectorised: every pixel counts there
        return np.ones((spec.height, spec.width), bool), None
    tau = view_optical_depth(spec, vol)
    return tau > CLOUD_TAU, np.exp(-tau).astype(np.float32)


def _render_key(spec, vol, spp_list, o: ReferenceOptions, worker_variant) -> str:
    """The fingerprint of a render (``checkpoints.fingerprint``): what its images depend on: the scene, the
    volume, the sample plan, every estimator option of the resolved ``o`` (``ReferenceOptions.key_items``:
    all but those declared out of it, with the reason), the variant and the workers'."""
    import mitsuba as mi
    options = [["estimator", o.key_items()], mi.variant()]
    if worker_variant is not None:  # other variants: the same image within noise only
        options.append(["worker variant", worker_variant])
    return checkpoints.fingerprint(spec, vol, spp_list, *options)


def _scale(spec: SceneSpec, normalize):
    """Factor of the radiance: 1, or pi / (mu0 E) per channel (reflectance)."""
    if normalize == "reflectance":
        return np.pi / (spec.sun.mu0 * np.asarray(spec.sun.irradiance))
    return 1.0


def _open_checkpoint(run: _Run, checkpoint, resume) -> None:
    """Where ``run`` checkpoints, and its estimate so far from the checkpoint it resumes (``resume``: a
    path or True); a checkpoint where a fresh render writes is kept aside."""
    ckpt = Path(checkpoint) if checkpoint is not None else None
    resume_path = ckpt if resume is True else (Path(resume) if resume else None)
    if resume_path is not None and resume_path.is_file():
        run.mean, run.m2, run.done, run.seconds, run.spp_done = checkpoints.load_checkpoint(
            resume_path, run.job.key, run.spp_list)
        ckpt = ckpt or resume_path
    elif resume_path is None and ckpt is not None and ckpt.is_file():
        checkpoints.keep_aside(ckpt)
    run.ckpt = ckpt


def _pass_source(run: _Run, client, worker_variant):
    """(iterator of (pass index, image, seconds) in pass order, the ``RemotePasses`` or None): the passes
    still wanted, rendered in this process or by Dask workers."""
    job = run.job
    if client is None:
        limit = run.planned if run.target_rse is None else MAX_TARGET_PASSES
        return local_passes(job.build(release=run.release_volume), job.spec.seed, run.per_pass, run.more, run.done, job.pixels_of,
                            n_pixels=job.spec.width * job.spec.height, planned=run.planned, limit=limit), None
    remote = RemotePasses(client, job, run.per_pass, run.more, run.done, len(run.spp_list), run.target_rse is not None,
                          worker_variant=worker_variant)
    return iter(remote), remote


def _merge_passes(run: _Run, client, worker_variant, progress: bool, on_pass):
    """Merge the passes still wanted into ``run`` in pass order (a checkpoint after each, ``on_pass``, the
    progress bar); the ``RemotePasses`` (its summary) or None."""
    from tqdm.auto import tqdm
    passes_in, remote = _pass_source(run, client, worker_variant)
    bar = tqdm(total=len(run.spp_list) if run.target_rse is None else None, initial=run.done, desc="reference",
               unit="pass", disable=not progress)
    try:
        for i, raw, dt in passes_in:  # pass i's image, in pass order; dt: its seconds (wall-clock over Dask)
            n = run.merge(i, raw, dt)
            bar.update(1)
            # noise over the cloud pixels: for the progress bar and on_pass only
            st = run.stats(n) if progress or on_pass is not None else None
            if progress and st is not None:
                bar.set_postfix_str(f"cloud RSE {st['rse_mean']:.3f} worst se/mean {st['worst_se_over_mean']:.2f}")
            if on_pass is not None:
                on_pass(run.image(n, st))
    finally:  # over Dask: cancels the passes still queued (target met, Ctrl-C, error); the checkpoint stays valid
        passes_in.close()
        bar.close()
    return remote


def _check_inputs(spec: SceneSpec, vol: OpticalVolume, integrator: str, variant):
    """The arguments besides the estimator options (``ReferenceOptions.resolved`` checks those): the variant
    (with the integrator) and the volume."""
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


def render_transmittance(spec: SceneSpec, vol: OpticalVolume, spp: int = 32, **kw) -> np.ndarray:
    """Eye-ray transmittance (H, W) through ``vol`` from the path tracer: the volume made purely
    absorbing, seen against a uniform sky of radiance 1 with no sun light and no ground, so that the
    rendered radiance is the transmittance (unbiased delta-tracking estimate, ``spp`` samples)."""
    from dataclasses import replace
    from ..scene.spec import Sky, Sun
    absorbing = replace(vol, albedo=np.zeros_like(vol.albedo))
    t_spec = replace(spec, sun=Sun(spec.sun.azimuth, spec.sun.elevation, irradiance=0.0, angular_diameter_deg=0.0),
                     sky=Sky("constant", radiance=1.0), ground=None)
    kw.setdefault("progress", False)
    return render_reference(t_spec, absorbing, spp=spp, **kw).radiance.mean(axis=2)
