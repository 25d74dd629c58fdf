"""An image cut into tiles of pixels, each with the sub-box of the model grid its rays need: the plan of a
tiled render (``satellite.tiles`` for a geostationary imager, ``reference.tiled_render`` for an aerial
camera), by ray set.

A tile's rays are given by their pixel corners (origins and directions, (h + 1, w + 1, 3)). The medium lies
between the heights ``bottom`` and ``top`` of the grid; the sub-box (``rays_box``) holds every point of the
rays in that slab, the slant sun path from each of those points up to ``top``, and a halo around them
(``halo``: light scattered sideways into those paths, the diffusion margin), clipped to the domain.

Why the corner rays suffice. For rays that all descend from above ``top`` (a pinhole's rays through a block
of pixels form the convex cone of its four corner rays; a geostationary imager's nearly parallel lines of
sight are bilinear between their corners), the points of the rays in the slab are the convex hull of where
the corner rays cross ``top`` and ``bottom``: that hull's vertices are the cone's edges met by the two
planes. The sun path of a point at height z reaches (top - z) / tan(elevation) towards the sun; that shift
is affine in the point, so the sun paths of the hull are the hull of its vertices' sun paths: those of the
bottom ends (the top ends have none). A tile whose rays include one that does not descend (a ray at or
above the horizon) reaches the domain's edge (the whole domain in the box); a ray whose origin is below
``top`` (a camera in or under the cloud layer: a ground camera's rays cross the whole domain) is refused by
``check_above``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DEFAULT_TILE_PX = 64       # a tile's side in pixels
DEFAULT_HALO_KM = 30.0     # the smallest measured halo whose image is within noise of one process's (docs/tiles.md)


@dataclass(frozen=True)
class Tile:
    """Pixels ``rows`` x ``cols`` (slices of the image) and the sub-box ``x``, ``y`` (slices of mass-point
    indices) they need; ``index``: the tile's number (its seed's offset)."""

    index: int
    rows: slice
    cols: slice
    x: slice
    y: slice

    @property
    def cells(self) -> int:
        """Columns of the sub-box."""
        return (self.x.stop - self.x.start) * (self.y.stop - self.y.start)

    def pixels(self, width: int) -> np.ndarray:
        """Flat (row-major) indices of the tile's pixels in an image ``width`` pixels wide."""
        r, c = np.meshgrid(np.arange(self.rows.start, self.rows.stop), np.arange(self.cols.start, self.cols.stop),
                           indexing="ij")
        return (r * int(width) + c).ravel()


def pixel_blocks(height: int, width: int, tile_px: int) -> list[tuple[slice, slice]]:
    """(rows, cols) of the image cut into blocks of at most ``tile_px`` x ``tile_px``, row by row."""
    if not (isinstance(tile_px, (int, np.integer)) and tile_px >= 1):
        raise ValueError(f"--tile-size: expected a positive number of pixels, got {tile_px!r}")
    return [(slice(r, min(r + tile_px, height)), slice(c, min(c + tile_px, width)))
            for r in range(0, height, tile_px) for c in range(0, width, tile_px)]


def check_above(origins_m, top_m: float, what: str = "the camera") -> None:
    """A ValueError where a ray starts below ``top_m`` (see the module)."""
    z = float(np.min(np.asarray(origins_m)[..., 2]))
    if z < top_m:
        raise ValueError(f"--tile-size: {what} is at {z / 1e3:.2f} km, below the top of the model's height grid "
                         f"({top_m / 1e3:.2f} km): its rays run through the cloud layer across the whole domain, so "
                         "every tile would read most of the file. Tiles are for a camera above the grid (--camera orbit, "
                         "or auto on a domain wider than 300 km); render this view without --tile-size")


def rays_box(origins_m, directions, bottom_m: float, top_m: float, sun_azimuth_deg: float,
             sun_elevation_deg: float, halo_m: float):
    """(x0, x1, y0, y1) (m) of the region the rays (corner rays of a block of pixels, (..., 3), starting at or
    above ``top_m``) need: their points between ``bottom_m`` and ``top_m``, the sun path (azimuth in the grid's
    frame, clockwise from +y; elevation, degrees) from their bottom ends up to ``top_m``, and ``halo_m``
    around (see the module); +-inf where a ray does not descend; None where no ray does."""
    o = np.asarray(origins_m).reshape(-1, 3)
    d = np.asarray(directions).reshape(-1, 3)
    down = d[:, 2] < 0
    if not down.any():
        return None
    if not down.all():
        return -np.inf, np.inf, -np.inf, np.inf
    pts = [o[:, :2] + d[:, :2] * ((z - o[:, 2]) / d[:, 2])[:, None] for z in (top_m, bottom_m)]
    az, el = np.radians(sun_azimuth_deg), np.radians(sun_elevation_deg)
    run = (top_m - bottom_m) / max(np.tan(el), 1e-3)  # the slant sun path's horizontal length
    pts.append(pts[1] + run * np.array([np.sin(az), np.cos(az)]))
    p = np.concatenate(pts)
    lo, hi = p.min(axis=0) - halo_m, p.max(axis=0) + halo_m
    return float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1])


def index_range(lo_m: float, hi_m: float, start_m: float, step_m: float, n: int) -> slice:
    """Cells (centres ``start_m`` + i ``step_m``, i < n) overlapping [lo_m, hi_m]; at least one."""
    edge = (start_m - step_m, start_m + n * step_m)  # +-inf: the domain's edge
    lo_m, hi_m = (min(max(v, edge[0]), edge[1]) for v in (lo_m, hi_m))
    i0 = int(np.floor((lo_m - start_m) / step_m + 0.5))
    i1 = int(np.ceil((hi_m - start_m) / step_m + 0.5))
    i0, i1 = min(max(i0, 0), n - 1), min(max(i1, 1), n)
    return slice(i0, max(i1, i0 + 1))


def plan_tiles(outline, origins_m, directions, sun_azimuth_deg: float, sun_elevation_deg: float, tile_px: int,
               halo_km: float) -> list[Tile]:
    """The tiles of an image of corner rays ``origins_m``, ``directions`` ((H + 1, W + 1, 3)) over
    ``outline``'s domain (``io.outline.Outline``); tiles whose rays miss the domain keep a one-column sub-box
    (their pixels see the ground or the sky only)."""
    if not (halo_km >= 0 and np.isfinite(halo_km)):
        raise ValueError(f"--halo: expected a width >= 0 in km, got {halo_km}")
    h, w = origins_m.shape[0] - 1, origins_m.shape[1] - 1
    _, ny, nx = outline.shape
    xs, ys = outline.dataset.x.values, outline.dataset.y.values
    tiles = []
    for k, (rows, cols) in enumerate(pixel_blocks(h, w, tile_px)):
        corners = (slice(rows.start, rows.stop + 1), slice(cols.start, cols.stop + 1))
        box = rays_box(origins_m[corners], directions[corners], outline.bottom_m, outline.top_m, sun_azimuth_deg,
                       sun_elevation_deg, halo_km * 1e3)
        x0, x1, y0, y1 = box if box is not None else (-np.inf, -np.inf, -np.inf, -np.inf)  # a corner column
        tiles.append(Tile(k, rows, cols, index_range(x0, x1, float(xs[0]), outline.dx_m, nx),
                          index_range(y0, y1, float(ys[0]), outline.dy_m, ny)))
    return tiles


__all__ = ["Tile", "pixel_blocks", "rays_box", "check_above", "index_range", "plan_tiles", "DEFAULT_TILE_PX",
           "DEFAULT_HALO_KM"]
