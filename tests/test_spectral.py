"""The spectral ground truth (issue 38 part 2): ``llvm_ad_spectral`` through ``hydrometeor_mixture`` and
``majorant_volpath``, checked against numbers computed here without the kernel: the phase tables at the
path's wavelengths, the species' co-albedo against Mie theory, a chromatic slab's CIE XYZ against DISORT
integrated over the solar spectrum, a white ground's colour against the sun's, and a grey cloud's luminance
against the RGB mode's. Every test puts the variant back as it found it."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.optics.phase import PhaseTable

SPECTRAL = "llvm_ad_spectral"
WL = np.arange(360.0, 830.0 + 0.1, 5.0)


def _astm_toa(wl):
    """ASTM G173-03 extraterrestrial irradiance (pvlib's copy), bin-averaged here on the 5 nm grid."""
    import pvlib
    ref = pvlib.spectrum.get_reference_spectra(standard="ASTM G173-03")
    lam, e = np.asarray(ref.index, float), np.asarray(ref["extraterrestrial"], float)
    fine = np.arange(wl[0] - 2.5, wl[-1] + 2.5, 0.1)
    return np.interp(fine, lam, e).reshape(wl.size, -1).mean(axis=1)


def _cmfs(wl):
    import colour
    return colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(
        colour.SpectralShape(wl[0], wl[-1], wl[1] - wl[0])).values


def _hg(g, mu):
    return (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * mu) ** 1.5)


# ---------------------------------------------------------------- optics by wavelength

def test_water_coalbedo_follows_mie_theory():
    """The cloud droplets' co-albedo spectrum (weak-absorption geometric optics, Hale & Querry's k) against
    miepython's Q_abs / Q_ext over a spread of radii about 10 um, at four wavelengths: within 30% (the
    formula's own accuracy at x ~ 100), across a 50-fold change of the co-albedo from 450 to 750 nm."""
    import miepython as mp
    from weather_mi.optics.spectral import species_coalbedo, water_nk
    cloud = wm.species.preset("physical")["cloud"]
    wl = np.array([450.0, 550.0, 650.0, 750.0])
    ours = species_coalbedo(cloud, wl)
    radii = np.linspace(8e-6, 12e-6, 41)
    for lam, c in zip(wl, ours):
        n, k = water_nk(lam)
        qext, qsca = np.transpose([mp.efficiencies_mx(complex(n, -k), 2 * np.pi * r / (lam * 1e-9))[:2]
                                   for r in radii])
        mie = 1.0 - np.sum(qsca * radii ** 2) / np.sum(qext * radii ** 2)
        assert c == pytest.approx(mie, rel=0.3), lam
    assert ours[3] / ours[0] > 20


def test_coalbedo_keeps_the_species_own_albedo_at_550nm():
    """Presets and overrides carry over: at 550 nm the co-albedo is 1 - the species' green albedo."""
    from weather_mi.optics.spectral import coalbedo_table
    species = wm.species.preset("physical")
    table = coalbedo_table([species[n] for n in species.names])
    np.testing.assert_allclose(table[:, -1], [1 - species[n].albedo_rgb[1] for n in species.names], rtol=1e-12)
    assert np.all(np.diff(table[:, [0, -2]], axis=1) > 0)  # every species absorbs more at 830 than at 360 nm


def test_phase_plugin_interpolates_the_tables_at_the_path_wavelengths(variant_restored):
    """``hydrometeor_mixture`` in ``llvm_ad_spectral``: eval_pdf at four wavelengths per lane is the R, G, B
    tables (HG g = 0.3 / 0.6 / 0.85 at 650 / 550 / 450 nm) interpolated linearly in wavelength (constant
    beyond the ends), computed here with numpy; the pdf is the channel mean's."""
    import drjit as dr
    import mitsuba as mi
    from weather_mi.kernel.plugins.hydrometeor_mixture import prepare_tables
    wm.set_variant(SPECTRAL)
    theta = np.unique(np.concatenate([np.linspace(0, np.pi, 2001), np.geomspace(1e-4, 0.2, 400)]))
    g = (0.3, 0.6, 0.85)
    table = PhaseTable.from_values(theta, np.stack([_hg(gc, np.cos(theta)) for gc in g], -1),
                                                   name="hg3")
    nodes, values = prepare_tables([table])
    phase = mi.load_dict({"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]),
                          "values": mi.TensorXf(values), "weights": mi.TensorXf(np.ones((1, 1, 1, 1), np.float32))})
    lanes = np.array([[380.0, 450.0, 500.0, 550.0], [600.0, 650.0, 700.0, 829.0]])
    cos = np.array([0.9, -0.5])
    mei = dr.zeros(mi.MediumInteraction3f, 2)
    mei.wi = mi.Vector3f(0, 0, -1)  # light travelling +z: forward is +z
    mei.sh_frame = mi.Frame3f(mei.wi)
    mei.wavelengths = mi.Spectrum(*(mi.Float(lanes[:, i]) for i in range(4)))
    wo = mi.Vector3f(np.sqrt(1 - cos ** 2), 0 * cos, cos)
    value, pdf = phase.eval_pdf(mi.PhaseFunctionContext(None), mei, wo)
    value = np.array(value).T  # (2 directions, 4 lanes)
    for j in range(2):
        mu = cos[j]
        v = 1 - mu
        per_channel = [np.interp(v, nodes, values[0, :, c]) for c in range(3)]  # the plugin's own tables
        expect = np.interp(lanes[j], [450.0, 550.0, 650.0], per_channel[::-1])
        np.testing.assert_allclose(value[j], expect, rtol=2e-3)
        np.testing.assert_allclose(value[j], np.interp(lanes[j], [450, 550, 650], [_hg(gc, mu) for gc in g[::-1]]),
                                   rtol=0.03)  # and the HG functions themselves
        assert np.array(pdf)[j] == pytest.approx(np.mean(per_channel), rel=2e-3)


def test_albedo_at_mixes_the_species_coalbedo_spectra(variant_restored):
    """``albedo_at``: 1 - (1 - omega_ref) sum_s w_s c_s(lambda) / sum_s w_s c_s(550), the co-albedo spectra
    interpolated linearly on their grid, computed here with numpy for two species and four wavelengths."""
    import drjit as dr
    import mitsuba as mi
    wm.set_variant(SPECTRAL)
    grid = np.array([400.0, 500.0, 600.0, 700.0])
    co = np.array([[1e-5, 2e-5, 4e-5, 8e-5, 3e-5], [1e-3, 1e-3, 3e-3, 5e-3, 2e-3]], np.float32)  # last: at 550
    w = np.array([3.0, 1.0], np.float32)
    phase = mi.load_dict({"type": "hydrometeor_mixture", "nodes": mi.TensorXf(np.array([[0.0], [2.0]], np.float32)),
                          "values": mi.TensorXf(np.full((2, 2, 3), 1 / (4 * np.pi), np.float32)),
                          "weights": mi.TensorXf(np.broadcast_to(w, (1, 1, 1, 2)).copy()),
                          "coalbedo": mi.TensorXf(co), "coalbedo_nm": mi.TensorXf(grid.astype(np.float32))})
    lanes = np.array([380.0, 450.0, 650.0, 800.0])
    mei = dr.zeros(mi.MediumInteraction3f, 1)
    mei.wavelengths = mi.Spectrum(*(mi.Float([v]) for v in lanes))
    got = np.array(phase.albedo_at(mei, mi.Float(0.999))).ravel()
    c = np.array([np.interp(lanes, grid, co[s, :4]) for s in range(2)])
    expect = 1 - (1 - 0.999) * (w @ c) / (w @ co[:, 4])
    np.testing.assert_allclose(got, expect, rtol=0, atol=2e-7)
    assert got[0] > got[-1] + 1e-4  # the check can fail: red absorbs more


# ---------------------------------------------------------------- renders against independent numbers

def _lerp_moments(lam, n_moments=256):
    """Legendre moments of the kernel's phase at ``lam`` nm: (1 - t) HG(g_a) + t HG(g_b), the tables at the
    channel wavelengths 650 / 550 / 450 nm (g 0.3 / 0.6 / 0.85) mixed linearly, constant beyond."""
    l = np.arange(n_moments + 1)
    gs, nodes = (0.85, 0.6, 0.3), (450.0, 550.0, 650.0)
    lam = float(np.clip(lam, 450.0, 650.0))
    i = 0 if lam <= 550.0 else 1
    t = (lam - nodes[i]) / 100.0
    return (1 - t) * gs[i] ** l + t * gs[i + 1] ** l


def test_chromatic_slab_xyz_against_disort(variant_restored):
    """A slab (tau 1, albedo 1, mu0 0.6) whose phase function changes with wavelength (HG g 0.85 at 450 nm
    to 0.3 at 650 nm), lit by the top-of-atmosphere sun: the nadir reflectance's CIE X, Y, Z from the spectral
    variant against DISORT solved at every 5 nm with the phase function the kernel holds there, integrated
    over the ASTM G173 spectrum and the CIE 1931 functions here (luminance 1 for the sun): within 3 standard
    errors and 0.01. Z is 0.4 times, X 1.3 times what a grey slab with the 550 nm phase function gives."""
    from weather_mi.optics.disort import solve
    from weather_mi.plane_parallel.slab import GAP, slab_volume, sun_for
    theta = np.unique(np.concatenate([np.linspace(0, np.pi, 2001), np.geomspace(1e-4, 0.2, 400)]))
    table = PhaseTable.from_values(
        theta, np.stack([_hg(g, np.cos(theta)) for g in (0.3, 0.6, 0.85)], -1), name="hg3")
    tau, mu0 = 1.0, 0.6
    vol = slab_volume(tau, 1.0, table)
    cam = wm.Camera.orthographic(center=(0.0, 0.0, 1.0 + 10 * GAP), direction=(0.0, 0.0, -1.0), width=0.01, height=0.01)
    spec = wm.SceneSpec(camera=cam, sun=sun_for(mu0), sky=None, ground=None, width=8, height=8)
    img = wm.render_reference(spec, vol, spp=512, passes=8, normalize="reflectance", progress=False, variant=SPECTRAL)
    refl = np.array([np.pi * solve([tau], [1.0], mu0, [1.0], [0.0], [0.0], moments=_lerp_moments(lam)[None]
                                   ).intensities(0, 0, 0) / mu0 for lam in WL])
    sun = _astm_toa(WL)
    cmf = _cmfs(WL)
    expect = (sun * refl) @ cmf / (sun @ cmf[:, 1])
    grey = (sun @ cmf) / (sun @ cmf[:, 1]) * refl[WL == 550.0]
    got = img.xyz.reshape(-1, 3).astype(float).mean(axis=0)
    from weather_mi.optics.spectrum import xyz_of_linear_srgb
    se = np.abs(xyz_of_linear_srgb(img.stderr.reshape(-1, 3).mean(axis=0))) / 8  # ~ over 64 pixels
    assert np.all(np.abs(got - expect) <= np.maximum(3 * se, 0.002)) and np.all(np.abs(got - expect) < 0.01), (got, expect, se)
    assert expect[2] / grey[2] < 0.6 and expect[0] / grey[0] > 1.1  # the check can fail: a chromatic slab


def test_white_ground_has_the_suns_colour(variant_restored):
    """A white Lambertian ground at sea level under a 20 deg sun through a clear atmosphere (AOD 0.2): its
    CIE XYZ is the direct sun's there times mu0 / pi, the sun's spectrum computed here from pvlib's ASTM G173
    table, the air's transmittance and colour-science's CIE 1931 functions (luminance 1 above the air):
    within 1.5% per component."""
    from weather_mi.optics.air import Atmosphere
    from weather_mi.optics.air.sunlight import transmittance
    atm = Atmosphere(aod_550=0.2)
    mu0 = np.sin(np.radians(20.0))
    box = ((-500.0, -500.0, 3000.0), (500.0, 500.0, 3100.0))
    vol = wm.OpticalVolume.from_arrays(beta_ext=np.zeros((2, 2, 2), np.float32), albedo=1.0,
                                       phase=wm.phase.henyey_greenstein(0.5), bbox=box)
    cam = wm.Camera.orthographic(center=(2000.0, 0.0, 100.0), direction=(0.0, 0.0, -1.0), width=50, height=50)
    spec = wm.SceneSpec(camera=cam, sun=wm.Sun(180.0, 20.0, angular_diameter_deg=0.53), sky=None,
                        ground=wm.Ground(height=0.0, albedo=(1.0, 1.0, 1.0)), width=4, height=4, atmosphere=atm)
    img = wm.render_reference(spec, vol, spp=64, progress=False, variant=SPECTRAL)
    sun = _astm_toa(WL)
    cmf = _cmfs(WL)
    expect = (sun * transmittance(atm, WL, 0.0, mu0)) @ cmf / (sun @ cmf[:, 1]) * mu0 / np.pi
    np.testing.assert_allclose(img.xyz.reshape(-1, 3).mean(axis=0), expect, rtol=0.015)
    assert expect[2] / expect[1] < 0.9  # a visibly yellow sun: the check can fail


def test_grey_cloud_luminance_equals_the_rgb_mode(variant_restored):
    """A grey medium (albedo 1, one HG phase), no atmosphere: the spectral luminance Y equals the RGB mode's
    (a white sun of luminance 1 in both) within 3 combined standard errors."""
    box = ((-4000.0, -4000.0, 6000.0), (4000.0, 4000.0, 6400.0))
    vol = wm.OpticalVolume.from_arrays(beta_ext=np.full((2, 4, 4), 0.004, np.float32), albedo=1.0,
                                       phase=wm.phase.henyey_greenstein(0.7), bbox=box)
    cam = wm.Camera.orthographic(center=(0.0, 0.0, 9000.0), direction=(0.0, 0.0, -1.0), width=6000, height=6000)
    spec = wm.SceneSpec(camera=cam, sun=wm.Sun(200.0, 35.0, angular_diameter_deg=0.53), sky=None, ground=None,
                        width=8, height=8)
    y = {}
    for v in ("llvm_ad_rgb", SPECTRAL):
        img = wm.render_reference(spec, vol, spp=1024, passes=8, progress=False, variant=v)
        lum = img.xyz[..., 1] if img.xyz is not None else img.radiance @ np.array([0.2126, 0.7152, 0.0722])
        n = lum.size
        se = img.stderr.mean(axis=2)
        y[v] = (float(lum.mean()), float(np.sqrt(np.sum(se ** 2)) / n))
    (a, sa), (b, sb) = y.values()
    assert abs(a - b) <= 3 * np.hypot(sa, sb), y
    assert sa < 0.015 * a and sb < 0.015 * b  # noise small enough for the check to fail


# ---------------------------------------------------------------- the command line

def test_render_without_a_spectral_variant_fails_before_rendering(tmp_path, capsys, monkeypatch):
    import mitsuba as mi
    from weather_mi.cli import commands as cli
    from weather_mi.reference import render as reference_module
    monkeypatch.setattr(mi, "variants", lambda: ["scalar_rgb", "llvm_ad_rgb"])
    monkeypatch.setattr(reference_module, "render_reference", lambda *a, **k: pytest.fail("rendering started"))
    rc = cli.main(["render", "--demo", "cumulus", "--size", "8x6", "--spp", "1", "--spectral", "-o",
                   str(tmp_path / "a.exr")])
    err = capsys.readouterr().err
    assert rc == 2 and "spectral variant" in err and "Traceback" not in err


def test_white_balance_scene_needs_spectral(tmp_path, capsys):
    from weather_mi.cli import commands as cli
    rc = cli.main(["render", "--demo", "cumulus", "--size", "8x6", "--spp", "1", "--white-balance", "scene", "-o",
                   str(tmp_path / "a.exr")])
    assert rc == 2 and "--spectral" in capsys.readouterr().err


def test_scene_white_balance_makes_the_suns_white_neutral():
    """CAT02 adaptation to the scene's sun: the sun's own colour becomes neutral (R = G = B)."""
    from weather_mi.display.white_balance import adapted_to, scene_white_xyz
    from weather_mi.optics.air import Atmosphere
    from weather_mi.optics.spectrum import linear_srgb
    from types import SimpleNamespace
    spec = SimpleNamespace(sun=wm.Sun(260.0, 4.0), atmosphere=Atmosphere())
    white = scene_white_xyz(spec, 3000.0)
    rgb = linear_srgb(white)
    assert rgb[2] / rgb[0] < 0.6  # a low sun is orange as a daylight camera records it
    out = adapted_to(rgb, white)
    np.testing.assert_allclose(out, out.mean(), rtol=1e-3)
