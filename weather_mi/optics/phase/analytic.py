"""Closed-form phase functions: Henyey-Greenstein, Cornette-Shanks and isotropic (same in R, G, B)."""
from __future__ import annotations

import numpy as np

from .table import PhaseTable, angle_grid


def _check_g(g: float) -> float:
    g = float(g)
    if not -1 < g < 1:
        raise ValueError(f"asymmetry parameter g must lie in (-1, 1), got {g!r}")
    return g


def values_of(mu):
    """``mu`` as float64 numpy values, or as it is where it is a kernel's array (Dr.Jit: the slicer evaluates the
    same closed forms inside its kernels)."""
    return mu if type(mu).__module__.startswith("drjit") else np.asarray(mu, np.float64)


def hg_value(g: float, mu) -> np.ndarray:
    """Henyey-Greenstein p(mu) = (1 - g^2) / (4 pi (1 + g^2 - 2 g mu)^(3/2)) in 1/sr (``mu``, and ``g``, may be
    Dr.Jit arrays: ``values_of``)."""
    mu = values_of(mu)
    return (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * mu) ** 1.5)


def cornette_shanks_value(g: float, mu) -> np.ndarray:
    """Cornette-Shanks (1992) p(mu) = 3/(8 pi) (1 - g^2)/(2 + g^2) (1 + mu^2)/(1 + g^2 - 2 g mu)^(3/2), 1/sr."""
    mu = np.asarray(mu, np.float64)
    return 3 / (8 * np.pi) * (1 - g * g) / (2 + g * g) * (1 + mu * mu) / (1 + g * g - 2 * g * mu) ** 1.5


def cornette_shanks_mean_cosine(g: float) -> float:
    """<mu> of Cornette-Shanks: 3 g (4 + g^2) / (5 (2 + g^2)) (its g parameter is not the mean cosine)."""
    return 3 * g * (4 + g * g) / (5 * (2 + g * g))


def cornette_shanks_cone_fraction(g: float, theta0) -> np.ndarray:
    """Fraction of scattered energy within ``theta0`` radians of forward for Cornette-Shanks, exact.

    F = 2 pi integral_mu0^1 p dmu with u = 1 + g^2 - 2 g mu (c = 1 + g^2, A = 4 g^2 + c^2):
    (1 + mu^2) = (A - 2 c u + u^2) / (4 g^2), dmu = -du / (2 g), so
    F = 2 pi K / (8 g^3) [-2 A u^(-1/2) - 4 c u^(1/2) + (2/3) u^(3/2)] from u = (1 - g)^2 to u0,
    K = 3 (1 - g^2) / (8 pi (2 + g^2)); g -> 0: F = 3/8 [(1 - mu0) + (1 - mu0^3)/3]."""
    g = _check_g(g)
    mu0 = np.cos(np.clip(np.asarray(theta0, np.float64), 0.0, np.pi))
    if abs(g) < 1e-6:
        return 0.375 * ((1 - mu0) + (1 - mu0 ** 3) / 3)
    c = 1 + g * g
    a = 4 * g * g + c * c
    k = 3 * (1 - g * g) / (8 * np.pi * (2 + g * g))

    def antideriv(u):
        return -2 * a / np.sqrt(u) - 4 * c * np.sqrt(u) + (2 / 3) * u ** 1.5

    u1 = (1 - g) ** 2
    u0 = c - 2 * g * mu0
    return 2 * np.pi * k / (8 * g ** 3) * (antideriv(u0) - antideriv(u1))


def hg_cone_fraction(g: float, theta0) -> np.ndarray:
    """Henyey-Greenstein cone fraction, exact: F = (1 - g^2)/(2 g) [(1 + g^2 - 2 g mu0)^(-1/2) - 1/(1 + g)]
    counted from forward: F(theta0) = 1 - CDF_mu(mu0) with CDF_mu(mu) = (1 - g^2)/(2 g) [u^(-1/2) - 1/(1 + g)]."""
    g = _check_g(g)
    mu0 = np.cos(np.clip(np.asarray(theta0, np.float64), 0.0, np.pi))
    if abs(g) < 1e-9:
        return 0.5 * (1 - mu0)
    return 1 - (1 - g * g) / (2 * g) * ((1 + g * g - 2 * g * mu0) ** -0.5 - 1 / (1 + g))


def henyey_greenstein(g: float, theta=None) -> PhaseTable:
    """Henyey-Greenstein phase function with mean cosine ``g`` in all channels (its Legendre
    moments are g^l). ``theta``: nodes in radians (default :func:`angle_grid`)."""
    g = _check_g(g)
    return PhaseTable.from_function(lambda th: hg_value(g, np.cos(th)), theta, name=f"henyey_greenstein(g={g:g})")


def cornette_shanks(g: float, theta=None) -> PhaseTable:
    """Cornette-Shanks phase function with parameter ``g`` (mean cosine 3g(4+g^2)/(5(2+g^2)))."""
    g = _check_g(g)
    return PhaseTable.from_function(lambda th: cornette_shanks_value(g, np.cos(th)), theta,
                                    name=f"cornette_shanks(g={g:g})")


def isotropic() -> PhaseTable:
    """p = 1 / (4 pi) in all channels."""
    return PhaseTable.from_values(np.array([0.0, np.pi]), np.full(2, 1 / (4 * np.pi)), name="isotropic")


__all__ = ["values_of", "henyey_greenstein", "cornette_shanks", "isotropic", "cornette_shanks_cone_fraction",
           "cornette_shanks_mean_cosine", "hg_cone_fraction", "hg_value", "cornette_shanks_value", "angle_grid"]
