"""The colour noise of a reference render, from its passes: what the luminance RSE (``estimates.luminance_rse``)
does not count. The spectral mode's R, G, B come from X, Y, Z through sRGB's matrix, and a path whose weight
blows up in one of its 4 wavelengths adds a coloured firefly with little luminance.

* :func:`pass_images`: each pass's image, from the running means ``render_reference``'s ``on_pass`` gives.
* :func:`channel_rse`: per channel (R, G, B of linear sRGB) the mean over the cloud pixels of se / mean.
* :func:`chroma_se`: the standard error of each cloud pixel's CIE 1976 chromaticity (u', v') of the mean of the
  passes, by the delta method (first order in the passes' X, Y, Z), as the Euclidean se in (u', v'), averaged
  over the cloud pixels. It falls as 1 / sqrt(samples), so (t se^2) ratios are the time to the same chroma noise.
  (u', v') is the CIE's uniform chromaticity scale: a difference of about 0.004 is just noticeable side by side.
* :func:`firefly_count`: the cloud pixels in which one pass of one channel exceeds ``k`` x the median of that
  pixel's passes in that channel.
"""
from __future__ import annotations

import numpy as np

from ..optics.spectrum import xyz_of_linear_srgb

FIREFLY_K = 10.0  # a firefly: one pass > this x the median of the pixel's passes (one channel)


def pass_images(means) -> np.ndarray:
    """(P, H, W, C) float64: pass i = (i + 1) mean_i - i mean_(i-1), from the running means after 1, 2, ... P
    passes (``means``: (H, W, C) each)."""
    m = np.stack([(i + 1) * np.asarray(x, np.float64) for i, x in enumerate(means)])
    m[1:] -= m[:-1].copy()
    return m


def _checked(passes, cloud) -> tuple[np.ndarray, np.ndarray]:
    p = np.asarray(passes, np.float64)
    if p.ndim != 4 or p.shape[0] < 2 or p.shape[-1] < 3:
        raise ValueError(f"colour noise needs passes shaped (P >= 2, H, W, 3), got {p.shape}")
    c = np.asarray(cloud, bool)
    if c.shape != p.shape[1:3]:
        raise ValueError(f"the cloud mask is {c.shape}, the passes' images {p.shape[1:3]}")
    return p[..., :3], c


def channel_rse(passes, cloud) -> np.ndarray:
    """(3,): per channel, the mean over the ``cloud`` pixels whose mean is > 0 in that channel of se / mean
    (se: the passes' sample standard deviation over sqrt(P))."""
    p, c = _checked(passes, cloud)
    n = p.shape[0]
    mean, se = p.mean(axis=0), p.std(axis=0, ddof=1) / np.sqrt(n)
    out = np.full(3, np.nan)
    for k in range(3):
        ok = c & (mean[..., k] > 0)
        if np.any(ok):
            out[k] = float(np.mean(se[..., k][ok] / mean[..., k][ok]))
    return out


def chroma_se(passes, cloud) -> float:
    """Mean over the ``cloud`` pixels of the standard error of the pixel's (u', v') (CIE 1976 UCS) of the mean of
    the passes: u' = 4 X / D, v' = 9 Y / D, D = X + 15 Y + 3 Z; to first order a pass's deviation moves u' by
    (4 X_p - u' D_p) / (P D) (Eq. of the delta method; likewise v'), so se(u') = std_p(4 X_p - u' D_p) /
    (sqrt(P) D) with D the mean's. The se is sqrt(se(u')^2 + se(v')^2). Pixels with D <= 0 are left out."""
    p, c = _checked(passes, cloud)
    n = p.shape[0]
    xyz = xyz_of_linear_srgb(p)
    d_p = xyz[..., 0] + 15.0 * xyz[..., 1] + 3.0 * xyz[..., 2]
    x_m, y_m, d = xyz[..., 0].mean(axis=0), xyz[..., 1].mean(axis=0), d_p.mean(axis=0)
    ok = c & (d > 0)
    if not np.any(ok):
        return float("nan")
    with np.errstate(divide="ignore", invalid="ignore"):
        u, v = 4.0 * x_m / d, 9.0 * y_m / d
        du = (4.0 * xyz[..., 0] - u * d_p).std(axis=0, ddof=1) / (np.sqrt(n) * d)
        dv = (9.0 * xyz[..., 1] - v * d_p).std(axis=0, ddof=1) / (np.sqrt(n) * d)
    return float(np.mean(np.hypot(du, dv)[ok]))


def firefly_count(passes, cloud, k: float = FIREFLY_K) -> int:
    """Number of ``cloud`` pixels in which, in some channel whose median over the passes is > 0, one pass
    exceeds ``k`` x that median."""
    p, c = _checked(passes, cloud)
    med = np.median(p, axis=0)
    hot = np.any((p > k * med) & (med > 0), axis=0)  # (H, W, 3)
    return int(np.sum(np.any(hot, axis=-1) & c))


def colour_noise(means, cloud, k: float = FIREFLY_K) -> dict:
    """The figures above from the running means of a render's passes: ``rse_rgb`` (3,), ``chroma_se`` and
    ``fireflies``."""
    passes = pass_images(means)
    return {"rse_rgb": channel_rse(passes, cloud), "chroma_se": chroma_se(passes, cloud),
            "fireflies": firefly_count(passes, cloud, k)}
