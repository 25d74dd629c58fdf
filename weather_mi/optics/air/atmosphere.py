"""A clear 1-D atmosphere: what it holds at each height and how each part's extinction depends on
wavelength (nm).

* Molecules: number density n_air(z) = rho(z) N_A / M_air from the US Standard Atmosphere 1976
  (``io.standard_atmosphere``; isothermal above 47 km), Rayleigh cross section of Bodhaine et al. (1999)
  (``optics.rayleigh``).
* Ozone: a column of ``ozone_atm_cm`` (atm-cm; 0.3 = 300 Dobson units) in a Gaussian layer centred at
  22 km (the height SPCTRL2's ozone air mass, Bird & Riordan 1986 Eq. 2-10, assumes) with a standard
  deviation of 7 km: a stand-in for the US Standard 1976 ozone profile (peak 20-25 km, half its peak
  density about 8 km either side); cross section of the Chappuis band from ``air.ozone``.
* Aerosol: extinction beta_a(z, lambda) = AOD / H exp(-z / H) (lambda / 550 nm)^-alpha: an exponential
  profile of scale height H (default 1.2 km, a continental boundary-layer aerosol as in Elterman 1968's
  tropospheric model and the sky models that follow it) whose column from sea level is ``aod_550``, and
  Angstrom's law with exponent alpha (default 1.14, SPCTRL2's rural aerosol). Single-scattering albedo
  ``aerosol_ssa`` (0.945, SPCTRL2's rural value at 400 nm) and asymmetry ``aerosol_g`` (0.65, SPCTRL2's)
  describe its scattering where the air enters a medium; the sun's transmittance needs extinction only.

* Water vapour: ``water_vapour_cm`` of precipitable water from sea level to space (default 1.4 cm, SPCTRL2's
  and the issue's reference; the US Standard 1976 column is similar) in an exponential profile of scale height
  2 km, absorbing by SPCTRL2's band model (``air.water_vapour``: near 593 nm and 690-740 nm in the visible, zero
  at 450, 550 and 650 nm). A band model holds for whole paths: it enters the sun's transmittance
  (``optical_depths`` of slant columns) and so the sun's colour (with 1.4 cm the setting sun's chromaticity moves
  by about 0.005); the air's extinction at a point (``extinction_per_m``: the box's medium, the eye rays) leaves it
  out.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...io.standard_atmosphere import standard_density
from ..rayleigh import AVOGADRO, M_AIR_KG_MOL, cross_section_m2 as rayleigh_cross_section_m2
from . import water_vapour
from .ozone import ATM_CM_M2, cross_section_m2 as ozone_cross_section_m2

TOP_M = 80e3                 # top of the atmosphere (the air above holds < 2e-5 of the column)
OZONE_PEAK_M = 22e3
OZONE_SIGMA_M = 7e3
REFERENCE_NM = 550.0         # the aerosol optical depth's wavelength
AOD_RANGE = (0.0, 3.0)
OZONE_RANGE_ATM_CM = (0.0, 0.6)


def _in_range(value, lo, hi, what):
    v = value
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) or not np.isfinite(v) \
            or not lo <= float(v) <= hi:
        raise ValueError(f"{what} must be a number in [{lo}, {hi}], got {value!r}")
    return float(v)


@dataclass(frozen=True)
class Atmosphere:
    """A clear atmosphere (module docstring): aerosol optical depth at 550 nm (sea level to space, in
    [0, 3]), ozone column (atm-cm, in [0, 0.6]), Angstrom exponent, aerosol scale height (m), aerosol
    single-scattering albedo and asymmetry, precipitable water (cm, in [0, 10]). A ValueError names the parameter
    out of range."""

    aod_550: float = 0.1
    ozone_atm_cm: float = 0.3
    angstrom: float = 1.14
    aerosol_scale_height_m: float = 1200.0
    aerosol_ssa: float = 0.945
    aerosol_g: float = 0.65
    water_vapour_cm: float = 1.4

    def __post_init__(self):
        for name, lo, hi, what in (("aod_550", *AOD_RANGE, "aerosol optical depth at 550 nm (--aod)"),
                                   ("ozone_atm_cm", *OZONE_RANGE_ATM_CM, "ozone column in atm-cm (--ozone)"),
                                   ("angstrom", 0.0, 3.0, "Angstrom exponent"),
                                   ("aerosol_scale_height_m", 100.0, 10e3, "aerosol scale height (m)"),
                                   ("aerosol_ssa", 0.0, 1.0, "aerosol single-scattering albedo"),
                                   ("aerosol_g", -1.0, 1.0, "aerosol asymmetry"),
                                   ("water_vapour_cm", *water_vapour.RANGE_CM,
                                    "precipitable water in cm (--water-vapour)")):
            object.__setattr__(self, name, _in_range(getattr(self, name), lo, hi, what))

    # ---------------------------------------------------------------- per height
    def air_number_density_m3(self, z_m) -> np.ndarray:
        """Molecules of air per m^3 at height z (m above sea level), US Standard 1976."""
        return standard_density(np.clip(z_m, 0.0, None)) * AVOGADRO / M_AIR_KG_MOL

    def ozone_number_density_m3(self, z_m) -> np.ndarray:
        """Ozone molecules per m^3 at z: the Gaussian layer holding ``ozone_atm_cm`` between 0 and TOP_M."""
        from scipy.special import erf
        s = OZONE_SIGMA_M * np.sqrt(2.0)
        norm = 0.5 * OZONE_SIGMA_M * np.sqrt(2 * np.pi) * (erf((TOP_M - OZONE_PEAK_M) / s) + erf(OZONE_PEAK_M / s))
        z = np.asarray(z_m, np.float64)
        return self.ozone_atm_cm * ATM_CM_M2 / norm * np.exp(-0.5 * ((z - OZONE_PEAK_M) / OZONE_SIGMA_M) ** 2)

    def aerosol_extinction_550_per_m(self, z_m) -> np.ndarray:
        """Aerosol extinction at 550 nm (1/m) at z: AOD / H exp(-z / H)."""
        h = self.aerosol_scale_height_m
        return self.aod_550 / h * np.exp(-np.clip(np.asarray(z_m, np.float64), 0.0, None) / h)

    # ---------------------------------------------------------------- per wavelength
    def aerosol_factor(self, wavelength_nm) -> np.ndarray:
        """Angstrom's law: extinction at lambda over extinction at 550 nm, (lambda / 550)^-alpha."""
        return (np.asarray(wavelength_nm, np.float64) / REFERENCE_NM) ** -self.angstrom

    def extinction_per_m(self, wavelength_nm, z_m) -> np.ndarray:
        """Extinction of the air (molecules, ozone, aerosol; 1/m) at wavelengths (n,) and heights (...):
        (..., n)."""
        wl = np.asarray(wavelength_nm, np.float64)
        z = np.asarray(z_m, np.float64)[..., None]
        return (self.air_number_density_m3(z) * rayleigh_cross_section_m2(wl * 1e-9)
                + self.ozone_number_density_m3(z) * ozone_cross_section_m2(wl)
                + self.aerosol_extinction_550_per_m(z) * self.aerosol_factor(wl))

    def optical_depths(self, wavelength_nm, columns: dict) -> np.ndarray:
        """Optical depth (..., n) of slant ``columns`` (``shell.slant_columns``: air and ozone in molecules
        per m^2, aerosol as its optical depth at 550 nm, water as precipitable cm, by the band model) at wavelengths
        (n,)."""
        wl = np.asarray(wavelength_nm, np.float64)
        tau = (np.asarray(columns["air"])[..., None] * rayleigh_cross_section_m2(wl * 1e-9)
               + np.asarray(columns["ozone"])[..., None] * ozone_cross_section_m2(wl)
               + np.asarray(columns["aerosol"])[..., None] * self.aerosol_factor(wl))
        if "water" in columns:
            tau = tau + water_vapour.band_optical_depth(wl, columns["water"])  # Bird & Riordan Eq. 2-8
        return tau

    def profiles(self, z_m, water: bool = True) -> dict:
        """The constituents at heights z_m: air and ozone (molecules/m^3), aerosol (1/m at 550 nm), water vapour
        (precipitable cm per m; only where ``water`` is asked for and ``water_vapour_cm`` > 0)."""
        out = {"air": self.air_number_density_m3(z_m), "ozone": self.ozone_number_density_m3(z_m),
               "aerosol": self.aerosol_extinction_550_per_m(z_m)}
        if water and self.water_vapour_cm > 0.0:
            out["water"] = water_vapour.column_density_cm_per_m(self.water_vapour_cm, z_m)
        return out


__all__ = ["Atmosphere", "TOP_M", "AOD_RANGE", "OZONE_RANGE_ATM_CM"]
