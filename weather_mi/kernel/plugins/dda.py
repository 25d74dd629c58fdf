"""The 3-D DDA over a grid of majorants (Amanatides & Woo 1987; pbrt-v4's ``DDAMajorantIterator``):
cell by cell along a ray, or across a cube of empty cells in one step (``empty_space_radius``).

A :class:`Grid` lives in the unit cube of the medium's sigma_t grid; the functions here are traced
Dr.Jit code used by the trackers (:mod:`.trackers`). Distances t are along the world ray (its ``d``
need not be normalised).
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi


class Grid:
    """A grid of majorants for the DDA: cell c (per axis lo <= c < lo + dims) spans [c, c + 1) in the
    coordinates q = local * scale + shift; ``majorant`` (Float, flattened (Z, Y, X), index c - lo) and
    ``empty`` (Int32, ``empty_space_radius``) per cell. Sizes and scales are opaque (no recompiles)."""

    def __init__(self, majorant, empty, dims, scale, shift: float, lo: int, reach: int | None = None):
        self.majorant, self.empty = majorant, empty
        self.dims = [dr.opaque(mi.Int32, int(v)) for v in dims]
        self.scale = [dr.opaque(mi.Float, float(v)) for v in scale]
        self.shift, self.lo = float(shift), int(lo)
        # periodic in x and y (``reach``: periods walked beyond the grid on each side, None: not periodic): the
        # cells of x and y run over the whole extended box and are looked up modulo dims (cell 0 first)
        self.reach = reach
        self.air = None  # the air of the box (``air_levels.AirLevels``): its cells count as empty, with its majorant

    def span(self, k: int):
        """(first, last) cell walked along axis k: the grid's, or for a periodic axis the extended box's
        (one period of slack on each side: the walk ends at the box anyway)."""
        if self.reach is None or k == 2:
            return self.lo, self.lo + self.dims[k] - 1
        return -(self.reach + 1) * self.dims[k], (self.reach + 2) * self.dims[k] - 1

    def wrapped(self, c, k: int):
        """Cell c of axis k as an index into the arrays (c - lo, modulo dims on a periodic axis)."""
        if self.reach is None or k == 2:
            return dr.clip(c - self.lo, 0, self.dims[k] - 1)
        m = c % self.dims[k]
        return dr.select(m < 0, m + self.dims[k], m)


def ray_box(to_local, ray, t_end, active, bounds=None):
    """The ray in the grid's local (unit-cube) coordinates (``to_local``: the world-to-unit-cube
    transform) and its overlap [t_near, t_far] with the cube within [0, t_end]; ``active`` cleared where
    it misses. ``bounds``: None (the unit cube) or per axis (lo, hi) in local units (a periodic grid's
    extended box, per lane)."""
    o_l = to_local @ ray.o
    d_l = to_local @ mi.Vector3f(ray.d)
    t_near, t_far = mi.Float(0.0), mi.Float(t_end)
    for k in range(3):
        o, d = o_l[k], d_l[k]
        b0, b1 = (0.0, 1.0) if bounds is None else bounds[k]
        flat = dr.abs(d) < 1e-30
        inv = dr.rcp(dr.select(flat, 1.0, d))
        ta, tb = (b0 - o) * inv, (b1 - o) * inv
        inside = (o >= b0) & (o <= b1)
        t_near = dr.select(flat, dr.select(inside, t_near, dr.inf), dr.maximum(t_near, dr.minimum(ta, tb)))
        t_far = dr.select(flat, dr.select(inside, t_far, -dr.inf), dr.minimum(t_far, dr.maximum(ta, tb)))
    return o_l, d_l, t_near, t_far, mi.Bool(active) & (t_near < t_far)


def locate(grid, q0, dq, t):
    """DDA state at distance t: per axis the cell (clipped to the grid; on a face, the cell the ray
    enters) and the distance at which the ray leaves it along that axis."""
    cells, nexts = [], []
    for k in range(3):
        q = q0[k] + dq[k] * t
        c = mi.Int32(dr.floor(q))
        c = dr.select((dq[k] < 0.0) & (mi.Float(c) == q), c - 1, c)
        c = dr.clip(c, *grid.span(k))
        boundary = mi.Float(c) + dr.select(dq[k] > 0.0, 1.0, 0.0)
        inv = dr.rcp(dr.select(dq[k] != 0.0, dq[k], 1.0))
        nexts.append(dr.select(dq[k] != 0.0, dr.maximum(t + (boundary - q) * inv, t), dr.inf))
        cells.append(c)
    return cells, nexts


def dda_step(grid, q0, dq, t, cells, nexts, jump_k, move):
    """Advance the DDA of the lanes ``move`` to distance t: to the next cell, or (``jump_k`` >= 1)
    to where the ray leaves the empty cube of radius jump_k; returns (cells, nexts, outside)."""
    jump = move & (jump_k > 0)
    jc, jn = locate(grid, q0, dq, t)
    tx, ty, tz = nexts
    ax = [(tx <= ty) & (tx <= tz)]
    ax.append(~ax[0] & (ty <= tz))
    ax.append(~ax[0] & ~ax[1])
    out_cells, out_nexts = [], []
    outside = mi.Bool(False)
    for a in range(3):
        plain = move & ~jump & ax[a]
        step = dr.select(dq[a] > 0.0, mi.Int32(1), mi.Int32(-1))
        delta = dr.abs(dr.rcp(dr.select(dq[a] != 0.0, dq[a], 1.0)))
        c = dr.select(jump, jc[a], dr.select(plain, cells[a] + step, cells[a]))
        out_cells.append(c)
        out_nexts.append(dr.select(jump, jn[a], dr.select(plain, nexts[a] + delta, nexts[a])))
        first, last = grid.span(a)
        outside |= (c < first) | (c > last)
    return out_cells, out_nexts, outside


def cell_of(grid, cells, active):
    """(majorant, flat index) of the current cells."""
    cx, cy, cz = (grid.wrapped(c, a) for a, c in enumerate(cells))
    idx = mi.UInt32((cz * grid.dims[1] + cy) * grid.dims[0] + cx)
    return dr.gather(mi.Float, grid.majorant, idx, active), idx


def cell_end(grid, q0, dq, cells, nexts, idx, empty, active):
    """Where the ray leaves the current cell or, in empty space, the empty cube of radius k >= 1
    about it (``empty_space_radius``): (t, k), k = 0 for a plain step."""
    k = dr.gather(mi.Int32, grid.empty, idx, active & empty)
    k = dr.select(active & empty, k, 0)
    t_cell = dr.minimum(nexts[0], dr.minimum(nexts[1], nexts[2]))
    t_exit = mi.Float(dr.inf)
    for c_k, o_k, d_k in zip(cells, q0, dq):
        face = dr.select(d_k > 0.0, mi.Float(c_k + k + 1), mi.Float(c_k - k))
        t_k = (face - o_k) * dr.rcp(dr.select(d_k != 0.0, d_k, 1.0))
        t_exit = dr.select(d_k != 0.0, dr.minimum(t_exit, t_k), t_exit)
    return dr.select(k > 0, dr.maximum(t_exit, t_cell), t_cell), k


def cell_interpolant(texels, grid, q0, dq, cells, ts, active):
    """sigma_t at distances ``ts`` along the ray, all in the texel cell ``cells``: the trilinear
    interpolant of its 8 texels (gathered once; indices clamped as the gridvolume clamps them),
    times the medium's scale. ``texels`` = (data, scale); grey extinction."""
    data, scale = texels
    if grid.reach is None:
        n = [d - 1 for d in grid.dims]  # texels per axis
        lo = [dr.clip(c, 0, m - 1) for c, m in zip(cells, n)]
        hi = [dr.clip(c + 1, 0, m - 1) for c, m in zip(cells, n)]
    else:  # periodic x and y: cell c lies between texels c and c + 1, modulo the texels per axis
        n = [grid.dims[0], grid.dims[1], grid.dims[2] - 1]
        lo = [grid.wrapped(cells[k], k) for k in range(2)] + [dr.clip(cells[2], 0, n[2] - 1)]
        hi = [dr.select(lo[k] + 1 == n[k], 0, lo[k] + 1) for k in range(2)] + [dr.clip(cells[2] + 1, 0, n[2] - 1)]
    v = {}
    for iz, z in enumerate((lo[2], hi[2])):
        for iy, y in enumerate((lo[1], hi[1])):
            for ix, x in enumerate((lo[0], hi[0])):
                v[iz, iy, ix] = dr.gather(mi.Float, data, mi.UInt32((z * n[1] + y) * n[0] + x), active)
    out = []
    for t in ts:
        f = [q0[k] + dq[k] * t - mi.Float(cells[k]) for k in range(3)]
        x00 = dr.lerp(v[0, 0, 0], v[0, 0, 1], f[0])
        x01 = dr.lerp(v[0, 1, 0], v[0, 1, 1], f[0])
        x10 = dr.lerp(v[1, 0, 0], v[1, 0, 1], f[0])
        x11 = dr.lerp(v[1, 1, 0], v[1, 1, 1], f[0])
        out.append(dr.lerp(dr.lerp(x00, x01, f[1]), dr.lerp(x10, x11, f[1]), f[2]) * scale)
    return out
