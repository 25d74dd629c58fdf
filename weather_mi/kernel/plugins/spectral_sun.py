"""The integrator's sun spectrum in spectral variants, after the air by height and cos(zenith): a table
T(mu, h, lambda) read trilinearly (clamped at its ends) at a path's 4 wavelengths.

A ``Texture3f`` read of each wavelength computes its own height and mu weights and cell; here the 4
wavelengths share them (the point is one), and each wavelength reads its two neighbouring values in the four
(mu, h) rows around the point: 32 scalar gathers from the table as it is (4 n_mu n_h n_lambda bytes, 1.6 MB
for the 33 x 129 x 95 of ``optics.air.sunlight``). Packing the corners into 16-byte packets (8 packet loads)
was tried and was slower at that size, 119 against 83 ns per lane for the texture (it quadruples the table,
which then misses the caches), where this takes 72 (2^20 random lanes, kernel time, alternating rounds).
"""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

from ..jitarrays import aligned_float


def _index(x, n_minus_1):
    """(cell i in [0, n - 2], weight in [0, 1]) of the fractional index ``x`` clamped to [0, n - 1]
    (``n_minus_1`` = n - 1 >= 1, as a Float): a linear, clamped lookup."""
    x = dr.clip(x, 0.0, n_minus_1)
    i = dr.minimum(dr.floor(x), n_minus_1 - 1.0)
    return mi.UInt32(i), x - i


class SpectrumTable:
    """T(mu, h, lambda), the table ``t`` (n_mu, n_h, n_lambda) on uniform grids: wavelengths ``nm`` = (first, last)
    nm, heights ``h`` = (first, last) m and ``mu`` = (first, last) cos zenith (ignored where the table has one row);
    :meth:`eval` at a point's height and mu."""

    def __init__(self, t: np.ndarray, nm, h=(0.0, 1.0), mu=(0.0, 1.0)):
        t = np.asarray(t, np.float32)
        if t.shape[0] == 1:  # one mu (or height): repeated, so every lookup has two rows to blend
            t = np.repeat(t, 2, axis=0)
        if t.shape[1] == 1:
            t = np.repeat(t, 2, axis=1)
        n_mu, n_h, n_l = t.shape
        self.data = aligned_float(mi, np.ascontiguousarray(t))
        # fractional index = (v - v0) (n - 1) / (v1 - v0); strides of mu and h in values
        vals = (nm[0], (n_l - 1) / (nm[1] - nm[0]), h[0], (n_h - 1) / (h[1] - h[0]), mu[0], (n_mu - 1) / (mu[1] - mu[0]),
                n_l - 1.0, n_h - 1.0, n_mu - 1.0)
        self.map = [mi.Float(v) for v in vals]
        self.stride = [mi.UInt32(v) for v in (n_h * n_l, n_l)]
        dr.make_opaque(*self.map, *self.stride)

    def eval(self, h, mu, wavelengths) -> list:
        """T at height ``h`` (m), cos zenith ``mu`` (Floats) and the 4 ``wavelengths`` (nm): 4 Floats."""
        l0, l_inv, h0, h_inv, mu0, mu_inv, nl1, nh1, nmu1 = self.map
        s_mu, s_h = self.stride
        k, th = _index((h - h0) * h_inv, nh1)
        i, tm = _index((mu - mu0) * mu_inv, nmu1)
        row = i * s_mu + k * s_h
        rows = (row, row + s_h, row + s_mu, row + s_mu + s_h)  # (mu_i, h_k), (mu_i, h_k+1), (mu_i+1, h_k), ...
        weights = ((1.0 - tm) * (1.0 - th), (1.0 - tm) * th, tm * (1.0 - th), tm * th)
        out = []
        for lane in range(4):
            j, tl = _index((wavelengths[lane] - l0) * l_inv, nl1)
            acc = mi.Float(0.0)
            for r, wt in zip(rows, weights):
                a = dr.gather(mi.Float, self.data, r + j)
                acc = dr.fma(wt, dr.fma(dr.gather(mi.Float, self.data, r + j + 1) - a, tl, a), acc)
            out.append(acc)
        return out


__all__ = ["SpectrumTable"]
