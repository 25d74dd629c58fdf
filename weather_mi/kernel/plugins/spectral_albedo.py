"""``hydrometeor_mixture``'s single-scattering albedo at a path's 4 wavelengths (spectral variants with
``coalbedo``): the species' co-albedo spectra c_s on a uniform grid of K wavelengths and at the reference
wavelength (S x (K + 1), ``optics.spectral.coalbedo_table``) give

    omega(lambda) = 1 - (1 - omega_ref) sum_s w_s c_s(lambda) / sum_s w_s c_s(ref),

c_s linear in wavelength between the grid's nodes, held beyond its ends (``HydrometeorMixture.albedo_at``).

Storage (:func:`pack_coalbedo`): one record of 4 Q floats per wavelength cell j, (c_s(lambda_j), c_s(lambda_j+1))
for every species, then c_s(ref) for every species, zero-padded to Q = ceil(3 S / 4) packets; a lane reads its
cell's record in Q packet loads (4 for 5 species; a path's 4 wavelengths 16, where one gather per value took
S + 8 S = 45), and the reference sum comes from the first lane's record.
"""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi


def pack_coalbedo(c: np.ndarray) -> np.ndarray:
    """(K - 1, 4 Q) float32 records (module docstring) from ``c`` (S, K + 1): K grid values, then the reference."""
    c = np.asarray(c, np.float32)
    n_s, k = c.shape[0], c.shape[1] - 1
    q = -(-3 * n_s // 4)
    out = np.zeros((k - 1, 4 * q), np.float32)
    out[:, 0:2 * n_s:2], out[:, 1:2 * n_s:2] = c[:, :k - 1].T, c[:, 1:k].T
    out[:, 2 * n_s:3 * n_s] = c[:, k][None, :]
    return out


def albedo_at(table, grid, n_species: int, w, wavelengths, albedo_ref, gather4):
    """mi.Spectrum: omega at the lanes' ``wavelengths`` (nm) with the species' weights ``w`` (S Floats) and the
    albedo ``albedo_ref`` (Float) at the reference; ``table`` from :func:`pack_coalbedo` (flat), ``grid`` =
    (first nm, 1 / step, K)."""
    lo, inv_step, k = grid
    q = -(-3 * n_species // 4)
    out, inv_ref = [], None
    for lane in range(4):
        u = dr.clip((wavelengths[lane] - lo) * inv_step, 0.0, k - 1.0001)
        i = mi.UInt32(u)
        t = u - mi.Float(i)
        e = []
        for p in range(q):
            packet = gather4(table, i * q + p)
            e += [packet[c] for c in range(4)]
        if inv_ref is None:  # sum_s w_s c_s(ref): the same in every record
            ref = mi.Float(0.0)
            for s in range(n_species):
                ref += w[s] * e[2 * n_species + s]
            inv_ref = dr.select(ref > 0.0, dr.rcp(ref), 0.0)
        co = mi.Float(0.0)
        for s in range(n_species):
            c0 = e[2 * s]
            co += w[s] * dr.fma(e[2 * s + 1] - c0, t, c0)
        ratio = dr.select(inv_ref > 0.0, co * inv_ref, 1.0)
        out.append(1.0 - (1.0 - albedo_ref) * ratio)
    return mi.Spectrum(*out)


__all__ = ["pack_coalbedo", "albedo_at"]
