"""WRF ``wrfout`` NetCDF -> Hydrometeors: ``open_wrf`` reads one time of a file (``weather_mi.io.wrfout``
converts it), or a time series of one or several files (``weather_mi.io.series``); times are selected by
``weather_mi.io.times`` (an index, a timestamp, "all", a slice or a list).
"""
from __future__ import annotations

import os
from pathlib import Path

import xarray as xr

from ..errors import WeatherDataError
from . import wrfout
from .series import open_wrf_series
from .times import is_several, select_times, time_strings
from .wrfout import G, R_D, RD_OVER_CP, EPS_INV, THETA0, dry_air_density  # noqa: F401  (the reader's constants)


def wrf_times(path) -> list[str]:
    """The timestamps of a wrfout file, in order (their indices where it has no ``Times``)."""
    with wrfout.open_dataset(str(path)) as ds:
        return time_strings(ds) or [str(i) for i in range(ds.sizes.get("Time", 1))]


def is_series(path, time) -> bool:
    """Whether ``open_wrf(path, time)`` asks for several times: several files, or a slice, a list or
    "all" as ``time``."""
    return not isinstance(path, (str, os.PathLike)) or is_several(time)


def open_wrf(path, time=None, *, x: slice | None = None, y: slice | None = None,
             dz: float | None = None, top: float | None = None, bottom: float | None = None,
             sizes: bool = True) -> xr.Dataset:
    """Read one time of a wrfout file into Hydrometeors on a uniform height grid.

    Parameters
    ----------
    path : str, path or list of them
        A wrfout NetCDF file; a list of files is always read as a series (``time`` counting through
        all their times in order; None: all of them).
    time : int, str, slice, list, "all" or None
        An index (negative counts from the end) or a timestamp ("2005-09-21_03:00:00" or ISO); or a
        slice, a list or "all": a time series with a ``time`` dimension (``weather_mi.io.series``).
        None: the last time of a file.
    x, y : slice, optional
        Slices of mass-point indices (west_east, south_north): a horizontal sub-box.
    dz : float, optional
        Vertical spacing (m); default the native mean layer depth.
    bottom, top : float, optional
        Extent of the height grid (m above MSL); default lowest terrain to highest model top.
    sizes : bool, default True
        The microphysics scheme's effective radii (``r_eff_<species>``, m; ``weather_mi.io.microphysics``)
        where the file names a scheme weather-mi knows; the file's RE_CLOUD/RE_ICE/RE_SNOW are read either way.

    Returns
    -------
    xarray.Dataset
        Hydrometeors (mixing ratios in kg/kg, dry-air density in kg/m^3 on a regular grid in metres).
    """
    if is_series(path, time):
        return open_wrf_series(path, "all" if time is None else time, x=x, y=y, dz=dz, top=top, bottom=bottom,
                               sizes=sizes)
    time = -1 if time is None else time
    path = os.fspath(path)
    if not Path(path).is_file():
        raise WeatherDataError(path, None, "an existing wrfout NetCDF file", "no such file")
    with wrfout.open_dataset(path) as ds:
        wrfout.check_required(ds, path)
        stamps = time_strings(ds)
        labels = stamps or [str(i) for i in range(ds.sizes.get("Time", 1))]
        it = select_times(labels, time, path, stamped=bool(stamps))[0]
        return wrfout.convert(ds, path, it, labels[it], x, y, dz, top, bottom, sizes)
