"""Ozone's absorption in the visible (the Chappuis band) as a function of wavelength.

The table is SPCTRL2's ozone absorption coefficient k (1/atm-cm), Bird & Riordan (1986, J. Clim. Appl.
Meteor. 25, 87-97; NREL TR-215-2436, 1984, Table 1; from Leckner (1978) after Vigroux (1953)), as
pvlib's ``pvlib/spectrum/spectrl2.py`` holds it (pvlib, BSD-3-Clause licence, (c) pvlib python
contributors; the report itself is a US government work), on SPCTRL2's wavelengths from 350 to 800 nm.
A cross section follows with Loschmidt's number: sigma = k / N_L, 1 atm-cm = N_L x 1 cm = 2.6868e19
molecules/cm^2. SPCTRL2 has the band's peak at 0.120 /atm-cm (4.5e-21 cm^2 near 600 nm); the laboratory
cross sections at 293 K (Serdyuchenko et al. 2014, AMT 7, 625) peak near 5.1e-21 cm^2 (about 10 % more),
and SPCTRL2 sets the band's wings below 450 nm to 0. Temperature dependence is neglected (weak in
the Chappuis band).

The RGB mode's channels (650 / 550 / 450 nm, one wavelength each for molecules and aerosol, whose spectra are
smooth) take ozone's cross section averaged over each channel's band: sigma_c = sum cbar_c E sigma / sum cbar_c E,
cbar_c the channel's sRGB colour-matching function (CIE 1931 through sRGB's matrix, ``optics.spectrum``) and E the
top-of-atmosphere sun (ASTM G173), the first-order (thin-path) absorption of sunlight in that channel; clipped at 0
(the negative lobes of the matching functions make blue's negative). The band peaks near 600 nm, inside the red
channel, and 650 nm sits on its flank: red takes 4.7e-25 m^2 against 2.6e-25 at 650 nm (1.78x), green 0.95x its
line, blue 0 against 1.1e-26 (``channel_cross_section_m2``). With the lines the RGB mode's cloud was 1-3 % too
red against the spectral mode (docs/spectral.md, "Why the RGB mode's cloud colour moved from the spectral mode's").
"""
from __future__ import annotations

import functools

import numpy as np

LOSCHMIDT_M3 = 2.6867811e25   # molecules per m^3 at 273.15 K and 101325 Pa (CODATA 2018)
ATM_CM_M2 = LOSCHMIDT_M3 * 0.01  # molecules per m^2 in a column of 1 atm-cm (1000 Dobson units)

# SPCTRL2's wavelengths (nm) and ozone absorption coefficients (1/atm-cm), 350-800 nm
_WAVELENGTH_NM = np.array([
    350.0, 360.0, 370.0, 380.0, 390.0, 400.0, 410.0, 420.0, 430.0, 440.0, 450.0, 460.0, 470.0, 480.0, 490.0,
    500.0, 510.0, 520.0, 530.0, 540.0, 550.0, 570.0, 593.0, 610.0, 630.0, 656.0, 667.6, 690.0, 710.0, 718.0,
    724.4, 740.0, 752.5, 757.5, 762.5, 767.5, 780.0, 800.0])
_K_PER_ATM_CM = np.array([
    0.007, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.003, 0.006, 0.009, 0.014, 0.021,
    0.03, 0.04, 0.048, 0.063, 0.075, 0.085, 0.12, 0.119, 0.12, 0.09, 0.065, 0.051, 0.028, 0.018, 0.015,
    0.012, 0.01, 0.008, 0.007, 0.006, 0.005, 0.0, 0.0])


def absorption_per_atm_cm(wavelength_nm) -> np.ndarray:
    """Ozone absorption coefficient k (1/atm-cm) at ``wavelength_nm`` (linear in the table; 0 past 800 nm).
    A ValueError below 350 nm (the Huggins band, not tabulated here)."""
    wl = np.asarray(wavelength_nm, np.float64)
    if np.any(wl < _WAVELENGTH_NM[0]):
        raise ValueError(f"ozone absorption is tabulated from {_WAVELENGTH_NM[0]:.0f} nm, got {float(np.min(wl))} nm")
    return np.interp(wl, _WAVELENGTH_NM, _K_PER_ATM_CM, right=0.0)


def cross_section_m2(wavelength_nm) -> np.ndarray:
    """Ozone absorption cross section (m^2 per molecule): k / (Loschmidt's number x 1 cm)."""
    return absorption_per_atm_cm(wavelength_nm) / ATM_CM_M2


def channel_cross_section_m2(wavelength_nm) -> np.ndarray:
    """Ozone's cross section (m^2) per channel: for the RGB mode's channels (``wavelength_nm`` 650, 550, 450 nm,
    ``phase.table.RGB_WAVELENGTHS_M``) the band averages of the module docstring, else :func:`cross_section_m2` at
    each wavelength (a satellite's bands, the spectral mode's wavelengths)."""
    from ..phase.table import RGB_WAVELENGTHS_M
    wl = np.asarray(wavelength_nm, np.float64)
    if wl.shape == (3,) and np.array_equal(wl, np.asarray(RGB_WAVELENGTHS_M) * 1e9):
        return rgb_channel_cross_sections_m2()
    return cross_section_m2(wl)


@functools.lru_cache(maxsize=1)
def _rgb_channels() -> tuple:
    from .. import spectrum
    wl = np.arange(360.0, 830.0 + 0.1, 1.0)
    weight = spectrum.linear_srgb(spectrum.cmfs_1931(wl)) * spectrum.solar_toa_w_m2_nm(wl)[:, None]   # (n, 3)
    return tuple(np.maximum(weight.T @ cross_section_m2(wl) / weight.sum(axis=0), 0.0).tolist())


def rgb_channel_cross_sections_m2() -> np.ndarray:
    """(3,) ozone's cross sections (m^2) for the RGB mode's R, G, B: each channel's band average (module
    docstring)."""
    return np.array(_rgb_channels())


__all__ = ["LOSCHMIDT_M3", "ATM_CM_M2", "absorption_per_atm_cm", "cross_section_m2", "channel_cross_section_m2",
           "rgb_channel_cross_sections_m2"]
