"""SHDOM / pyshdom "particle properties" LWC text files (LES output) -> Hydrometeors.

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

Conversions: LWC is a mass density (g/m^3), so the mixing ratio is q = LWC * 1e-3 / rho_air (kg/kg),
with rho_air the 1976 standard atmosphere at each level height unless given; the effective radius
(um) becomes ``r_eff_<species>`` in metres (0 where there is no liquid); the effective variance, when
the file has it, is kept as ``v_eff_<species>`` (dimensionless). x = i dx, y = j dy and z = the level
altitudes, all in metres. Levels uniform within their printed precision are kept, at their mean spacing:
uniform when every level lies within half a unit of the last printed digit (the finest among the levels,
read from the file's text) of one straight line a + b k, plus float rounding (25 m levels printed in km to
3 decimals read 24-26 m apart and are kept; the half unit counts only when it is under a tenth of the mean
spacing). Non-uniform levels are interpolated linearly in height onto a uniform grid
with the smallest level spacing (LWC linearly; r_eff and v_eff LWC-weighted, so they stay within the
range of the neighbouring cloudy values), and the attribute ``vertical_regrid`` says so.

A file cut short is an error naming the line: a last voxel line without its newline whose last number
has fewer decimals than the line before (cut inside the number), or a file that lists clear voxels too,
in order (so every voxel), with fewer lines than nx ny nz.
"""
from __future__ import annotations

import os
import re
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from .standard_atmosphere import standard_density
from ..errors import WeatherDataError
from .hydrometeors import DIMS, from_arrays

LIQUID_SPECIES = ("cloud", "rain")
UNIFORM_RTOL = 1e-4          # levels' distance from a straight line allowed for float rounding, of the mean spacing
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


def _line_misfit(z: np.ndarray) -> float:
    """The largest distance of the levels z_k from the straight line a + b k that makes it smallest
    (the minimax fit; same unit as z). The spread max_k - min_k of z_k - b k is convex in the slope b
    and smallest between the smallest and the largest step, so a ternary search over b finds it."""
    k = np.arange(z.size, dtype=np.float64)
    steps = np.diff(z)
    lo, hi = float(steps.min()), float(steps.max())

    def spread(b: float) -> float:
        r = z - b * k
        return float(r.max() - r.min())

    for _ in range(100):  # (2/3)^100 of the slope interval: far below float rounding
        m1, m2 = lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0
        if spread(m1) <= spread(m2):
            hi = m2
        else:
            lo = m1
    return 0.5 * spread(0.5 * (lo + hi))


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


def _rho_profile(path: str, rho_air, z_native: np.ndarray, z_out: np.ndarray) -> tuple[np.ndarray, str]:
    """Air density (kg/m^3) at the output heights z_out (m), and a description for the attributes."""
    nz = z_native.size
    expected = (f"None (1976 standard atmosphere), a positive number, a profile of length nz = {nz} (kg/m^3) "
                "or a callable of height (m)")
    if rho_air is None:
        rho, how = np.asarray(standard_density(z_out), dtype=np.float64), "U.S. Standard Atmosphere 1976 at each level"
    elif callable(rho_air):
        f: Callable = rho_air
        try:
            val = f(z_out.copy())
        except (TypeError, ValueError):
            val = [f(float(z)) for z in z_out]
        try:
            rho = np.broadcast_to(np.asarray(val, dtype=np.float64), z_out.shape).copy()
        except (TypeError, ValueError) as exc:
            raise WeatherDataError(path, "rho_air", f"the callable to return {z_out.size} densities (kg/m^3) "
                                   "for the level heights (m)", f"{np.shape(val)}") from exc
        how = f"callable {getattr(f, '__name__', type(f).__name__)} of height (m)"
    else:
        try:
            arr = np.asarray(rho_air, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise WeatherDataError(path, "rho_air", expected, repr(rho_air)[:80]) from exc
        if isinstance(rho_air, (bool, np.bool_)) or arr.ndim > 1:
            raise WeatherDataError(path, "rho_air", expected, f"{type(rho_air).__name__} of shape {arr.shape}")
        if arr.ndim == 0:
            rho, how = np.full(z_out.shape, float(arr)), f"constant {float(arr):g} kg/m^3"
        else:
            if arr.size != nz:
                raise WeatherDataError(path, "rho_air", expected, f"a profile of length {arr.size}")
            same = z_out.size == nz and np.allclose(z_out, z_native)
            rho = arr.copy() if same else np.interp(z_out, z_native, arr)
            how = "given profile (kg/m^3) at the levels"
    if not np.all(np.isfinite(rho)) or np.any(rho <= 0):
        raise WeatherDataError(path, "rho_air", "a positive, finite air density (kg/m^3) at every level",
                               f"values from {np.nanmin(rho):.4g} to {np.nanmax(rho):.4g}")
    return rho, how


def _interp_z(field: np.ndarray, z_native: np.ndarray, z_out: np.ndarray) -> np.ndarray:
    """Linear interpolation in height along axis 0 of a (nz, ny, nx) field."""
    lo = np.clip(np.searchsorted(z_native, z_out, side="right") - 1, 0, z_native.size - 2)
    w = (z_out - z_native[lo]) / (z_native[lo + 1] - z_native[lo])
    w = np.clip(w, 0.0, 1.0)[:, None, None]
    return (1.0 - w) * field[lo] + w * field[lo + 1]


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


def _uniform_levels(z_native: np.ndarray, lev_unit_km: float, attrs: dict):
    """(z_out, dz) in metres when the levels are uniform within their printed precision (see the module
    docstring), else None; says so in attrs["vertical_grid"]."""
    nz = z_native.size
    steps = np.diff(z_native)
    printed_m = 1000.0 * lev_unit_km  # one unit of the last printed digit: each level +- half that
    misfit = _line_misfit(z_native)
    tol_m = UNIFORM_RTOL * steps.mean() + (0.5 * printed_m if printed_m <= 0.1 * steps.mean() else 0.0)
    if misfit > tol_m:
        return None
    dz = (z_native[-1] - z_native[0]) / (nz - 1)
    attrs["vertical_grid"] = (f"uniform levels from the file, {dz:g} m apart (spacings {steps.min():g} to "
                              f"{steps.max():g} m as printed, to {printed_m:g} m; within {misfit:.3g} m "
                              "of a straight line)")
    return z_native[0] + dz * np.arange(nz), dz


def _regrid_levels(z_native: np.ndarray, lwc: np.ndarray, extra: dict, attrs: dict):
    """(z_out, dz, lwc, extra) on uniform levels at the smallest native spacing, fitted to the column: LWC
    interpolated linearly in height, r_eff and v_eff LWC-weighted; says so in the attributes."""
    steps = np.diff(z_native)
    dz_min = float(steps.min())
    span = z_native[-1] - z_native[0]
    n_out = int(np.ceil(span / dz_min - 1e-6)) + 1
    z_out = z_native[0] + (span / (n_out - 1)) * np.arange(n_out)
    z_out[-1] = z_native[-1]
    dz = span / (n_out - 1)
    weighted = {k: _interp_z(v * lwc, z_native, z_out) for k, v in extra.items()}
    lwc = _interp_z(lwc, z_native, z_out)
    with np.errstate(invalid="ignore", divide="ignore"):
        extra = {k: np.where(lwc > 0, w / np.where(lwc > 0, lwc, 1.0), 0.0) for k, w in weighted.items()}
    attrs["vertical_regrid"] = (
        f"levels not uniform (spacings {steps.min():g} to {steps.max():g} m): LWC interpolated linearly "
        f"in height onto {n_out} uniform levels {dz:g} m apart (the smallest spacing, fitted to the "
        f"column); r_eff and v_eff interpolated LWC-weighted")
    attrs["vertical_grid"] = "regridded to uniform levels"
    attrs["n_levels_native"] = int(z_native.size)
    return z_out, dz, lwc, extra


def _vertical_grid(z_native, lev_unit_km, dx, dy, lwc, extra, attrs):
    """(z_out, dz, lwc, extra): the file's levels when uniform (or single), else the regridded column."""
    if z_native.size == 1:
        dz = min(dx, dy)
        attrs["vertical_grid"] = f"a single level; layer depth taken as the horizontal spacing {dz:g} m"
        return z_native, dz, lwc, extra
    uniform = _uniform_levels(z_native, lev_unit_km, attrs)
    if uniform is not None:
        return (*uniform, lwc, extra)
    return _regrid_levels(z_native, lwc, extra, attrs)


def _file_attrs(path, comment, comments, names, sep, sizes, n_listed, lwc, species, dx, dy) -> dict:
    """The Dataset attributes that describe the file and its voxels."""
    nx, ny, nz = sizes
    attrs = {"source": path, "model": "LES", "format": "SHDOM/pyshdom particle properties (LWC)",
             "comment": comment, "n_voxels_listed": n_listed, "n_cloudy_voxels": int(np.count_nonzero(lwc > 0)),
             "n_voxels_grid": int(nx * ny * nz), "species": species,
             "max_lwc_g_m3": float(lwc.max()) if lwc.size else 0.0,
             "separator": "comma" if sep == "," else ("semicolon" if sep == ";" else "whitespace"),
             "dx": dx, "dy": dy,
             "periodic": 1}  # LES domains are doubly periodic (BOMEX, RICO): the renderers' default (optics/periodic.py)
    if len(comments) > 1:
        attrs["comments"] = "\n".join(comments)
    if names:
        attrs["columns"] = ",".join(names)
    return attrs


def open_les(path, rho_air=None, *, species: str = "cloud") -> xr.Dataset:
    """Open an SHDOM/pyshdom LWC text file (LES liquid water) as Hydrometeors.

    Parameters
    ----------
    path : str or os.PathLike
        The text file, space- or comma-separated (see the module docstring for the format).
    rho_air : None, float, array_like or callable, optional
        Air density (kg/m^3) that turns LWC (g/m^3) into a mixing ratio q = LWC 1e-3 / rho_air (kg/kg):
        None (default) for the 1976 standard atmosphere at each level height, a number, a profile of
        length nz (at the file's levels) or a callable of height in metres.
    species : {"cloud", "rain"}, default "cloud"
        The hydrometeor that receives the liquid.

    Returns
    -------
    xarray.Dataset
        Hydrometeors following :mod:`weather_mi.io.hydrometeors`: x = i dx, y = j dy, z = the level
        altitudes, in metres; ``r_eff_<species>`` (m) and, when the file has it, ``v_eff_<species>``
        (dimensionless). Levels that are not uniform are regridded (attribute ``vertical_regrid``).
        ``attrs["periodic"] = 1``: the domain is doubly periodic, which both renderers then honour by
        default (``optical_volume(..., periodic=False)`` renders it as an isolated box).

    Raises
    ------
    WeatherDataError
        For bad input, naming the file, the field and the expectation.
    """
    path = os.fspath(path)
    if species not in LIQUID_SPECIES:
        raise WeatherDataError(path, "species", "'cloud' or 'rain' (LES files hold liquid water)", repr(species))
    lines, ends_with_newline = _read_lines(path)
    comment, comments, sizes, (dx_km, dy_km), lev_km, lev_unit_km, names, start = _parse_header(path, lines)
    data, line_no, sep = _parse_data(path, lines, start)
    n_listed = int(data.shape[0])
    if n_listed == 0 and names:
        data = np.zeros((0, len(names)))
    cols = _column_map(path, names, data.shape[1], line_no)
    _check_values(path, data, cols, line_no, lines, sizes)
    _check_complete(path, lines, ends_with_newline, data, cols, line_no, sep, sizes)
    lwc, extra = _voxel_fields(path, data, cols, line_no, sizes)

    z_native = lev_km * 1000.0
    dx, dy = dx_km * 1000.0, dy_km * 1000.0
    attrs = _file_attrs(path, comment, comments, names, sep, sizes, n_listed, lwc, species, dx, dy)
    z_out, dz, lwc, extra = _vertical_grid(z_native, lev_unit_km, dx, dy, lwc, extra, attrs)
    attrs["dz"] = float(dz)

    rho, how = _rho_profile(path, rho_air, z_native, z_out)
    attrs["rho_air_source"] = how
    q = lwc * 1e-3 / rho[:, None, None]
    r_eff = {species: extra["reff"] * 1e-6} if "reff" in extra else None
    ds = from_arrays({species: q}, rho, (dz, dy, dx), (float(z_out[0]), 0.0, 0.0), r_eff=r_eff,
                     attrs=attrs, source=path)
    if "veff" in extra:
        ds[f"v_eff_{species}"] = (DIMS, extra["veff"].astype(np.float32),
                                  {"units": "1", "long_name": f"{species} effective variance of the size distribution"})
    return ds
