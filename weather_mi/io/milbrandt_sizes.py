"""Effective radii (m) of the Milbrandt-Yau two-moment scheme (Milbrandt & Yau 2005a,b; WRF
``phys/module_mp_milbrandt2mom.F``, MP_PHYSICS 9) from its number concentrations QNCLOUD, QNICE, QNRAIN,
QNSNOW, QNGRAUPEL, QNHAIL (per kg, times the air density).

Each category is N(D) = N0 D^alpha exp(-lambda D^mu) in the scheme's own symbols, with mass m(D) = c D^d;
``iLAMDA_x`` gives its inverse slope iLAM = (rho q / (N c Gamma(1 + alpha + d/mu) / Gamma(1 + alpha)))^(1/d)
(the scheme's icex* constants), and r_eff = 0.5 M3 / M2 = 0.5 Gamma(1 + alpha + 3/mu) / Gamma(1 + alpha + 2/mu)
iLAM:

* cloud: alpha_c = 1, mu_c = 3, spheres of water (c = pi/6 1000, d = 3): r_eff = 0.664639 iLAMc, the
  scheme's own reff_c (computed but commented out in WRF's copy);
* ice: alpha_i = 0, c = cmi = 440, d = 3: r_eff = 1.5 iLAMi (its reff_i), iLAMi >= iLAMmin2 = 1e-10 m;
* rain, graupel, hail: alpha = 0, spheres of 1000, 400 (deg) and 900 (deh) kg/m^3: r_eff = 1.5 iLAM,
  iLAM >= iLAMmin1 = 1e-6 m;
* snow: alpha_s = 0, snowSpherical = .false.: m(D) = 0.1597 D^2.078 (Brandes et al. 2007), iLAMs >= 1e-10 m:
  r_eff = 1.5 iLAMs (half the ratio of the diameter moments, as Thompson's snow).

N is floored at epsN = 1e-3 m^-3. The scheme writes no radius of its own and clips none; hail is combined with
graupel (``size_distributions.combined_radius``), each with its density.
"""
from __future__ import annotations

from math import gamma

import numpy as np

from .size_distributions import masked, sel

MY_FAMILY = {9: "Milbrandt-Yau"}
EPS_N = 1.0e-3  # m^-3
PI6 = np.pi / 6.0
# category: (alpha, mu, c, d, smallest iLAM (m), particle density for combining, kg/m^3)
PARAMS = {"cloud": (1.0, 3.0, PI6 * 1000.0, 3.0, 0.0, 1000.0),
          "ice": (0.0, 1.0, 440.0, 3.0, 1.0e-10, 440.0 / PI6),
          "rain": (0.0, 1.0, PI6 * 1000.0, 3.0, 1.0e-6, 1000.0),
          "snow": (0.0, 1.0, 0.1597, 2.078, 1.0e-10, 100.0),
          "graupel": (0.0, 1.0, PI6 * 400.0, 3.0, 1.0e-6, 400.0),
          "hail": (0.0, 1.0, PI6 * 900.0, 3.0, 1.0e-6, 900.0)}


def radius(name, rho_q, number) -> np.ndarray:
    """r_eff (m, float32; 0 where rho_q <= 0) of Milbrandt-Yau category ``name`` from the mass content rho_q
    (kg/m^3) and the number concentration (m^-3)."""
    alpha, mu, c, d, ilam_min, _ = PARAMS[name]
    icex = 1.0 / (c * gamma(1.0 + alpha + d / mu) / gamma(1.0 + alpha))
    factor = 0.5 * gamma(1.0 + alpha + 3.0 / mu) / gamma(1.0 + alpha + 2.0 / mu)
    def f(rq, has):
        ilam = np.maximum(ilam_min, (rq / np.maximum(sel(number, has), EPS_N) * icex) ** (1.0 / d))
        return factor * ilam
    return masked(rho_q, f, floor=0.0)  # the formula down to any content (the scheme sets no threshold here)


def rule_function(name):
    """``radius`` for category ``name`` in a SizeRule's signature."""
    def f(rho_q, number, t_k=None):
        return radius(name, rho_q, number)
    f.__name__ = f"milbrandt_{name}"
    return f
