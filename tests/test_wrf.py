"""WRF reader: air density, regridding conservation, species, orientation and every bad-input case."""
import warnings

import netCDF4
import numpy as np
import pytest
import xarray as xr

import weather_mi as wm
from weather_mi.io.standard_atmosphere import standard_density
from weather_mi.io import vertical
from conftest import WRF_SUPERCELL, WRF_THOMPSON, shared_file, write_wrfout


def rho_by_hand(p, t_pert, qv):
    """optics-notes: theta = T + 300, T_K = theta (p/1e5)^0.2857, rho_d = p / (287 T_K (1 + 1.608 qv))."""
    t_k = (t_pert + 300.0) * (p / 1e5) ** 0.2857
    return p / (287.0 * t_k * (1 + 1.608 * qv))


@pytest.mark.parametrize("path,t", [(WRF_SUPERCELL, 0), (WRF_THOMPSON, 2)])
def test_air_density_against_formula_and_alt(path, t):
    shared_file(path)
    with netCDF4.Dataset(path) as nc:
        points = [(0, 3, 4), (10, 5, 2), (20, 7, 9)]
        for k, j, i in points:
            p = float(nc["P"][t, k, j, i]) + float(nc["PB"][t, k, j, i])
            expected = rho_by_hand(p, float(nc["T"][t, k, j, i]), float(nc["QVAPOR"][t, k, j, i]))
            got = wm.io.wrf.dry_air_density(p, float(nc["T"][t, k, j, i]) + 300.0, float(nc["QVAPOR"][t, k, j, i]))
            assert got == pytest.approx(expected, rel=1e-9)
            # and plausible against the 1976 standard atmosphere at that height (within 20%)
            zw = (nc["PH"][t, k:k + 2, j, i] + nc["PHB"][t, k:k + 2, j, i]) / 9.81
            assert expected == pytest.approx(float(standard_density(zw.mean())), rel=0.2)
            if "ALT" in nc.variables:  # WRF's own inverse dry-air density
                assert expected * float(nc["ALT"][t, k, j, i]) == pytest.approx(1.0, abs=3e-3)
        # the regridded density at a cell centre equals the native profile interpolated there (within 1%)
        hyd = wm.open_wrf(path, time=t)
        zw = (nc["PH"][t, :, 5, 2] + nc["PHB"][t, :, 5, 2]) / 9.81
        zm = 0.5 * (zw[1:] + zw[:-1])
        p = nc["P"][t, :, 5, 2] + nc["PB"][t, :, 5, 2]
        rho = rho_by_hand(p, nc["T"][t, :, 5, 2], nc["QVAPOR"][t, :, 5, 2])
        for kk in range(2, hyd.sizes["z"] - 2, 5):
            z = float(hyd.z[kk])
            if zm[0] < z < zm[-1]:
                assert float(hyd.rho_air[kk, 5, 2]) == pytest.approx(np.interp(z, zm, rho), rel=0.01)


def test_supercell_species_and_maxima():
    hyd = wm.open_wrf(shared_file(WRF_SUPERCELL))
    # data README: max QCLOUD 3.8 g/kg, QRAIN 17.5, QICE 0.33, QSNOW 4.3, QGRAUP 13.3 (native grid);
    # the conservative height regridding averages peaks slightly
    readme = {"cloud": 3.8, "rain": 17.5, "ice": 0.33, "snow": 4.3, "graupel": 13.3}
    for name, gkg in readme.items():
        assert 1e3 * float(hyd[f"q_{name}"].max()) == pytest.approx(gkg, rel=0.2), name
    assert hyd.attrs["microphysics"] == "WSM6"
    assert hyd.sizes["y"] == 100 and hyd.sizes["x"] == 100
    assert float(hyd.x[1] - hyd.x[0]) == 1000.0
    assert hyd.attrs["alt_max_rel_diff"] < 0.01
    # cloud tops 15-17 km (README)
    cond = sum(hyd[f"q_{s}"] for s in wm.SPECIES_NAMES)
    top = float(hyd.z[np.nonzero((cond > 1e-5).any(axis=(1, 2)).values)[0].max()])
    assert 14e3 < top < 18e3


def native_water_path(nc, t):
    zw = (nc["PH"][t] + nc["PHB"][t]) / 9.81
    p = nc["P"][t] + nc["PB"][t]
    rho = rho_by_hand(p, nc["T"][t], nc["QVAPOR"][t])
    q = sum(np.maximum(nc[v][t], 0) for v in ("QCLOUD", "QRAIN", "QICE", "QSNOW", "QGRAUP"))
    return np.asarray((rho * q * np.diff(zw, axis=0)).sum(axis=0))


@pytest.mark.parametrize("dz", [None, 250.0, 1000.0])
def test_regridding_conserves_column_water_path_real_file(dz):
    path = shared_file(WRF_SUPERCELL)
    with netCDF4.Dataset(path) as nc:
        native = native_water_path(nc, 0)
    hyd = wm.open_wrf(path, dz=dz)
    q = sum(hyd[f"q_{s}"].values.astype(np.float64) for s in wm.SPECIES_NAMES)
    regridded = (hyd.rho_air.values * q).sum(axis=0) * float(hyd.z[1] - hyd.z[0])
    assert regridded.sum() == pytest.approx(native.sum(), rel=0.01)
    wet = native > 0.5 * native.max()  # the storm's core columns, kg/m^2
    np.testing.assert_allclose(regridded[wet], native[wet], rtol=0.01)


def test_regridding_exact_on_linear_profile():
    nz, top = 13, 6500.0
    zw = np.linspace(0.0, top, nz + 1)[:, None, None] * np.ones((1, 2, 3))
    zw[1:-1] += 80.0 * np.sin(np.arange(1, nz))[:, None, None]  # uneven layers
    zm = 0.5 * (zw[1:] + zw[:-1])
    f = 3.0 + 2e-4 * zm
    edges = np.linspace(0.0, top, 27)
    avg = vertical.cell_averages(zm, zw, f, edges)
    centres = 0.5 * (edges[1:] + edges[:-1])
    inner = (centres > zm[0, 0, 0] + 250) & (centres < zm[-1, 0, 0] - 250)  # away from the end caps
    np.testing.assert_allclose(avg[inner, 0, 0], 3.0 + 2e-4 * centres[inner], rtol=1e-12)
    # the column integral of the reconstruction equals the finite-volume integral for linear data
    # on uniform layers, exactly
    zw_u = np.linspace(0.0, top, nz + 1)[:, None, None]
    zm_u = 0.5 * (zw_u[1:] + zw_u[:-1])
    f_u = 3.0 + 2e-4 * zm_u
    avg_u = vertical.cell_averages(zm_u, zw_u, f_u, edges)
    assert avg_u.sum() * (edges[1] - edges[0]) == pytest.approx(float(vertical.column_integral(zw_u, f_u)[0, 0]),
                                                                rel=1e-12)
    assert avg_u.sum() * (edges[1] - edges[0]) == pytest.approx(3.0 * top + 1e-4 * top ** 2, rel=1e-12)


def test_terrain_cells_below_ground_are_clear(tmp_path):
    terrain = np.zeros((4, 5))
    terrain[:, 3:] = 1200.0
    q = np.full((1, 6, 4, 5), 1e-3)
    path = write_wrfout(tmp_path / "w.nc", terrain=terrain, override={"QCLOUD": q})
    hyd = wm.open_wrf(path, dz=300.0)
    assert float(hyd.q_cloud[0, 0, 4]) == 0.0 and float(hyd.q_cloud[3, 0, 4]) == 0.0  # under the hill
    assert float(hyd.q_cloud[0, 0, 0]) > 0.0


def test_orientation_kept_reader_to_optics(tmp_path):
    q = np.zeros((1, 6, 4, 5))
    q[0, 2, 1, 3] = 2e-3  # one blob: level 2, south_north 1, west_east 3
    path = write_wrfout(tmp_path / "w.nc", override={"QRAIN": q}, dx=2000.0)
    hyd = wm.open_wrf(path, dz=500.0)
    vol = wm.optical_volume(hyd)
    k, j, i = np.unravel_index(np.argmax(vol.beta_total), vol.shape)
    assert (j, i) == (1, 3) and k == 2
    assert float(hyd.x[i]) == 6000.0 and float(hyd.y[j]) == 2000.0
    assert 1000.0 <= float(hyd.z[k]) <= 1500.0


def test_time_selection_and_subbox(tmp_path):
    times = ("2020-01-01_00:00:00", "2020-01-01_01:00:00")
    q = np.zeros((2, 6, 4, 5))
    q[1] = 1e-3
    path = write_wrfout(tmp_path / "w.nc", times=times, override={"QSNOW": q})
    assert float(wm.open_wrf(path, time=0).q_snow.max()) == 0.0
    assert float(wm.open_wrf(path, time=-1).q_snow.max()) > 0.0
    assert wm.open_wrf(path, time="2020-01-01T01:00").attrs["time"] == times[1]
    sub = wm.open_wrf(path, x=slice(1, 4), y=slice(2, 4))
    assert (sub.sizes["y"], sub.sizes["x"]) == (2, 3) and float(sub.x[0]) == 1000.0 and float(sub.y[0]) == 2000.0
    with pytest.raises(wm.WeatherDataError, match=r"w\.nc.*Times.*2021"):
        wm.open_wrf(path, time="2021-01-01_00:00:00")
    with pytest.raises(wm.WeatherDataError, match="Times.*index"):
        wm.open_wrf(path, time=5)


def test_wsm3_missing_species_warns_with_scheme(tmp_path):
    path = write_wrfout(tmp_path / "w.nc", mp_physics=3, species=("QCLOUD", "QRAIN"))
    with pytest.warns(UserWarning, match="WSM3.*QICE"):
        hyd = wm.open_wrf(path)
    assert float(hyd.q_ice.max()) == 0.0 and float(hyd.q_graupel.max()) == 0.0


def test_negative_mixing_ratios_clipped_and_counted(tmp_path):
    q = np.zeros((1, 6, 4, 5))
    q[0, 1, 1, 1] = -1e-7
    q[0, 3, 2, 2] = -2e-8
    with pytest.warns(UserWarning, match="negative"):
        hyd = wm.open_wrf(write_wrfout(tmp_path / "w.nc", override={"QCLOUD": q}))
    assert hyd.attrs["n_negative_clipped"] == 2 and float(hyd.q_cloud.min()) >= 0.0


def test_effective_radius_read(tmp_path):
    q = np.full((1, 6, 4, 5), 1e-3)
    re = np.full((1, 6, 4, 5), 12e-6)
    hyd = wm.open_wrf(write_wrfout(tmp_path / "w.nc", override={"QCLOUD": q, "RE_CLOUD": re}))
    np.testing.assert_allclose(hyd.r_eff_cloud.values[1:-1], 12e-6, rtol=1e-5)


# ---- bad input: every case names the file, the variable and the expectation ----

def test_missing_file(tmp_path):
    with pytest.raises(wm.WeatherDataError, match="nope.nc.*existing wrfout"):
        wm.open_wrf(tmp_path / "nope.nc")


def test_not_netcdf(tmp_path):
    bad = tmp_path / "bad.nc"
    bad.write_text("this is not a NetCDF file\n")
    with pytest.raises(wm.WeatherDataError, match="bad.nc.*NetCDF"):
        wm.open_wrf(bad)


@pytest.mark.parametrize("var", ["P", "PB", "T", "PH", "PHB"])
def test_missing_required_variable(tmp_path, var):
    path = write_wrfout(tmp_path / "w.nc", drop=(var,))
    with pytest.raises(wm.WeatherDataError, match=rf"w.nc.*{var}.*expected the wrfout variables"):
        wm.open_wrf(path)


def test_nan_in_field(tmp_path):
    q = np.zeros((1, 6, 4, 5))
    q[0, 2, 2, 2] = np.nan
    with pytest.raises(wm.WeatherDataError, match="w.nc.*QGRAUP.*finite.*1 NaN"):
        wm.open_wrf(write_wrfout(tmp_path / "w.nc", override={"QGRAUP": q}))


def test_non_monotonic_heights(tmp_path):
    zw = np.broadcast_to((np.arange(7) * 500.0 * 9.81)[:, None, None], (7, 4, 5)).copy()
    zw[3, 1, 1] = zw[1, 1, 1]
    with pytest.raises(wm.WeatherDataError, match="w.nc.*PH\\+PHB.*increasing"):
        wm.open_wrf(write_wrfout(tmp_path / "w.nc", override={"PHB": zw[None]}))


def test_mismatched_shapes(tmp_path):
    path = write_wrfout(tmp_path / "w.nc")
    ds = xr.load_dataset(path)
    ds["QICE"] = (("Time", "bottom_top", "south_north", "we_other"), np.zeros((1, 6, 4, 7), np.float32))
    ds.to_netcdf(tmp_path / "m.nc")
    with pytest.raises(wm.WeatherDataError, match=r"m.nc.*QICE.*shape \(6, 4, 5\)"):
        wm.open_wrf(tmp_path / "m.nc")


def test_cli_reports_error_without_traceback(tmp_path, capsys):
    from weather_mi.cli.commands import main
    assert main(["info", str(tmp_path / "missing.nc")]) == 2
    err = capsys.readouterr().err
    assert "missing.nc" in err and "Traceback" not in err


def test_plateau_terrain_and_heights_above_sea_level():
    """Issue 23, item 3, on the Tibetan-plateau file (terrain 4484-5499 m): HGT on the model grid, land from
    LANDMASK (one lake column), albedo from ALBEDO at the time read; WRF's surface w-level (PH + PHB) / g
    is HGT; the regridded volume is in metres above MSL and starts at the lowest terrain; every cell wholly
    below a column's HGT is clear, and the volume's air above each column's HGT is the model's column of
    dry air within 0.2 % (the lowest model level sits on HGT: 50 m off would be 0.7 %)."""
    path = shared_file(WRF_THOMPSON)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        hyd = wm.open_wrf(path, time=2, dz=250.0)
    ds = xr.open_dataset(path)
    hgt = ds["HGT"].values.astype(float)
    terrain = wm.terrain.Terrain.of(hyd)
    np.testing.assert_array_equal(terrain.height_m, hgt)
    assert hgt.min() > 4400 and hgt.max() > 5400
    np.testing.assert_array_equal(terrain.land, ds["LANDMASK"].values > 0.5)
    assert int((~terrain.land).sum()) == 1 and terrain.albedo[~terrain.land][0] == pytest.approx(0.08)
    np.testing.assert_allclose(terrain.albedo, ds["ALBEDO"].values[2], rtol=1e-6)
    assert hyd.attrs["terrain_surface_max_diff_m"] < 0.01 and terrain.albedo_source == "ALBEDO"
    dz = float(hyd.z[1] - hyd.z[0])
    bottom = float(hyd.z[0]) - dz / 2
    assert bottom == pytest.approx(hgt.min(), abs=1e-3)  # above MSL, from the lowest terrain
    tops = (hyd.z.values + dz / 2)[:, None, None]
    below = tops <= hgt[None]  # cells wholly under the ground
    assert int(below.sum()) > 50
    water = sum(hyd[f"q_{s}"].values for s in ("cloud", "ice", "rain", "snow", "graupel"))
    assert float(water[below].max()) == 0.0
    # the air above HGT in the volume (each cell's part above HGT) is the model's column of dry air
    z_w = (ds["PH"].values[2] + ds["PHB"].values[2]) / 9.81
    above = np.clip((np.minimum(tops, z_w[-1][None]) - np.maximum(tops - dz, hgt[None])) / dz, 0.0, 1.0)
    column = (hyd["rho_air"].values * above).sum(axis=0) * dz
    p = ds["P"].values[2] + ds["PB"].values[2]
    rho = wm.io.wrf.dry_air_density(p, ds["T"].values[2] + 300.0, ds["QVAPOR"].values[2])
    native = vertical.column_integral(z_w, rho)
    print(f"column air: max relative difference {np.max(np.abs(column / native - 1)):.2e}")
    np.testing.assert_allclose(column, native, rtol=2e-3)
    np.testing.assert_allclose(z_w[0], hgt, atol=0.01)
    # the same columns' terrain in the height-field mesh the scene can build
    vertices, faces, albedo = terrain.mesh()
    assert vertices.shape == (80, 3) and faces.shape == (2 * 7 * 9, 3) and albedo.shape == (80,)
    np.testing.assert_array_equal(vertices[:, 2].reshape(8, 10), hgt)
    v = vertices[faces]
    normals = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    assert np.all(normals[:, 2] > 0)


def test_terrain_defaults_without_surface_variables(tmp_path):
    """A wrfout without HGT, LANDMASK, XLAND and ALBEDO: the terrain is the surface w-level and the albedo
    WRF's LW12 land default (20 %); with XLAND only, water columns get 8 %."""
    terrain = np.zeros((4, 5))
    terrain[:, 3:] = 1200.0
    path = write_wrfout(tmp_path / "w.nc", terrain=terrain)
    hyd = wm.open_wrf(path)
    np.testing.assert_allclose(hyd["terrain_height"].values, terrain, atol=1e-3)
    assert np.all(hyd["surface_albedo"].values == 0.20) and "land assumed" in hyd.attrs["surface_albedo_source"]
    xland = np.ones((1, 4, 5))
    xland[0, :, :2] = 2.0
    path = write_wrfout(tmp_path / "x.nc", override={"XLAND": xland})
    hyd = wm.open_wrf(path)
    np.testing.assert_array_equal(hyd["land"].values, xland[0] < 1.5)
    np.testing.assert_array_equal(hyd["surface_albedo"].values, np.where(xland[0] < 1.5, 0.20, 0.08))
