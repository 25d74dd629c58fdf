"""SHDOM / pyshdom "particle properties" LWC text files (LES output) -> Hydrometeors.

The format (header, columns, voxel lines) is read and checked by ``io.les_text``.

Conversions: LWC is a mass density (g/m^3), so the mixing ratio is q = LWC * 1e-3 / rho_air (kg/kg),
with rho_air the 1976 standard atmosphere at each level height unless given; the effective radius
(um) becomes ``r_eff_<species>`` in metres (0 where there is no liquid); the effective variance, when
the file has it, is kept as ``v_eff_<species>`` (dimensionless). x = i dx, y = j dy and z = the level
altitudes, all in metres. Levels uniform within their printed precision are kept, at their mean spacing:
uniform when every level lies within half a unit of the last printed digit (the finest among the levels,
read from the file's text) of one straight line a + b k, plus float rounding (25 m levels printed in km to
3 decimals read 24-26 m apart and are kept; the half unit counts only when it is under a tenth of the mean
spacing). Non-uniform levels are interpolated linearly in height onto a uniform grid
with the smallest level spacing (LWC linearly; r_eff and v_eff LWC-weighted, so they stay within the
range of the neighbouring cloudy values), and the attribute ``vertical_regrid`` says so.
"""
from __future__ import annotations

import os
from collections.abc import Callable

import numpy as np
import xarray as xr

from .standard_atmosphere import standard_density
from ..errors import WeatherDataError
from .hydrometeors import DIMS, from_arrays
from .les_text import read_voxel_file

LIQUID_SPECIES = ("cloud", "rain")
UNIFORM_RTOL = 1e-4          # levels' distance from a straight line allowed for float rounding, of the mean spacing


def _line_misfit(z: np.ndarray) -> float:
    """The largest distance of the levels z_k from the straight line a + b k that makes it smallest
    (the minimax fit; same unit as z). The spread max_k - min_k of z_k - b k is convex in the slope b
    and smallest between the smallest and the largest step, so a ternary search over b finds it."""
    k = np.arange(z.size, dtype=np.float64)
    steps = np.diff(z)
    lo, hi = float(steps.min()), float(steps.max())

    def spread(b: float) -> float:
        r = z - b * k
        return float(r.max() - r.min())

    for _ in range(100):  # (2/3)^100 of the slope interval: far below float rounding
        m1, m2 = lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0
        if spread(m1) <= spread(m2):
            hi = m2
        else:
            lo = m1
    return 0.5 * spread(0.5 * (lo + hi))


def _rho_profile(path: str, rho_air, z_native: np.ndarray, z_out: np.ndarray) -> tuple[np.ndarray, str]:
    """Air density (kg/m^3) at the output heights z_out (m), and a description for the attributes."""
    nz = z_native.size
    expected = (f"None (1976 standard atmosphere), a positive number, a profile of length nz = {nz} (kg/m^3) "
                "or a callable of height (m)")
    if rho_air is None:
        rho, how = np.asarray(standard_density(z_out), dtype=np.float64), "U.S. Standard Atmosphere 1976 at each level"
    elif callable(rho_air):
        f: Callable = rho_air
        try:
            val = f(z_out.copy())
        except (TypeError, ValueError):
            val = [f(float(z)) for z in z_out]
        try:
            rho = np.broadcast_to(np.asarray(val, dtype=np.float64), z_out.shape).copy()
        except (TypeError, ValueError) as exc:
            raise WeatherDataError(path, "rho_air", f"the callable to return {z_out.size} densities (kg/m^3) "
                                   "for the level heights (m)", f"{np.shape(val)}") from exc
        how = f"callable {getattr(f, '__name__', type(f).__name__)} of height (m)"
    else:
        try:
            arr = np.asarray(rho_air, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise WeatherDataError(path, "rho_air", expected, repr(rho_air)[:80]) from exc
        if isinstance(rho_air, (bool, np.bool_)) or arr.ndim > 1:
            raise WeatherDataError(path, "rho_air", expected, f"{type(rho_air).__name__} of shape {arr.shape}")
        if arr.ndim == 0:
            rho, how = np.full(z_out.shape, float(arr)), f"constant {float(arr):g} kg/m^3"
        else:
            if arr.size != nz:
                raise WeatherDataError(path, "rho_air", expected, f"a profile of length {arr.size}")
            same = z_out.size == nz and np.allclose(z_out, z_native)
            rho = arr.copy() if same else np.interp(z_out, z_native, arr)
            how = "given profile (kg/m^3) at the levels"
    if not np.all(np.isfinite(rho)) or np.any(rho <= 0):
        raise WeatherDataError(path, "rho_air", "a positive, finite air density (kg/m^3) at every level",
                               f"values from {np.nanmin(rho):.4g} to {np.nanmax(rho):.4g}")
    return rho, how


def _interp_z(field: np.ndarray, z_native: np.ndarray, z_out: np.ndarray) -> np.ndarray:
    """Linear interpolation in height along axis 0 of a (nz, ny, nx) field."""
    lo = np.clip(np.searchsorted(z_native, z_out, side="right") - 1, 0, z_native.size - 2)
    w = (z_out - z_native[lo]) / (z_native[lo + 1] - z_native[lo])
    w = np.clip(w, 0.0, 1.0)[:, None, None]
    return (1.0 - w) * field[lo] + w * field[lo + 1]


def _uniform_levels(z_native: np.ndarray, lev_unit_km: float, attrs: dict):
    """(z_out, dz) in metres when the levels are uniform within their printed precision (see the module
    docstring), else None; says so in attrs["vertical_grid"]."""
    nz = z_native.size
    steps = np.diff(z_native)
    printed_m = 1000.0 * lev_unit_km  # one unit of the last printed digit: each level +- half that
    misfit = _line_misfit(z_native)
    tol_m = UNIFORM_RTOL * steps.mean() + (0.5 * printed_m if printed_m <= 0.1 * steps.mean() else 0.0)
    if misfit > tol_m:
        return None
    dz = (z_native[-1] - z_native[0]) / (nz - 1)
    attrs["vertical_grid"] = (f"uniform levels from the file, {dz:g} m apart (spacings {steps.min():g} to "
                              f"{steps.max():g} m as printed, to {printed_m:g} m; within {misfit:.3g} m "
                              "of a straight line)")
    return z_native[0] + dz * np.arange(nz), dz


def _regrid_levels(z_native: np.ndarray, lwc: np.ndarray, extra: dict, attrs: dict):
    """(z_out, dz, lwc, extra) on uniform levels at the smallest native spacing, fitted to the column: LWC
    interpolated linearly in height, r_eff and v_eff LWC-weighted; says so in the attributes."""
    steps = np.diff(z_native)
    dz_min = float(steps.min())
    span = z_native[-1] - z_native[0]
    n_out = int(np.ceil(span / dz_min - 1e-6)) + 1
    z_out = z_native[0] + (span / (n_out - 1)) * np.arange(n_out)
    z_out[-1] = z_native[-1]
    dz = span / (n_out - 1)
    weighted = {k: _interp_z(v * lwc, z_native, z_out) for k, v in extra.items()}
    lwc = _interp_z(lwc, z_native, z_out)
    with np.errstate(invalid="ignore", divide="ignore"):
        extra = {k: np.where(lwc > 0, w / np.where(lwc > 0, lwc, 1.0), 0.0) for k, w in weighted.items()}
    attrs["vertical_regrid"] = (
        f"levels not uniform (spacings {steps.min():g} to {steps.max():g} m): LWC interpolated linearly "
        f"in height onto {n_out} uniform levels {dz:g} m apart (the smallest spacing, fitted to the "
        f"column); r_eff and v_eff interpolated LWC-weighted")
    attrs["vertical_grid"] = "regridded to uniform levels"
    attrs["n_levels_native"] = int(z_native.size)
    return z_out, dz, lwc, extra


def _vertical_grid(z_native, lev_unit_km, dx, dy, lwc, extra, attrs):
    """(z_out, dz, lwc, extra): the file's levels when uniform (or single), else the regridded column."""
    if z_native.size == 1:
        dz = min(dx, dy)
        attrs["vertical_grid"] = f"a single level; layer depth taken as the horizontal spacing {dz:g} m"
        return z_native, dz, lwc, extra
    uniform = _uniform_levels(z_native, lev_unit_km, attrs)
    if uniform is not None:
        return (*uniform, lwc, extra)
    return _regrid_levels(z_native, lwc, extra, attrs)


def _file_attrs(path, comment, comments, names, sep, sizes, n_listed, lwc, species, dx, dy) -> dict:
    """The Dataset attributes that describe the file and its voxels."""
    nx, ny, nz = sizes
    attrs = {"source": path, "model": "LES", "format": "SHDOM/pyshdom particle properties (LWC)",
             "comment": comment, "n_voxels_listed": n_listed, "n_cloudy_voxels": int(np.count_nonzero(lwc > 0)),
             "n_voxels_grid": int(nx * ny * nz), "species": species,
             "max_lwc_g_m3": float(lwc.max()) if lwc.size else 0.0,
             "separator": "comma" if sep == "," else ("semicolon" if sep == ";" else "whitespace"),
             "dx": dx, "dy": dy,
             "periodic": 1}  # LES domains are doubly periodic (BOMEX, RICO): the renderers' default (optics/periodic.py)
    if len(comments) > 1:
        attrs["comments"] = "\n".join(comments)
    if names:
        attrs["columns"] = ",".join(names)
    return attrs


def open_les(path, rho_air=None, *, species: str = "cloud") -> xr.Dataset:
    """Open an SHDOM/pyshdom LWC text file (LES liquid water) as Hydrometeors.

    Parameters
    ----------
    path : str or os.PathLike
        The text file, space- or comma-separated (see the module docstring for the format).
    rho_air : None, float, array_like or callable, optional
        Air density (kg/m^3) that turns LWC (g/m^3) into a mixing ratio q = LWC 1e-3 / rho_air (kg/kg):
        None (default) for the 1976 standard atmosphere at each level height, a number, a profile of
        length nz (at the file's levels) or a callable of height in metres.
    species : {"cloud", "rain"}, default "cloud"
        The hydrometeor that receives the liquid.

    Returns
    -------
    xarray.Dataset
        Hydrometeors following :mod:`weather_mi.io.hydrometeors`: x = i dx, y = j dy, z = the level
        altitudes, in metres; ``r_eff_<species>`` (m) and, when the file has it, ``v_eff_<species>``
        (dimensionless). Levels that are not uniform are regridded (attribute ``vertical_regrid``).
        ``attrs["periodic"] = 1``: the domain is doubly periodic, which both renderers then honour by
        default (``optical_volume(..., periodic=False)`` renders it as an isolated box).

    Raises
    ------
    WeatherDataError
        For bad input, naming the file, the field and the expectation.
    """
    path = os.fspath(path)
    if species not in LIQUID_SPECIES:
        raise WeatherDataError(path, "species", "'cloud' or 'rain' (LES files hold liquid water)", repr(species))
    f = read_voxel_file(path)
    z_native = f.levels_km * 1000.0
    dx, dy = f.spacing_km[0] * 1000.0, f.spacing_km[1] * 1000.0
    attrs = _file_attrs(path, f.comment, f.comments, f.names, f.separator, f.sizes, f.n_listed, f.lwc, species, dx,
                        dy)
    z_out, dz, lwc, extra = _vertical_grid(z_native, f.level_unit_km, dx, dy, f.lwc, f.extra, attrs)
    attrs["dz"] = float(dz)

    rho, how = _rho_profile(path, rho_air, z_native, z_out)
    attrs["rho_air_source"] = how
    q = lwc * 1e-3 / rho[:, None, None]
    r_eff = {species: extra["reff"] * 1e-6} if "reff" in extra else None
    ds = from_arrays({species: q}, rho, (dz, dy, dx), (float(z_out[0]), 0.0, 0.0), r_eff=r_eff,
                     attrs=attrs, source=path)
    if "veff" in extra:
        ds[f"v_eff_{species}"] = (DIMS, extra["veff"].astype(np.float32),
                                  {"units": "1", "long_name": f"{species} effective variance of the size distribution"})
    return ds
