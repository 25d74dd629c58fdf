"""The per-voxel optics of the species (Eq. 4, 5, 6, 8 and each voxel's albedo from its radius) in one compiled
pass over the grid (numba), with the same float32 (and, for the albedo of a radius, float64) operations in the
same order as the numpy expressions they replace (``optics.volume``'s images stay bit-identical; tested against
those expressions in tests/test_optics.py).

The pass reads each voxel's air density, mixing ratios and radii once and writes only what is kept: numpy took
about 50 passes over 4-byte grids for these, and on this machine much of the time of a large domain went to the
first touch of the fresh pages of its temporaries. The per-species grids and the total start as zeros (pages the
operating system maps on first write) and a chunk of voxels without mass writes nothing to them: the empty part
of a storm domain is never touched there. The pass is serial: as a numba ``prange`` its loops over voxels did
not vectorise (3 times the CPU time of the serial loops, measured at 400 x 400 x 51), which two shared cores
do not win back.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

GRID, SCALAR = 1, 0  # Eq. 4's radius: the voxel's own (a grid, the species' where <= 0) or the species' one
CHUNK = 2048  # voxels the pass takes at a time (its scratch: 8 kB a species, 12 kB of albedo sums)


@njit(cache=True)
def _not_plus_zero(x):  # pragma: no cover - compiled
    """Whether float32 ``x`` differs from +0.0 in its bits (a -0.0 is written into a zeroed grid, a +0.0 not)."""
    return x != 0 or math.copysign(1.0, x) < 0


@njit(cache=True)
def _eq4(rho, q, r, mode, c3, denom, d2, rdef, lo, m, out):  # pragma: no cover - compiled
    """out[:m] = Eq. 4 of one species on voxels lo..lo+m, as ``Species.beta_ext_per_m(rho, q, r, out=...)``
    computes it in float32: (rho (3 scale)) q, divided by 2 rho_p R (R the voxel's radius where > 0, else the
    species' ``rdef``, times ``d2`` = 2 rho_p; with ``mode`` SCALAR, by ``denom``: the species' 2 rho_p R)."""
    if mode == GRID:
        for j in range(m):
            rr = r[lo + j]
            out[j] = ((rho[lo + j] * c3) * q[lo + j]) / ((rr if rr > 0 else rdef) * d2)
    else:
        for j in range(m):
            out[j] = ((rho[lo + j] * c3) * q[lo + j]) / denom


@njit(cache=True)
def _add_albedo_of_radius(b, r, lo, m, radius_scale, wavelengths, k_abs, n_term, albedo64,
                          acc):  # pragma: no cover - compiled
    """acc[c, j] += (omega_c(r) - omega_c) b where b > 0 and the voxel's radius r = r[lo + j] > 0: the
    weak-absorption albedo of the radius (``species.albedo_of_radius``: x = 2 pi r' / lambda, Q_abs =
    min(8/3 x k n_term, 1), omega = 1 - Q_abs / 2, r' = r radius_scale), in float64, added in float32."""
    two_pi, eight_thirds = 2.0 * np.pi, 8.0 / 3.0
    for c in range(3):
        a, wl, k, nt, alb = acc[c], wavelengths[c], k_abs[c], n_term[c], albedo64[c]
        for j in range(m):
            x = two_pi * (np.float64(r[lo + j]) * radius_scale) / wl
            q_abs = min(eight_thirds * x * k * nt, 1.0)
            term = np.float32(((1.0 - q_abs / 2.0) - alb) * np.float64(b[j]))
            a[j] = a[j] + term if b[j] > 0 and r[lo + j] > 0 else a[j]


@njit(cache=True)
def voxel_optics(rho, q, r, mode, c3, denom, d2, rdef, rgb, mean_albedo, by_radius, radius_scale, wavelengths,
                 k_abs, n_term, albedo64, beta_ext, keep_beta, weights, keep_weights, beta_total,
                 albedo_sum):  # pragma: no cover - compiled
    """Per voxel v of the flat grids: beta_s (Eq. 4, ``_eq4``) of each species s; beta_total = sum_s beta_s
    (Eq. 6, in species order); albedo_sum (N, 3) = sum_s beta_s omega_s (Eq. 5's numerator) plus, for each
    species with ``by_radius`` (in species order, after the sum), the difference the albedo of the voxel's
    radius makes (``_add_albedo_of_radius``); weights (S, N) = beta_s w_s / sum_s beta_s w_s (Eq. 8, w_s the
    channel-mean albedo; 0 where nothing scatters); beta_ext (S, N) = beta_s when ``keep_beta``.

    In chunks of CHUNK voxels, species by species (the loops over voxels vectorise). q, r: tuples of S flat
    float32 grids (r a 1-element placeholder where ``mode`` is SCALAR); beta_ext, weights and beta_total zeroed
    by the caller: a chunk whose values are all +0.0 there is not written (its pages stay untouched);
    ``n_term``: n^3 - (n^2 - 1)^1.5."""
    n_s = len(q)
    n = rho.shape[0]
    b = np.empty((n_s, CHUNK), np.float32)
    total = np.empty(CHUNK, np.float32)
    sca = np.empty(CHUNK, np.float32)
    acc = np.empty((3, CHUNK), np.float32)
    has = np.zeros(n_s, np.bool_)  # species s has a value other than +0.0 in the chunk
    for chunk in range((n + CHUNK - 1) // CHUNK):
        lo = chunk * CHUNK
        m = min(CHUNK, n - lo)
        any_mass = False
        for s in range(n_s):
            bs = b[s]
            _eq4(rho, q[s], r[s], mode[s], c3[s], denom[s], d2[s], rdef[s], lo, m, bs)
            ma, col0, col1, col2 = mean_albedo[s], rgb[s, 0], rgb[s, 1], rgb[s, 2]
            nz = False
            if s == 0:
                for j in range(m):
                    x = bs[j]
                    total[j], sca[j] = x, x * ma
                    acc[0, j], acc[1, j], acc[2, j] = x * col0, x * col1, x * col2
                    nz = nz | _not_plus_zero(x)
            else:
                for j in range(m):
                    x = bs[j]
                    total[j], sca[j] = total[j] + x, sca[j] + x * ma
                    acc[0, j], acc[1, j], acc[2, j] = acc[0, j] + x * col0, acc[1, j] + x * col1, acc[2, j] + x * col2
                    nz = nz | _not_plus_zero(x)
            has[s] = nz
            any_mass = any_mass | nz
            if keep_beta and nz:
                for j in range(m):
                    beta_ext[s, lo + j] = bs[j]
        if not any_mass:
            continue  # total, weights 0 (as zeroed); the albedo the volume's fill (``finish_albedo``)
        for j in range(m):
            beta_total[lo + j] = total[j]
        for s in range(n_s):
            bs = b[s]
            if keep_weights and has[s]:
                ma = mean_albedo[s]
                for j in range(m):
                    weights[s, lo + j] = (bs[j] * ma) / sca[j] if sca[j] > 0 else np.float32(0.0)
            if by_radius[s] and has[s]:
                _add_albedo_of_radius(bs, r[s], lo, m, radius_scale[s], wavelengths, k_abs[s], n_term[s],
                                      albedo64[s], acc)
        for j in range(m):
            for c in range(3):
                albedo_sum[lo + j, c] = acc[c, j]


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


@njit(cache=True)
def finish_albedo(albedo, beta_total, fill):  # pragma: no cover - compiled
    """albedo (N, 3): albedo_sum / beta_total where there is extinction, ``fill`` (3,) elsewhere, clipped to
    [0, 1], in place."""
    for v in range(beta_total.shape[0]):
        t = beta_total[v]
        for c in range(3):
            a = albedo[v, c] / t if t > 0 else fill[c]
            albedo[v, c] = min(max(a, np.float32(0.0)), np.float32(1.0))
