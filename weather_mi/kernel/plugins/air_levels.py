"""The clear air inside the medium's box as ``majorant_volpath``'s trackers see it (``air_extinction``): one
extinction per level and channel (``optics.air.inside``: the air is horizontally homogeneous in the box),
which the medium's sigma_t grid holds added to the hydrometeors'. The trackers keep the hydrometeors' empty
space: a texel cell whose 8 texels hold air alone (every channel equal to its level's air, exactly) counts as
empty for the DDA, and an empty cube of radius k about cell level c is crossed in one step with

* the majorant ``bound(c, k)``: the largest texel-cell air majorant at or above level c - k (SAFETY x the
  larger of the cell's two levels, maximum over channels), so that a cube keeps its long free flights
  (delta tracking against the thin air's own small majorant, the real collisions by the medium's lookup);
* the optical depth in closed form, :meth:`AirLevels.tau`: the gridvolume's trilinear interpolant of a grid
  constant in x and y is linear in z between the level centres (constant beyond the outer ones), so its
  integral along a ray is a difference of the piecewise quadratic C(q) = integral of sigma dq (float64),
  divided by dq/dt.

q is the texel-centre coordinate along z (q = k at level k's centre; the trackers' ``Grid`` coordinates).
"""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

from ..jitarrays import aligned_float
from .majorants import SAFETY

PROPERTY = "air_extinction"
FLAT_DQ = 1e-9  # |q_b - q_a| below this (texel-centre units): the optical depth by the midpoint value


def parse(props, check):
    """``air_extinction`` (n_levels, 3), 1/m, finite and >= 0, as float32 numpy; None without it."""
    if PROPERTY not in props:
        return None
    a = np.asarray(props[PROPERTY], np.float32)
    a = a.reshape(a.shape[0], -1) if a.ndim >= 1 else a
    check(a.ndim == 2 and a.shape[1] == 3 and a.shape[0] >= 1 and np.all(np.isfinite(a)) and a.min() >= 0.0,
          f"'{PROPERTY}' must be a finite, non-negative (levels, 3) tensor, got shape {np.shape(props[PROPERTY])}")
    return a


def cloud_cells(data: np.ndarray, air: np.ndarray, periodic: bool) -> np.ndarray:
    """Texel cells (the shape of ``majorants.texel_majorant_grid``'s) that hold more than the air: where one of
    the cell's 8 texels differs from its level's air in a channel. ``data`` (z, y, x, 3) the medium's sigma_t."""
    from .majorants import texel_majorant_grid
    if air.shape[0] != data.shape[0] or data.ndim != 4 or data.shape[3] != 3:
        raise RuntimeError(f"majorant_volpath: '{PROPERTY}' has {air.shape[0]} levels, the sigma_t grid is "
                           f"{data.shape}: they must be the same levels, with 3 channels")
    occupied = np.empty(data.shape[:3], np.float32)
    for k, level in enumerate(data):  # a level at a time: no whole-grid temporaries
        occupied[k] = np.any(level != air[k], axis=-1)
    return texel_majorant_grid(occupied, safety=1.0, periodic=periodic) > 0.0


def equal_channels(air: np.ndarray) -> bool:
    """Whether the air (levels, 3) has one extinction in every channel (a satellite's single band)."""
    return bool(np.array_equal(air[:, 0], air[:, 1]) and np.array_equal(air[:, 0], air[:, 2]))


class AirLevels:
    """The air's per-level tables on Dr.Jit arrays: ``sigma`` (levels x 3, float32), the cube bounds, the
    cumulative C(q) per segment (float64)."""

    def __init__(self, air: np.ndarray, grey: bool = False):
        if grey and not equal_channels(air):  # ``grey``: one channel (the air :func:`equal_channels`), sigma_at and tau Floats
            raise RuntimeError(f"majorant_volpath: '{PROPERTY}' differs between channels: grey tracking needs "
                               "the air's channels equal")
        self.grey = bool(grey)
        air = np.ascontiguousarray(np.asarray(air)[:, :1]) if grey else air
        a = np.asarray(air, np.float64)
        self.values, self._split = a, None
        n, self.channels = a.shape[0], a.shape[1]  # 3 (R, G, B), or a wavelength grid's K (.spectral_air)
        self.n = dr.opaque(mi.Int32, n)
        self.sigma = aligned_float(mi, np.asarray(air, np.float32))
        # texel cells -1 .. n - 1 (array index i = cell + 1) lie between levels i - 1 and i (clamped)
        lo, hi = a[np.clip(np.arange(n + 1) - 1, 0, n - 1)], a[np.clip(np.arange(n + 1), 0, n - 1)]
        cell = (np.maximum(lo, hi).max(axis=1) * SAFETY).astype(np.float32)
        self.bound = aligned_float(mi, np.maximum.accumulate(cell[::-1])[::-1])  # max over the cells at or above
        # segments j = 0 .. n: [-0.5, 0], [0, 1], ..., [n - 2, n - 1], [n - 1, n - 0.5]; their left knots
        knots = np.concatenate([[-0.5], np.arange(n, dtype=np.float64)])
        s_left, s_right = lo, hi  # each segment's end values
        width = np.concatenate([[0.5], np.ones(n - 1), [0.5]])
        slope = np.where(np.arange(n + 1)[:, None] % n == 0, 0.0, s_right - s_left)  # per unit q; 0 in the end halves
        c = np.concatenate([[np.zeros(self.channels)], np.cumsum((s_left + 0.5 * slope * width[:, None]) * width[:, None], axis=0)])
        self.knot = mi.Float64(knots)
        self.s_left, self.slope, self.c_left = (mi.Float64(v[:n + 1].ravel()) for v in (s_left, slope, c))

    def split_max(self):
        """(The air's largest channel per level, grey; each channel's excess over it, <= 0), both ``AirLevels``
        (float64 differences, kept): a free flight tracked grey against the largest channel, the channels weighted
        by the excess in closed form (``trackers``: sigma_c = sigma_max + excess_c)."""
        if self._split is None:
            top = self.values.max(axis=1, keepdims=True)
            self._split = (AirLevels(np.repeat(top, self.channels, axis=1).astype(np.float32), grey=True),
                           AirLevels(self.values - top))
        return self._split

    def cube_bound(self, cz, k, lo: int, active):
        """The majorant of the empty cube of radius ``k`` about texel cell level ``cz`` (cells from ``lo``)."""
        i = dr.clip(cz - k - lo, 0, self.n)
        return dr.gather(mi.Float, self.bound, mi.UInt32(i), active)

    def sigma_at(self, q, active):
        """sigma (Color3f, or Float where grey; 1/m) at texel-centre coordinate q: linear between the level
        centres, clamped."""
        if self.grey:
            return self.sigma_channels(q, (0,), active)[0]
        return mi.Color3f(*self.sigma_channels(q, range(3), active))

    def sigma_channels(self, q, channels, active):
        """sigma (1/m) at q of each of ``channels`` (ints, or UInt32 per lane): a list of Floats."""
        qc = dr.clip(q, 0.0, mi.Float(self.n - 1))
        i0 = dr.clip(mi.Int32(dr.floor(qc)), 0, self.n - 1)
        i1 = dr.minimum(i0 + 1, self.n - 1)
        f = qc - mi.Float(i0)
        k = self.channels
        return [dr.lerp(dr.gather(mi.Float, self.sigma, mi.UInt32(i0 * k + c), active),
                        dr.gather(mi.Float, self.sigma, mi.UInt32(i1 * k + c), active), f) for c in channels]

    def _cumulative(self, q, active, channels=range(3)):
        """C(q) per channel of ``channels`` (float64), q in float64."""
        n, k = self.n, self.channels
        j = dr.clip(mi.Int32(dr.floor(q)) + 1, 0, n)
        x = dr.clip(q, -0.5, mi.Float64(n) - 0.5) - dr.gather(mi.Float64, self.knot, mi.UInt32(j), active)
        out = []
        for c in channels:
            idx = mi.UInt32(j * k + c)
            s0 = dr.gather(mi.Float64, self.s_left, idx, active)
            sl = dr.gather(mi.Float64, self.slope, idx, active)
            out.append(dr.gather(mi.Float64, self.c_left, idx, active) + x * (s0 + 0.5 * sl * x))
        return out

    def tau(self, qz0, dqz, t0, t1, active):
        """Optical depth (Color3f, or Float where grey) along a ray whose z texel coordinate is qz0 + dqz t, over
        [t0, t1]."""
        if self.grey:
            return self.tau_channels(qz0, dqz, t0, t1, (0,), active)[0]
        return mi.Color3f(*self.tau_channels(qz0, dqz, t0, t1, range(3), active))

    def tau_channels(self, qz0, dqz, t0, t1, channels, active):
        """Optical depth of each of ``channels`` (ints, or UInt32 per lane) over [t0, t1] (``tau``): Floats."""
        dq = mi.Float64(dqz) * (mi.Float64(t1) - mi.Float64(t0))
        qa = mi.Float64(qz0) + mi.Float64(dqz) * mi.Float64(t0)
        flat = dr.abs(dq) < FLAT_DQ
        mid = self.sigma_channels(mi.Float(qa + 0.5 * dq), channels, active & flat)
        ca = self._cumulative(qa, active & ~flat, channels)
        cb = self._cumulative(qa + dq, active & ~flat, channels)
        length = mi.Float64(t1) - mi.Float64(t0)
        inv = dr.select(flat, 0.0, length / dr.select(flat, 1.0, dq))
        return [dr.select(flat, m * (t1 - t0), mi.Float((b - a) * inv)) for m, a, b in zip(mid, ca, cb)]


WEIGHTS_PROPERTY = "air_weights"


def parse_weights(props, n_tables: int, n_levels: int, plugin: str):
    """``hydrometeor_mixture``'s ``air_weights`` (n_levels, A) or (n_levels, A, 3): the Eq. 8 scattering
    coefficients (1/m; one value, or one per colour channel R, G, B) of the box's air per level of the weights grid,
    the components of its last A tables, as float32 numpy (n_levels, A, C), C = 1 or 3; None without it. Constant in
    x and y, their trilinear lookup is the levels' linear interpolation in z, the same floats as of a grid that held
    them in every voxel (a lerp between equal values is exact)."""
    if WEIGHTS_PROPERTY not in props:
        return None
    a = np.asarray(props[WEIGHTS_PROPERTY], np.float32)
    a = a[..., None] if a.ndim == 2 else a
    if a.ndim != 3 or a.shape[0] != int(n_levels) or not 1 <= a.shape[1] < int(n_tables) or a.shape[2] not in (1, 3) \
            or not np.all(np.isfinite(a)) or a.min() < 0.0:
        raise ValueError(f"{plugin}: '{WEIGHTS_PROPERTY}' must be a finite, non-negative (levels, A) or (levels, A, 3) "
                         f"tensor with the weights grid's {n_levels} levels and A below the {n_tables} tables; got "
                         f"shape {np.shape(props[WEIGHTS_PROPERTY])}")
    return np.ascontiguousarray(a)


def with_coarse_air(majorant: np.ndarray, air: np.ndarray, cell: int, safety: float = SAFETY) -> np.ndarray:
    """``majorant`` ((Z, Y, X), ``majorants.majorant_grid``'s of the hydrometeors' sigma_t, 1/m) plus the air's bound in
    each coarse cell: ``safety`` x the largest air extinction (over channels) of the levels whose texels enter the
    cell ([K cell - 1, (K + 1) cell], clipped), in place: a majorant of the hydrometeors' and the air's sum."""
    e = np.asarray(air, np.float32).reshape(air.shape[0], -1).max(axis=1)
    n = e.shape[0]
    for k in range(majorant.shape[0]):
        lo, hi = max(0, k * cell - 1), min(n, (k + 1) * cell + 1)
        majorant[k] += np.float32(safety) * e[lo:hi].max()
    return majorant


def with_texel_air(majorant: np.ndarray, air: np.ndarray, safety: float = SAFETY) -> np.ndarray:
    """``majorant`` ((nz + 1, ...), ``majorants.texel_majorant_grid``'s of the hydrometeors' sigma_t alone) with the
    air: its cells with a cloud texel (> 0) plus ``safety`` x the air's largest extinction on the cell's two levels
    (a bound of the sum); the others 0 (the air's alone: the trackers cross them with the air's own majorant),
    in place, a level at a time."""
    a = np.asarray(air, np.float32).reshape(air.shape[0], -1).max(axis=1)
    n = a.shape[0]
    for i, level in enumerate(majorant):  # texel cell i - 1: between levels i - 1 and i (clamped)
        e = np.float32(safety) * max(a[min(max(i - 1, 0), n - 1)], a[min(i, n - 1)])
        np.add(level, e, out=level, where=level > 0.0)
    return majorant
