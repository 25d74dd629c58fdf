"""Majorant grids on the numpy side: bounds of the trilinear interpolant of a sigma_t grid per cell, and
the empty-space radii that let the DDA cross clear air in one step.

* :func:`majorant_grid`: the coarse grid (``cell`` fine voxels per cell, dilated by one voxel, because
  its cells are not aligned with the texel centres).
* :func:`texel_majorant_grid`: one cell between each 2 x 2 x 2 texel centres (cells -1 .. N - 1 per
  axis). The trilinear interpolant is one trilinear polynomial in such a cell, so the maximum of its 8
  texels is its exact maximum there: the tightest majorants a grid of this resolution can have.
* :func:`empty_space_radius`: "proximity clouds" (Cohen & Sheffer 1994).

All majorants are in the units of the input (1/m for sigma_t already multiplied by the medium's scale).
"""
from __future__ import annotations

import numpy as np

DEFAULT_CELL = 2  # fine voxels per coarse majorant cell (measured fastest on the storms: docs/reference-estimator.md)
SAFETY = 1.0001   # majorant = SAFETY x the maximum of the texels that enter the cell


def majorant_grid(sigma_t_zyx: np.ndarray, cell: int = DEFAULT_CELL, safety: float = SAFETY) -> np.ndarray:
    """Conservative majorants of the trilinear interpolant of ``sigma_t_zyx`` on a coarse grid.

    Parameters
    ----------
    sigma_t_zyx : numpy.ndarray
        Extinction, 1/m, (nz, ny, nx) or (nz, ny, nx, C) (the maximum over channels is used), indexed
        like a Mitsuba ``gridvolume`` (texel centres at (i + 0.5) / N, clamped at the borders). Negative
        values count as 0.
    cell : int
        Fine voxels per coarse cell along each axis.
    safety : float
        Factor on the maxima.

    Returns
    -------
    numpy.ndarray
        float32, 1/m, (ceil(nz/cell), ceil(ny/cell), ceil(nx/cell)): the majorant of coarse cell
        (K, J, I) is ``safety`` x the maximum of the fine voxels [K*cell - 1, (K+1)*cell] x ... (the
        cell's own voxels dilated by one voxel on each side, clipped to the grid): exactly the voxels
        whose values enter the interpolant somewhere inside the cell.
    """
    a = np.asarray(sigma_t_zyx)
    if a.ndim == 4:
        a = a.max(axis=3)
    if a.ndim != 3 or min(a.shape) < 1:
        raise ValueError(f"majorant_grid: expected a (nz, ny, nx) or (nz, ny, nx, C) array, got shape {a.shape}")
    cell = int(cell)
    if cell < 1:
        raise ValueError(f"majorant_grid: cell must be >= 1, got {cell}")
    a = np.asarray(a, np.float32 if a.dtype.itemsize <= 4 else np.float64)  # maxima are exact in either
    if not all(bool(np.isfinite(level).all()) for level in a):
        raise ValueError("majorant_grid: sigma_t contains non-finite values")
    # coarse cell K along an axis: the maximum over the fine voxels [K cell - 1, (K + 1) cell] (clipped); the
    # maximum is separable, so a slab of levels at a time (temporaries of a slab, not of the grid)
    nz = a.shape[0]
    d = np.empty((-(-nz // cell),) + tuple(-(-n // cell) for n in a.shape[1:]), a.dtype)
    for k, start in enumerate(range(0, nz, cell)):
        level = a[max(start - 1, 0):min(start + cell, nz - 1) + 1].max(axis=0)
        for axis in range(2):
            level = _dilated_block_max(level, axis, cell)
        d[k] = level
    return (np.maximum(d, 0.0).astype(np.float64) * float(safety)).astype(np.float32)


def _dilated_block_max(a: np.ndarray, axis: int, cell: int) -> np.ndarray:
    """The maximum of ``a`` along ``axis`` over each block of ``cell`` entries dilated by one on each side."""
    n = a.shape[axis]
    lo = [slice(None)] * a.ndim
    hi = [slice(None)] * a.ndim
    lo[axis], hi[axis] = slice(0, -1), slice(1, None)
    e = a.copy()  # 3-tap running maximum == dilation by one (edge clamped), then the blocks' maxima
    if n > 1:
        np.maximum(e[tuple(hi)], a[tuple(lo)], out=e[tuple(hi)])
        np.maximum(e[tuple(lo)], a[tuple(hi)], out=e[tuple(lo)])
    return np.maximum.reduceat(e, np.arange(0, n, cell), axis=axis)


def texel_majorant_grid(sigma_t_zyx: np.ndarray, safety: float = SAFETY, periodic: bool = False) -> np.ndarray:
    """Majorants per texel cell: the cells between 2 x 2 x 2 texel centres.

    Parameters
    ----------
    sigma_t_zyx : numpy.ndarray
        Extinction, 1/m, (nz, ny, nx) or (nz, ny, nx, C) (the maximum over channels); negative values
        count as 0.
    safety : float
        Factor on the maxima.
    periodic : bool
        Periodic in x and y: there the cells are 0 .. N - 1 (cell i between texels i and i + 1 modulo N),
        (nz + 1, ny, nx) in all.

    Returns
    -------
    numpy.ndarray
        float32, 1/m, (nz + 1, ny + 1, nx + 1): cells -1 .. N - 1 per axis (array index + 1), the first
        and last being the half cells between the box's faces and the outer texel centres (where the
        gridvolume clamps). The trilinear interpolant is one trilinear polynomial in such a cell, so
        ``safety`` x the maximum of its 8 texels bounds it there, tightly.
    """
    a = np.asarray(sigma_t_zyx)
    a = np.asarray(a, np.float32 if a.dtype.itemsize <= 4 else np.float64)  # maxima are exact in either
    a = a.max(axis=3) if a.ndim == 4 else a
    if a.ndim != 3 or min(a.shape) < 1 or not all(bool(np.isfinite(level).all()) for level in a):
        raise ValueError(f"texel_majorant_grid: expected a finite (nz, ny, nx) or (nz, ny, nx, C) array, got shape {a.shape}")
    if periodic:  # clamped in z; in x and y the first column again after the last (the tiling's next)
        a = np.pad(np.pad(a, ((1, 1), (0, 0), (0, 0)), mode="edge"), ((0, 0), (0, 1), (0, 1)), mode="wrap")
    else:
        a = np.pad(a, 1, mode="edge")  # clamped borders
    np.maximum(a, 0.0, out=a)
    for axis in range(3):  # the larger of the two texels on either side, per axis
        a = np.maximum(a[(slice(None),) * axis + (slice(0, -1),)], a[(slice(None),) * axis + (slice(1, None),)])
    out = np.empty(a.shape, np.float32)
    for k, level in enumerate(a):  # safety x in float64, a level at a time (no float64 copy of the grid)
        out[k] = level.astype(np.float64) * float(safety)
    return out


PERIODIC_RADIUS = 16  # periodic grids: empty-space radii are computed (and capped) this many cells across the wrap


def empty_space_radius(majorant: np.ndarray, periodic: bool = False) -> np.ndarray:
    """Empty-space radii of a majorant grid (proximity clouds, Cohen & Sheffer 1994).

    Parameters
    ----------
    majorant : numpy.ndarray
        Majorants (any units), (Z, Y, X).
    periodic : bool
        Periodic in x and y: the cubes may reach across the wrap (radii capped at PERIODIC_RADIUS cells).

    Returns
    -------
    numpy.ndarray
        int32, the shape of ``majorant``: for each cell the largest k such that every cell within k cells
        of it (Chebyshev distance, i.e. the cube of side 2k + 1 centred on it, cells beyond the grid
        counting as empty) has majorant 0, so that the DDA may cross that cube in one step. 0 for
        occupied cells and for empty cells next to an occupied one.
    """
    from scipy.ndimage import distance_transform_cdt
    if periodic and np.any(np.asarray(majorant) > 0.0):
        r = PERIODIC_RADIUS
        wrapped = np.pad(np.asarray(majorant), ((0, 0), (r, r), (r, r)), mode="wrap")
        return np.minimum(empty_space_radius(wrapped)[:, r:-r, r:-r], r).astype(np.int32)
    occupied = np.asarray(majorant) > 0.0
    if not occupied.any():
        return np.full(occupied.shape, max(occupied.shape), np.int32)
    np.logical_not(occupied, out=occupied)
    d = distance_transform_cdt(occupied, metric="chessboard")  # distance to the nearest occupied cell
    del occupied
    d -= 1
    np.maximum(d, 0, out=d)
    return d.astype(np.int32, copy=False)
