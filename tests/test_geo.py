"""Georeferenced grids (issue 23, item 1): the map projection of WRF's global attributes, checked against
the files' own latitude/longitude (every projection in ../shared/data), against closed forms for the
projections the data lack, the grid's rotation against WRF's own SINALPHA, the valid time, ideal cases
placed by hand, and bad input."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import xarray as xr

import weather_mi as wm
from weather_mi.cli import commands as cli
from weather_mi.io.projection import EARTH_RADIUS_M, grid_georeference
from weather_mi.io.series import time_steps
from weather_mi.scene.place import assume_place, place_of
from conftest import SHARED_DATA, WRF_SUPERCELL, WRF_THOMPSON, shared_file, write_wrfout

GEO = SHARED_DATA / "geo"
# (file, MAP_PROJ, bound on the largest distance (m) of an XLAT/XLONG point from the projected grid: measured
# 3.4, 1.4 and 215 m; the polar file's few large ones are next to the North Pole and on the line through it
# at right angles to STAND_LON (lat 64-65, lon -68 +- 90: WPS's float32 numerics); its 99th percentile is 9.2 m)
GEO_FILES = [("geo_em_d01_lambert.nc", 1, 10.0), ("geo_em_d01_mercator.nc", 3, 10.0),
             ("geo_em_d01_polarstereo.nc", 2, 300.0)]


def _open(path, **kw):
    with warnings.catch_warnings():  # the plateau file's negative mixing ratios, clipped
        warnings.simplefilter("ignore", UserWarning)
        return wm.open_wrf(path, **kw)


def _latlon(ds):
    lat = ds["XLAT_M" if "XLAT_M" in ds else "XLAT"].values
    lon = ds["XLONG_M" if "XLONG_M" in ds else "XLONG"].values
    return lat.reshape(lat.shape[-2:]), lon.reshape(lon.shape[-2:])


@pytest.mark.parametrize("name, map_proj, tol_m", GEO_FILES)
def test_projection_reproduces_geogrid_latlon(name, map_proj, tol_m):
    path = shared_file(GEO / name)
    ds = xr.open_dataset(path)
    lat, lon = _latlon(ds)
    g, check = grid_georeference(ds.attrs, lat, lon, str(path))
    print(f"{name}: {g.name}, max {check['projection_error_max_m']:.2f} m, {check['projection_error_max_deg']:.2e} deg")
    assert g.map_proj == map_proj and check["grid_offset_ij"] == (0, 0)
    assert check["projection_error_max_m"] < tol_m
    if map_proj == 2:  # but for a few points the check is as tight as for the others
        x, y = g.to_xy(lon, lat)
        gx, gy = np.meshgrid(*g.projected_xy())
        assert float(np.percentile(np.hypot(x - gx, y - gy), 99)) < 10.0
    # a sphere of another radius (WGS84's equatorial) misplaces the grid by far more than that
    other = g.proj.replace(f"+a={EARTH_RADIUS_M:.0f} +b={EARTH_RADIUS_M:.0f}", "+a=6378137 +b=6378137")
    wrong = type(g)(other, g.map_proj, g.x0_m, g.y0_m, g.dx_m, g.dy_m, g.nx, g.ny).check(lat, lon)
    assert wrong["projection_error_max_m"] > 20 * tol_m


def test_plateau_wrfout_placed_in_its_domain():
    """The cropped plateau file (10 x 8 of a 200 x 200 domain) is found at its offset and matches XLAT/XLONG
    within 2 m; a sub-box keeps the file's own latitude/longitude."""
    path = shared_file(WRF_THOMPSON)
    hyd = _open(path, time=1)
    ds = xr.open_dataset(path)
    assert hyd.attrs["map_projection"] == "Lambert conformal"
    assert (hyd.attrs["grid_offset_i"], hyd.attrs["grid_offset_j"]) == (95, 96)
    assert hyd.attrs["projection_error_max_m"] < 2.5
    assert hyd.attrs["valid_time"] == "2005-09-21T03:00:00Z"
    np.testing.assert_array_equal(hyd["lat"].values, ds["XLAT"].values.astype(float))
    sub = _open(path, time=1, x=slice(2, 7), y=slice(1, 5))
    assert (sub.attrs["grid_offset_i"], sub.attrs["grid_offset_j"]) == (97, 97)
    np.testing.assert_array_equal(sub["lon"].values, ds["XLONG"].values[1:5, 2:7].astype(float))
    place = place_of(sub)
    lon, lat = place.to_lonlat(sub.x.values[2], sub.y.values[1])  # a column centre of the Hydrometeors frame
    assert abs(float(lat) - float(ds["XLAT"].values[2, 4])) < 1e-4
    assert abs(float(lon) - float(ds["XLONG"].values[2, 4])) < 1e-4


def test_grid_rotation_matches_wrf_sinalpha():
    """The azimuth of grid north (meridian convergence) against WRF's own SINALPHA and the cone constant's
    closed form n (lon - STAND_LON), n = ln(cos p1 / cos p2) / ln(tan(45 + p2/2) / tan(45 + p1/2))
    (Snyder 1987, Eq. 15-3)."""
    path = shared_file(WRF_THOMPSON)
    ds = xr.open_dataset(path)
    lat, lon = _latlon(ds)
    g, _ = grid_georeference(ds.attrs, lat, lon, str(path))
    north = g.grid_north_deg(lat, lon)
    # WRF rotates grid winds to earth winds as u_e = u COSALPHA - v SINALPHA, v_e = v COSALPHA + u SINALPHA: a
    # wind along grid +y has the earth azimuth -alpha (east of true north where SINALPHA < 0, east of STAND_LON)
    alpha = np.degrees(np.arcsin(ds["SINALPHA"].values.reshape(lat.shape)))
    assert float(np.max(np.abs(north + alpha))) < 0.01 and float(np.max(np.abs(alpha))) > 0.5
    p1, p2 = np.radians(30.0), np.radians(35.0)
    n = math.log(math.cos(p1) / math.cos(p2)) / math.log(math.tan(math.pi / 4 + p2 / 2) / math.tan(math.pi / 4 + p1 / 2))
    assert float(np.max(np.abs(north - n * (lon - 87.0)))) < 0.01


def _attrs(map_proj, nx, ny, dx, **kw):
    return {"MAP_PROJ": map_proj, "DX": dx, "DY": dx, "WEST-EAST_GRID_DIMENSION": nx + 1,
            "SOUTH-NORTH_GRID_DIMENSION": ny + 1, **kw}


def test_latlon_grid_against_regular_degrees():
    """MAP_PROJ 6 (absent from the data): mass points on a regular grid of degrees, DX = R dlon."""
    nx, ny, step = 40, 30, 0.25
    dx = EARTH_RADIUS_M * math.radians(step)
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    lon = 10.0 + (i - (nx - 1) / 2) * step
    lat = -5.0 + (j - (ny - 1) / 2) * step
    attrs = _attrs(6, nx, ny, dx, CEN_LAT=-5.0, CEN_LON=10.0, STAND_LON=0.0, POLE_LAT=90.0, POLE_LON=0.0)
    g, check = grid_georeference(attrs, lat, lon, "synthetic")
    assert check["projection_error_max_m"] < 0.01 and check["grid_offset_ij"] == (0, 0)
    with pytest.raises(wm.WeatherDataError, match="rotated"):
        grid_georeference(dict(attrs, POLE_LAT=40.0), lat, lon, "synthetic")


def test_south_polar_stereographic_against_snyder():
    """MAP_PROJ 2 in the southern hemisphere (absent from the data): lat/lon of the grid from Snyder's
    closed form, rho = 2 R k0 tan(45 + phi/2), k0 = (1 - sin phi_c) / 2, x = rho sin(l - l0),
    y = rho cos(l - l0) (Snyder 1987, Eq. 21-33 to 21-36, the south-polar aspect)."""
    nx, ny, dx, truelat, lon0 = 60, 50, 25000.0, -71.0, 0.0
    k0 = (1 - math.sin(math.radians(truelat))) / 2
    cen_lat, cen_lon = -75.0, 30.0
    rho_c = 2 * EARTH_RADIUS_M * k0 * math.tan(math.pi / 4 + math.radians(cen_lat) / 2)
    xc, yc = rho_c * math.sin(math.radians(cen_lon - lon0)), rho_c * math.cos(math.radians(cen_lon - lon0))
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    x, y = xc + (i - (nx - 1) / 2) * dx, yc + (j - (ny - 1) / 2) * dx
    rho = np.hypot(x, y)
    lat = np.degrees(2 * np.arctan(rho / (2 * EARTH_RADIUS_M * k0))) - 90.0
    lon = lon0 + np.degrees(np.arctan2(x, y))
    attrs = _attrs(2, nx, ny, dx, TRUELAT1=truelat, STAND_LON=lon0, CEN_LAT=cen_lat, CEN_LON=cen_lon)
    _, check = grid_georeference(attrs, lat, lon, "synthetic")
    assert check["projection_error_max_m"] < 0.01
    with pytest.raises(wm.WeatherDataError, match="XLAT, XLONG"):  # a wrong true latitude misplaces the grid
        grid_georeference(dict(attrs, TRUELAT1=-60.0), lat, lon, "synthetic")


def _with_attrs(path, **attrs):
    ds = xr.load_dataset(path)
    ds.attrs.update(attrs)
    ds.to_netcdf(path)
    return path


@pytest.mark.parametrize("map_proj", [4, 5, 102])
def test_unsupported_map_proj_is_named(tmp_path, map_proj):
    path = _with_attrs(write_wrfout(tmp_path / "w.nc"), MAP_PROJ=np.int32(map_proj))
    with pytest.raises(wm.WeatherDataError) as err:
        wm.open_wrf(path)
    text = str(err.value)
    assert str(path) in text and f"MAP_PROJ={map_proj}" in text and "Lambert conformal" in text


def test_ideal_case_has_no_place_until_given_one():
    path = shared_file(WRF_SUPERCELL)
    hyd = wm.open_wrf(path)
    assert place_of(hyd) is None and "valid_time" not in hyd.attrs and "lat" not in hyd.coords
    placed = assume_place(hyd, 35.2, -97.4, "2013-05-20T20:00")
    place = place_of(placed)
    assert (place.centre_lat, place.centre_lon) == pytest.approx((35.2, -97.4), abs=1e-9)
    assert placed.attrs["valid_time"] == "2013-05-20T20:00:00Z"
    # 100 km at 1 km: the corner columns lie 49.5 km east and north of the centre (azimuthal equidistant)
    dlat = float(placed["lat"].values[-1, 50] - placed["lat"].values[0, 50])
    assert dlat == pytest.approx(math.degrees(99e3 / EARTH_RADIUS_M), rel=1e-6)
    with pytest.raises(ValueError, match="together"):
        assume_place(hyd, 35.2, None)
    with pytest.raises(ValueError, match="own latitude"):
        assume_place(placed, 10.0, 10.0)


def test_series_keeps_each_valid_time():
    path = shared_file(WRF_THOMPSON)
    series = _open(path, time="all")
    assert [h.attrs["valid_time"] for h in time_steps(series)] == [
        "2005-09-21T00:00:00Z", "2005-09-21T03:00:00Z", "2005-09-21T06:00:00Z", "2005-09-21T09:00:00Z"]


def test_info_prints_place_projection_time_and_sun(capsys):
    path = shared_file(WRF_THOMPSON)
    assert cli.main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "centre 30.0000 N, 87.0000 E; extent 300.0 km (east-west) x 240.0 km" in out
    assert "Lambert conformal (+proj=lcc +lat_1=30 +lat_2=35" in out and "XLAT/XLONG within" in out
    assert "valid time  : 2005-09-21T09:00:00Z" in out
    assert "azimuth 243.01 deg from true north" in out and "changes by up to 1.5" in out
    assert "terrain     : 4484..5499 m above MSL; 79 of 80 columns land" in out


def test_info_of_an_ideal_case(capsys):
    path = shared_file(WRF_SUPERCELL)
    assert cli.main(["info", str(path)]) == 0
    assert "no latitude/longitude in the input" in capsys.readouterr().out
    assert cli.main(["info", str(path), "--lat", "35.2", "--lon", "-97.4", "--date", "2013-05-20T20:00"]) == 0
    out = capsys.readouterr().out
    assert "centre 35.2000 N, 97.4000 W" in out and "valid time  : 2013-05-20T20:00:00Z" in out and "sun " in out
    assert cli.main(["info", str(WRF_THOMPSON), "--lat", "1", "--lon", "2"]) == 2
    assert "own latitude/longitude" in capsys.readouterr().err
