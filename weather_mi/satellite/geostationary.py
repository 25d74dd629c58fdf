"""Geometry of a geostationary imager: where a satellite sits, its fixed grid (scan angles) and the view
zenith/azimuth angles and parallax of a point seen from it.

The satellite is a point ``height_m`` above the WGS84 equator at ``sub_lon_deg`` (distance from the
earth's centre a + h, a = 6378137 m). Fixed-grid coordinates are scan angles in radians; PROJ's
``geos`` projection writes them multiplied by h (metres).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..io.projection import enu_vectors

WGS84_A_M = 6378137.0
WGS84_F = 1.0 / 298.257223563
WGS84_B_M = WGS84_A_M * (1.0 - WGS84_F)
WGS84_E2 = WGS84_F * (2.0 - WGS84_F)
SPHERE_RADIUS_M = 6371000.0
# GOES-R PUG (vol. 3/5, section 4.2.8, goes_imager_projection): perspective_point_height 35786023 m,
# sweep_angle_axis "x", GRS80 semi-major 6378137 m / semi-minor 6356752.31414 m.
GOES_HEIGHT_M = 35786023.0


@dataclass(frozen=True)
class Satellite:
    """A geostationary satellite.

    Parameters
    ----------
    name : str
        Short name, a key of ``SATELLITES``.
    sub_lon_deg : float
        Longitude of the sub-satellite point (degrees east).
    height_m : float
        Height above the ellipsoid's equator (metres).
    sweep : str
        PROJ ``sweep`` axis: "x" for GOES ABI, "y" for Himawari AHI and Meteosat SEVIRI.
    imager : str
        Its imager, a key of ``bands.Band.channels``: "abi", "ahi" or "seviri".
    """

    name: str
    sub_lon_deg: float
    height_m: float = GOES_HEIGHT_M
    sweep: str = "x"
    imager: str = "abi"

    def proj_string(self) -> str:
        """PROJ definition of the fixed grid on the WGS84 ellipsoid; its x/y are scan angle (rad) x h."""
        return (f"+proj=geos +h={self.height_m!r} +lon_0={self.sub_lon_deg!r} +sweep={self.sweep} "
                "+ellps=WGS84 +units=m +no_defs")

    def crs(self):
        """The fixed grid as a ``pyproj.CRS`` (WGS84 ellipsoid; coordinates are scan angle (rad) x h)."""
        import pyproj
        return pyproj.CRS.from_proj4(self.proj_string())


# Sub-satellite longitudes: GOES-East 75.2 W and GOES-West 137.2 W are the operational positions (the ABI
# product files' fixed grid uses the nominal -75.0 / -137.0). Himawari (140.7 E) and Meteosat (0.0) scan
# with sweep "y" (JMA HSD and EUMETSAT MSG navigation); the GOES height is used for all of them.
SATELLITES = {
    "goes-east": Satellite("goes-east", -75.2, sweep="x"),
    "goes-west": Satellite("goes-west", -137.2, sweep="x"),
    "himawari": Satellite("himawari", 140.7, sweep="y", imager="ahi"),
    "meteosat": Satellite("meteosat", 0.0, sweep="y", imager="seviri"),
}


def satellite(name: str) -> Satellite:
    """The ``Satellite`` called ``name``; a ValueError naming the valid names otherwise."""
    try:
        return SATELLITES[name]
    except KeyError:
        raise ValueError(f"unknown satellite {name!r}; choose one of {', '.join(SATELLITES)}") from None


@functools.lru_cache(maxsize=16)  # a Transformer takes milliseconds to build: one per satellite and direction
def _transformer(sat: Satellite, inverse: bool = False):
    import pyproj
    geo = pyproj.CRS.from_proj4("+proj=longlat +ellps=WGS84 +no_defs")
    a, b = (sat.crs(), geo) if inverse else (geo, sat.crs())
    return pyproj.Transformer.from_crs(a, b, always_xy=True)


def ecef_m(lat_deg, lon_deg, height_m=0.0):
    """Earth-centred earth-fixed x, y, z (metres, stacked on the last axis) of geodetic points on WGS84."""
    lat, lon = np.radians(lat_deg), np.radians(lon_deg)
    n = WGS84_A_M / np.sqrt(1.0 - WGS84_E2 * np.sin(lat) ** 2)
    h = np.asarray(height_m, dtype=float)
    return np.stack(np.broadcast_arrays((n + h) * np.cos(lat) * np.cos(lon), (n + h) * np.cos(lat) * np.sin(lon),
                                        (n * (1.0 - WGS84_E2) + h) * np.sin(lat)), axis=-1)


def satellite_ecef_m(sat: Satellite) -> np.ndarray:
    """ECEF position (metres) of the satellite: a + h from the centre, on the equator."""
    lon = np.radians(sat.sub_lon_deg)
    r = WGS84_A_M + sat.height_m
    return np.array([r * np.cos(lon), r * np.sin(lon), 0.0])


def view_angles(sat: Satellite, lat_deg, lon_deg, height_m=0.0):
    """View zenith and azimuth (degrees) of the satellite seen from points on/above WGS84.

    Parameters
    ----------
    sat : Satellite
    lat_deg, lon_deg : array_like
        Geodetic latitude and longitude of the points (degrees).
    height_m : array_like
        Height of the points above the ellipsoid (metres).

    Returns
    -------
    view_zenith_deg, view_azimuth_deg : ndarray
        Angle between the ellipsoid normal and the direction to the satellite (above 90 where it is below
        the horizon), and that direction's azimuth clockwise from true north in the local east-north plane.
    """
    v = satellite_ecef_m(sat) - ecef_m(lat_deg, lon_deg, height_m)
    east, north, up = enu_vectors(lat_deg, lon_deg)
    u, e, n = (np.sum(v * d, axis=-1) for d in (up, east, north))
    vza = np.degrees(np.arctan2(np.hypot(e, n), u))
    vaa = np.degrees(np.arctan2(e, n)) % 360.0
    return vza, vaa


def view_angles_sphere(sat: Satellite, lat_deg, lon_deg, radius_m=SPHERE_RADIUS_M):
    """View zenith and azimuth (degrees) on a sphere of radius ``radius_m``: the closed form.

    The central angle gamma between the point and the sub-satellite point has
    cos(gamma) = cos(lat) cos(lon - sub_lon); with r_s = R + h the zenith angle is
    atan2(r_s sin(gamma), r_s cos(gamma) - R) (law of sines, valid beyond 90 degrees) and the azimuth is
    the great-circle initial bearing towards the sub-satellite point (0, sub_lon).
    """
    lat = np.radians(lat_deg)
    dlon = np.radians(sat.sub_lon_deg) - np.radians(lon_deg)
    cos_g = np.clip(np.cos(lat) * np.cos(dlon), -1.0, 1.0)
    sin_g = np.sqrt(1.0 - cos_g ** 2)
    r_s = radius_m + sat.height_m
    vza = np.degrees(np.arctan2(r_s * sin_g, r_s * cos_g - radius_m))
    vaa = np.degrees(np.arctan2(np.sin(dlon), -np.sin(lat) * np.cos(dlon))) % 360.0
    return vza, vaa


def lonlat_to_fixed_grid(sat: Satellite, lat_deg, lon_deg):
    """Scan angles x_rad, y_rad of points (NaN where the satellite does not see them)."""
    x, y = _transformer(sat).transform(np.asarray(lon_deg, float), np.asarray(lat_deg, float), errcheck=False)
    x, y = np.asarray(x, float) / sat.height_m, np.asarray(y, float) / sat.height_m
    bad = ~(np.isfinite(x) & np.isfinite(y))
    return np.where(bad, np.nan, x), np.where(bad, np.nan, y)


def pixel_lonlat(sat: Satellite, x_rad, y_rad):
    """Longitude and latitude (degrees) of scan angles ``x_rad``, ``y_rad`` (NaN off the earth)."""
    lon, lat = _transformer(sat, inverse=True).transform(np.asarray(x_rad, float) * sat.height_m,
                                                         np.asarray(y_rad, float) * sat.height_m, errcheck=False)
    lon, lat = np.asarray(lon, float), np.asarray(lat, float)
    bad = ~(np.isfinite(lon) & np.isfinite(lat)) | (np.abs(lat) > 90.0)
    return np.where(bad, np.nan, lon), np.where(bad, np.nan, lat)


def fixed_grid(sat: Satellite, lat_deg, lon_deg, resolution_km: float):
    """Fixed-grid pixel centres covering the bounding box (in scan angle) of the given points.

    The pixel size is the band resolution at the sub-satellite point, resolution_m / height_m radians
    (GOES ABI 2 km: 56 microrad). Centres lie at odd multiples of half a pixel, as in the ABI full disk.

    Returns
    -------
    x_rad, y_rad : ndarray
        1D scan angles, x ascending (west to east) and y descending (north to south), like GOES files.
    """
    x, y = lonlat_to_fixed_grid(sat, lat_deg, lon_deg)
    if not np.all(np.isfinite(x)):
        raise ValueError(f"some points are not visible from {sat.name}")
    step = resolution_km * 1000.0 / sat.height_m

    def centres(lo, hi):
        k0, k1 = np.floor(lo / step - 0.5), np.ceil(hi / step - 0.5)
        return (np.arange(k0, k1 + 1) + 0.5) * step

    return centres(np.min(x), np.max(x)), centres(np.min(y), np.max(y))[::-1]


def check_visible(sat: Satellite, lat_deg, lon_deg, max_vza_deg: float = 80.0, source: str = "input"):
    """A ValueError naming ``source``, the satellite and the largest view zenith angle if any point is seen
    at more than ``max_vza_deg``."""
    vza, _ = view_angles(sat, lat_deg, lon_deg)
    worst = float(np.nanmax(vza))
    if worst > max_vza_deg:
        raise ValueError(f"{source}: largest view zenith angle {worst:.1f} deg from {sat.name} "
                         f"(sub-satellite longitude {sat.sub_lon_deg}) exceeds {max_vza_deg} deg")


def parallax_shift_m(height_m, vza_deg):
    """Parallax displacement h tan(VZA) (metres) of a cloud at ``height_m`` seen at ``vza_deg``.

    In an image georeferenced on the ground, the cloud appears displaced AWAY from the sub-satellite
    point: the line of sight through the cloud meets the ground farther from the sub-satellite point.
    """
    return np.asarray(height_m, float) * np.tan(np.radians(vza_deg))


def apparent_ground_point(sat: Satellite, lat_deg, lon_deg, height_m):
    """Latitude and longitude (degrees) where the line of sight from the satellite through a point
    ``height_m`` above (lat_deg, lon_deg) meets the WGS84 ellipsoid."""
    s = satellite_ecef_m(sat)
    d = ecef_m(lat_deg, lon_deg, height_m) - s
    w = np.array([1.0, 1.0, (WGS84_A_M / WGS84_B_M) ** 2])
    qa = np.sum(w * d * d, -1)
    qb = 2.0 * np.sum(w * s * d, -1)
    qc = np.sum(w * s * s) - WGS84_A_M ** 2
    disc = qb * qb - 4.0 * qa * qc
    t = (-qb - np.sqrt(np.where(disc >= 0, disc, np.nan))) / (2.0 * qa)  # first hit from the satellite
    p = s + t[..., None] * d
    lon = np.degrees(np.arctan2(p[..., 1], p[..., 0]))
    lat = np.degrees(np.arctan2(p[..., 2], (1.0 - WGS84_E2) * np.hypot(p[..., 0], p[..., 1])))
    return lat, lon
