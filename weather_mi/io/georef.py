"""Where and when one time of a wrfout file is: the valid time, the latitude/longitude of every column and
the map projection they lie on (``weather_mi.io.projection``, checked against the file's XLAT/XLONG), and the ground
(``weather_mi.io.terrain``: HGT, land/water, albedo), as coordinates and attributes of its Hydrometeors.

Ideal cases (MAP_PROJ 0, or XLAT/XLONG all zero, or a time before 1900 such as WRF's 0001-01-01) have no
place and no valid time: ``weather_mi.scene.place.assume_place`` gives them one.
"""
from __future__ import annotations

import numpy as np

from ..errors import WeatherDataError
from .projection import domain_georeference, grid_georeference, proj_string
from .terrain import surface_fields


def valid_time_iso(stamp: str, map_proj: int) -> str | None:
    """The valid time "YYYY-MM-DDTHH:MM:SSZ" (UTC) of a WRF timestamp, None for an ideal case (MAP_PROJ 0
    or a year before 1900, WRF's 0001-01-01 of idealised runs)."""
    s = str(stamp).strip().replace("_", "T")
    try:
        t = np.datetime64(s, "s")
    except ValueError:
        return None
    if map_proj == 0 or t < np.datetime64("1900-01-01T00:00:00"):
        return None
    return f"{t}Z"


def _read2d(ds, name, it, sel) -> np.ndarray:
    da = ds[name]
    if "Time" in da.dims:
        da = da.isel(Time=it)
    da = da.isel({k: v for k, v in sel.items() if k in da.dims})
    return np.asarray(da.values, dtype=np.float64)


def place_coords(ds, path: str, it: int, stamp: str, sel: dict, z_surface_m: np.ndarray) -> tuple[dict, dict]:
    """(coordinates, attributes) of the place, time and ground of time ``it`` of the open wrfout ``ds`` on
    the sub-box ``sel``: coordinates ``lat``, ``lon`` (where georeferenced) and the terrain's; attributes
    ``valid_time``, the georeference (``Georeference.attrs``), its check against XLAT/XLONG and the terrain's
    sources. A WeatherDataError for a MAP_PROJ weather-mi does not read."""
    mp = int(ds.attrs.get("MAP_PROJ", 0))
    if mp != 0:
        proj_string(ds.attrs, path)  # names the file and MAP_PROJ where weather-mi does not read it
    when = valid_time_iso(stamp, mp)
    lat = _read2d(ds, "XLAT", it, sel) if "XLAT" in ds.variables else None
    lon = _read2d(ds, "XLONG", it, sel) if "XLONG" in ds.variables else None
    place, attrs = None, {}
    if mp == 0 or (lat is not None and not (np.any(lat != 0) or np.any(lon != 0))):
        attrs["place"] = "none (ideal case: no map projection, no latitude/longitude)"
    else:
        if lat is None or lon is None:
            dom = domain_georeference(ds.attrs, path)
            if sel or z_surface_m.shape != (dom.ny, dom.nx):
                raise WeatherDataError(path, "XLAT, XLONG", "the latitude/longitude of the mass points (a file "
                                       "with part of a domain needs them to be placed)", "missing")
            lat, lon = dom.latlon()
            georef, check = dom, {"latlon_source": "the projection (no XLAT/XLONG in the file)"}
        else:
            georef, check = grid_georeference(ds.attrs, lat, lon, path)
            i0, j0 = check.pop("grid_offset_ij")
            check.update(grid_offset_i=i0, grid_offset_j=j0, latlon_source="XLAT, XLONG")
        if when is not None:
            attrs["valid_time"] = when
        attrs.update(georef.attrs(), **check, place="the file's (XLAT, XLONG, MAP_PROJ)")
        place = (lat, lon)
    coords, surface_attrs = surface_fields(lambda n: _read2d(ds, n, it, sel), lambda n: n in ds, z_surface_m,
                                           ds.attrs, place, path)
    attrs.update(surface_attrs)
    hgt = coords["terrain_height"][1]
    attrs["terrain_surface_max_diff_m"] = float(np.max(np.abs(hgt - z_surface_m)))
    if place is not None:
        coords["lat"] = (("y", "x"), lat, {"units": "degrees_north", "standard_name": "latitude"})
        coords["lon"] = (("y", "x"), lon, {"units": "degrees_east", "standard_name": "longitude"})
    return coords, attrs
