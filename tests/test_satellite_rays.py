"""The satellite's view in a domain's frame (weather_mi/satellite_rays.py): the rays of a fixed-grid view
checked against the geometry on the ellipsoid (geostationary.apparent_ground_point, an independent
intersection of the line of sight with WGS84) and against the parallax h tan(VZA)."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.geostationary import apparent_ground_point, satellite, view_angles
from weather_mi.place import assume_place, place_of
from weather_mi.satellite_rays import corner_rays, model_xy, satellite_view
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
    cos_vza = -view.rays.directions[..., 2]
    assert 55.0 < np.degrees(np.arccos(cos_vza)).mean() < 70.0  # the plateau from 140.7 E
    vza, vaa = view_angles(sat, view.lat, view.lon)
    np.testing.assert_array_equal(vza, view.view_zenith_deg)


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
