"""The per-voxel optics of the species (Eq. 4, 5, 6, 8 and each voxel's albedo from its radius) in compiled
passes over the grid (numba), with the same float32 (and, for the albedo of a radius, float64) operations in the
same order as the numpy expressions they replace (``optics.volume``'s images stay bit-identical; tested against
those expressions in tests/test_optics.py).

``species_pass`` takes one species at a time (Eq. 4 into the total and the albedo's numerator, in species
order), so that the caller frees each species' mixing ratio and radii before it reads the next: one pass over
all species at once held every input together with all the outputs (``render`` 84 -> 77 and ``view`` 85 -> 76
bytes per cell at the peak on 800 x 800 x 51, benchmarks/README.md). ``mixture_pass`` then gives the Eq. 8
weights and the albedo of each voxel's radius from the beta_s kept in the weights' (or beta_ext's) own grid and
the radii of the voxels with extinction.
numpy took about 50 passes over 4-byte grids for these, and on this machine much of the time of a large domain
went to the first touch of the fresh pages of its temporaries. The per-species grids and the total start as
zeros (pages the operating system maps on first write) and a chunk of voxels without mass writes nothing to
them: the empty part of a storm domain is never touched there. The passes are serial: as a numba ``prange`` the
loops over voxels did not vectorise (3 times the CPU time of the serial loops, measured at 400 x 400 x 51), which
two shared cores do not win back.
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
    """out[:m] = Eq. 4 of one species on voxels lo..lo+m, as numpy's float32 expression of it (``eq4_factors``;
    ``eq4_grid`` on a whole grid): (rho (3 scale)) q, divided by 2 rho_p R (R the voxel's radius where > 0, else the
    species' ``rdef``, times ``d2`` = 2 rho_p; with ``mode`` SCALAR, by ``denom``: the species' 2 rho_p R)."""
    if mode == GRID:
        for j in range(m):
            rr = r[lo + j]
            out[j] = ((rho[lo + j] * c3) * q[lo + j]) / ((rr if rr > 0 else rdef) * d2)
    else:
        for j in range(m):
            out[j] = ((rho[lo + j] * c3) * q[lo + j]) / denom


def eq4_factors(scale: float, density_kg_m3: float, radius_m: float) -> tuple:
    """Eq. 4's float32 factors of a species, as numpy rounds them in ``3 scale rho q / (2 rho_p R)``: (3 scale,
    2 rho_p R, 2 rho_p, R), the last two for a radius per voxel (``_eq4``'s ``d2`` and ``rdef``)."""
    return (np.float32(scale * 3.0), np.float32(2.0 * density_kg_m3 * radius_m), np.float32(2.0 * density_kg_m3),
            np.float32(radius_m))


def eq4_grid(rho, q, radius_m, scale: float, density_kg_m3: float, default_radius_m: float,
             out: np.ndarray) -> np.ndarray:
    """``out`` (a float32 grid of the inputs' shape) = Eq. 4 of one species (1/m), ``_eq4`` over the whole grid:
    rho (kg/m^3) and q (kg/kg) float32 grids, ``radius_m`` one radius (m) or a grid of them (a voxel's radius
    <= 0 replaced by ``default_radius_m``)."""
    grid = np.ndim(radius_m) != 0
    c3, denom, d2, rdef = eq4_factors(scale, density_kg_m3, default_radius_m if grid else radius_m)
    rho, q, r = (np.ascontiguousarray(np.broadcast_to(np.asarray(a, np.float32), out.shape)).reshape(-1)
                 for a in (rho, q, radius_m if grid else 0.0))
    dest = out.reshape(-1) if out.flags.c_contiguous else np.empty(out.size, np.float32)
    _eq4(rho, q, r, GRID if grid else SCALAR, c3, denom, d2, rdef, 0, dest.size, dest)
    if not out.flags.c_contiguous:
        out[...] = dest.reshape(out.shape)
    return out


@njit(cache=True)
def species_pass(rho, q, r, mode, c3, denom, d2, rdef, col, ma, first, keep_beta, beta_ext, keep_store, store,
                 beta_total, albedo_sum, touched, has):  # pragma: no cover - compiled
    """One species' part of the mixture, species after species (its q and r can go before the next is read):
    beta_s (Eq. 4, ``_eq4``) added to beta_total (Eq. 6) and beta_s col (the species' albedo, N, 3) to
    albedo_sum (Eq. 5's numerator), chunk by chunk of CHUNK voxels, with the float32 operations of the mixture
    in voxel order: the first species (``first``) sets them, a later one adds to them where an earlier species
    or this one has a value other than +0.0 in the chunk (``touched``, per chunk, updated); beta_s written to
    ``beta_ext`` (``keep_beta``) and ``store`` (``keep_store``: the rows ``mixture_pass`` reads back) where the
    species has such a value in the chunk (``has``, per chunk, set). The grids are zeroed by the caller: a chunk
    of +0.0 everywhere so far is never written (its pages stay untouched)."""
    n = rho.shape[0]
    b = np.empty(CHUNK, np.float32)
    c0, c1, c2 = col[0], col[1], col[2]
    for chunk in range((n + CHUNK - 1) // CHUNK):
        lo = chunk * CHUNK
        m = min(CHUNK, n - lo)
        _eq4(rho, q, r, mode, c3, denom, d2, rdef, lo, m, b)
        nz = False
        for j in range(m):
            nz = nz | _not_plus_zero(b[j])
        has[chunk] = nz
        if first and nz:
            for j in range(m):
                x = b[j]
                beta_total[lo + j] = x
                albedo_sum[lo + j, 0], albedo_sum[lo + j, 1], albedo_sum[lo + j, 2] = x * c0, x * c1, x * c2
        elif touched[chunk] and not nz:  # + (+0.0) changes only a -0.0 (to +0.0)
            for j in range(m):
                v = lo + j
                if beta_total[v] == 0:
                    beta_total[v] = beta_total[v] + np.float32(0.0)
                for c in range(3):
                    if albedo_sum[v, c] == 0:
                        albedo_sum[v, c] = albedo_sum[v, c] + np.float32(0.0)
        elif nz or touched[chunk]:
            for j in range(m):
                x, v = b[j], lo + j
                beta_total[v] = beta_total[v] + x
                albedo_sum[v, 0] = albedo_sum[v, 0] + x * c0
                albedo_sum[v, 1] = albedo_sum[v, 1] + x * c1
                albedo_sum[v, 2] = albedo_sum[v, 2] + x * c2
        touched[chunk] = touched[chunk] | nz
        if nz:
            if keep_beta:
                beta_ext[lo:lo + m] = b[:m]
            if keep_store:
                store[lo:lo + m] = b[:m]


@njit(cache=True)
def radii_with_extinction(beta, r, has):  # pragma: no cover - compiled
    """The radii r[v] of the voxels with beta[v] > 0, in voxel order (float32): all ``mixture_pass`` needs of a
    species' radius grid once the grid itself is gone (only the chunks of CHUNK voxels where ``has`` is read)."""
    n = beta.shape[0]
    count = 0
    for chunk in range(has.shape[0]):
        if has[chunk]:
            for v in range(chunk * CHUNK, min(chunk * CHUNK + CHUNK, n)):
                count += beta[v] > 0
    out = np.empty(count, np.float32)
    i = 0
    for chunk in range(has.shape[0]):
        if has[chunk]:
            for v in range(chunk * CHUNK, min(chunk * CHUNK + CHUNK, n)):
                if beta[v] > 0:
                    out[i] = r[v]
                    i += 1
    return out


@njit(cache=True)
def _add_albedo_of_radius(b, radii, cursor, m, radius_scale, wavelengths, k_abs, n_term, albedo64,
                          acc):  # pragma: no cover - compiled
    """acc[c, j] += (omega_c(r) - omega_c) b where b = b[j] > 0 and the voxel's radius r > 0 (r the next of
    ``radii``, the radii of the voxels with b > 0 in voxel order, from ``cursor``): the weak-absorption albedo of
    the radius (``species.albedo_of_radius``: x = 2 pi r' / lambda, Q_abs = min(8/3 x k n_term, 1),
    omega = 1 - Q_abs / 2, r' = r radius_scale), in float64, added in float32. Returns the cursor after the
    chunk."""
    two_pi, eight_thirds = 2.0 * np.pi, 8.0 / 3.0
    for j in range(m):
        if b[j] > 0:
            rr = radii[cursor]
            cursor += 1
            if rr > 0:
                for c in range(3):
                    x = two_pi * (np.float64(rr) * radius_scale) / wavelengths[c]
                    q_abs = min(eight_thirds * x * k_abs[c] * n_term[c], 1.0)
                    acc[c, j] = acc[c, j] + np.float32(((1.0 - q_abs / 2.0) - albedo64[c]) * np.float64(b[j]))
    return cursor


@njit(cache=True)
def mixture_pass(store, mean_albedo, keep_weights, weights, by_radius, radii, radius_scale, wavelengths, k_abs,
                 n_term, albedo64, albedo_sum, touched, has):  # pragma: no cover - compiled
    """After ``species_pass`` of every species: weights (S, N) = beta_s w_s / sum_s beta_s w_s (Eq. 8, w_s
    the channel-mean albedo, the sum in species order; 0 where nothing scatters) from the species' beta_s in
    ``store`` (S, N; it may be ``weights`` itself: each chunk is read before it is overwritten), and, for each
    species with ``by_radius`` in species order, the difference the albedo of the voxel's radius makes added to
    albedo_sum (``_add_albedo_of_radius``; ``radii[s]``: ``radii_with_extinction``). Chunks that no species
    touched are skipped (weights 0 as zeroed; the albedo the volume's fill, ``finish_albedo``)."""
    n_s, n = store.shape[0], store.shape[1]
    b = np.empty((n_s, CHUNK), np.float32)
    sca = np.empty(CHUNK, np.float32)
    acc = np.empty((3, CHUNK), np.float32)
    cursor = np.zeros(n_s, np.int64)
    for chunk in range((n + CHUNK - 1) // CHUNK):
        if not touched[chunk]:
            continue
        lo = chunk * CHUNK
        m = min(CHUNK, n - lo)
        for s in range(n_s):
            ma = mean_albedo[s]
            for j in range(m):
                x = store[s, lo + j]
                b[s, j] = x
                sca[j] = x * ma if s == 0 else sca[j] + x * ma
        for j in range(m):
            for c in range(3):
                acc[c, j] = albedo_sum[lo + j, c]
        for s in range(n_s):
            if not has[s, chunk]:
                continue
            if keep_weights:
                ma = mean_albedo[s]
                for j in range(m):
                    weights[s, lo + j] = (b[s, j] * ma) / sca[j] if sca[j] > 0 else np.float32(0.0)
            if by_radius[s]:
                cursor[s] = _add_albedo_of_radius(b[s], radii[s], cursor[s], m, radius_scale[s], wavelengths,
                                                  k_abs[s], n_term[s], albedo64[s], acc)
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
