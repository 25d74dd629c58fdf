"""Light as a function of wavelength (nm), and colour as its projection: the top-of-atmosphere solar
spectrum, CIE 1931 XYZ and linear sRGB.

* The solar spectrum at the top of the atmosphere: the extraterrestrial column of ASTM G173-03
  (ASTM International, "Standard Tables for Reference Solar Spectral Irradiances: Direct Normal and
  Hemispherical on 37 deg Tilted Surface", 2003/2012; W m^-2 nm^-1 at 1 AU; the copy bundled with pvlib,
  read through ``pvlib.spectrum.get_reference_spectra``), averaged over each wavelength's bin (its
  Fraunhofer lines are finer than the grid).
* Colour: CIE 1931 2 degree colour-matching functions (colour-science), X, Y, Z = sum S(lambda)
  xbar(lambda) dlambda on a uniform grid, and linear sRGB (IEC 61966-2-1, D65 white) from XYZ through
  colour-science without chromatic adaptation: the RGB of a spectrum is its colour as sRGB shows it.

The spectral grid ``WAVELENGTHS_NM`` (360-830 nm, the CIE range, 5 nm) is what the spectral mode of the
ground truth will sample; RGB is always a projection of a spectrum on it.
"""
from __future__ import annotations

import functools

import numpy as np

WAVELENGTHS_NM = np.arange(360.0, 830.0 + 0.1, 5.0)  # the CIE 1931 range, 5 nm steps
STEP_NM = 5.0


def _check_grid(wavelength_nm) -> np.ndarray:
    wl = np.asarray(wavelength_nm, np.float64)
    if wl.ndim != 1 or wl.size < 2 or not np.allclose(np.diff(wl), wl[1] - wl[0]) or wl[0] < 300 or wl[-1] > 4000:
        raise ValueError("wavelengths must be a uniform 1-D grid in nm within 300-4000 nm, got "
                         f"{wl.size} values {wl[:3].tolist()}...")
    return wl


@functools.lru_cache(maxsize=8)
def _solar_toa(key: tuple) -> np.ndarray:
    import pvlib
    wl = np.asarray(key)
    ref = pvlib.spectrum.get_reference_spectra(standard="ASTM G173-03")
    lam = np.asarray(ref.index, np.float64)
    e = np.asarray(ref["extraterrestrial"], np.float64)
    step = wl[1] - wl[0]
    # bin averages: integral of the piecewise-linear spectrum over [lambda - step/2, lambda + step/2] / step
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (e[1:] + e[:-1]) * np.diff(lam))])
    edges = np.concatenate([wl - step / 2, [wl[-1] + step / 2]])
    integ = np.interp(edges, lam, cum)
    return np.diff(integ) / step


def solar_toa_w_m2_nm(wavelength_nm=WAVELENGTHS_NM) -> np.ndarray:
    """Extraterrestrial solar spectral irradiance normal to the beam at 1 AU (W m^-2 nm^-1), ASTM G173-03,
    averaged over each bin of the uniform grid ``wavelength_nm``."""
    wl = _check_grid(wavelength_nm)
    return _solar_toa(tuple(wl.tolist())).copy()


@functools.lru_cache(maxsize=8)
def _cmfs(key: tuple) -> np.ndarray:
    import colour
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    wl = np.asarray(key)
    out = np.stack([np.interp(wl, cmfs.wavelengths, cmfs.values[:, i], left=0.0, right=0.0) for i in range(3)], -1)
    return out


def cmfs_1931(wavelength_nm=WAVELENGTHS_NM) -> np.ndarray:
    """CIE 1931 2 degree colour-matching functions xbar, ybar, zbar at ``wavelength_nm``: (n, 3), 0 outside
    360-830 nm."""
    return _cmfs(tuple(_check_grid(wavelength_nm).tolist())).copy()


def xyz(spectrum, wavelength_nm=WAVELENGTHS_NM) -> np.ndarray:
    """CIE 1931 XYZ of spectra (..., n) on the uniform grid ``wavelength_nm``: sum S xbar dlambda
    (the spectrum's unit times nm): (..., 3)."""
    wl = _check_grid(wavelength_nm)
    s = np.asarray(spectrum, np.float64)
    if s.shape[-1] != wl.size:
        raise ValueError(f"a spectrum has {s.shape[-1]} values, the wavelength grid {wl.size}")
    return s @ cmfs_1931(wl) * (wl[1] - wl[0])


def linear_srgb(xyz_values) -> np.ndarray:
    """Linear sRGB (D65 white, no chromatic adaptation) of CIE XYZ (..., 3): colour-science's matrix."""
    import colour
    return np.asarray(colour.XYZ_to_RGB(np.asarray(xyz_values, np.float64), "sRGB", illuminant=None,
                                        chromatic_adaptation_transform=None, apply_cctf_encoding=False))


def xyz_of_linear_srgb(rgb) -> np.ndarray:
    """CIE XYZ (..., 3) of linear sRGB (D65 white, no chromatic adaptation): the inverse of :func:`linear_srgb`."""
    import colour
    return np.asarray(colour.RGB_to_XYZ(np.asarray(rgb, np.float64), "sRGB", illuminant=None,
                                        chromatic_adaptation_transform=None, apply_cctf_decoding=False))


def chromaticity_xy(xyz_values) -> np.ndarray:
    """CIE 1931 chromaticity (x, y) of XYZ (..., 3)."""
    v = np.asarray(xyz_values, np.float64)
    return v[..., :2] / np.sum(v, axis=-1, keepdims=True)


__all__ = ["WAVELENGTHS_NM", "solar_toa_w_m2_nm", "cmfs_1931", "xyz", "linear_srgb", "xyz_of_linear_srgb",
           "chromaticity_xy"]
