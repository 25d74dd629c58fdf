"""The size distributions the WRF microphysics schemes share, as effective radii r_eff = <r^3>/<r^2> (m): the
radius that makes Eq. 4 exact for a distribution (beta_ext = 3 rho_air q / (2 rho_p r_eff), geometric Q_ext = 2).

For a gamma distribution in diameter N(D) = N0 D^mu exp(-lambda D) the mass content is
rho_air q = (pi rho_p / 6) N_t Gamma(mu + 4) / (Gamma(mu + 1) lambda^3) (N_t = N0 Gamma(mu + 1) / lambda^(mu+1)),
so lambda = (pi rho_p N_t Gamma(mu + 4) / (6 Gamma(mu + 1) rho_air q))^(1/3) and r_eff = (mu + 3) / (2 lambda)
(exponential, mu = 0: r_eff = 1.5 / lambda, and with a fixed intercept N0: lambda = (pi rho_p N0 / (rho_air q))^(1/4)).

``SizeRule`` says how one species' radius follows from a wrfout's fields; the schemes' rules are in
``weather_mi.io.microphysics`` (and the modules it names). Two categories that the renderer draws as one species
(graupel and hail) get one radius, ``combined_radius``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from math import gamma, pi
from typing import Callable

import numpy as np

RHO_W = 1000.0       # kg/m^3, WSM/WDM/Thompson liquid water
T0C = 273.15         # K
R1 = 1.0e-12         # kg/m^3: WRF effectRad's smallest mass content


@dataclass(frozen=True)
class SizeRule:
    """How one species' effective radius follows from the fields: ``radius(rho_q, number, t_k, **inputs)`` with
    the mass content rho_q (kg/m^3), the number concentration (m^-3; None where ``number_var`` is None), the
    temperature (K; None unless ``needs_temperature``) and, as keywords, the ``inputs`` the rule names gives
    r_eff (m, 0 where rho_q <= 0). ``inputs``: "rho" (dry-air density, kg/m^3, for thresholds the scheme sets
    on mixing ratios), a WRF variable "Q..." (its mass or volume mixing ratio times the density: kg/m^3 or
    m^3/m^3) or "QN..." (its number times the density, m^-3), all on the native grid (bottom_top first).
    ``density``: the scheme's particle density (kg/m^3; with ``volume_var`` where it has one: a variable-density
    category's volume, per kg of air), used to combine graupel and hail."""

    species: str
    radius: Callable
    number_var: str | None = None
    needs_temperature: bool = False
    formula: str = ""
    inputs: tuple[str, ...] = field(default=())
    density: float | None = None
    volume_var: str | None = None


def masked(rho_q, compute, floor=R1) -> np.ndarray:
    """``compute(rho_q, has)`` (float64) where rho_q > 0, else 0, as float32 (rho_q floored at ``floor``)."""
    rq = np.asarray(rho_q)
    out = np.zeros(rq.shape, np.float32)
    has = rq > 0
    if np.any(has):  # float64 of the voxels with mass only (not a float64 copy of the grid)
        out[has] = compute(np.maximum(rq[has].astype(np.float64), floor), has)
    return out


def sel(a, has):
    """``a`` (a number, a grid like rho_q, or None) at the points ``has``, float64."""
    return None if a is None else np.asarray(a)[has].astype(np.float64) if np.ndim(a) else float(a)


def exponential_fixed_n0(rho_q, n0_per_m4, rho_p, lam_max=np.inf, lam_min=0.0) -> np.ndarray:
    """r_eff = 1.5 / lambda, lambda = (pi rho_p N0 / rho_q)^(1/4) clipped to [lam_min, lam_max] (1/m);
    ``n0_per_m4`` a number or a grid like ``rho_q``."""
    def f(rq, has):
        lam = (pi * rho_p * sel(n0_per_m4, has) / rq) ** 0.25
        return 1.5 / np.clip(lam, lam_min, lam_max)
    return masked(rho_q, f)


def gamma_radius(rq, n, rho_p, mu=0.0, lam_min=0.0, lam_max=np.inf) -> np.ndarray:
    """r_eff = (mu + 3) / (2 lambda) (m, float64) of gamma distributions in diameter (module docstring), lambda =
    (pi rho_p N Gamma(mu+4) / (6 Gamma(mu+1) rho_q))^(1/3) clipped to [lam_min, lam_max] (1/m), from the mass
    content ``rq`` (kg/m^3, > 0), the number ``n`` (m^-3, > 0) and the particle density ``rho_p`` (kg/m^3), all
    float64 (numbers or arrays alike): no mask, no floor (:func:`gamma_from_number`, ``nssl_sizes``)."""
    lam = (pi * rho_p / 6.0 * (gamma(mu + 4.0) / gamma(mu + 1.0)) * n / rq) ** (1.0 / 3.0)
    return (mu + 3.0) / (2.0 * np.clip(lam, lam_min, lam_max))


def gamma_from_number(rho_q, n_per_m3, rho_p, mu=0.0, lam_min=0.0, lam_max=np.inf) -> np.ndarray:
    """:func:`gamma_radius` where rho_q > 0 (float32, 0 elsewhere); N (m^-3) floored at 1e-6 as WRF's R2; rho_p a
    number or a grid like rho_q."""
    def f(rq, has):
        return gamma_radius(rq, np.maximum(sel(n_per_m3, has), 1e-6), sel(rho_p, has), mu, lam_min, lam_max)
    return masked(rho_q, f)


def combined_radius(parts) -> np.ndarray:
    """One effective radius (m, float32) for categories drawn as one species: 0.5 sum M3 / sum M2 over the
    ``parts`` [(r_eff (m), particle volume per m^3 of air)], i.e. sum V / sum (V / r_eff) (the third moment is
    6 V / pi, the second 6 V / (2 pi r_eff)); as NSSL's calc_eff_radius combines graupel and hail."""
    volume = sum(np.asarray(v, np.float64) for _, v in parts)
    area = sum(np.divide(np.asarray(v, np.float64), r, out=np.zeros(np.shape(r)), where=np.asarray(r) > 0)
               for r, v in parts)
    return np.divide(volume, area, out=np.zeros(np.shape(volume)), where=area > 0).astype(np.float32)
