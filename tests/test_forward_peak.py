"""Forward peaks counted as unscattered light (delta-M, weather_mi.optics.forward_peak) and the aureole
estimator of majorant_volpath (``aureole_nee``).

Reference numbers: a phase function built as f x (a narrow lobe) + (1 - f) x isotropic, whose peak
share and truncated table are known in closed form; the delta-M relations sigma_t' = sigma_t (1 -
omega f), omega' = omega (1 - f) / (1 - omega f) (Wiscombe 1977); and, for the stochastic forms,
agreement within noise with the estimator without them (the aureole estimator is an MIS partner of
the path's own sampling: the estimate must not move).
"""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.optics.forward_peak import check_cone_deg, delta_scaled, peak_excess, truncated_table

LOBE_DEG = 0.02
F_PEAK = 0.4
BBOX = ((0.0, 0.0, 1000.0), (1000.0, 1000.0, 1400.0))


def peaked_table(f=F_PEAK):
    """f x a Gaussian lobe of width LOBE_DEG (normalised over the sphere) + (1 - f) x isotropic."""
    theta = np.union1d(wm.phase.table.angle_grid(), np.deg2rad(np.linspace(0, 0.2, 201)))
    s = np.deg2rad(LOBE_DEG)
    lobe = np.exp(-0.5 * (theta / s) ** 2) / (2 * np.pi * s * s)  # small-angle normalisation
    return wm.phase.PhaseTable(theta, f * lobe + (1 - f) / (4 * np.pi))


def test_peak_share_and_truncated_table_match_the_construction():
    t = peaked_table()
    f = peak_excess(t, 0.5)
    np.testing.assert_allclose(f, F_PEAK, rtol=2e-3)
    tt = truncated_table(t, 0.5, float(f.min()))
    np.testing.assert_allclose(tt.total, 1.0, rtol=1e-9)
    far = np.deg2rad([1.0, 30.0, 120.0])
    np.testing.assert_allclose(tt.eval(far), 1 / (4 * np.pi), rtol=3e-3)  # the isotropic rest
    np.testing.assert_allclose(tt.eval(np.deg2rad([0.0, 0.3])), 1 / (4 * np.pi), rtol=3e-3)  # flattened


def test_channels_with_different_peaks_keep_no_narrow_residual():
    """Peak shares 0.3 / 0.35 / 0.4 in R / G / B: 0.3 leaves every channel, and the rest of each
    channel's peak (0, 0.05, 0.1) is spread evenly over the cone, not left as a narrow spike."""
    tables = [peaked_table(f) for f in (0.3, 0.35, 0.4)]
    t = wm.phase.PhaseTable(tables[0].theta, np.stack([tb.values[:, c] for c, tb in enumerate(tables)], axis=1))
    f = float(peak_excess(t, 0.5).min())
    assert f == pytest.approx(0.3, rel=3e-3)
    tt = truncated_table(t, 0.5, f)
    cone = 2 * np.pi * (1 - np.cos(np.deg2rad(0.5)))
    inside = tt.eval(np.deg2rad([0.0, 0.25, 0.45]))
    np.testing.assert_allclose(inside, inside[[0]].repeat(3, axis=0), rtol=1e-6)  # flat in the cone
    rest = np.array([0.7, 0.65, 0.6]) / (4 * np.pi)  # the isotropic part, per channel
    expect = (rest + np.maximum(np.array([0.3, 0.35, 0.4]) - f, 0.0) / cone) / (1 - f)
    np.testing.assert_allclose(inside[0], expect, rtol=5e-3)


def test_delta_scaled_volume_follows_delta_m():
    omega = 0.9
    vol = wm.OpticalVolume.from_arrays(np.full((2, 2, 2), 0.01, np.float32), albedo=omega, phase=peaked_table(),
                                       bbox=BBOX)
    out = delta_scaled(vol, 0.5)
    f = F_PEAK  # the construction's share (the lobe is 1e-4 of its mass wider than the cone)
    np.testing.assert_allclose(out.beta_total, 0.01 * (1 - omega * f), rtol=1e-3)
    np.testing.assert_allclose(out.albedo, omega * (1 - f) / (1 - omega * f), rtol=1e-3)
    np.testing.assert_allclose(out.beta_ext.sum(axis=0), out.beta_total, rtol=1e-6)
    assert delta_scaled(vol, 0.0) is vol


@pytest.mark.parametrize("cone", [-0.1, 11.0, float("nan"), "0.1", True])
def test_bad_cones_are_refused(cone):
    with pytest.raises(ValueError):
        check_cone_deg(cone)


def _slab_mean(spp=512, seed=0, sky=False, diameter=0.0, phase=None, **kw):
    vol = wm.OpticalVolume.from_arrays(np.full((4, 4, 4), 0.004, np.float32), albedo=0.95,
                                       phase=phase or peaked_table(), bbox=BBOX)
    cam = wm.Camera.orthographic(center=(500.0, 500.0, 3000.0), direction=(0.0, 0.0, -1.0), width=600, height=600)
    sun = wm.Sun(200.0, 50.0, irradiance=0.0 if sky else 1.0, angular_diameter_deg=diameter)
    spec = wm.SceneSpec(camera=cam, sun=sun, sky=wm.Sky("constant", radiance=1.0) if sky else None, ground=None,
                        width=8, height=8, seed=seed)
    img = wm.render_reference(spec, vol, spp=spp, progress=False, **kw)
    lum = img.radiance.mean(axis=2)
    se = np.sqrt((img.stderr.mean(axis=2) ** 2).sum()) / lum.size
    return float(lum.mean()), float(se)


def test_delta_m_slab_equals_the_full_phase_function_under_a_uniform_sky():
    """Scattering exactly forward is no scattering (the transfer equation with p = f delta + (1 - f) p'
    is the delta-M one): under a uniform sky, where the estimator with the full table converges,
    both must agree. (Under a point sun they do not at practical spp: the forward-scattered sun beam
    is reached only by rare paths aimed within the lobe's 0.02 deg, so the full table reads ~22% low
    here; that is the fireflies' mechanism, see the module doc of weather_mi.optics.forward_peak.)"""
    full, se_f = _slab_mean(sky=True, forward_peak_deg=0.0)
    delta, se_d = _slab_mean(sky=True, forward_peak_deg=0.5, seed=1)
    assert abs(full - delta) < 4 * np.hypot(se_f, se_d), (full, se_f, delta, se_d)
    # the test can fail: the truncated table alone, the extinction left as it is (the lobe's light
    # scattered isotropically instead of passing straight), reads differently
    wrong, se_w = _slab_mean(sky=True, forward_peak_deg=0.0, phase=truncated_table(peaked_table(), 0.5, F_PEAK),
                             seed=2)
    assert abs(wrong - delta) > 4 * np.hypot(se_w, se_d), (wrong, se_w, delta, se_d)


@pytest.mark.parametrize("diameter", [0.0, 5.0])
def test_aureole_estimator_leaves_the_estimate_unchanged(diameter):
    """A point sun, and a disk (the estimator then draws half its directions uniformly in the disk)."""
    plain, se_p = _slab_mean(forward_peak_deg=0.5, diameter=diameter)
    aureole, se_a = _slab_mean(forward_peak_deg=0.5, aureole_nee=1.0, diameter=diameter, seed=2)
    assert plain > 1e-3
    assert abs(aureole - plain) < 4 * np.hypot(se_p, se_a), (aureole, se_a, plain, se_p)


def test_delta_scaled_for_the_kernel_keeps_the_species_extinction_unscaled():
    """``species_extinction=False`` (the path tracer's medium): beta_total, albedo and weights as the full
    delta scaling, bit for bit, the per-species beta_s the input's own array (no copy); with it, the scaled
    beta_s sum to the scaled beta_total (Eq. 6) and lie below the input's."""
    vol = wm.optical_volume(wm.synthetic.cumulus(), "physical", phase_quality="test")
    full = delta_scaled(vol, 3.0)
    lean = delta_scaled(vol, 3.0, species_extinction=False)
    for name in ("beta_total", "albedo", "weights"):
        np.testing.assert_array_equal(getattr(lean, name), getattr(full, name))
    assert np.shares_memory(lean.beta_ext, vol.beta_ext)
    assert full.beta_total.sum() < vol.beta_total.sum()
    np.testing.assert_allclose(full.beta_ext.sum(axis=0), full.beta_total, rtol=1e-5, atol=1e-9)
    assert np.all(full.beta_ext <= vol.beta_ext)
