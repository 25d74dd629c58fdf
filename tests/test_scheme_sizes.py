"""Particle sizes of the schemes added in issue 39 part 3 (NSSL two-moment, Milbrandt-Yau, Kessler, P3, Thompson
graupel by WRF version, hail with graupel): each rule against WRF's Fortran transcribed here (loops and
constants as the Fortran writes them, not the library's helpers) or the size distribution integrated
numerically, at points spanning every threshold and clipping bound; the reader's combination of graupel and
hail and its bad-input errors on small synthetic wrfout files."""
from __future__ import annotations

from math import gamma as G, pi

import numpy as np
import pytest
import xarray as xr

import weather_mi as wm
from weather_mi.errors import WeatherDataError
from weather_mi.io import microphysics as mp, milbrandt_sizes, nssl_sizes, thompson_graupel
from weather_mi.io.particle_sizes import SizeReader
from conftest import write_wrfout

Q = [1e-15, 1e-13, 1e-11, 1e-9, 1e-7, 1e-5, 1e-4, 1e-3, 1e-2]       # kg/kg
N = [1e-9, 1e-2, 1e1, 1e3, 1e5, 1e7, 1e9, 1e11]                     # m^-3


def reff_quadrature(n_of_d, d=None):
    """<r^3>/<r^2> of a size distribution n(D) by quadrature (m)."""
    d = np.logspace(-8, 0, 400001) if d is None else d
    w = n_of_d(d)
    return 0.5 * np.trapezoid(w * d ** 3, d) / np.trapezoid(w * d ** 2, d)


# ---- NSSL two-moment: calc_eff_radius (module_mp_nssl_2mom.F), WRF's namelist defaults ----

NSSL_XDN0 = {"cloud": 1000.0, "ice": 900.0, "rain": 1000.0, "snow": 100.0, "graupel": 500.0, "hail": 900.0}
NSSL_RE_BOUNDS = {"cloud": (2.51e-6, 50e-6), "ice": (10.01e-6, 125e-6), "snow": (25e-6, 999e-6),
                  "rain": (50e-6, 2999e-6), "graupel": (50e-6, 10e-3), "hail": (50e-6, 40e-3)}


def nssl_fortran(cat, qx, cx, rho0, hwdn=None, literal=False):
    """calc_eff_radius for one point: qx (kg/kg), cx (m^-3), rho0 (kg/m^3); clipped as nssl_2mom_driver clips
    re_*. ``literal``: the Fortran's (alpha+3)(alpha+1)(alpha+1) in factor_r/h/hl (else (alpha+3)(alpha+2)
    (alpha+1), the scheme's moments)."""
    cnu, cinu, snu, alphar, alphah, alphahl = 0.0, 0.0, -0.8, 0.0, 0.0, 1.0
    lo, hi = NSSL_RE_BOUNDS[cat]
    t = {"cloud": 2.51e-6, "ice": 10.01e-6, "snow": 25e-6, "rain": 50e-6, "graupel": 50e-6, "hail": 50e-6}[cat]
    if cat in ("cloud", "ice", "snow"):
        nu = {"cloud": cnu, "ice": cinu, "snow": snu}[cat]
        gam1 = G(2.0 + nu)
        gam2 = 1.0 if cat != "snow" else G(1.0 + snu)      # gamc2 = gami2 = 1.
        factor = (1.0 + nu) * G(1.0 + nu) / G(5.0 / 3.0 + nu)
        if qx > 1.0e-13 and cx > 1.0e-8:                    # qxmin (two-moment), cxmin
            lam = ((cx * (pi / 6.0) * NSSL_XDN0[cat] * gam1) / (qx * rho0 * gam2)) ** (1.0 / 3.0)
            t = 0.5 * factor / lam
    else:
        alpha = {"rain": alphar, "graupel": alphah, "hail": alphahl}[cat]
        middle = (alpha + 1.0) if literal else (alpha + 2.0)
        factor = ((pi * (alpha + 3.0) * middle * (alpha + 1.0)) / 6.0) ** (1.0 / 3.0)
        dn = NSSL_XDN0[cat] if hwdn is None else hwdn
        if qx > max(1.0e-8, 1.0e-12) and (cat != "rain" or cx > 1.0e-8):
            lam = factor * ((dn * cx) / (qx * rho0)) ** (1.0 / 3.0) if cx > 0 else 0.0
            t = 0.5 * (alpha + 3.0) / lam if lam > 0 else np.inf
    return max(lo, min(t, hi))


@pytest.mark.parametrize("cat", ["cloud", "ice", "snow", "rain", "graupel", "hail"])
def test_nssl_against_calc_eff_radius(cat):
    rho0 = 0.9
    hit = set()
    for qx in Q:
        for cx in N:
            expected = nssl_fortran(cat, qx, cx, rho0)
            got = float(nssl_sizes.radius(cat, np.array([qx * rho0]), np.array([cx]), np.array([rho0]))[0])
            assert got == pytest.approx(expected, rel=1e-5), (cat, qx, cx)
            lo, hi = NSSL_RE_BOUNDS[cat]
            hit.add("lo" if expected <= lo * 1.000001 else "hi" if expected >= hi * 0.999999 else "in")
    assert hit == {"lo", "in", "hi"}, hit       # the points span both clips and the range between


def test_nssl_volume_gamma_is_the_effective_radius():
    """cloud/ice/snow: n(v) ~ v^nu exp(-lambda_v v) integrated in D (v = pi/6 D^3): <r^3>/<r^2> equals the
    scheme's r (snu = -0.8 included), at a point inside the clips."""
    rho0 = 1.0
    for cat, nu, rho_p, qx, cx in (("cloud", 0.0, 1000.0, 1e-3, 1e8), ("snow", -0.8, 100.0, 1e-4, 1e4),
                                   ("ice", 0.0, 900.0, 1e-4, 1e5)):
        lam_v = rho_p * cx * (nu + 1.0) / (qx * rho0)             # mean mass = rho_p (nu + 1) / lambda_v
        d = np.logspace(-11, -1, 800001)
        v = pi / 6 * d ** 3
        expected = reff_quadrature(lambda dd: (pi / 6 * dd ** 3) ** nu * np.exp(-lam_v * pi / 6 * dd ** 3)
                                   * pi / 2 * dd ** 2, d)
        assert np.trapezoid(rho_p * v * (v ** nu * np.exp(-lam_v * v)) * pi / 2 * d ** 2, d) / \
            np.trapezoid((v ** nu * np.exp(-lam_v * v)) * pi / 2 * d ** 2, d) == pytest.approx(qx * rho0 / cx, rel=5e-3)
        got = float(nssl_sizes.radius(cat, np.array([qx * rho0]), np.array([cx]), np.array([rho0]))[0])
        assert got == pytest.approx(expected, rel=5e-3), cat


def test_nssl_rain_hail_lambda_and_calc_eff_radius_typo():
    """Rain (alpha 0) and hail (alpha 1) gamma in diameter: ours is the distribution's <r^3>/<r^2> by
    quadrature; calc_eff_radius's literal (alpha+1)(alpha+1) gives ((alpha+2)/(alpha+1))^(1/3) times that."""
    rho0, qx, cx = 1.0, 1e-3, 2e3
    for cat, alpha, rho_p in (("rain", 0.0, 1000.0), ("hail", 1.0, 900.0)):
        lam = (pi / 6 * rho_p * cx * G(alpha + 4) / G(alpha + 1) / (qx * rho0)) ** (1 / 3)
        expected = reff_quadrature(lambda d: d ** alpha * np.exp(-lam * d))
        got = float(nssl_sizes.radius(cat, np.array([qx * rho0]), np.array([cx]), np.array([rho0]))[0])
        assert got == pytest.approx(expected, rel=2e-3)
        literal = nssl_fortran(cat, qx, cx, rho0, literal=True)
        assert literal / got == pytest.approx(((alpha + 2) / (alpha + 1)) ** (1 / 3), rel=1e-5)


def test_nssl_variable_density_graupel():
    rho0, qx, cx, vol = 1.1, 2e-3, 1e3, 2e-3 / 700.0             # QVGRAUPEL (m^3/kg): density 700
    expected = nssl_fortran("graupel", qx, cx, rho0, hwdn=rho0 * qx / (vol * rho0))
    got = nssl_sizes.radius("graupel", np.array([qx * rho0]), np.array([cx]), np.array([rho0]),
                            np.array([vol * rho0]))
    assert float(got[0]) == pytest.approx(expected, rel=1e-5)
    assert float(got[0]) != pytest.approx(nssl_fortran("graupel", qx, cx, rho0), rel=1e-3)


# ---- Milbrandt-Yau (module_mp_milbrandt2mom.F) ----

def my_fortran(cat, qx, nx, de):
    """The scheme's iLAMDA_x with its icex* constants (alpha_x, cmx, dmx as in the Fortran), r = 0.5 M3/M2;
    N floored at epsN = 1e-3 m^-3."""
    piov6 = pi / 6.0
    nx = max(nx, 1e-3)
    if cat == "cloud":                                  # alpha_c = 1, MUc = 3, reff_c = 0.664639 iLAMc
        icexc9 = 1.0 / (G(1.0 + 1.0 + 3.0 / 3.0) / G(1.0 + 1.0) * piov6 * 1000.0)
        return 0.664639 * (de * qx / nx * icexc9) ** (1 / 3)
    if cat == "ice":                                    # cmi = 440, reff_i = 1.5 iLAMi, iLAMmin2
        icexi9 = 1.0 / (440.0 * G(1.0 + 0.0 + 3.0) / G(1.0))
        return 1.5 * max(1e-10, (de * qx / nx * icexi9) ** (1 / 3))
    if cat == "snow":                                   # cms = 0.1597, dms = 2.078 (snowSpherical = .false.)
        igs20 = 1.0 / (G(1.0 + 2.078) / G(1.0) * 0.1597)
        return 1.5 * max(1e-10, (de * qx / nx * igs20) ** (1 / 2.078))
    cm = piov6 * {"rain": 1000.0, "graupel": 400.0, "hail": 900.0}[cat]
    return 1.5 * max(1e-6, (de * qx / nx / (G(4.0) * cm)) ** (1 / 3))   # icexr9, iGG99, iGH99; iLAMmin1


@pytest.mark.parametrize("cat", ["cloud", "ice", "rain", "snow", "graupel", "hail"])
def test_milbrandt_yau(cat):
    de = 0.8
    for qx in Q:
        for nx in N[1:]:
            got = float(milbrandt_sizes.radius(cat, np.array([qx * de]), np.array([nx]))[0])
            assert got == pytest.approx(my_fortran(cat, qx, nx, de), rel=1e-5), (cat, qx, nx)
    # the iLAMmin floors bind for rain/graupel/hail at tiny contents: 1.5 um
    if cat in ("rain", "graupel", "hail"):
        assert float(milbrandt_sizes.radius(cat, np.array([1e-14]), np.array([1e11]))[0]) == pytest.approx(1.5e-6)


def test_milbrandt_yau_cloud_distribution():
    """MY cloud (alpha_c = 1, mu_c = 3 in the code's convention) is n(D) ~ D^5 exp(-(D / iLAM)^3): its mass
    is the content and 0.5 M3/M2 = 0.664639 iLAM."""
    rq, n = 5e-4, 1e8
    ilam = my_fortran("cloud", rq, n, 1.0) / 0.664639
    d = np.logspace(-8, -3, 400001)
    shape = d ** 5 * np.exp(-(d / ilam) ** 3)
    mass = pi / 6 * 1000 * np.trapezoid(shape * d ** 3, d) / np.trapezoid(shape, d) * n
    assert mass == pytest.approx(rq, rel=1e-3)
    assert reff_quadrature(lambda dd: dd ** 5 * np.exp(-(dd / ilam) ** 3), d) == pytest.approx(0.664639 * ilam, rel=1e-4)


# ---- Kessler, P3 ----

def test_kessler_rain_marshall_palmer():
    for rq in (1e-9, 1e-6, 1e-4, 1e-3, 1e-2):
        lam = (pi * 1000.0 * 8e6 / rq) ** 0.25          # Marshall & Palmer (1948): N0 = 0.08 cm^-4
        assert float(mp.kessler_rain(np.array([rq]))[0]) == pytest.approx(1.5 / lam, rel=1e-5)
    assert set(mp.rules(1, [])) == {"rain"}


def test_p3_cloud_and_rain_as_get_dsd2():
    hit = set()
    for qc in (1e-9, 1e-6, 1e-4, 1e-3, 5e-3):
        for nc in (None, 1e6, 5e7, 3e8, 2e9, 1e11):
            ncc = 200e6 if nc is None else nc                       # nccnst (per m^3 here, rho = 1)
            mu = 0.0005714 * (ncc * 1e-6) + 0.2714
            mu = min(max(1.0 / mu ** 2 - 1.0, 2.0), 15.0)
            lamc = (pi / 6 * 997.0 * ncc * (mu + 3.0) * (mu + 2.0) * (mu + 1.0) / qc) ** (1 / 3)
            lammin, lammax = (mu + 1.0) * 2.5e4, (mu + 1.0) * 1.0e6
            hit.add("min" if lamc < lammin else "max" if lamc > lammax else "in")
            lamc = min(max(lamc, lammin), lammax)
            got = float(mp.p3_cloud(np.array([qc]), None if nc is None else np.array([nc]))[0])
            assert got == pytest.approx(0.5 * (mu + 3.0) / lamc, rel=1e-5)
    assert hit == {"min", "max", "in"}
    for qr, nr in ((1e-3, 1e3), (1e-4, 1e6), (1e-9, 1e7), (1e-2, 1.0)):
        lamr = (pi / 6 * 997.0 * nr * 6.0 / qr) ** (1 / 3)          # mu_r = 0
        lamr = min(max(lamr, 1.0 / 0.002), 1.0e5)
        assert float(mp.p3_rain(np.array([qr]), np.array([nr]))[0]) == pytest.approx(1.5 / lamr, rel=1e-5)


# ---- Thompson graupel, as mp_thompson of each WRF version ----

def thompson_n0_fortran(version, rg_in, temp, rr_in, nr_in, rc_in, rho):
    """The graupel intercept loop of mp_thompson, transcribed per version (k from the top down)."""
    r1 = 1e-12
    nz = len(rg_in)
    rg = [rg_in[k] if rg_in[k] / rho[k] > r1 else r1 for k in range(nz)]
    rr = [rr_in[k] if rr_in[k] / rho[k] > r1 else r1 for k in range(nz)]
    rc = [rc_in[k] if rc_in[k] / rho[k] > r1 else r1 for k in range(nz)]
    l_qr = [rr_in[k] / rho[k] > r1 for k in range(nz)]
    mvd_r = []
    for k in range(nz):
        lamr = (pi / 6 * 1000.0 * 6.0 * max(1e-6, nr_in[k]) / rr[k]) ** (1 / 3)
        mvd = 3.672 / lamr
        mvd_r.append(2.5e-3 if mvd > 2.5e-3 else 0.75 * 50e-6 if mvd < 0.75 * 50e-6 else mvd)
    out = [0.0] * nz
    if version in ("4.2", "4.3", "4.5"):
        for k in range(nz - 1, -1, -1):
            ygra1 = np.log10(max(1e-9, rg_in[k]))
            zans1 = 3.5 + 2 / 7 * (ygra1 + 7) if version == "4.2" else 3.0 + 2 / 7 * (ygra1 + 8)
            zans1 = max(2.0, min(zans1, 7.0 if version == "4.2" else 6.0))
            out[k] = 10 ** zans1
        return out
    gonv = {"3.3": (1e4, 3e6), "3.4": (2e4, 2e6), "3.5": (1e4, 3e6)}[version]
    n0_min = gonv[1]
    k_0 = 0
    for k in range(nz - 1, -1, -1):
        if temp[k] >= 270.65:
            k_0 = max(k_0, k)
    for k in range(nz - 1, -1, -1):
        if version == "3.3":
            if temp[k] < 273.15 and (rc[k] + rr[k]) > 1e-5:
                xslw1 = 5.0 + np.log10(max(1e-5, min(1e-2, rc[k] + rr[k])))
            else:
                xslw1 = 0.0001
            ygra1 = 4.302 + np.log10(max(5e-5, min(5e-2, rg[k])))
            zans1 = 3.565 + (90.0 / (50.0 * xslw1 * ygra1 / (5.0 / xslw1 + 1.0 + 0.25 * ygra1) + 30.0 + 15.0 * ygra1))
        else:
            cond = temp[k] < 270.65 if version == "3.4" else k > k_0
            xslw1 = 4.01 + np.log10(mvd_r[k]) if cond and l_qr[k] and mvd_r[k] > 100e-6 else 0.01
            ygra1 = 4.31 + np.log10(max(5e-5, rg[k]))
            c0, cy = (3.0, 5.0) if version == "3.4" else (3.1, 10.0)
            zans1 = c0 + (100.0 / (300.0 * xslw1 * ygra1 / (10.0 / xslw1 + 1.0 + 0.25 * ygra1) + 30.0 + cy * ygra1))
        n0_exp = max(gonv[0], min(10 ** zans1, gonv[1]))
        n0_min = min(n0_exp, n0_min)
        out[k] = n0_min
    return out


@pytest.mark.parametrize("version", ["3.3", "3.4", "3.5", "4.2", "4.3", "4.5"])
def test_thompson_graupel_intercept_by_version(version):
    # two columns (bottom up): warm rain below, supercooled rain aloft, graupel contents 1e-9..2e-2 kg/m^3
    temp = np.array([[290, 280, 272, 270, 265, 255, 240, 225], [285, 275, 271, 268, 262, 250, 235, 220]], float).T
    rho = np.linspace(1.2, 0.4, 8)[:, None] * np.ones((1, 2))
    rg = np.array([[1e-9, 1e-6, 1e-4, 2e-3, 5e-3, 2e-2, 1e-3, 1e-5], [0, 1e-5, 3e-3, 1e-2, 4e-4, 1e-7, 1e-12, 0]]).T
    rr = np.array([[2e-3, 1e-3, 8e-4, 5e-4, 3e-4, 1e-4, 0, 0], [1e-3, 3e-3, 2e-3, 1e-3, 6e-4, 0, 0, 0]]).T
    nr = np.array([[1e3, 5e2, 3e2, 2e2, 1e2, 1e3, 0, 0], [3e3, 1e2, 1e2, 5e1, 1e2, 0, 0, 0]]).T
    rc = np.array([[1e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 0, 0], [0, 0, 1e-4, 1e-4, 1e-4, 1e-5, 0, 0]]).T
    rho_g = {"3.3": 400.0, "4.5": 400.0}.get(version, 500.0)
    for c in range(2):
        n0 = thompson_n0_fortran(version, rg[:, c], temp[:, c], rr[:, c], nr[:, c], rc[:, c], rho[:, c])
        got = thompson_graupel.radius(version, rg, temp, rho, rr, nr, rc)[:, c]
        for k in range(8):
            if rg[k, c] <= 0:
                assert got[k] == 0
                continue
            lamg = (n0[k] * pi / 6 * rho_g * 6.0 / rg[k, c]) ** 0.25    # am_g cgg(1), oge1 = 1/4
            if version == "4.5":                                       # mvd_g in [D0r, 25.4 mm]
                lamg = min(max(lamg, 3.672 / 25.4e-3), 3.672 / 50e-6)
            assert float(got[k]) == pytest.approx(1.5 / lamg, rel=1e-5), (version, c, k)
    if version in ("3.3", "3.5"):  # the column minimum and the rain term act: differs from the local formula
        local = thompson_graupel.radius("4.3", rg, temp, rho, rr, nr, rc)
        assert not np.allclose(got, local[:, 1])


def test_thompson_version_of_title_and_two_moment_graupel():
    assert thompson_graupel.version_of(" OUTPUT FROM WRF V3.3.1 MODEL") == "3.3"
    assert thompson_graupel.version_of("OUTPUT FROM WRF V3.4 MODEL") == "3.4"
    assert thompson_graupel.version_of("OUTPUT FROM WRF V3.9.1.1 MODEL") == "3.5"
    assert thompson_graupel.version_of("OUTPUT FROM WRF V4.1.2 MODEL") == "3.5"
    assert thompson_graupel.version_of("OUTPUT FROM WRF V4.2.2 MODEL") == "4.2"
    assert thompson_graupel.version_of("OUTPUT FROM WRF V4.4 MODEL") == "4.3"
    assert thompson_graupel.version_of("OUTPUT FROM WRF V4.7.1 MODEL") == "4.5"
    assert thompson_graupel.version_of("OUTPUT FROM A TEST FACTORY") is None
    # QNGRAUPEL + QVGRAUPEL (MP 38): rho_g of the bin nint(rho / 100) + 1 among 50, 100, 200, ..., 800
    rq, ng = np.array([1e-3, 1e-3, 1e-3, 1e-3]), np.array([1e3, 1e3, 1e-9, 1e6])
    vol = rq / np.array([640.0, 2000.0, 500.0, 120.0])  # 640 -> bin nint(6.4)+1 = 7 (600); 2000 -> 800; 120 -> 100
    got = thompson_graupel.radius_from_number(rq, ng, vol)
    for k, rho_g in enumerate((600.0, 800.0, 500.0, 100.0)):
        lamg = (pi / 6 * rho_g * 6.0 * ng[k] / rq[k]) ** (1 / 3) if ng[k] > 1e-6 else 3.672 / 1.5e-3
        lamg = min(max(lamg, 3.672 / 25.4e-3), 3.672 / 50e-6)
        assert float(got[k]) == pytest.approx(1.5 / lamg, rel=1e-5), k


# ---- the reader: graupel with hail, bad input ----

def _reader(path, mp_physics, present=("cloud", "ice", "rain", "snow", "graupel")):
    ds = xr.open_dataset(path)
    read = lambda var, shape: ds[var].values[0].astype(np.float32)   # noqa: E731
    return ds, SizeReader(ds, str(path), read, mp_physics, f"MP_PHYSICS={mp_physics}", list(present), True)


def test_nssl_graupel_and_hail_combined_as_calc_eff_radius(tmp_path):
    shape = (1, 6, 4, 5)
    qg, qh = np.full(shape, 2e-3), np.full(shape, 1e-3)
    qh[0, :, 0] = 0.0                                       # graupel only in one row
    ng, nh, vg = np.full(shape, 5e3), np.full(shape, 200.0), np.full(shape, 2e-3 / 650.0)
    path = write_wrfout(tmp_path / "n.nc", mp_physics=18, override={
        "QGRAUP": qg, "QHAIL": qh, "QNGRAUPEL": ng, "QNHAIL": nh, "QVGRAUPEL": vg})
    ds, reader = _reader(path, 18)
    rho = np.full(shape[1:], 0.9, np.float32)
    r = reader.radius("graupel", (qg[0] * rho).astype(np.float32), rho, shape[1:],
                      (qh[0] * rho).astype(np.float32))
    # calc_eff_radius's combined branch (numh + numhl) / (denomh + denomhl), the lambdas as in the scheme
    lam_h = ((pi * 3 * 2 * 1) / 6 * 650.0 * 5e3 * 0.9 / (2e-3 * 0.9)) ** (1 / 3)
    lam_hl = ((pi * 4 * 3 * 2) / 6 * 900.0 * 200 * 0.9 / (1e-3 * 0.9)) ** (1 / 3)
    cx_h, cx_hl = 5e3 * 0.9, 200 * 0.9
    numh, numhl = cx_h * 3 * 2 * 1 / lam_h ** 3, cx_hl * 4 * 3 * 2 / lam_hl ** 3
    denomh, denomhl = cx_h * 2 * 1 / lam_h ** 2, cx_hl * 3 * 2 / lam_hl ** 2
    assert float(r[2, 2, 2]) == pytest.approx(0.5 * (numh + numhl) / (denomh + denomhl), rel=1e-4)
    assert float(r[2, 0, 2]) == pytest.approx(1.5 / lam_h, rel=1e-5)     # graupel alone
    hyd = wm.open_wrf(path)
    assert "with QHAIL: calc_eff_radius from QNHAIL" in hyd.attrs["r_eff_source_graupel"]
    has = hyd.q_graupel.values > 0
    assert np.all(hyd.r_eff_graupel.values[has] > 0)


def test_nssl_hail_with_its_own_volume_reads_each_field_once(tmp_path):
    """Graupel and hail both of predicted volume (QVGRAUPEL, QVHAIL: their densities q / V): the combined radius
    is calc_eff_radius's, and every field the rules need is read once."""
    shape = (1, 6, 4, 5)
    qg, qh = np.full(shape, 2e-3), np.full(shape, 1e-3)
    vg, vh = np.full(shape, 2e-3 / 650.0), np.full(shape, 1e-3 / 800.0)
    path = write_wrfout(tmp_path / "n.nc", mp_physics=18, override={
        "QGRAUP": qg, "QHAIL": qh, "QNGRAUPEL": np.full(shape, 5e3), "QNHAIL": np.full(shape, 200.0),
        "QVGRAUPEL": vg, "QVHAIL": vh})
    ds = xr.open_dataset(path)
    reads = []
    reader = SizeReader(ds, str(path), lambda var, shp: reads.append(var) or ds[var].values[0].astype(np.float32),
                        18, "MP_PHYSICS=18", ["graupel"], True)
    rho = np.full(shape[1:], 0.9, np.float32)
    r = reader.radius("graupel", (qg[0] * rho).astype(np.float32), rho, shape[1:], (qh[0] * rho).astype(np.float32))
    assert sorted(reads) == ["QNGRAUPEL", "QNHAIL", "QVGRAUPEL", "QVHAIL"]
    lam_h = ((pi * 3 * 2 * 1) / 6 * 650.0 * 5e3 * 0.9 / (2e-3 * 0.9)) ** (1 / 3)
    lam_hl = ((pi * 4 * 3 * 2) / 6 * 800.0 * 200 * 0.9 / (1e-3 * 0.9)) ** (1 / 3)
    cx_h, cx_hl = 5e3 * 0.9, 200 * 0.9
    numh, numhl = cx_h * 3 * 2 * 1 / lam_h ** 3, cx_hl * 4 * 3 * 2 / lam_hl ** 3
    denomh, denomhl = cx_h * 2 * 1 / lam_h ** 2, cx_hl * 3 * 2 / lam_hl ** 2
    np.testing.assert_allclose(r, 0.5 * (numh + numhl) / (denomh + denomhl), rtol=1e-4)


def test_wsm7_hail_exponential_combined(tmp_path):
    shape = (1, 6, 4, 5)
    path = write_wrfout(tmp_path / "w7.nc", mp_physics=24, override={"QGRAUP": np.full(shape, 1e-3),
                                                                      "QHAIL": np.full(shape, 4e-3)})
    _, reader = _reader(path, 24)
    rho = np.ones(shape[1:], np.float32)
    r = reader.radius("graupel", np.full(shape[1:], 1e-3, np.float32), rho, shape[1:],
                      np.full(shape[1:], 4e-3, np.float32))
    r_g = 1.5 / min((pi * 500 * 4e6 / 1e-3) ** 0.25, 6e4)             # WSM7 n0g, deng, lamdagmax
    r_h = 1.5 / min((pi * 912 * 4e4 / 4e-3) ** 0.25, 2e4)             # n0h, denh, lamdahmax
    v_g, v_h = 1e-3 / 500, 4e-3 / 912
    assert float(r[0, 0, 0]) == pytest.approx((v_g + v_h) / (v_g / r_g + v_h / r_h), rel=1e-5)


def test_nssl_open_wrf_radii_within_the_clips(tmp_path):
    shape = (1, 6, 4, 5)
    rng = np.random.default_rng(1)
    q = {v: rng.uniform(0, 3e-3, shape) for v in ("QCLOUD", "QRAIN", "QICE", "QSNOW", "QGRAUP", "QHAIL")}
    n = {v: 10 ** rng.uniform(0, 9, shape) for v in ("QNDROP", "QNRAIN", "QNICE", "QNSNOW", "QNGRAUPEL", "QNHAIL")}
    path = write_wrfout(tmp_path / "n.nc", mp_physics=18, override={**q, **n})
    hyd = wm.open_wrf(path)
    scheme = wm.optical_volume(hyd, "physical", sizes="scheme", phase_tables=[None] * 5)
    fixed = wm.optical_volume(hyd, "physical", sizes="physical", phase_tables=[None] * 5)
    assert np.all(np.isfinite(scheme.beta_total)) and not np.array_equal(scheme.beta_total, fixed.beta_total)
    for name, (lo, hi) in (("cloud", (2.51e-6, 50e-6)), ("ice", (10.01e-6, 125e-6)), ("snow", (25e-6, 999e-6)),
                           ("rain", (50e-6, 2999e-6)), ("graupel", (50e-6, 40e-3))):
        r = hyd[f"r_eff_{name}"].values[hyd[f"q_{name}"].values > 0]
        assert r.size and r.min() >= lo * 0.999 and r.max() <= hi * 1.001, name
        assert hyd.attrs[f"r_eff_source_{name}"].startswith("NSSL")


@pytest.mark.parametrize("var, value, expectation", [("QNHAIL", -3.0, "QNHAIL.*>= 0"),
                                                     ("QVGRAUPEL", -1e-6, "QVGRAUPEL.*volumes.*>= 0"),
                                                     ("QNDROP", np.nan, "QNDROP.*finite")])
def test_nssl_bad_numbers_and_volumes_are_named(tmp_path, var, value, expectation):
    shape = (1, 6, 4, 5)
    fields = {"QCLOUD": np.full(shape, 1e-4), "QGRAUP": np.full(shape, 1e-3), "QHAIL": np.full(shape, 1e-3),
              "QNDROP": np.full(shape, 1e8), "QNGRAUPEL": np.full(shape, 1e3), "QNHAIL": np.full(shape, 10.0),
              "QVGRAUPEL": np.full(shape, 2e-6)}
    fields[var] = fields[var].copy()
    fields[var][0, 3, 2, 2] = value
    path = write_wrfout(tmp_path / "bad.nc", mp_physics=18, override=fields)
    with pytest.raises(WeatherDataError, match=expectation) as err:
        wm.open_wrf(path)
    assert "bad.nc" in str(err.value)


def test_schemes_without_a_rule_warn_naming_the_fallback(tmp_path):
    shape = (1, 6, 4, 5)
    path = write_wrfout(tmp_path / "k.nc", mp_physics=1, species=("QCLOUD", "QRAIN"),
                        override={"QCLOUD": np.full(shape, 1e-4), "QRAIN": np.full(shape, 1e-4)})
    with pytest.warns(UserWarning, match="Kessler: Kessler has no cloud droplet size distribution.*cloud radii are "
                                         "the species table's"):
        hyd = wm.open_wrf(path)
    assert hyd.attrs["r_eff_source_rain"].startswith("Kessler") and "r_eff_cloud" not in hyd
    path = write_wrfout(tmp_path / "p3.nc", mp_physics=51, species=("QCLOUD", "QRAIN", "QICE"),
                        override={"QICE": np.full(shape, 1e-4), "QNCLOUD": np.full(shape, 1e8),
                                  "QNRAIN": np.full(shape, 1e3)})
    with pytest.warns(UserWarning, match="P3 1-ice \\+ nc: P3's ice sizes need its lookup tables and the file has "
                                         "no RE_ICE.*ice radii are the species table's"):
        wm.open_wrf(path)
    re_ice = np.full(shape, 30e-6)                           # P3 writing RE_ICE (m): read through, no warning
    path = write_wrfout(tmp_path / "p3re.nc", mp_physics=51, species=("QCLOUD", "QRAIN", "QICE"),
                        override={"QICE": np.full(shape, 1e-4), "RE_ICE": re_ice})
    import netCDF4
    with netCDF4.Dataset(path, "a") as nc:
        nc["RE_ICE"].units = "m"
    hyd = wm.open_wrf(path)
    assert hyd.attrs["r_eff_source_ice"] == "file RE_ICE"
    np.testing.assert_allclose(hyd.r_eff_ice.values[hyd.q_ice.values > 0], 30e-6, rtol=1e-5)


def test_re_in_metres_labelled_micrometres_is_named(tmp_path):
    shape = (1, 6, 4, 5)
    path = write_wrfout(tmp_path / "w.nc", override={"QCLOUD": np.full(shape, 1e-3),
                                                      "RE_CLOUD": np.full(shape, 12e-6)})
    import netCDF4
    with netCDF4.Dataset(path, "a") as nc:
        nc["RE_CLOUD"].units = "um"
    with pytest.raises(WeatherDataError, match="RE_CLOUD.*wrong units"):
        wm.open_wrf(path)
