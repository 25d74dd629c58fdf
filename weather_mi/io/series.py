"""A time series of wrfout output (several times of a file, or several files) as one Hydrometeors
Dataset with a leading ``time`` dimension, every time regridded onto the same uniform height grid, so
that each time becomes an OpticalVolume on the same grid (``time_steps``).

The ``time`` coordinate holds WRF's timestamps as strings (ideal cases start at year 1, outside the
range of datetime64[ns]); ``time_index`` and ``source`` say where each time came from.
"""
from __future__ import annotations

import os
from contextlib import ExitStack
from pathlib import Path

import numpy as np
import xarray as xr

from ..errors import WeatherDataError
from . import wrfout
from .georef import valid_time_iso
from .times import select_times, time_strings


def _timeline(paths: list[str], opened: dict) -> tuple[list[tuple[str, int, str]], bool]:
    """(file, index in that file, timestamp) of every time of every file, in the order given
    (``opened``: path -> its open Dataset), and whether every file has timestamps."""
    out, stamped = [], True
    for p in paths:
        ds = opened[p]
        stamps = time_strings(ds)
        stamped = stamped and bool(stamps)
        n = ds.sizes.get("Time", 1)
        out += [(p, i, stamps[i] if stamps else str(i)) for i in range(n)]
    return out, stamped


def open_wrf_series(paths, time="all", *, x: slice | None = None, y: slice | None = None,
                    dz: float | None = None, top: float | None = None, bottom: float | None = None,
                    sizes: bool = True) -> xr.Dataset:
    """Times of one or several wrfout files as Hydrometeors with a ``time`` dimension (see the module).

    time : "all", a slice or a list of indices/timestamps into the times of all files in the order given.
    The common height grid: ``dz`` default the first time's mean layer depth; ``bottom``/``top`` default
    the lowest terrain and the highest model top over the selected times; ``sizes``: the scheme's effective
    radii (``open_wrf``)."""
    paths = [os.fspath(p) for p in ([paths] if isinstance(paths, (str, os.PathLike)) else paths)]
    if not paths:
        raise WeatherDataError("open_wrf", "path", "at least one wrfout file", "an empty list")
    for p in paths:
        if not Path(p).is_file():
            raise WeatherDataError(p, None, "an existing wrfout NetCDF file", "no such file")
    sel = {k: v for k, v in (("west_east", x), ("south_north", y)) if v is not None}
    with ExitStack() as stack:  # every file opened once, for all of its times
        opened = {p: stack.enter_context(wrfout.open_dataset(p)) for p in dict.fromkeys(paths)}
        timeline, stamped = _timeline(paths, opened)
        where = paths[0] if len(paths) == 1 else f"{len(paths)} wrfout files"
        chosen = [timeline[k] for k in select_times([e[2] for e in timeline], time, where, stamped=stamped)]
        lows, highs = [], []
        for p, it, _ in chosen:  # one grid for all: from the heights of every selected time
            z_w = wrfout.w_level_heights(opened[p], it, sel, p, np.float32)  # as convert reads them
            lows.append(float(np.min(z_w[0])))
            highs.append(float(np.max(z_w[-1])))
            if dz is None:  # the first time's mean layer depth
                dz = float(np.mean(z_w[-1] - z_w[0], dtype=np.float64) / (z_w.shape[0] - 1))
        bottom = min(lows) if bottom is None else bottom
        top = max(highs) if top is None else top
        frames = [wrfout.convert(opened[p], p, it, stamp, x, y, dz, top, bottom, sizes) for p, it, stamp in chosen]
    stamps = [stamp for _, _, stamp in chosen]
    out = xr.concat(frames, dim="time", combine_attrs="drop_conflicts", coords="minimal", compat="override")
    out = out.assign_coords(time=("time", stamps), time_index=("time", [it for _, it, _ in chosen]),
                            source=("time", [p for p, _, _ in chosen]))
    out.attrs.update({"source": paths[0] if len(paths) == 1 else ", ".join(paths), "times": len(stamps)})
    return out


def time_steps(ds: xr.Dataset) -> list[xr.Dataset]:
    """The Hydrometeors of every time of a series from ``open_wrf_series`` (or [ds] for one time), each
    with its own ``time`` and ``source`` attributes."""
    if "time" not in ds.dims:
        return [ds]
    out = []
    for k in range(ds.sizes["time"]):
        one = ds.isel(time=k)
        attrs = dict(ds.attrs, time=str(one["time"].values), time_index=int(one["time_index"].values),
                     source=str(one["source"].values))
        attrs.pop("times", None)
        valid = valid_time_iso(attrs["time"], int(attrs.get("map_proj", 0)))
        if valid:  # drop_conflicts dropped the per-time valid times
            attrs["valid_time"] = valid
        one = one.drop_vars(["time", "time_index", "source"])
        one.attrs = attrs
        out.append(one)
    return out
