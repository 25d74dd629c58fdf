"""The exceptions a user sees: bad input (the file, the variable and the expectation named) and an output
that could not be written (the file named, with what was kept)."""
from __future__ import annotations


class WeatherDataError(ValueError):
    """Bad input data: names the file (or source), the variable and what was expected."""

    def __init__(self, source: str, variable: str | None, expected: str, found: str | None = None):
        self.source = str(source)
        self.variable = variable
        self.expected = expected
        self.found = found
        where = f"{self.source}"
        if variable:
            where += f", variable {variable!r}"
        msg = f"{where}: expected {expected}"
        if found:
            msg += f"; found {found}"
        super().__init__(msg)


class OutputWriteError(OSError):
    """An output file that could not be written (a full disk, a quota, a lost mount): names the file and
    what it is (``what``: "checkpoint", "EXR image", ...), the system's reason and, in ``advice``, what
    was kept and how to go on. ``errno`` is the cause's (``errno.ENOSPC`` for a full disk)."""

    def __init__(self, path, what: str, errno: int | None, reason: str, advice: str = ""):
        super().__init__(errno, reason, str(path))
        self.path, self.what, self.reason, self.advice = str(path), what, reason, advice

    def __str__(self) -> str:
        advice = f"; {self.advice}" if self.advice else ""
        return f"could not write the {self.what} {self.path}: {self.reason}{advice}"

    def __reduce__(self):
        return type(self), (self.path, self.what, self.errno, self.reason, self.advice)


class DomainTooLargeError(WeatherDataError, MemoryError):
    """A domain whose grids would not fit in memory, raised before anything is allocated: names the input,
    the grid, the estimate in GB against what is available, and what to do (``weather_mi.io.budget``)."""

    def __init__(self, source: str, grid: tuple[int, ...], step: str, needed: float, available: float):
        self.grid, self.step, self.needed, self.available = tuple(grid), step, float(needed), float(available)
        super().__init__(source, None, f"a domain that fits in memory for {step}: the {' x '.join(map(str, grid))} "
                         f"(z, y, x) grid needs about {needed / 1e9:.1f} GB more at peak and {available / 1e9:.1f} GB are "
                         "available",
                         "too large; read a sub-box (open_wrf(..., x=slice(i0, i1), y=slice(j0, j1))), coarser levels "
                         "(open_wrf(..., dz=...), top=... or bottom=...), or render it in tiles on a cluster "
                         "(the environment variable WEATHER_MI_MAX_MEMORY_GB sets the memory to plan for)")
