"""History-aware channel sampling in the spectral variant (``kernel.plugins.lane_channels``, issue 38 chroma38):
directions drawn from the phase function's R, G, B densities in the throughput's shares by wavelength. Checked on
a chromatic phase function (Henyey-Greenstein g 0.85 / 0.6 / 0.3 at 450 / 550 / 650 nm, written out here): every
lane's weight f_i / q has expectation 1 (a phase function integrates to 1 over the sphere), the path's total
throughput is preserved exactly by a draw, and the channel mean's draw (as before) does not preserve it."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.optics.phase import PhaseTable

SPECTRAL = "llvm_ad_spectral"
G = (0.3, 0.6, 0.85)  # at 650, 550, 450 nm (R, G, B)


def _hg(g, mu):
    return (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * mu) ** 1.5)


def _draws(n: int, seed: int = 0, densities: bool = False):
    """The plugin, n vertices with throughputs and wavelengths in 450-650 nm, and their directions drawn by
    channel with the shares beta: (throughput (n, 4), f (n, 4) at the drawn directions, q there, f / q from
    the channel mean's sample()); q from ``lane_channels.continuation_pdf``, or with ``densities`` from the
    channels' densities ``sample_channel`` returns with the draw (what the path loop uses)."""
    import drjit as dr
    import mitsuba as mi
    from weather_mi.kernel.plugins import lane_channels as lc
    from weather_mi.kernel.plugins.hydrometeor_mixture import prepare_tables
    wm.set_variant(SPECTRAL)
    theta = np.unique(np.concatenate([np.linspace(0, np.pi, 2001), np.geomspace(1e-4, 0.2, 400)]))
    table = PhaseTable.from_values(theta, np.stack([_hg(g, np.cos(theta)) for g in G], -1), name="hg3")
    nodes, values = prepare_tables([table])
    phase = mi.load_dict({"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]),
                          "values": mi.TensorXf(values), "weights": mi.TensorXf(np.ones((1, 1, 1, 1), np.float32))})
    rng = np.random.default_rng(seed)
    tp = rng.random((n, 4)) ** 3  # uneven lanes
    lam = 450.0 + 200.0 * rng.random((n, 4))
    u = rng.random((4, n))
    mei = dr.zeros(mi.MediumInteraction3f, n)
    mei.wi = mi.Vector3f(0, 0, -1)
    mei.sh_frame = mi.Frame3f(mei.wi)
    mei.wavelengths = mi.Spectrum(*(mi.Float(lam[:, i]) for i in range(4)))
    throughput = mi.Spectrum(*(mi.Float(tp[:, i]) for i in range(4)))
    beta = lc.channel_shares(throughput, mei.wavelengths, phase.channel_nm)
    b = np.array(beta)
    uc = mi.Float(u[0])
    channel = mi.UInt32(dr.select(uc >= beta[0], 1, 0) + dr.select(uc >= beta[0] + beta[1], 1, 0))
    ctx = mi.PhaseFunctionContext(None)
    if densities:
        wo, f, dens = phase.sample_channel(ctx, mei, channel, mi.Float(u[1]), mi.Point2f(u[2], u[3]),
                                           densities=True)
        q = dr.sum(beta * dens)
    else:
        wo, f = phase.sample_channel(ctx, mei, channel, mi.Float(u[1]), mi.Point2f(u[2], u[3]))
        q = lc.continuation_pdf(phase, mei, wo, beta)
    _, w_mean, _ = phase.sample(ctx, mei, mi.Float(u[1]), mi.Point2f(u[2], u[3]))
    return tp, np.array(f).T, np.array(q), np.array(w_mean).T, b.T, lam


def test_channel_shares_split_each_lane_between_its_bracketing_channels(variant_restored):
    tp, _, _, _, b, lam = _draws(64)
    expect = np.zeros((64, 3))
    for i in range(4):
        a = tp[:, i] / tp.sum(axis=1)
        expect += a[:, None] * np.stack([np.interp(lam[:, i], [450, 550, 650], [0, 0, 1]),
                                         np.interp(lam[:, i], [450, 550, 650], [0, 1, 0]),
                                         np.interp(lam[:, i], [450, 550, 650], [1, 0, 0])], -1)
    np.testing.assert_allclose(b, expect, atol=1e-6)


def test_each_lanes_weight_has_expectation_one(variant_restored):
    """E[f_i(wo) / q(wo)] = integral of f_i = 1 for every lane (the draws' density is q): within 3 se."""
    n = 1 << 18
    _, f, q, _, _, _ = _draws(n, densities=True)
    w = f / q[:, None]
    se = w.std(axis=0) / np.sqrt(n)
    assert np.all(np.abs(w.mean(axis=0) - 1.0) < 3 * se + 1e-3), (w.mean(axis=0), se)


def test_a_draw_preserves_the_paths_total_throughput(variant_restored):
    """sum_i T_i f_i / q = sum_i T_i when each lane's phase function is the channels' linear interpolant (this
    table): to float rounding; the channel mean's draw spreads it by tens of per cent (the check can fail)."""
    tp, f, q, w_mean, _, _ = _draws(4096)
    after = np.sum(tp * f / q[:, None], axis=1)
    assert after == pytest.approx(tp.sum(axis=1), rel=2e-3)
    before = np.sum(tp * w_mean, axis=1) / tp.sum(axis=1)
    assert np.std(np.log(before)) > 0.1


def test_the_draws_own_densities_are_the_continuation_pdf(variant_restored):
    """The channels' densities ``sample_channel`` returns with a draw (from the draw's weights and node segment)
    give the pdf ``continuation_pdf`` finds again from the direction (a new search), to float rounding."""
    _, _, q_search, _, _, _ = _draws(4096)
    _, _, q_draw, _, _, _ = _draws(4096, densities=True)
    np.testing.assert_allclose(q_draw, q_search, rtol=2e-3)
