"""The numpy side of ``hydrometeor_mixture``: its phase tables prepared once (the species' tables on one common
versine node set, normalised; the channel-mean densities the sampler draws from, their segment masses as Walker
alias tables, and the guide table that bounds ``eval_pdf``'s node search)."""
from __future__ import annotations

import numpy as np

GUIDE_THETA0 = 1e-3  # rad: the guide table's angle warp is linear below, logarithmic above


def common_nodes(tables, max_nodes: int = 16384) -> np.ndarray:
    """Ascending versine nodes v = 1 - cos(theta): the union of the tables' theta grids (thinned if
    too many), distinct in float32."""
    theta = np.unique(np.concatenate([np.asarray(t.theta, np.float64) for t in tables] + [[0.0, np.pi]]))
    theta = theta[(theta >= 0) & (theta <= np.pi)]
    if theta.size > max_nodes:
        keep = np.unique(np.round(np.linspace(0, theta.size - 1, max_nodes)).astype(int))
        theta = theta[keep]
    v = np.unique((2.0 * np.sin(theta / 2) ** 2).astype(np.float32)).astype(np.float64)  # 1 - cos, accurately
    v[0], v[-1] = 0.0, 2.0
    return v


def _normalise(v: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Scale p (N, ...) so that 2 pi * trapezoid(p, v) = 1 (piecewise linear in v = 1 - cos)."""
    integral = 2 * np.pi * np.sum(0.5 * (p[1:] + p[:-1]) * np.diff(v)[:, None], axis=0)
    return p / integral


def prepare_tables(tables, max_nodes: int = 16384):
    """(nodes v = 1 - cos (N,), values (S, N, 3)) in 1/sr from PhaseTable-like objects (``theta``
    ascending in radians, ``values`` (len(theta), 3) in 1/sr), resampled linearly in v."""
    v = common_nodes(tables, max_nodes)
    out = np.empty((len(tables), v.size, 3))
    for s, t in enumerate(tables):
        th = np.asarray(t.theta, np.float64)
        vals = np.asarray(t.values, np.float64).reshape(th.size, -1)
        if vals.shape[1] == 1:
            vals = np.repeat(vals, 3, axis=1)
        tv = 2.0 * np.sin(th / 2) ** 2
        for c in range(3):
            out[s, :, c] = np.interp(v, tv, vals[:, c])
        out[s] = _normalise(v, out[s])
    return v.astype(np.float32), out.astype(np.float32)


def channel_mean_pdf(v: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(S, N) channel-mean density pbar of every species (1/sr, 2 pi * integral dv = 1): the density
    the sampler draws from."""
    return _normalise(np.asarray(v, np.float64), np.asarray(values, np.float64).mean(axis=2).T).T


def segment_masses(v: np.ndarray, pbar: np.ndarray) -> np.ndarray:
    """(S, N - 1) probability of every node segment under the piecewise-linear density pbar (S, N)."""
    seg = 0.5 * (pbar[:, 1:] + pbar[:, :-1]) * np.diff(np.asarray(v, np.float64))[None]
    return seg / seg.sum(axis=1, keepdims=True)


def alias_table(p: np.ndarray):
    """Walker's alias table (Vose's construction) of the discrete distribution p (M,): (prob (M,),
    alias (M,)). Bucket j, drawn uniformly, keeps j when a uniform coin is below prob[j] and takes
    alias[j] otherwise; that draws j with probability p[j] exactly (up to float rounding)."""
    p = np.asarray(p, np.float64)
    m = p.size
    scaled = p * (m / p.sum())
    prob, alias = np.ones(m), np.arange(m)
    small = [j for j in range(m) if scaled[j] < 1.0]
    large = [j for j in range(m) if scaled[j] >= 1.0]
    while small and large:
        j, k = small.pop(), large.pop()
        prob[j], alias[j] = scaled[j], k
        scaled[k] -= 1.0 - scaled[j]
        (small if scaled[k] < 1.0 else large).append(k)
    return prob, alias  # leftovers (rounding) keep prob 1


def angle_warp(v, theta0: float = GUIDE_THETA0):
    """Guide-table coordinate in [0, 1] of versines v: asinh(Theta / theta0) / asinh(pi / theta0),
    linear in Theta below theta0 and logarithmic above, as the tables' angle grids are."""
    theta = 2.0 * np.arcsin(np.sqrt(np.clip(np.asarray(v, np.float64), 0.0, 2.0) / 2.0))
    return np.arcsinh(theta / theta0) / np.arcsinh(np.pi / theta0)


def guide_table(v: np.ndarray, max_steps: int = 3, theta0: float = GUIDE_THETA0):
    """(bounds (M, 2) uint32, steps): bucket j of M equal buckets in :func:`angle_warp` holds versines
    whose node segment lies in [bounds[j, 0], bounds[j, 1]] (widened by one segment either side for
    float32 rounding), found in ``steps`` bisection steps. M grows from 2 N (doubling, up to 64 N)
    until steps <= max_steps."""
    t = angle_warp(v, theta0)
    n_seg = v.size - 1
    m = 2 * v.size
    while True:
        start = np.clip(np.searchsorted(t, np.arange(m + 1) / m, side="right") - 1, 0, n_seg - 1)
        lo = np.clip(start[:-1] - 1, 0, n_seg - 1)
        hi = np.clip(start[1:] + 1, 0, n_seg - 1)
        steps = int(np.ceil(np.log2(np.max(hi - lo) + 1)))
        if steps <= max_steps or m >= 64 * v.size:
            return np.stack([lo, hi], axis=1).astype(np.uint32), steps
        m *= 2
