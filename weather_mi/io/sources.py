"""Opening any input as Hydrometeors: a wrfout NetCDF file (one time or a time series), a WPS geogrid
file (a clear sky over its ground, ``geogrid``), an LES text file, a Hydrometeors Dataset in memory (plain arrays through ``weather_mi.from_arrays``) or a built-in
demo storm. The CLI, the viewer, the validation study and ``weather-mi animate`` all open their inputs
here; times are selected by ``weather_mi.io.times`` (one rule for all).

    hyd = open_source("wrfout_d01.nc", time=-1)       # one time (default the last)
    hyds = open_times(["a.nc", "b.nc"], time="all")   # every time, one height grid
    hyd = open_source(demo="cumulus")
"""
from __future__ import annotations

from pathlib import Path

DEMOS = ("supercell", "cumulus", "stratocumulus")
LES_SUFFIXES = (".txt", ".dat", ".csv")


def kind(path=None, demo: str | None = None, dataset=None) -> str:
    """What an input is: "dataset" (Hydrometeors in memory), "demo", "les" (a text file by its suffix,
    ``LES_SUFFIXES``) or "wrf" (anything else, or a list of files)."""
    if dataset is not None:
        return "dataset"
    if path is None:
        return "demo"
    if isinstance(path, (str, Path)) and Path(path).suffix.lower() in LES_SUFFIXES:
        return "les"
    return "wrf"


def open_demo(name: str = "supercell", **kw):
    """The built-in demo storm ``name`` (one of ``DEMOS``; ``kw``: its grid, see ``weather_mi.io.synthetic``)."""
    from . import synthetic
    if name not in DEMOS:
        raise ValueError(f"unknown demo storm {name!r}; expected one of {DEMOS}")
    return getattr(synthetic, name)(**kw)


def check_time(path=None, demo: str | None = None, time=None) -> None:
    """A ValueError where ``time`` is given for an input that has one time only (a demo, an LES file)."""
    if time is None:
        return
    what = kind(path, demo)
    if what == "demo":
        raise ValueError(f"--time {time} selects a time of a WRF file; the demo storm {demo or 'supercell'} "
                         "has one time: leave --time out")
    if what == "les":
        raise ValueError(f"--time {time} selects a time of a WRF file; {path} (an LES text file) has one time: "
                         "leave --time out")


def open_source(path=None, demo: str | None = None, time=None, *, dataset=None, sizes: bool = True):
    """The Hydrometeors of an input.

    Parameters
    ----------
    path : str or path, optional
        A wrfout NetCDF or LES text file (by its suffix, ``LES_SUFFIXES``); None: the demo.
    demo : str, optional
        A built-in demo storm (``DEMOS``), default "supercell" where ``path`` is None.
    time : int or str, optional
        A WRF file's time (index or timestamp, ``weather_mi.io.times``); None: the last. Refused for
        inputs with one time.
    dataset : xarray.Dataset, optional
        Hydrometeors already in memory: returned as they are.
    sizes : bool, default True
        WRF files: the microphysics scheme's effective radii (``weather_mi.io.open_wrf``).

    Returns
    -------
    xarray.Dataset
        Hydrometeors: mixing ratios (kg/kg) and dry-air density (kg/m^3) on a regular grid in metres.
    """
    from . import open_les, open_wrf
    what = kind(path, demo, dataset)
    if what == "dataset":
        return dataset
    check_time(path, demo, time)
    if what == "demo":
        return open_demo(demo or "supercell")
    if what == "les":
        return open_les(Path(path))
    if isinstance(path, (str, Path)) and is_geogrid_file(path):
        from .geogrid import open_geogrid
        if time is not None:
            raise ValueError(f"--time {time}: {path} is WPS geogrid output (static fields, no time): leave --time "
                             "out, give --date for the sun")
        return open_geogrid(path)
    return open_wrf(Path(path), time=-1 if time is None else time, sizes=sizes)


def is_geogrid_file(path) -> bool:
    """Whether ``path`` is WPS geogrid output (``io.geogrid``: a clear sky over its ground); False for anything
    that does not open as NetCDF (its reader then says why)."""
    import xarray as xr
    from .geogrid import is_geogrid
    try:
        with xr.open_dataset(path) as ds:
            return is_geogrid(ds)
    except (OSError, ValueError):
        return False


def open_times(path=None, demo: str | None = None, time="all", *, dataset=None, sizes: bool = True) -> list:
    """Every selected time of an input as Hydrometeors, all on one height grid: for WRF file(s)
    (``path``: one or a list) the times ``time`` selects ("all", a slice, a list, an index or a
    timestamp; ``weather_mi.io.open_wrf``, with the scheme's radii where ``sizes``), for the other inputs their
    one time.

    Returns
    -------
    list of xarray.Dataset
        One Hydrometeors Dataset per time, in order, each with its ``time`` and ``source`` attributes.
    """
    from . import open_wrf, time_steps
    if kind(path, demo, dataset) != "wrf":
        return [open_source(path, demo, dataset=dataset)]
    if not isinstance(path, (str, Path)):
        path = path[0] if len(path) == 1 else list(path)
    return time_steps(open_wrf(path, time=time, sizes=sizes))


def time_labels(path=None, demo: str | None = None, dataset=None) -> list[str] | None:
    """The timestamps of a WRF file's times, in order (their indices where it has none); None for the
    inputs of one time."""
    if kind(path, demo, dataset) != "wrf":
        return None
    from .wrf import wrf_times
    return wrf_times(path)
