"""The clear 1-D atmosphere (``Atmosphere``) as DISORT's layers at one wavelength: optical depth, single-scattering
albedo and Legendre moments of each layer, top first (``optics.disort.solve``'s input). Used by the
satellite's air outside its box (``satellite.air``) and the skylight the render's box receives from the air around
it (``air.skylight``)."""
from __future__ import annotations

import numpy as np

TOP_LAYERS_M = (0.0, 30e3, 80e3)  # DISORT layers: LAYER_M up to 30 km, 5 km above
LAYER_M = 1000.0
N_STREAMS = 16                    # Rayleigh needs 4; the aerosol's forward peak is left to DISORT's corrections


def air_layers(atm, wavelength_nm: float, ground_m: float = 0.0, split_m=None, layer_m: float = LAYER_M):
    """The 1-D atmosphere from ``ground_m`` to its top as DISORT layers (top first): (optical depth, single-
    scattering albedo, Legendre moments (layers, N_STREAMS + 1)) at ``wavelength_nm``: molecules (Rayleigh with
    depolarisation, ``optics.rayleigh``), ozone (absorbing), aerosol (Henyey-Greenstein of ``atm.aerosol_g``,
    albedo ``atm.aerosol_ssa``); ``split_m``: a layer edge there (a height or a sequence of heights, m);
    ``layer_m``: the layers' thickness up to 30 km."""
    from ..rayleigh import DEPOLARISATION, cross_section_m2 as rayleigh_sigma
    from .ozone import cross_section_m2 as ozone_sigma
    edges = layer_edges(ground_m, split_m, layer_m)
    wl = float(wavelength_nm)
    z = np.linspace(edges[:-1], edges[1:], 41, axis=-1)          # (layers, 41)
    p = atm.profiles(z, water=False)  # the layers hold no water vapour's bands
    t_r, t_o, t_a = (np.trapezoid(p[k], z, axis=-1)[::-1] * f   # top first
                     for k, f in (("air", float(rayleigh_sigma(wl * 1e-9))), ("ozone", float(ozone_sigma(wl))),
                                  ("aerosol", float(atm.aerosol_factor(wl)))))
    sca_a = atm.aerosol_ssa * t_a
    tau = t_r + t_o + t_a
    gamma = DEPOLARISATION / (2.0 - DEPOLARISATION)
    chi_r = np.zeros(N_STREAMS + 1)
    chi_r[0], chi_r[2] = 1.0, (1.0 - gamma) / (10.0 * (1.0 + 2.0 * gamma))
    chi_a = atm.aerosol_g ** np.arange(N_STREAMS + 1)
    sca = t_r + sca_a
    moments = (t_r[:, None] * chi_r + sca_a[:, None] * chi_a) / np.maximum(sca, 1e-30)[:, None]
    return tau, np.clip(sca / np.maximum(tau, 1e-30), 0.0, 1.0 - 1e-7), moments


def layer_edges(ground_m: float, split_m=None, layer_m: float = LAYER_M) -> np.ndarray:
    """The heights (m, ascending) of ``air_layers``' layer edges: every ``layer_m`` to 30 km, every 5 km above,
    and ``split_m`` (None, a height or heights)."""
    lo, mid, top = TOP_LAYERS_M
    edges = np.r_[np.arange(max(ground_m, lo), mid, layer_m), np.arange(mid, top + 1.0, 5000.0)]
    splits = [] if split_m is None else np.atleast_1d(np.asarray(split_m, np.float64))
    return np.unique(np.r_[edges, np.clip(splits, ground_m, top)])


__all__ = ["air_layers", "layer_edges", "N_STREAMS", "LAYER_M", "TOP_LAYERS_M"]
