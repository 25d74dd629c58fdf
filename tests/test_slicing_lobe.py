"""The "multiple" light model's diffused forward lobe (SliceParams.diffusion_lobe) and the shadowed ground
under a cloud's base (SliceParams.below_shadow) against closed forms: the lobe moves diffused light from
the isotropic phase to the phase function, so that what it adds is proportional to P(Theta) - 1 / (4 pi)
(Henyey-Greenstein's, evaluated here) and nothing for an isotropic phase; the light from below a cloud is
dimmed by the delta-Eddington transmission of the column above the ground beneath it (Joseph, Wiscombe and
Weinman 1976, written out here); both are frame parameters (nothing recompiles)."""
from __future__ import annotations

import math

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.slicing import SliceMode, SliceParams, SliceRenderer
from conftest import kernels_compiled

MULTIPLE = SliceMode("per_species", "multiple")


def hg(g, theta):
    """Henyey-Greenstein phase function (1/sr) at scattering angle theta (rad)."""
    return (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * np.cos(theta)) ** 1.5)


def table(g):
    theta = np.unique(np.r_[np.geomspace(1e-4, 0.3, 300), np.linspace(0.0, np.pi, 1500)])
    if g is None:
        return wm.phase.PhaseTable.from_values(theta, np.full_like(theta, 1 / (4 * np.pi)))
    return wm.phase.PhaseTable.from_values(theta, hg(g, theta))


def layer(g, tau=8.0, albedo=1.0):
    """A conservative layer 1-2 km up, 40 km wide, of vertical optical depth tau."""
    beta = np.full((8, 8, 8), tau / 1000.0, np.float32)
    return wm.OpticalVolume.from_arrays(beta, albedo, table(g), ((-20e3, -20e3, 1000.0), (20e3, 20e3, 2000.0)))


def camera(z, up):
    return wm.Camera.orthographic(center=(0.0, 0.0, z), direction=(0, 0, 1 if up else -1), width=2000.0, height=2000.0)


ELEVATION = 60.0


def lobe_change(g, up):
    """The image with the whole diffused light in the lobe less the image without it (forward peaks kept in
    the phase function: forward_peak_deg=0, so that every table gives the layer the same optical depth)."""
    vol = layer(g)
    spec = wm.SceneSpec(camera=camera(3000.0 if not up else 500.0, up), sun=wm.Sun(30.0, ELEVATION), sky=None,
                        ground=None, width=6, height=6)
    r = SliceRenderer(vol, MULTIPLE, slices=64, light_res=32, forward_peak_deg=0.0)
    without = r.frame(spec, SliceParams(diffusion_lobe=0.0)).radiance.mean(axis=(0, 1))
    with_lobe = r.frame(spec, SliceParams(diffusion_lobe=1.0)).radiance.mean(axis=(0, 1))
    return with_lobe - without, without


def test_the_diffused_lobe_follows_the_phase_function():
    """Seen from below (the sun behind the layer: scattering angle 90 - 60 = 30 deg) the lobe brightens a
    forward-scattering layer, seen from above (150 deg) it darkens it, by P(Theta) - 1/(4 pi): the change
    for g = 0.85 against g = 0.5 is Henyey-Greenstein's ratio, and an isotropic phase changes nothing."""
    for up, theta in ((True, math.radians(90.0 - ELEVATION)), (False, math.radians(90.0 + ELEVATION))):
        d85, base = lobe_change(0.85, up)
        d50, _ = lobe_change(0.5, up)
        expected = (hg(0.85, theta) - 1 / (4 * np.pi)) / (hg(0.5, theta) - 1 / (4 * np.pi))
        np.testing.assert_allclose(d85 / d50, expected, rtol=0.03)
        assert np.all(d85 > 0) if up else np.all(d85 < 0)
        assert np.all(np.abs(d85) > 0.02 * base)  # the test can fail: the lobe moves light
        d_iso, base_iso = lobe_change(None, up)
        np.testing.assert_allclose(d_iso, 0.0, atol=1e-5 * float(base_iso.max()))


def delta_eddington_transmission(tau, mu0, g):
    """Total transmission of a conservative layer (Joseph, Wiscombe and Weinman 1976, Eqs. for R with
    f = g^2), clamped to at least the delta-scaled direct beam."""
    f = g * g
    tp, gp = (1 - f) * tau, g / (1 + g)
    k = 0.75 * (1 - gp) * tp
    reflection = (k + (0.5 - 0.75 * mu0) * (1 - math.exp(-tp / mu0))) / (1 + k)
    return max(1 - reflection, math.exp(-tp / mu0))


def test_the_light_from_below_comes_from_the_shadowed_ground():
    """Looking up at a layer's base from between it and the ground: the ground's light on the base (the image
    with the ground's albedo less the image with a black ground) is dimmed by the layer's transmission of
    sunlight onto the ground beneath, T = delta-Eddington(tau, mu0, g), times below_shadow."""
    tau, g, mu0 = 8.0, 0.85, math.sin(math.radians(ELEVATION))
    vol = layer(g, tau)
    r = SliceRenderer(vol, MULTIPLE, slices=64, light_res=32, forward_peak_deg=0.0)

    def image(albedo, below_shadow):
        spec = wm.SceneSpec(camera=camera(500.0, True), sun=wm.Sun(30.0, ELEVATION), sky=wm.Sky("sunsky"),
                            ground=wm.Ground(albedo, height=0.0), width=6, height=6)
        return r.frame(spec, SliceParams(below_shadow=below_shadow)).radiance.astype(np.float64)

    black = image(0.0, 0.0)
    np.testing.assert_array_equal(black, image(0.0, 1.0))  # no ground light: nothing to shadow
    from_ground = image(0.6, 0.0) - black
    assert np.all(from_ground > 0.01 * black)
    T = delta_eddington_transmission(tau, mu0, g)
    for s in (1.0, 0.5):
        shadowed = image(0.6, s) - black
        np.testing.assert_allclose(shadowed, (1 - s * (1 - T)) * from_ground, rtol=0.03)


def test_the_new_parameters_are_checked_and_compile_nothing():
    for name in ("diffusion_lobe", "below_shadow"):
        with pytest.raises(ValueError, match=name):
            SliceParams(**{name: 1.5})
        with pytest.raises(ValueError, match=name):
            SliceParams(**{name: -0.1})
    vol = layer(0.85)
    r = SliceRenderer(vol, MULTIPLE, slices=16, light_res=16)
    spec = wm.SceneSpec(camera=camera(500.0, True), sun=wm.Sun(30.0, ELEVATION), sky=wm.Sky("sunsky"),
                        ground=wm.Ground(0.3, height=0.0), width=8, height=6)
    for i in range(3):  # warm-up: records (literal values made opaque)
        r.frame(spec, SliceParams(diffusion_lobe=0.1 * i, below_shadow=0.2 * i))
    with kernels_compiled() as compiled:
        images = {r.frame(spec, SliceParams(diffusion_lobe=0.3 + 0.2 * i, below_shadow=0.9 - 0.3 * i)).radiance.tobytes()
                  for i in range(3)}
    assert compiled == [], f"{len(compiled)} kernels compiled after the first frames"
    assert len(images) == 3
