"""Where each eye ray can meet the medium: a coarse, conservative map of the grid's occupied blocks and,
per view, the span of every pixel ray between its first and last occupied sample. The eye pass visits
only the slabs of that span: the slabs it skips hold no extinction at all (the trilinear texture is
exactly 0 there), so they change neither the transmittance nor the colour, and images are bit-identical
to visiting every slab of the box.

Conservative by construction: the map marks the blocks (BLOCK voxels a side) that hold a voxel with
extinction, or are next to one (the reach of trilinear interpolation is one voxel), and then their
neighbours; a ray through any point where the interpolated extinction is positive therefore runs at
least two blocks through marked ones, and the march samples every half block.
"""
from __future__ import annotations

import numpy as np

BLOCK = 2  # voxels per block side (4: spans ~2x longer, the demo's drag 0-18% slower, benchmarks/README.md)


def occupied_blocks(beta_total: np.ndarray, block: int = BLOCK) -> np.ndarray:
    """(z, y, x) bool map of blocks: a block is marked when a voxel within one voxel of it (or in it)
    has extinction, and then the marks are grown by one block."""
    voxels = _grown(np.asarray(beta_total) > 0)  # the trilinear interpolation's reach: one voxel
    nb = [-(-n // block) for n in voxels.shape]
    padded = np.zeros([n * block for n in nb], dtype=bool)
    padded[:voxels.shape[0], :voxels.shape[1], :voxels.shape[2]] = voxels
    blocks = padded.reshape(nb[0], block, nb[1], block, nb[2], block).any(axis=(1, 3, 5))
    return _grown(blocks)


def _grown(a: np.ndarray) -> np.ndarray:
    """``a`` or any of its 26 neighbours (no wrap-around at the faces)."""
    out = a.copy()
    for dz in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                shift = (dz, dy, dx)
                src = tuple(slice(max(-c, 0), a.shape[i] - max(c, 0)) for i, c in enumerate(shift))
                dst = tuple(slice(max(c, 0), a.shape[i] - max(-c, 0)) for i, c in enumerate(shift))
                out[dst] |= a[src]
    return out


class OccupancyMap:
    """The occupied blocks of a grid as a nearest-filtered Dr.Jit texture, and the spans of rays in it."""

    def __init__(self, mi, beta_total: np.ndarray, grid_box, spacing, block: int = BLOCK):
        import drjit as dr
        self.mi = mi
        blocks = occupied_blocks(beta_total, block)
        self.empty = not blocks.any()
        self.tex = mi.Texture3f(mi.TensorXf(blocks.astype(np.float32)[..., None]), use_accel=False,
                                filter_mode=dr.FilterMode.Nearest)
        lo = np.asarray(grid_box[0], dtype=np.float64)
        block_m = block * np.asarray(spacing, dtype=np.float64)[::-1]         # (x, y, z) block size
        span = np.array(blocks.shape[::-1], dtype=np.float64) * block_m     # the padded blocks' extent
        self.lo, self.inv_span = lo, 1.0 / span
        self.step_m = 0.5 * float(block_m.min())

    def spans(self, origin, direction, t0, t1):
        """(ta, tb): per ray, the part of [t0, t1] between its first and last sample in a marked block,
        widened by a step (ta > tb: none). Directions given as numbers should be opaque Dr.Jit values, or
        every new one compiles a kernel."""
        mi = self.mi
        import drjit as dr
        op = lambda v: dr.opaque(mi.Float, float(v))  # noqa: E731  (new values compile nothing)
        glo = mi.Point3f(*(op(c) for c in self.lo))
        inv = mi.Vector3f(*(op(c) for c in self.inv_span))
        dt = op(self.step_m)
        n = dr.width(t0)

        def body(t, first, last):
            occupied = self.tex.eval((origin + t * direction - glo) * inv)[0] > 0.5
            first = dr.select(occupied & (first > t), t, first)
            last = dr.select(occupied, t, last)
            return t + dt, first, last

        start = mi.Float(t0)
        _, first, last = dr.while_loop((start, dr.full(mi.Float, np.inf, n), dr.full(mi.Float, -np.inf, n)),
                                       lambda t, f, l: t <= t1 + dt, body)
        ta = dr.maximum(first - dt, t0)
        tb = dr.minimum(last + dt, t1)
        dr.eval(ta, tb)
        return ta, tb
