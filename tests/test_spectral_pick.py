"""The spectral mode's phase values as renders read them (issue 38 part 2, its cost): ``spectral_interpolation``
"stochastic" (``kernel.plugins.spectral_phase.picked_value``): each lane reads one of its two bracketing wavelength
nodes, the upper with probability equal to its linear weight, from 16-bit tables (``encode16``). Checked against
numbers made here: the codes' rounding against the 2^-11 a 10-bit mantissa allows, each lane's value against the
Henyey-Greenstein tables at the two nodes (numpy), the pick's frequency against the linear weight (binomial), the
mean against the bilinear value, and the sampling weights' mean (1 at every wavelength: the pdf is untouched)."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.optics.phase.table import PhaseTable

SPECTRAL = "llvm_ad_spectral"
GRID = np.arange(350.0, 851.0, 25.0)


def _hg(g, mu):
    return (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * mu) ** 1.5)



def _interactions(mi, rng, n: int, lanes_nm):
    """``n`` medium interactions at random points of the unit cube, looking down, with the 4 lanes' wavelengths."""
    import drjit as dr
    mei = dr.zeros(mi.MediumInteraction3f, n)
    mei.p = mi.Point3f(*(mi.Float(rng.random(n).astype(np.float32)) for _ in range(3)))
    mei.wi = mi.Vector3f(0, 0, -1)
    mei.sh_frame = mi.Frame3f(mei.wi)
    mei.wavelengths = mi.Spectrum(*(mi.Float(np.full(n, v, np.float32)) for v in lanes_nm))
    return mei

def test_16bit_codes_round_to_a_10_bit_mantissa():
    """decode16(encode16(x)) within 2^-11 relative of x from 2^-38 to 3e7 1/sr (a raindrop's forward peak is 1.4e7),
    0 and values below 2^-39 as 0; negative, infinite or too large values a ValueError."""
    from weather_mi.kernel.plugins.spectral_phase import decode16, encode16
    x = np.concatenate([[0.0, 1e-13], np.geomspace(2.0 ** -38, 3e7, 20001)]).astype(np.float32)
    y = decode16(encode16(x))
    assert y[0] == 0.0 and y[1] == 0.0
    rel = np.abs(y[2:].astype(np.float64) - x[2:]) / x[2:]
    assert rel.max() <= 2.0 ** -11 and rel.max() > 2.0 ** -13  # the bound, and not exact (the test can fail)
    for bad in ([-1.0], [np.inf], [4e7]):
        with pytest.raises(ValueError, match="16-bit"):
            encode16(np.array(bad, np.float32))


def _plugins(mi, weights):
    from weather_mi.kernel.plugins.hydrometeor_mixture import prepare_tables
    from weather_mi.kernel.plugins.spectral_phase import prepare_spectral
    theta = np.unique(np.concatenate([np.linspace(0, np.pi, 2001), np.geomspace(1e-4, 0.2, 400)]))
    gs = 0.2 + 0.7 * (GRID - 350) / 500  # g rising with wavelength: the value changes between nodes
    signs = (1.0, -0.5, 0.3)
    stacks = [[PhaseTable.from_values(theta, _hg(sign * g, np.cos(theta))) for g in gs] for sign in signs]
    rgb = [PhaseTable.from_values(theta, np.stack([_hg(sign * g, np.cos(theta)) for g in (0.8, 0.6, 0.4)], -1))
           for sign in signs]
    nodes, values = prepare_tables(rgb)
    sv = prepare_spectral(nodes, stacks)
    base = {"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]), "values": mi.TensorXf(values),
            "weights": mi.TensorXf(np.broadcast_to(weights, (2, 2, 2, len(signs))).copy()),
            "spectral_values": mi.TensorXf(sv), "spectral_nm": mi.TensorXf(GRID.astype(np.float32))}
    return nodes, sv, mi.load_dict(base), mi.load_dict({**base, "spectral_interpolation": "stochastic"})


def test_each_lane_reads_one_node_with_its_linear_weight(variant_restored):
    """At one direction and four wavelengths, over 40000 vertices (the pick hashed from the point): every lane's
    value is the mixture at its lower or its upper wavelength node (numpy, linear in v; within the codes'
    2^-11), the upper one as often as its linear weight (4 binomial sigma), and the mean is the bilinear
    value of the "linear" plugin (4 se); the pdf is the "linear" plugin's, float for float."""
    import mitsuba as mi
    wm.set_variant(SPECTRAL)
    w = np.array([3.0, 1.0, 0.5], np.float32)
    nodes, sv, linear, picked = _plugins(mi, w)
    lanes = np.array([361.0, 437.5, 512.0, 829.0])
    n = 40000
    rng = np.random.default_rng(5)
    mei = _interactions(mi, rng, n, lanes)
    cos = -0.6
    wo = mi.Vector3f(float(np.sqrt(1 - cos ** 2)), 0.0, cos)
    ctx = mi.PhaseFunctionContext(None)
    v_lin, pdf_lin = linear.eval_pdf(ctx, mei, wo)
    v_pick, pdf_pick = picked.eval_pdf(ctx, mei, wo)
    assert np.array_equal(np.array(pdf_lin), np.array(pdf_pick))
    v_lin, v_pick = np.array(v_lin), np.array(v_pick)  # (4, n)
    wn = w.astype(np.float64) / w.sum()
    at_nodes = wn @ np.array([[np.interp(1 - cos, nodes, sv[s, :, k]) for k in range(GRID.size)]
                              for s in range(3)])  # the mixture at every wavelength node
    for lane, lam in enumerate(lanes):
        x = (lam - GRID[0]) / 25.0
        j, t = int(x), x - int(x)
        lo, hi = at_nodes[j], at_nodes[j + 1]
        assert abs(hi - lo) > 1e-3 * lo  # the two nodes differ: a wrong pick would show
        got = v_pick[lane]
        is_hi = np.abs(got - hi) <= 2.0 ** -10 * hi
        is_lo = np.abs(got - lo) <= 2.0 ** -10 * lo
        assert np.all(is_hi | is_lo)
        frac = is_hi.mean()
        assert abs(frac - t) <= 4 * np.sqrt(max(t * (1 - t), 1.0 / n) / n)
        np.testing.assert_allclose(v_lin[lane], (1 - t) * lo + t * hi, rtol=1e-4)
        assert abs(got.mean() - v_lin[lane].mean()) <= 4 * got.std() / np.sqrt(n) + 2.0 ** -10 * hi


def test_picked_sampling_weights_have_mean_one_at_every_wavelength(variant_restored):
    """Directions drawn from the wavelengths' mean density with the values picked per lane: the weights
    value / pdf average to 1 at each wavelength (every wavelength's table is normalised, the pick is unbiased)."""
    import mitsuba as mi
    wm.set_variant(SPECTRAL)
    _, _, _, picked = _plugins(mi, np.array([3.0, 1.0, 0.5], np.float32))
    n = 200_000
    rng = np.random.default_rng(1)
    mei = _interactions(mi, rng, n, (380.0, 487.5, 580.0, 780.0))
    u = rng.random((3, n))
    _, weight, _ = picked.sample(mi.PhaseFunctionContext(None), mei, mi.Float(u[0]), mi.Point2f(u[1], u[2]))
    np.testing.assert_allclose(np.array(weight).mean(axis=1), 1.0, atol=0.01)


def test_the_renderer_picks_and_a_bad_choice_is_refused(variant_restored):
    """``kernel.medium`` asks for the picked values; an unknown ``spectral_interpolation`` is a clear error."""
    import mitsuba as mi
    from weather_mi.kernel.medium import spectral_phase_properties
    wm.set_variant(SPECTRAL)
    vol = wm.optical_volume(wm.synthetic.cumulus(shape=(8, 8, 8), spacing_m=(200.0, 200.0, 200.0)),
                            species="physical", phase_quality="test")
    from weather_mi.kernel.plugins.hydrometeor_mixture import prepare_tables
    nodes, _ = prepare_tables(vol.require_phase_tables())
    assert spectral_phase_properties(vol, nodes)["spectral_interpolation"] == "stochastic"
    with pytest.raises(Exception, match="spectral_interpolation"):
        mi.load_dict({"type": "hydrometeor_mixture", "nodes": mi.TensorXf(np.array([[0.0], [2.0]], np.float32)),
                      "values": mi.TensorXf(np.full((1, 2, 3), 1 / (4 * np.pi), np.float32)),
                      "weights": mi.TensorXf(np.ones((1, 1, 1, 1), np.float32)),
                      "spectral_values": mi.TensorXf(np.full((1, 2, 21), 1 / (4 * np.pi), np.float32)),
                      "spectral_nm": mi.TensorXf(GRID.astype(np.float32)), "spectral_interpolation": "nearest"})
