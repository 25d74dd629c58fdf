import math

import numpy as np
import pytest
import pyproj

from weather_mi.satellite import geostationary as gs

EAST = gs.satellite("goes-east")


def test_unknown_satellite_names_the_valid_ones():
    with pytest.raises(ValueError, match="goes-east"):
        gs.satellite("goes-north")


def test_ellipsoid_and_sphere_view_angles_agree():
    lat, lon = np.meshgrid(np.arange(-70.0, 71.0, 5.0), np.arange(-150.0, 1.0, 5.0))
    vza, vaa = gs.view_angles(EAST, lat, lon)
    vza_s, vaa_s = gs.view_angles_sphere(EAST, lat, lon)
    seen = vza < 80.0
    assert seen.sum() > 100
    assert np.max(np.abs(vza - vza_s)[seen]) < 0.2
    far = seen & (vza > 5.0)  # the azimuth is ill defined at the sub-satellite point
    daz = (vaa - vaa_s + 180.0) % 360.0 - 180.0
    assert np.max(np.abs(daz)[far]) < 0.2


def test_view_zenith_at_the_sub_point_and_60_degrees_away():
    vza, _ = gs.view_angles(EAST, 0.0, EAST.sub_lon_deg)
    assert vza == pytest.approx(0.0, abs=1e-9)
    r, r_s, g = 6371000.0, 6371000.0 + EAST.height_m, math.radians(60.0)
    d = math.sqrt(r * r + r_s * r_s - 2 * r * r_s * math.cos(g))  # law of cosines
    by_hand = math.degrees(math.asin(r_s * math.sin(g) / d))  # law of sines (VZA < 90 here)
    vza_s, vaa_s = gs.view_angles_sphere(EAST, 0.0, EAST.sub_lon_deg + 60.0)
    assert vza_s == pytest.approx(by_hand, abs=0.01)
    assert vaa_s == pytest.approx(270.0, abs=1e-6)  # the satellite is due west


def test_fixed_grid_round_trip_and_spacing():
    lat = np.array([30.0, 35.0, 40.0, 33.3])
    lon = np.array([-100.0, -95.0, -90.0, -97.1])
    x, y = gs.lonlat_to_fixed_grid(EAST, lat, lon)
    lon2, lat2 = gs.pixel_lonlat(EAST, x, y)
    assert np.allclose(lon2, lon, atol=1e-6) and np.allclose(lat2, lat, atol=1e-6)
    xs, ys = gs.fixed_grid(EAST, lat, lon, 2.0)
    step = 2000.0 / EAST.height_m
    assert np.allclose(np.diff(xs), step) and np.allclose(np.diff(ys), -step)
    assert xs[0] <= x.min() and xs[-1] >= x.max() and ys[-1] <= y.min() and ys[0] >= y.max()
    assert np.all(np.isnan(gs.pixel_lonlat(EAST, 0.2, 0.2)))  # off the disk


def test_pixel_lonlat_reproduces_the_goes_r_pug_example():
    # GOES-R PUG section 4.2.8.1 worked example (GOES-East fixed grid, lon_0 = -75.0, GRS80):
    # x = -0.024052 rad, y = 0.095340 rad -> 33.846162 N, 84.690932 W
    sat = gs.Satellite("pug", -75.0)
    lon, lat = gs.pixel_lonlat(sat, -0.024052, 0.095340)
    assert lat == pytest.approx(33.846162, abs=1e-4)
    assert lon == pytest.approx(-84.690932, abs=1e-4)


def test_crs_is_geos_on_wgs84():
    crs = EAST.crs()
    assert "geos" in EAST.proj_string() and "+sweep=x" in EAST.proj_string()
    assert crs.ellipsoid.semi_major_metre == pytest.approx(6378137.0)
    assert "+sweep=y" in gs.satellite("himawari").proj_string()


def test_check_visible():
    with pytest.raises(ValueError, match=r"largest view zenith angle \d+\.\d deg from goes-east"):
        gs.check_visible(EAST, np.array([0.0, 35.0]), np.array([60.0, -97.0]), source="wrfout")
    gs.check_visible(EAST, np.array([34.0, 36.5]), np.array([-100.0, -95.0]))


def test_parallax_moves_the_cloud_away_from_the_sub_point():
    h = 10000.0
    lat, lon = gs.apparent_ground_point(EAST, 35.0, -97.0, h)
    geod = pyproj.Geod(ellps="WGS84")
    _, _, shift = geod.inv(-97.0, 35.0, lon, lat)
    vza, _ = gs.view_angles(EAST, 35.0, -97.0)
    assert shift == pytest.approx(float(gs.parallax_shift_m(h, vza)), rel=0.02)
    _, _, d_true = geod.inv(EAST.sub_lon_deg, 0.0, -97.0, 35.0)
    _, _, d_seen = geod.inv(EAST.sub_lon_deg, 0.0, lon, lat)
    assert d_seen > d_true
