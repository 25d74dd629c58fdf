"""Time selection, the one rule for every reader and front end: a time is an index (negative counts from
the end) or a timestamp ("2005-09-21_03:00:00", WRF's form, or ISO "2005-09-21T03:00:00"); a time series
is "all", a slice, or a list of indices and timestamps. ``select_times`` turns any of them into positions
in a list of time labels; ``open_wrf``, ``open_wrf_series`` and the viewer's ``--time`` all use it.
"""
from __future__ import annotations

import numpy as np

from ..errors import WeatherDataError


def parse_time(text: str | None):
    """A ``--time`` text as a time: an int where it is one (an index), else the text (a timestamp);
    None stays None."""
    if text is None:
        return None
    try:
        return int(text)
    except ValueError:
        return text


def parse_times(text: str):
    """A time-series text as a selection for ``select_times``: "all", "START:STOP[:STEP]" (a slice),
    "I,J,..." or one of them (a list of indices and timestamps), as ``weather-mi animate --time`` takes it."""
    if text == "all":
        return "all"
    if ":" in text and not any(c.isalpha() or c in "-_" for c in text.lstrip("-")):
        parts = [int(v) if v.strip() else None for v in text.split(":")]
        return slice(*parts)
    return [parse_time(v.strip()) for v in text.split(",")]


def is_several(time) -> bool:
    """Whether ``time`` selects several times: "all", a slice, a list or a tuple."""
    return isinstance(time, (slice, list, tuple)) or (isinstance(time, str) and time == "all")


def normalise_time(t) -> np.datetime64:
    """A WRF or ISO timestamp as datetime64 (seconds); a ValueError where it is not one."""
    s = str(t).strip().replace("_", "T")
    return np.datetime64(s, "s")


def time_strings(ds) -> list[str]:
    """The timestamps of a wrfout Dataset's ``Times`` variable, in order ([] where it has none)."""
    if "Times" not in ds:
        return []
    out = []
    for t in np.atleast_1d(ds["Times"].values):
        s = t.decode() if isinstance(t, bytes) else ("".join(c.decode() for c in t) if np.ndim(t) else str(t))
        out.append(s.strip())
    return out


def select_times(labels: list[str], time, where: str, *, stamped: bool = True) -> list[int]:
    """Positions in ``labels`` (the input's times, in order) of the time(s) ``time`` selects.

    Parameters
    ----------
    labels : list of str
        The timestamps of the input's times (their indices as text where the input has none).
    time : int, str, slice, list or "all"
        An index or a timestamp (one time), or "all", a slice, a list of indices and timestamps.
    where : str
        The input, as named in an error (a path, "--time").
    stamped : bool
        Whether ``labels`` are timestamps; if not, a timestamp is an error that says so.

    Returns
    -------
    list of int
        Positions in ``labels``, in the order selected (one for a single time).

    Raises
    ------
    WeatherDataError
        For an index out of range, a text that is no timestamp, a timestamp not among ``labels``, or a
        selection of no time.
    """
    n = len(labels)
    single = not is_several(time)
    if isinstance(time, str) and time == "all":
        return list(range(n))
    if isinstance(time, slice):
        chosen = list(range(n))[time]
    else:
        chosen = [_position(labels, t, where, stamped, single) for t in (time if not single else [time])]
    if not chosen:
        raise WeatherDataError(where, "Times", f"at least one of the {n} times selected", repr(time))
    return chosen


def _position(labels, t, where, stamped, single) -> int:
    n = len(labels)
    if isinstance(t, (int, np.integer)):
        if not -n <= int(t) < n:
            raise WeatherDataError(where, "Times", f"{'a time index' if single else 'time indices'} in [{-n}, {n - 1}]",
                                   str(t))
        return int(t) % n
    if not stamped:
        raise WeatherDataError(where, "Times", "a 'Times' variable to select a time by timestamp")
    try:
        want = normalise_time(t)
        have = [normalise_time(s) for s in labels]
    except ValueError as exc:
        raise WeatherDataError(where, "Times", f"{'a timestamp' if single else 'timestamps'} like 2005-09-21_03:00:00",
                               repr(t)) from exc
    for i, h in enumerate(have):
        if h == want:
            return i
    what = "one of the file's times" if single else "one of the times"
    raise WeatherDataError(where, "Times", f"{what} {labels}", repr(str(t)))
