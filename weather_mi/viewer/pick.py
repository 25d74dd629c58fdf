"""The viewer's hover read-out: what the camera ray through a pixel meets first in the storm.

The ray is the renderers' own (``weather_mi.slicing.geometry.camera_rays``, which matches Mitsuba's
``perspective`` sensor with a horizontal field of view and its ``orthographic`` sensor): pixel
coordinates (px, py) in an image of ``spec.width`` x ``spec.height`` pixels, origin at the top-left
corner of the picture, x to the right, y down, so the centre of pixel (i, j) is (i + 0.5, j + 0.5).

The volume is a grid of cells (``OpticalVolume.bbox`` split into ``shape`` cells of ``spacing``; the
values of the Hydrometeors Dataset are cell averages at the cell centres), and the ray visits the
cells it crosses in order (an exact grid traversal, Amanatides & Woo, vectorised): the first cell whose
total extinction exceeds the threshold is the answer. The ray stops at the ground plane, as in the
pictures, and starts at the camera (a camera inside the box sees the cells in front of it).
"""
from __future__ import annotations

import numpy as np

from ..io.hydrometeors import SPECIES_NAMES
from ..scene.spec import SceneSpec
from ..slicing.geometry import film_rays


def default_threshold_per_m(vol) -> float:
    """Extinction (1/m) of a cell of optical depth 0.1 across its mean size: 0.1 / mean(dz, dy, dx)."""
    return 0.1 / float(np.mean(vol.spacing))


def pixel_ray(spec: SceneSpec, px: float, py: float) -> tuple[np.ndarray, np.ndarray]:
    """Origin and unit direction (world metres) of the camera ray through pixel coordinates (px, py)
    (origin top-left; pixel centres at half-integers): the renderers' ``film_rays``."""
    o, d = film_rays(spec, np.float64(px), np.float64(py))
    return o, d


def _cells_along(o: np.ndarray, d: np.ndarray, lo: np.ndarray, cell: np.ndarray, n: np.ndarray, t0: float, t1: float):
    """The cells (k, j, i) crossed by o + t d for t in [t0, t1], in order, with the t where the ray
    enters each: (idx (m, 3) as (i, j, k), t_enter (m,))."""
    ts = [np.array([t0, t1])]
    for a in range(3):
        if d[a] != 0.0:
            planes = lo[a] + cell[a] * np.arange(n[a] + 1)
            t = (planes - o[a]) / d[a]
            ts.append(t[(t > t0) & (t < t1)])
    t = np.unique(np.concatenate(ts))  # sorted
    length = np.diff(t)
    keep = length > 1e-9 * max(t1 - t0, 1e-30)  # a ray through an edge or a corner: no empty segment
    enter = t[:-1][keep]
    mid = enter + 0.5 * length[keep]
    idx = np.floor((o[None] + mid[:, None] * d[None] - lo[None]) / cell[None]).astype(np.int64)
    np.clip(idx, 0, n[None] - 1, out=idx)
    return idx, enter


def first_dense_voxel(hyd, vol, spec: SceneSpec, px: float, py: float,
                      threshold_per_m: float | None = None) -> dict | None:
    """The first cell along the camera ray through pixel (px, py) of ``spec`` whose total extinction
    ``vol.beta_total`` exceeds ``threshold_per_m`` (default ``default_threshold_per_m(vol)``: optical
    depth 0.1 across one cell), or None when the ray leaves the box (or meets the ground, or the pixel
    is outside the picture) without one. ``hyd``: the Hydrometeors Dataset of ``vol`` (the same grid),
    for the mixing ratios; None leaves them out.

    Returns {"index": (k, j, i) (z, y, x indices), "position_m": (x, y, z) where the ray enters the cell,
    "centre_m": (x, y, z) of the cell, "distance_m": from the camera (orthographic: from the film plane)
    to that entry point, "beta_ext_per_m": total extinction of the cell, "beta_ext_by_species": {species:
    1/m}, "mixing_ratio_kg_per_kg": {species: kg/kg for every species with a ``q_<species>`` in hyd},
    "dominant": the species of largest extinction there}."""
    w, h = int(spec.width), int(spec.height)
    if not (0.0 <= px <= w and 0.0 <= py <= h):
        return None
    beta = vol.beta_total
    n_zyx = np.asarray(beta.shape)
    if hyd is not None:
        shape = tuple(int(hyd.sizes[dim]) for dim in ("z", "y", "x"))
        if shape != tuple(n_zyx):
            raise ValueError(f"first_dense_voxel: the Hydrometeors grid {shape} (z, y, x) is not the volume's "
                             f"{tuple(n_zyx)}")
    thr = default_threshold_per_m(vol) if threshold_per_m is None else float(threshold_per_m)
    o, d = pixel_ray(spec, px, py)
    lo, hi = (np.asarray(p, np.float64) for p in vol.bbox)
    n = n_zyx[::-1]                     # (nx, ny, nz)
    cell = (hi - lo) / n                # (dx, dy, dz)
    with np.errstate(divide="ignore", invalid="ignore"):
        ta, tb = (lo - o) / d, (hi - o) / d
    ta, tb = np.where(d == 0, -np.inf, ta), np.where(d == 0, np.inf, tb)
    inside = (d != 0) | ((o >= lo) & (o <= hi))  # parallel to a pair of faces: inside them or missing
    if not np.all(inside):
        return None
    t0 = max(float(np.max(np.minimum(ta, tb))), 0.0)
    t1 = float(np.min(np.maximum(ta, tb)))
    if spec.ground is not None and d[2] < 0:
        tg = (spec.ground.height - o[2]) / d[2]
        if tg > 0:
            t1 = min(t1, tg)
    if not t1 > t0:
        return None
    idx, enter = _cells_along(o, d, lo, cell, n, t0, t1)
    dense = np.nonzero(beta[idx[:, 2], idx[:, 1], idx[:, 0]] > thr)[0]
    if dense.size == 0:
        return None
    m = int(dense[0])
    i, j, k = (int(v) for v in idx[m])
    t = float(enter[m])
    pos = o + t * d
    ext = np.asarray(vol.beta_ext[:, k, j, i], np.float64)
    out = {"index": (k, j, i), "position_m": tuple(float(v) for v in pos),
           "centre_m": tuple(float(v) for v in lo + (np.array([i, j, k]) + 0.5) * cell),
           "distance_m": t, "beta_ext_per_m": float(beta[k, j, i]),
           "beta_ext_by_species": {s: float(e) for s, e in zip(vol.species, ext)},
           "mixing_ratio_kg_per_kg": {}, "dominant": str(vol.species[int(np.argmax(ext))])}
    if hyd is not None:
        out["mixing_ratio_kg_per_kg"] = (hyd.at(k, j, i) if isinstance(hyd, DenseMixingRatios) else
                                         {s: float(hyd[f"q_{s}"].values[k, j, i]) for s in SPECIES_NAMES if f"q_{s}" in hyd})
    return out


class DenseMixingRatios:
    """The mixing ratios (kg/kg, the Dataset's float values) of the cells a hover read-out can report: those
    whose total extinction exceeds ``threshold_per_m`` (default ``default_threshold_per_m(vol)``), so that the
    viewer need not hold (or reopen) the whole Hydrometeors Dataset: 8 bytes of index and 4 a species per dense
    cell instead of 4 a species per cell. ``first_dense_voxel`` takes it in place of ``hyd`` at that threshold
    (or above); ``at`` a cell it does not hold raises KeyError."""

    def __init__(self, hyd, vol, threshold_per_m: float | None = None):
        self.threshold_per_m = default_threshold_per_m(vol) if threshold_per_m is None else float(threshold_per_m)
        self.shape = tuple(int(n) for n in vol.beta_total.shape)
        self.sizes = dict(zip(("z", "y", "x"), self.shape))
        self.index = np.flatnonzero(vol.beta_total > self.threshold_per_m)  # sorted flat (z, y, x) indices
        self.q = {s: np.asarray(hyd[f"q_{s}"].values).reshape(-1)[self.index] for s in SPECIES_NAMES if f"q_{s}" in hyd}

    @property
    def nbytes(self) -> int:
        return int(self.index.nbytes + sum(a.nbytes for a in self.q.values()))

    def at(self, k: int, j: int, i: int) -> dict:
        """{species: kg/kg} of cell (k, j, i) (z, y, x indices)."""
        flat = np.ravel_multi_index((k, j, i), self.shape)
        m = int(np.searchsorted(self.index, flat))
        if m >= self.index.size or self.index[m] != flat:
            raise KeyError(f"cell {(k, j, i)} is not denser than {self.threshold_per_m:.3g} 1/m")
        return {s: float(a[m]) for s, a in self.q.items()}
