"""The two marches through the air, compiled (numba): the slant columns of the sun's path through the shell
(``shell.slant_columns``) and the single scattering along an eye ray's segment (``eye_path.segment_air``).
Each is the same trapezoidal sum on the same points as the numpy expressions it replaces (so the results agree
to float rounding, apart from ``segment_air``'s profiles, linear on a 1 m grid: within 1e-7); numpy spent most
of its time on (rays x samples x channels) temporaries, about 1 s for a satellite view's few thousand lines of
sight (``satellite.air``) and the sun's tables of every render with the air."""
from __future__ import annotations

import numpy as np
from numba import njit, prange

# points x samples below which a march runs on the calling thread alone (its serial kernel): waking the thread pool
# (OpenMP) for a parallel region cost 40-100 ms on a loaded 2-core machine against 0.7 ms for the slicer's per-frame
# sun column (129 heights x 128 samples) on one thread (the same numbers: every point is summed alone)
SERIAL_WORK = 1 << 17


@njit(cache=True)
def _node(z, z0, dz, n):  # pragma: no cover - compiled
    """(j, z - z_j) of np.interp on the uniform grid z0 + dz * arange(n): j = -1 below it, n - 1 above it."""
    f = (z - z0) / dz
    if f <= 0.0:
        return -1, 0.0
    if f >= n - 1:
        return n - 1, 0.0
    j = min(int(f), n - 2)
    return j, z - (z0 + dz * j)


@njit(cache=True)
def _at(values, j, off, dz):  # pragma: no cover - compiled
    """np.interp's value at the ``_node`` (j, off) (clamped to the ends)."""
    if j < 0:
        return values[0]
    if j >= values.shape[0] - 1:
        return values[values.shape[0] - 1]
    return (values[j + 1] - values[j]) / dz * off + values[j]


@njit(cache=True)
def _column(profiles, z0, dz, r0, mu, s_a, s_b, radius_m, top_m, t, out, i):  # pragma: no cover - compiled
    """Adds |trapezoid(profile(z(s)), s)| over s = s_a + (s_b - s_a) t^2 of the ray at radius r0, cos(zenith)
    mu to out[:, i] (``shell._segment``)."""
    n_p, k = profiles.shape[0], t.shape[0]
    if s_a == s_b:  # an empty segment (a sun above the horizon: none before the point) adds 0
        return
    acc = np.zeros(n_p)
    prev = np.zeros(n_p)
    s_prev = 0.0
    for m in range(k):
        s = s_a + (s_b - s_a) * t[m] * t[m]
        r2 = r0 * r0 + 2.0 * (r0 * mu) * s + s * s
        z = min(max(np.sqrt(max(r2, 0.0)) - radius_m, 0.0), top_m)
        j, off = _node(z, z0, dz, profiles.shape[1])
        for p in range(n_p):
            v = _at(profiles[p], j, off, dz)
            if m > 0:
                acc[p] += (s - s_prev) * (v + prev[p]) / 2.0
            prev[p] = v
        s_prev = s
    for p in range(n_p):
        out[p, i] += abs(acc[p])


@njit(cache=True)
def _columns_of(profiles, z0, dz, r0, mu, s_star, s_top, blocked, radius_m, top_m, t, out, i):  # pragma: no cover
    """Point i's columns into out[:, i]: from the lowest point back to the point (none where the sun is above
    the horizon: s_star = 0, a segment of length 0 that adds 0), then from it to the top."""
    if blocked[i]:
        return
    if s_star[i] != 0.0:
        _column(profiles, z0, dz, r0[i], mu[i], s_star[i], 0.0, radius_m, top_m, t, out, i)
    _column(profiles, z0, dz, r0[i], mu[i], s_star[i], s_top[i], radius_m, top_m, t, out, i)


@njit(parallel=True, cache=True)
def _slant_columns_parallel(profiles, z0, dz, r0, mu, s_star, s_top, blocked, radius_m, top_m, t):  # pragma: no cover
    out = np.zeros((profiles.shape[0], r0.shape[0]))
    for i in prange(r0.shape[0]):
        _columns_of(profiles, z0, dz, r0, mu, s_star, s_top, blocked, radius_m, top_m, t, out, i)
    return out


@njit(cache=True)
def _slant_columns_serial(profiles, z0, dz, r0, mu, s_star, s_top, blocked, radius_m, top_m, t):  # pragma: no cover
    out = np.zeros((profiles.shape[0], r0.shape[0]))
    for i in range(r0.shape[0]):
        _columns_of(profiles, z0, dz, r0, mu, s_star, s_top, blocked, radius_m, top_m, t, out, i)
    return out


def slant_columns(profiles, z0, dz, r0, mu, s_star, s_top, blocked, radius_m, top_m, t):
    """Columns (n_profiles, n) of ``profiles`` (n_profiles, n_z; on heights z0 + dz * arange(n_z)) from the points
    at radius r0 (n,) towards cos(zenith) mu (n,): from the lowest point s_star back to the point and from it to
    the top s_top, each on s_star +- L t^2; 0 where ``blocked``. The same floats on one thread or several."""
    run = _slant_columns_parallel if r0.shape[0] * t.shape[0] >= SERIAL_WORK else _slant_columns_serial
    return run(profiles, z0, dz, r0, mu, s_star, s_top, blocked, radius_m, top_m, t)


@njit(cache=True)
def _cell(v, grid):  # pragma: no cover - compiled
    """``sunlight.SunAirTable.at``'s (index, fraction) of v on the uniform ``grid`` (clamped)."""
    f = min(max((v - grid[0]) / (grid[-1] - grid[0]), 0.0), 1.0) * (grid.shape[0] - 1)
    i = min(int(np.floor(f)), grid.shape[0] - 2)
    return i, f - i


@njit(cache=True)
def _table_at(tab, ih, fh, im, fm, c):  # pragma: no cover - compiled
    """``sunlight.SunAirTable.at`` of channel c at the cells (ih, fh), (im, fm) (bilinear; ``tab`` float64)."""
    lo = tab[im, ih, c] * (1 - fh) + tab[im, ih + 1, c] * fh
    hi = tab[im + 1, ih, c] * (1 - fh) + tab[im + 1, ih + 1, c] * fh
    return lo * (1 - fm) + hi * fm


@njit(parallel=True, cache=True)
def segment_air(o, d, t0, length, sun, x, z0, dz, profiles, sigma_r, sigma_o, aerosol_factor, aerosol_ssa,
                p_r, p_hg, tab_h, tab_mu, tab, shadow, radius_m):  # pragma: no cover - compiled
    """(T (n, c), S (n, c)) of ``eye_path.segment_air``: the rays o + s d (n, 3) over s = t0 + length x^2 (x the
    unit samples (k,)); ``profiles`` (3, n_z): air, ozone (per m^3), aerosol extinction at 550 nm (1/m) on
    heights z0 + dz * arange(n_z); per channel (c,): the molecules' and ozone's cross sections (m^2), the
    aerosol's Angstrom factor; per ray: Rayleigh's and Henyey-Greenstein's phase function (1/sr); ``tab``
    (n_mu, n_h, c): the sun's table; ``shadow`` (n, k) a factor on it, or (0, 0): none."""
    n, k, n_c = o.shape[0], x.shape[0], sigma_r.shape[0]
    trans, inscatter = np.ones((n, n_c)), np.zeros((n, n_c))
    has_shadow = shadow.shape[0] > 0
    for i in prange(n):
        tau, prev_ext, prev_src = np.zeros(n_c), np.zeros(n_c), np.zeros(n_c)
        acc = np.zeros(n_c)
        s_prev = 0.0
        for m in range(k):
            s = t0[i] + length[i] * x[m] * x[m]
            q0, q1, q2 = o[i, 0] + s * d[i, 0], o[i, 1] + s * d[i, 1], o[i, 2] + s * d[i, 2] + radius_m
            r = np.sqrt(q0 * q0 + q1 * q1 + q2 * q2)
            h = max(r - radius_m, 0.0)
            mu = (q0 * sun[0] + q1 * sun[1] + q2 * sun[2]) / r
            j, off = _node(h, z0, dz, profiles.shape[1])
            n_air, n_o3, b_a = _at(profiles[0], j, off, dz), _at(profiles[1], j, off, dz), _at(profiles[2], j, off, dz)
            (ih, fh), (im, fm) = _cell(h, tab_h), _cell(mu, tab_mu)
            lit = shadow[i, m] if has_shadow else 1.0
            for c in range(n_c):
                beta_r, beta_a = n_air * sigma_r[c], b_a * aerosol_factor[c]
                ext = beta_r + beta_a + n_o3 * sigma_o[c]
                if m > 0:
                    tau[c] += 0.5 * (ext + prev_ext[c]) * (s - s_prev)
                src = (beta_r * p_r[i] + aerosol_ssa * beta_a * p_hg[i]) * _table_at(tab, ih, fh, im, fm, c) \
                    * np.exp(-tau[c]) * lit
                if m > 0:
                    acc[c] += 0.5 * (src + prev_src[c]) * (s - s_prev)
                prev_ext[c], prev_src[c] = ext, src
            s_prev = s
        for c in range(n_c):
            trans[i, c] = np.exp(-tau[c])
            inscatter[i, c] = acc[c]
    return trans, inscatter


__all__ = ["SERIAL_WORK", "slant_columns", "segment_air"]
