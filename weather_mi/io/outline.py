"""A wrfout domain without its 3-D fields, and one sub-box of it read on the domain's grid: what a tiled
render (``reference.tile_plan``, ``satellite.tiles``, ``reference.tiled_render``) plans with in the client and
reads in each worker.

The outline (``domain_outline``) is the grid's size and spacing, the height grid ``open_wrf`` would build (from
the lowest and highest w-levels alone), the place (XLAT/XLONG, the projection) and the valid time; no process
that holds it holds a 3-D field. ``read_sub_box`` reads the columns ``x``, ``y`` of the file on that height grid
and in the domain's frame (the domain's spacing: a sub-box's mean map factor differs from the domain's).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr


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
        from .hydrometeors import bbox_of
        return bbox_of(self.dataset)

    @property
    def grid(self) -> tuple:
        """(dz, bottom, top, dx, dy) in m: what ``read_sub_box`` needs of the domain's grid."""
        return (self.dz_m, self.bottom_m, self.top_m, self.dx_m, self.dy_m)


def domain_outline(path, time=None) -> Outline:
    """The outline of one time of the wrfout ``path`` (see the module): 2-D fields and two w-levels read,
    no 3-D field."""
    import os

    from . import wrfout
    from .georef import place_coords
    from .map_factors import horizontal_spacing
    from .times import select_times, time_strings
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
    return Outline(out, path, it, dz, z_lo, z_lo + dz * nzt, dx, dy)


def _end_levels(ds, it) -> np.ndarray:
    """(2, ny, nx) heights (m) of the lowest and highest w-levels, (PH + PHB) / g in float32."""
    from .wrfout import G
    ends = [0, int(ds.sizes["bottom_top_stag"]) - 1]
    z = [np.asarray(ds[v].isel(Time=it, bottom_top_stag=ends).values, np.float32) for v in ("PH", "PHB")]
    z[0] += z[1]
    z[0] /= np.float32(G)
    return z[0]


def read_sub_box(path, time_index: int, grid: tuple, x: slice, y: slice, sizes: bool = True):
    """The columns ``x``, ``y`` (slices of mass-point indices) of the wrfout ``path`` as Hydrometeors on the
    whole domain's height grid ``grid`` (``Outline.grid``: dz, bottom, top, dx, dy in m) and in its frame;
    ``sizes``: read the fields of the scheme's particle sizes (``open_wrf``'s)."""
    from .wrf import open_wrf
    dz, bottom, top, dx, dy = grid
    hyd = open_wrf(path, time_index, x=x, y=y, dz=dz, top=top, bottom=bottom, sizes=sizes)
    # the domain's spacing (a sub-box's mean map factor differs from the domain's)
    return hyd.assign_coords(x=("x", (x.start + np.arange(hyd.sizes["x"])) * dx, hyd.x.attrs),
                             y=("y", (y.start + np.arange(hyd.sizes["y"])) * dy, hyd.y.attrs))


__all__ = ["Outline", "domain_outline", "read_sub_box"]
