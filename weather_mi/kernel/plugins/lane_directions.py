"""Each scattering's direction from the phase table of one of the path's own wavelengths (spectral variants with
``hydrometeor_mixture``'s tables every 25 nm; issue 38, spectralmis38): the one-sample MIS of hero wavelength
spectral sampling (Wilkie et al. 2014, "Hero wavelength spectral sampling", EGSR), the lane picked in proportion to
its throughput (or uniformly, as there).

At a scattering vertex each lane i (wavelength lambda_i, throughput T_i) reads ONE of the two 25 nm table nodes that
bracket lambda_i, the upper with probability equal to its linear weight, picked once for the vertex
(:func:`pick_nodes`, independent of any direction): g_i(wo) = sum_s w_s(lambda_i) p_s(wo, node_i), an unbiased
estimate of the lane's bilinear phase function. Lane l is picked with probability c_l = T_l / sum_j T_j (``shares``
"throughput", the renders' choice; 1/4 each where the throughput is 0) or c_l = 1/4 ("uniform") and the direction
drawn from its g_l (a species by the lane's weights, a node segment by that (node, species)'s alias table, v within
it). The direction's density is the mixture

    q(wo) = sum_j c_j g_j(wo)                                            (one-sample MIS, balance heuristic)

and every lane's weight is g_i(wo) / q(wo): unbiased for any c (given the picks, E[g_i / q] = integral g_i = 1; over
them, the bilinear value). With c proportional to the throughput sum_i T_i g_i / q = sum_i T_i exactly: a draw keeps
the path's total throughput, and no lane can exceed it (T_i g_i / q <= sum_j T_j). The uniform pick bounds a
vertex's weights by 4, but their product over thousands of scatterings is a random walk in log space (as the
channel-mean draw's was before chroma38): at 1024 spp its blue and red fireflies gave up to 1.27x main's chroma se,
where the pick by throughput gave main's or less (docs/spectral.md, "Each lane's direction from its own table"). The
vertex's next-event estimate reads the same nodes and weights (:class:`LaneVertex`) and weights its MIS with the
same q (:func:`eval_pdf`). This replaces ``lane_channels`` (directions from the R, G, B tables, whose interpolant
the 25 nm tables are only approximately: its lanes drifted, R = 11 from one 20 deg sample) where the phase has its
tables by wavelength. Without picked nodes (``at`` None) the lanes' tables are bilinear (two nodes a lane), the same
otherwise.

Tables (:func:`prepare`, once a phase object, cached on it): the species' values at every wavelength node exactly
as the lanes read them (the 16-bit codes of ``spectral_phase.pack_half_nodes`` decoded for the species that change
with wavelength, float32 for the flat ones), and per (node, species) a Walker alias table of the segment masses of
that piecewise-linear density: K S (N - 1) x 2 floats, 2.1 MB for 7 species, 21 wavelengths, 1828 nodes. Values
and pdf come from the codes (2 packet loads a lane, its node at two versine nodes; 4 bilinear), so the pdf is the
density the draw has to float rounding; the codes' tables integrate to 1 within 2^-11 (tests/test_lane_directions)."""
from __future__ import annotations


import numpy as np

import drjit as dr
import mitsuba as mi

from . import linear_segment, spectral_air_weights
from .mixture_tables import alias_table, segment_masses
from .spectral_phase import _decoded, decode16, encode16, pack_half_nodes, picked_node
from ..jitarrays import aligned_uint
from ..kept import Kept, digest

_HOST = Kept(4)  # :func:`_host_tables`' tables by their inputs' digest (about 2 MB each for 7 species, 21 nm, 1828 nodes)
SHARES = ("throughput", "uniform")  # c_l: in proportion to the lanes' throughput (the renders'), or 1/4 each


def applies(phase) -> bool:
    """Whether ``phase`` has tables by wavelength this module can draw from (JIT variants)."""
    return getattr(phase, "spectral_grid", None) is not None and dr.is_array_v(mi.Float)


def node_values(values: np.ndarray, flat: tuple) -> np.ndarray:
    """(S, N, K) float32: ``values`` as the lanes read them: the 16-bit codes' values (:func:`decode16`) for the
    species not in ``flat``, float32 for the flat ones (read from ``spectral_flat_table``)."""
    v = np.asarray(values, np.float32).copy()
    rest = [s for s in range(v.shape[0]) if s not in flat]
    v[rest] = decode16(encode16(v[rest]))
    return v


def alias_tables(nodes: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(K, S, N - 1, 2) float32: per wavelength node and species the alias table (probability, alias index as a
    float, exact below 2^24) of the node segments' masses under ``values`` (S, N, K) piecewise linear in v."""
    n_s, n, k = values.shape
    out = np.empty((k, n_s, n - 1, 2), np.float32)
    for j in range(k):
        for s, m in enumerate(segment_masses(nodes, np.asarray(values[:, :, j], np.float64))):
            prob, alias = alias_table(m)
            out[j, s, :, 0], out[j, s, :, 1] = prob, alias
    return out


def _host_tables(values: np.ndarray, flat: tuple, nodes: np.ndarray):
    """(node values (K S N,), alias tables (K S (N - 1) x 2,)) as numpy float32, kept by the bytes of their inputs
    (:data:`_HOST`, the last 4): a phase object is built per render, and the alias tables' Python
    loops (147 tables of 1827 segments, ~0.3 s) would otherwise run again for the same tables every render."""
    def make():
        exact = node_values(values, flat)
        return (np.ascontiguousarray(np.transpose(exact, (2, 0, 1))).ravel(), alias_tables(nodes, exact).ravel())
    return _HOST.get(digest(np.ascontiguousarray(values), (values.shape, flat, nodes.shape),
                            np.ascontiguousarray(nodes)), make)


def prepare(phase):
    """The phase's tables for this module (module docstring), built on first use and kept on ``phase``:
    (node values (K S N,), alias tables (K S (N - 1) x 2,), codes of the non-flat species (``pack_half_nodes``))."""
    if getattr(phase, "lane_tables", None) is None:
        values, flat = np.asarray(phase.spectral_values, np.float32), tuple(phase.spectral_flat)
        nodes = np.asarray(phase.nodes, np.float64)
        rest = [s for s in range(values.shape[0]) if s not in flat]
        codes = phase.spectral_codes if phase.spectral_codes is not None else \
            aligned_uint(mi, pack_half_nodes(values[rest]))
        exact, alias = _host_tables(values, flat, nodes)
        phase.lane_tables = (mi.Float(exact), mi.Float(alias), codes)
    return phase.lane_tables


def shares(throughput, how: str = "throughput"):
    """c (Spectrum, summing to 1): each lane's probability of lending its table to the direction."""
    if how == "uniform":
        return mi.Spectrum(0.25)
    total = dr.sum(throughput)
    return dr.select(total > 0.0, throughput * dr.rcp(dr.select(total > 0.0, total, 1.0)), 0.25)


def _lane_weights(phase, mei):
    """(the vertex's weights, each lane's weights (4 lists of S Floats))."""
    from .hydrometeor_mixture import _channel_mean, _gather4
    w = _channel_mean(phase._weights_at(mei))
    if phase.air_spectral is None:
        return w, [list(w)] * 4
    return w, spectral_air_weights.by_lane(phase.air_spectral, w, mei.wavelengths, _gather4)


class LaneVertex:
    """What a vertex's draw and its next-event estimate share: each lane's Eq. 8 weights (``lane_w``, 4 lists of S
    Floats; one lookup of the weight grid for both) and its wavelength node (``nodes``, :func:`pick_nodes`; None:
    bilinear)."""

    def __init__(self, lane_w, nodes=None):
        self.lane_w, self.nodes = lane_w, nodes


def at_vertex(phase, mei, u=None):
    """The :class:`LaneVertex` of ``mei``: its weights, and with a uniform ``u`` one node a lane."""
    _, lane_w = _lane_weights(phase, mei)
    return LaneVertex(lane_w, None if u is None else pick_nodes(phase, mei.wavelengths, u))


def pick_nodes(phase, wavelengths, u):
    """Each lane's wavelength node for one vertex (4 UInt32): of the two that bracket its wavelength, the upper
    with probability equal to its linear weight (lane l's uniform frac(``u`` + l / 4), stratified as
    ``spectral_phase.picked_value``). Independent of the direction: the lane's table at that node is an unbiased
    estimate of its bilinear one, and the vertex's draw and its next-event estimate use the same (module
    docstring)."""
    return [picked_node(phase.spectral_grid, wavelengths[lane], u, lane) for lane in range(4)]


def _values(phase, lane_w, idx, t, wavelengths, nodes=None):
    """mi.Spectrum: every lane's value g_i, linear in v at fraction ``t`` of segment ``idx``, from the codes and the
    flat species' table: at its node of ``nodes`` (:func:`pick_nodes`), or without them bilinear (its two wavelength
    nodes): what the draws' densities are."""
    _, _, codes = prepare(phase)
    lo, inv_step, k = phase.spectral_grid
    n = phase.n_nodes
    flat = phase.spectral_flat
    shared = {}
    for f, s in enumerate(flat):
        e = dr.gather(mi.Vector4f, phase.spectral_flat_table, idx * len(flat) + f)
        shared[s] = dr.fma(e[2] - e[0], t, e[0])
    rest = [s for s in range(phase.n_species) if s not in shared]
    out = []
    for lane in range(4):
        if nodes is None:
            x = dr.clip((wavelengths[lane] - lo) * inv_step, 0.0, k - 1.0001)
            j = mi.UInt32(x)
            tl, at = x - mi.Float(j), (j, j + 1)
        else:
            tl, at = None, (nodes[lane],)
        node = []
        for jj in at:
            near, far = (dr.gather(mi.Vector4u, codes, jj * n + idx + d) for d in (0, 1))
            node.append((near, far))
        acc = mi.Float(0.0)
        for s in range(phase.n_species):
            if s in shared:
                acc += lane_w[lane][s] * shared[s]
                continue
            r = rest.index(s)
            p = [dr.fma(_decoded(far[r // 2], r % 2 == 1) - _decoded(near[r // 2], r % 2 == 1), t,
                        _decoded(near[r // 2], r % 2 == 1)) for near, far in node]
            acc += lane_w[lane][s] * (p[0] if tl is None else dr.fma(p[1] - p[0], tl, p[0]))
        out.append(acc)
    return mi.Spectrum(*out)


def eval_pdf(phase, mei, wo, c, at=None):
    """(every lane's phase value g_i(wo), the continuation pdf q(wo) = sum_j c_j g_j(wo)); ``at``: the vertex's
    :class:`LaneVertex` (else looked up, bilinear)."""
    at = at_vertex(phase, mei) if at is None else at
    idx, t = phase._segment(0.5 * dr.squared_norm(wo + mei.wi))
    g = _values(phase, at.lane_w, idx, t, mei.wavelengths, at.nodes)
    return g, dr.sum(c * g)


def _pick(weights, u):
    """(index, the remainder of ``u`` rescaled to [0, 1)) of the entry of ``weights`` (a list of Floats summing to 1)
    that the uniform ``u`` falls in."""
    pick = mi.UInt32(0)
    acc, lower, sel = mi.Float(0.0), mi.Float(0.0), weights[0]
    for i in range(len(weights) - 1):
        acc += weights[i]
        above = u >= acc
        pick += mi.UInt32(dr.select(above, 1, 0))
        lower = dr.select(above, acc, lower)
        sel = dr.select(above, weights[i + 1], sel)
    return pick, dr.clip((u - lower) / dr.maximum(sel, 1e-30), 0.0, 1.0)


def _of_lane(values, lane):
    """values[lane] for a UInt32 ``lane`` (values: 4 per-lane Floats)."""
    return dr.select(lane == 0, values[0], dr.select(lane == 1, values[1], dr.select(lane == 2, values[2], values[3])))


def sample(phase, mei, c, u_lane, sample1, sample2, at=None):
    """(wo, every lane's value g_i(wo), q(wo)) with the vertex's :class:`LaneVertex` ``at`` (else looked up,
    bilinear): lane l drawn with probability c_l (``u_lane``), its node (without nodes, one of its two wavelength
    nodes by its linear weight, from what is left of ``u_lane``: its bilinear table), a species by the lane's
    weights (``sample1``; its remainder the alias coin), a node segment (``sample2.x``) and v within it, the
    azimuth (``sample2.y``)."""
    node_vals, alias, _ = prepare(phase)
    lo, inv_step, k = phase.spectral_grid
    n_s, n = phase.n_species, phase.n_nodes
    at = at_vertex(phase, mei) if at is None else at
    lane_w, nodes = at.lane_w, at.nodes
    lane, u_node = _pick([c[i] for i in range(4)], u_lane)
    if nodes is None:
        x = dr.clip((_of_lane([mei.wavelengths[i] for i in range(4)], lane) - lo) * inv_step, 0.0, k - 1.0001)
        j = mi.UInt32(x)
        j = dr.select(u_node < x - mi.Float(j), j + 1, j)  # node j + 1 with its linear weight
    else:
        j = _of_lane(nodes, lane)
    species, coin = _pick([_of_lane([lane_w[i][s] for i in range(4)], lane) for s in range(n_s)], sample1)
    u = sample2.x * (n - 1)
    b = mi.UInt32(dr.clip(u, 0.0, n - 2.0))
    r = dr.clip(u - mi.Float(b), 0.0, 1.0)
    table = j * n_s + species
    entry = dr.gather(mi.Vector2f, alias, table * (n - 1) + b)
    idx = dr.select(coin < entry[0], b, mi.UInt32(entry[1]))
    f0, f1 = (dr.gather(mi.Float, node_vals, table * n + idx + d) for d in (0, 1))
    v0, v1 = (dr.gather(mi.Float, phase.nodes, idx + d) for d in (0, 1))
    v, t = linear_segment.invert(v0, v1, f0, f1, r)
    wo = linear_segment.direction(mei, v, sample2.y)
    g = _values(phase, lane_w, idx, t, mei.wavelengths, nodes)
    return wo, g, dr.sum(c * g)
