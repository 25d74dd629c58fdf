"""The satellite's view in a domain's frame (weather_mi/satellite/rays.py): the rays of a fixed-grid view
checked against the geometry on the ellipsoid (geostationary.apparent_ground_point, an independent
intersection of the line of sight with WGS84) and against the parallax h tan(VZA)."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.satellite.geostationary import apparent_ground_point, satellite, view_angles
from weather_mi.scene.place import assume_place, place_of
from weather_mi.satellite.rays import corner_rays, model_xy, satellite_view
from conftest import WRF_SUPERCELL, WRF_THOMPSON, shared_file


def _plateau():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return wm.open_wrf(shared_file(WRF_THOMPSON), time=1)


def _ray_at_height(rays, h_m):
    o, d = rays.origins_m[0, 0], rays.directions[0, 0]
    return o + d * ((h_m - o[2]) / d[2])


@pytest.mark.parametrize("which, sat_name", [("plateau", "himawari"), ("supercell", "goes-east"),
                                             ("supercell", "goes-west")])
@pytest.mark.parametrize("h_m", [3000.0, 12000.0])
def test_line_of_sight_through_a_cloud_top_meets_the_ground_where_the_ellipsoid_says(which, sat_name, h_m):
    """A point h above a column is seen at the ground point where the straight line from the satellite
    through it meets WGS84: the ray through that ground point passes the column at height h (within 1% of
    the parallax; the flat frame ignores the earth's curvature over the parallax, h tan(VZA)^2 / R ~ 10 m)."""
    hyd = _plateau() if which == "plateau" else assume_place(wm.open_wrf(shared_file(WRF_SUPERCELL)), 35.2, -97.4)
    place, sat = place_of(hyd), satellite(sat_name)
    lat, lon = place.lat[2, 3], place.lon[2, 3]
    glat, glon = apparent_ground_point(sat, lat, lon, h_m)
    rays = corner_rays(place, sat, np.full((2, 2), glat), np.full((2, 2), glon), 20000.0)
    p = _ray_at_height(rays, h_m)
    x, y = model_xy(place, lon, lat)
    shift = np.hypot(*(np.subtract(model_xy(place, glon, glat), (x, y))))
    vza, _ = view_angles(sat, lat, lon)
    assert shift == pytest.approx(h_m * np.tan(np.radians(vza)), rel=0.01)
    assert np.hypot(p[0] - x, p[1] - y) < 0.01 * shift, (p, x, y, shift)


def test_view_covers_the_domain_and_its_angles_are_the_satellites():
    hyd = _plateau()
    place, sat = place_of(hyd), satellite("himawari")
    view = satellite_view(place, sat, 2.0, 20000.0)
    w, h = view.size
    assert view.rays.origins_m.shape == (h + 1, w + 1, 3)
    (x0, y0, _), (x1, y1, _) = wm.hydrometeors.bbox_of(hyd)
    assert view.x_m.min() <= x0 + 2e3 and view.x_m.max() >= x1 - 2e3
    assert view.y_m.min() <= y0 + 2e3 and view.y_m.max() >= y1 - 2e3
    assert np.all(np.diff(view.y_m[:, w // 2]) < 0)  # row 0 is the north edge
    # every ray starts at 20 km and points away from the satellite (down)
    np.testing.assert_allclose(view.rays.origins_m[..., 2], 20000.0, atol=1e-6)
    assert np.all(view.rays.directions[..., 2] < 0)
    # each corner ray's zenith angle is the view zenith angle of a spherical earth's closed form at the
    # corner (WGS84 vs sphere: < 0.05 deg, tests/test_geostationary.py) and its direction is away from
    # the satellite, whose azimuth (closed form) is turned into the grid by the meridian convergence
    from weather_mi.satellite.geostationary import pixel_lonlat, view_angles_sphere
    from weather_mi.satellite.rays import _edges
    clon, clat = pixel_lonlat(sat, *np.meshgrid(_edges(view.x_rad), _edges(view.y_rad)))
    vza_s, vaa_s = view_angles_sphere(sat, clat, clon)
    d = -view.rays.directions
    np.testing.assert_allclose(np.degrees(np.arccos(d[..., 2])), vza_s, atol=0.05)
    az = np.degrees(np.arctan2(d[..., 0], d[..., 1])) + place.georef.grid_north_deg(clat, clon)
    np.testing.assert_allclose((az - vaa_s + 180.0) % 360.0 - 180.0, 0.0, atol=0.05)
    assert 55.0 < vza_s.mean() < 70.0  # the plateau from 140.7 E


def test_domain_beyond_80_degrees_is_refused_naming_the_angle():
    place = place_of(_plateau())
    with pytest.raises(ValueError, match=r"view zenith angle 9\d\.\d deg from meteosat"):
        satellite_view(place, satellite("meteosat"), 2.0, 20000.0, source="plateau.nc")


def test_ray_table_checks_its_shape_and_scene_size():
    o = np.zeros((3, 5, 3))
    d = np.broadcast_to([0.0, 0.0, -1.0], o.shape)
    rays = wm.RayTable(o, d)
    assert rays.film_size == (4, 2)
    with pytest.raises(ValueError, match=r"\(H \+ 1, W \+ 1, 3\)"):
        wm.RayTable(o[0], d[0])
    cam = wm.Camera.orthographic(center=(0.0, 0.0, 1.0e4), direction=(0.0, 0.0, -1.0), width=1.0, height=1.0)
    with pytest.raises(ValueError, match="ray table is for a 4 x 2 image"):
        wm.SceneSpec(camera=cam, width=8, height=2, rays=rays)
    spec = wm.SceneSpec(camera=cam, width=4, height=2, rays=rays)
    assert spec.to_dict()["rays"]["shape"] == [3, 5, 3]
    assert "rays" not in wm.SceneSpec(camera=cam).to_dict()  # fingerprints of camera views unchanged


def test_lines_of_sight_through_the_box():
    """``crosses_box``: rays tilted 45 deg towards +x from 20 km, over a box 0-10 km wide and 0-5 km tall,
    meeting the ground at x_g: between z = 5 km and the floor a ray spans x_g - 5 km to x_g, so it crosses
    the box iff 0 < x_g < 15 km (and its y is inside)."""
    from weather_mi.satellite.rays import crosses_box
    cx = np.arange(-3.0, 18.5, 1.0) * 1e3 + 0.25e3  # corners; pixel centres at x_g = -2.25 ... 17.75 km
    for y, inside_y in ((5e3, True), (12e3, False)):
        gx, gy = np.meshgrid(cx, [y - 500.0, y + 500.0])
        d = np.broadcast_to(np.array([1.0, 0.0, -1.0]) / np.sqrt(2.0), gx.shape + (3,))
        o = np.stack([gx - 20e3, gy, np.full_like(gx, 20e3)], -1)
        got = crosses_box(wm.RayTable(o, d), ((0.0, 0.0, 0.0), (10e3, 10e3, 5e3)))[0]
        x_g = (cx[:-1] + cx[1:]) / 2
        np.testing.assert_array_equal(got, (x_g > 0) & (x_g < 15e3) & inside_y)
