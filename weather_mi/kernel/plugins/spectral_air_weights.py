"""``hydrometeor_mixture``'s Eq. 8 weights of the box's air by wavelength (spectral variants): the air's components
(molecules, aerosol: the last A of the mixture's S tables) scatter by wavelength (molecules ~ lambda^-4) where the
hydrometeors are grey, so a lane's phase function at wavelength lambda is

    p(lambda) = sum_s beta_s(lambda) p_s(lambda) / sum_s beta_s(lambda),

the hydrometeors' beta_s their (grey) weights, the air's its scattering coefficients at the point's height and
lambda (``air_weights_spectral`` (levels, K, A) on the uniform wavelengths ``air_weights_nm`` (K,), 1/m; linear
between level centres and between nodes). Directions are still drawn with the wavelength-independent weights
(``air_weights``, the channel mean: the density whose pdf the mixture reports), so a lane's value / pdf stays
unbiased; only the value is by wavelength (:func:`by_lane`).

Storage (:func:`pack`): per level and wavelength cell j one record of 4 Q floats, (b_a(lambda_j), b_a(lambda_j+1))
for every component a, zero-padded to Q = ceil(2 A / 4) packets (A = 2: one packet load per level and lane).
"""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

TABLE_PROPERTY, NM_PROPERTY = "air_weights_spectral", "air_weights_nm"


class Weights(list):
    """The mixture's normalised weights (a list of S Floats) with the point's air context ``air`` = (z0, z1, fz,
    1 / the weights' raw sum, whether anything scatters), which :func:`by_lane` needs."""

    def __init__(self, values, air):
        super().__init__(values)
        self.air = air


def pack(table: np.ndarray) -> np.ndarray:
    """(levels, K - 1, 4 Q) float32 records (module docstring) of ``table`` (levels, K, A)."""
    t = np.asarray(table, np.float32)
    n_l, k, n_a = t.shape
    q = -(-2 * n_a // 4)
    out = np.zeros((n_l, k - 1, 4 * q), np.float32)
    out[:, :, 0:2 * n_a:2], out[:, :, 1:2 * n_a:2] = t[:, :-1, :], t[:, 1:, :]
    return out


def parse(props, air_weights, name: str, storage):
    """(The packed table (``storage`` of :func:`pack`), (first nm, 1 / step, K), A) from ``air_weights_spectral`` and
    ``air_weights_nm``; None without them. They need ``air_weights`` (levels, A) with the same levels and A."""
    if TABLE_PROPERTY not in props and NM_PROPERTY not in props:
        return None
    t = np.asarray(props[TABLE_PROPERTY], np.float32) if TABLE_PROPERTY in props else np.zeros((0,))
    nm = np.asarray(props[NM_PROPERTY], np.float64).ravel() if NM_PROPERTY in props else np.zeros(0)
    ok = (mi.is_spectral and air_weights is not None and (air_weights.ndim == 2 or air_weights.shape[2] == 1)
          and t.ndim == 3 and t.shape[0] == air_weights.shape[0]
          and t.shape[2] == air_weights.shape[1] and t.shape[1] == nm.size >= 2 and np.all(np.diff(nm) > 0)
          and np.allclose(np.diff(nm), nm[1] - nm[0]) and np.all(np.isfinite(t)) and t.min() >= 0.0)
    if not ok:
        raise ValueError(f"{name}: '{TABLE_PROPERTY}' must be a finite, non-negative (levels, K, A) tensor with "
                         f"'air_weights'' levels and A (one value per component), on the K uniform ascending wavelengths "
                         f"'{NM_PROPERTY}', in a "
                         f"spectral variant; got {t.shape} on {nm.size} wavelengths in {mi.variant()!r}")
    return storage(pack(t)), (float(nm[0]), float(1.0 / (nm[1] - nm[0])), int(nm.size)), int(t.shape[2])


def by_lane(spectral, w, wavelengths, gather4):
    """Per lane of ``wavelengths`` (nm) the mixture's weights with the air's at that wavelength (a list of 4 lists
    of S Floats, each summing to 1); ``w`` a :class:`Weights`, ``spectral`` :func:`parse`'s."""
    table, (lo, inv_step, k), n_a = spectral
    z0, z1, fz, inv_total, scattering = w.air
    q = -(-2 * n_a // 4)
    hydro = list(w[:len(w) - n_a])
    hydro_sum = dr.sum(hydro)
    out = []
    for lane in range(4):
        u = dr.clip((wavelengths[lane] - lo) * inv_step, 0.0, k - 1.0001)
        j = mi.UInt32(u)
        t = u - mi.Float(j)
        rec = []
        for z in (z0, z1):
            e = []
            for p in range(q):
                packet = gather4(table, (mi.UInt32(z) * (k - 1) + j) * q + p)
                e += [packet[c] for c in range(4)]
            rec.append(e)
        air = [dr.lerp(dr.fma(rec[0][2 * a + 1] - rec[0][2 * a], t, rec[0][2 * a]),
                       dr.fma(rec[1][2 * a + 1] - rec[1][2 * a], t, rec[1][2 * a]), fz) * inv_total for a in range(n_a)]
        total = dr.sum([hydro_sum] + air)  # in this order: hydro_sum + air_0 + air_1 ...
        use = scattering & (total > 0.0)
        inv = dr.rcp(dr.select(use, total, 1.0))
        out.append([dr.select(use, wi * inv, wi) for wi in hydro] +
                   [dr.select(use, a * inv, wa) for a, wa in zip(air, w[len(w) - n_a:])])
    return out


__all__ = ["Weights", "pack", "parse", "by_lane"]
