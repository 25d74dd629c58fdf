"""The air along eye rays outside the box (``optics.air.eye_path``, issue 38 part 1): transmittance and
single-scattered sunlight against a closed form (a short horizontal path), an independent ODE integration
(a slant path to the top of the air), and the blue haze of a distant dark target."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from weather_mi.optics.air import Atmosphere, sun_rgb
from weather_mi.optics.air.eye_path import TOP_M, segment_air, top_distance, wide_sun_table

R_EARTH = 6371e3
ELEV = 30.0
SUN = np.array([0.0, -math.cos(math.radians(ELEV)), math.sin(math.radians(ELEV))])


def _table(atm):
    return wide_sun_table(atm, float(SUN[2]), reach_m=400e3, n_mu=33, n_h=121)


def _p_rayleigh(mu, depol=0.0279):
    g = depol / (2 - depol)
    return 3 / (16 * math.pi * (1 + 2 * g)) * ((1 + 3 * g) + (1 - g) * mu * mu)


def _p_hg(g, mu):
    return (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * mu) ** 1.5)


def _coefficients(atm, h):
    """(molecular scattering, aerosol extinction, total extinction) at height h, per channel (650/550/450; ozone
    each channel's band average, checked in ``test_air.py``)."""
    from weather_mi.optics.air.ozone import rgb_channel_cross_sections_m2
    wl = np.array([650.0, 550.0, 450.0])
    aer = atm.aerosol_extinction_550_per_m(h) * (wl / 550.0) ** -atm.angstrom
    from weather_mi.optics.rayleigh import cross_section_m2
    mol = atm.air_number_density_m3(h) * cross_section_m2(wl * 1e-9)
    # the RGB channels' ozone, pinned by test_air.py::test_the_rgb_channels_take_ozones_band_average
    return mol, aer, mol + atm.ozone_number_density_m3(h) * rgb_channel_cross_sections_m2() + aer


def test_a_short_horizontal_path_is_the_homogeneous_closed_form():
    """1 km level at 2 km (the path drops 0.08 m below its height over the sphere): T = exp(-beta L),
    S = (beta_R p_R + omega_a beta_a p_HG) C (1 - exp(-beta L)) / beta, C the direct sun's colour there."""
    atm = Atmosphere(aod_550=0.2)
    d = np.array([[1.0, 0.0, 0.0]])
    t, s = segment_air(atm, SUN, [[-500.0, 0.0, 2000.0]], d, [0.0], [1000.0], _table(atm))
    mol, aer, beta = _coefficients(atm, 2000.0)
    cos_t = float(d[0] @ SUN)
    colour = sun_rgb(atm, 2000.0, float(SUN[2]))
    closed = (mol * _p_rayleigh(cos_t) + atm.aerosol_ssa * aer * _p_hg(atm.aerosol_g, cos_t)) * colour \
        * (1 - np.exp(-beta * 1000.0)) / beta
    assert t[0] == pytest.approx(np.exp(-beta * 1000.0), rel=1e-6)
    assert s[0] == pytest.approx(closed, rel=2e-3)


def test_a_slant_path_to_the_top_against_an_ode_solver():
    """From 300 m up at 3 deg elevation towards the sun's side, to the top of the air (several hundred km over
    the sphere): T and S against scipy's adaptive Runge-Kutta on dtau/ds = beta, dS/ds = exp(-tau) J(s)."""
    from scipy.integrate import solve_ivp
    atm = Atmosphere(aod_550=0.1)
    e = math.radians(3.0)
    d = np.array([0.0, -math.cos(e), math.sin(e)])
    o = np.array([0.0, 0.0, 300.0])
    length = float(top_distance(o[None], d[None])[0])
    q_top = o + length * d + [0, 0, R_EARTH]
    assert np.linalg.norm(q_top) - R_EARTH == pytest.approx(TOP_M, rel=1e-6)
    cos_t = float(d @ SUN)

    def rhs(s, y):
        q = o + s * d + [0.0, 0.0, R_EARTH]
        r = np.linalg.norm(q)
        h, mu = r - R_EARTH, float(q @ SUN) / r
        mol, aer, beta = _coefficients(atm, h)
        j = (mol * _p_rayleigh(cos_t) + atm.aerosol_ssa * aer * _p_hg(atm.aerosol_g, cos_t)) * sun_rgb(atm, h, mu)
        return np.concatenate([beta, np.exp(-y[:3]) * j])
    sol = solve_ivp(rhs, (0.0, length), np.zeros(6), rtol=1e-6, atol=1e-12, max_step=20e3)
    tau, s_ref = sol.y[:3, -1], sol.y[3:, -1]
    t, s = segment_air(atm, SUN, o[None], d[None], [0.0], [length], _table(atm))
    assert t[0] == pytest.approx(np.exp(-tau), rel=5e-3)
    assert s[0] == pytest.approx(s_ref, rel=1e-2)


def test_a_distant_dark_target_is_bluer_with_distance():
    """Clean air (AOD 0.02): a dark ground (albedo 0.05, lit by the sun at 30 deg) seen level from 300 m at
    1, 5 and 20 km: the blue share of its apparent colour grows with distance, past its own."""
    atm = Atmosphere(aod_550=0.02)
    target = 0.05 * sun_rgb(atm, 0.0, float(SUN[2])) * float(SUN[2]) / math.pi
    shares = [target[2] / target.sum()]
    for dist in (1e3, 5e3, 20e3):
        t, s = segment_air(atm, SUN, [[0.0, 0.0, 300.0]], [[1.0, 0.0, 0.0]], [0.0], [dist], _table(atm))
        seen = t[0] * target + s[0]
        shares.append(seen[2] / seen.sum())
    assert np.all(np.diff(shares) > 0.005), shares


def _scene(sky):
    from weather_mi.optics.phase.analytic import isotropic
    from weather_mi.optics.volume import OpticalVolume
    from weather_mi.scene.framing import scene_spec
    vol = OpticalVolume.from_arrays(np.zeros((4, 4, 4), np.float32), 1.0, isotropic(),
                                    ((-5e3, -5e3, 0.0), (5e3, 5e3, 10e3)))
    spec = scene_spec(vol, (16, 12), camera="ground", camera_distance_km=40.0, camera_height=300.0, fov=60.0,
                      sun_elevation=ELEV, sky=sky, atmosphere="clear", aod=0.1)
    return spec, vol


def test_eye_air_on_an_image_is_the_segments_air():
    """``display.aerial``: a ground pixel gets E S + T L along camera-to-ground, a box pixel camera-to-box;
    a sky pixel keeps the sky model's value with ``sunsky`` and gets the air's sky with ``--sky air``, blue away
    from the sun."""
    from weather_mi.display.aerial import with_eye_air
    from weather_mi.io.image import Image
    from weather_mi.optics.air.eye_path import wide_sun_table
    from weather_mi.slicing.geometry import camera_rays, ray_box
    spec, vol = _scene("sunsky")
    flat = np.full((12, 16, 3), 0.02, np.float32)
    img = Image(radiance=flat, stderr=flat * 0.1, transmittance=np.zeros((12, 16), np.float32))  # opaque box
    out = with_eye_air(img, spec, vol)
    o, d = (a.reshape(-1, 3) for a in camera_rays(spec))
    t_in, t_out = ray_box(o, d, (np.array([-5e3, -5e3, 0.0]), np.array([5e3, 5e3, 10e3])))
    hit = t_out > t_in
    e = np.asarray(spec.sun.irradiance)
    table = wide_sun_table(spec.atmosphere, spec.sun.mu0)
    sky = (~hit) & (d[:, 2] > 0)
    ground = (~hit) & (d[:, 2] < 0)
    assert hit.any() and sky.any() and ground.any()
    for mask, t_end in ((hit, t_in), (ground, (0.0 - o[:, 2]) / np.where(d[:, 2] == 0, 1, d[:, 2]))):
        i = int(np.flatnonzero(mask)[0])
        t, s = segment_air(spec.atmosphere, spec.sun.to_sun, o[i:i + 1], d[i:i + 1], [0.0], [t_end[i]], table)
        assert out.radiance.reshape(-1, 3)[i] == pytest.approx(e * s[0] + t[0] * 0.02, rel=1e-5)
    assert np.all(out.radiance.reshape(-1, 3)[sky] == 0.02)
    clear_box = with_eye_air(replace(img, transmittance=np.ones((12, 16), np.float32)), spec, vol)
    through = hit & (d[:, 2] > 0.0)  # a clear box with the sky model's sky behind: the render holds the air
    assert through.any() and np.all(clear_box.radiance.reshape(-1, 3)[through] == 0.02)
    spec_air, _ = _scene("air")
    assert spec_air.sky.kind == "air"  # the air's light into the box (kernel.air_sky); its sky on the eye rays here
    out_air = with_eye_air(replace_radiance(img, 0.0), spec_air, vol, sky_air=True)
    away = sky & (d @ np.asarray(spec.sun.to_sun) < 0.5) & (d[:, 2] > 0.17)  # > 60 deg from the sun, > 10 deg up
    assert away.any() and np.all(out_air.radiance.reshape(-1, 3)[away][:, 2] > out_air.radiance.reshape(-1, 3)[away][:, 0])


def replace_radiance(img, value):
    from dataclasses import replace
    return replace(img, radiance=np.full_like(img.radiance, value))


def test_sky_air_needs_the_atmosphere():
    from weather_mi.optics.phase.analytic import isotropic
    from weather_mi.optics.volume import OpticalVolume
    from weather_mi.scene.framing import scene_spec
    vol = OpticalVolume.from_arrays(np.zeros((2, 2, 2), np.float32), 1.0, isotropic(), ((0, 0, 0), (1e3, 1e3, 1e3)))
    with pytest.raises(ValueError, match="--sky air"):
        scene_spec(vol, (8, 8), sky="air")


def _trapezoid_march(atm, to_sun, o, d, t0, t1, table, wl, samples, shadow=None):
    """The single-scattering sums written out with numpy on (rays x samples x channels): the trapezoidal rule on
    s = t0 + (t1 - t0) x^2, the profiles at each sample's height above the sphere (the module docstring)."""
    from weather_mi.optics.rayleigh import cross_section_m2
    from weather_mi.optics.air.ozone import channel_cross_section_m2 as ozone_m2  # RGB: the band averages
    sun = np.asarray(to_sun) / np.linalg.norm(to_sun)
    x = np.linspace(0.0, 1.0, samples)
    s = t0[:, None] + np.maximum(t1 - t0, 0.0)[:, None] * x * x
    p = o[:, None, :] + s[..., None] * d[:, None, :]
    q = p + [0.0, 0.0, R_EARTH]
    r = np.linalg.norm(q, axis=-1)
    h, mu = np.maximum(r - R_EARTH, 0.0), (q @ sun) / r
    mol = atm.air_number_density_m3(h)[..., None] * cross_section_m2(wl * 1e-9)
    aer = atm.aerosol_extinction_550_per_m(h)[..., None] * (wl / 550.0) ** -atm.angstrom
    ext = mol + aer + atm.ozone_number_density_m3(h)[..., None] * ozone_m2(wl)
    ds = np.diff(s, axis=1)[..., None]
    tau = np.concatenate([np.zeros((len(o), 1, wl.size)), np.cumsum(0.5 * (ext[:, 1:] + ext[:, :-1]) * ds, 1)], 1)
    cos_t = (d @ sun)[:, None, None]
    src = (mol * _p_rayleigh(cos_t) + atm.aerosol_ssa * aer * _p_hg(atm.aerosol_g, cos_t)) * table.at(h, mu) \
        * np.exp(-tau) * (1.0 if shadow is None else shadow(p)[..., None])
    return np.exp(-tau[:, -1]), np.sum(0.5 * (src[:, 1:] + src[:, :-1]) * ds, axis=1)


@pytest.mark.parametrize("shadowed", [False, True])
def test_the_compiled_march_is_the_trapezoidal_sum(shadowed):
    """``segment_air``'s compiled march against the same trapezoidal sums in numpy (written out here) on 40
    random segments (an empty one among them), with and without a storm's shadow: within 1e-6 (the compiled
    march reads the profiles linear between heights 1 m apart)."""
    rng = np.random.default_rng(3)
    atm = Atmosphere(aod_550=0.3, ozone_atm_cm=0.4)
    o = np.c_[rng.uniform(-80e3, 80e3, (40, 2)), rng.uniform(0.0, 15e3, 40)]
    d = rng.normal(size=(40, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    t1 = np.where(top_distance(o, d) > 0, top_distance(o, d), 50e3) * rng.uniform(0.2, 1.0, 40)
    t0 = t1 * rng.uniform(0.0, 0.5, 40)
    t0[7] = t1[7] + 10.0
    shadow = (lambda p: 0.55 + 0.45 * np.tanh((p[..., 2] - 4e3) / 2e3)) if shadowed else None
    wl = np.array([650.0, 550.0, 450.0])
    t, s = segment_air(atm, SUN, o, d, t0, t1, _table(atm), samples=65, shadow=shadow)
    t_ref, s_ref = _trapezoid_march(atm, SUN, o, d, t0, t1, _table(atm), wl, 65, shadow)
    np.testing.assert_allclose(t, t_ref, rtol=1e-6)
    np.testing.assert_allclose(s, s_ref, rtol=1e-6, atol=1e-6 * s_ref.max())
    assert t[7] == pytest.approx([1.0, 1.0, 1.0]) and np.all(s[7] == 0.0) and np.all(s_ref[np.arange(40) != 7] > 0)


def test_a_band_given_three_times_is_marched_once_per_wavelength():
    """A satellite's channels (640, 470, 640 nm) and the sun's table at the same wavelengths: the channels that
    repeat a wavelength are the first one's, and every channel equals its own march alone."""
    atm = Atmosphere()
    o, d = np.array([[0.0, 0.0, 59e3], [20e3, 0.0, 59e3]]), np.array([[0.2, 0.0, -0.98], [0.0, 0.3, -0.95]])
    d /= np.linalg.norm(d, axis=1)[:, None]
    band = wide_sun_table(atm, float(SUN[2]), reach_m=400e3, n_mu=17, n_h=61, band_nm=(640.0, 470.0, 640.0))
    t, s = segment_air(atm, SUN, o, d, [0.0, 0.0], [50e3, 50e3], band, wavelengths_nm=(640.0, 470.0, 640.0))
    assert np.array_equal(t[:, 0], t[:, 2]) and np.array_equal(s[:, 0], s[:, 2]) and np.all(s[:, 1] > s[:, 0])
    for c, wl in ((0, 640.0), (1, 470.0)):
        one = replace(band, rgb=np.repeat(band.rgb[..., c:c + 1], 3, axis=-1))
        t1, s1 = segment_air(atm, SUN, o, d, [0.0, 0.0], [50e3, 50e3], one, wavelengths_nm=(wl, wl, wl))
        np.testing.assert_allclose(t[:, c], t1[:, 0], rtol=1e-12)
        np.testing.assert_allclose(s[:, c], s1[:, 0], rtol=1e-12)
