"""Particle sizes from the microphysics scheme (io/microphysics.py, io/particle_sizes.py): every rule against the
published formula evaluated here independently (WRF's Fortran transcribed in the test, or the size distribution
integrated numerically), at points spanning each clipping range; the reader on synthetic and real wrfout files."""
from __future__ import annotations

from math import gamma, pi
from pathlib import Path

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.errors import WeatherDataError
from weather_mi.io import microphysics as mp
from conftest import write_wrfout

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "wrf"
SUPERCELL = DATA / "wrfout_quarter_ss_0130.nc"   # WSM6
PLATEAU = DATA / "wrf_d01_allvars_cropped.nc"    # Thompson with QNICE, QNRAIN

# mass contents (kg/m^3) from 1e-9 (tiny) to 1e-2 (a heavy core): both ends of every clipping range
RHO_Q = np.array([1e-12, 1e-9, 1e-7, 1e-5, 1e-4, 1e-3, 3e-3, 1e-2])


def reff_numeric(rho_q, n_t, rho_p, mu):
    """<r^3>/<r^2> of N(D) = N0 D^mu exp(-lambda D) holding mass rho_q (kg/m^3) in n_t particles (m^-3), by
    quadrature in D (lambda from the ratio of the integrated moments, not from the closed form)."""
    d = np.logspace(-8, -1, 200001)
    def moments(lam):
        shape = d ** mu * np.exp(-lam * d)
        return [np.trapezoid(shape * d ** k, d) for k in (0, 2, 3)]
    lo, hi = 1e1, 1e8  # mass per particle rho_q / n_t decreases with lambda: bisect in log
    for _ in range(80):
        lam = np.sqrt(lo * hi)
        m0, _, m3 = moments(lam)
        if pi / 6 * rho_p * m3 / m0 > rho_q / n_t:
            lo = lam
        else:
            hi = lam
    m0, m2, m3 = moments(lam)
    return 0.5 * m3 / m2, lam


@pytest.mark.parametrize("rho_q, n_t, mu", [(1e-3, 1e3, 0.0), (2e-4, 5e3, 0.0), (1e-3, 1e3, 1.0), (5e-4, 2e4, 2.0)])
def test_gamma_from_number_matches_the_integrated_distribution(rho_q, n_t, mu):
    expected, lam = reff_numeric(rho_q, n_t, 1000.0, mu)
    got = float(mp.gamma_from_number(np.array([rho_q]), np.array([n_t]), 1000.0, mu=mu)[0])
    assert got == pytest.approx(expected, rel=2e-3)
    assert expected == pytest.approx((mu + 3) / (2 * lam), rel=2e-3)


def test_wsm6_rain_exponential_fixed_intercept_and_lamdarmax():
    for rq in RHO_Q:
        lam = min((pi * 1000.0 * 8e6 / rq) ** 0.25, 8e4)   # Hong et al. 2004; lamdarmax
        assert float(mp.wsm_rain(np.array([rq]))[0]) == pytest.approx(1.5 / lam, rel=1e-5)
    assert float(mp.wsm_rain(np.array([1e-11]))[0]) == pytest.approx(1.5 / 8e4, rel=1e-5)  # clipped: 18.75 um
    assert float(mp.wsm_rain(np.array([0.0]))[0]) == 0.0


def test_wsm6_rain_against_quadrature():
    # the exponential with N0 = 8e6: n_t = N0 / lambda; check r_eff by quadrature at 1 g/m^3
    rq = 1e-3
    lam = (pi * 1000.0 * 8e6 / rq) ** 0.25
    expected, _ = reff_numeric(rq, 8e6 / lam, 1000.0, 0.0)
    assert float(mp.wsm_rain(np.array([rq]))[0]) == pytest.approx(expected, rel=2e-3)


@pytest.mark.parametrize("t_c", [10.0, 0.0, -5.0, -20.0, -40.0, -100.0])
def test_wsm6_snow_temperature_dependent_intercept(t_c):
    factor = min(max(np.exp(0.12 * (0.0 - t_c)), 1.0), 1e11 / 2e6)   # Hong et al. 2004, n0smax = 1e11
    for rq in RHO_Q:
        lam = min((pi * 100.0 * 2e6 * factor / rq) ** 0.25, 1e5)
        expected = min(max(1.5 / lam, 25e-6), 999e-6)
        got = float(mp.wsm_snow(np.array([rq]), t_k=np.array([273.15 + t_c]))[0])
        assert got == pytest.approx(expected, rel=1e-5)
    assert float(mp.wsm_snow(np.array([1e-12]), t_k=np.array([253.15]))[0]) == pytest.approx(25e-6)
    assert float(mp.wsm_snow(np.array([1e-2]), t_k=np.array([280.0]))[0]) == pytest.approx(999e-6)


def test_wsm6_cloud_and_ice_as_effectrad_wsm6():
    for rq in RHO_Q:
        lamdac = (pi * 1000.0 / 6.0 * 3e8 / rq) ** (1 / 3)                  # effectRad_wsm6, pidnc = pi denr / 6
        assert float(mp.wsm_cloud(np.array([rq]))[0]) == pytest.approx(min(max(1.5 / lamdac, 2.51e-6), 50e-6), rel=1e-5)
        ni = min(max(5.38e7 * np.sqrt(np.sqrt(rq ** 3)), 1e3), 1e6)
        diai = 11.9 * np.sqrt(rq / ni)
        assert float(mp.wsm_ice(np.array([rq]))[0]) == pytest.approx(min(max(0.75 * 0.163 * diai, 10.01e-6), 125e-6),
                                                                   rel=1e-5)
    assert float(mp.wsm_cloud(np.array([1e-9]))[0]) == pytest.approx(2.51e-6)
    assert float(mp.wsm_cloud(np.array([1e-1]))[0]) == pytest.approx(50e-6)
    assert float(mp.wsm_ice(np.array([1e-9]))[0]) == pytest.approx(10.01e-6)


def test_wsm6_graupel_and_wdm_rain():
    for rq in RHO_Q:
        lam = min((pi * 500.0 * 4e6 / rq) ** 0.25, 6e4)
        assert float(mp.wsm_graupel(np.array([rq]))[0]) == pytest.approx(1.5 / lam, rel=1e-5)
    # WDM6 rain: pidnr = 4 pi rho_w, i.e. gamma mu = 1; r_eff = 2 / lambda, lamdarmin 2e3 .. lamdarmax 5e4
    for rq, n in ((1e-3, 1e3), (1e-3, 1e6), (1e-9, 1e6), (1e-2, 1.0)):
        lam = min(max((4 * pi * 1000.0 * n / rq) ** (1 / 3), 2e3), 5e4)
        assert float(mp.wdm_rain(np.array([rq]), np.array([n]))[0]) == pytest.approx(2.0 / lam, rel=1e-5)
    # WDM6 cloud: effectRad_wdm6, lamc = 2 Gamma(5/3) (pidnc nc / rqc)^(1/3)
    for rq, n in ((1e-4, 1e8), (1e-3, 3e8), (1e-9, 1e9), (1e-2, 1e6)):
        lamc = 2 * gamma(5 / 3) * (pi * 1000.0 / 6 * n / rq) ** (1 / 3)
        assert float(mp.wdm_cloud(np.array([rq]), np.array([n]))[0]) == pytest.approx(
            min(max(1 / lamc, 2.51e-6), 50e-6), rel=1e-5)


def test_thompson_cloud_ice_rain():
    for rq in RHO_Q:
        for n in (None, 30e6, 300e6, 1500e6):
            nc = 100e6 if n is None else n
            mu = min(15, round(1000e6 / nc) + 2)                              # calc_effectRad inu_c
            g_ratio = [24, 60, 120, 210, 336, 504, 720, 990, 1320, 1716, 2184, 2730, 3360, 4080, 4896][mu - 1]
            lamc = (nc * pi * 1000.0 / 6 * g_ratio / rq) ** (1 / 3)
            got = float(mp.thompson_cloud(np.array([rq]), None if n is None else np.array([n]))[0])
            assert got == pytest.approx(min(max(0.5 * (3 + mu) / lamc, 2.51e-6), 50e-6), rel=1e-5)
        for ni in (1e3, 1e5, 1e7):
            lami = (pi * 890.0 / 6 * 6.0 * ni / rq) ** (1 / 3)                # am_i cig(2) oig1
            got = float(mp.thompson_ice(np.array([rq]), np.array([ni]))[0])
            assert got == pytest.approx(min(max(1.5 / lami, 2.51e-6), 125e-6), rel=1e-5)
        for nr in (1e2, 1e4, 1e6):
            lamr = min(max((pi * 1000.0 * nr / rq) ** (1 / 3), 3.672 / 2.5e-3), 3.672 / 37.5e-6)
            got = float(mp.thompson_rain(np.array([rq]), np.array([nr]))[0])
            assert got == pytest.approx(1.5 / lamr, rel=1e-5)
    # the rain clipping: mvd 2.5 mm at most (r_eff 1.02 mm), 0.75 D0r at least (r_eff 15.3 um)
    assert float(mp.thompson_rain(np.array([1e-2]), np.array([1e-2]))[0]) == pytest.approx(1.5 * 2.5e-3 / 3.672)
    assert float(mp.thompson_rain(np.array([1e-9]), np.array([1e6]))[0]) == pytest.approx(1.5 * 37.5e-6 / 3.672)


def test_thompson_snow_field_moments():
    sa = [5.065339, -0.062659, -3.032362, 0.029469, -0.000285, 0.31255, 0.000204, 0.003199, 0.0, -0.015952]
    sb = [0.476221, -0.015896, 0.165977, 0.007468, -0.000141, 0.060366, 0.000079, 0.000594, 0.0, -0.003577]
    for t_c in (5.0, -5.0, -30.0):
        for rq in RHO_Q:
            tc0, n = min(-0.1, t_c), 3.0
            terms = [1, tc0, n, tc0 * n, tc0 * tc0, n * n, tc0 * tc0 * n, tc0 * n * n, tc0 ** 3, n ** 3]
            a = 10 ** sum(c * t for c, t in zip(sa, terms))
            b = sum(c * t for c, t in zip(sb, terms))
            smob = rq / 0.069
            expected = min(max(0.5 * a * smob ** b / smob, 5.01e-6), 999e-6)
            got = float(mp.thompson_snow(np.array([rq]), t_k=np.array([273.15 + t_c]))[0])
            assert got == pytest.approx(expected, rel=1e-4)


def test_morrison():
    for rq in RHO_Q:
        pgam = min(max(1 / (0.0005714 * 250 + 0.2714) ** 2 - 1, 2), 10)    # Martin et al. 1994 at 250 cm^-3
        lamc = (pi / 6 * 997 * 250e6 * gamma(pgam + 4) / (rq * gamma(pgam + 1))) ** (1 / 3)
        lamc = min(max(lamc, (pgam + 1) / 60e-6), (pgam + 1) / 1e-6)
        assert float(mp.morrison_cloud(np.array([rq]))[0]) == pytest.approx(
            gamma(pgam + 4) / gamma(pgam + 3) / lamc / 2, rel=1e-5)
        for name, rho_p, lmin, lmax in (("ice", 500, 1 / 350e-6, 1e6), ("snow", 100, 1 / 2000e-6, 1 / 10e-6),
                                        ("rain", 997, 1 / 2800e-6, 1 / 20e-6), ("graupel", 400, 1 / 2000e-6, 1 / 20e-6)):
            for n in (1e2, 1e5):
                lam = min(max((pi * rho_p * n / rq) ** (1 / 3), lmin), lmax)
                assert float(mp.MORRISON[name](np.array([rq]), np.array([n]))[0]) == pytest.approx(1.5 / lam, rel=1e-5)


def test_rules_by_scheme():
    assert set(mp.rules(6, [])) == {"cloud", "ice", "rain", "snow", "graupel"}
    assert mp.rules(16, ["QNCLOUD", "QNRAIN"])["rain"].number_var == "QNRAIN"
    assert mp.rules(8, ["QNICE", "QNRAIN"])["ice"].number_var == "QNICE"
    assert "ice" not in mp.rules(8, [])            # Thompson ice needs QNICE
    assert set(mp.rules(10, ["QNICE", "QNSNOW", "QNRAIN", "QNGRAUPEL"])) == {"cloud", "ice", "snow", "rain", "graupel"}
    assert set(mp.rules(17, ["QNICE"])) == {"ice"}  # NSSL: each category from its own number concentration
    assert mp.rules(19, ["QNICE"]) == {} and not mp.has_rules(19)  # NSSL 1-moment: no rules (warning, preset)


# ---- the reader ----

def _rain_file(tmp_path, **kw):
    q = np.zeros((1, 6, 4, 5))
    q[0, 1:5] = np.linspace(1e-4, 3e-3, 4)[:, None, None]   # a profile of rain across levels
    return write_wrfout(tmp_path / "w.nc", override={"QRAIN": q, **kw.pop("override", {})}, **kw), q


def test_regridded_radius_conserves_eq4_extinction(tmp_path):
    """The column optical depth of rain with the scheme's radii on the regridded grid equals the native column's
    sum of 3 rho q / (2 rho_w r_eff) dz, r_eff from the WSM6 formula evaluated here."""
    import xarray as xr
    path, q = _rain_file(tmp_path)
    hyd = wm.open_wrf(path, dz=330.0)
    vol = wm.optical_volume(hyd, sizes="scheme", phase_tables=[None] * 5)
    tau = vol.optical_depth_z()
    ds = xr.open_dataset(path)
    p = (ds.P + ds.PB).values[0]
    rho = wm.io.wrf.dry_air_density(p, ds["T"].values[0] + 300.0, ds["QVAPOR"].values[0])
    z_w = ((ds.PH + ds.PHB) / 9.81).values[0]
    rq = rho * q[0]
    lam = np.minimum((pi * 1000 * 8e6 / np.where(rq > 0, rq, 1)) ** 0.25, 8e4)
    beta = np.where(rq > 0, 3 * rq / (2 * 1000 * 1.5 / lam), 0)
    expected = (beta * np.diff(z_w, axis=0)).sum(axis=0)
    np.testing.assert_allclose(tau, expected, rtol=2e-3)
    assert hyd.attrs["r_eff_source_rain"].startswith("WSM6")


def test_re_cloud_read_through_in_its_units(tmp_path):
    q = np.full((1, 6, 4, 5), 1e-3)
    re = np.full((1, 6, 4, 5), 12.0)
    path = write_wrfout(tmp_path / "w.nc", override={"QCLOUD": q, "RE_CLOUD": re})
    import netCDF4
    with netCDF4.Dataset(path, "a") as nc:
        nc["RE_CLOUD"].units = "um"
    hyd = wm.open_wrf(path)
    np.testing.assert_allclose(hyd.r_eff_cloud.values[1:-1], 12e-6, rtol=1e-5)
    assert hyd.attrs["r_eff_source_cloud"] == "file RE_CLOUD"


def test_re_in_the_wrong_units_is_named(tmp_path):
    q = np.full((1, 6, 4, 5), 1e-3)
    path = write_wrfout(tmp_path / "w.nc", override={"QCLOUD": q, "RE_CLOUD": np.full((1, 6, 4, 5), 12.0)})
    import netCDF4
    with netCDF4.Dataset(path, "a") as nc:
        nc["RE_CLOUD"].units = "m"
    with pytest.raises(WeatherDataError, match="RE_CLOUD.*wrong units"):
        wm.open_wrf(path)


def test_negative_or_nan_number_concentration_is_named(tmp_path):
    q = np.full((1, 6, 4, 5), 1e-3)
    n = np.full((1, 6, 4, 5), 1e4)
    n[0, 2, 1, 1] = -5.0
    path = write_wrfout(tmp_path / "w.nc", mp_physics=8, override={"QRAIN": q, "QNRAIN": n, "QNICE": np.full_like(n, 1e4)})
    with pytest.raises(WeatherDataError, match="QNRAIN.*>= 0"):
        wm.open_wrf(path)
    n[0, 2, 1, 1] = np.nan
    path = write_wrfout(tmp_path / "v.nc", mp_physics=8, override={"QRAIN": q, "QNRAIN": n, "QNICE": np.full_like(n, 1e4)})
    with pytest.raises(WeatherDataError, match="QNRAIN.*finite"):
        wm.open_wrf(path)


def test_unknown_scheme_warns_with_the_fallback(tmp_path):
    path = write_wrfout(tmp_path / "w.nc", mp_physics=19)
    with pytest.warns(UserWarning, match="no size rules for NSSL 1-moment.*species table"):
        hyd = wm.open_wrf(path)
    assert not any(str(v).startswith("r_eff_") for v in hyd.data_vars)


def test_sizes_false_reads_no_radii_and_paper_default_unchanged(tmp_path):
    path, _ = _rain_file(tmp_path)
    with_sizes, without = wm.open_wrf(path), wm.open_wrf(path, sizes=False)
    assert "r_eff_rain" in with_sizes and "r_eff_rain" not in without
    for name in ("q_rain", "rho_air"):
        assert np.array_equal(with_sizes[name].values, without[name].values)
    tables = [None] * 5
    a = wm.optical_volume(with_sizes, phase_tables=tables)          # the library default: the paper's radii
    b = wm.optical_volume(without, phase_tables=tables)
    assert np.array_equal(a.beta_total, b.beta_total)
    paper = wm.optical_volume(with_sizes, "physical", sizes="paper", phase_tables=tables)
    assert np.array_equal(paper.beta_total, b.beta_total)
    scheme = wm.optical_volume(with_sizes, sizes="scheme", phase_tables=tables)
    assert not np.array_equal(scheme.beta_total, b.beta_total)
    with pytest.raises(WeatherDataError, match="sizes"):
        wm.optical_volume(with_sizes, sizes="big")


@pytest.mark.skipif(not SUPERCELL.is_file(), reason="needs ../shared/data/wrf (real WRF output)")
def test_supercell_wsm6_radii_plausible():
    hyd = wm.open_wrf(SUPERCELL)
    bounds = {"cloud": (2.5e-6, 50e-6), "ice": (10e-6, 125e-6), "rain": (18e-6, 2e-3), "snow": (25e-6, 1e-3),
              "graupel": (25e-6, 3e-3)}
    for name, (lo, hi) in bounds.items():
        r = hyd[f"r_eff_{name}"].values[hyd[f"q_{name}"].values > 0]
        assert r.size and r.min() >= lo * 0.99 and r.max() <= hi * 1.01, name
    core = hyd.r_eff_rain.values[hyd.q_rain.values > 5e-3]        # heavy rain: millimetre drops
    assert 0.3e-3 < np.median(core) < 1.3e-3


@pytest.mark.skipif(not PLATEAU.is_file(), reason="needs ../shared/data/wrf (real WRF output)")
def test_plateau_thompson_radii_from_qnice_qnrain():
    hyd = wm.open_wrf(PLATEAU, time=1)
    assert "QNRAIN" in hyd.attrs["r_eff_source_rain"] and hyd.attrs["r_eff_source_ice"].startswith("Thompson")
    for name, lo, hi in (("cloud", 2.5e-6, 50e-6), ("ice", 2.5e-6, 125e-6), ("rain", 15e-6, 1.03e-3),
                         ("snow", 5e-6, 1e-3)):
        r = hyd[f"r_eff_{name}"].values[hyd[f"q_{name}"].values > 0]
        assert r.size and r.min() >= lo * 0.99 and r.max() <= hi * 1.01, name


@pytest.mark.skipif(not SUPERCELL.is_file(), reason="needs ../shared/data/wrf (real WRF output)")
def test_info_prints_effective_radius_ranges(capsys):
    from weather_mi.cli.commands import main
    assert main(["info", str(SUPERCELL)]) == 0
    out = capsys.readouterr().out
    assert "particle sizes: scheme" in out and "WSM6: exponential, N0r = 8e6" in out
    assert main(["info", str(SUPERCELL), "--sizes", "physical"]) == 0
    out = capsys.readouterr().out
    assert "physical preset" in out and "r_eff (um)" in out


def test_voxel_albedo_from_the_scheme_radius(tmp_path):
    """With sizes="scheme" a rain-only voxel's albedo is 1 - Q_abs/2 of its own radius (van de Hulst's weak
    absorption, Q_abs = 8/3 x k (n^3 - (n^2 - 1)^1.5), x = 2 pi r / lambda; water n, k at 650/550/450 nm)."""
    path, _ = _rain_file(tmp_path)
    hyd = wm.open_wrf(path)
    tables = [None] * 5
    vol = wm.optical_volume(hyd, "physical", sizes="scheme", phase_tables=tables)
    fixed = wm.optical_volume(hyd, "physical", phase_tables=tables)
    n, k = (1.331, 1.333, 1.337), (1.6e-8, 2.0e-9, 1.0e-9)
    rain = hyd.q_rain.values > 0
    r = hyd.r_eff_rain.values[rain].astype(np.float64)
    for c, lam in enumerate((650e-9, 550e-9, 450e-9)):
        q_abs = np.minimum(8 / 3 * (2 * pi * r / lam) * k[c] * (n[c] ** 3 - (n[c] ** 2 - 1) ** 1.5), 1)
        np.testing.assert_allclose(1 - vol.albedo[..., c][rain], q_abs / 2, rtol=2e-2, atol=3e-8)
    assert np.ptp(vol.albedo[..., 0][rain]) > 0 and np.ptp(fixed.albedo[..., 0][rain]) < 1e-7


# ---- size classes: Eq. 8 components by radius ----

def test_size_classes_split_conserves_the_species():
    from weather_mi.optics.size_classes import class_radii_m, split
    rng = np.random.default_rng(3)
    shape = (4, 5, 6)
    q = {n: np.zeros(shape) for n in wm.SPECIES_NAMES}
    q["rain"] = rng.uniform(0, 2e-3, shape)
    r_rain = np.exp(rng.uniform(np.log(20e-6), np.log(2e-3), shape)).astype(np.float32)
    hyd = wm.from_arrays(q, rho_air=1.0, spacing=(100.0, 100.0, 100.0), r_eff={"rain": r_rain})
    sp = wm.species.preset("physical")
    beta = np.zeros((5,) + shape, np.float32)
    beta[2] = sp["rain"].beta_ext_per_m(1.0, q["rain"], r_rain).astype(np.float32)
    weights = (beta > 0).astype(np.float32)
    names, b, w, comps = split(hyd, sp, beta, weights, 3)
    assert names[:2] == ("cloud", "ice") and [n for n in names if n.startswith("rain")] == ["rain#1", "rain#2", "rain#3"]
    k = [i for i, n in enumerate(names) if n.startswith("rain")]
    np.testing.assert_array_equal(b[k].sum(0), beta[2])            # each voxel in exactly one class
    np.testing.assert_array_equal(w[k].sum(0), weights[2])
    # rain's classes stated independently: 15 um (Thompson's smallest rain r_eff, 1.5 x 0.75 D0r / 3.672) to
    # 2.5 mm in 3 equal log steps of (2500 / 15)^(1/3) = 5.5032: edges 15, 82.55, 454.3, 2500 um; the tables'
    # radii their geometric centres to 3 digits, 35.2, 194 and 1070 um
    edges = np.array([15e-6, 82.55e-6, 454.3e-6, 2.5e-3])
    centres = np.array([35.2e-6, 194e-6, 1070e-6])
    got_edges, got_centres = class_radii_m("rain", 3)
    np.testing.assert_allclose(got_edges, edges, rtol=2e-4)
    np.testing.assert_allclose(got_centres, centres, rtol=1e-12)
    for j, c in zip(k, range(3)):
        inside = b[j] > 0
        assert inside.any()
        assert np.all(r_rain[inside] >= edges[c] * (1 - 2e-4)) and np.all(r_rain[inside] <= edges[c + 1] * (1 + 2e-4))
        assert comps[j].radius_m == pytest.approx(centres[c], rel=1e-12)
    assert sp[names[k[1]]].name == "rain"                           # a component's species by its name


def test_size_classes_volume_and_sized_tables(tmp_path):
    path, _ = _rain_file(tmp_path)
    hyd = wm.open_wrf(path)
    one = wm.optical_volume(hyd, "physical", sizes="scheme", phase="paper", phase_quality="test")
    three = wm.optical_volume(hyd, "physical", sizes="scheme", phase="paper", phase_quality="test", size_classes=3)
    assert len(three.species) == len(three.phase_tables) > 5 and three.attrs["size_classes"] == 3
    np.testing.assert_array_equal(three.beta_total, one.beta_total)
    np.testing.assert_array_equal(three.albedo, one.albedo)
    with pytest.raises(WeatherDataError, match="size_classes"):
        wm.optical_volume(hyd, sizes="scheme", size_classes=0, phase_tables=[None] * 5)
    # a size class's cloud table is Mie at its radius: its asymmetry at 550 nm against miepython's single-size
    # efficiencies integrated here over the Hansen gamma distribution n(r) ~ r^((1-3v)/v) exp(-r/(r_eff v))
    import miepython
    from weather_mi.optics.phase.species_tables import table_for
    from weather_mi.optics.species import Species
    r = np.linspace(0.2e-6, 20e-6, 3000)
    n_r = r ** ((1 - 3 * 0.1) / 0.1) * np.exp(-r / (4e-6 * 0.1))
    _, qsca, _, g = miepython.efficiencies(1.333 - 2e-9j, 2 * r, 550e-9)
    expected = float(np.sum(qsca * r ** 2 * n_r * g) / np.sum(qsca * r ** 2 * n_r))
    small = table_for(Species("cloud", 4e-6, 1000.0, (1, 1, 1), "water", (1, 0, 0)), quality="test", sized=True)
    assert "r_eff=4e-06" in small.name and small.g[1] == pytest.approx(expected, abs=3e-3)
    assert small.g[1] < table_for(Species("cloud", 10e-6, 1000.0, (1, 1, 1), "water", (1, 0, 0)), quality="test",
                                  sized=True).g[1]
