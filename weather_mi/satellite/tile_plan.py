"""A satellite image cut into tiles of pixels, each with the sub-box of the model grid it needs: the plan
that ``satellite.tiles`` renders as Dask tasks.

The domain's outline (``domain_outline``) is what the client reads of a wrfout without its 3-D fields: the
grid's size and spacing, the height grid ``open_wrf`` would build (from the lowest and highest w-levels
alone), the place and valid time (XLAT/XLONG, the projection; or ``assume_place`` for an ideal case).
From it come the satellite's view, the one sun and every tile's sub-box, so that each worker reads only
its sub-box and renders its pixels in the whole domain's frame, height grid and light.

The halo (``tile_box``). A tile's pixels see the medium along their lines of sight between the top and
the bottom of the height grid (parallax: a slant view crosses the cloud layer up to (top - bottom)
tan(VZA) from where it meets the ground); the sun lights each point along those lines through the medium
between it and the top, (top - z) / tan(elevation) towards the sun (the slant sun path). The sub-box is
the box holding the lines' ends at the top and the bottom and the sun path of the bottom end (their convex
hull holds every point's sun path), widened on every side by ``halo_km`` for the light that scatters
sideways into those paths (the diffusion margin), and clipped to the domain.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

DEFAULT_TILE_PX = 64       # a tile's side in pixels
DEFAULT_HALO_KM = 30.0     # the smallest measured halo whose image is within noise of one process's (docs/tiles.md)


@dataclass(frozen=True)
class Outline:
    """A wrfout domain without its fields: ``dataset`` (coordinates z, y, x in the Hydrometeors frame, m;
    lat/lon and the georeference attributes where placed; the ground's 2-D coordinates), the file, the time index, the height grid
    (``dz_m``, ``bottom_m``, ``top_m``: what ``open_wrf`` builds by default) and the grid's spacing."""

    dataset: xr.Dataset
    path: str
    time_index: int
    dz_m: float
    bottom_m: float
    top_m: float
    dx_m: float
    dy_m: float

    @property
    def shape(self) -> tuple[int, int, int]:
        """(nz, ny, nx) of the Hydrometeors grid."""
        return tuple(self.dataset.sizes[d] for d in ("z", "y", "x"))

    @property
    def bbox(self):
        """((x0, y0, z0), (x1, y1, z1)) of the cells (m), as ``hydrometeors.bbox_of``."""
        from ..io.hydrometeors import bbox_of
        return bbox_of(self.dataset)


def domain_outline(path, time=None, *, lat=None, lon=None, date=None) -> Outline:
    """The outline of one time of the wrfout ``path`` (see the module): 2-D fields and two w-levels read,
    no 3-D field. ``lat``, ``lon``, ``date``: an ideal case placed as ``place.assume_place`` places it."""
    import os

    from ..io import wrfout
    from ..io.georef import place_coords
    from ..io.map_factors import horizontal_spacing
    from ..io.times import select_times, time_strings
    path = os.fspath(path)
    with wrfout.open_dataset(path) as ds:
        wrfout.check_required(ds, path)
        stamps = time_strings(ds)
        labels = stamps or [str(i) for i in range(ds.sizes.get("Time", 1))]
        it = select_times(labels, -1 if time is None else time, path, stamped=bool(stamps))[0]
        nz, ny, nx = (int(ds.sizes[d]) for d in ("bottom_top", "south_north", "west_east"))
        z_w = _end_levels(ds, it)
        # the height grid of wrfout._height_grid with its defaults (float32 levels, as the reader reads them)
        dz = float(np.mean(z_w[-1] - z_w[0], dtype=np.float64) / nz)
        z_lo, z_hi = float(np.min(z_w[0])), float(np.max(z_w[-1]))
        nzt = max(int(np.ceil((z_hi - z_lo) / dz - 1e-6)), 1)
        dx0 = float(ds.attrs.get("DX", 1000.0))
        factors = {v: wrfout.read(ds, v, it, {}, path, (ny, nx)) for v in wrfout.MAP_FACTOR_VARS if v in ds}
        if "MAPFAC_MX" in factors and "MAPFAC_MY" in factors:
            factors.pop("MAPFAC_M", None)
        dx, dy, _ = horizontal_spacing(path, dx0, float(ds.attrs.get("DY", dx0)), factors, stacklevel=3)
        coords, attrs = place_coords(ds, path, it, labels[it], {}, z_w[0].astype(np.float64))
    out = xr.Dataset(coords={"z": ("z", z_lo + dz * (np.arange(nzt) + 0.5)), "y": ("y", np.arange(ny) * dy),
                             "x": ("x", np.arange(nx) * dx), **coords},
                     attrs={"source": path, **attrs})
    if lat is not None or lon is not None or date is not None:
        from ..scene.place import assume_place
        out = assume_place(out, lat, lon, date)
    return Outline(out, path, it, dz, z_lo, z_lo + dz * nzt, dx, dy)


def _end_levels(ds, it) -> np.ndarray:
    """(2, ny, nx) heights (m) of the lowest and highest w-levels, (PH + PHB) / g in float32."""
    from ..io.wrfout import G
    ends = [0, int(ds.sizes["bottom_top_stag"]) - 1]
    z = [np.asarray(ds[v].isel(Time=it, bottom_top_stag=ends).values, np.float32) for v in ("PH", "PHB")]
    z[0] += z[1]
    z[0] /= np.float32(G)
    return z[0]


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


def pixel_blocks(height: int, width: int, tile_px: int) -> list[tuple[slice, slice]]:
    """(rows, cols) of the image cut into blocks of at most ``tile_px`` x ``tile_px``, row by row."""
    if not (isinstance(tile_px, (int, np.integer)) and tile_px >= 1):
        raise ValueError(f"--tile-size: expected a positive number of pixels, got {tile_px!r}")
    return [(slice(r, min(r + tile_px, height)), slice(c, min(c + tile_px, width)))
            for r in range(0, height, tile_px) for c in range(0, width, tile_px)]


def tile_box(rays, rows: slice, cols: slice, bottom_m: float, top_m: float, sun_azimuth_deg: float,
             sun_elevation_deg: float, halo_m: float) -> tuple[float, float, float, float]:
    """(x0, x1, y0, y1) (m) of the region the pixels ``rows`` x ``cols`` of ``rays`` (corner rays, a
    ``RayTable``) need: their lines of sight between heights ``top_m`` and ``bottom_m``, the sun path (azimuth
    in the grid's frame, clockwise from +y; elevation, degrees) from their bottom ends up to ``top_m``, and
    ``halo_m`` around (see the module)."""
    o = rays.origins_m[rows.start:rows.stop + 1, cols.start:cols.stop + 1].reshape(-1, 3)
    d = rays.directions[rows.start:rows.stop + 1, cols.start:cols.stop + 1].reshape(-1, 3)
    pts = [o[:, :2] + d[:, :2] * ((z - o[:, 2]) / d[:, 2])[:, None] for z in (top_m, bottom_m)]
    az, el = np.radians(sun_azimuth_deg), np.radians(sun_elevation_deg)
    run = (top_m - bottom_m) / max(np.tan(el), 1e-3)  # the slant sun path's horizontal length
    pts.append(pts[1] + run * np.array([np.sin(az), np.cos(az)]))
    p = np.concatenate(pts)
    lo, hi = p.min(axis=0) - halo_m, p.max(axis=0) + halo_m
    return float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1])


def index_range(lo_m: float, hi_m: float, start_m: float, step_m: float, n: int) -> slice:
    """Cells (centres ``start_m`` + i ``step_m``, i < n) overlapping [lo_m, hi_m]; at least one."""
    i0 = int(np.floor((lo_m - start_m) / step_m + 0.5))
    i1 = int(np.ceil((hi_m - start_m) / step_m + 0.5))
    i0, i1 = min(max(i0, 0), n - 1), min(max(i1, 1), n)
    return slice(i0, max(i1, i0 + 1))


def plan_tiles(outline: Outline, rays, sun_azimuth_deg: float, sun_elevation_deg: float, tile_px: int,
               halo_km: float) -> list[Tile]:
    """The tiles of an image of ``rays`` (corner rays (H + 1, W + 1)) over ``outline``'s domain; tiles whose
    region misses the domain keep a one-column sub-box (their pixels see the ground only)."""
    if not (halo_km >= 0 and np.isfinite(halo_km)):
        raise ValueError(f"--halo: expected a width >= 0 in km, got {halo_km}")
    h, w = rays.origins_m.shape[0] - 1, rays.origins_m.shape[1] - 1
    _, ny, nx = outline.shape
    xs, ys = outline.dataset.x.values, outline.dataset.y.values
    tiles = []
    for k, (rows, cols) in enumerate(pixel_blocks(h, w, tile_px)):
        x0, x1, y0, y1 = tile_box(rays, rows, cols, outline.bottom_m, outline.top_m, sun_azimuth_deg,
                                  sun_elevation_deg, halo_km * 1e3)
        tiles.append(Tile(k, rows, cols, index_range(x0, x1, float(xs[0]), outline.dx_m, nx),
                          index_range(y0, y1, float(ys[0]), outline.dy_m, ny)))
    return tiles


__all__ = ["Outline", "domain_outline", "Tile", "pixel_blocks", "tile_box", "index_range", "plan_tiles",
           "DEFAULT_TILE_PX", "DEFAULT_HALO_KM"]
