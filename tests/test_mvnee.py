"""Multiple-vertex next-event estimation (``weather_mi/kernel/plugins/mvnee.py``, ``render_reference(mvnee=...)``).

Reference numbers that did not come from our code: DISORT (``disortpp``) radiances of homogeneous HG
slabs (the estimator with chains must reproduce them: the chains and the path's own sun NEE share the
sun light by MIS weights that sum to one), the normalisation of the chain's direction density over the
sphere (numerical quadrature), and a deliberately wrong weight (the path's own NEE left at full
weight, i.e. the chains' light counted twice) that the DISORT check must reject.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.plane_parallel import slab

disortpp = pytest.importorskip("disortpp")


def _slab(tau, albedo, g, mu0, view, spp, seed, diameter=0.0, **kw):
    """pi L / (mu0 E) of the slab's centre (as ``slab.slab_radiance``) by ``majorant_volpath`` with its
    own sun: (mean, standard error)."""
    vol = slab.slab_volume(tau, albedo, wm.phase.henyey_greenstein(g))
    z, d = ((1.0 + 10 * slab.GAP), -1.0) if view == "nadir" else (-10 * slab.GAP, 1.0)
    cam = wm.Camera.orthographic(center=(0.0, 0.0, z), direction=(0.0, 0.0, d), width=0.01, height=0.01)
    sun = slab.sun_for(mu0)
    if diameter:
        sun = wm.Sun(azimuth=sun.azimuth, elevation=sun.elevation, angular_diameter_deg=diameter)
    spec = wm.SceneSpec(camera=cam, sun=sun, sky=None, ground=None, width=8, height=8, seed=seed)
    img = wm.render_reference(spec, vol, spp=spp, passes=16, normalize="reflectance", progress=False,
                              forward_peak_deg=0.0, **kw)
    rad = img.radiance.astype(np.float64).mean(axis=2)
    se = img.stderr.astype(np.float64).mean(axis=2)
    return float(rad.mean()), float(np.sqrt(np.sum(se ** 2)) / rad.size)


# g = 0.85 (cloud-like), transmitted and reflected; an oblique sun so that the camera looking up does not
# look into it
CASES = [(0.85, 0.99, 4.0, 0.5, "zenith"), (0.85, 0.99, 4.0, 0.5, "nadir")]


@pytest.mark.parametrize("g, albedo, tau, mu0, view", CASES)
def test_slab_with_chains_against_disort(g, albedo, tau, mu0, view):
    ref = slab.disort_slab(tau, albedo, g, mu0)["L_zenith" if view == "zenith" else "L_nadir"]
    mc, se = _slab(tau, albedo, g, mu0, view, spp=1024, seed=5, mvnee=0.5)
    assert se > 0 and slab.agrees(mc, se, ref, abs_tol=0.01), (mc, se, ref)  # <= 3 se and <= 0.01


def test_a_wrong_weight_is_caught(monkeypatch):
    """The path's own sun NEE at full weight (the chains' share counted twice) reads high by many se."""
    from weather_mi.kernel.plugins import mvnee
    g, albedo, tau, mu0, view = CASES[0]
    ref = slab.disort_slab(tau, albedo, g, mu0)["L_zenith"]
    monkeypatch.setattr(mvnee, "path_weight", lambda r: r[0] * 0.0 + 1.0)
    mc, se = _slab(tau, albedo, g, mu0, view, spp=1024, seed=5, mvnee=0.5)
    assert mc - ref > 6 * se and mc - ref > 0.02, (mc, se, ref)


@pytest.mark.parametrize("length", [1, 4])
def test_chain_lengths_and_a_disk_sun_leave_the_estimate_unchanged(length, monkeypatch):
    """Against the estimator without chains, in the same slab (z-test), for chain lengths 1 and 4 and a
    5-degree disk (half the chain's directions uniform in the disk)."""
    from weather_mi.kernel.plugins import mvnee
    monkeypatch.setattr(mvnee, "DEFAULT_LENGTH", length)
    args = (4.0, 0.99, 0.85, 0.5, "zenith")
    plain, se_p = _slab(*args, spp=512, seed=1, diameter=5.0)
    chains, se_c = _slab(*args, spp=512, seed=2, diameter=5.0, mvnee=0.5)
    assert abs(chains - plain) < 4 * math.hypot(se_p, se_c), (chains, se_c, plain, se_p)


@pytest.mark.parametrize("value, message", [(1.5, "'mvnee' must be a probability"),
                                            (-0.1, "'mvnee' must be a probability")])
def test_bad_probabilities_are_refused(value, message):
    with pytest.raises(ValueError, match="mvnee"):
        wm.render_reference(wm.SceneSpec(camera=wm.Camera.orthographic(center=(0, 0, 2), direction=(0, 0, -1),
                                                                       width=0.01, height=0.01),
                                         sun=slab.sun_for(0.5), sky=None, ground=None, width=2, height=2),
                            slab.slab_volume(1.0, 0.9, wm.phase.henyey_greenstein(0.5)), spp=1,
                            progress=False, mvnee=value)


@pytest.mark.parametrize("length", [0, 5, 2.5, True])
def test_bad_chain_lengths_are_refused(length):
    import mitsuba as mi
    wm.set_variant()
    from weather_mi.kernel.plugins import majorant_volpath  # noqa: F401 (registers)
    wm.kernel.scene_dict.ensure_registered()
    with pytest.raises(Exception, match="mvnee_length"):
        mi.load_dict({"type": "majorant_volpath", "sun_direction": [0, 0, 1], "mvnee": 0.5, "mvnee_length": length})


@pytest.mark.parametrize("diameter", [0.0, 5.0])
def test_chain_direction_density_is_normalised(diameter):
    """The density g of a chain's direction (``sun.aureole_pdf``: the phase function about the sun, half
    of it uniform in the disk) integrates to 1 over the sphere (quadrature in the angle from the sun;
    the disk's part resolved by its own nodes)."""
    import drjit as dr
    import mitsuba as mi
    wm.set_variant()
    from weather_mi.kernel.plugins import sun as sun_mod
    vmax, _ = sun_mod.sun_disk(diameter, 1.0)

    class Sun:
        sun_dir = mi.Vector3f(0.0, 0.0, 1.0)
        sun_vmax = mi.Float(vmax)
        sun_mode = "disk" if diameter > 0 else "point"

    phase = mi.load_dict({"type": "hg", "g": 0.85})
    r = math.radians(diameter) / 2
    theta = np.concatenate([np.linspace(0.0, r, 2001, endpoint=False), np.geomspace(max(r, 1e-6), math.pi, 20001)])
    theta = np.unique(theta)
    d = mi.Vector3f(np.sin(theta), 0.0 * theta, np.cos(theta))
    mei = dr.zeros(mi.MediumInteraction3f, len(theta))
    mei.wi = mi.Vector3f(1.0, 0.0, 0.0)  # any incident direction: g does not depend on it
    mei.sh_frame = mi.Frame3f(mei.wi)
    pdf = np.asarray(sun_mod.aureole_pdf(Sun, phase, None, mei, d, mi.Bool(True)), np.float64)
    integral = 2 * np.pi * np.trapezoid(pdf * np.sin(theta), theta)
    assert integral == pytest.approx(1.0, abs=3e-3)
