"""The "multiple" light model's diffused light entering through a lit face at incidence cosine cos i
(SliceParams.diffusion_incidence; slicing/eye.py Eqs. D1, D2) against closed forms: the 1-D diffusion
equation with the sunlight's exponential source in a slab lit at cos i, solved here by its Green's function
(scipy's quadrature, not the model's point source), and the horizontal layer's geometry (the optical depth
towards a sun at zenith cosine mu0 is the depth towards the zenith over mu0). A frame parameter: nothing
recompiles."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad

from weather_mi.slicing import SliceMode, SliceParams, SliceRenderer
from weather_mi.slicing.eye import DIFFUSION_Z0, diffusion_profile, incidence_cosine, leaking_diffusion
from conftest import kernels_compiled

Z0 = 2.0 / 3.0  # the diffusion approximation's extrapolation length (2 D, D = 1/3), transport depths


def slab_fluence(x, X, mu):
    """Fluence (in units of 3 F0 z0, the lit face of a semi-infinite cloud at normal incidence) at transport
    depth x along the normal of a conservative slab X thick, lit by a beam of flux F0 at incidence cosine mu:
    the beam's source F0 exp(-x'/mu) per unit depth (it removes the flux F0 mu over the slab) diffuses with
    D = 1/3 between extrapolated boundaries z0 beyond both faces (Green's function
    G(x, x') = 3 (min + z0)(X + z0 - max) / (X + 2 z0)); integrated numerically."""
    def g(xp):
        lo, hi = min(x, xp), max(x, xp)
        return np.exp(-xp / mu) * 3.0 * (lo + Z0) * (X + Z0 - hi) / (X + 2 * Z0)
    cuts = sorted({0.0, x, min(X, x + 60.0 * mu), X})  # the source lies within tens of mu of the face
    total = sum(quad(g, a, b, limit=200)[0] for a, b in zip(cuts[:-1], cuts[1:]))
    return total / (3.0 * Z0)


def test_the_extrapolation_length_is_the_diffusion_approximations():
    assert DIFFUSION_Z0 == pytest.approx(Z0)


@pytest.mark.parametrize("mu", [0.1, 0.3, 0.6, 1.0])
def test_the_profile_at_incidence_is_the_slabs_diffusion_beyond_the_source(mu):
    """Deep in a thick slab (transport depth X = 40 along its normal) and beyond a few mu from the lit face,
    Eq. D1 is the exponential source's solution within 1% (the Green's function is linear in the source's depth
    there, and the source's mean depth is mu); the sun ray's depths are the normal's over mu."""
    scale, X = 1.0, 40.0
    tau_col = X / mu  # the column along the sun ray
    for x in (6 * mu + 0.5, 5.0, 20.0, 35.0):
        model = diffusion_profile(np, x / mu, tau_col, scale, incidence=mu)
        np.testing.assert_allclose(model, slab_fluence(x, X, mu), rtol=0.01)
    # deep inside: 3 F0 mu (mu + z0) (the semi-infinite layer's constant, written out), here / (3 F0 z0)
    deep = diffusion_profile(np, 2.0 / mu, 1e4 / mu, scale, incidence=mu)
    assert deep == pytest.approx(mu * (mu + Z0) / Z0, rel=1e-3)


def test_at_normal_incidence_the_profile_is_unchanged():
    tau = np.linspace(0.0, 60.0, 61)
    for tau_col in (0.5, 5.0, 60.0):
        np.testing.assert_allclose(diffusion_profile(np, tau, tau_col, 0.38, incidence=1.0),
                                   diffusion_profile(np, tau, tau_col, 0.38), rtol=1e-12)
        np.testing.assert_allclose(leaking_diffusion(np, tau, tau_col, 0.38, 1.5, incidence=1.0),
                                   leaking_diffusion(np, tau, tau_col, 0.38, 1.5), rtol=1e-12)


def test_a_grazing_sun_on_a_wide_layer_takes_mu0_of_the_light_at_its_face():
    """The leaking (face) term at the lit face is the fluence there: 3 F0 mu z0 for a semi-infinite slab lit at mu
    (the same solution at x = 0), mu of the normal face's."""
    mu = 0.1
    face = leaking_diffusion(np, 0.0, 1e4, 0.4, 1.5, incidence=mu)
    assert face == pytest.approx(slab_fluence(1e-9, 4000.0, mu), rel=1e-3)  # the exponential source's, at the face


@pytest.mark.parametrize("mu0", [0.1, 0.5, 0.9])
def test_the_incidence_is_mu0_in_a_horizontal_layer_and_1_beside_a_tall_sunlit_side(mu0):
    """A horizontal homogeneous layer: the optical depth towards the sun is the depth towards the zenith over
    mu0 at every depth, so Eq. D2 gives mu0 (its top is the lit face); beside a sunlit side under a tall cloud
    (little cloud towards the sun, much above) it gives 1; the weight blends towards 1."""
    tau_up = np.array([0.0, 0.3, 3.0, 30.0])
    np.testing.assert_allclose(incidence_cosine(np, tau_up / mu0, tau_up, mu0, 1.0), mu0, rtol=1e-12)
    assert incidence_cosine(np, 0.5, 40.0, mu0, 1.0) == 1.0
    np.testing.assert_allclose(incidence_cosine(np, tau_up / mu0, tau_up, mu0, 0.25), 1 - 0.25 * (1 - mu0))
    np.testing.assert_allclose(incidence_cosine(np, tau_up / mu0, tau_up, mu0, 0.0), 1.0)


def test_it_dims_a_wide_layer_at_a_low_sun_is_checked_and_compiles_nothing():
    import weather_mi as wm
    with pytest.raises(ValueError, match="diffusion_incidence"):
        SliceParams(diffusion_incidence=1.5)
    beta = np.full((8, 8, 8), 8.0 / 1000.0, np.float32)  # tau 8, 1 km thick, 40 km wide
    vol = wm.OpticalVolume.from_arrays(beta, 1.0, wm.phase.henyey_greenstein(0.85),
                                       ((-20e3, -20e3, 1000.0), (20e3, 20e3, 2000.0)))
    r = SliceRenderer(vol, SliceMode("per_species", "multiple"), slices=16, light_res=16)
    cam = wm.Camera.orthographic(center=(0.0, 0.0, 2500.0), direction=(0, 0, -1), width=2000.0, height=2000.0)
    spec = wm.SceneSpec(camera=cam, sun=wm.Sun(30.0, 6.0), sky=None, ground=None, width=8, height=6)
    only = dict(ms_contribution=0.0, sky_gain=0.0, leak_gain=0.0, diffusion_flux=0.0, diffusion_lobe=0.0)
    r.frame(spec, SliceParams(**only, diffusion_incidence=0.1))  # warm-up: records
    r.frame(spec, SliceParams(**only, diffusion_incidence=0.2))
    with kernels_compiled() as compiled:
        img = {w: r.frame(spec, SliceParams(**only, diffusion_incidence=w)).radiance.mean() for w in (0.3, 0.6, 1.0)}
    assert compiled == [], f"{len(compiled)} kernels compiled after the first frames"
    plain = r.frame(spec, SliceParams(**only, diffusion_incidence=0.0)).radiance.mean()  # every face to the sun
    single = r.frame(spec, SliceParams(**only, diffusion_gain=0.0)).radiance.mean()
    # the diffused light seen from above: at sun 6 deg the layer's top takes mu0 ~ 0.10 of the face-on light
    assert single < img[1.0] < img[0.6] < img[0.3] < plain
    assert (img[1.0] - single) < 0.25 * (plain - single)
