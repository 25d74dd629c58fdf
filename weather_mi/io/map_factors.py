"""WRF map factors: a projected grid (Mercator, Lambert, polar stereographic) has mass points DX / m apart
on the earth, m the map factor (MAPFAC_M, or MAPFAC_MX / MAPFAC_MY along x / y). The Hydrometeors grid is
uniform, so the spacing is DX (DY) over the mean map factor of the domain read; where m varies across it,
a warning gives how far the local spacings and the positions of the mass points are from the true ones.
"""
from __future__ import annotations

import warnings

import numpy as np

from ..errors import WeatherDataError

VARIES_REL = 1e-3  # below this relative spread the map factor counts as constant (no warning)


def _positions_m(spacing_m: float, m: np.ndarray, axis: int) -> np.ndarray:
    """True distances of the mass points from the first along ``axis``: steps of spacing / (mean m of the
    two points)."""
    mid = 0.5 * (np.take(m, range(1, m.shape[axis]), axis) + np.take(m, range(m.shape[axis] - 1), axis))
    steps = spacing_m / mid
    zero = np.zeros_like(np.take(m, [0], axis))
    return np.concatenate([zero, np.cumsum(steps, axis=axis)], axis=axis)


def horizontal_spacing(path: str, dx: float, dy: float, factors: dict[str, np.ndarray], stacklevel: int = 2):
    """(dx, dy, attrs) from the grid's DX, DY (m) and its map factors (``factors``: variable name ->
    (south_north, west_east) array; MAPFAC_MX and MAPFAC_MY, or MAPFAC_M for both; empty: none given)."""
    if not factors:
        return dx, dy, {"grid": "no map factors in the file: DX, DY taken as the true spacing"}
    for name, m in factors.items():
        if not (np.all(np.isfinite(m)) and np.all(m > 0)):
            raise WeatherDataError(path, name, "positive, finite map factors",
                                   f"values from {np.nanmin(m):.4g} to {np.nanmax(m):.4g}")
    mx = factors.get("MAPFAC_MX", factors.get("MAPFAC_M"))
    my = factors.get("MAPFAC_MY", factors.get("MAPFAC_M"))
    mean_x, mean_y = float(mx.mean()), float(my.mean())
    dx_true, dy_true = dx / mean_x, dy / mean_y
    spread = max(float(np.abs(mx / mean_x - 1).max()), float(np.abs(my / mean_y - 1).max()))
    err_m = 0.0
    if mx.shape[1] > 1:
        err_m = max(err_m, float(np.abs(_positions_m(dx, mx, 1) - dx_true * np.arange(mx.shape[1])).max()))
    if my.shape[0] > 1:
        err_m = max(err_m, float(np.abs(_positions_m(dy, my, 0) - dy_true * np.arange(my.shape[0])[:, None]).max()))
    names = ", ".join(factors)
    attrs = {"map_factor_mean": mean_x if mean_x == mean_y else (mean_x, mean_y), "map_factor_spread": spread,
             "map_factor_position_error_m": err_m,
             "grid": f"spacing DX / mean map factor ({names}); local spacings within {100 * spread:.2g}%"}
    if spread > VARIES_REL:
        lo = min(float(mx.min()), float(my.min()))
        hi = max(float(mx.max()), float(my.max()))
        warnings.warn(f"{path}: map factors {names} vary from {lo:.3g} to {hi:.3g} across the domain: the uniform "
                      f"grid has spacings DX / {mean_x:.4g} = {dx_true:.1f} m and DY / {mean_y:.4g} = {dy_true:.1f} m; "
                      f"the true local spacings differ by up to {100 * spread:.1f}% and the mass points lie up to "
                      f"{err_m:.0f} m from their true distances", UserWarning, stacklevel=stacklevel + 1)
    return dx_true, dy_true, attrs
