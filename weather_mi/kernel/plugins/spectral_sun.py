"""The integrator's sun spectrum in spectral variants, after the air by height and cos(zenith): a table
T(mu, h, lambda) read trilinearly (clamped at its ends) at a path's 4 wavelengths in 8 packet loads.

A ``Texture3f`` read takes 8 scalar gathers per lane (32 for a path's 4 wavelengths, at every sun
connection); here every (mu_i, h_k, lambda_j) holds the Vector4f of its (h, lambda) cell's corners,

    (T(mu_i, h_k, lambda_j), T(mu_i, h_k, lambda_j+1), T(mu_i, h_k+1, lambda_j), T(mu_i, h_k+1, lambda_j+1)),

so a wavelength needs two packet loads (mu_i and mu_i+1); height and mu weights are shared by the 4
wavelengths. Memory: 16 n_mu (n_h - 1)(n_lambda - 1) bytes (a table of one height or mu is repeated).
"""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

from ..jitarrays import aligned_float


def pack_corners(t: np.ndarray) -> np.ndarray:
    """(n_mu, n_h - 1, n_lambda - 1, 4) float32 from the table ``t`` (n_mu, n_h, n_lambda), n_h, n_lambda >= 2."""
    t = np.asarray(t, np.float32)
    return np.ascontiguousarray(np.stack([t[:, :-1, :-1], t[:, :-1, 1:], t[:, 1:, :-1], t[:, 1:, 1:]], axis=-1))


def _index(x, n_minus_1):
    """(cell i in [0, n - 2], weight in [0, 1]) of the fractional index ``x`` clamped to [0, n - 1]
    (``n_minus_1`` = n - 1 >= 1, as a Float): a linear, clamped lookup."""
    x = dr.clip(x, 0.0, n_minus_1)
    i = dr.minimum(dr.floor(x), n_minus_1 - 1.0)
    return mi.UInt32(i), x - i


class SpectrumTable:
    """T(mu, h, lambda) on uniform grids (``spectrum_table``); :meth:`eval` at a point's height and mu."""

    def __init__(self, t: np.ndarray, nm, h=(0.0, 1.0), mu=(0.0, 1.0)):
        t = np.asarray(t, np.float32)
        if t.shape[0] == 1:  # one mu (or height): repeated, so every lookup has two rows to blend
            t = np.repeat(t, 2, axis=0)
        if t.shape[1] == 1:
            t = np.repeat(t, 2, axis=1)
        n_mu, n_h, n_l = t.shape
        self.data = aligned_float(mi, pack_corners(t))
        # fractional index = (v - v0) (n - 1) / (v1 - v0); strides of (mu, h, lambda) in packets
        vals = (nm[0], (n_l - 1) / (nm[1] - nm[0]), h[0], (n_h - 1) / (h[1] - h[0]), mu[0], (n_mu - 1) / (mu[1] - mu[0]),
                n_l - 1.0, n_h - 1.0, n_mu - 1.0)
        self.map = [mi.Float(v) for v in vals]
        self.stride = [mi.UInt32(v) for v in ((n_h - 1) * (n_l - 1), n_l - 1)]
        dr.make_opaque(*self.map, *self.stride)

    def eval(self, h, mu, wavelengths) -> list:
        """T at height ``h`` (m), cos zenith ``mu`` (Floats) and the 4 ``wavelengths`` (nm): 4 Floats."""
        l0, l_inv, h0, h_inv, mu0, mu_inv, nl1, nh1, nmu1 = self.map
        s_mu, s_h = self.stride
        k, th = _index((h - h0) * h_inv, nh1)
        i, tm = _index((mu - mu0) * mu_inv, nmu1)
        base = i * s_mu + k * s_h
        out = []
        for lane in range(4):
            j, tl = _index((wavelengths[lane] - l0) * l_inv, nl1)
            rows = []
            for q in (base + j, base + s_mu + j):  # mu_i, mu_i+1
                c = dr.gather(mi.Vector4f, self.data, q)
                near = dr.fma(c[1] - c[0], tl, c[0])
                far = dr.fma(c[3] - c[2], tl, c[2])
                rows.append(dr.fma(far - near, th, near))
            out.append(dr.fma(rows[1] - rows[0], tm, rows[0]))
        return out


def spectrum_table(t, nm, h=(0.0, 1.0), mu=(0.0, 1.0)) -> SpectrumTable:
    """The table ``t`` (n_mu, n_h, n_lambda) on uniform grids: wavelengths ``nm`` = (first, last) nm, heights
    ``h`` = (first, last) m and ``mu`` = (first, last) cos zenith (ignored where the table has one row)."""
    return SpectrumTable(t, nm, h, mu)


__all__ = ["SpectrumTable", "spectrum_table", "pack_corners"]
