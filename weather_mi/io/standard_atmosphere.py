"""U.S. Standard Atmosphere 1976 (NOAA/NASA/USAF), layers up to 47 km: air density for inputs
that carry no thermodynamic state (LES liquid-water files, synthetic storms)."""
from __future__ import annotations

import numpy as np

G0 = 9.80665            # m/s^2
R_AIR = 287.053         # J/(kg K), USSA-1976 value of R*/M0
R_EARTH = 6356766.0     # m, radius used by USSA-1976 for geopotential height
# layer base geopotential height (m), base temperature (K), lapse rate (K/m)
_LAYERS = ((0.0, 288.15, -0.0065), (11000.0, 216.65, 0.0), (20000.0, 216.65, 0.001),
           (32000.0, 228.65, 0.0028), (47000.0, 270.65, 0.0))
P0_PA = 101325.0


def _base_pressures() -> list[float]:
    p = [P0_PA]
    for (h0, t0, lapse), (h1, _, _) in zip(_LAYERS[:-1], _LAYERS[1:]):
        if lapse == 0.0:
            p.append(p[-1] * np.exp(-G0 * (h1 - h0) / (R_AIR * t0)))
        else:
            p.append(p[-1] * ((t0 + lapse * (h1 - h0)) / t0) ** (-G0 / (R_AIR * lapse)))
    return p


_P_BASE = _base_pressures()


def standard_temperature_pressure(z_m):
    """Temperature (K) and pressure (Pa) of the 1976 standard atmosphere at geometric height z_m (m)."""
    z = np.asarray(z_m, dtype=np.float64)
    h = R_EARTH * z / (R_EARTH + z)  # geopotential height
    t = np.empty_like(h)
    p = np.empty_like(h)
    for i, (h0, t0, lapse) in enumerate(_LAYERS):
        upper = _LAYERS[i + 1][0] if i + 1 < len(_LAYERS) else np.inf
        sel = (h >= h0) & (h < upper) if i > 0 else (h < upper)
        dh = h[sel] - h0
        if lapse == 0.0:
            t[sel] = t0
            p[sel] = _P_BASE[i] * np.exp(-G0 * dh / (R_AIR * t0))
        else:
            t[sel] = t0 + lapse * dh
            p[sel] = _P_BASE[i] * (t[sel] / t0) ** (-G0 / (R_AIR * lapse))
    return t, p


def standard_density(z_m):
    """Air density (kg/m^3) of the 1976 standard atmosphere at geometric height z_m (m): 1.225 at 0 m."""
    t, p = standard_temperature_pressure(z_m)
    return p / (R_AIR * t)
