"""The view of a geostationary imager in a domain's flat frame: fixed-grid pixels over the domain and, at
every pixel corner, the line of sight from the satellite as a ray of the reference renderer's ``raytable``
sensor.

Geometry. A pixel corner (scan angles x, y) is the point where the line of sight meets the WGS84
ellipsoid (``geostationary.pixel_lonlat``); the model's latitudes/longitudes are taken as geodetic. In the
renderer's frame (the map plane of the model grid: x east, y grid north, z height above sea level, flat)
that corner is (x_m, y_m, 0), and the direction towards the satellite there is the local view zenith and
azimuth (``geostationary.view_angles``), its azimuth turned into the grid's frame by the meridian
convergence (``Georeference.grid_north_deg``). The ray starts where that line is at ``top_m`` (above the
medium) and runs down it. The frame ignores the earth's curvature over the domain, as the renderers do
everywhere (a 100 km domain's edge drops 0.8 km below the centre's tangent plane); the view angles vary
per corner, so parallax is each column's own: a cloud top at height h lands h tan(VZA) away from the
sub-satellite point, as ``geostationary.apparent_ground_point`` puts it on the ellipsoid.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .geostationary import Satellite, apparent_ground_point, check_visible, fixed_grid, pixel_lonlat, view_angles
from ..scene.place import Place
from ..scene.spec import RayTable


@dataclass(frozen=True, eq=False)
class SatelliteView:
    """Pixels of a satellite's fixed grid over a domain and their rays.

    Attributes
    ----------
    satellite : Satellite
    x_rad, y_rad : numpy.ndarray
        Scan angles of the pixel centres (W,), (H,) (radians; x west to east, y north to south).
    lat, lon : numpy.ndarray
        (H, W) geodetic latitude, longitude of the pixel centres on the ellipsoid (degrees).
    view_zenith_deg, view_azimuth_deg : numpy.ndarray
        (H, W) view angles at the pixel centres (azimuth clockwise from true north, towards the satellite).
    x_m, y_m : numpy.ndarray
        (H, W) pixel centres in the domain's frame (m).
    rays : RayTable
        Corner rays in the domain's frame (m).
    resolution_km : float
        Pixel size at the sub-satellite point.
    """

    satellite: Satellite
    x_rad: np.ndarray
    y_rad: np.ndarray
    lat: np.ndarray
    lon: np.ndarray
    view_zenith_deg: np.ndarray
    view_azimuth_deg: np.ndarray
    x_m: np.ndarray
    y_m: np.ndarray
    rays: RayTable
    resolution_km: float

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return self.x_rad.size, self.y_rad.size


def model_xy(place: Place, lon_deg, lat_deg) -> tuple[np.ndarray, np.ndarray]:
    """Points (degrees) in the domain's frame (m): the projection's x, y, scaled from the projection's grid
    spacing to the Hydrometeors grid's (the inverse of ``Place.to_lonlat``)."""
    px, py = place.georef.to_xy(lon_deg, lat_deg)
    g = place.georef
    return (place.x0_m + (np.asarray(px) - g.x0_m) / g.dx_m * place.dx_m,
            place.y0_m + (np.asarray(py) - g.y0_m) / g.dy_m * place.dy_m)


def to_satellite(place: Place, sat: Satellite, lat_deg, lon_deg) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit vectors (..., 3) towards the satellite in the domain's frame at points on the ellipsoid, with
    the view zenith and true azimuth (degrees) there."""
    vza, vaa = view_angles(sat, lat_deg, lon_deg)
    a = np.radians(vaa - place.georef.grid_north_deg(lat_deg, lon_deg))  # true azimuth -> the grid's frame
    t = np.radians(vza)
    return np.stack([np.sin(t) * np.sin(a), np.sin(t) * np.cos(a), np.cos(t)], -1), vza, vaa


def corner_rays(place: Place, sat: Satellite, lat_deg, lon_deg, top_m: float) -> RayTable:
    """Rays down the lines of sight through ground points (H + 1, W + 1) (degrees): each starts where its
    line is at height ``top_m`` (m) and points away from the satellite."""
    s, _, _ = to_satellite(place, sat, lat_deg, lon_deg)
    x, y = model_xy(place, lon_deg, lat_deg)
    ground = np.stack([x, y, np.zeros_like(x)], -1)
    return RayTable(ground + s * (float(top_m) / s[..., 2:3]), -s)


def _edges(centres: np.ndarray) -> np.ndarray:
    step = centres[1] - centres[0] if centres.size > 1 else 0.0
    return np.r_[centres - step / 2, centres[-1] + step / 2]


def satellite_view(place: Place, sat: Satellite, resolution_km: float, top_m: float,
                   max_vza_deg: float = 80.0, source: str = "input") -> SatelliteView:
    """The satellite's fixed-grid pixels of ``resolution_km`` covering the domain of ``place`` and their
    corner rays from ``top_m`` (m, above the medium). The pixels cover the columns' ground points and where
    their tops at ``top_m`` appear (``apparent_ground_point``, h tan(VZA) away from the sub-satellite point):
    a cloud at the domain's far edge is in the image, not cut off by its parallax.

    Raises
    ------
    ValueError
        Where a column of the domain is seen at a view zenith angle above ``max_vza_deg`` (named with the
        angle), or for a non-positive resolution.
    """
    if not (resolution_km > 0 and np.isfinite(resolution_km)):
        raise ValueError(f"--resolution: expected a positive pixel size in km, got {resolution_km}")
    check_visible(sat, place.lat, place.lon, max_vza_deg, source)
    top_lat, top_lon = apparent_ground_point(sat, place.lat, place.lon, top_m)
    x_rad, y_rad = fixed_grid(sat, np.r_[place.lat.ravel(), top_lat.ravel()], np.r_[place.lon.ravel(), top_lon.ravel()],
                              resolution_km)
    gx, gy = np.meshgrid(_edges(x_rad), _edges(y_rad))
    clon, clat = pixel_lonlat(sat, gx, gy)
    if not np.all(np.isfinite(clon)):
        raise ValueError(f"{source}: some pixels of the {sat.name} view lie off the earth's disc")
    rays = corner_rays(place, sat, clat, clon, top_m)
    lon, lat = pixel_lonlat(sat, *np.meshgrid(x_rad, y_rad))
    vza, vaa = view_angles(sat, lat, lon)
    x_m, y_m = model_xy(place, lon, lat)
    return SatelliteView(sat, x_rad, y_rad, lat, lon, vza, vaa, x_m, y_m, rays, float(resolution_km))


def pixel_rays(rays: RayTable) -> tuple[np.ndarray, np.ndarray]:
    """Origins and unit directions (H, W, 3) of the pixel centres' rays: the means of their corner rays."""
    def centre(a):
        return (a[:-1, :-1] + a[1:, :-1] + a[:-1, 1:] + a[1:, 1:]) / 4.0
    d = centre(rays.directions)
    return centre(rays.origins_m), d / np.linalg.norm(d, axis=-1, keepdims=True)


def crosses_box(rays: RayTable, bbox) -> np.ndarray:
    """(H, W) whether each pixel centre's line of sight (going down) passes through the box
    ((x0, y0, z0), (x1, y1, z1), m) after its start."""
    t0, t1, _, _ = box_segment(rays, bbox)
    return t0 <= t1


def box_segment(rays: RayTable, bbox):
    """(t0, t1, origins, directions) of each pixel centre's line of sight (going down, (H, W, 3) origins and
    unit directions ``pixel_rays``): where it enters and leaves the box ((x0, y0, z0), (x1, y1, z1), m), in
    metres from its start; t0 > t1 where it misses the box."""
    o, d = pixel_rays(rays)
    (lo, hi) = (np.asarray(p, float) for p in bbox)
    # the rays go down: inside the box's heights between its top (or the start) and its floor
    t0 = np.maximum((hi[2] - o[..., 2]) / d[..., 2], 0.0)
    t1 = (lo[2] - o[..., 2]) / d[..., 2]
    for k in range(2):  # the prism's sides
        with np.errstate(divide="ignore", invalid="ignore"):
            ta, tb = (lo[k] - o[..., k]) / d[..., k], (hi[k] - o[..., k]) / d[..., k]
        inside = (o[..., k] >= lo[k]) & (o[..., k] <= hi[k])
        near = np.where(d[..., k] == 0, np.where(inside, -np.inf, np.inf), np.minimum(ta, tb))
        far = np.where(d[..., k] == 0, np.where(inside, np.inf, -np.inf), np.maximum(ta, tb))
        t0, t1 = np.maximum(t0, near), np.minimum(t1, far)
    return t0, t1, o, d


__all__ = ["SatelliteView", "satellite_view", "corner_rays", "model_xy", "to_satellite", "pixel_rays", "crosses_box",
           "box_segment"]
