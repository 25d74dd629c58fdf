"""The air along an eye ray outside the model's box (aerial perspective): the ray's transmittance and the
sunlight it scatters towards the eye once (single scattering), per colour channel.

Along the segment s in [t0, t1] of the ray o + s d (the kernel's frame: heights above sea level, the
Earth's centre at (0, 0, -R), as ``kernel.plugins.sun``):

    T(t0, s) = exp(-integral_t0^s beta_ext(h(s'), lambda) ds')                             (Beer-Lambert)
    S = integral_t0^t1 T(t0, s) [beta_R(h) p_R(Theta) + omega_a beta_a(h) p_HG(Theta)] C(h, mu) ds   (single scattering)

with h(s) the height above the sphere, cos Theta = d . sun (the sun's light, travelling along -sun,
scattered into -d), beta_R, beta_a the molecules' and the aerosol's extinction of the 1-D atmosphere
(``Atmosphere``; ozone absorbs only), p_R Rayleigh's phase function (``optics.rayleigh``), p_HG
Henyey-Greenstein's with the aerosol's asymmetry, and C(h, mu) the direct sun's colour at h, its
cos(zenith) there mu = (q . sun) / |q| (``sunlight.sun_rgb``, over a table wide enough for every point of
the segment). S is a radiance per unit irradiance of the sun above the air (1/sr): times the scene's sun
irradiance it is the radiance added at the eye. The integrals are trapezoidal on s = t0 + (t1 - t0) x^2,
x uniform (dense near t0, where an eye ray near the ground meets most of its air), compiled
(``march_kernels.segment_air``; the profiles linear on a ``PROFILE_STEP_M`` grid).
"""
from __future__ import annotations

import functools

import numpy as np

from ..phase.analytic import hg_value
from ..rayleigh import cross_section_m2 as rayleigh_cross_section_m2, phase_value
from . import march_kernels
from .atmosphere import Atmosphere
from .inside import CHANNEL_NM
from .ozone import channel_cross_section_m2 as ozone_cross_section_m2
from .shell import EARTH_RADIUS_M
from .sunlight import SunAirTable, channel_values

TOP_M = 60e3        # the eye path's air ends here (above it < 1e-4 of the molecules' column)
SAMPLES = 257
PROFILE_STEP_M = 1.0  # the air's profiles, linear between heights this far apart (within 1e-7 of the formulas)


def wide_sun_table(atm: Atmosphere, mu0: float, reach_m: float = 1500e3, n_mu: int = 129, n_h: int = 121,
                   band_nm=None) -> SunAirTable:
    """The direct sun's colour over heights 0..TOP_M and the band of mu that points up to ``reach_m``
    from the scene's centre see (the sun at cos(zenith) ``mu0`` there); ``band_nm``: its transmittance at
    each channel's wavelength instead (``sunlight.channel_values``)."""
    sza, delta = np.arccos(mu0), reach_m / EARTH_RADIUS_M
    mu = np.linspace(np.cos(min(sza + delta, np.pi)), np.cos(max(sza - delta, 0.0)), n_mu)
    heights = np.linspace(0.0, TOP_M, n_h)
    rgb = channel_values(atm, heights[None, :], mu[:, None], band_nm)
    return SunAirTable(heights_m=heights, mu=mu, rgb=rgb.astype(np.float32))


def top_distance(origins, dirs, top_m: float = TOP_M) -> np.ndarray:
    """Distance along the rays (n, 3) to where they leave the sphere of radius R + top_m (0 beyond it)."""
    q = np.asarray(origins, np.float64) + [0.0, 0.0, EARTH_RADIUS_M]
    d = np.asarray(dirs, np.float64)
    b = np.sum(q * d, axis=-1)
    c = np.sum(q * q, axis=-1) - (EARTH_RADIUS_M + top_m) ** 2
    return np.maximum(-b + np.sqrt(np.maximum(b * b - c, 0.0)), 0.0)


def segment_air(atm: Atmosphere, to_sun, origins, dirs, t0, t1, table: SunAirTable,
                wavelengths_nm=CHANNEL_NM, samples: int = SAMPLES, shadow=None,
                isotropic: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(T (n, c), S (n, c)) of the segments [t0, t1] (n,) of the rays (n, 3) (module docstring; S in 1/sr per
    unit irradiance of the sun above the air); T = 1, S = 0 where t1 <= t0. ``shadow``: the direct sun's
    transmittance through the storm at points (..., 3) of the frame (``storm_shadow.StormShadow.transmittance``),
    a factor on C(h, mu); None: no storm. ``isotropic``: the phase functions 1 in place of p_R and p_HG, so that
    with the diffuse light's mean intensity as ``table`` (``skylight.diffuse_source_table``) S is the air's
    multiple scattering along the segment, its diffuse source taken as isotropic."""
    o, d = np.asarray(origins, np.float64).reshape(-1, 3), np.asarray(dirs, np.float64).reshape(-1, 3)
    sun = np.asarray(to_sun, np.float64) / np.linalg.norm(to_sun)
    t0 = np.broadcast_to(np.asarray(t0, np.float64), o.shape[:1])
    length = np.maximum(np.asarray(t1, np.float64) - t0, 0.0)
    wl = np.asarray(wavelengths_nm, np.float64).reshape(-1)
    wl = np.repeat(wl, table.rgb.shape[-1]) if wl.size == 1 else wl  # one wavelength, the table's channels
    x = np.linspace(0.0, 1.0, samples)
    lit = np.zeros((0, 0))
    if shadow is not None:  # the storm's shadow on the direct sun at the samples
        s = t0[:, None] + length[:, None] * x * x
        lit = np.asarray(shadow(o[:, None, :] + s[..., None] * d[:, None, :]), np.float64).reshape(s.shape)
    z_top = float(np.max(np.r_[_heights(o, d, t0), _heights(o, d, t0 + length), 0.0]))
    cos_t = np.clip(d @ sun, -1.0, 1.0)
    tab = np.asarray(table.rgb, np.float64)
    own, first = _distinct_channels(wl, tab)
    w = wl[own]
    ozone = ozone_cross_section_m2(wl)[own]  # the RGB mode's channels: the band averages (air.ozone)
    per_channel = [np.broadcast_to(v, own.shape).astype(np.float64)
                   for v in (rayleigh_cross_section_m2(w * 1e-9), ozone, atm.aerosol_factor(w))]
    t, s = march_kernels.segment_air(
        o, d, np.ascontiguousarray(t0), length, sun, x, 0.0, PROFILE_STEP_M,
        _profile_grid(atm, z_top if z_top > TOP_M else TOP_M),
        *per_channel, float(atm.aerosol_ssa), *((np.ones_like(cos_t),) * 2 if isotropic else
                                                (phase_value(cos_t), hg_value(atm.aerosol_g, cos_t))),
        np.asarray(table.heights_m, np.float64), np.asarray(table.mu, np.float64), np.ascontiguousarray(tab[..., own]),
        lit, float(EARTH_RADIUS_M))
    return t[:, first], s[:, first]


@functools.lru_cache(maxsize=8)
def _profile_grid(atm: Atmosphere, z_top: float) -> np.ndarray:
    """(3, n) the air, ozone (per m^3) and aerosol (1/m at 550 nm) on heights 0, PROFILE_STEP_M, ... past ``z_top``:
    once per atmosphere (up to ``TOP_M``; a straight segment is highest at an end, so no point lies above it; the
    grid's nodes are the same at any length, so a longer one gives the same sums)."""
    z = np.arange(0.0, z_top + 2 * PROFILE_STEP_M, PROFILE_STEP_M)
    grid = np.stack([atm.air_number_density_m3(z), atm.ozone_number_density_m3(z), atm.aerosol_extinction_550_per_m(z)])
    grid.flags.writeable = False
    return grid


def _distinct_channels(wl, tab) -> tuple[np.ndarray, np.ndarray]:
    """(The channels computed, the column of the result each channel takes): a channel with an earlier one's
    wavelength and column of the sun's table ``tab`` (a satellite's single band, three times) takes its."""
    own, first = [], []
    for c in range(wl.size):
        same = [i for i, e in enumerate(own) if wl[e] == wl[c] and np.array_equal(tab[..., e], tab[..., c])]
        if not same:
            own.append(c)
        first.append(same[0] if same else len(own) - 1)
    return np.asarray(own), np.asarray(first)


def _heights(o, d, s) -> np.ndarray:
    """Heights above the sphere (m) of the points o + s d (n,)."""
    q = o + s[:, None] * d + [0.0, 0.0, EARTH_RADIUS_M]
    return np.linalg.norm(q, axis=-1) - EARTH_RADIUS_M


__all__ = ["TOP_M", "wide_sun_table", "top_distance", "segment_air"]
