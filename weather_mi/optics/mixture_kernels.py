"""The per-voxel mixture of the species' optics (Eq. 5, 6, 8) in one pass over the grid (numba), with
the same float32 operations in the same order as the numpy expressions they replace (``optics.volume``'s
images stay bit-identical): numpy took about 50 passes over 4-byte grids for these, most of the time
``optical_volume`` spent on a large domain."""
from __future__ import annotations

import numpy as np
from numba import njit, prange


@njit(parallel=True, cache=True)
def mix(beta_ext, rgb, mean_albedo, beta_total, albedo_sum, weights):  # pragma: no cover - compiled
    """beta_ext (S, N) -> beta_total (N,) = sum_s beta_s (Eq. 6, in species order), albedo_sum (N, 3) =
    sum_s beta_s omega_s (Eq. 5's numerator) and weights (S, N) = beta_s w_s / sum (Eq. 8; 0 where nothing
    scatters), float32; rgb (S, 3) and mean_albedo (S,) float32."""
    n_s, n = beta_ext.shape
    for v in prange(n):
        total = beta_ext[0, v]
        for s in range(1, n_s):
            total = total + beta_ext[s, v]
        beta_total[v] = total
        for c in range(3):
            acc = beta_ext[0, v] * rgb[0, c]
            for s in range(1, n_s):
                acc = acc + beta_ext[s, v] * rgb[s, c]
            albedo_sum[v, c] = acc
        sca = beta_ext[0, v] * mean_albedo[0]
        weights[0, v] = sca
        for s in range(1, n_s):
            w = beta_ext[s, v] * mean_albedo[s]
            weights[s, v] = w
            sca = sca + w
        for s in range(n_s):
            weights[s, v] = weights[s, v] / sca if sca > 0 else np.float32(0.0)


@njit(parallel=True, cache=True)
def finish_albedo(albedo, beta_total, fill):  # pragma: no cover - compiled
    """albedo (N, 3): albedo_sum / beta_total where there is extinction, ``fill`` (3,) elsewhere, clipped to
    [0, 1], in place."""
    for v in prange(beta_total.shape[0]):
        t = beta_total[v]
        for c in range(3):
            a = albedo[v, c] / t if t > 0 else fill[c]
            albedo[v, c] = min(max(a, np.float32(0.0)), np.float32(1.0))



@njit(parallel=True, cache=True)
def add_voxel_albedo(voxels, beta, radius, radius_scale, wavelengths, k_abs, n_term, albedo_rgb,
                     albedo_sum):  # pragma: no cover - compiled
    """albedo_sum (N, 3) += (omega_c(r) - albedo_rgb_c) beta, float32, in place, at the flat indices ``voxels``
    (those with beta > 0 and r > 0; ``radius`` their radii): the weak-absorption albedo of each voxel's radius
    (``species.albedo_of_radius``: x = 2 pi r' / lambda, Q_abs = min(8/3 x k n_term, 1), omega = 1 - Q_abs / 2;
    r' = r x ``radius_scale``), in float64 with the operations of those numpy expressions in their order (the
    same floats). ``n_term``: n^3 - (n^2 - 1)^1.5."""
    two_pi, eight_thirds = 2.0 * np.pi, 8.0 / 3.0
    for i in prange(voxels.shape[0]):
        v = voxels[i]
        r = np.float64(radius[i]) * radius_scale
        b = np.float64(beta[v])
        for c in range(3):
            x = two_pi * r / wavelengths[c]
            q_abs = min(eight_thirds * x * k_abs[c] * n_term[c], 1.0)
            albedo_sum[v, c] = albedo_sum[v, c] + np.float32(((1.0 - q_abs / 2.0) - albedo_rgb[c]) * b)
