"""Water vapour's absorption in the visible and near infrared: SPCTRL2's band model.

The coefficients a_w (1/cm of precipitable water) are SPCTRL2's, Bird & Riordan (1986, J. Clim. Appl. Meteor. 25,
87-97; NREL TR-215-2436, 1984, Table 1; from Leckner 1978), as pvlib's ``pvlib/spectrum/spectrl2.py`` holds them
(pvlib, BSD-3-Clause licence, (c) pvlib python contributors; the report itself is a US government work), on
SPCTRL2's wavelengths from 300 to 4000 nm, linear in wavelength between them. In the visible, water absorbs in
the bands near 593 nm and 690-740 nm (zero at 450, 550 and 650 nm); the strong bands beyond (820, 940 nm) lie
outside CIE XYZ's weights.

A band model, not Beer-Lambert: the transmittance of a path holding u cm of precipitable water is
(Bird & Riordan 1986, Eq. 2-8)

    T_w = exp(-0.2385 a_w u / (1 + 20.07 a_w u)^0.45),

so the optical depth it adds, ``band_optical_depth``, grows more slowly than u: the lines saturate. It applies to
whole paths (the sun's slant path, ``Atmosphere.optical_depths``); a local extinction coefficient does not exist.
"""
from __future__ import annotations

import numpy as np

SCALE_HEIGHT_M = 2000.0  # water vapour's scale height: its density falls as exp(-z / 2 km) (mid-latitudes, 1.5-2.5 km)
RANGE_CM = (0.0, 10.0)   # precipitable water from sea level to space, cm (tropics about 5, deserts and polar below 1)

# SPCTRL2's wavelengths (nm) and water vapour absorption coefficients (1/cm), 300-4000 nm (all 122 of its nodes)
_WAVELENGTH_NM = np.array([
    300.0, 305.0, 310.0, 315.0, 320.0, 325.0, 330.0, 335.0, 340.0, 345.0, 350.0, 360.0, 370.0, 380.0, 390.0,
    400.0, 410.0, 420.0, 430.0, 440.0, 450.0, 460.0, 470.0, 480.0, 490.0, 500.0, 510.0, 520.0, 530.0, 540.0,
    550.0, 570.0, 593.0, 610.0, 630.0, 656.0, 667.6, 690.0, 710.0, 718.0, 724.4, 740.0, 752.5, 757.5, 762.5,
    767.5, 780.0, 800.0, 816.0, 823.7, 831.5, 840.0, 860.0, 880.0, 905.0, 915.0, 925.0, 930.0, 937.0, 948.0,
    965.0, 980.0, 993.5, 1040.0, 1070.0, 1100.0, 1120.0, 1130.0, 1145.0, 1161.0, 1170.0, 1200.0, 1240.0, 1270.0,
    1290.0, 1320.0, 1350.0, 1395.0, 1442.5, 1462.5, 1477.0, 1497.0, 1520.0, 1539.0, 1558.0, 1578.0, 1592.0,
    1610.0, 1630.0, 1646.0, 1678.0, 1740.0, 1800.0, 1860.0, 1920.0, 1960.0, 1985.0, 2005.0, 2035.0, 2065.0,
    2100.0, 2148.0, 2198.0, 2270.0, 2360.0, 2450.0, 2500.0, 2600.0, 2700.0, 2800.0, 2900.0, 3000.0, 3100.0,
    3200.0, 3300.0, 3400.0, 3500.0, 3600.0, 3700.0, 3800.0, 3900.0, 4000.0])
_A_PER_CM = np.array([
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.075, 0.0, 0.0, 0.0, 0.0, 0.016, 0.0125, 1.8, 2.5,
    0.061, 0.0008, 0.0001, 1e-05, 1e-05, 0.0006, 0.036, 1.6, 2.5, 0.5, 0.155, 1e-05, 0.0026, 7.0, 5.0, 5.0,
    27.0, 55.0, 45.0, 4.0, 1.48, 0.1, 1e-05, 0.001, 3.2, 115.0, 70.0, 75.0, 10.0, 5.0, 2.0, 0.002, 0.002, 0.1,
    4.0, 200.0, 1000.0, 185.0, 80.0, 80.0, 12.0, 0.16, 0.002, 0.0005, 0.0001, 1e-05, 0.0001, 0.001, 0.01, 0.036,
    1.1, 130.0, 1000.0, 500.0, 100.0, 4.0, 2.9, 1.0, 0.4, 0.22, 0.25, 0.33, 0.5, 4.0, 80.0, 310.0, 15000.0,
    22000.0, 8000.0, 650.0, 240.0, 230.0, 100.0, 120.0, 19.5, 3.6, 3.1, 2.5, 1.4, 0.17, 0.0045])


def absorption_per_cm(wavelength_nm) -> np.ndarray:
    """SPCTRL2's a_w (1/cm) at wavelengths (nm), linear between its nodes; a ValueError outside 300-4000 nm."""
    wl = np.asarray(wavelength_nm, np.float64)
    if np.any((wl < _WAVELENGTH_NM[0]) | (wl > _WAVELENGTH_NM[-1])):
        raise ValueError(f"water vapour's absorption is tabulated for {_WAVELENGTH_NM[0]:g}-{_WAVELENGTH_NM[-1]:g} "
                         f"nm, got {wl.min():g}-{wl.max():g} nm")
    return np.interp(wl, _WAVELENGTH_NM, _A_PER_CM)


def band_optical_depth(wavelength_nm, water_cm) -> np.ndarray:
    """-ln T_w of paths holding ``water_cm`` (...) cm of precipitable water at wavelengths (n,): (..., n)
    (Bird & Riordan 1986, Eq. 2-8; module docstring)."""
    aw_u = absorption_per_cm(wavelength_nm) * np.asarray(water_cm, np.float64)[..., None]
    return 0.2385 * aw_u / (1.0 + 20.07 * aw_u) ** 0.45


def column_density_cm_per_m(water_cm: float, z_m) -> np.ndarray:
    """Precipitable water per metre of path (cm/m) at heights z (m above sea level): ``water_cm`` from sea level to
    space in an exponential profile of ``SCALE_HEIGHT_M``."""
    z = np.clip(np.asarray(z_m, np.float64), 0.0, None)
    return water_cm / SCALE_HEIGHT_M * np.exp(-z / SCALE_HEIGHT_M)


__all__ = ["absorption_per_cm", "band_optical_depth", "column_density_cm_per_m", "RANGE_CM", "SCALE_HEIGHT_M"]
