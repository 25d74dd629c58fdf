"""The light pass's step through one slab (``light.LightVolume.run``'s loop kernel): the mean extinction over
each half slab, the light carried through it and stored at the slab's plane, the slabs a light ray may read.

Translucent light's pair (log D, log(D + I)) is stored as one 64-bit word a texel-plane (``pair_word``: the two
floats' bits, so the same floats): one scatter a plane in the light pass and one scalar gather a texel in every
lookup (``LightVolume._gather``) where a packet of 2 floats cost more (the drag at 300 x 300, uniform/translucent:
~3% less of a frame's kernel time, benchmarks/README.md). A differentiated pass keeps 2 floats (no gradients
through integer bits).
"""
from __future__ import annotations

import math

# extinction samples per half slab of the light pass (the midpoint rule over each half). One sample per
# slab puts a cloud top that lies inside the slab at the slab's middle, and the dense stratocumulus deck
# kept changing with the slice count (validation/slice_convergence.py: 128 vs 256 up to 2.9 with the eye
# pass's other measures, 1.9 with one sample per half; two per half: 1.8 at 1.7x the light pass's cost)
LIGHT_SUBSAMPLES = 1


def pair_word(mi, dr, a, b):
    """Two mi.Float as one mi.UInt64: a's bits low, b's high (``word_pair`` reads them back, bit for bit)."""
    return mi.UInt64(dr.reinterpret_array(mi.UInt32, a)) | (mi.UInt64(dr.reinterpret_array(mi.UInt32, b)) << 32)


def word_pair(mi, dr, v):
    """The two mi.Float of ``pair_word`` words v (mi.UInt64), as a mi.Array2f."""
    return mi.Array2f(dr.reinterpret_array(mi.Float, mi.UInt32(v)), dr.reinterpret_array(mi.Float, mi.UInt32(v >> 32)))


def _slab_step(mi, source, rays, dl, store, lane, plane, translucent: bool, offset=None, n_slices: int = 0,
               span=(None, None), keep=None, words: bool = False):
    """The step of the light pass through one slab k: (k, D, I) -> (D, I) after the slab (translucent
    light: (k, log D, log(D + I)) -> the same after the slab: optical depths subtracted, no exp or log),
    storing the light at plane k (``store[lane + k plane]``, or its 2 channels for translucent light). ``rays``:
    (q0, qs, kin, kout) of ``LightVolume._light_rays``; ``dl``: the light path (m) across one slab; ``offset``: None or each
    lane's plane offset j (slice units): its slabs are [k + j - 1/2, k + j + 1/2], the first and the last
    reaching to where the ray enters and leaves the box; ``keep``: see ``SweepPlan``; ``words``: translucent
    light's pair stored as one word (``store_light``)."""
    import drjit as dr
    q0, qs, kin, kout = rays

    def through_slab(k, D, I):
        """Carry (D, I) (translucent light: (log D, log(D + I))) through slab k in two halves, [k - 1/2, k]
        and [k, k + 1/2] (+ j) clipped to the box (slice units); store the light at plane k (+ j)."""
        kf = mi.Float(k)
        if offset is None:
            a, m, b = (dr.clip(kf + h, kin, kout) for h in (-0.5, 0.0, 0.5))
        else:
            kj = kf + offset
            a = dr.select(k == 0, kin, dr.clip(kj - 0.5, kin, kout))
            m = dr.clip(kj, kin, kout)
            b = dr.select(k == n_slices - 1, kout, dr.clip(kj + 0.5, kin, kout))
        ka, kb = span  # (nothing to sample outside the box, nor outside the occupied span)
        (e1, keep1), (e2, keep2) = (_mean_extinction(dr, source, q0, qs, x0, x1, LIGHT_SUBSAMPLES,
                                                     (x1 > x0) if ka is None else (x1 > x0) & (x1 >= ka) & (x0 <= kb),
                                                     keep)
                                    for x0, x1 in ((a, m), (m, b)))
        if translucent:  # in logarithms: D' = D exp(-tau), F' = F exp(-tau_keep), F = D + I
            log_d, log_f = D, I
            tau1, kap1 = e1 * dl * (m - a), keep1 * dl * (m - a)
            # stored at the plane: log D, log(D + I), floored at log(1e-30)
            store_light(mi, dr, store, lane + k * plane, dr.maximum(log_d - tau1, LOG_FLOOR),
                        dr.maximum(log_f - kap1, LOG_FLOOR), True, words)
            return log_d - (tau1 + e2 * dl * (b - m)), log_f - (kap1 + keep2 * dl * (b - m))
        t1, t2 = dr.exp(-e1 * dl * (m - a)), dr.exp(-e2 * dl * (b - m))
        D_mid = D * t1
        dr.scatter(store, D_mid, lane + k * plane)  # no forward light: D alone
        return D_mid * t2, I

    return through_slab


def _hold_step(mi, dr, store, lane, plane, translucent: bool, words: bool = False):
    """The store of ``_slab_step``'s ``through_slab`` at plane k of a slab where the light ray reads no medium
    (the optical depths are 0): (k, D, I) -> (D, I), the state stored as that step stores it, unchanged."""
    def hold(k, D, I):
        if translucent:
            store_light(mi, dr, store, lane + k * plane, dr.maximum(D, LOG_FLOOR), dr.maximum(I, LOG_FLOOR), True,
                        words)
        else:
            dr.scatter(store, D, lane + k * plane)
        return D, I
    return hold


def _slab_range(mi, dr, ka, kb, n_slices: int):
    """(first, end) per light ray: the slabs k in [first, end) that may sample the medium within the ray's
    occupied span [ka, kb] (slice units). A slab's halves reach half a slab beyond k, a plane offset half
    a slab more and the first and last slabs to the box's faces: a slab more than 1.5 slice units outside
    the span reads nothing (``_slab_step``'s activity mask), here with a margin of one more; none where
    ka > kb (an empty span)."""
    n = float(n_slices)
    first = mi.UInt32(dr.clip(dr.floor(ka) - 2.0, 0.0, n))
    end = mi.UInt32(dr.clip(dr.ceil(kb) + 3.0, 0.0, n))
    return first, dr.select(kb >= ka, dr.maximum(end, first), first)


def store_light(mi, dr, store, at, D, I, translucent: bool, words: bool):
    """Store the light (D, I) at texel-plane ``at`` (a mi.UInt32 index): translucent light's pair (log D,
    log(D + I)) as one word (``words``: the floats' bits, ``pair_word``) or as 2 floats, other light's D alone."""
    if words:
        dr.scatter(store, pair_word(mi, dr, D, I), at)
    elif translucent:
        dr.scatter(store, D, at * 2)
        dr.scatter(store, I, at * 2 + 1)
    else:
        dr.scatter(store, D, at)


LOG_FLOOR = math.log(1e-30)  # stored logarithms of light are at least this (the light at least 1e-30)


def source_extinction(dr, source, t, active=True, keep=None):
    """(extinction, extinction of all forward light beta - beta_f) in 1/m of the light pass's ``source``
    texture at texture coordinates t: channels (beta, beta_f), or beta alone, where no light is scattered
    forward (the low-albedo and "multiple" light: then both are beta) or where beta - beta_f is ``keep``
    x beta."""
    v = source.eval(t, active)
    e = dr.maximum(v[0], 0.0)
    if len(v) == 1:
        return e, (e if keep is None else e * keep)
    return e, dr.maximum(e - dr.maximum(v[1], 0.0), 0.0)


def _mean_extinction(dr, source, q0, qs, x0, x1, n: int, active=True, keep=None):
    """Mean extinction and mean extinction of all forward light (beta - beta_f, 1/m) along the light ray
    q0 + k qs between slice units x0 and x1, from ``n`` evenly spaced samples (the midpoint rule)."""
    ext, kept = 0.0, 0.0
    for i in range(n):
        e, k = source_extinction(dr, source, q0 + (x0 + ((i + 0.5) / n) * (x1 - x0)) * qs, active, keep)
        ext += e
        kept += k
    return ext * (1.0 / n), kept * (1.0 / n)


__all__ = ["LIGHT_SUBSAMPLES", "LOG_FLOOR", "pair_word", "source_extinction", "store_light", "word_pair"]
