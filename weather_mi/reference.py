"""Ground truth: path-traced rendering of an OpticalVolume in Mitsuba 3, in passes, with a per-pixel
standard error, checkpoints after every pass and resume.

The estimate is the mean of P independent passes (consecutive seeds, k samples per pixel each); its
standard error is the sample standard deviation of the pass means over sqrt(P) (Welford updates).
"""
from __future__ import annotations

import hashlib
import json
import os
import time
from pathlib import Path

import numpy as np

from .errors import WeatherDataError
from .imageio import Image
from .optics import OpticalVolume
from .scene import SceneSpec

INTEGRATORS = ("majorant", "volpath")
MAX_LANES_PER_PASS = 1 << 22


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
    """Samples per pixel of each pass: at least 4 passes when spp allows (for the error estimate),
    and at most MAX_LANES_PER_PASS paths per pass (memory)."""
    if passes is None:
        per = max(1, min(spp // 4 if spp >= 4 else 1, MAX_LANES_PER_PASS // (spec.width * spec.height)))
        passes = -(-spp // per)
    passes = max(1, min(int(passes), spp))
    base, extra = divmod(spp, passes)
    return [base + (1 if i < extra else 0) for i in range(passes)]


def integrator_dict(vol: OpticalVolume, integrator: str, max_depth: int, rr_depth: int | None = None,
                    cell: int | None = None) -> dict:
    """Mitsuba integrator dict: stock ``volpath`` or ``majorant_volpath`` with a majorant grid of
    ``cell``^3 voxels per coarse cell (None: the plugin's ``DEFAULT_CELL``). ``rr_depth``: depth at which Russian roulette starts (None: the
    integrators' default, 5; a huge value turns it off)."""
    if integrator == "volpath":
        d = {"type": "volpath", "max_depth": int(max_depth)}
    else:
        import mitsuba as mi
        from .plugins.hydrometeor_mixture import bbox_transform
        from .plugins.majorant_volpath import DEFAULT_CELL, majorant_grid, register
        register()
        cell = DEFAULT_CELL if cell is None else cell
        d = {"type": "majorant_volpath", "max_depth": int(max_depth), "cell": int(cell),
             "majorant": mi.TensorXf(majorant_grid(vol.beta_total, cell=int(cell))),
             "to_world": bbox_transform(vol.bbox)}
    if rr_depth is not None:
        d["rr_depth"] = int(rr_depth)
    return d


def _fingerprint(spec: SceneSpec, vol: OpticalVolume, spp_list, integrator, max_depth, normalize, variant,
                 rr_depth=None) -> str:
    h = hashlib.sha256()
    h.update(json.dumps([spec.to_dict(), spp_list, integrator, max_depth, normalize, variant, rr_depth],
                        sort_keys=True, default=str).encode())
    for a in (vol.beta_total, vol.albedo, vol.weights):
        h.update(np.ascontiguousarray(a).tobytes())
    for t in vol.phase_tables:  # the phase functions are part of the scene too
        h.update(np.ascontiguousarray(t.theta, np.float64).tobytes())
        h.update(np.ascontiguousarray(t.values, np.float64).tobytes())
    h.update(json.dumps([list(map(float, p)) for p in vol.bbox]).encode())
    return h.hexdigest()


def _save_checkpoint(path: Path, state: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp.npz")
    np.savez(tmp, **state)
    os.replace(tmp, path)


def render_reference(spec: SceneSpec, vol: OpticalVolume, spp: int = 256, max_depth: int = -1, *,
                     integrator: str = "majorant", passes: int | None = None, normalize: str | None = None,
                     checkpoint=None, resume=None, progress: bool = True, variant: str | None = None,
                     rr_depth: int | None = None, cell: int | None = None) -> Image:
    """Path-trace ``vol`` as seen by ``spec`` (Mitsuba ``volpath`` or our local-majorant tracker).

    spp        : samples per pixel in total, split into passes (``passes``, default >= 4).
    integrator : "majorant" (delta tracking over a coarse majorant grid; default) or "volpath"
                 (Mitsuba's own, one global majorant: the reference's reference).
    normalize  : None (radiance) or "reflectance" (pi L / (mu0 E) per channel).
    rr_depth   : depth at which Russian roulette starts (None: the integrators' default, 5).
    cell       : fine voxels per coarse cell of the majorant grid ("majorant" only; None: the default).
    checkpoint : a .npz path written after every pass; ``resume`` (a path, or True to use
                 ``checkpoint``) continues a render from it; the scene must be identical.
    """
    from .variant import set_variant
    _check_inputs(spec, vol, spp, normalize, integrator, variant)
    set_variant(variant) if variant is not None else set_variant(_current_or_default())
    import mitsuba as mi
    from tqdm.auto import tqdm

    from .mitsuba_scene import recentred, scene_dict

    spp_list = _passes(spec, int(spp), passes)
    key = _fingerprint(spec, vol, spp_list, integrator, max_depth, normalize, mi.variant(), rr_depth)  # cell: speed only
    ckpt = Path(checkpoint) if checkpoint is not None else None
    resume_path = ckpt if resume is True else (Path(resume) if resume else None)
    h, w = spec.height, spec.width
    mean = np.zeros((h, w, 3))
    m2 = np.zeros((h, w, 3))
    done, seconds = 0, 0.0
    if resume_path is not None and resume_path.is_file():
        with np.load(resume_path) as state:
            if str(state["key"]) != key:
                raise ValueError(f"checkpoint {resume_path} belongs to a different scene, volume or sample plan")
            mean, m2, done, seconds = state["mean"], state["m2"], int(state["done"]), float(state["seconds"])
        ckpt = ckpt or resume_path

    spec_k, vol_k, _ = recentred(spec, vol)  # kernel-side coordinates: bbox centred on the origin
    scene = mi.load_dict(scene_dict(spec_k, vol_k, integrator_dict(vol_k, integrator, max_depth, rr_depth, cell)))
    scale = 1.0
    if normalize == "reflectance":
        scale = np.pi / (spec.sun.mu0 * np.asarray(spec.sun.irradiance))
    bar = tqdm(total=len(spp_list), initial=done, desc="reference", unit="pass", disable=not progress)
    for i in range(done, len(spp_list)):
        t0 = time.perf_counter()
        img = np.array(mi.render(scene, spp=spp_list[i], seed=pass_seed(spec.seed, i)), dtype=np.float64)
        img = img[..., :3] * scale
        seconds += time.perf_counter() - t0
        n = i + 1  # Welford update of per-pixel mean and M2 over pass means
        delta = img - mean
        mean += delta / n
        m2 += delta * (img - mean)
        if ckpt is not None:
            _save_checkpoint(ckpt, {"key": key, "mean": mean, "m2": m2, "done": n, "seconds": seconds})
        bar.update(1)
    bar.close()
    n = len(spp_list)
    stderr = np.sqrt(m2 / (n - 1) / n) if n > 1 else np.full_like(mean, np.nan)
    meta = {"renderer": "reference", "integrator": integrator, "variant": mi.variant(), "spp": int(spp),
            "passes": n, "max_depth": int(max_depth), "rr_depth": rr_depth, "seconds": seconds, "normalize": normalize,
            "scene": spec.to_dict(), "species_preset": vol.attrs.get("species_preset"),
            "source": vol.attrs.get("source"), "time": vol.attrs.get("time"),
            "phase_mode": vol.phase_mode}
    return Image(mean.astype(np.float32), stderr.astype(np.float32), meta)


def render_transmittance(spec: SceneSpec, vol: OpticalVolume, spp: int = 32, **kw) -> np.ndarray:
    """Eye-ray transmittance (H, W) through ``vol`` from the path tracer: the volume made purely
    absorbing, seen against a uniform sky of radiance 1 with no sun light and no ground, so that the
    rendered radiance is the transmittance (unbiased delta-tracking estimate, ``spp`` samples)."""
    from dataclasses import replace
    from .scene import Sky, Sun
    absorbing = replace(vol, albedo=np.zeros_like(vol.albedo))
    t_spec = replace(spec, sun=Sun(spec.sun.azimuth, spec.sun.elevation, irradiance=0.0),
                     sky=Sky("constant", radiance=1.0), ground=None)
    kw.setdefault("progress", False)
    return render_reference(t_spec, absorbing, spp=spp, **kw).radiance.mean(axis=2)


def _current_or_default() -> str:
    import mitsuba as mi
    from .variant import default_variant
    return mi.variant() or default_variant()
