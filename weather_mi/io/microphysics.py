"""Particle sizes from a WRF microphysics scheme's own size distributions: the effective radius
r_eff = <r^3>/<r^2> (m) of each species at each grid point, the radius that makes Eq. 4 exact for the
distribution (beta_ext = 3 rho_air q / (2 rho_p r_eff) with the geometric-optics Q_ext = 2).

For a gamma distribution in diameter N(D) = N0 D^mu exp(-lambda D) the mass content is
rho_air q = (pi rho_p / 6) N_t Gamma(mu + 4) / (Gamma(mu + 1) lambda^3) (N_t = N0 Gamma(mu + 1) / lambda^(mu+1)),
so lambda = (pi rho_p N_t Gamma(mu + 4) / (6 Gamma(mu + 1) rho_air q))^(1/3) and r_eff = (mu + 3) / (2 lambda)
(exponential, mu = 0: r_eff = 1.5 / lambda, and with a fixed intercept N0: lambda = (pi rho_p N0 / (rho_air q))^(1/4)).

Schemes (WRF source, github.com/wrf-model/WRF, ``phys/``; each formula's routine is named where it is used):

* WSM3/5/6/7 (Hong et al. 2004, Hong & Lim 2006) and WDM5/6/7 (Lim & Hong 2010): cloud water and cloud ice
  as WRF's ``effectRad_wsm6`` / ``effectRad_wdm6`` (Bae, KIAPS 2015; ``module_mp_wsm6.F`` before the CCPP move,
  commit 81410a36a~1, and ``module_mp_wdm6.F``) with their clipping (cloud 2.51-50 um, ice 10.01-125 um); snow
  exponential with N0s = 2e6 exp(0.12 (273.15 K - T)) m^-4 (1 <= factor <= n0smax / n0s = 5e4) and rho_s = 100,
  rain exponential with N0r = 8e6 m^-4 (WDM: gamma mu = 1 from QNRAIN, ``pidnr = 4 pi rho_w``), graupel
  exponential with N0g = 4e6 m^-4 and rho_g = 500, each slope limited as the scheme limits it (lamdarmax,
  lamdasmax, lamdagmax; WDM lamdarmin/max) and snow clipped to effectRad's 25-999 um. WRF's radiation radius of
  snow is 0.5 / lambda (the mean radius); Eq. 4 needs <r^3>/<r^2> = 1.5 / lambda, used here.
* Thompson (Thompson et al. 2008; ``module_mp_thompson.F``, ``calc_effectRad``): cloud gamma with
  mu_c = min(15, 1000e6 / N_c + 2), N_c = 100e6 m^-3 or QNCLOUD (aerosol-aware); ice mu = 0, rho_i = 890 from
  QNICE; snow 0.5 M3 / M2 from the Field et al. (2005) moment relations (bm_s = 2, am_s = 0.069); clipping
  2.51-50 um (cloud), 2.51-125 um (ice), 5.01-999 um (snow). Rain mu = 0 from QNRAIN with the scheme's
  median-volume-diameter limits (0.75 D0r = 37.5 um to 2.5 mm); graupel rho_g = 500 with the intercept of
  ``mp_thompson``'s graupel N0 formula without its supercooled-rain term and column minimum (xslw1 = 0.01).
* Morrison two-moment (Morrison et al. 2009; ``module_mp_morr_two_moment.F``, EFFC/EFFI/EFFS/EFFR/EFFG):
  cloud gamma with the Martin et al. (1994) shape (2 <= pgam <= 10) from N_c = 250 cm^-3 (INUM = 1) or
  QNCLOUD; ice (rho 500), snow (100), rain (997) and graupel (400) exponential from QNICE, QNSNOW, QNRAIN,
  QNGRAUPEL, each slope clipped to the scheme's LAMMIN*/LAMMAX*.

Other schemes (NSSL, Milbrandt-Yau, P3, ...) have no rule here: ``rules`` returns none for them, and the
reader warns and keeps the species table's radii.
"""
from __future__ import annotations

from dataclasses import dataclass
from math import gamma, pi
from typing import Callable

import numpy as np

RHO_W = 1000.0       # kg/m^3, WSM/WDM/Thompson liquid water
T0C = 273.15         # K
R1 = 1.0e-12         # kg/m^3: WRF effectRad's smallest mass content
NUMBER_VARS = {"cloud": "QNCLOUD", "ice": "QNICE", "rain": "QNRAIN", "snow": "QNSNOW", "graupel": "QNGRAUPEL"}
WSM_FAMILY = {3: "WSM3", 4: "WSM5", 6: "WSM6", 24: "WSM7"}
WDM_FAMILY = {14: "WDM5", 16: "WDM6", 26: "WDM7"}
THOMPSON_FAMILY = {8: "Thompson", 28: "Thompson aerosol-aware", 38: "Thompson hail-aware"}
MORRISON_FAMILY = {10: "Morrison", 40: "Morrison+CESM aerosol"}


@dataclass(frozen=True)
class SizeRule:
    """How one species' effective radius follows from the fields: ``radius(rho_q, number, t_k)`` with the
    mass content rho_q (kg/m^3), the number concentration (m^-3; None where ``number_var`` is None) and the
    temperature (K; None unless ``needs_temperature``) gives r_eff (m, 0 where rho_q <= 0)."""

    species: str
    radius: Callable
    number_var: str | None = None
    needs_temperature: bool = False
    formula: str = ""


def _masked(rho_q, compute) -> np.ndarray:
    """``compute(rho_q)`` (float64) where rho_q > 0, else 0, as float32."""
    rq = np.asarray(rho_q)
    out = np.zeros(rq.shape, np.float32)
    has = rq > 0
    if np.any(has):  # float64 of the voxels with mass only (not a float64 copy of the grid)
        out[has] = compute(np.maximum(rq[has].astype(np.float64), R1), has)
    return out


def _sel(a, has):
    return None if a is None else np.asarray(a)[has].astype(np.float64) if np.ndim(a) else float(a)


def exponential_fixed_n0(rho_q, n0_per_m4, rho_p, lam_max=np.inf, lam_min=0.0) -> np.ndarray:
    """r_eff = 1.5 / lambda, lambda = (pi rho_p N0 / rho_q)^(1/4) clipped to [lam_min, lam_max] (1/m);
    ``n0_per_m4`` a number or a grid like ``rho_q``."""
    def f(rq, has):
        lam = (pi * rho_p * _sel(n0_per_m4, has) / rq) ** 0.25
        return 1.5 / np.clip(lam, lam_min, lam_max)
    return _masked(rho_q, f)


def gamma_from_number(rho_q, n_per_m3, rho_p, mu=0.0, lam_min=0.0, lam_max=np.inf) -> np.ndarray:
    """r_eff = (mu + 3) / (2 lambda), lambda = (pi rho_p N Gamma(mu+4) / (6 Gamma(mu+1) rho_q))^(1/3) clipped
    to [lam_min, lam_max] (1/m); N (m^-3) floored at 1e-6 as WRF's R2."""
    g = gamma(mu + 4.0) / gamma(mu + 1.0)
    def f(rq, has):
        n = np.maximum(_sel(n_per_m3, has), 1e-6)
        lam = (pi * rho_p / 6.0 * g * n / rq) ** (1.0 / 3.0)
        return (mu + 3.0) / (2.0 * np.clip(lam, lam_min, lam_max))
    return _masked(rho_q, f)


# ---- WSM / WDM ----

def wsm_cloud(rho_q, number=None, t_k=None) -> np.ndarray:
    """effectRad_wsm6: lamdac = (pi rho_w / 6 * 3e8 / rho_q)^(1/3), r = 1.5 / lamdac in [2.51, 50] um."""
    return _masked(rho_q, lambda rq, has: np.clip(1.5 / (pi * RHO_W / 6.0 * 3.0e8 / rq) ** (1.0 / 3.0),
                                                  2.51e-6, 50e-6))


def wdm_cloud(rho_q, number, t_k=None) -> np.ndarray:
    """effectRad_wdm6: n(D) = 3 N lambda^3 D^2 exp(-(lambda D)^3), lambda = (pi rho_w N / (6 rho_q))^(1/3)
    (lamdac), r_eff = 1 / (2 Gamma(5/3) lambda) in [2.51, 50] um."""
    def f(rq, has):
        lam = (pi * RHO_W / 6.0 * np.maximum(_sel(number, has), 1e-6) / rq) ** (1.0 / 3.0)
        return np.clip(1.0 / (2.0 * gamma(5.0 / 3.0) * lam), 2.51e-6, 50e-6)
    return _masked(rho_q, f)


def wsm_ice(rho_q, number=None, t_k=None) -> np.ndarray:
    """effectRad_wsm6: N_i = 5.38e7 rho_q^0.75 in [1e3, 1e6] m^-3, D_i = 11.9 sqrt(rho_q / N_i),
    r = 0.75 * 0.163 D_i in [10.01, 125] um."""
    def f(rq, has):
        ni = np.clip(5.38e7 * rq ** 0.75, 1.0e3, 1.0e6)
        return np.clip(0.75 * 0.163 * 11.9 * np.sqrt(rq / ni), 10.01e-6, 125e-6)
    return _masked(rho_q, f)


def wsm_snow_n0(t_k) -> np.ndarray:
    """N0s = 2e6 max(min(exp(0.12 (T0 - T)), n0smax / n0s), 1) m^-4 (Hong et al. 2004; n0smax = 1e11)."""
    return 2.0e6 * np.clip(np.exp(0.12 * (T0C - np.asarray(t_k, np.float64))), 1.0, 1.0e11 / 2.0e6)


def wsm_snow(rho_q, number=None, t_k=None) -> np.ndarray:
    """Exponential snow, rho_s = 100, N0s(T), lambda <= lamdasmax = 1e5, r_eff = 1.5 / lambda in [25, 999] um."""
    def f(rq, has):
        lam = np.minimum((pi * 100.0 * wsm_snow_n0(_sel(t_k, has)) / rq) ** 0.25, 1.0e5)
        return np.clip(1.5 / lam, 25e-6, 999e-6)
    return _masked(rho_q, f)


def wsm_rain(rho_q, number=None, t_k=None) -> np.ndarray:
    """Exponential rain, N0r = 8e6 m^-4, lambda <= lamdarmax = 8e4."""
    return exponential_fixed_n0(rho_q, 8.0e6, RHO_W, lam_max=8.0e4)


def wdm_rain(rho_q, number, t_k=None) -> np.ndarray:
    """WDM rain: gamma mu = 1 (pidnr = 4 pi rho_w) from N_r, lamdarmin = 2e3 <= lambda <= lamdarmax = 5e4."""
    return gamma_from_number(rho_q, number, RHO_W, mu=1.0, lam_min=2.0e3, lam_max=5.0e4)


def wsm_graupel(rho_q, number=None, t_k=None) -> np.ndarray:
    """Exponential graupel, N0g = 4e6 m^-4, rho_g = 500 (hail_opt = 0), lambda <= lamdagmax = 6e4."""
    return exponential_fixed_n0(rho_q, 4.0e6, 500.0, lam_max=6.0e4)


# ---- Thompson ----

THOMPSON_NT_C = 100.0e6
THOMPSON_SA = (5.065339, -0.062659, -3.032362, 0.029469, -0.000285, 0.31255, 0.000204, 0.003199, 0.0, -0.015952)
THOMPSON_SB = (0.476221, -0.015896, 0.165977, 0.007468, -0.000141, 0.060366, 0.000079, 0.000594, 0.0, -0.003577)


def thompson_cloud(rho_q, number=None, t_k=None) -> np.ndarray:
    """calc_effectRad: mu_c = min(15, nint(1000e6 / N_c) + 2) (15 below 100, 2 above 1e10 m^-3), N_c = 100e6
    (or QNCLOUD, <= 1999e6), r = 0.5 (3 + mu_c) / lambda_c in [2.51, 50] um."""
    def f(rq, has):
        n = np.full(rq.shape, THOMPSON_NT_C) if number is None else np.clip(_sel(number, has), 2.0, 1999.0e6)
        mu = np.where(n < 100, 15, np.where(n > 1e10, 2, np.minimum(15, np.rint(1000.0e6 / n) + 2)))
        g = (mu + 3) * (mu + 2) * (mu + 1)  # g_ratio = Gamma(mu + 4) / Gamma(mu + 1)
        lam = (n * pi * RHO_W / 6.0 * g / rq) ** (1.0 / 3.0)
        return np.clip(0.5 * (3.0 + mu) / lam, 2.51e-6, 50e-6)
    return _masked(rho_q, f)


def thompson_ice(rho_q, number, t_k=None) -> np.ndarray:
    """calc_effectRad: lambda_i = (am_i Gamma(4) N_i / rho_q)^(1/3), am_i = pi 890 / 6, r = 1.5 / lambda_i in
    [2.51, 125] um."""
    r = gamma_from_number(rho_q, number, 890.0, mu=0.0)
    return np.where(r > 0, np.clip(r, 2.51e-6, 125e-6), 0).astype(np.float32)


def _field_moment(n_moment: float, tc, m2):
    """Field et al. (2005) as in Thompson: M_n = a(T, n) M2^b(T, n), log10 a and b cubic in (T_c, n)."""
    def poly(c):
        return (c[0] + c[1] * tc + c[2] * n_moment + c[3] * tc * n_moment + c[4] * tc * tc
                + c[5] * n_moment ** 2 + c[6] * tc * tc * n_moment + c[7] * tc * n_moment ** 2
                + c[8] * tc ** 3 + c[9] * n_moment ** 3)
    return 10.0 ** poly(THOMPSON_SA) * m2 ** poly(THOMPSON_SB)


def thompson_snow(rho_q, number=None, t_k=None) -> np.ndarray:
    """calc_effectRad: M2 = rho_q / am_s (am_s = 0.069, bm_s = 2), M3 = a M2^b at T_c = min(-0.1, T - T0),
    r = 0.5 M3 / M2 in [5.01, 999] um."""
    def f(rq, has):
        tc = np.minimum(-0.1, _sel(t_k, has) - T0C)
        m2 = rq / 0.069
        return np.clip(0.5 * _field_moment(3.0, tc, m2) / m2, 5.01e-6, 999e-6)
    return _masked(rho_q, f)


def thompson_rain(rho_q, number, t_k=None) -> np.ndarray:
    """Rain mu = 0 from N_r; the median volume diameter (3.672 / lambda) kept in [0.75 D0r, 2.5 mm]."""
    return gamma_from_number(rho_q, number, RHO_W, mu=0.0, lam_min=3.672 / 2.5e-3, lam_max=3.672 / 37.5e-6)


def thompson_graupel_n0(rho_q) -> np.ndarray:
    """mp_thompson's graupel intercept without supercooled rain: ygra1 = 4.31 + log10(max(5e-5, rho_q)),
    zans1 = 3.1 + 100 / (300 xslw1 ygra1 / (10 / xslw1 + 1 + 0.25 ygra1) + 30 + 10 ygra1), xslw1 = 0.01,
    N0 = 10^zans1 in [gonv_min, gonv_max] = [1e4, 3e6] m^-4."""
    ygra1 = 4.31 + np.log10(np.maximum(5.0e-5, rho_q))
    x = 0.01
    zans1 = 3.1 + 100.0 / (300.0 * x * ygra1 / (10.0 / x + 1.0 + 0.25 * ygra1) + 30.0 + 10.0 * ygra1)
    return np.clip(10.0 ** zans1, 1.0e4, 3.0e6)


def thompson_graupel(rho_q, number=None, t_k=None) -> np.ndarray:
    """Graupel mu = 0, rho_g = 500, N0 of ``thompson_graupel_n0`` (or from QNGRAUPEL where given)."""
    if number is not None:
        return gamma_from_number(rho_q, number, 500.0, mu=0.0)
    return _masked(rho_q, lambda rq, has: 1.5 / (pi * 500.0 * thompson_graupel_n0(rq) / rq) ** 0.25)


# ---- Morrison ----

MORRISON_NC = 250.0e6  # m^-3 (NDCNST = 250 cm^-3, INUM = 1)


def morrison_cloud(rho_q, number=None, t_k=None) -> np.ndarray:
    """EFFC: pgam = 1 / (0.0005714 N_c[cm^-3] + 0.2714)^2 - 1 in [2, 10] (Martin et al. 1994), lambda_c =
    (pi rho_w / 6 N_c Gamma(pgam + 4) / (rho_q Gamma(pgam + 1)))^(1/3) in [(pgam + 1) / 60 um, (pgam + 1) / 1 um],
    r = (pgam + 3) / (2 lambda_c); rho_w = 997."""
    def f(rq, has):
        n = np.full(rq.shape, MORRISON_NC) if number is None else np.maximum(_sel(number, has), 1e-6)
        pgam = np.clip(1.0 / (0.0005714 * n / 1e6 + 0.2714) ** 2 - 1.0, 2.0, 10.0)
        g = (pgam + 3) * (pgam + 2) * (pgam + 1)
        lam = np.clip((pi * 997.0 / 6.0 * n * g / rq) ** (1.0 / 3.0), (pgam + 1) / 60e-6, (pgam + 1) / 1e-6)
        return (pgam + 3.0) / (2.0 * lam)
    return _masked(rho_q, f)


def _morrison(rho_p, d_max_m, d_min_m):
    def radius(rho_q, number, t_k=None):
        return gamma_from_number(rho_q, number, rho_p, mu=0.0, lam_min=1.0 / d_max_m, lam_max=1.0 / d_min_m)
    return radius


MORRISON = {"ice": _morrison(500.0, 2 * 125e-6 + 100e-6, 1e-6), "snow": _morrison(100.0, 2000e-6, 10e-6),
            "rain": _morrison(997.0, 2800e-6, 20e-6), "graupel": _morrison(400.0, 2000e-6, 20e-6)}


def rules(mp: int, variables) -> dict[str, SizeRule]:
    """The size rules of microphysics scheme ``mp`` (MP_PHYSICS) by species, given the names of the file's
    ``variables`` (number concentrations used where the file has them); empty for a scheme without rules."""
    has = set(variables)
    if mp in WSM_FAMILY or mp in WDM_FAMILY:
        wdm = mp in WDM_FAMILY
        out = {"ice": SizeRule("ice", wsm_ice, formula="effectRad_wsm6 ice"),
               "snow": SizeRule("snow", wsm_snow, needs_temperature=True, formula="exponential, N0s(T)"),
               "graupel": SizeRule("graupel", wsm_graupel, formula="exponential, N0g = 4e6")}
        if wdm and "QNCLOUD" in has:
            out["cloud"] = SizeRule("cloud", wdm_cloud, "QNCLOUD", formula="effectRad_wdm6 cloud")
        else:
            out["cloud"] = SizeRule("cloud", wsm_cloud, formula="effectRad_wsm6 cloud")
        if wdm and "QNRAIN" in has:
            out["rain"] = SizeRule("rain", wdm_rain, "QNRAIN", formula="gamma mu = 1 from QNRAIN")
        else:
            out["rain"] = SizeRule("rain", wsm_rain, formula="exponential, N0r = 8e6")
        return out
    if mp in THOMPSON_FAMILY:
        out = {"cloud": SizeRule("cloud", thompson_cloud, "QNCLOUD" if "QNCLOUD" in has else None,
                                 formula="calc_effectRad cloud"),
               "snow": SizeRule("snow", thompson_snow, needs_temperature=True, formula="calc_effectRad snow"),
               "graupel": SizeRule("graupel", thompson_graupel, "QNGRAUPEL" if "QNGRAUPEL" in has else None,
                                   formula="exponential graupel")}
        if "QNICE" in has:
            out["ice"] = SizeRule("ice", thompson_ice, "QNICE", formula="calc_effectRad ice")
        if "QNRAIN" in has:
            out["rain"] = SizeRule("rain", thompson_rain, "QNRAIN", formula="exponential from QNRAIN")
        return out
    if mp in MORRISON_FAMILY:
        out = {"cloud": SizeRule("cloud", morrison_cloud, "QNCLOUD" if "QNCLOUD" in has else None,
                                 formula="EFFC")}
        for name, fn in MORRISON.items():
            if NUMBER_VARS[name] in has:
                out[name] = SizeRule(name, fn, NUMBER_VARS[name], formula=f"exponential from {NUMBER_VARS[name]}")
        return out
    return {}
