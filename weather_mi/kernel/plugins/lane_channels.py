"""History-aware channel sampling in spectral variants (issue 38, chroma38): the phase function's directions drawn
from its R, G, B densities (650 / 550 / 450 nm, ``hydrometeor_mixture``'s table rows 0..2) with probabilities
that follow the path's throughput over its 4 wavelengths, instead of from the channels' mean density.

Why: a lane's phase weight is f_i(wo) / q(wo). With q the channel mean, the lanes' weights are a product of
ratios f_i / q over the path's vertices, a random walk in log space whose spread grows with the number of
scatterings: in a storm (thousands of scatterings a path) one lane's weight reaches 10^2, the others 10^-20, and
the path adds a coloured firefly (a single sample of X = 215 against a pixel's median of 0.05, front view, sun 4
deg: docs/spectral.md, "The colour fireflies"). Drawing the direction from q = sum_c beta_c p_c with beta_c the
throughput's share of channel c (each lane's share alpha_i = T_i / sum_j T_j spread over the channels by its
wavelength, linearly between 450, 550 and 650 nm and held beyond, as ``lerp_channels`` reads the channels) makes
q ~ sum_i alpha_i f_i, so that sum_i T_i f_i / q ~ sum_i T_i: the path's total throughput is preserved by the
phase sampling (exactly where each lane's phase function is the channels' linear interpolant), as Kutz et al.'s
(2017) history-aware spectral tracking preserves it in free flights. Unbiased for any beta: q is the density
the direction is drawn from (channel c with probability beta_c, then its density p_c)."""
from __future__ import annotations

import drjit as dr
import mitsuba as mi


def channel_shares(throughput, wavelengths, channel_nm):
    """beta (Color3f, summing to 1): the channels' shares of the throughput ``throughput`` (4 lanes at
    ``wavelengths``, nm), each lane's share split between the two channels (``channel_nm``, descending) that
    bracket its wavelength, linearly, and given to the end channel beyond them; 1/3 each where the throughput
    is 0."""
    from .hydrometeor_mixture import channel_bracket  # the lanes' values read the channels as lerp_channels
    total = dr.sum(throughput)
    inv = dr.select(total > 0.0, dr.rcp(total), 0.0)
    beta = [mi.Float(0.0), mi.Float(0.0), mi.Float(0.0)]
    for lane in range(4):
        a = throughput[lane] * inv
        red, t_hi, t_lo = channel_bracket(wavelengths[lane], channel_nm)
        beta[0] += dr.select(red, a * t_hi, 0.0)
        beta[1] += dr.select(red, a * (1.0 - t_hi), a * t_lo)
        beta[2] += dr.select(red, 0.0, a * (1.0 - t_lo))
    none = total <= 0.0
    return mi.Color3f(*(dr.select(none, 1.0 / 3.0, b) for b in beta))


def channel_pdfs(phase, mei, wo):
    """(Color3f, 1/sr) the densities p_R, p_G, p_B at ``wo`` that ``phase.sample_channel`` draws from (the
    mixture's R, G, B table rows with the channel-mean species weights, as ``_sample`` uses them)."""
    h = wo + mei.wi  # |wo + wi|^2 = 2 (1 - cos Theta), as eval_pdf
    idx, t = phase._segment(0.5 * dr.squared_norm(h))
    value, _ = phase._mix(phase._weights_at(mei), idx, t)  # each channel's own weights (a ByChannel's row)
    return value


def eval_pdf(phase, mei, wo, beta):
    """(the lanes' phase values, sum_c beta_c p_c(wo)) at ``wo`` from one lookup of the vertex's weights and of
    the direction's node segment (``phase.eval_pdf``'s values; its channel-mean pdf is not needed)."""
    w = phase._weights_at(mei)
    h = wo + mei.wi
    idx, t = phase._segment(0.5 * dr.squared_norm(h))
    value, _ = phase._mix_at(w, idx, t, mei, wo)
    channels, _ = phase._mix(w, idx, t)  # each channel's own weights, as the draws (a ByChannel's row)
    return value, dr.sum(beta * channels)


def continuation_pdf(phase, mei, wo, beta):
    """The density with which a vertex continues in ``wo``: sum_c beta_c p_c(wo)."""
    return dr.sum(beta * channel_pdfs(phase, mei, wo))
