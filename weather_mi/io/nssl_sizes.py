"""Effective radii (m) of the NSSL two-moment scheme (Mansell et al. 2010, Mansell & Ziegler 2013; WRF
``phys/module_mp_nssl_2mom.F``, ``calc_eff_radius``; MP_PHYSICS 17, 18, 22) from its number concentrations.

The distributions, with WRF's namelist defaults (Registry.EM_COMMON ``nssl_*``):

* cloud droplets, cloud ice and snow: gamma in particle volume, n(v) ~ v^nu exp(-lambda_v v), nu = cnu = 0,
  cinu = 0, snu = -0.8; lambda = (pi/6 rho_p N Gamma(2 + nu) / (rho q Gamma(1 + nu)))^(1/3) and
  r_eff = 0.5 (1 + nu) Gamma(1 + nu) / (Gamma(5/3 + nu) lambda) (``calc_eff_radius``'s t1, t2, t3, which is
  <r^3>/<r^2> of that distribution); rho_p 1000 (cloud), 900 (ice), 100 (snow, nssl_rho_qs);
* rain (imurain = 1), graupel and hail: gamma in diameter with alpha = 0 (alphar, nssl_alphah) and 1
  (nssl_alphahl); lambda = (pi/6 rho_p N (alpha + 1)(alpha + 2)(alpha + 3) / (rho q))^(1/3), r_eff =
  (alpha + 3) / (2 lambda); rho_p 1000 (rain), 500 (graupel, nssl_rho_qh) and 900 (hail, nssl_rho_qhl), or the
  category's own density q / QVGRAUPEL, q / QVHAIL where the file predicts its volume (nssl_density_on).
  ``calc_eff_radius`` writes (alpha + 3)(alpha + 1)(alpha + 1) in that lambda, where the scheme's own moments
  (its ``xdia``, line ~6828) have (alpha + 1)(alpha + 2)(alpha + 3): its t4/t5/t6 are 2^(1/3) (alpha = 0) and
  1.5^(1/3) (hail) times the distribution's <r^3>/<r^2>. Eq. 4 needs the latter, used here.

The scheme's thresholds and clipping: below q = qxmin (1e-13 kg/kg cloud, ice, snow) or max(qmin, qxmin)
= 1e-8 kg/kg (rain, graupel, hail), or N <= cxmin = 1e-8 m^-3 (not for graupel and hail), the radius is WRF's
default (the lower clip); r_eff is clipped to 2.51-50 um (cloud), 10.01-125 um (ice), 25-999 um (snow),
50-2999 um (rain), 50 um-10 mm (graupel) and 50 um-40 mm (hail), the re_* bounds of ``nssl_2mom_driver``
(WRF clips re_hail with the graupel's t5; its own t6 is used here). Graupel and hail are one species in
weather-mi: ``size_distributions.combined_radius`` gives them 0.5 sum M3 / sum M2, as ``calc_eff_radius``
combines them where it has no hail array.
"""
from __future__ import annotations

from math import gamma, pi

import numpy as np

from .size_distributions import gamma_radius, masked, sel

NSSL_FAMILY = {17: "NSSL 2-moment", 18: "NSSL 2-moment + CCN", 22: "NSSL 2-moment (no hail)"}
CXMIN = 1.0e-8          # m^-3
VOLMIN = 1.0e-30        # m^3/m^3: a predicted volume at or below this is ignored (the default density)
# species: (particle density kg/m^3, shape: ("volume", nu) or ("diameter", alpha), q threshold kg/kg,
#           number checked, clip (m))
PARAMS = {"cloud": (1000.0, ("volume", 0.0), 1.0e-13, True, (2.51e-6, 50e-6)),
          "ice": (900.0, ("volume", 0.0), 1.0e-13, True, (10.01e-6, 125e-6)),
          "snow": (100.0, ("volume", -0.8), 1.0e-13, True, (25e-6, 999e-6)),
          "rain": (1000.0, ("diameter", 0.0), 1.0e-8, True, (50e-6, 2999e-6)),
          "graupel": (500.0, ("diameter", 0.0), 1.0e-8, False, (50e-6, 10e-3)),
          "hail": (900.0, ("diameter", 1.0), 1.0e-8, False, (50e-6, 40e-3))}
VOLUME_VARS = {"graupel": "QVGRAUPEL", "hail": "QVHAIL"}


def particle_density(name, rho_q, volume=None) -> np.ndarray | float:
    """The particle density (kg/m^3) of category ``name``: q / V where the file predicts a volume ``volume``
    (m^3 per m^3 of air) above VOLMIN, else the scheme's fixed one."""
    rho_p = PARAMS[name][0]
    if volume is None:
        return rho_p
    volume = np.asarray(volume, np.float64)
    return np.divide(np.asarray(rho_q, np.float64), volume, out=np.full(volume.shape, rho_p), where=volume > VOLMIN)


def radius(name, rho_q, number, rho, volume=None) -> np.ndarray:
    """r_eff (m, float32; 0 where rho_q <= 0) of NSSL category ``name`` with mass content rho_q (kg/m^3),
    number concentration ``number`` (m^-3), dry-air density ``rho`` (kg/m^3, for the mixing-ratio thresholds)
    and, for graupel and hail, the predicted particle volume ``volume`` (m^3/m^3) or None."""
    _, (kind, shape), q_min, check_n, (lo, hi) = PARAMS[name]
    rho_p = particle_density(name, rho_q, volume)
    def f(rq, has):
        n = np.maximum(sel(number, has), 1e-30)
        dens = sel(rho_p, has)
        if kind == "volume":  # calc_eff_radius t1..t3
            lam = (n * pi / 6.0 * dens * gamma(2.0 + shape) / (rq * gamma(1.0 + shape))) ** (1.0 / 3.0)
            r = 0.5 * (1.0 + shape) * gamma(1.0 + shape) / gamma(5.0 / 3.0 + shape) / lam
        else:  # gamma in diameter, as the other schemes' (N floored at 1e-30, not 1e-6)
            r = gamma_radius(rq, n, dens, shape)
        ok = rq / sel(rho, has) > q_min
        if check_n:
            ok &= sel(number, has) > CXMIN
        return np.clip(np.where(ok, r, lo), lo, hi)
    return masked(rho_q, f, floor=0.0)  # the scheme's own thresholds, on the unfloored content


def rule_function(name):
    """``radius`` for category ``name`` in a SizeRule's signature (inputs "rho" and the volume variable)."""
    vvar = VOLUME_VARS.get(name)
    def f(rho_q, number, t_k=None, rho=None, **inputs):
        return radius(name, rho_q, number, rho, inputs.get(vvar) if vvar else None)
    f.__name__ = f"nssl_{name}"
    return f
