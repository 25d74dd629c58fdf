"""The sun as a disk (issue 10): its irradiance, the MIS of next-event estimation and phase sampling,
the estimator's fireflies, and the checks on the sun's size.

Reference numbers come from closed forms (a Lambertian ground: L = rho E mu0 / pi) or from the
integrator's own strategies taken one at a time (NEE only, phase sampling only: each unbiased on its
own, so all three must agree within noise).
"""
from __future__ import annotations

import numpy as np
import pytest

import mitsuba as mi

import weather_mi as wm
from weather_mi.kernel.scene_dict import integrator_dict
from weather_mi.kernel.scene_dict import recentred, scene_dict

BBOX = ((0.0, 0.0, 1000.0), (1000.0, 1000.0, 1400.0))
DOWN = wm.Camera.orthographic(center=(500.0, 500.0, 3000.0), direction=(0.0, 0.0, -1.0), width=600, height=600)


def slab(beta=0.004, g=0.8, albedo=1.0, n=4):
    return wm.OpticalVolume.from_arrays(beta_ext=np.full((n, n, n), beta, np.float32), albedo=albedo,
                                        phase=wm.phase.henyey_greenstein(g), bbox=BBOX)


def test_disk_irradiance_equals_the_point_suns_on_a_lambertian_ground():
    """An empty volume over a grey ground: radiance = albedo E mu0 / pi, for the disk and the point."""
    vol = slab(beta=0.0)
    sun_el, rho = 40.0, 0.5
    expect = rho * np.array([1.0, 0.8, 0.6]) * np.sin(np.radians(sun_el)) / np.pi
    for diameter in (0.0, 0.53, 5.0):
        spec = wm.SceneSpec(camera=DOWN, sun=wm.Sun(200.0, sun_el, irradiance=(1.0, 0.8, 0.6),
                                                    angular_diameter_deg=diameter),
                            sky=None, ground=wm.Ground(albedo=rho), width=8, height=8)
        img = wm.render_reference(spec, vol, spp=16, passes=4, progress=False)
        got = img.radiance.reshape(-1, 3).mean(axis=0)
        # a disk of radius r averages cos over the cap: relative change <= r^2 / 2 (2.4e-4 at 5 deg)
        np.testing.assert_allclose(got, expect, rtol=2e-3, err_msg=f"diameter {diameter}")


def _render_strategy(strategy, spp=256, seed=0, guiding=0.0):
    vol = slab()
    spec = wm.SceneSpec(camera=DOWN, sun=wm.Sun(200.0, 50.0, angular_diameter_deg=5.0), sky=None, ground=None,
                        width=8, height=8, seed=seed)
    spec_k, vol_k, _ = recentred(spec, vol)
    integ = integrator_dict(vol_k, "majorant", -1, sun=spec.sun, sun_guiding=guiding)
    integ["sun_sampling"] = strategy
    scene = mi.load_dict(scene_dict(spec_k, vol_k, integ))
    passes = np.stack([np.array(mi.render(scene, spp=spp // 16, seed=1000 * seed + i))[..., :3].mean()
                       for i in range(16)])
    return passes.mean(), passes.std(ddof=1) / np.sqrt(passes.size)


def test_nee_only_phase_only_and_mis_agree_under_a_disk_sun():
    """A forward-scattering slab (HG 0.8, optical depth 1.6) under a 5 deg sun seen from above."""
    mis, se_mis = _render_strategy("mis")
    nee, se_nee = _render_strategy("nee")
    phase, se_phase = _render_strategy("phase", spp=1024)
    assert mis > 0.005
    for name, v, se in (("nee", nee, se_nee), ("phase", phase, se_phase)):
        assert abs(v - mis) < 4 * np.hypot(se, se_mis), f"{name}: {v} +- {se} vs MIS {mis} +- {se_mis}"
    assert se_mis < se_phase  # MIS is the better of the strategies where they differ
    # sun guiding changes the continuation pdf in both MIS weights: the estimate must not move
    guided, se_g = _render_strategy("mis", guiding=0.5, seed=1)
    assert abs(guided - mis) < 4 * np.hypot(se_g, se_mis), f"guided {guided} +- {se_g} vs {mis} +- {se_mis}"


def chromatic_table():
    """HG with g = 0.9 / 0.5 / 0 in R / G / B: sampled by channel mean, each event multiplies a channel's
    weight by p_c / mean_c p_c, up to 3."""
    from weather_mi.optics.phase.analytic import hg_value
    th = wm.phase.henyey_greenstein(0.5).theta
    return wm.phase.PhaseTable(th, np.stack([hg_value(g, np.cos(th)) for g in (0.9, 0.5, 0.0)], axis=1))


def test_fireflies_of_the_old_estimator_are_gone_in_a_white_furnace():
    """Issue 10's fireflies, root cause: in a non-absorbing medium the old estimator (Russian roulette
    as Mitsuba's volpath, survival capped at 0.95, and phase sampling by channel mean) multiplies a
    surviving path's weight by 1/0.95 per event and each colour channel's by up to 3 per event: a
    heavy-tailed, rare-event estimator. A white furnace (albedo 1 under a sky of radiance 1) must
    render exactly 1 in every channel, whatever the phase function; optical depth 30, chromatic phase."""
    vol = wm.OpticalVolume.from_arrays(beta_ext=np.full((4, 4, 4), 0.03, np.float32), albedo=1.0,
                                       phase=chromatic_table(), bbox=((0.0, 0.0, 0.0), (1000.0, 1000.0, 1000.0)))
    cam = wm.Camera.orthographic(center=(500.0, -2000.0, 500.0), direction=(0.0, 1.0, 0.0), width=800, height=800)
    spec = wm.SceneSpec(camera=cam, sun=wm.Sun(200.0, 40.0, irradiance=0.0, angular_diameter_deg=0.0),
                        sky=wm.Sky("constant", radiance=1.0), ground=None, width=8, height=8, seed=3)
    worst = {}
    for legacy in (True, False):
        img = wm.render_reference(spec, vol, spp=64, progress=False, legacy=legacy)
        worst[legacy] = img.metadata["noise"]["worst_se_over_mean"]
        mean = img.radiance.reshape(-1, 3).mean(axis=0)
        se = np.sqrt((img.stderr.reshape(-1, 3) ** 2).sum(axis=0)) / 64
        if not legacy:
            assert np.all(np.abs(mean - 1.0) < 4 * se + 0.01), (mean, se)
    assert worst[True] > 2.0, f"the test cannot fail: the old estimator gives {worst[True]}"
    assert worst[False] < 1.0, worst


@pytest.mark.parametrize("diameter", [-0.1, 5.5, float("nan"), "0.5", True])
def test_bad_sun_diameters_are_refused(diameter):
    with pytest.raises(ValueError, match="angular_diameter_deg"):
        wm.Sun(200.0, 40.0, angular_diameter_deg=diameter)


def test_a_disk_sun_needs_the_majorant_integrator(monkeypatch):
    for name in ("render_pass", "render_passes"):
        monkeypatch.setattr(wm.reference.passes, name, lambda *a, **k: pytest.fail("rendered"))
    spec = wm.SceneSpec(camera=DOWN, sun=wm.Sun(200.0, 40.0), width=4, height=4)
    with pytest.raises(ValueError, match="angular_diameter_deg=0"):
        wm.render_reference(spec, slab(), spp=4, integrator="volpath", progress=False)
    with pytest.raises(ValueError, match="sun_guiding"):
        wm.render_reference(spec, slab(), spp=4, sun_guiding=1.5, progress=False)
    with pytest.raises(ValueError, match="target_rse"):
        wm.render_reference(spec, slab(), spp=4, target_rse=0.0, progress=False)
