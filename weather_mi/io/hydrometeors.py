"""The Hydrometeors data contract (docs/design.md): an xarray.Dataset on a regular (z, y, x) grid in metres.

Data variables ``q_cloud, q_ice, q_rain, q_snow, q_graupel`` (kg per kg of dry air, never negative),
``rho_air`` (dry-air density, kg/m^3) and optional ``r_eff_<species>`` (effective radius, m; 0 where
the model gives none). Coordinates ``z, y, x`` are cell centres in metres (z above mean sea level),
uniformly spaced. Attributes keep the source (file, time, model, microphysics scheme) and
``n_negative_clipped``. Every reader returns a Dataset that passes :func:`validate`.

Optional, where the input has them (WRF files; ``weather_mi.io.georef``), all on (y, x) and none of them
data variables: the georeference, coordinates ``lat``, ``lon`` (degrees) with the attributes
``crs_proj4``, ``map_proj``, ``map_projection``, ``proj_x0_m``, ``proj_y0_m``, ``proj_dx_m``,
``proj_dy_m`` (``weather_mi.io.projection.Georeference``; ``weather_mi.scene.place.place_of`` reads them back) and
``valid_time`` ("YYYY-MM-DDTHH:MM:SSZ", UTC); the ground, coordinates ``terrain_height`` (m above MSL),
``land`` (1 land, 0 water) and ``surface_albedo`` (``weather_mi.io.terrain.Terrain``).
"""
from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import xarray as xr

from ..errors import WeatherDataError

SPECIES_NAMES: tuple[str, ...] = ("cloud", "ice", "rain", "snow", "graupel")
DIMS = ("z", "y", "x")
GROUND_COORDS = ("lat", "lon", "terrain_height", "land", "surface_albedo", "surface_kind", "snow_cover")  # optional (y, x) coordinates


def check_species_name(name: str, source: str = "input", variable: str | None = None) -> str:
    """Return ``name`` if it is one of the five hydrometeors, else raise WeatherDataError."""
    if name not in SPECIES_NAMES:
        raise WeatherDataError(source, variable or name,
                               f"a species name among {', '.join(SPECIES_NAMES)}", repr(name))
    return name


def _as_field(a, shape, source, variable, *, allow_profile=False, allow_scalar=False, copy=True) -> np.ndarray:
    """A finite float32 (z, y, x) field from an array, a z-profile or a scalar, with clear errors: a new
    array, or with ``copy=False`` a float32 C-contiguous ``a`` itself (no float64 copy in either case)."""
    arr = np.asarray(a)
    if arr.ndim == 0 and allow_scalar:
        arr = np.full(shape, float(arr), np.float32)
    elif arr.ndim == 1 and allow_profile:
        if arr.shape[0] != shape[0]:
            raise WeatherDataError(source, variable, f"a vertical profile of length {shape[0]} (nz)",
                                   f"length {arr.shape[0]}")
        arr = np.broadcast_to(arr.astype(np.float32)[:, None, None], shape)
    if arr.shape != tuple(shape):
        raise WeatherDataError(source, variable, f"an array of shape (z, y, x) = {tuple(shape)}",
                               f"shape {arr.shape}")
    if not np.issubdtype(arr.dtype, np.number):
        raise WeatherDataError(source, variable, "numbers", f"dtype {arr.dtype}")
    out = np.array(arr, dtype=np.float32, order="C", copy=True if copy else None)
    if not _all_finite(out):
        n = int(np.size(out) - np.count_nonzero(np.isfinite(out)))
        raise WeatherDataError(source, variable, "finite values everywhere", f"{n} NaN or infinite values")
    return out


def _all_finite(a: np.ndarray) -> bool:
    """Whether every value of ``a`` is finite, level by level (no whole-grid temporary)."""
    return all(bool(np.isfinite(level).all()) for level in a)


def from_arrays(q: Mapping[str, np.ndarray], rho_air, spacing, origin=(0.0, 0.0, 0.0), *,
                r_eff: Mapping[str, np.ndarray] | None = None, attrs: Mapping | None = None,
                source: str = "arrays", copy: bool = True) -> xr.Dataset:
    """Hydrometeors from plain arrays.

    Parameters
    ----------
    q : mapping of str to array_like
        Mixing ratios (kg/kg of dry air) by species name, each shaped (z, y, x); species not given are
        zero. Negatives are clipped to 0, counted (``n_negative_clipped``) and reported in a warning
        with their count and minimum.
    rho_air : float or array_like
        Dry-air density (kg/m^3): a number, a z-profile (nz,) or a (z, y, x) array.
    spacing : tuple of 3 float
        (dz, dy, dx) in metres, positive.
    origin : tuple of 3 float, default (0.0, 0.0, 0.0)
        (z0, y0, x0), the centre of the first cell in metres.
    r_eff : mapping of str to array_like, optional
        Effective radii (m) by species, (z, y, x), 0 where unknown.
    attrs : mapping, optional
        Dataset attributes added to ``source`` and ``n_negative_clipped``.
    source : str, default "arrays"
        Names the input in attributes and error messages.
    copy : bool, default True
        False: float32 C-contiguous arrays become the dataset's fields as they are (negatives clipped in
        place), without a copy: for readers handing over arrays they made.

    Returns
    -------
    xarray.Dataset
        Hydrometeors: ``q_<species>`` (kg/kg) for every species, ``rho_air`` (kg/m^3) and the
        ``r_eff_<species>`` given (m), float32 on (z, y, x) cell centres in metres.

    Raises
    ------
    WeatherDataError
        For an unknown species, a shape that is not (z, y, x), non-finite values, a non-positive
        spacing or density, or negative radii.
    """
    if not q:
        raise WeatherDataError(source, "q", "at least one species mixing ratio")
    for name in q:
        check_species_name(name, source)
    shapes = {name: np.shape(a) for name, a in q.items()}
    shape = next(iter(shapes.values()))
    if len(shape) != 3:
        raise WeatherDataError(source, f"q[{next(iter(q))!r}]", "a 3-D (z, y, x) array", f"shape {shape}")
    try:
        dz, dy, dx = (float(s) for s in spacing)
        z0, y0, x0 = (float(o) for o in origin)
    except (TypeError, ValueError) as exc:
        raise WeatherDataError(source, "spacing/origin", "three numbers each, (dz, dy, dx) and (z0, y0, x0)") from exc
    if not all(np.isfinite(s) and s > 0 for s in (dz, dy, dx)):
        raise WeatherDataError(source, "spacing", "three positive grid spacings in metres", str(spacing))

    data_vars = {}
    clipped_total = 0
    minima = {}
    for name in SPECIES_NAMES:
        var = f"q_{name}"
        if name in q:
            field = _as_field(q[name], shape, source, var, copy=copy)
            n_neg = int(np.count_nonzero(field < 0))
            if n_neg:
                minima[var] = (n_neg, float(field.min()))
                np.maximum(field, 0, out=field)
        else:
            field, n_neg = np.zeros(shape, np.float32), 0
        clipped_total += n_neg
        data_vars[var] = (DIMS, field, {"units": "kg kg-1", "long_name": f"{name} mixing ratio (per kg dry air)",
                                        "n_negative_clipped": n_neg})
    if minima:
        warn_clipped(source, minima, stacklevel=2)
    rho = _as_field(rho_air, shape, source, "rho_air", allow_profile=True, allow_scalar=True, copy=copy)
    if np.any(rho <= 0):
        raise WeatherDataError(source, "rho_air", "a positive dry-air density (kg/m^3)",
                               f"minimum {float(rho.min()):.4g}")
    data_vars["rho_air"] = (DIMS, rho, {"units": "kg m-3", "long_name": "dry-air density"})
    for name, a in (r_eff or {}).items():
        check_species_name(name, source, f"r_eff[{name!r}]")
        field = _as_field(a, shape, source, f"r_eff_{name}", copy=copy)
        if np.any(field < 0):
            raise WeatherDataError(source, f"r_eff_{name}", "effective radii >= 0 m")
        data_vars[f"r_eff_{name}"] = (DIMS, field, {"units": "m", "long_name": f"{name} effective radius"})

    nz, ny, nx = shape
    coords = {"z": ("z", z0 + dz * np.arange(nz), {"units": "m", "long_name": "height above MSL (cell centre)"}),
              "y": ("y", y0 + dy * np.arange(ny), {"units": "m", "long_name": "northing (cell centre)"}),
              "x": ("x", x0 + dx * np.arange(nx), {"units": "m", "long_name": "easting (cell centre)"})}
    all_attrs = {"source": source, "n_negative_clipped": clipped_total}
    all_attrs.update(attrs or {})
    ds = xr.Dataset(data_vars, coords=coords, attrs=all_attrs)
    validate(ds)
    return ds


def warn_clipped(source: str, minima: Mapping[str, tuple[int, float]], stacklevel: int = 2) -> None:
    """Warn that negative mixing ratios were set to 0: per variable, how many and the most negative
    (``minima``: variable -> (count, minimum in kg/kg))."""
    import warnings
    parts = [f"{var}: {n} value{'s' if n != 1 else ''} (minimum {lo:.3g} kg/kg)" for var, (n, lo) in minima.items()]
    warnings.warn(f"{source}: negative mixing ratios clipped to 0: {'; '.join(parts)}", UserWarning,
                  stacklevel=stacklevel + 1)


def spacing_of(ds: xr.Dataset) -> tuple[float, float, float]:
    """(dz, dy, dx) in metres of a Hydrometeors dataset (one cell if an axis has a single point)."""
    out = []
    for d in DIMS:
        c = np.asarray(ds[d].values, dtype=np.float64)
        out.append(float(c[1] - c[0]) if c.size > 1 else float(ds.attrs.get(f"d{d}", 1.0)))
    return tuple(out)


def bbox_of(ds: xr.Dataset) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """World bounding box ((x0, y0, z0), (x1, y1, z1)) in metres: cell centres +- half a cell."""
    dz, dy, dx = spacing_of(ds)
    lo = (float(ds.x[0]) - dx / 2, float(ds.y[0]) - dy / 2, float(ds.z[0]) - dz / 2)
    hi = (float(ds.x[-1]) + dx / 2, float(ds.y[-1]) + dy / 2, float(ds.z[-1]) + dz / 2)
    return lo, hi


def validate(ds: xr.Dataset) -> xr.Dataset:
    """Check that ``ds`` follows the Hydrometeors contract; raise WeatherDataError otherwise."""
    source = str(ds.attrs.get("source", "dataset"))
    for d in DIMS:
        if d not in ds.coords:
            raise WeatherDataError(source, d, "a coordinate in metres along each of z, y, x")
        c = np.asarray(ds[d].values, dtype=np.float64)
        if c.size > 1:
            step = np.diff(c)
            if not np.all(step > 0):
                raise WeatherDataError(source, d, "strictly increasing cell-centre coordinates")
            if not np.allclose(step, step[0], rtol=1e-4, atol=1e-6):
                raise WeatherDataError(source, d, "a regular grid (uniform spacing)",
                                       f"spacings from {step.min():.6g} to {step.max():.6g} m")
    for name in SPECIES_NAMES:
        var = f"q_{name}"
        if var not in ds:
            raise WeatherDataError(source, var, "a mixing ratio for every species (zeros if absent)")
        if ds[var].dims != DIMS:
            raise WeatherDataError(source, var, f"dims {DIMS}", str(ds[var].dims))
        values = np.asarray(ds[var].values)
        if values.size and bool(np.fmin.reduce(values, axis=None) < 0):  # (q < 0).any(), no grid of booleans
            raise WeatherDataError(source, var, "mixing ratios >= 0 (clip negatives first)")
    if "rho_air" not in ds or ds["rho_air"].dims != DIMS:
        raise WeatherDataError(source, "rho_air", f"dry-air density with dims {DIMS}")
    for name in GROUND_COORDS:
        if name in ds.coords and ds[name].dims != ("y", "x"):
            raise WeatherDataError(source, name, "a (y, x) coordinate", f"dims {ds[name].dims}")
    if "lat" in ds.coords and not bool(((ds["lat"] >= -90) & (ds["lat"] <= 90)).all()):
        raise WeatherDataError(source, "lat", "latitudes in [-90, 90] degrees")
    return ds
