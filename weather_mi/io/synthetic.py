"""Procedural demo storms: the built-in default input of every command (docs/design.md).

Two deterministic storms built from smooth analytic shapes plus seeded multi-scale noise, returned as
Hydrometeors (:func:`weather_mi.io.hydrometeors.from_arrays`): mixing ratios in kg per kg of dry air on
a regular (z, y, x) grid of cell centres in metres, x east, y north, z up, the first cell centre at
(dz/2, dy/2, dx/2) so the domain starts at x = y = z = 0. ``rho_air`` is the U.S. Standard
Atmosphere 1976 density at the cell heights (:func:`weather_mi.io.standard_atmosphere.standard_density`), a
z-profile. The same arguments give the same arrays bit for bit (numpy's PCG64 generator and
single-threaded pocketfft); every step is vectorised and a storm builds in well under 2 s.

``supercell()`` -- a mature, tilted supercell on a 1 km x 1 km x 500 m grid (96 x 96 x 20 km)
---------------------------------------------------------------------------------------------
Modelled on the real WRF ``em_quarter_ss`` supercell in ``../shared/data`` (WSM6, 01:30; its maxima
QCLOUD 3.8, QRAIN 17.5, QICE 0.33, QSNOW 4.3, QGRAUP 13.3 g/kg, cloud tops 15-17 km, anvil at
9-13 km over ~4000 km^2) and on textbook supercell anatomy (Bluestein 2013, *Severe Convective
Storms and Tornadoes*; Markowski & Richardson 2010, *Mesoscale Meteorology in Midlatitudes*):

* **Updraft tower (cloud water).** Cloud base (lifting condensation level) at 1.2 km, flat. The
  tower is ~9-12 km across and its axis leans downshear by 0.35 km per km of height (the updraft
  is tilted by the shear). Liquid water rises roughly adiabatically above cloud base (a moist
  adiabat condenses ~1.5-2 g/kg per km in the warm, humid lower troposphere of a supercell
  environment) but is depleted by entrainment, collection into rain and graupel and freezing, so
  the profile peaks at ~4.5 km, 2.8 g/kg (times +-25 % noise; WRF's maximum is 3.8 g/kg at
  4.6 km). Cloud water exists only where T > -40 C (homogeneous freezing): below 10 km in this
  environment, and up to ~11.8 km in the updraft core, where 40-50 m/s carry supercooled droplets
  higher before they freeze (WRF: cloud water up to 10.8 km).
* **Flanking line.** Three cumulus turrets stepping down (8.5, 6.5, 4.5 km tops) upshear and to
  the right of the updraft, the classic feeder towers of the rear flank.
* **Overshooting top.** A glaciated dome of ice and snow above the updraft summit, from the anvil
  top (~13 km, the equilibrium level near the tropopause) to 15.8 km: the updraft's momentum
  carries it 2-3 km past its equilibrium level (WRF: condensate up to 15-17 km).
* **Anvil (ice and snow).** Detrained ice spreads downshear with the upper-level wind: from the
  updraft summit it reaches ~46 km downshear (50-60 km from the updraft's base) and ~8 km upshear
  (the back-sheared anvil), fanning from ~30 km wide at the summit to ~50-55 km, ~2000-2600 km^2
  in all (the WRF storm's ~4000 km^2 include its left mover). Its top sinks from 13.3 to 12 km and
  its base rises from 9.3 to 11 km downshear as the crystals sediment and sublimate; it thins at its lateral
  edges. Small ice (cloud ice, WRF max 0.33 g/kg) is spread evenly, ~0.25-0.3 g/kg, weighted to
  the upper anvil; snow (aggregates, WRF max 4.3 g/kg) is ~2.4 g/kg near the updraft and falls out
  with an e-folding distance of ~18 km, weighted to the lower anvil, with fall streaks of snow
  hanging below the anvil base near the storm.
* **Graupel core.** Graupel grows by riming in the supercooled-water-rich updraft periphery, a
  few km downshear of the updraft axis at 2-9 km, peaking at 6 km with ~8.5 g/kg (up to ~10 with
  noise; WRF: 13.3 g/kg); below the 0 C level (~4 km) it melts into rain and is gone by ~1.5 km.
* **Rain.** The forward-flank precipitation core: a rain shaft ~12 km x 9 km centred 6.5 km
  downshear of the updraft base, from the ground to ~7 km (rain drops are lofted above the
  0 C level in the updraft), ~10 g/kg (up to ~12 with noise) at 2.5-4.5 km, a quarter less at
  the ground after evaporation (WRF: 17.5 g/kg aloft, 9.2 g/kg at the lowest level), beside a
  precipitation-free updraft base (the "vault"), plus lighter stratiform rain (~1.2 g/kg) under
  the anvil farther downshear.

``cumulus()`` -- a cumulus congestus on a 50 m grid (6.4 x 6.4 x 5.5 km)
-----------------------------------------------------------------------
In the spirit of the paper's Straka-model cumulus congestus (50 m voxels, a cloud "capable of light
precipitation"): a flat base at 1.0 km (the LCL of a moist boundary layer), a slightly leaning chain
of six rising thermals 2.3-1.0 km across and, on them, two generations of smaller bubbles (the
cauliflower turrets), giving a cloud ~3.7-4 km deep (top 4.7-5 km) and ~3-3.5 km wide. Liquid
water follows the adiabatic increase of ~2 g/kg per km above cloud base reduced by entrainment (an
adiabatic fraction falling from 0.85 at the base with an e-folding depth of 2.2 km, and less water
near the cloud edges), so the maximum is ~1.8 g/kg near 3.2 km, like the 1-2 g/m^3 measured in
congestus cores (the BOMEX LES in ``../shared/data`` peaks at 1.7 g/m^3). Light rain (drizzle,
~0.25-0.35 g/kg) falls from the lower cloud core to the ground. A warm cloud: no ice, snow or graupel.

Noise: smooth Gaussian random fields with a power-law (fractional-Brownian) spectrum between two
length scales, made by filtering white noise in Fourier space; they perturb the shapes' edges,
heights and amplitudes so nothing is a perfect ellipsoid. Features are placed in physical units
(metres, relative to the horizontal domain centre); a smaller domain crops the storm.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from .standard_atmosphere import standard_density
from ..errors import WeatherDataError
from .hydrometeors import from_arrays

__all__ = ["supercell", "cumulus"]

KM = 1000.0


# ----------------------------------------------------------------------------- helpers
def _grid(shape, spacing_m, source):
    """Validated (nz, ny, nx), (dz, dy, dx) and the cell-centre coordinates z, y, x (1-D, metres)."""
    try:
        shp = tuple(int(n) for n in shape)
        spc = tuple(float(s) for s in spacing_m)
    except (TypeError, ValueError) as exc:
        raise WeatherDataError(source, "shape/spacing_m", "three integers (nz, ny, nx) and three numbers "
                               "(dz, dy, dx) in metres", f"{shape!r}, {spacing_m!r}") from exc
    if len(shp) != 3 or any(n < 2 for n in shp):
        raise WeatherDataError(source, "shape", "three grid sizes (nz, ny, nx), each >= 2", repr(shape))
    if len(spc) != 3 or not all(np.isfinite(s) and s > 0 for s in spc):
        raise WeatherDataError(source, "spacing_m", "three positive grid spacings (dz, dy, dx) in metres",
                               repr(spacing_m))
    coords = tuple(d / 2 + d * np.arange(n, dtype=np.float64) for n, d in zip(shp, spc))
    return shp, spc, coords


def _smoothstep(x, a, b):
    """0 below a, 1 above b, C1-smooth cubic in between."""
    t = np.clip((np.asarray(x, dtype=np.float64) - a) / (b - a), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _noise(rng, shape, spacing, l_min, l_max, hurst=0.6):
    """A zero-mean, unit-variance smooth random field (periodic) with a fractional-Brownian spectrum.

    White noise filtered in Fourier space by |k|^-(hurst + ndim/2), rolled off above wavelength
    ``l_max`` and below ``l_min`` (metres): structure on all scales in between, none at grid scale.
    """
    white = rng.standard_normal(shape)
    axes = [np.fft.fftfreq(n, d) for n, d in zip(shape[:-1], spacing[:-1])]
    axes.append(np.fft.rfftfreq(shape[-1], spacing[-1]))
    k2 = np.zeros([len(a) for a in axes])
    for i, a in enumerate(axes):
        idx = [None] * len(axes)
        idx[i] = slice(None)
        k2 = k2 + a[tuple(idx)] ** 2
    k0 = 1.0 / l_max
    amp = (k2 + k0 * k0) ** (-(hurst + len(shape) / 2.0) / 2.0) * np.exp(-k2 * (l_min / 2.0) ** 2)
    amp.flat[0] = 0.0
    field = np.fft.irfftn(np.fft.rfftn(white) * amp, s=shape, axes=tuple(range(len(shape))))
    std = field.std()
    return field / std if std > 0 else field


def _modulation(n, amp, lo, hi):
    """Multiplicative amplitude noise 1 + amp * n, clipped to [lo, hi]."""
    return np.clip(1.0 + amp * n, lo, hi)


def _dataset(q, z, spacing, attrs, source):
    dz, dy, dx = spacing
    return from_arrays(q, standard_density(z), spacing, origin=(dz / 2, dy / 2, dx / 2), attrs=attrs,
                       source=source)


# ----------------------------------------------------------------------------- supercell
# heights (m)
_SC_CLOUD_BASE = 1.2 * KM          # LCL
_SC_QC_PEAK_Z = 4.5 * KM           # height of the cloud-water maximum
_SC_Z_HOMOGENEOUS = 10.0 * KM      # -40 C level of the storm environment
_SC_Z_HOMOGENEOUS_CORE = 11.8 * KM  # supercooled water lofted higher in the updraft core
_SC_ANVIL_TOP = 13.3 * KM
_SC_ANVIL_BASE = 9.3 * KM
_SC_OVERSHOOT_BASE = 12.5 * KM
_SC_OVERSHOOT_TOP = 15.8 * KM
# horizontal layout (m), in the shear frame: s downshear, n to the left of the shear vector
_SC_TILT = 0.35                    # updraft axis displacement per unit height
_SC_ANVIL_DOWN = 46.0 * KM         # anvil length downshear of the updraft summit
_SC_ANVIL_UP = 8.0 * KM            # back-sheared anvil upshear of the summit
_SC_ANVIL_HALF_WIDTH = (15.0 * KM, 38.0 * KM)  # at the summit and far downshear
_SC_STORM_OFFSET = 26.0 * KM       # updraft base upshear of the domain centre, so the anvil fits
# peak mixing ratios (kg/kg)
_SC_QC = 2.8e-3
_SC_QI = 0.28e-3
_SC_QS = 2.4e-3
_SC_QG = 8.5e-3
_SC_QR = 10.0e-3
_SC_QR_STRATIFORM = 1.2e-3


def _adiabatic_shape(h, h_peak, power):
    """Adiabatic rise then entrainment/precipitation depletion: (h/hp * e^(1 - h/hp))^power, peak 1 at hp."""
    u = np.maximum(h, 0.0) / h_peak
    return (u * np.exp(1.0 - u)) ** power


def _turret(S, N, Z, s0, n0, z_base, z_top, radius, n_edge, tilt=0.0):
    """A cumulus tower: vertical cylinder from z_base with a domed top; returns sqrt(1 - rho^2)_+."""
    cap = 0.8 * radius
    ds = S - (s0 + tilt * np.maximum(Z - z_base, 0.0))
    r = np.sqrt(ds ** 2 + (N - n0) ** 2)
    over = np.maximum(Z - (z_top - cap), 0.0) / cap
    rho2 = ((r / radius) ** 2 + over ** 2) * _modulation(n_edge, 0.22, 0.4, 2.0) ** 2
    inside = np.sqrt(np.clip(1.0 - rho2, 0.0, 1.0))
    return np.where(Z >= z_base, inside, 0.0)


def _shear_azimuth(source, shear_azimuth_deg) -> float:
    """The shear azimuth in radians, checked."""
    try:
        az = np.deg2rad(float(shear_azimuth_deg))
    except (TypeError, ValueError) as exc:
        raise WeatherDataError(source, "shear_azimuth_deg", "a number (degrees clockwise from north)",
                               repr(shear_azimuth_deg)) from exc
    if not np.isfinite(az):
        raise WeatherDataError(source, "shear_azimuth_deg", "a finite number", repr(shear_azimuth_deg))
    return az


def _sc_noise(rng, shp3, spacing) -> dict:
    """The supercell's noise fields, drawn in this order from rng (edges, amplitude, anvil top, base, outline)."""
    shp2 = shp3[1:]
    return {"edge": _noise(rng, shp3, spacing, 2.0 * KM, 30.0 * KM),        # shape of edges
            "amp": _noise(rng, shp3, spacing, 1.5 * KM, 12.0 * KM),         # amplitude texture
            "top": _noise(rng, shp2, spacing[1:], 3.0 * KM, 30.0 * KM),     # anvil top height
            "bot": _noise(rng, shp2, spacing[1:], 3.0 * KM, 30.0 * KM),     # anvil base height
            "foot": _noise(rng, shp2, spacing[1:], 4.0 * KM, 40.0 * KM)}    # anvil outline


def _sc_frame(x, y, z, domain_m, az):
    """The shear frame (m): S downshear and N left of the shear vector from the updraft base axis, each
    (1, ny, nx), Z (nz, 1, 1), and the updraft base (x_up, y_up)."""
    ue, un = np.sin(az), np.cos(az)                                # downshear unit vector (east, north)
    x_up = domain_m[0] / 2 - _SC_STORM_OFFSET * ue                 # updraft base axis
    y_up = domain_m[1] / 2 - _SC_STORM_OFFSET * un
    X = x[None, :] - x_up
    Y = y[:, None] - y_up
    S = (X * ue + Y * un)[None]                                    # (1, ny, nx): downshear distance
    N = (-X * un + Y * ue)[None]                                   # left of the shear vector
    return S, N, z[:, None, None], x_up, y_up


def _sc_cloud_water(S, N, Z, n_edge, mod):
    """Cloud water of the updraft tower (tilted downshear, flat base, -40 C cut-off) and of the flanking
    line, and the tower's axis: (q_cloud, s_axis, r_axis, r_tower), distances in metres."""
    s_axis = _SC_TILT * np.maximum(Z - _SC_CLOUD_BASE, 0.0)
    r_axis = np.sqrt((S - s_axis) ** 2 + N ** 2)
    r_tower = 4.5 * KM + 1.5 * KM * np.clip((Z - _SC_CLOUD_BASE) / (9.0 * KM), 0.0, 1.0)
    rho = r_axis / r_tower * _modulation(n_edge, 0.22, 0.4, 2.0)
    tower = np.sqrt(np.clip(1.0 - rho ** 2, 0.0, 1.0))
    core = np.exp(-(r_axis / (0.35 * r_tower)) ** 2)
    z_hom = _SC_Z_HOMOGENEOUS + (_SC_Z_HOMOGENEOUS_CORE - _SC_Z_HOMOGENEOUS) * core
    warm = 1.0 - _smoothstep(Z, z_hom - 1.2 * KM, z_hom)
    h = Z - _SC_CLOUD_BASE
    base = np.clip(h / 300.0 + 0.5, 0.0, 1.0)                      # flat base within one cell
    profile = _adiabatic_shape(h, _SC_QC_PEAK_Z - _SC_CLOUD_BASE, 1.5)
    q_cloud = _SC_QC * profile * tower * warm * base * mod
    # flanking line: turrets stepping down upshear and to the right of the updraft
    fdir = np.array([-np.cos(np.pi / 4), -np.sin(np.pi / 4)])
    for dist, top, rad in ((9.0 * KM, 8.5 * KM, 2.8 * KM), (15.0 * KM, 6.5 * KM, 2.3 * KM),
                           (21.0 * KM, 4.5 * KM, 1.8 * KM)):
        t = _turret(S, N, Z, dist * fdir[0], dist * fdir[1], _SC_CLOUD_BASE, top, rad, n_edge, tilt=0.15)
        q_cloud = np.maximum(q_cloud, 0.85 * _SC_QC * profile * t * warm * mod)
    return q_cloud, s_axis, r_axis, r_tower


def _sc_column_ice_snow(Z, r_axis, r_tower, n_edge, mod):
    """Ice and snow (kg/kg) of the glaciated upper updraft and the overshooting top."""
    dome = np.clip((_SC_OVERSHOOT_TOP - Z) / (_SC_OVERSHOOT_TOP - _SC_OVERSHOOT_BASE), 0.0, 1.0)
    r_col = np.where(Z <= _SC_OVERSHOOT_BASE, r_tower, r_tower * np.sqrt(dome))  # paraboloid dome
    rho_c = r_axis / np.maximum(r_col, 1.0) * _modulation(n_edge, 0.2, 0.4, 2.0)
    column = np.sqrt(np.clip(1.0 - rho_c ** 2, 0.0, 1.0)) * (Z < _SC_OVERSHOOT_TOP)
    q_ice = _SC_QI * _smoothstep(Z, 7.0 * KM, 10.5 * KM) * column * mod
    q_snow = (_SC_QS * _smoothstep(Z, 6.0 * KM, 9.5 * KM)
              * (1.0 - 0.6 * _smoothstep(Z, _SC_OVERSHOOT_BASE, _SC_OVERSHOOT_TOP)) * column * mod)
    return q_ice, q_snow


def _sc_anvil(S, N, Z, noise, mod):
    """Ice and snow (kg/kg) of the anvil spreading downshear from the updraft summit, snow including the
    fall streaks below its base near the storm."""
    s_rel = S[0] - _SC_TILT * (12.0 * KM - _SC_CLOUD_BASE)           # (ny, nx)
    t_down = np.clip(s_rel / _SC_ANVIL_DOWN, 0.0, 1.0)
    w0, w1 = _SC_ANVIL_HALF_WIDTH
    half_width = w0 + (w1 - w0) * t_down ** 0.7
    length = np.where(s_rel < 0.0, _SC_ANVIL_UP, _SC_ANVIL_DOWN)
    rho_h = (np.sqrt((N[0] / half_width) ** 2 + np.abs(s_rel / length) ** 2.5)
             * _modulation(noise["foot"], 0.15, 0.75, 1.3))
    foot = np.sqrt(np.clip(1.0 - rho_h ** 2, 0.0, 1.0))
    z_top = _SC_ANVIL_TOP - 1.3 * KM * t_down + 250.0 * noise["top"]
    z_bot = _SC_ANVIL_BASE + 1.7 * KM * t_down + 400.0 * noise["bot"]
    depth = np.maximum(z_top - z_bot, 0.0)
    top_e = z_top - 0.3 * (1.0 - foot) * depth                     # thins at its edges, mostly from below
    bot_e = z_bot + 0.7 * (1.0 - foot) * depth
    zeta = (Z - bot_e) / np.maximum(top_e - bot_e, 1.0) + 0.06 * noise["edge"]
    inside = np.clip(zeta, 0.0, 1.0) * (top_e > bot_e)
    layer = np.sqrt(np.sin(np.pi * inside))                         # sharp top and base
    s_plus = np.maximum(s_rel, 0.0)
    lateral = foot ** 0.3
    ice_amp = _SC_QI * (0.6 + 0.4 * np.exp(-s_plus / (40.0 * KM))) * lateral
    snow_amp = _SC_QS * (0.12 + 0.88 * np.exp(-s_plus / (18.0 * KM))) * lateral
    anvil_ice = ice_amp * layer * (0.55 + 0.45 * inside) * mod
    anvil_snow = snow_amp * layer * (1.0 - 0.5 * inside) * mod
    # fall streaks of snow below the anvil base near the storm
    below = np.maximum(bot_e - Z, 0.0)
    streak = (0.35 * snow_amp * np.exp(-below / 900.0) * np.exp(-s_plus / (15.0 * KM))
              * (Z < bot_e) * (foot > 0) * _modulation(noise["amp"], 0.6, 0.0, 2.0))
    return anvil_ice, np.maximum(anvil_snow, streak)


def _sc_graupel(S, N, Z, s_axis, n_edge, mod):
    """Graupel (kg/kg) of the core on the downshear flank of the updraft, 2-9 km, melting below ~4 km."""
    s_g = s_axis + 3.0 * KM
    r_g = np.sqrt((S - s_g) ** 2 + (N - 1.0 * KM) ** 2) / (4.5 * KM) * _modulation(n_edge, 0.2, 0.4, 2.0)
    zg = 6.0 * KM
    vert_g = (np.exp(-((Z - zg) / np.where(Z >= zg, 2.0 * KM, 1.6 * KM)) ** 2)
              * _smoothstep(Z, 1.5 * KM, 3.8 * KM))
    return _SC_QG * vert_g * np.clip(1.0 - r_g ** 2, 0.0, 1.0) * mod


def _sc_rain(S, N, Z, r_axis, n_edge, mod):
    """Rain (kg/kg): the forward-flank shaft beside the precipitation-free updraft base, and stratiform rain."""
    r_r = (np.sqrt(((S - 6.5 * KM) / (6.0 * KM)) ** 2 + ((N - 1.5 * KM) / (4.5 * KM)) ** 2)
           * _modulation(n_edge, 0.2, 0.4, 2.0))
    vert_r = (np.where(Z < 2.5 * KM, 0.7 + 0.3 * Z / (2.5 * KM), 1.0)      # evaporation below 2.5 km
              * (1.0 - _smoothstep(Z, 4.5 * KM, 7.0 * KM)))
    vault = 1.0 - 0.8 * np.exp(-(r_axis / (2.5 * KM)) ** 2) * (Z < 6.0 * KM)
    q_rain = _SC_QR * vert_r * np.clip(1.0 - r_r ** 2, 0.0, 1.0) ** 0.8 * vault * mod
    r_s = (np.sqrt(((S - 18.0 * KM) / (14.0 * KM)) ** 2 + ((N - 3.0 * KM) / (7.0 * KM)) ** 2)
           * _modulation(n_edge, 0.25, 0.4, 2.0))
    vert_s = 1.0 - _smoothstep(Z, 3.8 * KM, 5.0 * KM)
    return np.maximum(q_rain, _SC_QR_STRATIFORM * vert_s * np.clip(1.0 - r_s ** 2, 0.0, 1.0) * mod)


def supercell(shape=(40, 96, 96), spacing_m=(500.0, 1000.0, 1000.0), seed=0,
              shear_azimuth_deg=60.0) -> xr.Dataset:
    """A procedural mature supercell (see the module docstring for the physics of every part).

    Parameters
    ----------
    shape : tuple of 3 int, default (40, 96, 96)
        (nz, ny, nx), each >= 2; with the default spacing the default covers 96 km x 96 km x 20 km.
    spacing_m : tuple of 3 float, default (500.0, 1000.0, 1000.0)
        (dz, dy, dx) in metres.
    seed : int, default 0
        Seeds the noise that roughens every edge and amplitude (same seed, same arrays).
    shear_azimuth_deg : float, default 60.0
        Direction the deep-layer shear vector points (degrees clockwise from north), i.e. where the
        anvil spreads; the storm is placed upshear of the domain centre so the anvil stays inside a
        ~100 km domain.

    Returns
    -------
    xarray.Dataset
        Hydrometeors (:func:`weather_mi.io.hydrometeors.from_arrays`): cloud, ice, rain, snow and graupel
        mixing ratios (kg/kg) on cell centres from (dz/2, dy/2, dx/2) (m), ``rho_air`` the 1976
        standard atmosphere (kg/m^3); attributes ``seed``, ``shear_azimuth_deg`` and the updraft base
        ``updraft_x_m``, ``updraft_y_m`` (m).

    Raises
    ------
    WeatherDataError
        For a bad shape, spacing or shear azimuth.
    """
    source = "synthetic.supercell"
    (nz, ny, nx), spacing, (z, y, x) = _grid(shape, spacing_m, source)
    dz, dy, dx = spacing
    az = _shear_azimuth(source, shear_azimuth_deg)
    shp3 = (nz, ny, nx)
    noise = _sc_noise(np.random.default_rng(seed), shp3, spacing)
    S, N, Z, x_up, y_up = _sc_frame(x, y, z, (nx * dx, ny * dy), az)
    n_edge = noise["edge"]
    mod = _modulation(noise["amp"], 0.2, 0.5, 1.25)

    q_cloud, s_axis, r_axis, r_tower = _sc_cloud_water(S, N, Z, n_edge, mod)
    q_ice, q_snow = _sc_column_ice_snow(Z, r_axis, r_tower, n_edge, mod)
    anvil_ice, anvil_snow = _sc_anvil(S, N, Z, noise, mod)
    q_ice = np.maximum(q_ice, anvil_ice)
    q_snow = np.maximum(q_snow, anvil_snow)
    q_graupel = _sc_graupel(S, N, Z, s_axis, n_edge, mod)
    q_rain = _sc_rain(S, N, Z, r_axis, n_edge, mod)

    q = {"cloud": q_cloud, "ice": q_ice, "rain": q_rain, "snow": q_snow, "graupel": q_graupel}
    q = {k: np.broadcast_to(v, shp3) for k, v in q.items()}
    attrs = {"model": "synthetic", "microphysics": "none (procedural)",
             "description": "procedural supercell: tilted updraft tower of cloud water (base 1.2 km), "
                            "flanking line, overshooting top to 15.8 km, ice/snow anvil at 9-13 km spreading "
                            "~50-60 km downshear, graupel core at 2-9 km, forward-flank rain shaft to the ground",
             "seed": int(seed), "shear_azimuth_deg": float(shear_azimuth_deg),
             "updraft_x_m": float(x_up), "updraft_y_m": float(y_up)}
    return _dataset(q, z, spacing, attrs, source)


# ----------------------------------------------------------------------------- cumulus
_CU_CLOUD_BASE = 1.0 * KM
_CU_GAMMA = 2.0e-6                 # adiabatic liquid-water increase, kg/kg per metre (2 g/kg per km)
_CU_ADIABATIC_FRACTION = 0.85      # at cloud base
_CU_ENTRAINMENT_DEPTH = 2.2 * KM   # e-folding depth of the adiabatic fraction
_CU_QR = 0.25e-3


def _cumulus_blobs(rng, xc, yc):
    """(x, y, z, r) of the thermals (a tilted chain) and two generations of turrets on their upper surfaces."""
    heights = np.array([0.35, 0.9, 1.5, 2.1, 2.65, 3.15]) * KM
    radii = np.array([1.1, 1.15, 1.0, 0.85, 0.7, 0.5]) * KM
    blobs = []
    for hz, r in zip(heights, radii):
        hz = hz + rng.uniform(-0.08, 0.08) * KM
        r = r * rng.uniform(0.9, 1.1)
        bx = xc + 0.12 * hz + rng.uniform(-0.3, 0.3) * KM          # leans slightly east (downwind)
        by = yc + rng.uniform(-0.3, 0.3) * KM
        blobs.append((bx, by, _CU_CLOUD_BASE + hz, r))
    parents = list(blobs)
    # (elevation range in degrees, children per parent, distance and radius as fractions of the parent)
    for (elev_lo, elev_hi, n_child, dist, rad) in ((-10.0, 75.0, 6, (0.8, 1.0), (0.3, 0.55)),
                                                   (0.0, 80.0, 3, (0.8, 1.0), (0.35, 0.55))):
        children = []
        for (px, py, pz, pr) in parents:
            for _ in range(n_child):
                azm = rng.uniform(0.0, 2 * np.pi)
                elev = np.deg2rad(rng.uniform(elev_lo, elev_hi))
                d = pr * rng.uniform(*dist)
                cr = pr * rng.uniform(*rad)
                children.append((px + d * np.cos(elev) * np.cos(azm), py + d * np.cos(elev) * np.sin(azm),
                                 pz + d * np.sin(elev), cr))
        blobs += children
        parents = children
    return blobs


def cumulus(shape=(110, 128, 128), spacing_m=(50.0, 50.0, 50.0), seed=0, rain=True) -> xr.Dataset:
    """A procedural cumulus congestus with cauliflower turrets (see the module docstring).

    Parameters
    ----------
    shape : tuple of 3 int, default (110, 128, 128)
        (nz, ny, nx), each >= 2; the default at 50 m covers 6.4 km x 6.4 km x 5.5 km.
    spacing_m : tuple of 3 float, default (50.0, 50.0, 50.0)
        (dz, dy, dx) in metres.
    seed : int, default 0
        Places the turrets and seeds the edge noise (same seed, same arrays).
    rain : bool, default True
        Include light rain (drizzle) from the lower cloud core to the ground.

    Returns
    -------
    xarray.Dataset
        Hydrometeors (:func:`weather_mi.io.hydrometeors.from_arrays`): cloud (and rain) mixing ratios
        (kg/kg) on cell centres from (dz/2, dy/2, dx/2) (m), ``rho_air`` the 1976 standard atmosphere
        (kg/m^3); a warm cloud, no ice, snow or graupel.

    Raises
    ------
    WeatherDataError
        For a bad shape or spacing.
    """
    source = "synthetic.cumulus"
    (nz, ny, nx), spacing, (z, y, x) = _grid(shape, spacing_m, source)
    dz, dy, dx = spacing
    rng = np.random.default_rng(seed)
    xc, yc = nx * dx / 2, ny * dy / 2
    blobs = _cumulus_blobs(rng, xc, yc)
    shp3 = (nz, ny, nx)
    n_edge = _noise(rng, shp3, spacing, 100.0, 1500.0, hurst=0.3)
    n_amp = _noise(rng, shp3, spacing, 150.0, 1000.0)
    n_base = _noise(rng, (ny, nx), spacing[1:], 300.0, 3000.0)

    # union of bubbles: F = max_b (1 - d^2 / r^2), positive inside; evaluated in each bubble's box
    F = np.full(shp3, -2.0)                                       # >= -2 inside boxes too
    for bx, by, bz, br in blobs:
        sl = []
        for c0, n, d, cc in ((z[0], nz, dz, bz), (y[0], ny, dy, by), (x[0], nx, dx, bx)):
            lo = int(np.clip(np.floor((cc - br - c0) / d), 0, n))
            hi = int(np.clip(np.ceil((cc + br - c0) / d) + 1, 0, n))
            sl.append(slice(lo, hi))
        if any(s.stop <= s.start for s in sl):
            continue
        zz, yy, xx = z[sl[0], None, None], y[None, sl[1], None], x[None, None, sl[2]]
        f = 1.0 - ((zz - bz) ** 2 + (yy - by) ** 2 + (xx - bx) ** 2) / (br * br)
        np.maximum(F[tuple(sl)], f, out=F[tuple(sl)])
    Fp = F + 0.25 * n_edge
    Z = z[:, None, None]
    z_base = _CU_CLOUD_BASE + 20.0 * n_base                        # flat base, +-20 m
    h = Z - z_base
    in_cloud = (Fp > 0) & (h >= 0)
    interior = np.clip(Fp / 0.35, 0.0, 1.0) ** 0.7                 # entrainment dries the edges
    q_adiabatic = _CU_GAMMA * np.maximum(h, 0.0) + 0.05e-3         # a little water right at the base
    fraction = _CU_ADIABATIC_FRACTION * np.exp(-np.maximum(h, 0.0) / _CU_ENTRAINMENT_DEPTH)
    q_cloud = np.where(in_cloud, q_adiabatic * fraction * interior * _modulation(n_amp, 0.15, 0.6, 1.3), 0.0)

    q = {"cloud": q_cloud}
    if rain:
        bx, by, bz, br = blobs[1]                                  # under the second thermal
        r = np.sqrt((y[:, None] - by) ** 2 + (x[None, :] - bx) ** 2)[None] / (0.6 * br)
        r = r * _modulation(n_edge, 0.25, 0.4, 2.0)
        z_rt = _CU_CLOUD_BASE + 1.8 * KM
        # grows by accretion on its way down through the cloud; evaporates partly below the base
        vert = np.where(Z >= _CU_CLOUD_BASE, 1.0 - _smoothstep(Z, _CU_CLOUD_BASE, z_rt),
                        0.6 + 0.4 * Z / _CU_CLOUD_BASE)
        q["rain"] = _CU_QR * vert * np.clip(1.0 - r ** 2, 0.0, 1.0) * _modulation(n_amp, 0.3, 0.3, 1.5)
    attrs = {"model": "synthetic", "microphysics": "none (procedural)",
             "description": "procedural cumulus congestus: flat base at 1 km, cauliflower turrets to "
                            "~4.7-5 km, sub-adiabatic liquid water" + (", light rain to the ground" if rain else ""),
             "seed": int(seed)}
    return _dataset(q, z, spacing, attrs, source)


# ----------------------------------------------------------------------------- stratocumulus
_SCU_BASE = 400.0        # m: the deck's flat base (a well-mixed boundary layer's LCL)
_SCU_TOP = 850.0         # m: the mean inversion height
_SCU_TOP_SPREAD = 70.0   # m: standard deviation of the cloud top (closed cells)
_SCU_GAMMA = 2.0e-6      # kg/kg per m: the adiabatic liquid-water lapse (~2 g/kg/km at 10 C)
_SCU_ADIABATIC_FRACTION = 0.85


def stratocumulus(shape=(40, 96, 96), spacing_m=(25.0, 100.0, 100.0), seed=0) -> xr.Dataset:
    """A dense marine stratocumulus deck: a flat base at 400 m, closed cells whose tops undulate about
    850 m, near-adiabatic liquid water (0.85 x 2 g/kg per km above the base, ~0.8 g/kg at the top), the
    top 30 m thinned by entrainment. Optical depth ~30-40 through the cell centres (r = 10 um), the thick,
    uniform layer a slicer must converge on.

    Parameters
    ----------
    shape : tuple of 3 int, default (40, 96, 96)
        (nz, ny, nx); the default covers 9.6 km x 9.6 km x 1 km.
    spacing_m : tuple of 3 float, default (25.0, 100.0, 100.0)
        (dz, dy, dx) in metres.
    seed : int, default 0
        Seeds the cells (same seed, same arrays).

    Returns
    -------
    xarray.Dataset
        Hydrometeors (cloud water only, kg/kg; ``rho_air`` the 1976 standard atmosphere).
    """
    source = "synthetic.stratocumulus"
    (nz, ny, nx), spacing, (z, y, x) = _grid(shape, spacing_m, source)
    rng = np.random.default_rng(seed)
    n_top = _noise(rng, (ny, nx), spacing[1:], 400.0, 2500.0)
    n_amp = _noise(rng, (nz, ny, nx), spacing, 150.0, 1500.0)
    top = (_SCU_TOP + _SCU_TOP_SPREAD * n_top)[None]
    Z = z[:, None, None]
    h = Z - _SCU_BASE
    q = _SCU_ADIABATIC_FRACTION * _SCU_GAMMA * np.maximum(h, 0.0)
    q = q * (1.0 - _smoothstep(Z, top - 30.0, top)) * _modulation(n_amp, 0.1, 0.7, 1.3)
    q = np.where((h >= 0) & (Z <= top), q, 0.0)
    attrs = {"model": "synthetic", "microphysics": "none (procedural)",
             "description": "procedural marine stratocumulus: base 400 m, closed cells topping 850 +- 70 m, "
                            "near-adiabatic liquid water", "seed": int(seed)}
    return _dataset({"cloud": q}, z, spacing, attrs, source)
