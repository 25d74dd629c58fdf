"""Mie phase functions of water drops (miepython), averaged over a gamma size distribution.

Size distribution (Hansen & Travis 1974): n(r) ~ r^((1 - 3 v)/v) exp(-r / (a v)), effective radius
a = r_eff = <r^3>/<r^2>, effective variance v = v_eff. This is a gamma distribution of shape
alpha + 1 = (1 - 2 v)/v and scale b = a v; weighted by geometric area r^2 it is a gamma of shape
alpha + 3.

Distribution phase function, weighted by the scattering cross-section:

    p(theta) = integral n(r) dC_sca/dOmega(theta, r) dr / integral n(r) C_sca(r) dr,
    dC_sca/dOmega = (|S1|^2 + |S2|^2) / (2 k^2),   k = 2 pi / lambda

(S1, S2 unnormalised amplitudes, miepython norm="wiscombe"). The r-integral is a stratified
quantile rule over the area-weighted distribution: radii r_i at the midpoints of N equal-probability
bins of r^2 n(r), each with weight 1/r_i^2 (so the sum estimates integral n dC/dOmega dr).
The denominator is fixed by normalising the table numerically.

Refractive indices of water (Hale & Querry 1973), m = n - i k as miepython expects:
650 nm 1.331 - 1.6e-8 i, 550 nm 1.333 - 2.0e-9 i, 450 nm 1.337 - 1.0e-9 i.
"""
from __future__ import annotations

import os

import numpy as np

from .cache import cached_table
from .table import RGB_WAVELENGTHS_M, PhaseTable, angle_grid

# numba-compiled miepython (x = 11400 in ~0.3 s instead of minutes); must precede its first import.
# An explicit MIEPYTHON_USE_JIT=0 from the user is respected.
os.environ.setdefault("MIEPYTHON_USE_JIT", "1")

# complex refractive index n - i k per channel wavelength (R, G, B)
WATER_M = {650e-9: 1.331 - 1.6e-8j, 550e-9: 1.333 - 2.0e-9j, 450e-9: 1.337 - 1.0e-9j}

# Hale & Querry (1973, Appl. Opt. 12, 555) refractive index of liquid water n, k at 25 C (their Table 1; the
# values as transcribed by refractiveindex.info, database/data/main/H2O/nk/Hale.yml, CC0 1.0 / public domain):
# wavelength (m), n, k; ``water_index`` interpolates (n linearly, k log-linearly) for single-band tables and the
# spectral mode's tables (``spectral_tables``, 360-830 nm). The rows below 450 nm serve the spectral mode only.
WATER_HALE_QUERRY = ((350e-9, 1.343, 6.50e-9), (375e-9, 1.341, 3.50e-9), (400e-9, 1.339, 1.86e-9),
                     (425e-9, 1.338, 1.30e-9), (450e-9, 1.337, 1.02e-9), (475e-9, 1.336, 9.35e-10),
                     (500e-9, 1.335, 1.00e-9),
                     (525e-9, 1.334, 1.32e-9), (550e-9, 1.333, 1.96e-9), (575e-9, 1.333, 3.60e-9),
                     (600e-9, 1.332, 1.09e-8), (625e-9, 1.332, 1.39e-8), (650e-9, 1.331, 1.64e-8),
                     (675e-9, 1.331, 2.23e-8), (700e-9, 1.331, 3.35e-8), (725e-9, 1.330, 9.15e-8),
                     (750e-9, 1.330, 1.56e-7), (775e-9, 1.330, 1.48e-7), (800e-9, 1.329, 1.25e-7),
                     (825e-9, 1.329, 1.82e-7), (850e-9, 1.329, 2.93e-7), (875e-9, 1.328, 3.91e-7),
                     (900e-9, 1.328, 4.86e-7))

# quality -> number of radii per wavelength
CLOUD_SIZES = {"test": 200, "default": 600, "high": 2000}
RAIN_SIZES = {"test": 6, "default": 32, "high": 96}


def _rain_grid(quality: str) -> np.ndarray:
    """Angle nodes for rain: the default grid; "test" keeps 0.1 deg from 120 to 180 deg (bows) but
    thins the forward and middle ranges (about half the nodes, half the cost)."""
    if quality == "test":
        return angle_grid(n_forward=60, middle_step_deg=1.0)
    return angle_grid()


def water_index(wavelength_m: float) -> complex:
    """Complex refractive index n - i k of liquid water at ``wavelength_m`` (350-900 nm, Hale & Querry 1973)."""
    wl, n, k = (np.array(c, np.float64) for c in zip(*WATER_HALE_QUERRY))
    lam = float(wavelength_m)
    if not wl[0] <= lam <= wl[-1]:
        raise ValueError(f"water refractive index tabulated for {wl[0] * 1e9:.0f}-{wl[-1] * 1e9:.0f} nm, "
                         f"got {lam * 1e9:.1f} nm")
    return complex(np.interp(lam, wl, n), -np.exp(np.interp(lam, wl, np.log(k))))


def _channels(wavelength_m):
    """(wavelength, refractive index) of the three channels: R, G, B, or one band's in all three."""
    if wavelength_m is None:
        return [(wl, WATER_M[wl]) for wl in RGB_WAVELENGTHS_M]
    return [(float(wavelength_m), water_index(wavelength_m))] * 3


def _miepython():
    """miepython, imported on first use (it takes seconds); warns when it runs without numba."""
    import miepython
    if not miepython.USE_JIT:
        import warnings
        warnings.warn("miepython was imported without MIEPYTHON_USE_JIT=1 before weather_mi.optics.phase; "
                      "large drops will take minutes", RuntimeWarning, stacklevel=3)
    return miepython


def _quality(q: str, table: dict) -> int:
    if q not in table:
        raise ValueError(f"quality must be one of {', '.join(map(repr, table))}, got {q!r}")
    return table[q]


def gamma_area_quantile_radii(r_eff: float, v_eff: float, n: int) -> np.ndarray:
    """Radii (m) at the midpoints of ``n`` equal-probability bins of the area-weighted gamma
    distribution r^2 n(r), n(r) ~ r^((1-3v)/v) exp(-r/(r_eff v)): shape (1 - 2v)/v + 2, scale r_eff v."""
    from scipy.stats import gamma
    if not (r_eff > 0 and 0 < v_eff < 0.5):
        raise ValueError(f"need r_eff > 0 and 0 < v_eff < 0.5, got r_eff={r_eff!r}, v_eff={v_eff!r}")
    shape = (1 - 2 * v_eff) / v_eff + 2
    return gamma.ppf((np.arange(n) + 0.5) / n, shape, scale=r_eff * v_eff)


def _distribution_phase(radii, wavelength_m, m, theta_nodes, offsets=None, progress=None):
    """Unnormalised sum_i dC_sca/dOmega(theta; r_i) / r_i^2 at theta_nodes (per-size angle offsets
    ``offsets[i]`` (N,) in radians, if given, are added to the evaluation angles)."""
    mp = _miepython()
    k = 2 * np.pi / wavelength_m
    acc = np.zeros(theta_nodes.size)
    for i, r in enumerate(radii):
        th = theta_nodes if offsets is None else np.clip(theta_nodes + offsets[i], 0.0, np.pi)
        s1, s2 = mp.S1_S2(m, k * r, np.cos(th), norm="wiscombe")
        acc += 0.5 * (np.abs(s1) ** 2 + np.abs(s2) ** 2) / k ** 2 / r ** 2
        if progress is not None:
            progress.update(1)
    return acc


def _progress(total: int, desc: str, enable: bool):
    from tqdm.auto import tqdm
    return tqdm(total=total, desc=desc, unit="size", leave=False, disable=not enable)


def _per_channel(theta, wavelength_m, one_channel) -> np.ndarray:
    """(N, 3) values of ``one_channel(wavelength, refractive index)`` per channel (``_channels``); one band's
    single wavelength is computed once and copied to the three channels."""
    channels = _channels(wavelength_m)
    values = np.empty((theta.size, 3))
    for c, (wl, m) in enumerate(channels):
        values[:, c] = values[:, c - 1] if c and channels[c] == channels[c - 1] else one_channel(wl, m)
    return values


def _compute_cloud(r_eff, v_eff, n_sizes, theta, wavelength_m=None):
    radii = gamma_area_quantile_radii(r_eff, v_eff, n_sizes)
    with _progress(3 * n_sizes, "Mie cloud", n_sizes >= 300) as bar:
        return _per_channel(theta, wavelength_m, lambda wl, m: _distribution_phase(radii, wl, m, theta, progress=bar))


def _band_params(params: dict, wavelength_m) -> dict:
    """Cache parameters, with the band's wavelength where one is given (RGB tables keep their old keys)."""
    return params if wavelength_m is None else {**params, "wavelength_m": float(wavelength_m)}


def _table(theta, values, name: str, wavelength_m) -> PhaseTable:
    """A Mie table named ``name(...)``, of R, G, B or of one band (its wavelength in the name and channels)."""
    if wavelength_m is None:
        return PhaseTable.from_values(theta, values, name=f"{name})")
    return PhaseTable.from_values(theta, values, name=f"{name}, {wavelength_m * 1e9:.0f} nm)",
                                  wavelengths_m=(float(wavelength_m),) * 3)


def mie_cloud(r_eff: float = 10e-6, v_eff: float = 0.1, *, quality: str = "default",
              theta=None, cache: bool = True, wavelength_m: float | None = None) -> PhaseTable:
    """Cloud droplets: Mie theory averaged over a gamma distribution (r_eff in m, v_eff), at the
    R, G, B wavelengths 650 / 550 / 450 nm, or at one band's ``wavelength_m`` in all three channels
    (refractive index ``water_index``). ``quality`` "test" (200 radii per wavelength, ~2 s),
    "default" (600, ~10 s) or "high" (2000, ~35 s). For r_eff = 10 um, v_eff = 0.1: g ~ 0.86, 4 pi p(0) ~ 7400 at
    550 nm. Cached on disk (see :mod:`weather_mi.optics.phase.cache`)."""
    n_sizes = _quality(quality, CLOUD_SIZES)
    th = angle_grid() if theta is None else np.asarray(theta, np.float64)
    params = _band_params({"r_eff": float(r_eff), "v_eff": float(v_eff), "n_sizes": n_sizes, "theta": th},
                          wavelength_m)

    def compute():
        return _table(th, _compute_cloud(float(r_eff), float(v_eff), n_sizes, th, wavelength_m),
                      f"mie_cloud(r_eff={r_eff:g}, v_eff={v_eff:g}", wavelength_m)

    return cached_table("mie_cloud", params, compute, use_cache=cache)


def _stratified_offsets(theta: np.ndarray, n: int) -> np.ndarray:
    """(n, N) angle offsets: for size i, node j is evaluated at theta_j + (s_i - 1/2) h_j with
    h_j the local node spacing and s_i a scrambled stratified sequence in (0, 1). Averaged over the
    sizes this is a box filter of width h_j, which removes the high-frequency interference ripple
    (period ~ lambda / (2 r), 0.016 deg for 1 mm drops) that point samples would alias. The end
    nodes 0 and pi are evaluated exactly."""
    h = np.empty_like(theta)
    h[1:-1] = 0.5 * (theta[2:] - theta[:-2])
    h[0] = h[-1] = 0.0
    s = (np.arange(n) + 0.5) / n
    s = s[np.argsort((np.arange(n) * 0.6180339887498949) % 1.0)]  # decorrelate offset from radius
    return (s - 0.5)[:, None] * h[None, :]


def _compute_rain(radius, v_eff, n_sizes, theta, progress, wavelength_m=None):
    radii = gamma_area_quantile_radii(radius, v_eff, n_sizes)
    offsets = _stratified_offsets(theta, n_sizes)
    with _progress(3 * n_sizes, "Mie rain", progress) as bar:
        return _per_channel(theta, wavelength_m,
                            lambda wl, m: _distribution_phase(radii, wl, m, theta, offsets, progress=bar))


def mie_rain(radius: float = 1e-3, *, v_eff: float = 0.003, quality: str = "default", theta=None,
             cache: bool = True, wavelength_m: float | None = None) -> PhaseTable:
    """Raindrops of effective radius ``radius`` (m): Mie theory (size parameter ~11400 for 1 mm at
    550 nm) over a narrow gamma distribution (v_eff = 0.003: relative standard deviation ~5.5 %)
    so that single-size ripple averages out, plus a per-size stratified angle offset within each
    node's spacing (a box filter against aliasing of the 0.016 deg interference ripple). The grid
    is <= 0.1 deg from 120 to 180 deg, resolving the primary (~138 deg) and secondary (~129 deg)
    bows. ``quality``: "test" (6 radii per wavelength on a thinned grid, ~3 s), "default" (32,
    ~30 s) or "high" (96, ~100 s). Drops are spheres (real large drops flatten, which shifts and
    weakens the bows; not modelled). ``wavelength_m``: one band's wavelength in all three channels
    (as ``mie_cloud``). Cached on disk."""
    n_sizes = _quality(quality, RAIN_SIZES)
    th = _rain_grid(quality) if theta is None else np.asarray(theta, np.float64)
    params = _band_params({"radius": float(radius), "v_eff": float(v_eff), "n_sizes": n_sizes, "theta": th},
                          wavelength_m)

    def compute():
        est_s = 3 * n_sizes * th.size * radius / 1e-3 * 1.6e-4  # ~0.23 s per size per 1400 angles at 1 mm
        values = _compute_rain(float(radius), float(v_eff), n_sizes, th, est_s > 3, wavelength_m)
        return _table(th, values, f"mie_rain(radius={radius:g}, v_eff={v_eff:g}", wavelength_m)

    return cached_table("mie_rain", params, compute, use_cache=cache)


__all__ = ["mie_cloud", "mie_rain", "WATER_M", "water_index", "gamma_area_quantile_radii"]
