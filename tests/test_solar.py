"""The sun where and when it was (issue 23, item 2): solar position against published values, the
azimuth convention, the one sun's largest error across a domain against closed forms, and Sun.at."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.cli import commands as cli
from weather_mi.io.projection import EARTH_RADIUS_M, haversine_m
from weather_mi.io.image import Image, read_exr
from weather_mi.scene.place import assume_place, place_of, sun_from_time
from weather_mi.scene.solar import solar_position, sun_across_domain
from conftest import WRF_THOMPSON, shared_file, write_wrfout


def test_spa_published_example():
    """Reda & Andreas (2004), Solar Energy 76, 577-589 (NREL/TP-560-34302), Table A5.1: 17 October 2003,
    12:30:30 local time (UTC-7), latitude 39.742476, longitude -105.1786, elevation 1830.14 m, 820 mbar,
    11 C, delta T 67 s: topocentric zenith 50.11162 deg (refraction-corrected) and azimuth 194.34024 deg
    (from north, eastward); the same values are pvlib's own test expectations (tests/test_solarposition.py:
    apparent_zenith 50.111622, azimuth 194.340241, elevation without refraction 39.872046)."""
    p = solar_position("2003-10-17T12:30:30-07:00", 39.742476, -105.1786, altitude_m=1830.14, pressure_pa=82000.0,
                       temperature_c=11.0, delta_t_s=67.0)
    assert p.zenith_deg == pytest.approx(50.11162, abs=0.01)
    assert p.azimuth_deg == pytest.approx(194.34024, abs=0.01)
    assert 90.0 - p.zenith_geometric_deg == pytest.approx(39.872046, abs=0.01)
    assert abs(p.zenith_deg - 50.11162) < 1e-4 and abs(p.azimuth_deg - 194.34024) < 1e-4  # the SPA itself


def test_azimuth_clockwise_from_north():
    """docs/design.md's convention: on the equinox at the equator the morning sun is in the east (90), the
    evening sun in the west (270); at noon the sun is south (180) of a northern mid-latitude observer and
    north (0) of a southern one."""
    morning = solar_position("2005-09-22T07:00:00Z", 0.0, 0.0)  # 7 h local solar time
    evening = solar_position("2005-09-22T17:00:00Z", 0.0, 0.0)
    assert 80 < morning.azimuth_deg < 100 and 260 < evening.azimuth_deg < 280
    assert solar_position("2005-12-21T12:00:00Z", 45.0, 0.0).azimuth_deg == pytest.approx(180.0, abs=3.0)
    south = solar_position("2005-12-21T12:00:00Z", -45.0, 0.0).azimuth_deg
    assert abs((south + 180.0) % 360.0 - 180.0) < 3.0


def test_one_sun_error_along_a_meridian_at_noon():
    """At transit the zenith is |latitude - declination|: along a meridian (one column wide, 8 to 12 N), the
    sun at the ends differs from the centre's (10 N) by the 2 deg of latitude (refraction changes it by less
    than 0.002 deg at these elevations)."""
    lat = np.linspace(8.0, 12.0, 5)[:, None]
    lon = np.zeros_like(lat)
    transit = "2005-09-21T11:52:30Z"  # equation of time +7.5 min on 21 September
    r = sun_across_domain(transit, lat, lon)
    assert r["max_angle_deg"] == pytest.approx(2.0, abs=0.01)
    assert r["centre_latlon"] == pytest.approx((10.0, 0.0))


def test_one_sun_error_on_the_plateau_file():
    """Measured on the plateau file (300 x 240 km, 2005-09-21 09 UTC): the largest angle between a column's
    sun (in its own horizon, turned into the grid's frame) and the centre's is bounded by the angle between
    their verticals, distance / R (a rotation by theta moves a vector by at most theta), and close to it."""
    path = shared_file(WRF_THOMPSON)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        hyd = wm.open_wrf(path)
    place = place_of(hyd)
    r = place.sun_spread()
    far = float(np.max(haversine_m(place.centre_lat, place.centre_lon, place.lat, place.lon)))
    bound = math.degrees(far / EARTH_RADIUS_M)
    print(f"plateau 09 UTC: one sun up to {r['max_angle_deg']:.3f} deg off (vertical tilt bound {bound:.3f} deg)")
    assert 0.6 * bound < r["max_angle_deg"] <= bound + 0.02
    az, el, meta = sun_from_time(hyd)
    assert meta["one_sun_max_error_deg"] == pytest.approx(r["max_angle_deg"])
    assert el == pytest.approx(90 - 50.859, abs=0.01) and az == pytest.approx(243.01, abs=0.05)


def test_sun_at_and_grid_north():
    t = "2003-10-17T19:30:30Z"
    s = wm.Sun.at(39.742476, -105.1786, t)
    p = solar_position(t, 39.742476, -105.1786)
    assert s.azimuth == pytest.approx(p.azimuth_deg) and s.elevation == pytest.approx(p.elevation_deg)
    turned = wm.Sun.at(39.742476, -105.1786, t, grid_north_deg=10.0, angular_diameter_deg=0.0)
    assert turned.azimuth == pytest.approx(p.azimuth_deg - 10.0) and turned.angular_diameter_deg == 0.0
    with pytest.raises(ValueError, match="below the horizon"):
        wm.Sun.at(39.742476, -105.1786, "2003-10-17T07:00:00Z")


def _ideal_wrfout(tmp_path):
    """A small ideal-case wrfout (MAP_PROJ 0, no XLAT/XLONG) with a cloud."""
    q = np.zeros((1, 6, 4, 5))
    q[0, 2:4, 1:3, 2:4] = 1e-3
    return write_wrfout(tmp_path / "ideal.nc", override={"QCLOUD": q})


def test_sun_from_time_needs_a_place_and_day(tmp_path):
    hyd = wm.open_wrf(_ideal_wrfout(tmp_path))
    with pytest.raises(ValueError, match="--lat, --lon and --date"):
        sun_from_time(hyd)
    with pytest.raises(ValueError, match="below the horizon"):
        sun_from_time(assume_place(hyd, 35.2, -97.4, "2013-05-20T08:00"))
    az, el, _ = sun_from_time(assume_place(hyd, 35.2, -97.4, "2013-05-20T20:00"))
    p = solar_position("2013-05-20T20:00Z", 35.2, -97.4)
    assert (az, el) == pytest.approx((p.azimuth_deg, p.elevation_deg), abs=1e-6)


def test_render_sun_from_time_writes_it(tmp_path, monkeypatch, capsys):
    """``render --sun-from-time``: the scene's sun is the data's, the EXR keeps where, when and the one
    sun's error; at night it refuses before rendering."""
    from weather_mi.reference import render as reference_module
    seen = {}

    def render(spec, vol, **kw):
        seen["sun"] = spec.sun
        rad = np.full((spec.height, spec.width, 3), 0.5, np.float32)
        return Image(rad, np.full_like(rad, 0.01), {"spp": 1, "seconds": 0.0, "noise": None})
    monkeypatch.setattr(reference_module, "render_reference", render)
    path = str(_ideal_wrfout(tmp_path))
    args = ["render", path, "--size", "8x6", "--spp", "1", "--lat", "35.2", "--lon", "-97.4", "--sun-from-time"]
    assert cli.main([*args, "--date", "2013-05-20T20:00", "-o", str(tmp_path / "a.exr")]) == 0
    p = solar_position("2013-05-20T20:00Z", 35.2, -97.4)
    assert seen["sun"].elevation == pytest.approx(p.elevation_deg) and seen["sun"].azimuth == pytest.approx(p.azimuth_deg)
    meta = read_exr(tmp_path / "a.exr")[2]["sun_from_time"]
    assert meta["valid_time"] == "2013-05-20T20:00:00Z" and meta["one_sun_max_error_deg"] < 1.0
    seen.clear()
    assert cli.main([*args, "--date", "2013-05-20T08:00", "-o", str(tmp_path / "b.exr")]) == 2
    assert "below the horizon" in capsys.readouterr().err and not seen


def test_a_tiled_render_takes_the_same_sun_from_time(tmp_path, capsys):
    """``render --tile-size --sun-from-time`` lights the scene as the one-process render does (one
    ``cli.sun_option.with_sun_from_time``): the same line printed, the same sun in the EXR's metadata, the
    solar position of NREL's SPA at the data's place and time."""
    path = str(_ideal_wrfout(tmp_path))
    args = ["render", path, "--size", "8x6", "--spp", "1", "--lat", "35.2", "--lon", "-97.4", "--sun-from-time",
            "--date", "2013-05-20T20:00", "--camera", "orbit", "--camera-elevation", "60", "--no-denoise"]
    assert cli.main([*args, "--tile-size", "4", "-o", str(tmp_path / "t.exr")]) == 0
    tiled = capsys.readouterr().out
    meta = read_exr(tmp_path / "t.exr")[2]["sun_from_time"]
    p = solar_position("2013-05-20T20:00Z", 35.2, -97.4)
    assert meta["valid_time"] == "2013-05-20T20:00:00Z"
    assert meta["centre_lat"] == pytest.approx(35.2) and meta["centre_lon"] == pytest.approx(-97.4)
    line = next(s for s in tiled.splitlines() if s.startswith("sun from the time:"))
    assert f"elevation {p.elevation_deg:.2f} deg, azimuth {p.azimuth_deg:.2f} deg" in line
