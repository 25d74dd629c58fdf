"""Thompson graupel's size distribution as ``mp_thompson`` sets it, by the WRF version that wrote the file
(``module_mp_thompson.F`` at the release tags of github.com/wrf-model/WRF): exponential (mu_g = 0) with an
intercept N0 from the graupel content (and, up to V4.1, from the supercooled rain or liquid in the column), or
from QNGRAUPEL where the scheme predicts it; r_eff = 1.5 / lambda_g, lambda_g = (pi rho_g N0 / rg)^(1/4).

| WRF | rho_g | N0 (m^-4), ygra1 / zans1 as in the Fortran |
|---|---|---|
| <= V3.3 | 400 | xslw1 = 5 + log10(rc + rr in [1e-5, 1e-2]) where T < 273.15 K and rc + rr > 1e-5, else 1e-4; ygra1 = 4.302 + log10(rg in [5e-5, 5e-2]); zans1 = 3.565 + 90 / (50 xslw1 ygra1 / (5 / xslw1 + 1 + 0.25 ygra1) + 30 + 15 ygra1); N0 in [1e4, 3e6] |
| V3.4 | 500 | xslw1 = 4.01 + log10(mvd_r) where T < 270.65 K and mvd_r > 100 um, else 0.01; ygra1 = 4.31 + log10(max(5e-5, rg)); zans1 = 3.0 + 100 / (300 xslw1 ygra1 / (10 / xslw1 + 1 + 0.25 ygra1) + 30 + 5 ygra1); N0 in [2e4, 2e6] |
| V3.5-V4.1 | 500 | as V3.4 but the rain term above k_0, the highest level with T >= 270.65 K; zans1 = 3.1 + 100 / (... + 30 + 10 ygra1); N0 in [1e4, 3e6] |
| V4.2 | 500 | zans1 = 3.5 + 2/7 (log10(max(1e-9, rg)) + 7) in [2, 7] |
| V4.3-V4.4 | 500 | zans1 = 3.0 + 2/7 (log10(max(1e-9, rg)) + 8) in [2, 6] |
| >= V4.5 | 400 (rho_g(idx_bg1 = 5)) | as V4.3, then the median volume diameter 3.672 / lambda_g kept in [D0r = 50 um, 25.4 mm] |

Up to V4.1 the intercept is the running minimum from the model top down each column (N0_min); there rg, rc
and rr are the contents (kg/m^3) where the mixing ratio exceeds R1 = 1e-12, else R1, and the rain's median
volume diameter mvd_r = 3.672 / lambda_r (lambda_r = (pi rho_w N_r / rr)^(1/3), kept in [37.5 um, 2.5 mm]).
With QNGRAUPEL (V4.5's two-moment graupel, MP_PHYSICS 38): lambda_g = (pi rho_g N_g / rg)^(1/3) with rho_g
from QVGRAUPEL in the scheme's 9 density bins (50..800 kg/m^3; 400 without it), the same diameter limits
(1.5 mm where N_g <= R2 = 1e-6). Arrays have the vertical first (bottom_top, bottom up).
"""
from __future__ import annotations

import re
from math import pi

import numpy as np

from .size_distributions import R1, RHO_W, T0C, masked, sel

VERSIONS = ("3.3", "3.4", "3.5", "4.2", "4.3", "4.5")
NEWEST = "4.5"
RHO_G = {"3.3": 400.0, "3.4": 500.0, "3.5": 500.0, "4.2": 500.0, "4.3": 500.0, "4.5": 400.0}
RHO_G_BINS = np.array([50.0, 100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0])
D0R = 50.0e-6
MVD_G = (D0R, 25.4e-3)


def version_of(title) -> str | None:
    """The graupel formula's version key ("3.3" ... "4.5") of a wrfout TITLE ("OUTPUT FROM WRF V3.3.1 MODEL"),
    None where it names no WRF version."""
    m = re.search(r"WRF V(\d+)\.(\d+)", str(title or ""))
    if not m:
        return None
    v = (int(m.group(1)), int(m.group(2)))
    for key, first in (("4.5", (4, 5)), ("4.3", (4, 3)), ("4.2", (4, 2)), ("3.5", (3, 5)), ("3.4", (3, 4))):
        if v >= first:
            return key
    return "3.3"


def _floored(q, rho):
    """mp_thompson's content: rho q where q > R1 (kg/kg), else R1 (kg/m^3)."""
    return np.where(q / rho > R1, q, R1)


def rain_mvd(rho_q_rain, n_rain) -> np.ndarray:
    """The rain's median volume diameter (m), mu_r = 0: 3.672 / lambda_r in [0.75 D0r, 2.5 mm]."""
    lam = (pi * RHO_W * np.maximum(n_rain, 1e-6) / rho_q_rain) ** (1.0 / 3.0)
    return np.clip(3.672 / lam, 0.75 * D0R, 2.5e-3)


def intercept(version, rho_q, t_k=None, rho=None, rho_q_rain=None, n_rain=None, rho_q_cloud=None) -> np.ndarray:
    """N0 (m^-4) of Thompson graupel of ``version`` at every point of the columns (vertical axis 0): contents
    rho_q, rho_q_rain, rho_q_cloud (kg/m^3), rain number n_rain (m^-3), temperature t_k (K), air density rho
    (kg/m^3) as the version needs them."""
    rq = np.asarray(rho_q, np.float64)
    if version in ("4.2", "4.3", "4.5"):
        y = np.log10(np.maximum(1.0e-9, rq))
        z = np.clip(3.5 + 2.0 / 7.0 * (y + 7.0), 2.0, 7.0) if version == "4.2" else \
            np.clip(3.0 + 2.0 / 7.0 * (y + 8.0), 2.0, 6.0)
        return 10.0 ** z
    rho = np.asarray(rho, np.float64)
    t = np.asarray(t_k, np.float64)
    rg = _floored(rq, rho)
    rr = _floored(np.asarray(rho_q_rain, np.float64), rho)
    if version == "3.3":
        liquid = rr + _floored(np.asarray(rho_q_cloud, np.float64), rho)
        x = np.where((t < T0C) & (liquid > 1.0e-5), 5.0 + np.log10(np.clip(liquid, 1.0e-5, 1.0e-2)), 1.0e-4)
        y = 4.302 + np.log10(np.clip(rg, 5.0e-5, 5.0e-2))
        z = 3.565 + 90.0 / (50.0 * x * y / (5.0 / x + 1.0 + 0.25 * y) + 30.0 + 15.0 * y)
        lo, hi = 1.0e4, 3.0e6
    else:
        mvd = rain_mvd(rr, np.asarray(n_rain, np.float64))
        if version == "3.4":
            above = t < 270.65
        else:  # above k_0, the highest level at or above 270.65 K (k_0 = kts where none is)
            warm = t >= 270.65
            k = np.arange(t.shape[0]).reshape((-1,) + (1,) * (t.ndim - 1))
            k_0 = np.maximum(0, np.max(np.where(warm, k, -1), axis=0))
            above = k > k_0
        rain = above & (np.asarray(rho_q_rain, np.float64) / rho > R1) & (mvd > 100.0e-6)  # L_qr
        x = np.where(rain, 4.01 + np.log10(mvd), 0.01)
        y = 4.31 + np.log10(np.maximum(5.0e-5, rg))
        c0, cy, lo, hi = (3.0, 5.0, 2.0e4, 2.0e6) if version == "3.4" else (3.1, 10.0, 1.0e4, 3.0e6)
        z = c0 + 100.0 / (300.0 * x * y / (10.0 / x + 1.0 + 0.25 * y) + 30.0 + cy * y)
    n0 = np.clip(10.0 ** z, lo, hi)
    return np.minimum.accumulate(n0[::-1], axis=0)[::-1]  # N0_min, from the top down


def radius(version, rho_q, t_k=None, rho=None, rho_q_rain=None, n_rain=None, rho_q_cloud=None) -> np.ndarray:
    """r_eff (m, float32; 0 where rho_q <= 0) of one-moment Thompson graupel of ``version`` (see ``intercept``)."""
    n0 = intercept(version, rho_q, t_k, rho, rho_q_rain, n_rain, rho_q_cloud)
    rho_g = RHO_G[version]
    def f(rq, has):
        lam = (pi * rho_g * n0[has] / rq) ** 0.25
        if version == "4.5":
            lam = np.clip(lam, 3.672 / MVD_G[1], 3.672 / MVD_G[0])
        return 1.5 / lam
    return masked(rho_q, f)


def bin_density(rho_q, volume) -> np.ndarray:
    """mp_thompson's graupel density (kg/m^3) from its volume (m^3/m^3): rb = q / rho_g clipped to the bins'
    ends, idx_bg = max(1, min(nint(q / rb * 0.01) + 1, 9)), rho_g(idx_bg)."""
    rq = np.asarray(rho_q, np.float64)
    rb = np.clip(np.asarray(volume, np.float64), rq / RHO_G_BINS[-1], rq / RHO_G_BINS[0])
    ratio = np.divide(rq, rb, out=np.full(rq.shape, RHO_G_BINS[4]), where=rb > 0)
    idx = np.clip(np.floor(ratio * 0.01 + 0.5).astype(int) + 1, 1, 9)  # nint: half away from zero (> 0 here)
    return RHO_G_BINS[idx - 1]


def radius_from_number(rho_q, number, volume=None) -> np.ndarray:
    """r_eff (m, float32) of two-moment Thompson graupel (V4.5, QNGRAUPEL; QVGRAUPEL for its density)."""
    rho_g = RHO_G["4.5"] if volume is None else bin_density(rho_q, volume)
    def f(rq, has):
        n = sel(number, has)
        dens = sel(rho_g, has)
        lam_default = 3.672 / 1.5e-3
        lam = np.where(n > 1.0e-6, (pi * dens * np.maximum(n, 1e-6) / rq) ** (1.0 / 3.0), lam_default)
        return 1.5 / np.clip(lam, 3.672 / MVD_G[1], 3.672 / MVD_G[0])
    return masked(rho_q, f)
