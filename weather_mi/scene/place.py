"""The place and time of a Hydrometeors Dataset: its georeference (from the reader, ``weather_mi.io.georef``,
or assumed for an ideal case with ``assume_place``), the sun there at its valid time, and how much that
sun changes across the domain.

The renderers light a domain with one sun in one flat frame (x east, y grid north, z up): the sun of the
centre column, its azimuth turned into the grid's frame by the meridian convergence there
(``Georeference.grid_north_deg``). ``Place.sun_spread`` measures the largest angle between that sun and
the true sun of any column (``weather_mi.scene.solar.sun_across_domain``), which ``info`` prints and
``render --sun-from-time`` writes into the image's metadata.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import WeatherDataError
from ..io.projection import EARTH_RADIUS_M, Georeference, latlon_text
from ..io.hydrometeors import bbox_of
from .solar import SolarPosition, as_utc, solar_position, sun_across_domain


@dataclass(frozen=True)
class Place:
    """Where and when a Hydrometeors Dataset is.

    Attributes
    ----------
    georef : Georeference
        The grid on its map projection.
    lat, lon : numpy.ndarray
        (ny, nx) latitude, longitude of the columns (degrees).
    centre_lat, centre_lon : float
        The domain's centre (degrees).
    extent_km : (float, float)
        East-west and north-south extent of the grid (km).
    valid_time : str or None
        "YYYY-MM-DDTHH:MM:SSZ" (UTC), None where unknown.
    source : str
        "file" or "assumed".
    x0_m, y0_m, dx_m, dy_m : float
        The Hydrometeors frame: column (j, i) at (x0_m + i dx_m, y0_m + j dy_m) (m).
    """

    georef: Georeference
    lat: np.ndarray
    lon: np.ndarray
    centre_lat: float
    centre_lon: float
    extent_km: tuple
    valid_time: str | None
    source: str
    x0_m: float
    y0_m: float
    dx_m: float
    dy_m: float

    def to_lonlat(self, x_m, y_m) -> tuple[np.ndarray, np.ndarray]:
        """Longitude, latitude (degrees) of points (x_m, y_m) of the Hydrometeors frame (m)."""
        i = (np.asarray(x_m, float) - self.x0_m) / self.dx_m
        j = (np.asarray(y_m, float) - self.y0_m) / self.dy_m
        return self.georef.to_lonlat(self.georef.x0_m + i * self.georef.dx_m, self.georef.y0_m + j * self.georef.dy_m)

    def grid_north_deg(self) -> float:
        """Azimuth of the grid's +y axis at the centre, degrees clockwise from true north."""
        return float(self.georef.grid_north_deg(self.centre_lat, self.centre_lon))

    def sun(self, time=None) -> SolarPosition:
        """The sun at the centre at ``time`` (default the valid time; a ValueError where there is none)."""
        return solar_position(self._time(time), self.centre_lat, self.centre_lon)

    def sun_spread(self, time=None) -> dict:
        """``weather_mi.scene.solar.sun_across_domain`` at ``time`` (default the valid time)."""
        return sun_across_domain(self._time(time), self.lat, self.lon, self.georef.grid_north_deg(self.lat, self.lon))

    def _time(self, time):
        if time is None and self.valid_time is None:
            raise ValueError("no valid time: an ideal case needs a date (--date, or assume_place(..., date=...))")
        return self.valid_time if time is None else time


def place_of(hyd) -> Place | None:
    """The Place of a Hydrometeors Dataset (None where it has no latitude/longitude)."""
    if "lat" not in hyd.coords or "lon" not in hyd.coords:
        return None
    lat, lon = np.asarray(hyd["lat"].values, float), np.asarray(hyd["lon"].values, float)
    ny, nx = lat.shape
    georef = Georeference.from_attrs(hyd.attrs, nx, ny)
    if georef is None:
        raise WeatherDataError(str(hyd.attrs.get("source", "dataset")), "crs_proj4",
                               "the georeference attributes beside the lat/lon coordinates")
    (x0, y0, _), (x1, y1, _) = bbox_of(hyd)
    xs, ys = np.asarray(hyd.x.values, float), np.asarray(hyd.y.values, float)
    dx = float(xs[1] - xs[0]) if nx > 1 else float(hyd.attrs.get("proj_dx_m", 1.0))
    dy = float(ys[1] - ys[0]) if ny > 1 else float(hyd.attrs.get("proj_dy_m", 1.0))
    clat, clon = georef.to_lonlat(georef.x0_m + georef.dx_m * (nx - 1) / 2, georef.y0_m + georef.dy_m * (ny - 1) / 2)[::-1]
    return Place(georef, lat, lon, float(clat), float(clon), ((x1 - x0) / 1e3, (y1 - y0) / 1e3),
                 hyd.attrs.get("valid_time"), str(hyd.attrs.get("place_source", "file")), float(xs[0]), float(ys[0]),
                 dx, dy)


def assume_place(hyd, lat: float | None = None, lon: float | None = None, date=None):
    """A copy of an ideal case's Hydrometeors placed at (``lat``, ``lon``) (degrees: the grid's centre) and
    dated ``date`` (its valid time, UTC), on a local azimuthal-equidistant projection centred there on
    WRF's sphere (grid y = true north at the centre).

    Raises
    ------
    ValueError
        Where ``hyd`` has its own latitude/longitude (or valid time, for ``date``), where only one of
        ``lat``, ``lon`` is given, or for a latitude/longitude out of range.
    """
    source = str(hyd.attrs.get("source", "input"))
    if (lat is None) != (lon is None):
        raise ValueError("--lat and --lon go together: give both (degrees north, degrees east)")
    if lat is not None and "lat" in hyd.coords:
        raise ValueError(f"{source} has its own latitude/longitude (XLAT/XLONG): --lat/--lon are for ideal cases")
    if date is not None and hyd.attrs.get("valid_time"):
        raise ValueError(f"{source} has its own valid time ({hyd.attrs['valid_time']}): --date is for ideal cases")
    out = hyd.copy()
    if date is not None:
        try:
            out.attrs["valid_time"] = as_utc(date).strftime("%Y-%m-%dT%H:%M:%SZ")
        except (ValueError, TypeError) as exc:
            raise ValueError(f"--date {date!r}: expected a date and time (UTC), e.g. 2024-05-20T21:00") from exc
        out.attrs["place_source"] = "assumed"
    if lat is None:
        return out
    if not (-90.0 < float(lat) < 90.0 and -180.0 <= float(lon) <= 360.0):
        raise ValueError(f"--lat {lat} --lon {lon}: expected a latitude in (-90, 90) and a longitude in [-180, 360]")
    lon = (float(lon) + 180.0) % 360.0 - 180.0
    xs, ys = np.asarray(hyd.x.values, float), np.asarray(hyd.y.values, float)
    dx = float(xs[1] - xs[0]) if xs.size > 1 else 1000.0
    dy = float(ys[1] - ys[0]) if ys.size > 1 else 1000.0
    proj = (f"+proj=aeqd +lat_0={float(lat):.10g} +lon_0={lon:.10g} +a={EARTH_RADIUS_M:.0f} "
            f"+b={EARTH_RADIUS_M:.0f} +units=m +no_defs")
    georef = Georeference(proj, 0, -dx * (xs.size - 1) / 2, -dy * (ys.size - 1) / 2, dx, dy, xs.size, ys.size)
    la, lo = georef.latlon()
    out = out.assign_coords(lat=(("y", "x"), la, {"units": "degrees_north", "standard_name": "latitude"}),
                            lon=(("y", "x"), lo, {"units": "degrees_east", "standard_name": "longitude"}))
    out.attrs.update(georef.attrs(), place_source="assumed",
                     place=f"assumed: the grid's centre at {latlon_text(float(lat), lon)}")
    return out


def sun_from_time(hyd) -> tuple[float, float, dict]:
    """(azimuth in the grid's frame, elevation, metadata) of the one sun that lights ``hyd``: the sun at its
    centre at its valid time (degrees), and the metadata the image keeps (the place, the time, the sun's
    true azimuth and its largest angular error across the domain).

    Raises
    ------
    ValueError
        Where ``hyd`` has no place or valid time (an ideal case without --lat/--lon/--date), or where the
        sun is below the horizon there and then.
    """
    place = place_of(hyd)
    source = str(hyd.attrs.get("source", "input"))
    if place is None or place.valid_time is None:
        raise ValueError(f"{source}: the sun from the time needs a place and a valid time; the file has "
                         f"{'no latitude/longitude' if place is None else 'no valid time'} (an ideal case: "
                         "give --lat, --lon and --date)")
    sun = place.sun()
    if not sun.above_horizon:
        raise ValueError(f"{source}: at {place.valid_time} the sun is {-sun.elevation_deg:.2f} degrees below the "
                         f"horizon at {latlon_text(place.centre_lat, place.centre_lon, 3)} (the domain's centre)")
    north = place.grid_north_deg()
    spread = place.sun_spread()
    meta = {"valid_time": place.valid_time, "centre_lat": place.centre_lat, "centre_lon": place.centre_lon,
            "solar_zenith_deg": sun.zenith_deg, "solar_zenith_geometric_deg": sun.zenith_geometric_deg,
            "solar_azimuth_true_deg": sun.azimuth_deg,
            "grid_north_deg": north, "one_sun_max_error_deg": spread["max_angle_deg"],
            "one_sun_error_columns": spread["columns"]}
    return (sun.azimuth_deg - north) % 360.0, sun.elevation_deg, meta
