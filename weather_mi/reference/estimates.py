"""The estimate of a reference render and how converged it is: the per-pixel mean of its passes with
Welford's running M2, the standard error of that mean, the passes each pixel has had, the noise figures
over the cloud pixels, and the cloud pixels themselves (eye-ray optical depth above ln 2, from a
deterministic ray march through the volume, no rendering).

The estimate is the mean of P independent passes; its standard error is the sample standard deviation
of the pass means over sqrt(P).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..kernel.scene_dict import recentred, sensor_dict
from ..optics.volume import OpticalVolume
from .passes import current_or_default_variant
from ..scene.spec import SceneSpec
from .colour_noise import pass_images

CLOUD_TAU = np.log(2.0)  # cloud pixels: eye-ray transmittance below 1/2


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


def pass_stderr(m2: np.ndarray, n) -> np.ndarray:
    """Standard error of the mean over ``n`` passes from Welford's M2 (NaN below two passes); ``n`` a
    number or per-pixel counts that broadcast against ``m2``."""
    n = np.asarray(n, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(n > 1, np.sqrt(m2 / np.maximum(n - 1, 1) / n), np.nan)


def pass_counts(n: int, planned: int, target: np.ndarray | None) -> np.ndarray:
    """(H, W, 1) passes per pixel after ``n`` passes of a render whose passes past the ``planned`` ones
    cover only the ``target`` pixels (render to a target: its cloud pixels), or (1, 1, 1) of n."""
    if target is None or n <= planned:
        return np.full((1, 1, 1), n)
    return np.where(target, n, planned)[..., None]


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


Y_OF_LINEAR_SRGB = np.array([0.2126729, 0.7151522, 0.0721750])  # CIE Y of linear sRGB (D65; IEC 61966-2-1)


def luminance_rse(means, cloud: np.ndarray) -> float:
    """Mean over the ``cloud`` pixels (H, W) of se(Y) / Y, Y the luminance of linear sRGB: each pass's image
    recovered from the running means after 1, 2, ... P passes (``means``: (H, W, 3) each, as ``on_pass`` gives
    them), se the sample standard deviation of the passes' Y over sqrt(P). Unlike ``noise_stats``' rse_mean
    (the channels' mean se), it does not count the colour noise that the spectral mode's R, G, B get from its
    X, Y, Z through sRGB's matrix."""
    n = len(means)
    if n < 2:
        raise ValueError(f"luminance_rse needs at least 2 passes, got {n}")
    y = pass_images(means)[..., :3] @ Y_OF_LINEAR_SRGB  # pass i = (i + 1) mean_i - i mean_(i-1), in Y (linear)
    ym, se = y.mean(axis=0), y.std(axis=0, ddof=1) / np.sqrt(n)
    ok = np.asarray(cloud, bool) & (ym > 0)
    return float(np.mean(se[ok] / ym[ok])) if np.any(ok) else float("nan")


def view_optical_depth(spec: SceneSpec, vol: OpticalVolume) -> np.ndarray:
    """Optical depth (H, W) of the full extinction (not delta-scaled) along each pixel's central camera
    ray of the scene's sensor (``eye_optical_depth``), in the current Mitsuba variant (or the default)."""
    import mitsuba as mi
    from ..kernel.variant import set_variant
    set_variant(current_or_default_variant())
    spec_k, vol_k, _ = recentred(spec, vol)
    return eye_optical_depth(mi.load_dict(sensor_dict(spec_k)), vol_k, spec_k)


def cloud_mask(spec: SceneSpec, vol: OpticalVolume) -> np.ndarray:
    """Cloud pixels (H, W) of a view: eye-ray optical depth > ln 2 (transmittance below 1/2), as the
    noise figures of ``render_reference`` count them (deterministic, no rendering)."""
    return view_optical_depth(spec, vol) > CLOUD_TAU


class EyeRays(NamedTuple):
    o: list
    d: list
    t0: object
    seg: object
    ray: object
    ext: np.ndarray


def eye_rays_in_box(sensor, spec: SceneSpec, bbox):
    """The central camera ray of every pixel (row-major) of ``sensor`` in the unit-cube coordinates of
    ``bbox`` (m): origins ``o`` and directions ``d`` (3 lists of mi.Float; t counts metres along the
    world ray), where the ray enters the box ``t0`` (0 for a camera inside), the length of its segment
    inside ``seg`` (0 for a ray that misses it), the world rays ``ray`` and the box's size ``ext`` (m)."""
    import drjit as dr
    import mitsuba as mi
    from ..kernel.jitarrays import aligned_float
    h, w = spec.height, spec.width
    jj, ii = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    pos = mi.Point2f(aligned_float(mi, ((ii + 0.5) / w).ravel()), aligned_float(mi, ((jj + 0.5) / h).ravel()))
    ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
    lo, hi = (np.asarray(p, np.float64) for p in bbox)
    ext = hi - lo
    o = [(ray.o[k] - float(lo[k])) / float(ext[k]) for k in range(3)]
    d = [ray.d[k] / float(ext[k]) for k in range(3)]
    t0, t1 = mi.Float(0.0), mi.Float(dr.inf)
    for k in range(3):
        inv = dr.rcp(dr.select(dr.abs(d[k]) < 1e-30, 1e-30, d[k]))
        ta, tb = -o[k] * inv, (1.0 - o[k]) * inv
        t0, t1 = dr.maximum(t0, dr.minimum(ta, tb)), dr.minimum(t1, dr.maximum(ta, tb))
    seg = dr.maximum(t1 - t0, 0.0)
    return EyeRays(o, d, t0, seg, ray, ext)


def eye_optical_depth(sensor, vol_k: OpticalVolume, spec: SceneSpec, steps: int = 512) -> np.ndarray:
    """Optical depth (H, W) of the medium along each pixel's central camera ray, by the midpoint rule
    over ``steps`` steps of the ray's segment in the volume's box (deterministic; the scene's own
    ``sensor``, so the same rays as the render). ``vol_k``: the volume in the sensor's coordinates."""
    import drjit as dr
    import mitsuba as mi
    h, w = spec.height, spec.width
    o, d, t0, seg, _, _ = eye_rays_in_box(sensor, spec, vol_k.bbox)
    tex = mi.Texture3f(mi.TensorXf(np.ascontiguousarray(vol_k.beta_total, np.float32)[..., None]),
                       wrap_mode=dr.WrapMode.Clamp, use_accel=False)  # CUDA: float weights, as on LLVM
    n_steps = dr.opaque(mi.UInt32, steps)

    def body(i, tau):  # one small symbolic loop: an unrolled march compiles for a minute
        t = t0 + seg * ((mi.Float(i) + 0.5) / mi.Float(n_steps))
        tau += tex.eval(mi.Point3f(*(o[k] + d[k] * t for k in range(3))))[0]
        return i + 1, tau

    _, tau = dr.while_loop(state=(mi.UInt32(0), dr.zeros(mi.Float, h * w)), cond=lambda i, tau: i < n_steps,
                           body=body, label="eye optical depth")
    return np.asarray(tau * seg / steps, np.float64).reshape(h, w)
