"""Forward peaks counted as unscattered light (delta-M scaling, Wiscombe 1977).

Every hydrometeor phase table has a narrow forward peak: a 1 mm drop, snow and graupel put ~45% of
the scattered light within 0.1 deg of forward (diffraction, 4 pi p(0) ~ 1e8), ice crystals ~60%
within 3 deg (transmission through parallel faces), cloud droplets ~40% within 3 deg. To a path
tracer the sun light scattered into such a peak is a rare event: the forward-scattered sun beam is
reached only by paths aimed within the peak's width of the sun, so the estimate is a sum of rare,
huge values. At practical sample counts it is noisy (fireflies) AND low. The peak scatters light
by less than its width, so it can be moved from the phase function into the transmittance:

    p(Theta) = f delta_peak(Theta) + (1 - f) p'(Theta)        f: the peak's excess in the cone
    sigma_t' = sigma_t (1 - omega f),  sigma_s' = sigma_s (1 - f),  omega' = omega (1 - f) / (1 - omega f)

with p' the table whose values inside ``cone_deg`` are pulled toward p(cone_deg). For the transfer
equation this is exact in the limit of a narrow peak (what DISORT does internally, and MYSTIC's and
MCARaTS's truncation); it only moves light by less than ``cone_deg``.

Measured (``validation/forward_peak_slabs.py``: slabs of optical depth 4, mu0 0.5, against DISORT
with the tables' own 2048 Legendre moments): without delta-M the path tracer reads low and noisy,
e.g. snow R = 0.270 +- 0.002 against DISORT's 0.473, cloud nadir radiance noisy to +-25%; with a
0.1 deg cone snow is within 2.3% but ice is still heavy-tailed; with 3 deg every flux agrees within
1.2% (cloud, ice, snow) and the cloud's radiances within 2 standard errors, with 5-40x smaller
errors. Hence the default, 3 deg. What it changes in an image: the sun seen through thin cloud
keeps, within 3 deg of its disk, the light that the peak would have spread around it (the
aureole: ``validation/sun_aureole.py`` renders it with 0.1 deg), and light transmitted through a
cloud is blurred by less than 3 deg.

A slab whose phase function is 40% a 0.02 deg lobe renders identically with and without delta-M
under a uniform sky, but under a point sun the full table reads 22% low at 1024 spp, with
Mitsuba's own volpath as with majorant_volpath (tests/test_forward_peak.py).

The extinction stays grey (the reference's medium has one sigma_t), so one f per species is taken
out of every channel: the smallest channel excess. What differs between channels (at most ~2% of
the scattered light for a 1 mm drop) stays in the table, spread evenly over the cone.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .volume import OpticalVolume
from .phase.table import PhaseTable

DEFAULT_CONE_DEG = 3.0  # validation/forward_peak_slabs.py: agrees with DISORT; 0 and 0.1 read low (rare events)
MAX_CONE_DEG = 10.0  # a larger cone would blur what the images show


def check_cone_deg(cone_deg) -> float:
    """``cone_deg`` as a float in [0, MAX_CONE_DEG] (0: no truncation), else ValueError."""
    if isinstance(cone_deg, bool) or not isinstance(cone_deg, (int, float, np.integer, np.floating)):
        raise ValueError(f"forward_peak_deg must be a number of degrees in [0, {MAX_CONE_DEG}], got {cone_deg!r}")
    c = float(cone_deg)
    if not (0.0 <= c <= MAX_CONE_DEG):
        raise ValueError(f"forward_peak_deg must be in [0, {MAX_CONE_DEG}] deg, got {cone_deg!r}")
    return c


def peak_excess(table: PhaseTable, cone_deg: float) -> np.ndarray:
    """(3,) the fraction of scattered energy within ``cone_deg`` of forward above the level
    p(cone_deg): integral over the cone of (p - p(cone_deg)) dOmega, per channel."""
    th = np.deg2rad(cone_deg)
    flat = table.eval(th) * 2 * np.pi * (1 - np.cos(th))
    return np.asarray(table.cone_fraction(th) - flat)


def truncated_table(table: PhaseTable, cone_deg: float, fraction: float) -> PhaseTable:
    """p' = (p - f delta_peak) / (1 - f): inside the cone every channel is flat, at p(cone_deg) plus
    what is left of its excess once ``fraction`` has left it (excess_c - f, spread evenly over the
    cone: the channels' peaks differ by a few percent, and a narrow residual peak would be as much a
    rare event as the whole one); outside the cone p' = p / (1 - f)."""
    th0 = np.deg2rad(cone_deg)
    theta = np.union1d(table.theta, [th0])
    p = table.eval(theta)
    residual = np.maximum(peak_excess(table, cone_deg) - fraction, 0.0)  # >= 0 by the choice of fraction
    inside = theta < th0
    p[inside] = table.eval(th0) + residual / (2 * np.pi * (1 - np.cos(th0)))
    return PhaseTable(theta, p / (1 - fraction), table.wavelengths_m, f"{table.name} (peak < {cone_deg:g} deg as unscattered)")


def peak_tables(tables, cone_deg: float):
    """(f (S,), truncated tables): each table's forward-peak share within ``cone_deg`` (the smallest
    channel excess, :func:`peak_excess`) and the table without it (:func:`truncated_table`; the table
    itself where f = 0)."""
    f = np.array([max(float(np.min(peak_excess(t, cone_deg))), 0.0) for t in tables])
    return f, [truncated_table(t, cone_deg, fs) if fs > 0 else t for t, fs in zip(tables, f)]


CHUNK = 1 << 20  # voxels at a time in ``delta_scaled`` and ``ScaledWeights``: temporaries of a chunk, not of the grid


def _chunks(n: int):
    for start in range(0, n, CHUNK):
        yield slice(start, min(start + CHUNK, n))


class ScaledWeights:
    """The delta-scaled Eq. 8 weights w'_s = w_s (1 - f_s) / sum_r w_r (1 - f_r) (0 where that sum is not > 0),
    (S, z, y, x) float32, computed where they are read instead of held (``delta_scaled(deferred_weights=True)``):
    ``chunk`` gives a run of voxels (the path tracer's medium packs them with each voxel's scattering coefficient
    in one pass, ``kernel.medium.phase_arrays``), ``np.asarray`` the whole grid. The same float32 operations as
    on the whole grid, so the same values."""

    deferred = True

    def __init__(self, weights, factors):
        self.source = weights  # (S, z, y, x) float32: the weights before the scaling
        self.factors = np.asarray(factors, np.float32).reshape(-1)  # (S,) 1 - f_s
        self.shape, self.dtype, self.ndim = tuple(weights.shape), np.dtype(np.float32), len(weights.shape)

    def __len__(self):
        return self.shape[0]

    def chunk(self, part: slice) -> np.ndarray:
        """(S, n) the scaled weights of the voxels ``part`` of the flattened (z, y, x) grid."""
        ws = np.multiply(np.asarray(self.source).reshape(self.shape[0], -1)[:, part], self.factors[:, None])
        total = ws.sum(axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            np.divide(ws, total, out=ws)
        np.copyto(ws, np.float32(0), where=~(total > 0))
        return ws

    def __array__(self, dtype=None, copy=None):
        out = np.empty(self.shape, np.float32)
        flat = out.reshape(self.shape[0], -1)
        for part in _chunks(flat.shape[1]):
            flat[:, part] = self.chunk(part)
        return out if dtype is None else out.astype(dtype, copy=False)

    def __getitem__(self, index):
        return np.asarray(self)[index]

    def __iter__(self):
        return iter(np.asarray(self))


def is_grey(albedo) -> bool:
    """Whether an albedo grid (..., 3) is one channel seen three times (a broadcast view: stride 0)."""
    return isinstance(albedo, np.ndarray) and albedo.ndim >= 1 and albedo.shape[-1] == 3 and albedo.strides[-1] == 0


def grey_albedo(channel: np.ndarray) -> np.ndarray:
    """(z, y, x, 3): the one-channel albedo ``channel`` (z, y, x) as the three channels an OpticalVolume holds,
    a read-only broadcast view (4 bytes per cell, not 12)."""
    return np.broadcast_to(np.ascontiguousarray(channel, np.float32)[..., None], tuple(channel.shape) + (3,))


def delta_scaled(vol: OpticalVolume, cone_deg: float = DEFAULT_CONE_DEG, *, species_extinction: bool = True,
                 deferred_weights: bool = False) -> OpticalVolume:
    """``vol`` with each species' forward peak within ``cone_deg`` counted as unscattered light.

    Per voxel (albedo omega_c, Eq. 8 weights w_s, peak fractions f_s), with F = sum_s w_s f_s the
    share of the scattered light in the peaks:  sigma_t' = sigma_t (1 - mean_c(omega) F),
    omega'_c = omega_c (1 - F) / (1 - mean_c(omega) F),  w'_s ~ w_s (1 - f_s), and per-species
    beta_s' = beta_s - f_s w_s mean(omega) sigma_t (they sum to sigma_t'). Returns ``vol`` itself
    when ``cone_deg`` is 0 or no table has a peak there. ``species_extinction`` False: the per-species
    beta_s are left as ``vol``'s (shared, not scaled; 4 bytes per cell and species saved), for a caller that
    reads only beta_total, the albedo and the weights (the path tracer's medium, ``reference.passes``).
    ``deferred_weights``: the weights are a :class:`ScaledWeights`, computed where read (20 bytes per cell
    for five species not held). A grey albedo (``is_grey``) stays one channel.

    Memory: the new grids, F (4 bytes per cell) and temporaries of ``CHUNK`` voxels; every value is what the
    whole-grid float32 expressions give (the same operations in the same order, voxel by voxel)."""
    if check_cone_deg(cone_deg) == 0.0:
        return vol
    cone_deg = float(cone_deg)
    f, truncated = peak_tables(vol.phase_tables, cone_deg)
    if not np.any(f > 0):
        return vol
    f32 = f.astype(np.float32)
    w = vol.weights  # (S, z, y, x)
    F = np.tensordot(f32, w, axes=1).reshape(-1)  # (z y x,): whole, as BLAS sums it
    grey = is_grey(vol.albedo)
    bt_in = np.asarray(vol.beta_total).reshape(-1)
    alb_in = np.asarray(vol.albedo)[..., 0].reshape(-1, 1) if grey else np.asarray(vol.albedo).reshape(-1, 3)
    beta_total = np.empty(vol.beta_total.shape, np.float32)
    albedo = np.empty(vol.beta_total.shape + (alb_in.shape[1],), np.float32)
    bt_out, alb_out = beta_total.reshape(-1), albedo.reshape(-1, alb_in.shape[1])
    beta_ext = vol.beta_ext
    if species_extinction:
        beta_ext = np.empty(vol.beta_ext.shape, np.float32)
        be_out, be_in, w_in = (np.asarray(a).reshape(len(f32), -1) for a in (beta_ext, vol.beta_ext, w))
    with np.errstate(invalid="ignore", divide="ignore"):
        for c in _chunks(F.size):
            a_in = np.broadcast_to(alb_in[c], (alb_in[c].shape[0], 3)) if grey else alb_in[c]
            omega_mean = a_in.mean(axis=-1)
            scattering = omega_mean * bt_in[c]  # 1/m
            if species_extinction:  # beta_s - f_s w_s scattering: the peaks' scattering, now transmitted
                be = np.multiply(f32[:, None], w_in[:, c])
                np.multiply(be, scattering[None], out=be)
                np.maximum(np.subtract(be_in[:, c], be, out=be), 0, out=be_out[:, c])
            bt = np.multiply(F[c], scattering)
            np.maximum(np.subtract(bt_in[c], bt, out=bt), 0, out=bt_out[c])
            a = np.multiply(alb_in[c], ((1 - F[c]) / (1 - omega_mean * F[c]))[:, None])
            np.copyto(a, alb_in[c], where=~(bt_in[c] > 0)[:, None])
            np.clip(a, 0, 1, out=alb_out[c])
    del F
    weights = ScaledWeights(w, 1 - f32)
    if not deferred_weights:
        weights = np.asarray(weights)
    return replace(vol, beta_ext=beta_ext, beta_total=beta_total,
                   albedo=grey_albedo(albedo[..., 0]) if grey else albedo, weights=weights,
                   attrs={**vol.attrs, "forward_peak_deg": cone_deg,
                          "forward_peak_fraction": dict(zip(vol.species, f.round(6).tolist()))},
                   phase_tables=tuple(truncated))


__all__ = ["DEFAULT_CONE_DEG", "ScaledWeights", "check_cone_deg", "delta_scaled", "grey_albedo", "is_grey", "peak_excess",
           "peak_tables", "truncated_table"]
