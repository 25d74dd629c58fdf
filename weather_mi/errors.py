"""The one exception a user sees for bad input, with the file, the variable and the expectation named."""
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
