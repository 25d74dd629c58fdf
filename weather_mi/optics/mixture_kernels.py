"""The per-voxel optics of the species (Eq. 4, 5, 6, 8 and each voxel's albedo from its radius) in one compiled
pass over the grid (numba), with the same float32 (and, for the albedo of a radius, float64) operations in the
same order as the numpy expressions they replace (``optics.volume``'s images stay bit-identical; tested against
those expressions in tests/test_optics.py).

The pass reads each voxel's air density, mixing ratios and radii once and writes only what is kept: numpy took
about 50 passes over 4-byte grids for these, and on this machine most of the time of a large domain went to the
first touch of the fresh pages of its temporaries. The per-species grids and the total start as zeros (pages
the operating system maps on first write) and a voxel without mass writes nothing to them: the empty part of a
storm domain (most of it) is never touched there.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

GRID, SCALAR = 1, 0  # Eq. 4's radius: the voxel's own (a grid, the species' where <= 0) or the species' one


@njit(inline="always")
def _eq4(rho_v, q, r, s, v, mode, c3, denom, d2, rdef):  # pragma: no cover - compiled
    """Eq. 4 of species s at voxel v as ``Species.beta_ext_per_m(rho, q, r, out=...)`` computes it in float32:
    (rho (3 scale)) q, divided by 2 rho_p R (R the voxel's radius where > 0, else the species'; with ``mode``
    SCALAR, ``denom``: the species' 2 rho_p R)."""
    b = (rho_v * c3[s]) * q[s][v]
    if mode[s] == GRID:
        rr = r[s][v]
        return b / ((rr if rr > 0 else rdef[s]) * d2[s])
    return b / denom[s]


@njit(inline="always")
def _not_plus_zero(x):  # pragma: no cover - compiled
    """Whether float32 ``x`` differs from +0.0 in its bits (a -0.0 is written into a zeroed grid, a +0.0 not)."""
    return x != 0 or math.copysign(1.0, x) < 0


@njit(parallel=True, cache=True)
def voxel_optics(rho, q, r, mode, c3, denom, d2, rdef, rgb, mean_albedo, by_radius, radius_scale, wavelengths,
                 k_abs, n_term, albedo64, beta_ext, keep_beta, weights, keep_weights, beta_total,
                 albedo_sum):  # pragma: no cover - compiled
    """Per voxel v of the flat grids: beta_s (Eq. 4, as ``_eq4``) of each species s; beta_total = sum_s beta_s
    (Eq. 6, in species order); albedo_sum (N, 3) = sum_s beta_s omega_s (Eq. 5's numerator; written only where
    beta_total > 0) plus, for each species with ``by_radius``, (omega_c(r) - omega_s,c) beta_s where beta_s > 0
    and its radius r > 0 (the weak-absorption albedo of the voxel's radius, ``species.albedo_of_radius``: x = 2 pi
    r' / lambda, Q_abs = min(8/3 x k n_term, 1), omega = 1 - Q_abs / 2, r' = r radius_scale; in float64, added in
    float32 after the sum); weights (S, N) = beta_s w_s / sum_s beta_s w_s (Eq. 8, w_s the channel-mean albedo;
    0 where nothing scatters); beta_ext (S, N) = beta_s when ``keep_beta``.

    q, r: tuples of S flat float32 grids (r a 1-element placeholder where ``mode`` is SCALAR); beta_ext, weights
    and beta_total zeroed by the caller (what is +0.0 is not written); ``n_term``: n^3 - (n^2 - 1)^1.5."""
    n_s = len(q)
    n = rho.shape[0]
    two_pi, eight_thirds = 2.0 * np.pi, 8.0 / 3.0
    for v in prange(n):
        rho_v = rho[v]
        total = np.float32(0.0)
        sca = np.float32(0.0)
        for s in range(n_s):
            b = _eq4(rho_v, q, r, s, v, mode, c3, denom, d2, rdef)
            if keep_beta and _not_plus_zero(b):
                beta_ext[s, v] = b
            w = b * mean_albedo[s]
            total = b if s == 0 else total + b
            sca = w if s == 0 else sca + w
        if _not_plus_zero(total):
            beta_total[v] = total
        if not total > 0:
            continue  # no extinction: weights 0 (as zeroed), the albedo the volume's fill (``finish_albedo``)
        for c in range(3):
            acc = np.float32(0.0)
            for s in range(n_s):
                b = _eq4(rho_v, q, r, s, v, mode, c3, denom, d2, rdef)
                acc = b * rgb[s, c] if s == 0 else acc + b * rgb[s, c]
            albedo_sum[v, c] = acc
        for s in range(n_s):
            b = _eq4(rho_v, q, r, s, v, mode, c3, denom, d2, rdef)
            if keep_weights:
                w = (b * mean_albedo[s]) / sca if sca > 0 else np.float32(0.0)
                if _not_plus_zero(w):
                    weights[s, v] = w
            if by_radius[s] and b > 0 and r[s][v] > 0:
                rad = np.float64(r[s][v]) * radius_scale[s]
                b64 = np.float64(b)
                for c in range(3):
                    x = two_pi * rad / wavelengths[c]
                    q_abs = min(eight_thirds * x * k_abs[s, c] * n_term[s, c], 1.0)
                    albedo_sum[v, c] = albedo_sum[v, c] + np.float32(((1.0 - q_abs / 2.0) - albedo64[s, c]) * b64)


@njit(cache=True)
def albedo_sums(albedo_sum, beta_total):  # pragma: no cover - compiled
    """(3,) float64: sum over the voxels of albedo_sum (N, 3), in voxel order, as numpy's
    ``albedo_sum.sum(axis=0, dtype=np.float64)`` adds them (a sequential sum, tested), the voxels without
    extinction (whose sum is 0 and which ``voxel_optics`` leaves unwritten) skipped."""
    acc = np.zeros(3)
    for v in range(beta_total.shape[0]):
        if beta_total[v] > 0:
            for c in range(3):
                acc[c] += np.float64(albedo_sum[v, c])
    return acc


@njit(parallel=True, cache=True)
def finish_albedo(albedo, beta_total, fill):  # pragma: no cover - compiled
    """albedo (N, 3): albedo_sum / beta_total where there is extinction, ``fill`` (3,) elsewhere, clipped to
    [0, 1], in place."""
    for v in prange(beta_total.shape[0]):
        t = beta_total[v]
        for c in range(3):
            a = albedo[v, c] / t if t > 0 else fill[c]
            albedo[v, c] = min(max(a, np.float32(0.0)), np.float32(1.0))
