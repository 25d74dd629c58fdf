"""The sun's light after its path through the air: transmittance per wavelength, height and solar zenith,
and its colour as linear sRGB.

* :func:`transmittance`: T(lambda, h, mu) = exp(-sum_k sigma_k(lambda) C_k(h, mu)), the slant columns C_k
  of ``shell.slant_columns`` through the spherical shell (0 where the Earth blocks the sun).
* :func:`sun_rgb`: the colour of the direct sun, the projection of the spectrum E_toa(lambda) T(lambda)
  (``optics.spectrum``: ASTM G173-03 extraterrestrial spectrum, CIE 1931 XYZ, linear sRGB with its D65
  white, no chromatic adaptation) divided by the luminance Y of the sun above the atmosphere. So the
  top-of-atmosphere sun has luminance 1 and its own colour, linear sRGB (1.10, 0.98, 0.94) (chromaticity
  (0.3234, 0.3327), a little warmer than D65's (0.3127, 0.3290)): the colours are absolute (a white cloud
  lit by it has the sun's chromaticity), not white-balanced.
* :class:`SunAirTable`: that colour tabulated once per scene over heights and a band of mu about the
  scene's sun (a point displaced horizontally by d from the scene's centre sees the sun at a zenith angle
  d / R larger or smaller): what the path tracer looks up per vertex (``rgb``, (n_mu, n_h, 3)) and the
  slicer per height (:meth:`SunAirTable.by_height`).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .. import spectrum
from .atmosphere import TOP_M, Atmosphere
from .shell import EARTH_RADIUS_M, slant_columns

MU_SAMPLES = 33
HEIGHT_SAMPLES = 129
MU_MARGIN_DEG = 0.25


def transmittance(atm: Atmosphere, wavelength_nm, h_m, mu, samples: int | None = None) -> np.ndarray:
    """Direct-beam transmittance from space to heights ``h_m`` (m above sea level) with the sun at cos(zenith)
    ``mu`` (broadcast together: (...)) at wavelengths (n,): (..., n); 0 where the Earth is in the way.
    ``samples``: the slant columns' points per segment (``shell.slant_columns``; None: its default)."""
    kw = {} if samples is None else {"samples": int(samples)}
    columns, blocked = slant_columns(atm.profiles, h_m, mu, TOP_M, **kw)
    tau = atm.optical_depths(wavelength_nm, columns)
    return np.where(blocked[..., None], 0.0, np.exp(-tau))


def toa_luminance(wl) -> float:
    """The top-of-atmosphere sun's luminance Y (ASTM G173 over the wavelengths ``wl``, nm)."""
    return _toa_luminance(tuple(np.asarray(wl, np.float64).tolist()))


@functools.lru_cache(maxsize=8)
def _toa_luminance(wl: tuple) -> float:
    """``toa_luminance`` of a wavelength grid, once per grid (0.3-0.6 ms of every new sun in the slicer)."""
    return float(spectrum.xyz(spectrum.solar_toa_w_m2_nm(wl), wl)[1])


def sun_xyz(atm: Atmosphere, h_m, mu, wavelength_nm=spectrum.WAVELENGTHS_NM, samples: int | None = None) -> np.ndarray:
    """CIE XYZ of the direct sun at (h_m, mu) (...), over the top-of-atmosphere sun's luminance: (..., 3)."""
    wl = np.asarray(wavelength_nm, np.float64)
    t = transmittance(atm, wl, h_m, mu, samples)
    return spectrum.xyz(spectrum.solar_toa_w_m2_nm(wl) * t, wl) / toa_luminance(wl)


def sun_rgb(atm: Atmosphere, h_m, mu, wavelength_nm=spectrum.WAVELENGTHS_NM, samples: int | None = None) -> np.ndarray:
    """Linear sRGB of the direct sun at (h_m, mu), the top-of-atmosphere sun's luminance 1 (module docstring;
    ``samples``: ``transmittance``'s)."""
    return spectrum.linear_srgb(sun_xyz(atm, h_m, mu, wavelength_nm, samples))


@dataclass(frozen=True)
class SunAirTable:
    """The direct sun's linear sRGB over heights (m above sea level, uniform) and cos(zenith) (uniform):
    ``rgb`` (n_mu, n_h, 3), float32 (``sun_rgb``)."""

    heights_m: np.ndarray
    mu: np.ndarray
    rgb: np.ndarray

    def at(self, h_m, mu) -> np.ndarray:
        """Bilinear lookup (clamped to the table) at heights and cosines (...): (..., 3)."""
        def coord(v, grid):
            f = np.clip((np.asarray(v, np.float64) - grid[0]) / (grid[-1] - grid[0]), 0.0, 1.0) * (grid.size - 1)
            i = np.minimum(np.floor(f).astype(int), grid.size - 2)
            return i, (f - i)[..., None]
        (ih, fh), (im, fm) = coord(h_m, self.heights_m), coord(mu, self.mu)
        t = self.rgb.astype(np.float64)
        lo = t[im, ih] * (1 - fh) + t[im, ih + 1] * fh
        hi = t[im + 1, ih] * (1 - fh) + t[im + 1, ih + 1] * fh
        return lo * (1 - fm) + hi * fm

    def by_height(self, mu: float) -> np.ndarray:
        """The sun's RGB at every height of the table for one cos(zenith): (n_h, 3) (for the slicer)."""
        return self.at(self.heights_m, np.full(self.heights_m.shape, float(mu)))


def sun_air_table(atm: Atmosphere, mu0: float, top_m: float, half_width_m: float = 0.0,
                  band_nm=None) -> SunAirTable:
    """The table for a scene whose sun is at cos(zenith) ``mu0`` at its centre, heights 0..``top_m`` and
    points up to ``half_width_m`` horizontally from the centre (the band of mu their local zenith spans).
    ``band_nm``: one wavelength per channel (a satellite's bands, nm): ``rgb`` holds the direct beam's
    ``transmittance`` at each instead of the sun's colour."""
    if not -1.0 <= mu0 <= 1.0:
        raise ValueError(f"mu0 must be a cosine, got {mu0}")
    if not top_m > 0.0:
        raise ValueError(f"the table's top must be above sea level, got {top_m} m")
    sza = np.arccos(mu0)
    delta = half_width_m / EARTH_RADIUS_M + np.radians(MU_MARGIN_DEG)
    mu = np.cos(np.linspace(min(sza + delta, np.pi), max(sza - delta, 0.0), MU_SAMPLES))
    mu = np.linspace(mu[0], mu[-1], MU_SAMPLES)  # uniform in mu (the lookup's grid)
    heights = np.linspace(0.0, float(top_m), HEIGHT_SAMPLES)
    rgb = channel_values(atm, heights[None, :], mu[:, None], band_nm)
    return SunAirTable(heights_m=heights, mu=mu, rgb=rgb.astype(np.float32))


def channel_values(atm: Atmosphere, h_m, mu, band_nm=None) -> np.ndarray:
    """The direct sun per channel at (h_m, mu) (...): (..., 3): its colour (``sun_rgb``) for ``band_nm`` None,
    else its ``transmittance`` at each channel's wavelength ``band_nm`` (3,) (nm; a satellite's bands)."""
    if band_nm is None:
        return sun_rgb(atm, h_m, mu)
    return transmittance(atm, np.asarray(band_nm, np.float64), h_m, mu)


__all__ = ["transmittance", "sun_xyz", "sun_rgb", "SunAirTable", "sun_air_table", "channel_values"]
