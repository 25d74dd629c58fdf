"""Procedural demo storms (weather_mi.io.synthetic): determinism, the Hydrometeors contract, the
1976 standard-atmosphere density, storm anatomy (anvil, updraft, graupel, rain, overshooting top,
cumulus shape) and orders of magnitude against the real WRF supercell in ../shared/data.

Expected numbers come from published tables (U.S. Standard Atmosphere 1976), from the real WRF file
read here directly with xarray, and from geometry computed here from the arrays -- never from the
module's own constants.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from weather_mi.io import synthetic
from weather_mi.errors import WeatherDataError
from weather_mi.io.hydrometeors import SPECIES_NAMES, validate

WRF_SUPERCELL = Path(__file__).resolve().parents[2] / "shared" / "data" / "wrf" / "wrfout_quarter_ss_0130.nc"
WRF_VARS = {"cloud": "QCLOUD", "rain": "QRAIN", "ice": "QICE", "snow": "QSNOW", "graupel": "QGRAUP"}
THRESHOLD = 1e-5  # kg/kg: "there is condensate here"
# U.S. Standard Atmosphere 1976, Table I (geometric height m -> density kg/m^3)
USSA_1976 = {0.0: 1.2250, 5000.0: 0.73643, 10000.0: 0.41351, 15000.0: 0.19476}


@pytest.fixture(scope="module")
def sc():
    return synthetic.supercell()


@pytest.fixture(scope="module")
def cu():
    return synthetic.cumulus()


@pytest.fixture(scope="module")
def real():
    """Per-species maxima (kg/kg), storm top and cloud-water top (m) of the real WRF supercell."""
    if not WRF_SUPERCELL.is_file():
        pytest.skip(f"real WRF supercell {WRF_SUPERCELL} is absent "
                    "(tests use ../shared/data relative to the repository)")
    with xr.open_dataset(WRF_SUPERCELL) as ds:
        ds = ds.isel(Time=0)
        zw = ((ds["PH"] + ds["PHB"]) / 9.81).values                 # heights of the w levels (m)
        zm = 0.5 * (zw[1:] + zw[:-1]).mean(axis=(1, 2))              # destaggered, flat terrain
        q = {name: ds[var].values.astype(np.float64) for name, var in WRF_VARS.items()}
        cell_km2 = float(ds.attrs["DX"]) * float(ds.attrs["DY"]) / 1e6
    total = sum(q.values())
    return {"max": {name: float(a.max()) for name, a in q.items()},
            "top": _highest(total, zm), "cloud_top": _highest(q["cloud"], zm),
            "anvil_km2": _area_above(total, zm, 9000.0, cell_km2)}


# ----------------------------------------------------------------------------- helpers
def _highest(q, z):
    """Highest level (m) where q exceeds THRESHOLD anywhere."""
    levels = np.nonzero(np.asarray(q).reshape(len(z), -1).max(axis=1) > THRESHOLD)[0]
    return float(z[levels.max()]) if levels.size else float("nan")


def _area_above(q, z, height, cell_km2):
    """Area (km^2) of the columns with condensate above ``height`` (m)."""
    return float((np.asarray(q)[z > height] > THRESHOLD).any(axis=0).sum()) * cell_km2


def _lowest(q, z):
    levels = np.nonzero(np.asarray(q).reshape(len(z), -1).max(axis=1) > THRESHOLD)[0]
    return float(z[levels.min()])


def _q(ds, name):
    return ds[f"q_{name}"].values.astype(np.float64)


def _total(ds):
    return sum(_q(ds, s) for s in SPECIES_NAMES)


def _updraft_xy(ds):
    """The updraft, found from the data: the column with the largest cloud-water path below 8 km."""
    z = ds.z.values
    low = z < 8000.0
    path = (_q(ds, "cloud")[low] * ds.rho_air.values[low]).sum(axis=0)
    j, i = np.unravel_index(int(np.argmax(path)), path.shape)
    return float(ds.x[i]), float(ds.y[j])


def _shear_frame(ds, azimuth_deg, origin):
    """(s, n) on the (y, x) grid: distance downshear and to the left of the shear vector from origin."""
    az = np.deg2rad(azimuth_deg)
    ue, un = np.sin(az), np.cos(az)
    X = ds.x.values[None, :] - origin[0]
    Y = ds.y.values[:, None] - origin[1]
    return X * ue + Y * un, -X * un + Y * ue


def _anvil_columns(ds):
    z = ds.z.values
    frozen = _q(ds, "ice") + _q(ds, "snow")
    return ((frozen > THRESHOLD) & (z[:, None, None] > 8000.0)).any(axis=0)


def _roughness(mask):
    """Boundary edges of a 2-D mask over those of a digitised disk of the same area (1 for a disk)."""
    def edges(m):
        m = np.pad(m.astype(np.int8), 1)
        return int(np.abs(np.diff(m, axis=0)).sum() + np.abs(np.diff(m, axis=1)).sum())
    area = int(mask.sum())
    r = np.sqrt(area / np.pi)
    n = int(2 * r + 6)
    yy, xx = np.mgrid[:n, :n] - n / 2 + 0.5
    return edges(mask) / edges(xx ** 2 + yy ** 2 <= r * r)


def _arrays_equal(a, b):
    return all(np.array_equal(a[v].values, b[v].values) for v in a.data_vars) and \
        all(np.array_equal(a[c].values, b[c].values) for c in a.coords)


# ----------------------------------------------------------------------------- determinism and contract
@pytest.mark.parametrize("which,build,small", [("sc", synthetic.supercell, (24, 48, 48)),
                                                ("cu", synthetic.cumulus, (48, 64, 64))])
def test_deterministic_per_seed(which, build, small, request):
    assert _arrays_equal(build(), request.getfixturevalue(which)), "same seed, same arrays bit for bit"
    a, b, c = build(shape=small, seed=3), build(shape=small, seed=3), build(shape=small, seed=4)
    assert _arrays_equal(a, b)
    assert not np.array_equal(a.q_cloud.values, c.q_cloud.values), "another seed must give another storm"


@pytest.mark.parametrize("which", ["sc", "cu"])
def test_contract(which, request):
    ds = request.getfixturevalue(which)
    validate(ds)
    assert tuple(ds[f"q_{SPECIES_NAMES[0]}"].dims) == ("z", "y", "x")
    for name in SPECIES_NAMES:
        a = ds[f"q_{name}"].values
        assert a.dtype == np.float32 and a.shape == tuple(ds.sizes[d] for d in ("z", "y", "x"))
        assert np.all(np.isfinite(a)) and a.min() >= 0.0
    assert ds.attrs["source"] == ("synthetic.supercell" if which == "sc" else "synthetic.cumulus")
    assert ds.attrs["model"] == "synthetic" and len(ds.attrs["description"]) > 20
    assert ds.attrs["n_negative_clipped"] == 0
    # cell centres: the domain starts at x = y = z = 0, uniform spacing
    for d in ("z", "y", "x"):
        c = ds[d].values
        step = c[1] - c[0]
        np.testing.assert_allclose(np.diff(c), step)
        assert c[0] == pytest.approx(step / 2)


def test_default_grids(sc, cu):
    # supercell: ~1 km horizontal, 0.5 km vertical, ~100 km x 100 km x 20 km
    assert (sc.sizes["z"], sc.sizes["y"], sc.sizes["x"]) == (40, 96, 96)
    assert float(sc.x[1] - sc.x[0]) == 1000.0 and float(sc.z[1] - sc.z[0]) == 500.0
    # cumulus: 50 m, at most ~2M cells
    assert float(cu.x[1] - cu.x[0]) == 50.0 and float(cu.z[1] - cu.z[0]) == 50.0
    assert cu.sizes["z"] * cu.sizes["y"] * cu.sizes["x"] <= 2_000_000
    # custom grids are honoured
    small = synthetic.supercell(shape=(20, 50, 60), spacing_m=(1000.0, 2000.0, 2000.0))
    assert (small.sizes["z"], small.sizes["y"], small.sizes["x"]) == (20, 50, 60)
    assert float(small.y[0]) == 1000.0


@pytest.mark.parametrize("which", ["sc", "cu"])
def test_rho_air_is_the_1976_standard_atmosphere(which, request):
    ds = request.getfixturevalue(which)
    rho = ds.rho_air.values.astype(np.float64)
    assert np.all(rho == rho[:, :1, :1]), "rho_air is a z-profile"
    z, prof = ds.z.values, rho[:, 0, 0]
    assert np.all(np.diff(prof) < 0)
    for height, published in USSA_1976.items():
        if height > z[-1]:
            continue
        # log-linear interpolation (extrapolation to 0 m from the two lowest cell centres)
        k = int(np.clip(np.searchsorted(z, height) - 1, 0, len(z) - 2))
        w = (height - z[k]) / (z[k + 1] - z[k])
        got = np.exp((1 - w) * np.log(prof[k]) + w * np.log(prof[k + 1]))
        assert got == pytest.approx(published, rel=0.01), f"rho_air at {height} m"


def test_bad_arguments():
    with pytest.raises(WeatherDataError, match="shape"):
        synthetic.supercell(shape=(10, 20))
    with pytest.raises(WeatherDataError, match="spacing"):
        synthetic.cumulus(spacing_m=(50.0, -50.0, 50.0))
    with pytest.raises(WeatherDataError, match="shear_azimuth_deg"):
        synthetic.supercell(shear_azimuth_deg="north")


# ----------------------------------------------------------------------------- supercell anatomy
def test_supercell_anvil_high_and_downshear(sc):
    z = sc.z.values
    frozen_mass = (_q(sc, "ice") + _q(sc, "snow")) * sc.rho_air.values
    assert frozen_mass[z > 8000.0].sum() > 0.8 * frozen_mass.sum(), "anvil mass mostly above 8 km"
    cols = _anvil_columns(sc)
    area_km2 = cols.sum() * float(sc.x[1] - sc.x[0]) * float(sc.y[1] - sc.y[0]) / 1e6
    assert 1500.0 < area_km2 < 5000.0
    s, n = _shear_frame(sc, sc.attrs["shear_azimuth_deg"], _updraft_xy(sc))
    down, up = s[cols].max(), -s[cols].min()
    assert 35e3 < down < 75e3, f"anvil reaches {down / 1e3:.1f} km downshear"
    assert up < 12e3 and down > 3 * up, f"anvil {down / 1e3:.1f} km downshear, {up / 1e3:.1f} km upshear"
    # the anvil's footprint centre is well downshear, and so (less so: snow falls out near the
    # updraft) is its ice+snow mass
    assert s[cols].mean() > 15e3
    col_mass = frozen_mass[z > 8000.0].sum(axis=0)
    assert (s * col_mass).sum() / col_mass.sum() > 5e3
    # an irregular outline, not an ellipse (an ellipse of aspect 2 scores 1.09)
    assert _roughness(cols) > 1.3
    # the whole storm stays inside the domain
    assert not (cols[0].any() or cols[-1].any() or cols[:, 0].any() or cols[:, -1].any())


@pytest.mark.parametrize("azimuth", [200.0, 315.0])
def test_supercell_shear_azimuth_turns_the_anvil(azimuth):
    ds = synthetic.supercell(shear_azimuth_deg=azimuth)
    cols = _anvil_columns(ds)
    s, _ = _shear_frame(ds, azimuth, _updraft_xy(ds))
    assert s[cols].max() > 3 * max(-s[cols].min(), 1.0)
    # and in compass terms: the anvil centroid lies in the shear direction from the updraft
    xu, yu = _updraft_xy(ds)
    jj, ii = np.nonzero(cols)
    dx, dy = ds.x.values[ii].mean() - xu, ds.y.values[jj].mean() - yu
    bearing = np.rad2deg(np.arctan2(dx, dy)) % 360
    assert abs((bearing - azimuth + 180) % 360 - 180) < 30


def test_supercell_updraft_graupel_rain(sc):
    z = sc.z.values
    xu, yu = _updraft_xy(sc)
    X, Y = sc.x.values[None, :], sc.y.values[:, None]
    # graupel core: 2-9 km, maximum within 8 km of the updraft, 3-12 g/kg
    qg = _q(sc, "graupel")
    k, j, i = np.unravel_index(int(np.argmax(qg)), qg.shape)
    assert 2000.0 <= z[k] <= 9000.0
    assert np.hypot(X[0, i] - xu, Y[j, 0] - yu) < 8e3
    assert 3e-3 <= qg.max() <= 12e-3
    assert _lowest(qg, z) >= 1500.0, "graupel melts before reaching the ground"
    # rain: maximum near the updraft, reaching the lowest level, 5-15 g/kg
    qr = _q(sc, "rain")
    k, j, i = np.unravel_index(int(np.argmax(qr)), qr.shape)
    assert z[k] < 7000.0 and np.hypot(X[0, i] - xu, Y[j, 0] - yu) < 12e3
    assert 5e-3 <= qr.max() <= 15e-3
    assert qr[0].max() > 2e-3, "a rain shaft reaches the ground"
    j0, i0 = np.unravel_index(int(np.argmax(qr[0])), qr[0].shape)
    assert np.hypot(X[0, i0] - xu, Y[j0, 0] - yu) < 15e3
    # cloud water: flat base at ~1-1.5 km, maxima 2-4 g/kg, nothing below cloud base
    qc = _q(sc, "cloud")
    assert 900.0 <= _lowest(qc, z) <= 1600.0
    assert 2e-3 <= qc.max() <= 4e-3
    # ice and snow magnitudes
    assert 0.1e-3 <= _q(sc, "ice").max() <= 0.5e-3
    assert 1e-3 <= _q(sc, "snow").max() <= 4e-3


def test_supercell_cloud_water_top_and_overshooting_top(sc):
    z = sc.z.values
    total, qc = _total(sc), _q(sc, "cloud")
    storm_top, cloud_top = _highest(total, z), _highest(qc, z)
    assert 14.5e3 <= storm_top <= 17e3, "overshooting top at ~15-16 km"
    assert cloud_top < storm_top - 2500.0
    assert 9e3 <= cloud_top <= 12.5e3, "liquid only where T > -40 C"
    # the overshooting top stands above the updraft
    xu, yu = _updraft_xy(sc)
    k = int(np.nonzero(z == storm_top)[0][0])
    jj, ii = np.nonzero(total[k] > THRESHOLD)
    assert np.hypot(sc.x.values[ii] - xu, sc.y.values[jj] - yu).min() < 8e3
    # above 10.5 km, supercooled cloud water survives only in the updraft core
    high = z > 10.5e3
    kk, jj, ii = np.nonzero(qc[high] > THRESHOLD)
    if kk.size:
        assert np.hypot(sc.x.values[ii] - xu, sc.y.values[jj] - yu).max() < 9e3
    # the anvil sits above ~8 km near the storm: ice+snow extent there is much larger than at 5 km
    frozen = _q(sc, "ice") + _q(sc, "snow")
    area = lambda height: int((frozen[int(np.argmin(np.abs(z - height)))] > THRESHOLD).sum())
    assert area(11.5e3) > 5 * max(area(5e3), 1)


# ----------------------------------------------------------------------------- cumulus anatomy
def test_cumulus_shape_and_water(cu):
    z = cu.z.values
    qc = _q(cu, "cloud")
    base, top = _lowest(qc, z), _highest(qc, z)
    assert 800.0 <= base <= 1300.0
    assert 2000.0 <= top - base <= 4500.0, f"depth {top - base:.0f} m"
    cols = (qc > THRESHOLD).any(axis=0)
    d = float(cu.x[1] - cu.x[0])
    jj, ii = np.nonzero(cols)
    width_x, width_y = (np.ptp(ii) + 1) * d, (np.ptp(jj) + 1) * d
    assert 2000.0 <= width_x <= 5500.0 and 2000.0 <= width_y <= 5500.0
    assert not (cols[0].any() or cols[-1].any() or cols[:, 0].any() or cols[:, -1].any())
    assert 0.8e-3 <= qc.max() <= 2.5e-3
    # adiabatic-like: liquid water grows with height above the base
    prof = qc.max(axis=(1, 2))
    k_base = int(np.argmin(np.abs(z - (base + 200.0))))
    k_mid = int(np.argmin(np.abs(z - (base + 1500.0))))
    assert prof[k_mid] > 2 * prof[k_base]
    # a flat base: 100 m above the base the cloud already covers at least half its widest area
    area = (qc > THRESHOLD).sum(axis=(1, 2))
    assert area[int(np.argmin(np.abs(z - (base + 100.0))))] > 0.5 * area.max()
    assert qc[z < base - 60.0].max() == 0.0
    # cauliflower turrets: an irregular outline at mid-cloud
    k = int(np.argmin(np.abs(z - (base + top) / 2)))
    assert _roughness(qc[k] > THRESHOLD) > 1.3
    # warm cloud with light rain to the ground
    for name in ("ice", "snow", "graupel"):
        assert _q(cu, name).max() == 0.0
    qr = _q(cu, "rain")
    assert 0.0 < qr.max() < 1e-3 and qr[0].max() > 0.0
    assert synthetic.cumulus(shape=(48, 64, 64), rain=False).q_rain.values.max() == 0.0


# ----------------------------------------------------------------------------- against the real WRF storm
def test_supercell_magnitudes_against_real_wrf(sc, real):
    for name in SPECIES_NAMES:
        ratio = float(_q(sc, name).max()) / real["max"][name]
        assert 1 / 3 <= ratio <= 3, f"{name}: synthetic max / WRF max = {ratio:.2f}"
    z = sc.z.values
    storm_top = _highest(_total(sc), z)
    assert storm_top == pytest.approx(real["top"], rel=0.25), \
        f"storm top {storm_top / 1e3:.2f} km vs WRF {real['top'] / 1e3:.2f} km"
    cloud_top = _highest(_q(sc, "cloud"), z)
    assert cloud_top == pytest.approx(real["cloud_top"], rel=0.15)
    # anvil footprint (columns with condensate above 9 km) within a factor 2.5 of the real storm's
    # (whose ~4000 km^2 include the left mover's anvil)
    cell_km2 = float(sc.x[1] - sc.x[0]) * float(sc.y[1] - sc.y[0]) / 1e6
    area = _area_above(_total(sc), z, 9000.0, cell_km2)
    assert real["anvil_km2"] / 2.5 <= area <= real["anvil_km2"] * 2.5, \
        f"anvil {area:.0f} km^2 vs WRF {real['anvil_km2']:.0f} km^2"


def test_stratocumulus_is_a_dense_deck():
    """The demo deck: cloud water only between the 400 m base and the undulating top (850 +- 70 m, so
    within 600-1000 m), at most the adiabatic 0.85 x 2 g/kg/km x (z - base) x 1.3, covering the domain with
    vertical optical depths of a dense stratocumulus (median 20-40 at r = 10 um)."""
    import numpy as np
    import weather_mi as wm
    hyd = wm.synthetic.stratocumulus()
    q = hyd["q_cloud"].values
    z = hyd.z.values[:, None, None]
    assert np.all(q[np.broadcast_to(z < 400.0, q.shape)] == 0) and np.all(q[np.broadcast_to(z > 1000.0, q.shape)] == 0)
    assert np.all(q <= 0.85 * 2.0e-6 * np.maximum(z - 400.0, 0.0) * 1.3 * (1 + 1e-6))  # float32
    assert all(float(hyd[f"q_{s}"].max()) == 0.0 for s in ("ice", "rain", "snow", "graupel"))
    tau = wm.optical_volume(hyd, species="physical", phase_quality="test").optical_depth_z()
    assert np.all(tau > 1.0) and 20.0 < float(np.median(tau)) < 40.0
