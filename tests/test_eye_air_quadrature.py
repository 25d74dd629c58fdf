"""The slicer's Gauss-Legendre rule for the air along eye rays (``slicing.eye_air_quadrature``, issue 38 part 3)
against closed forms: polynomials, a homogeneous path, an exponential atmosphere whose scatterers have half the
extinction's scale height, and the slicer's own source (``eye_air.source_at``) on a vertical ray through an
exponential atmosphere, where single scattering is omega p (1 - T)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from weather_mi.slicing.eye_air_quadrature import NODES, gauss_segment, rule

R_EARTH = 6371e3


def _p_rayleigh(mu, depol=0.0279):  # Rayleigh's phase function with Young's (1980) depolarisation, 1/sr
    g = depol / (2 - depol)
    return 3 / (16 * math.pi * (1 + 2 * g)) * ((1 + 3 * g) + (1 - g) * mu * mu)


@pytest.mark.parametrize("n", [4, 8])
def test_the_rule_integrates_polynomials_exactly(n):
    """The n nodes' weights integrate u^k over [0, 1] for k < 2n, and the integration matrix gives
    int_0^{x_i} u^k du = x_i^(k+1) / (k+1) at every node for k < n (to float64 rounding); at k = n it does not."""
    x, w, a = rule(n)
    for k in range(2 * n):
        assert abs(w @ x ** k - 1.0 / (k + 1)) < 1e-13, k
    for k in range(n):
        np.testing.assert_allclose(a @ x ** k, x ** (k + 1) / (k + 1), rtol=0, atol=1e-13)
    assert np.max(np.abs(a @ x ** n - x ** (n + 1) / (n + 1))) > 1e-6  # the test can tell


def _mi():
    import mitsuba as mi
    return mi


@pytest.mark.parametrize("squared", [False, True])
def test_a_homogeneous_path_is_the_closed_form(squared):
    """Constant extinction sigma and source c over lengths L with sigma L from 0.02 to 12 (the horizon's
    haze is ~10 in blue): T = exp(-sigma L) within 1e-5 (absolute), S = c / sigma (1 - exp(-sigma L)) within
    1e-4 (measured 1.4e-7: float32) on the slicer's ``NODES`` (12), on either spacing (uniform, or dense near
    the camera as the slicer's outside segment). As many trapezoids on the same spacing miss S by over 1% (the
    test can tell)."""
    mi = _mi()
    lengths = np.array([2e3, 20e3, 100e3, 300e3, 1200e3])
    sigma = np.array([1e-5, 2e-5, 1e-5])
    c = np.array([3e-6, 1e-6, 2e-6])

    def source(s):
        return mi.Color3f(*sigma.tolist()) + 0.0 * s, mi.Color3f(*c.tolist()) + 0.0 * s
    t0 = mi.Float(np.full(lengths.size, 50.0))
    T, S = gauss_segment(mi, source, t0, t0 + mi.Float(lengths), NODES, squared)
    T, S = np.asarray(T).T, np.asarray(S).T  # (rays, 3)
    tau = lengths[:, None] * sigma
    np.testing.assert_allclose(T, np.exp(-tau), rtol=0, atol=1e-5)
    exact = c / sigma * (1.0 - np.exp(-tau))
    np.testing.assert_allclose(S, exact, rtol=1e-4)
    # as many trapezoids on the same points' spacing
    xs = np.linspace(0.0, 1.0, NODES)
    s = lengths[:, None] * (xs ** 2 if squared else xs)
    trap_tau = s[:, :, None] * sigma
    g = c * np.exp(-trap_tau)
    trap = (0.5 * (g[:, 1:] + g[:, :-1]) * np.diff(s)[:, :, None]).sum(axis=1)
    assert np.max(np.abs(trap / exact - 1.0)) > 0.01


def test_scatterers_thinner_than_the_extinction_are_the_closed_form():
    """A vertical path through an exponential atmosphere, extinction sigma0 e^(-h/H) and source
    a e^(-2h/H) (scatterers at half its scale height, as the aerosol's under the molecules'), from h0 over
    lengths L up to 20 km (17 e-folds): with u = e^(-h/H), k = sigma0 H: tau = k (u0 - u1) and
    S = a H e^(-k u0) [e^(k u)(u/k - 1/k^2)] from u1 to u0. Within 1e-5 (T) and 1e-4 (S) on ``NODES``, either spacing (measured 6e-6; 8 nodes: 0.36% at
    20 km, where the scatterers fall over 33 e-folds)."""
    mi = _mi()
    H, sigma0, a, h0 = 1200.0, np.array([8e-5, 4e-5, 2e-5]), np.array([5e-6, 3e-6, 1e-6]), 300.0
    lengths = np.array([500.0, 3e3, 10e3, 20e3])
    k = sigma0 * H
    u0, u1 = np.exp(-h0 / H), np.exp(-(h0 + lengths[:, None]) / H)
    tau = k * (u0 - u1)
    prim = lambda u: np.exp(k * u) * (u / k - 1.0 / k ** 2)  # noqa: E731
    exact = a * H * np.exp(-k * u0) * (prim(u0) - prim(u1))

    def source(s):
        import drjit as dr
        u = dr.exp(-(s + h0) / H)
        return mi.Color3f(*sigma0.tolist()) * u, mi.Color3f(*a.tolist()) * u * u
    for squared in (False, True):
        t0 = mi.Float(np.zeros(lengths.size))
        T, S = gauss_segment(mi, source, t0, t0 + mi.Float(lengths), NODES, squared)
        np.testing.assert_allclose(np.asarray(T).T, np.exp(-tau), rtol=0, atol=1e-5)
        np.testing.assert_allclose(np.asarray(S).T, exact, rtol=1e-4)


def test_the_slicers_source_on_a_vertical_ray_is_omega_p_one_minus_t():
    """``eye_air.source_at`` on an ``EyeAir`` whose 1-D air is molecules alone with extinction sigma0 e^(-h/8 km)
    (a table every 10 m), scattering albedo 0.9, a white sun at every height: along a vertical ray from the
    Earth's centre's vertical (h = h0 + s) single scattering is omega p_R(mu) (1 - T) and T = exp(-sigma0 H
    (e^(-h0/H) - e^(-h1/H))), against ``gauss_segment`` on ``NODES``: within 1e-5 and 1e-4 (measured 1.2e-6 and
    5.9e-6)."""
    import drjit as dr
    from weather_mi.slicing.eye_air import EyeAir, source_at
    from weather_mi.slicing.packets import packed
    mi = _mi()
    H, omega, step = 8000.0, 0.9, 10.0
    sigma0 = np.array([1.2e-5, 2.5e-5, 5.5e-5])
    h = np.arange(0.0, 60e3 + step, step)
    # the profiles (molecules, ozone, aerosol) and their cross sections (eye_air.cross_sections): molecules scatter
    # omega of the extinction, the "ozone" absorbs the rest
    prof = np.exp(-h / H)[:, None] * np.array([omega, 1.0 - omega, 0.0])
    cross = tuple(mi.Color3f(*c.tolist()) for c in (sigma0, sigma0, np.zeros(3), np.zeros(3)))
    op = lambda v: dr.opaque(mi.Float, float(v))  # noqa: E731
    to_sun = np.array([0.0, -math.cos(math.radians(25.0)), math.sin(math.radians(25.0))])
    air = EyeAir(air=mi.Float(packed(prof)), cross=cross, h_step=op(1.0 / step), n_h=h.size,
                 sun_rgb=mi.Float(packed(np.ones((2, 2, 3)))), sun_mu=(op(-1.0), op(0.5), op(1.0 / 100e3)), n_mu=2,
                 n_s=2, to_sun=mi.Vector3f(*to_sun.tolist()), irradiance=mi.Color3f(1.0), aerosol_g=op(0.7),
                 centre=mi.Point3f(0.0, 0.0, 0.0), box=(mi.Point3f(-1.0), mi.Point3f(1.0)), floor=op(0.0),
                 ground=False, diffuse=mi.Float(packed(np.zeros((2, 3)))))
    h0 = np.array([0.0, 500.0, 2000.0])
    lengths = np.array([40e3, 8e3, 20e3])
    o = mi.Point3f(0.0, 0.0, mi.Float(h0))
    d = mi.Vector3f(0.0, 0.0, 1.0)
    T, S = gauss_segment(mi, source_at(mi, air, o, d), mi.Float(np.zeros(3)), mi.Float(lengths), NODES, True)
    tau = sigma0 * H * (np.exp(-h0 / H) - np.exp(-(h0 + lengths) / H))[:, None]
    np.testing.assert_allclose(np.asarray(T).T, np.exp(-tau), rtol=0, atol=1e-5)
    np.testing.assert_allclose(np.asarray(S).T, omega * _p_rayleigh(to_sun[2]) * (1.0 - np.exp(-tau)), rtol=1e-4)
