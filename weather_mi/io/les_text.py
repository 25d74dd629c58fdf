"""SHDOM / pyshdom "particle properties" LWC text files (LES output): the text read and checked, up to the
voxels' fields on the file's levels (:func:`read_voxel_file`; ``io.les.open_les`` makes them Hydrometeors).

The format (see ../shared/data/README.md, "Formats")::

    # a comment line
    nx ny nz
    dx dy            (km)
    z_1 ... z_nz     (level altitudes, km; on the dx dy line or on their own line)
    [i,j,k,lwc,reff  (an optional column-name line)]
    i j k LWC reff [veff]     one line per listed voxel, 0-based indices

Values are separated by spaces or commas; header lines may carry trailing ``# comments`` and may be
combined or split (the header is read as a stream of numbers: 3 sizes, 2 spacings, nz levels).
Voxels that are not listed are clear; files that list every voxel (zeros included) work the same.

A file cut short is an error naming the line: a last voxel line without its newline whose last number
has fewer decimals than the line before (cut inside the number), or a file that lists clear voxels too,
in order (so every voxel), with fewer lines than nx ny nz.
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass, field

import numpy as np

from ..errors import WeatherDataError

_SPLIT = re.compile(r"[,;\s]+")
_INT = re.compile(r"^[+-]?\d+$")
# column-name aliases -> canonical column
_ALIASES = {"i": "i", "ix": "i", "j": "j", "iy": "j", "k": "k", "iz": "k",
            "lwc": "lwc", "reff": "reff", "re": "reff", "r_eff": "reff", "veff": "veff", "ve": "veff",
            "v_eff": "veff"}
_POSITIONAL = {4: ("i", "j", "k", "lwc"), 5: ("i", "j", "k", "lwc", "reff"),
               6: ("i", "j", "k", "lwc", "reff", "veff")}
_INDEX_INFO = {"i": ("nx", "x"), "j": ("ny", "y"), "k": ("nz", "z (level)")}


def _show(line: str, n: int = 90) -> str:
    s = line.strip()
    return repr(s if len(s) <= n else s[:n] + "...")


def _tokens(line: str) -> list[str]:
    """Tokens of a header line: trailing '# comment' removed, split on spaces, commas or semicolons."""
    body = line.split("#", 1)[0].strip()
    return [t for t in _SPLIT.split(body) if t]


def _floats(tokens: list[str]) -> list[float] | None:
    try:
        return [float(t) for t in tokens]
    except ValueError:
        return None


def _looks_like_data(tokens: list[str]) -> bool:
    """A voxel line: 4 to 6 numbers, the first three integers (i j k)."""
    return 4 <= len(tokens) <= 6 and all(_INT.match(t) for t in tokens[:3]) and _floats(tokens) is not None


def _decimals(token: str) -> int:
    """Digits printed after the decimal point (0 for an integer, mantissa digits with an exponent)."""
    mantissa = token.lower().split("e", 1)[0]
    return len(mantissa.split(".", 1)[1]) if "." in mantissa else 0


def _last_digit_unit(token: str) -> float:
    """One unit of the last digit printed in a number: 0.001 for '0.438', 1 for '12', 1e-5 for '4.38e-3'."""
    mantissa, _, exponent = token.lower().partition("e")
    try:
        shift = int(exponent) if exponent else 0
    except ValueError:
        shift = 0
    return 10.0 ** (shift - _decimals(mantissa))


def _read_lines(path: str) -> tuple[list[str], bool]:
    """The file's lines and whether it ends with a newline."""
    if not os.path.exists(path):
        raise WeatherDataError(path, None, "an existing SHDOM/pyshdom LWC text file", "no such file")
    if os.path.isdir(path):
        raise WeatherDataError(path, None, "an SHDOM/pyshdom LWC text file", "a directory")
    try:
        with open(path, encoding="utf-8") as fh:
            text = fh.read()
    except UnicodeDecodeError as exc:
        raise WeatherDataError(path, None, "a plain-text SHDOM/pyshdom LWC file",
                               f"undecodable bytes ({exc.reason} at byte {exc.start})") from exc
    except OSError as exc:
        raise WeatherDataError(path, None, "a readable SHDOM/pyshdom LWC text file", str(exc)) from exc
    lines = text.splitlines()
    if not any(line.strip() for line in lines):
        raise WeatherDataError(path, None, "an SHDOM/pyshdom LWC text file (comment, nx ny nz, dx dy, levels, voxels)",
                               "an empty file")
    return lines, text.endswith(("\n", "\r"))


@dataclass
class _Header:
    """The header as it is read: the comment lines, then a stream of numbers (3 sizes, 2 spacings, nz levels)."""

    comments: list[str] = field(default_factory=list)
    sizes: list[float] = field(default_factory=list)
    spacing: list[float] = field(default_factory=list)
    levels: list[float] = field(default_factory=list)
    level_unit: float = np.inf           # one unit of the finest last digit printed in the levels (km)
    level_lines: list[int] = field(default_factory=list)   # 0-based lines holding levels
    stage: str = "sizes"                 # the numbers read next: "sizes", "spacing" or "levels"
    nz_expected: int = 0
    seen_numbers: bool = False

    def take(self, path: str, n: int, line: str, toks: list[str], vals: list[float]) -> None:
        """Add the numbers of header line n (0-based) to the sizes, spacings or levels, in that order."""
        self.seen_numbers = True
        for tok, v in zip(toks, vals):
            if self.stage == "sizes":
                if not (np.isfinite(v) and v == int(v) and v >= 1):
                    raise WeatherDataError(path, f"header line {n + 1}", "three positive integers nx ny nz",
                                           f"{tok!r} in {_show(line)}")
                self.sizes.append(v)
                if len(self.sizes) == 3:
                    self.stage, self.nz_expected = "spacing", int(v)
            elif self.stage == "spacing":
                if not (np.isfinite(v) and v > 0):
                    raise WeatherDataError(path, f"header line {n + 1}", "two positive numbers dx dy (km)",
                                           f"{tok!r} in {_show(line)}")
                self.spacing.append(v)
                if len(self.spacing) == 2:
                    self.stage = "levels"
            else:
                self.levels.append(v)
                self.level_unit = min(self.level_unit, _last_digit_unit(tok))
                if not self.level_lines or self.level_lines[-1] != n:
                    self.level_lines.append(n)

    def complete(self) -> bool:
        return self.stage == "levels" and len(self.levels) >= self.nz_expected


def _read_header_numbers(path: str, lines: list[str]) -> tuple[_Header, int]:
    """The comment lines and the header numbers, and the 0-based index of the line after the last level
    (or of the line that stopped the levels: column names or voxel data)."""
    h = _Header()
    n = 0
    while n < len(lines):
        line = lines[n]
        stripped = line.strip()
        n += 1
        if not stripped:
            continue
        if stripped.startswith("#"):
            if not h.seen_numbers:
                h.comments.append(stripped.lstrip("#").strip())
            continue
        toks = _tokens(line)
        if not toks:  # only a trailing comment
            continue
        vals = _floats(toks)
        if h.stage == "sizes" and vals is None and not h.seen_numbers and not h.comments:
            h.comments.append(stripped)  # a first line of free text without '#' is the comment line
            continue
        if h.stage == "levels" and (vals is None or (len(toks) != h.nz_expected - len(h.levels)
                                                     and _looks_like_data(toks))):
            return h, n - 1  # column names or voxel data before all levels were read: reported later
        if vals is None:
            what = {"sizes": "three positive integers nx ny nz",
                    "spacing": "two positive numbers dx dy (km)"}[h.stage]
            raise WeatherDataError(path, f"header line {n}", what, _show(line))
        h.take(path, n - 1, line, toks, vals)
        if h.complete():
            break
    return h, n


def _checked_levels(path: str, h: _Header, n: int) -> np.ndarray:
    """The level altitudes (km) once the header is known to be whole: nz of them, finite, increasing."""
    if h.stage == "sizes":
        raise WeatherDataError(path, "header (nx ny nz)", "three positive integers nx ny nz after the comment line",
                               f"{len(h.sizes)} number(s) before the end of the file")
    if h.stage == "spacing":
        raise WeatherDataError(path, "header (dx dy)", "two positive numbers dx dy (km) after nx ny nz",
                               f"{len(h.spacing)} number(s) before the end of the file")
    nz, lines_ = int(h.sizes[2]), h.level_lines
    where = ("" if not lines_ else f"line {lines_[0] + 1}" if len(lines_) == 1 else
             f"lines {lines_[0] + 1}-{lines_[-1] + 1}")
    if len(h.levels) != nz:
        raise WeatherDataError(path, "levels", f"nz = {nz} level altitudes (km) after dx dy",
                               f"{len(h.levels)} on {where}" if h.levels else f"none before line {n + 1}")
    lev = np.asarray(h.levels, dtype=np.float64)
    if not np.all(np.isfinite(lev)):
        raise WeatherDataError(path, "levels", "finite level altitudes (km)", f"non-finite values on {where}")
    if nz > 1 and not np.all(np.diff(lev) > 0):
        bad = int(np.argmax(np.diff(lev) <= 0))
        raise WeatherDataError(path, "levels", "strictly increasing level altitudes (km)",
                               f"level {bad + 1} = {lev[bad]:g} km then level {bad + 2} = {lev[bad + 1]:g} km "
                               f"on {where}")
    return lev


def _column_names(lines: list[str], n: int) -> tuple[list[str] | None, int]:
    """The optional column-name line at or after line n (lower-cased names, or None), and the index of the
    first line of the data block."""
    while n < len(lines):
        stripped = lines[n].strip()
        if not stripped or stripped.startswith("#"):
            n += 1
            continue
        toks = _tokens(lines[n])
        if toks and _floats(toks) is None and all(re.match(r"^[A-Za-z_][\w\[\]\(\)/^-]*$", t) for t in toks):
            return [t.lower() for t in toks], n + 1
        break
    return None, n


def _parse_header(path: str, lines: list[str]):
    """(comment, comments, (nx, ny, nz), (dx_km, dy_km), levels_km, one unit of the finest last digit
    printed in the levels (km), column names or None, index of first data line)."""
    h, n = _read_header_numbers(path, lines)
    lev = _checked_levels(path, h, n)
    names, start = _column_names(lines, n)
    comment = h.comments[0] if h.comments else ""
    return comment, h.comments, tuple(int(s) for s in h.sizes), tuple(h.spacing), lev, h.level_unit, names, start


def _column_map(path: str, names: list[str] | None, ncol: int, line_no) -> dict[str, int]:
    if names is not None:
        canon = [_ALIASES.get(re.sub(r"[\[\(].*$", "", nm)) for nm in names]
        if len(names) != ncol:
            raise WeatherDataError(path, "column names", f"one name per data column ({ncol} columns)",
                                   f"{len(names)} names {','.join(names)}")
        unknown = [nm for nm, c in zip(names, canon) if c is None]
        if unknown:
            raise WeatherDataError(path, "column names", "columns among i, j, k, lwc, reff, veff",
                                   f"{', '.join(unknown)}")
        cols = {c: idx for idx, c in enumerate(canon)}
        missing = [c for c in ("i", "j", "k", "lwc") if c not in cols]
        if missing or len(cols) != len(canon):
            raise WeatherDataError(path, "column names", "each of i, j, k, lwc once (reff, veff optional)",
                                   ",".join(names))
        return cols
    if ncol not in _POSITIONAL:
        raise WeatherDataError(path, f"data line {line_no[0]}", "4 to 6 columns: i j k LWC [reff [veff]]",
                               f"{ncol} columns")
    return {c: idx for idx, c in enumerate(_POSITIONAL[ncol])}


class _LineNumbers:
    """1-based file line numbers of the voxel rows, worked out only when a message needs one."""

    def __init__(self, body: list[str], start: int):
        self._body, self._start, self._numbers = body, start, None

    def __getitem__(self, row: int) -> int:
        if self._numbers is None:
            self._numbers = [self._start + m + 1 for m, line in enumerate(self._body)
                             if line.split("#", 1)[0].strip()]
        return self._numbers[int(row)]


def _parse_data(path: str, lines: list[str], start: int):
    """(data array (n, ncol), row -> 1-based file line number, separator) of the voxel block."""
    body = lines[start:]
    line_no = _LineNumbers(body, start)
    first = next((line.split("#", 1)[0] for line in body if line.split("#", 1)[0].strip()), None)
    if first is None:
        return np.zeros((0, 5)), line_no, None
    sep = "," if "," in first else (";" if ";" in first else None)
    try:
        # numpy's C reader skips blank lines and '#' comments (whole-line or trailing)
        return np.loadtxt(body, delimiter=sep, comments="#", ndmin=2, dtype=np.float64), line_no, sep
    except ValueError:
        pass
    # locate the offending line for the message (only on the error path)
    ncol = len(_data_tokens(first, sep))
    for n, row in enumerate(body):
        toks = _data_tokens(row, sep)
        if not toks:
            continue
        if len(toks) != ncol:
            raise WeatherDataError(path, f"data line {start + n + 1}", f"{ncol} columns like the first voxel line",
                                   f"{len(toks)} in {_show(row)}")
        if _floats(toks) is None:
            raise WeatherDataError(path, f"data line {start + n + 1}", "numbers i j k LWC reff [veff]", _show(row))
    raise WeatherDataError(path, "data", "numeric voxel lines i j k LWC reff [veff]", "an unreadable data block")


def _data_tokens(row: str, sep: str | None) -> list[str]:
    body = row.split("#", 1)[0]
    if not body.strip():
        return []
    return [t.strip() for t in body.split(sep)] if sep else body.split()


def _check_values(path, data, cols, line_no, lines, sizes):
    nx, ny, nz = sizes
    finite = np.isfinite(data)
    if not finite.all():
        r, c = np.argwhere(~finite)[0]
        name = next(k for k, v in cols.items() if v == c)
        raise WeatherDataError(path, name, "finite numbers on every voxel line",
                               f"{data[r, c]} on line {line_no[r]}: {_show(lines[line_no[r] - 1])}")
    for name, (nname, axis) in _INDEX_INFO.items():
        col = data[:, cols[name]]
        limit = {"nx": nx, "ny": ny, "nz": nz}[nname]
        bad = np.flatnonzero(col != np.round(col))
        if bad.size:
            r = bad[0]
            raise WeatherDataError(path, name, f"an integer 0-based {axis} index",
                                   f"{name} = {col[r]:g} on line {line_no[r]}")
        bad = np.flatnonzero((col < 0) | (col >= limit))
        if bad.size:
            r = bad[0]
            raise WeatherDataError(path, name, f"a 0-based {axis} index with 0 <= {name} < {nname} = {limit}",
                                   f"{name} = {int(col[r])} on line {line_no[r]} ({bad.size} line(s) out of range)")
    for name, what in (("lwc", "LWC >= 0 g/m^3"), ("reff", "effective radius >= 0 um"),
                       ("veff", "effective variance >= 0")):
        if name in cols:
            bad = np.flatnonzero(data[:, cols[name]] < 0)
            if bad.size:
                r = bad[0]
                raise WeatherDataError(path, name, what, f"{data[r, cols[name]]:g} on line {line_no[r]} "
                                       f"({bad.size} negative value(s))")


def _check_complete(path, lines, ends_with_newline, data, cols, line_no, sep, sizes):
    """Errors for a file cut short (see the module docstring)."""
    n = data.shape[0]
    if n > 1 and not ends_with_newline and line_no[n - 1] == len(lines):
        last, prev = (_data_tokens(lines[line_no[r] - 1], sep)[-1] for r in (n - 1, n - 2))
        if _decimals(last) < _decimals(prev):
            raise WeatherDataError(path, f"data line {line_no[n - 1]}",
                                   f"a complete voxel line (its last number printed like line {line_no[n - 2]}'s "
                                   f"{prev!r})", f"{last!r} at the end of a file without a final newline: "
                                   "the file looks cut")
    nx, ny, nz = sizes
    if 1 < n < nx * ny * nz and np.any(data[:, cols["lwc"]] == 0):
        ii, jj, kk = (data[:, cols[c]].astype(np.int64) for c in ("i", "j", "k"))
        for flat in ((kk * ny + jj) * nx + ii, (ii * ny + jj) * nz + kk):
            if flat[0] == 0 and np.all(np.diff(flat) == 1):
                raise WeatherDataError(path, "voxel lines", f"nx ny nz = {nx * ny * nz} voxel lines (the file "
                                       "lists clear voxels too, in order, so every voxel)",
                                       f"{n} lines, the last on line {line_no[n - 1]}: the file looks cut")


def _voxel_fields(path, data, cols, line_no, sizes):
    """LWC (g/m^3) and the r_eff (um) / v_eff fields on the (nz, ny, nx) grid of the file's levels, from the
    voxel rows; r_eff and v_eff are 0 where there is no liquid. A voxel listed twice is an error."""
    nx, ny, nz = sizes
    ii, jj, kk = (data[:, cols[c]].astype(np.int64) for c in ("i", "j", "k"))
    flat = (kk * ny + jj) * nx + ii
    if data.shape[0] > 1:
        order = np.argsort(flat, kind="stable")
        dup = np.flatnonzero(flat[order][1:] == flat[order][:-1])
        if dup.size:
            a, b = order[dup[0]], order[dup[0] + 1]
            raise WeatherDataError(path, "i,j,k", "each voxel listed at most once",
                                   f"voxel (i, j, k) = ({ii[a]}, {jj[a]}, {kk[a]}) on lines {line_no[a]} and "
                                   f"{line_no[b]} ({dup.size} duplicate line(s))")
    shape = (nz, ny, nx)
    lwc = np.zeros(shape)
    lwc.flat[flat] = data[:, cols["lwc"]]
    extra = {}
    for name in ("reff", "veff"):
        if name in cols:
            f = np.zeros(shape)
            f.flat[flat] = data[:, cols[name]]
            f[lwc <= 0] = 0.0
            extra[name] = f
    return lwc, extra


@dataclass(frozen=True)
class VoxelFile:
    """An LWC text file as read and checked: its header and the voxels' fields on its own levels."""

    comment: str                   # the first comment line ("" without one)
    comments: list                 # every comment line before the numbers
    sizes: tuple                   # (nx, ny, nz)
    spacing_km: tuple              # (dx, dy), km
    levels_km: np.ndarray          # (nz,) level altitudes, km, increasing
    level_unit_km: float           # one unit of the finest last digit printed in the levels, km
    names: list | None             # the column names (lower case), or None
    separator: str | None          # ",", ";" or None (whitespace)
    n_listed: int                  # voxel lines
    lwc: np.ndarray                # (nz, ny, nx) liquid water content, g/m^3
    extra: dict                    # "reff" (um) and "veff" (nz, ny, nx) where the file has them, 0 where clear


def read_voxel_file(path: str) -> VoxelFile:
    """The file ``path`` read and checked (module docstring); a WeatherDataError naming the file, the line and
    the expectation for bad input."""
    lines, ends_with_newline = _read_lines(path)
    comment, comments, sizes, spacing_km, lev_km, lev_unit_km, names, start = _parse_header(path, lines)
    data, line_no, sep = _parse_data(path, lines, start)
    n_listed = int(data.shape[0])
    if n_listed == 0 and names:
        data = np.zeros((0, len(names)))
    cols = _column_map(path, names, data.shape[1], line_no)
    _check_values(path, data, cols, line_no, lines, sizes)
    _check_complete(path, lines, ends_with_newline, data, cols, line_no, sep, sizes)
    lwc, extra = _voxel_fields(path, data, cols, line_no, sizes)
    return VoxelFile(comment, comments, sizes, spacing_km, lev_km, lev_unit_km, names, sep, n_listed, lwc, extra)


__all__ = ["VoxelFile", "read_voxel_file"]
