"""A WPS geogrid file (``geo_em.d0N.nc``: a WRF domain's static fields, no atmosphere) as Hydrometeors: a clear
sky over the domain's ground, for the surface alone as a renderer or an imager sees it (a domain before its
run, the land/sea mask and the sun glint checked without clouds in the way).

The grid is the geogrid's mass points (XLAT_M, XLONG_M and the map-projection attributes, placed and checked
as a wrfout's, ``projection.grid_georeference``), the ground its HGT_M (0 where absent), LANDMASK / LU_INDEX
where present, else the global land mask (``terrain.land_and_kind``), the albedo by surface kind
(ALBEDO12M, a monthly field, is not read); the air a few layers of the
US 1976 standard atmosphere up to ``top_m`` with no hydrometeors. A geogrid has no time: give it one for the
sun with ``scene.place.assume_place(hyd, date=...)`` (the CLI's ``--date``).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import WeatherDataError
from .projection import grid_georeference
from .terrain import surface_fields

GEOGRID_NAMES = {"HGT": "HGT_M", "LANDMASK": "LANDMASK", "LU_INDEX": "LU_INDEX"}


def is_geogrid(ds) -> bool:
    """Whether an open NetCDF dataset is WPS geogrid output (its TITLE, or XLAT_M without any atmosphere)."""
    return "GEOGRID" in str(ds.attrs.get("TITLE", "")).upper() or ("XLAT_M" in ds and "PH" not in ds)


def _read(ds, name, sel):
    da = ds[name]
    if "Time" in da.dims:
        da = da.isel(Time=0)
    return np.asarray(da.isel(sel).values, np.float64)


def open_geogrid(path, *, x: slice | None = None, y: slice | None = None, top_m: float = 2000.0,
                 layers: int = 2):
    """A clear sky over a geogrid's ground (module docstring) as a Hydrometeors Dataset.

    Parameters
    ----------
    path : str or path
        A ``geo_em`` NetCDF file.
    x, y : slice, optional
        Mass-point index ranges (west_east, south_north) of a part of the domain.
    top_m, layers : float, int
        Height of the air's top (m above the highest ground) and its layers.

    Raises
    ------
    WeatherDataError
        For a file without XLAT_M/XLONG_M, or a map projection weather-mi does not read.
    """
    import xarray as xr
    from .hydrometeors import from_arrays
    from .standard_atmosphere import standard_density
    path = str(Path(path))
    with xr.open_dataset(path) as ds:
        for name in ("XLAT_M", "XLONG_M"):
            if name not in ds:
                raise WeatherDataError(path, name, "the mass points' latitude/longitude of a geogrid file", "missing")
        sel = {"west_east": x or slice(None), "south_north": y or slice(None)}
        lat, lon = _read(ds, "XLAT_M", sel), _read(ds, "XLONG_M", sel)
        georef, check = grid_georeference(ds.attrs, lat, lon, path)
        check.pop("grid_offset_ij")

        def has(name):
            return GEOGRID_NAMES.get(name, name) in ds and name in GEOGRID_NAMES

        coords, surface_attrs = surface_fields(lambda n: _read(ds, GEOGRID_NAMES[n], sel), has, np.zeros(lat.shape),
                                               dict(ds.attrs), (lat, lon), path)
    ny, nx = lat.shape
    ground = coords["terrain_height"][1]
    z_lo, z_hi = float(ground.min()), float(ground.max()) + float(top_m)
    dz = (z_hi - z_lo) / int(layers)
    z = z_lo + dz * (np.arange(int(layers)) + 0.5)
    rho = np.asarray(standard_density(z), np.float32)[:, None, None] * np.ones((1, ny, nx), np.float32)
    attrs = {"model": "WPS geogrid (clear sky)", **georef.attrs(), **check, **surface_attrs,
             "place": "the file's (XLAT_M, XLONG_M, MAP_PROJ)"}
    hyd = from_arrays({"cloud": np.zeros(rho.shape, np.float32)}, rho, (dz, georef.dy_m, georef.dx_m),
                      (float(z[0]), 0.0, 0.0), source=path, attrs=attrs)
    coords["lat"] = (("y", "x"), lat, {"units": "degrees_north", "standard_name": "latitude"})
    coords["lon"] = (("y", "x"), lon, {"units": "degrees_east", "standard_name": "longitude"})
    return hyd.assign_coords(coords)


__all__ = ["open_geogrid", "is_geogrid"]
