"""``weather-mi satellite`` (weather_mi/satellite/imagery.py, weather_mi/satellite/ipa.py): the 1-D solver's geometry
against the single-scattering closed form, the satellite view of a uniform layer against DISORT, per-pixel
solar angles against NREL SPA, the command's outputs and its refusals before rendering."""
from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest
import xarray as xr

import weather_mi as wm
from weather_mi.cli import commands as cli
from weather_mi.satellite.ipa import disort_reflectance, scattering_geometry
from conftest import WRF_THOMPSON, shared_file

pytest.importorskip("disortpp")


@pytest.mark.parametrize("phi_deg", [0.0, 60.0, 180.0])
def test_disort_geometry_in_the_single_scattering_limit(phi_deg):
    """tau 1e-5 (single scattering; double scattering adds ~tau): R = pi I / mu0 with
    I = omega p(Theta) mu0 / (mu0 + mu) (1 - exp(-tau (1/mu0 + 1/mu))), p normalised to 1 over 4 pi; the
    azimuth convention (phi - phi0 = 0 forward) shows in p(Theta)."""
    g, mu0, mu, w, tau = 0.7, 0.6, 0.8, 0.9, 1e-5
    r = disort_reflectance([tau], [w], np.array([[g ** k for k in range(65)]]), mu0, mu, phi_deg)
    cos_t = -mu0 * mu + np.sqrt(1 - mu0 ** 2) * np.sqrt(1 - mu ** 2) * np.cos(np.radians(phi_deg))
    p = (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * cos_t) ** 1.5)
    assert r == pytest.approx(np.pi * w * p / (mu0 + mu) * (1 - np.exp(-tau * (1 / mu0 + 1 / mu))), rel=2e-4)


def test_scattering_geometry_of_sun_and_sensor_vectors():
    sun = wm.Sun(120.0, 40.0).to_sun
    sensor = wm.scene.spec.direction_from_angles(300.0, 60.0)  # the sensor opposite the sun: forward scattering
    mu0, mu, phi = scattering_geometry(sun, sensor)
    assert (mu0, mu, phi) == pytest.approx((np.sin(np.radians(40)), np.sin(np.radians(60)), 0.0), abs=1e-6)
    _, _, phi = scattering_geometry(sun, wm.scene.spec.direction_from_angles(120.0, 60.0))  # towards the sun
    assert phi == pytest.approx(180.0)


def test_satellite_view_of_a_uniform_layer_matches_disort():
    """validation/satellite_plane_parallel.py's near-nadir case at tau 10 (the table in its docstring):
    within 1% of DISORT or 3 standard errors."""
    from validation.satellite_plane_parallel import GEOMETRIES, run_case
    wm.set_variant("llvm_ad_rgb")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        row = run_case(10.0, GEOMETRIES[0], spp=1024)
    assert row["pixels"] >= 50 and 0.3 < row["R_disort"] < 0.6
    assert abs(row["R_mc"] - row["R_disort"]) <= max(0.01 * row["R_disort"], 3 * row["se"]), row


def test_per_pixel_sun_is_the_spa_sun_there():
    """One SPA evaluation at the centre carried to points 1000 km away: within 0.01 deg of SPA there."""
    from weather_mi.scene.solar import solar_position, sun_angles_at
    t = "2005-09-21T03:00:00Z"
    centre = solar_position(t, 30.0, 87.0)
    lat, lon = np.array([38.0, 22.0, 30.5]), np.array([95.0, 80.0, 98.0])
    zen, az = sun_angles_at(centre, 30.0, 87.0, lat, lon)
    for k in range(3):
        p = solar_position(t, lat[k], lon[k])
        assert zen[k] == pytest.approx(p.zenith_geometric_deg, abs=0.01)
        assert az[k] == pytest.approx(p.azimuth_deg, abs=0.01)


def _plateau_args(tmp_path, *more):
    return ["satellite", str(shared_file(WRF_THOMPSON)), "--time", "1", "--satellite", "himawari",
            "--resolution", "30km", "--spp", "4", "-o", str(tmp_path / "sat.nc"), *more]


def test_satellite_command_writes_a_cf_netcdf_exr_and_png(tmp_path, capsys):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        assert cli.main(_plateau_args(tmp_path, "--rayleigh")) == 0
    out = capsys.readouterr().out
    assert "himawari" in out and "wrote" in out
    for ext in ("nc", "exr", "png"):
        assert (tmp_path / f"sat.{ext}").is_file()
    assert not (tmp_path / "sat.exr.ckpt.npz").exists()
    ds = xr.open_dataset(tmp_path / "sat.nc")
    assert ds.attrs["Conventions"] == "CF-1.8" and ds.attrs["rayleigh"] == 1
    assert ds["fixed_grid_projection"].attrs["grid_mapping_name"] == "geostationary"
    assert ds["reflectance"].attrs["grid_mapping"] == "fixed_grid_projection"
    for name in ("reflectance", "reflectance_standard_error", "solar_zenith_angle", "sensor_zenith_angle",
                 "sensor_azimuth_angle", "solar_azimuth_angle", "lat", "lon", "cloud", "in_domain"):
        assert name in ds.variables, name
    r = ds.reflectance.values
    assert np.all(np.isfinite(r)) and 0.0 < float(r.mean()) < 1.5
    assert 55.0 < float(ds.sensor_zenith_angle.mean()) < 75.0  # the plateau seen from 140.7 E
    assert int(ds.in_domain.sum()) > 0


@pytest.mark.parametrize("argv, message", [
    (["satellite", "--demo", "cumulus", "--resolution", "5km", "-o", "{tmp}/a.nc"], "latitude/longitude"),
    (["satellite", str(WRF_THOMPSON), "--time", "1", "--satellite", "meteosat", "-o", "{tmp}/a.nc"],
     r"view zenith angle 9\d\.\d deg from meteosat"),
    (["satellite", str(WRF_THOMPSON), "--time", "1", "-o", "{tmp}/a.exr"], "ending in .nc"),
    (["satellite", str(WRF_THOMPSON), "--time", "1", "--resolution", "fine", "-o", "{tmp}/a.nc"], "--resolution"),
    (["satellite", str(WRF_THOMPSON), "--time", "9", "--satellite", "himawari", "-o", "{tmp}/a.nc"],
     r"time index in \[-4, 3\]; found 9"),
    (["satellite", str(WRF_THOMPSON), "--time", "2030-01-01_00:00:00", "--satellite", "himawari", "--rgb",
      "-o", "{tmp}/a.nc"], r"expected one of the file's times"),
])
def test_satellite_refuses_before_rendering(tmp_path, capsys, argv, message):
    shared_file(WRF_THOMPSON)
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert len(__import__("re").findall(message, err)) == 1, err
    assert not list(tmp_path.glob("*.exr")) and not list(tmp_path.glob("*.nc"))


def test_satellite_over_dask_is_bit_identical(tmp_path, capsys):
    """The satellite render's passes as Dask tasks (a LocalCluster of one worker), with the default clear air: the
    same reflectance. And without an atmosphere (``--atmosphere none``), a pixel that sees the bare surround far
    from the domain reads its albedo (a Lambertian surface: R = albedo, whatever the angles), the file's boundary
    albedo in the band (its broadband ALBEDO shaped by the land use, ``--surface file``)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        assert cli.main(_plateau_args(tmp_path)) == 0
        far = tmp_path / "dask"
        assert cli.main(_plateau_args(far) + ["--workers", "1"]) == 0
        assert cli.main(_plateau_args(tmp_path / "none", "--atmosphere", "none")) == 0
        hyd = wm.open_wrf(shared_file(WRF_THOMPSON), time=1)
    a, b = (xr.open_dataset(p / "sat.nc").reflectance.values for p in (tmp_path, far))
    assert xr.open_dataset(tmp_path / "sat.nc").attrs["atmosphere"] == "clear"
    np.testing.assert_array_equal(a, b)
    ds = xr.open_dataset(tmp_path / "none" / "sat.nc")
    a = ds.reflectance.values
    edge = wm.terrain.Terrain.of(hyd).in_band(0.64).edge_albedo()
    surround = (ds.in_domain.values == 0) & (ds.cloud.values == 0)
    assert surround.sum() > 5
    assert float(np.median(a[surround])) == pytest.approx(edge, rel=0.02)


def test_satellite_keeps_an_unfinished_render(tmp_path, capsys):
    """A checkpoint left by an unfinished satellite render is not overwritten without --resume."""
    ckpt = tmp_path / "sat.exr.ckpt.npz"
    ckpt.write_bytes(b"earlier passes")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        assert cli.main(_plateau_args(tmp_path)) == 2
    assert "--resume" in capsys.readouterr().err and ckpt.read_bytes() == b"earlier passes"


def test_the_netcdf_carries_what_the_ecosystem_reads(tmp_path):
    """platform, sensor, times and the band's wavelength as satpy-like tools read them, and a grid mapping
    from which pyresample (an independent reader of CF) rebuilds the fixed grid: its AreaDefinition's
    longitudes and latitudes are the dataset's own, pixel by pixel."""
    pytest.importorskip("pyresample")
    from pyresample.utils.cf import load_cf_area
    from weather_mi.scene.place import assume_place
    from weather_mi.satellite.imagery import render_satellite, satellite_scene
    hyd = assume_place(wm.synthetic.cumulus(), lat=20.0, lon=-60.0, date="2024-07-01T15:00:00Z")
    scene = satellite_scene(hyd, wm.optical_volume(hyd), "goes-east", "0.64", resolution_km=4.0)
    ds, _ = render_satellite(scene, spp=2, progress=False)
    assert ds.attrs["platform_name"] == "GOES-East" and ds.attrs["sensor"] == "abi"
    assert ds.attrs["start_time"] == ds.attrs["end_time"] == "2024-07-01T15:00:00Z"
    r = ds["reflectance"].attrs
    assert r["standard_name"] == "toa_bidirectional_reflectance" and r["wavelength"] == pytest.approx(0.64)
    assert r["channel"] == "C02"
    ds.to_netcdf(tmp_path / "sat.nc")
    area, info = load_cf_area(str(tmp_path / "sat.nc"), variable="reflectance")
    assert info["type_of_grid_mapping"] == "geostationary" and area.shape == ds["reflectance"].shape
    lons, lats = area.get_lonlats()
    np.testing.assert_allclose(lons, ds["lon"].values, atol=1e-6)
    np.testing.assert_allclose(lats, ds["lat"].values, atol=1e-6)
