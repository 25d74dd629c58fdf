"""Conservative regridding of terrain-following model levels onto a uniform height grid.

Each column's profile f(z) is reconstructed piecewise linearly between mass levels, held constant
from the lowest mass level down to the surface (lowest w-level) and from the top mass level up to the
model top, and zero outside [surface, top]. A target cell [e_j, e_j+1] receives the average of that
reconstruction over the cell: F(e_j+1) - F(e_j) over dz, with F the cumulative integral. Column
integrals are therefore conserved exactly (for the reconstruction) and linear profiles are reproduced
exactly; cells entirely below the terrain are zero.

Memory and time: a :class:`VerticalPlan` finds, once for every field, the node segment of each target
edge in each column (1 byte per target cell, and its offset in the segment, 4 bytes for float32 heights); each field is then
regridded column by column in one compiled pass (numba, parallel; float64 inside a column only, the float
operations of the numpy expressions it replaced, in their order), into a float32 output by default. A field
costs its input and its output, never a float64 copy of the whole field.
"""
from __future__ import annotations

import numpy as np
from numba import njit, prange


class VerticalPlan:
    """Where each target edge falls in each column of the w-level heights ``z_w`` ((n+1, ny, nx), m): shared
    by every field regridded onto ``edges`` ((m+1,), m, increasing). ``z_mass`` (n, ny, nx): the mass-level
    heights, default the mid-points of ``z_w``."""

    def __init__(self, z_w: np.ndarray, edges: np.ndarray, z_mass: np.ndarray | None = None):
        self.z_w, self.z_mass = z_w, z_mass
        self.edges = np.asarray(edges, np.float64)
        n, cols = z_w.shape[0] - 1, z_w.shape[1:]
        kind = np.uint8 if n + 1 < 256 else np.uint16
        self.k = np.empty((len(self.edges),) + cols, kind)   # segment [nodes[k], nodes[k+1]] holding the edge
        self.t = np.empty((len(self.edges),) + cols, np.result_type(z_w.dtype, np.float32))  # the edge's height above nodes[k], clipped
        z_w2, z_mass2, given = self._columns()
        m1 = len(self.edges)
        _plan_columns(z_w2, z_mass2, given, self.edges, bool(np.all(np.diff(self.edges) >= 0)),
                      self.k.reshape(m1, -1), self.t.reshape(m1, -1))

    @property
    def shape(self) -> tuple[int, ...]:
        """Shape of a regridded field: (m,) + the columns' shape."""
        return (len(self.edges) - 1,) + self.z_w.shape[1:]

    def _columns(self):
        """(z_w (n+1, columns), z_mass (n, columns) or a placeholder, whether z_mass is given)."""
        n = self.z_w.shape[0] - 1
        z_w = np.ascontiguousarray(self.z_w).reshape(n + 1, -1)
        if self.z_mass is None:
            return z_w, np.zeros((1, 1), z_w.dtype), False
        return z_w, np.ascontiguousarray(self.z_mass).reshape(n, -1), True

    def average(self, f: np.ndarray, out: np.ndarray | None = None, dtype=np.float32) -> np.ndarray:
        """Average of each column's reconstruction of ``f`` ((n, ny, nx) on the mass levels) over the target
        cells: (m, ny, nx), written into ``out`` (new, of ``dtype``, when None). One compiled pass over the
        columns (:func:`_average_columns`: float64 inside a column, the float operations of the numpy
        expressions it replaced, in their order)."""
        out = np.empty(self.shape, dtype) if out is None else out
        z_w, z_mass, given = self._columns()
        m1 = len(self.edges)
        _average_columns(z_w, np.ascontiguousarray(f).reshape(z_w.shape[0] - 1, -1), self.k.reshape(m1, -1),
                         self.t.reshape(m1, -1), self.edges, z_mass, given, out.reshape(m1 - 1, -1))
        return out


COLUMNS = 256  # columns per block of the compiled passes: their levels' values side by side in memory


@njit(cache=True)
def _block_nodes(z_w, z_mass, given_mass, c0, c1):  # pragma: no cover - compiled
    """The reconstruction nodes (float64, (n + 2, c1 - c0)) of columns c0 .. c1 - 1: the surface, the mass levels
    (given, or the mid-points of the w-levels), the top."""
    n = z_w.shape[0] - 1
    nodes = np.empty((n + 2, c1 - c0))
    for c in range(c1 - c0):
        nodes[0, c], nodes[n + 1, c] = np.float64(z_w[0, c0 + c]), np.float64(z_w[n, c0 + c])
    for i in range(n):
        for c in range(c1 - c0):
            nodes[i + 1, c] = np.float64(z_mass[i, c0 + c]) if given_mass else \
                0.5 * (np.float64(z_w[i + 1, c0 + c]) + np.float64(z_w[i, c0 + c]))
    return nodes


@njit(parallel=True, cache=True)
def _plan_columns(z_w, z_mass, given_mass, edges, edges_increasing, k, t):  # pragma: no cover - compiled
    """``VerticalPlan``'s segments ``k`` (the count of nodes at or below the edge, less one, in [0, n]) and
    offsets ``t`` (the edge's height above node k, clipped to the segment) of every edge in every column."""
    n, cols, m1 = z_w.shape[0] - 1, z_w.shape[1], edges.shape[0]
    for b in prange((cols + COLUMNS - 1) // COLUMNS):
        c0 = b * COLUMNS
        c1 = min(c0 + COLUMNS, cols)
        nodes = _block_nodes(z_w, z_mass, given_mass, c0, c1)
        for c in range(c1 - c0):
            ordered = edges_increasing
            for i in range(n + 1):
                ordered = ordered and nodes[i, c] <= nodes[i + 1, c]
            below = 0
            for j in range(m1):
                e = edges[j]
                if ordered:  # the count of nodes at or below e: where the last edge's count ended, onwards
                    while below < n + 2 and nodes[below, c] <= e:
                        below += 1
                else:
                    below = 0
                    for i in range(n + 2):
                        if nodes[i, c] <= e:
                            below += 1
                kk = min(max(below - 1, 0), n)
                v = e - nodes[kk, c]
                v = v if v > 0.0 else 0.0
                hi = nodes[kk + 1, c] - nodes[kk, c]
                k[j, c0 + c] = kk
                t[j, c0 + c] = hi if v > hi else v  # 0 below the surface: F = 0 there


@njit(parallel=True, cache=True)
def _average_columns(z_w, f, k, t, edges, z_mass, given_mass, out):  # pragma: no cover - compiled
    """``VerticalPlan.average`` per column: the nodes (surface, mass levels, top), the values held constant
    beyond the lowest and top mass levels, the slopes, the cumulative trapezoid integral F, and each target cell's
    (F(e_j+1) - F(e_j)) / dz from the plan's segments ``k`` and offsets ``t``. Arrays (levels, columns), worked
    through in blocks of ``COLUMNS`` columns (each level's values of a block contiguous)."""
    n, cols, m1 = f.shape[0], f.shape[1], edges.shape[0]
    for b in prange((cols + COLUMNS - 1) // COLUMNS):
        c0 = b * COLUMNS
        c1 = min(c0 + COLUMNS, cols)
        w = c1 - c0
        nodes = _block_nodes(z_w, z_mass, given_mass, c0, c1)
        vals, slope, cum = np.empty((n + 2, w)), np.empty((n + 1, w)), np.empty((n + 2, w))
        for i in range(n):
            for c in range(w):
                vals[i + 1, c] = np.float64(f[i, c0 + c])
        for c in range(w):
            vals[0, c], vals[n + 1, c] = vals[1, c], vals[n, c]
            cum[0, c] = 0.0
        for i in range(n + 1):
            for c in range(w):
                h = nodes[i + 1, c] - nodes[i, c]
                slope[i, c] = (vals[i + 1, c] - vals[i, c]) / h if h > 0 else 0.0
                seg = 0.5 * (vals[i + 1, c] + vals[i, c]) * h
                cum[i + 1, c] = seg if i == 0 else cum[i, c] + seg
        prev = np.zeros(w)
        for j in range(m1):
            for c in range(w):
                kk, tt = k[j, c0 + c], np.float64(t[j, c0 + c])
                nxt = cum[kk, c] + tt * (vals[kk, c] + 0.5 * slope[kk, c] * tt)
                if j > 0:
                    out[j - 1, c0 + c] = (nxt - prev[c]) / (edges[j] - edges[j - 1])
                prev[c] = nxt


def column_integral(z_w: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Finite-volume column integral sum f_k (z_w[k+1] - z_w[k]) on the native levels."""
    return (f * np.diff(z_w, axis=0)).sum(axis=0)


def cell_averages(z_mass: np.ndarray, z_w: np.ndarray, f: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Average of each column's reconstruction over target cells [edges[j], edges[j+1]] (per column).

    z_mass, f : (n, ...) mass-level heights (m) and values; z_w : (n+1, ...) w-level heights (m);
    edges     : (m+1,) uniform target cell edges (m). Returns (m, ...) float64 (one field: a reader with
    several fields on one grid shares a :class:`VerticalPlan`).
    """
    return VerticalPlan(z_w, edges, z_mass).average(f, dtype=np.float64)


def above_ground_fraction(z_w: np.ndarray, edges: np.ndarray, dtype=np.float32) -> np.ndarray:
    """Fraction (m, ...) of each target cell that lies between the surface and the model top (level by level:
    no float64 copy of the whole grid)."""
    surface, top = z_w[0], z_w[-1]
    out = np.empty((len(edges) - 1,) + surface.shape, dtype)
    for j in range(len(edges) - 1):
        lo = np.maximum(edges[j], surface)
        hi = np.minimum(edges[j + 1], top)
        out[j] = np.clip(hi - lo, 0.0, None) / (edges[j + 1] - edges[j])
    return out
