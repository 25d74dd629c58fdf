"""Where a WRF grid lies on the earth: its map projection as a pyproj CRS, the projected x/y of its mass
points and their latitude/longitude.

WRF (and WPS) place the grid on a sphere of radius 6370 km (``EARTH_RADIUS_M``; WPS
``geogrid/src/constants_module.F``: EARTH_RADIUS_M = 6370000) in one of the projections of the global
attribute MAP_PROJ: 1 Lambert conformal (TRUELAT1, TRUELAT2, STAND_LON), 2 polar stereographic (true at
TRUELAT1, STAND_LON the meridian parallel to the grid's y axis), 3 Mercator (true at TRUELAT1) and 6
latitude-longitude (a regular grid in degrees: DX, DY in metres along the equator; only an unrotated
pole, POLE_LAT = 90, is supported). The full domain (WEST-EAST_GRID_DIMENSION - 1 by
SOUTH-NORTH_GRID_DIMENSION - 1 mass points, DX, DY metres apart on the projection plane) is centred on
CEN_LAT, CEN_LON. A file may hold a part of the domain (cropped output, or a sub-box read with
``x=``/``y=``): its offset in the domain is found from the projected position of its first XLAT/XLONG
point, and the projection is then checked against every XLAT/XLONG of the file (``check``). MAP_PROJ 0
(ideal cases: Cartesian, no latitude/longitude) has no georeference.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ..errors import WeatherDataError

EARTH_RADIUS_M = 6370000.0  # WRF's sphere (WPS constants_module.F)
PROJECTIONS = {1: "Lambert conformal", 2: "polar stereographic", 3: "Mercator", 6: "latitude-longitude"}
LOCAL_PROJECTION = "local azimuthal equidistant (assumed place)"  # map_proj 0: an ideal case placed by hand
NOT_SET = 1.0e19  # WPS writes 1e20 for an attribute the projection does not use


def proj_string(attrs, source: str) -> str:
    """The PROJ definition of MAP_PROJ and its parameters in ``attrs`` (WRF's global attributes); a
    WeatherDataError naming ``source`` and the attribute for a MAP_PROJ weather-mi does not read."""
    mp = int(attrs.get("MAP_PROJ", 0))
    if mp not in PROJECTIONS:
        raise WeatherDataError(source, "MAP_PROJ", "a map projection WRF writes and weather-mi reads: " +
                               ", ".join(f"{k} ({v})" for k, v in PROJECTIONS.items()) +
                               "; 0 for an ideal case without latitude/longitude", f"MAP_PROJ={mp}")

    def get(name, default=None):
        v = attrs.get(name, default)
        if v is None or not math.isfinite(float(v)) or abs(float(v)) >= NOT_SET:
            if default is None:
                raise WeatherDataError(source, name, f"a number (MAP_PROJ={mp}, {PROJECTIONS[mp]}, needs it)",
                                       "missing" if v is None else repr(v))
            return float(default)
        return float(v)

    sphere = f"+a={EARTH_RADIUS_M:.0f} +b={EARTH_RADIUS_M:.0f} +units=m +no_defs"
    if mp == 1:
        lat1 = get("TRUELAT1")
        lat2 = get("TRUELAT2", lat1)
        return (f"+proj=lcc +lat_1={lat1:.10g} +lat_2={lat2:.10g} +lat_0={lat1:.10g} "
                f"+lon_0={get('STAND_LON'):.10g} {sphere}")
    if mp == 2:
        lat1 = get("TRUELAT1")
        pole = 90 if lat1 >= 0 else -90
        return f"+proj=stere +lat_0={pole} +lat_ts={lat1:.10g} +lon_0={get('STAND_LON'):.10g} {sphere}"
    if mp == 3:
        return f"+proj=merc +lat_ts={get('TRUELAT1'):.10g} +lon_0={get('CEN_LON'):.10g} {sphere}"
    if abs(get("POLE_LAT", 90.0) - 90.0) > 1e-6 or abs(get("POLE_LON", 0.0)) > 1e-6:
        raise WeatherDataError(source, "POLE_LAT, POLE_LON", "an unrotated latitude-longitude grid "
                               "(POLE_LAT 90, POLE_LON 0); rotated-pole grids are not supported",
                               f"POLE_LAT={attrs.get('POLE_LAT')}, POLE_LON={attrs.get('POLE_LON')}")
    return f"+proj=eqc +lat_ts=0 +lat_0=0 +lon_0={get('STAND_LON', 0.0):.10g} {sphere}"


@dataclass(frozen=True)
class Georeference:
    """A regular grid on a map projection: mass point (j, i) at projected (x0_m + i dx_m, y0_m + j dy_m).

    Attributes
    ----------
    proj : str
        The PROJ definition of the projection (WRF's sphere).
    map_proj : int
        WRF's MAP_PROJ (1, 2, 3 or 6); 0 for an ideal case placed by hand (``place.assume_place``).
    x0_m, y0_m : float
        Projected coordinates (m) of the first mass point (south-west corner) of the grid.
    dx_m, dy_m : float
        Spacing on the projection plane (m): WRF's DX, DY.
    nx, ny : int
        Mass points along x (west_east) and y (south_north).
    """

    proj: str
    map_proj: int
    x0_m: float
    y0_m: float
    dx_m: float
    dy_m: float
    nx: int
    ny: int

    @property
    def crs(self):
        """The projection as a ``pyproj.CRS``."""
        import pyproj
        return pyproj.CRS.from_proj4(self.proj)

    @property
    def name(self) -> str:
        return PROJECTIONS.get(self.map_proj, LOCAL_PROJECTION)

    def _transformer(self, inverse: bool):
        return _transformer(self.proj, inverse)

    def projected_xy(self) -> tuple[np.ndarray, np.ndarray]:
        """1-D projected x (nx,) and y (ny,) of the mass points (m)."""
        return self.x0_m + self.dx_m * np.arange(self.nx), self.y0_m + self.dy_m * np.arange(self.ny)

    def to_lonlat(self, x_m, y_m) -> tuple[np.ndarray, np.ndarray]:
        """Longitude, latitude (degrees) of projected points (m)."""
        lon, lat = self._transformer(True).transform(np.asarray(x_m, float), np.asarray(y_m, float))
        return np.asarray(lon), np.asarray(lat)

    def to_xy(self, lon, lat) -> tuple[np.ndarray, np.ndarray]:
        """Projected x, y (m) of longitudes, latitudes (degrees)."""
        x, y = self._transformer(False).transform(np.asarray(lon, float), np.asarray(lat, float))
        return np.asarray(x), np.asarray(y)

    def latlon(self) -> tuple[np.ndarray, np.ndarray]:
        """Latitude and longitude (degrees, (ny, nx)) of every mass point, from the projection."""
        x, y = self.projected_xy()
        lon, lat = self.to_lonlat(*np.meshgrid(x, y))
        return lat, lon

    def grid_north_deg(self, lat, lon) -> np.ndarray:
        """Azimuth of the grid's +y axis at (lat, lon), degrees clockwise from true north (the meridian
        convergence; 0 on the central meridian of a Lambert or polar grid, everywhere on Mercator and
        latitude-longitude grids). A direction of true azimuth A points at A - grid_north_deg in the
        grid's frame (x east, y grid north)."""
        lat, lon = np.asarray(lat, float), np.asarray(lon, float)
        step = 1e-4  # degrees of latitude towards true north
        x0, y0 = self.to_xy(lon, lat)
        x1, y1 = self.to_xy(lon, np.minimum(lat + step, 89.9999))
        north = np.degrees(np.arctan2(x1 - x0, y1 - y0))  # true north, clockwise from grid +y
        return -north

    def check(self, lat, lon) -> dict:
        """How far the projection's mass points lie from the file's own ``lat``, ``lon`` (degrees, (ny, nx)):
        the largest distance on the projection plane (m) and the largest differences in degrees."""
        x, y = self.projected_xy()
        gx, gy = np.meshgrid(x, y)
        fx, fy = self.to_xy(lon, lat)
        plat, plon = self.latlon()
        dlon = (np.asarray(lon, float) - plon + 180.0) % 360.0 - 180.0
        return {"projection_error_max_m": float(np.max(np.hypot(fx - gx, fy - gy))),
                "projection_error_max_deg": float(max(np.max(np.abs(lat - plat)), np.max(np.abs(dlon))))}

    def attrs(self) -> dict:
        """The georeference as Dataset attributes (numbers and strings; ``from_attrs`` reads them back)."""
        return {"crs_proj4": self.proj, "map_proj": self.map_proj, "map_projection": self.name,
                "proj_x0_m": self.x0_m, "proj_y0_m": self.y0_m, "proj_dx_m": self.dx_m, "proj_dy_m": self.dy_m}

    @classmethod
    def from_attrs(cls, attrs, nx: int, ny: int) -> Georeference | None:
        """The georeference stored by ``attrs()`` in a Hydrometeors Dataset's attributes (None: none)."""
        if "crs_proj4" not in attrs:
            return None
        return cls(str(attrs["crs_proj4"]), int(attrs["map_proj"]), float(attrs["proj_x0_m"]),
                   float(attrs["proj_y0_m"]), float(attrs["proj_dx_m"]), float(attrs["proj_dy_m"]), nx, ny)


@functools.lru_cache(maxsize=32)  # a Transformer takes milliseconds: one per projection and direction
def _transformer(proj: str, inverse: bool):
    import pyproj
    geo = pyproj.CRS.from_proj4(f"+proj=longlat +a={EARTH_RADIUS_M:.0f} +b={EARTH_RADIUS_M:.0f} +no_defs")
    crs = pyproj.CRS.from_proj4(proj)
    a, b = (crs, geo) if inverse else (geo, crs)
    return pyproj.Transformer.from_crs(a, b, always_xy=True)


def domain_georeference(attrs, source: str) -> Georeference:
    """The georeference of a WRF domain's full mass grid from its global attributes (MAP_PROJ, TRUELAT1/2,
    STAND_LON, CEN_LAT, CEN_LON, DX, DY, WEST-EAST_GRID_DIMENSION, SOUTH-NORTH_GRID_DIMENSION)."""
    proj = proj_string(attrs, source)
    for name in ("DX", "DY", "CEN_LAT", "CEN_LON", "WEST-EAST_GRID_DIMENSION", "SOUTH-NORTH_GRID_DIMENSION"):
        if name not in attrs:
            raise WeatherDataError(source, name, "the global attribute of a georeferenced WRF grid", "missing")
    dx, dy = float(attrs["DX"]), float(attrs["DY"])
    nx, ny = int(attrs["WEST-EAST_GRID_DIMENSION"]) - 1, int(attrs["SOUTH-NORTH_GRID_DIMENSION"]) - 1
    g = Georeference(proj, int(attrs["MAP_PROJ"]), 0.0, 0.0, dx, dy, nx, ny)
    xc, yc = g.to_xy(float(attrs["CEN_LON"]), float(attrs["CEN_LAT"]))  # the domain's centre
    return Georeference(proj, g.map_proj, float(xc) - dx * (nx - 1) / 2, float(yc) - dy * (ny - 1) / 2,
                        dx, dy, nx, ny)


def grid_georeference(attrs, lat, lon, source: str) -> tuple[Georeference, dict]:
    """The georeference of a grid of ``lat``, ``lon`` (degrees, (ny, nx): a WRF domain or any part of it)
    and its check against them (``Georeference.check``, plus the part's offset ``grid_offset_ij`` in the
    domain).

    Raises
    ------
    WeatherDataError
        For an unsupported MAP_PROJ, a missing attribute, or latitudes/longitudes more than half a grid
        spacing from the projection's mass points.
    """
    lat, lon = np.asarray(lat, float), np.asarray(lon, float)
    dom = domain_georeference(attrs, source)
    x, y = dom.to_xy(lon[0, 0], lat[0, 0])  # the part's first point, in the domain
    i0, j0 = round((float(x) - dom.x0_m) / dom.dx_m), round((float(y) - dom.y0_m) / dom.dy_m)
    ny, nx = lat.shape
    g = Georeference(dom.proj, dom.map_proj, dom.x0_m + i0 * dom.dx_m, dom.y0_m + j0 * dom.dy_m,
                     dom.dx_m, dom.dy_m, nx, ny)
    found = g.check(lat, lon)
    if not found["projection_error_max_m"] < 0.5 * min(dom.dx_m, dom.dy_m):
        raise WeatherDataError(source, "XLAT, XLONG", f"latitudes and longitudes on the {dom.name} grid of the "
                               "global attributes (MAP_PROJ, TRUELAT1/2, STAND_LON, CEN_LAT/LON, DX/DY)",
                               f"points up to {found['projection_error_max_m'] / 1e3:.1f} km from it")
    found["grid_offset_ij"] = (int(i0), int(j0))
    return g, found


def enu_vectors(lat_deg, lon_deg):
    """Local east, north and up unit vectors (..., 3) in earth-centred coordinates at geodetic points (up:
    the ellipsoid's normal)."""
    lat, lon = np.radians(lat_deg), np.radians(lon_deg)
    east = np.stack(np.broadcast_arrays(-np.sin(lon), np.cos(lon), 0.0 * lon), -1)
    north = np.stack(np.broadcast_arrays(-np.sin(lat) * np.cos(lon), -np.sin(lat) * np.sin(lon), np.cos(lat)), -1)
    up = np.stack(np.broadcast_arrays(np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)), -1)
    return east, north, up


def haversine_m(lat0, lon0, lat1, lon1) -> np.ndarray:
    """Great-circle distance (m) on WRF's sphere between points given in degrees."""
    p0, p1 = np.radians(lat0), np.radians(lat1)
    a = np.sin((p1 - p0) / 2) ** 2 + np.cos(p0) * np.cos(p1) * np.sin(np.radians(np.subtract(lon1, lon0)) / 2) ** 2
    return 2 * EARTH_RADIUS_M * np.arcsin(np.sqrt(np.clip(a, 0, 1)))


def latlon_text(lat: float, lon: float, digits: int = 4) -> str:
    """"30.0000 N, 87.0000 E" (hemispheres by letter)."""
    return f"{abs(lat):.{digits}f} {'N' if lat >= 0 else 'S'}, {abs(lon):.{digits}f} {'E' if lon >= 0 else 'W'}"
