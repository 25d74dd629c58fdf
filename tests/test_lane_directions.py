"""Each scattering's direction from one lane's own phase table (``kernel.plugins.lane_directions``, issue 38
spectralmis38: the one-sample MIS of hero wavelength sampling over a path's 4 wavelengths). Checked on a chromatic
mixture written out here: a Henyey-Greenstein species whose g falls linearly from 0.9 at 350 nm to 0.1 at 850 nm
(its tables every 25 nm) and a flat one (g = 0.5 at every wavelength), weights 0.7 / 0.3. Every lane's weight
g_i / q has expectation 1 (a phase function integrates to 1), with the lanes' tables bilinear in wavelength and
with one node a lane picked per vertex; a wrong pdf (the shares of q not those of the draw) fails the same check;
the lanes' values are the tables' written-out interpolant; a draw keeps the path's total throughput exactly with
the lanes picked by throughput, not with the uniform pick (the renders', whose weights are at most 4); the draw's
pdf is the next-event estimate's."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.optics.phase import PhaseTable

SPECTRAL = "llvm_ad_spectral"
NM = np.arange(350.0, 851.0, 25.0)
W = (0.7, 0.3)


def _hg(g, mu):
    return (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * mu) ** 1.5)


def _g(lam):
    return 0.9 - 0.8 * (np.asarray(lam) - 350.0) / 500.0


def _expected(lam, mu):
    """The mixture's value at wavelengths ``lam`` (the HG tables at the bracketing 25 nm nodes, linear between)."""
    j = np.clip(((lam - 350.0) // 25.0).astype(int), 0, NM.size - 2)
    t = (lam - NM[j]) / 25.0
    chromatic = (1 - t) * _hg(_g(NM[j]), mu) + t * _hg(_g(NM[j + 1]), mu)
    return W[0] * chromatic + W[1] * _hg(0.5, mu)


@pytest.fixture(scope="module")
def phase():
    import mitsuba as mi
    from weather_mi.kernel.plugins.hydrometeor_mixture import prepare_tables
    from weather_mi.kernel.plugins.spectral_phase import prepare_spectral
    own = mi.variant()
    wm.set_variant(SPECTRAL)
    theta = np.unique(np.concatenate([np.linspace(0, np.pi, 2001), np.geomspace(1e-4, 0.2, 400)]))
    mu = np.cos(theta)
    chromatic = [PhaseTable.from_values(theta, np.stack([_hg(_g(x), mu)] * 3, -1), name=f"hg{x:g}") for x in NM]
    flat = [PhaseTable.from_values(theta, np.stack([_hg(0.5, mu)] * 3, -1), name="hg0.5")] * NM.size
    nodes, values = prepare_tables([chromatic[8], flat[0]])
    sv = prepare_spectral(nodes, [chromatic, flat])
    weights = np.array(W, np.float32).reshape(1, 1, 1, 2)
    yield mi.load_dict({"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]),
                        "values": mi.TensorXf(values), "weights": mi.TensorXf(weights),
                        "spectral_values": mi.TensorXf(sv), "spectral_nm": mi.TensorXf(NM.astype(np.float32)),
                        "spectral_interpolation": "stochastic"})
    if own:
        wm.set_variant(own)


def _draws(phase, n: int, shares="throughput", picked=False, q_shares=None, seed=0, tp=None):
    """(throughput (n, 4), wavelengths (n, 4), cos of the scattering angle (n,), g (n, 4), q (n,), q of
    ``eval_pdf`` at the drawn directions (n,)) for n vertices with uneven lanes and wavelengths over 360-830 nm;
    ``q_shares``: the pdf's shares (a wrong pdf where they are not the draw's); ``tp``: every vertex's throughput."""
    import drjit as dr
    import mitsuba as mi
    from weather_mi.kernel.plugins import lane_directions as ld
    rng = np.random.default_rng(seed)
    tp = rng.random((n, 4)) ** 3 if tp is None else np.broadcast_to(np.asarray(tp, np.float64), (n, 4))
    lam = 360.0 + 470.0 * rng.random((n, 4))
    u = rng.random((5, n))
    mei = dr.zeros(mi.MediumInteraction3f, n)
    mei.wi = mi.Vector3f(0, 0, -1)
    mei.sh_frame = mi.Frame3f(mei.wi)
    mei.wavelengths = mi.Spectrum(*(mi.Float(lam[:, i]) for i in range(4)))
    throughput = mi.Spectrum(*(mi.Float(tp[:, i]) for i in range(4)))
    c = ld.shares(throughput, shares)
    at = ld.at_vertex(phase, mei, mi.Float(u[4]) if picked else None)
    wo, g, q = ld.sample(phase, mei, c, mi.Float(u[0]), mi.Float(u[1]), mi.Point2f(u[2], u[3]), at)
    _, q_eval = ld.eval_pdf(phase, mei, wo, c, at)
    if q_shares is not None:
        q = dr.sum(ld.shares(throughput, q_shares) * g)
    return tp, lam, np.array(wo.z), np.array(g).T, np.array(q), np.array(q_eval)


@pytest.mark.parametrize("picked, shares", [(False, "throughput"), (True, "throughput"), (True, "uniform")])
def test_each_lanes_weight_has_expectation_one(phase, picked, shares):
    """E[g_i(wo) / q(wo)] = integral of g_i = 1 for every lane, within 3 se (2^18 draws); with the uniform pick
    every weight is at most 4."""
    n = 1 << 18
    _, _, _, g, q, _ = _draws(phase, n, shares=shares, picked=picked)
    w = g / q[:, None]
    se = w.std(axis=0) / np.sqrt(n)
    assert np.all(np.abs(w.mean(axis=0) - 1.0) < 3 * se + 2e-4), (w.mean(axis=0), se)
    if shares == "uniform":
        assert w.max() <= 4.0 * (1 + 1e-5)


def test_a_wrong_pdf_fails_the_expectation(phase):
    """The draw by throughput (1, 0.1, 0.01, 0.001 at every vertex) weighted with the uniform shares' mixture (a pdf
    that is not the draw's): some lane's mean weight is off by more than 10 se."""
    n = 1 << 18
    _, _, _, g, q, _ = _draws(phase, n, q_shares="uniform", tp=(1.0, 0.1, 0.01, 0.001))
    w = g / q[:, None]
    se = w.std(axis=0) / np.sqrt(n)
    assert np.max(np.abs(w.mean(axis=0) - 1.0) / se) > 10.0


def test_lane_values_are_the_tables_interpolant(phase):
    """The lanes' bilinear values (no pick) against the HG tables written out here: within 0.2 % (the tables'
    16-bit codes 0.05 %, their resampling on the mixture's nodes)."""
    _, lam, mu, g, _, _ = _draws(phase, 1 << 14)
    np.testing.assert_allclose(g, _expected(lam, mu[:, None]), rtol=2e-3)


def test_a_draw_keeps_the_paths_total_throughput(phase):
    """sum_i T_i g_i / q = sum_i T_i to float rounding with the lanes drawn by throughput (bilinear and picked); the
    uniform pick (hero wavelength sampling's) spreads it by more than 10 % (log sd)."""
    for picked in (False, True):
        tp, _, _, g, q, _ = _draws(phase, 4096, picked=picked)
        np.testing.assert_allclose(np.sum(tp * g / q[:, None], axis=1), tp.sum(axis=1), rtol=1e-5)
    tp, _, _, g, q, _ = _draws(phase, 4096, shares="uniform")
    assert np.std(np.log(np.sum(tp * g / q[:, None], axis=1) / tp.sum(axis=1))) > 0.1


@pytest.mark.parametrize("picked", [False, True])
def test_the_draws_pdf_is_the_next_event_estimates(phase, picked):
    """q from the draw (its own node segment) equals ``eval_pdf``'s at the drawn direction (a new search), as the
    next-event estimate's MIS weights need: to float rounding."""
    _, _, _, _, q, q_eval = _draws(phase, 4096, picked=picked)
    np.testing.assert_allclose(q_eval, q, rtol=2e-3)


def test_the_codes_tables_integrate_to_one(phase):
    """The tables the draws use (16-bit codes decoded) integrate to 1 within 2^-11 at every node: the bound on what
    the codes' rounding can do to the weights' expectation."""
    from weather_mi.kernel.plugins import lane_directions as ld
    vals = ld.node_values(np.asarray(phase.spectral_values), tuple(phase.spectral_flat))
    v = np.asarray(phase.nodes, np.float64)
    integral = 2 * np.pi * np.sum(0.5 * (vals[:, 1:] + vals[:, :-1]) * np.diff(v)[None, :, None], axis=1)
    assert np.all(np.abs(integral - 1.0) < 2.0 ** -11), integral
