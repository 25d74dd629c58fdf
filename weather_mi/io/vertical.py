"""Conservative regridding of terrain-following model levels onto a uniform height grid.

Each column's profile f(z) is reconstructed piecewise linearly between mass levels, held constant
from the lowest mass level down to the surface (lowest w-level) and from the top mass level up to the
model top, and zero outside [surface, top]. A target cell [e_j, e_j+1] receives the average of that
reconstruction over the cell: F(e_j+1) - F(e_j) over dz, with F the cumulative integral. Column
integrals are therefore conserved exactly (for the reconstruction) and linear profiles are reproduced
exactly; cells entirely below the terrain are zero.
"""
from __future__ import annotations

import numpy as np


def _augmented(z_mass: np.ndarray, z_w: np.ndarray, f: np.ndarray):
    """Nodes (n+2, ...) and values of the reconstruction: [surface, mass levels..., top]."""
    nodes = np.concatenate([z_w[:1], z_mass, z_w[-1:]], axis=0)
    vals = np.concatenate([f[:1], f, f[-1:]], axis=0)
    return nodes, vals


def _cumulative(nodes: np.ndarray, vals: np.ndarray) -> np.ndarray:
    """Cumulative trapezoid integral at each node (starts at 0 at the surface)."""
    seg = 0.5 * (vals[1:] + vals[:-1]) * np.diff(nodes, axis=0)
    return np.concatenate([np.zeros_like(seg[:1]), np.cumsum(seg, axis=0)], axis=0)


def _integral_to(e: float, nodes, vals, cum) -> np.ndarray:
    """F(e) = integral of the reconstruction from the surface up to height e, per column."""
    n = nodes.shape[0]
    k = np.clip((nodes <= e).sum(axis=0) - 1, 0, n - 2)[None]
    z0 = np.take_along_axis(nodes, k, 0)[0]
    z1 = np.take_along_axis(nodes, k + 1, 0)[0]
    f0 = np.take_along_axis(vals, k, 0)[0]
    f1 = np.take_along_axis(vals, k + 1, 0)[0]
    c0 = np.take_along_axis(cum, k, 0)[0]
    t = np.clip(e - z0, 0.0, z1 - z0)
    slope = np.divide(f1 - f0, z1 - z0, out=np.zeros_like(f0), where=(z1 > z0))
    out = c0 + t * (f0 + 0.5 * slope * t)
    out = np.where(e <= nodes[0], 0.0, out)
    return out


def column_integral(z_w: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Finite-volume column integral sum f_k (z_w[k+1] - z_w[k]) on the native levels."""
    return (f * np.diff(z_w, axis=0)).sum(axis=0)


def cell_averages(z_mass: np.ndarray, z_w: np.ndarray, f: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Average of each column's reconstruction over target cells [edges[j], edges[j+1]] (per column).

    z_mass, f : (n, ...) mass-level heights (m) and values; z_w : (n+1, ...) w-level heights (m);
    edges     : (m+1,) uniform target cell edges (m). Returns (m, ...) float64.
    """
    nodes, vals = _augmented(z_mass.astype(np.float64), z_w.astype(np.float64), f.astype(np.float64))
    cum = _cumulative(nodes, vals)
    prev = _integral_to(float(edges[0]), nodes, vals, cum)
    out = np.empty((len(edges) - 1,) + f.shape[1:], np.float64)
    for j in range(len(edges) - 1):
        nxt = _integral_to(float(edges[j + 1]), nodes, vals, cum)
        out[j] = (nxt - prev) / (edges[j + 1] - edges[j])
        prev = nxt
    return out


def above_ground_fraction(z_w: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Fraction (m, ...) of each target cell that lies between the surface and the model top."""
    lo = np.maximum(edges[:-1, None, None], z_w[0][None])
    hi = np.minimum(edges[1:, None, None], z_w[-1][None])
    return np.clip(hi - lo, 0.0, None) / np.diff(edges)[:, None, None]
