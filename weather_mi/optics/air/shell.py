"""Paths through a spherical-shell atmosphere: the column of each constituent between a point at height
h (m above sea level) and space along a direction at cos(zenith) ``mu``, the Earth a sphere of radius
EARTH_RADIUS_M and the air ending at ``top_m``. No refraction (it lengthens a horizon path by ~7 %).

Along the straight ray r(s)^2 = r0^2 + 2 r0 mu s + s^2 (r0 = R + h); below the horizon (mu < 0) the ray
passes its lowest point at s* = -r0 mu, radius r0 sqrt(1 - mu^2), and is blocked by the Earth when that
is below R (column infinite, transmittance 0). The column is the trapezoidal integral of the tabulated
density over [0, s*] and [s*, s_top], each sampled as s = s_lowest +- L t^2 (dense where the air is), linear
between the table's heights (compiled: ``march_kernels.slant_columns``).
"""
from __future__ import annotations

import functools

import numpy as np

from .march_kernels import slant_columns as slant_columns_kernel

EARTH_RADIUS_M = 6371e3  # mean radius
DZ_TABLE_M = 20.0        # profiles are tabulated on this height step
SAMPLES = 512            # per segment (Chapman's 90 deg column within 1e-5)


def horizon_mu(h_m, radius_m: float = EARTH_RADIUS_M) -> np.ndarray:
    """cos(zenith) of the geometric horizon seen from height h: -sqrt(1 - (R / (R + h))^2)."""
    r0 = radius_m + np.maximum(np.asarray(h_m, np.float64), 0.0)
    return -np.sqrt(1.0 - (radius_m / r0) ** 2)


def _tabulate(profiles_of_height, top_m: float) -> tuple[list, np.ndarray]:
    """(names, (n_profiles, n_z) densities) of ``profiles_of_height`` on heights 0..``top_m`` every ``DZ_TABLE_M``."""
    z_tab = np.arange(0.0, top_m + DZ_TABLE_M, DZ_TABLE_M)
    profiles = {k: np.broadcast_to(np.asarray(v, np.float64), z_tab.shape)
                for k, v in profiles_of_height(z_tab).items()}
    return list(profiles), np.stack([profiles[k] for k in profiles])


@functools.lru_cache(maxsize=8)
def _profile_table(profiles_of_height, top_m: float) -> tuple[list, np.ndarray]:
    """``_tabulate`` of a bound method of a frozen (hashable) atmosphere, kept: the same floats, computed once
    (0.3-0.5 ms of every new sun in the slicer's drag, ``slicing.sun_air``)."""
    names, stacked = _tabulate(profiles_of_height, top_m)
    stacked.flags.writeable = False
    return names, stacked


def slant_columns(profiles_of_height, h_m, mu, top_m: float, radius_m: float = EARTH_RADIUS_M,
                  samples: int = SAMPLES) -> tuple[dict, np.ndarray]:
    """Columns from (h_m, mu) (broadcast together) to space of each density that ``profiles_of_height(z)``
    returns (a dict name -> per-m^3 or per-m values at heights z, m): (dict name -> columns, blocked),
    ``blocked`` True where the Earth is in the way (columns 0 there). ``samples``: points per segment (fewer
    for a table an interactive renderer builds: 64 keep the sun's colour within 1e-3)."""
    h, m = np.broadcast_arrays(np.clip(np.asarray(h_m, np.float64), 0.0, top_m), np.asarray(mu, np.float64))
    if np.any(np.abs(m) > 1.0 + 1e-12):
        raise ValueError("mu must be a cosine in [-1, 1]")
    m = np.clip(m, -1.0, 1.0)
    if getattr(profiles_of_height, "__self__", None) is not None:  # an atmosphere's method: once per atmosphere
        profiles = _profile_table(profiles_of_height, float(top_m))
    else:
        profiles = _tabulate(profiles_of_height, top_m)
    hf, mf = h.ravel(), m.ravel()
    r0 = radius_m + hf
    blocked = (mf < 0.0) & (r0 * np.sqrt(1.0 - mf * mf) < radius_m)
    rt = radius_m + top_m
    s_star = np.maximum(-r0 * mf, 0.0)
    s_top = -r0 * mf + np.sqrt(np.maximum((r0 * mf) ** 2 + rt * rt - r0 * r0, 0.0))
    names, stacked = profiles
    cols = slant_columns_kernel(stacked, 0.0, DZ_TABLE_M, r0, mf,
                                s_star, s_top, blocked, float(radius_m), float(top_m), np.linspace(0.0, 1.0, samples))
    out = dict(zip(names, cols))
    return {k: v.reshape(h.shape) for k, v in out.items()}, blocked.reshape(h.shape)


__all__ = ["EARTH_RADIUS_M", "horizon_mu", "slant_columns"]
