"""The sun's colour by height for a new sun, read off a table over sun elevations kept per atmosphere and box (issue
38 part 3, the air's cost per drag frame): ``sun_air.sun_by_height``'s slant columns for every new sun cost 1 ms of
the calling thread's CPU, and the table the frame reads (``sun_air.SunAir``) was a host array that Dr.Jit used in
place: freeing last frame's one queued a host function that waited for the interpreter's lock behind the frame's
kernels (1.9-9 ms of a worker thread, kernel history, the drag at 300 x 300 on 2 loaded cores). Here the
per-atmosphere table holds log CIE XYZ (positive, nearly linear in the air mass) on ``sun_by_height``'s heights
for suns on a grid in sqrt(elevation), uploaded once; a new sun gives four weights and a node (``SunAirSource``, opaque
values: 0.10 ms of the calling thread's CPU), and the frame's kernels compute its rows (``as_sun_air``: Catmull-Rom,
exp, linear sRGB and the linear interpolant on the ``sun_air.FINE_ROWS`` heights, one small kernel recorded with the
frame's: a new sun traces and recompiles nothing)."""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..kernel.jitarrays import aligned_float
from .packets import packed, packet
from .sun_air import COLUMN_SAMPLES, FINE_ROWS, TOP_ABOVE_BOX_M, SunAir, sun_air_of_rows, sun_by_height

# a new sun (a drag of the sun) reads its rows off a table over sun elevations built once per atmosphere and box
# (``elevation_table``: log XYZ, cubic in t = sqrt(elevation) on ``ELEVATION_NODES`` columns from
# ``ELEVATION_MIN_DEG`` to 90 deg, one more beyond each end; 0.1 s once) instead of computing its slant columns:
# ``sun_air_input`` 0.10 ms of the calling thread's CPU a new sun instead of 1.0; within 4.6e-5 of
# ``sun_by_height``'s rows (of each row's brightest channel) at 2-90 deg, 1.8e-4 with AOD 0.4, 4.1e-4 with AOD 1
# (at the dimmest heights of a low sun); below ``ELEVATION_MIN_DEG`` (the terminator's heights) computed for the
# sun itself
ELEVATION_MIN_DEG, ELEVATION_NODES = 2.0, 92
MU_MIN = float(np.sin(np.radians(ELEVATION_MIN_DEG)))  # below it a sun's rows are computed for the sun itself


@functools.lru_cache(maxsize=4)
def elevation_table(atm, z_top_m: float):
    """(t nodes (n,), heights (h,), log XYZ (n, h, 3)): the logarithm of the direct sun's CIE XYZ (``sunlight.sun_xyz``,
    positive: its linear sRGB may not be) on ``sun_by_height``'s heights for suns at elevations t^2 deg, on a
    uniform grid of t = sqrt(elevation) from ``ELEVATION_MIN_DEG`` to 90 deg and one node beyond each end (dense
    near the horizon, where the colour changes fastest), for the atmosphere ``atm`` and a box whose top is
    ``z_top_m`` (m). The logarithm is nearly linear in the air mass, so a cubic holds to the dimmest sun."""
    from ..optics.air.sunlight import HEIGHT_SAMPLES, sun_xyz
    dt = (np.sqrt(90.0) - np.sqrt(ELEVATION_MIN_DEG)) / (ELEVATION_NODES - 1)
    t = np.sqrt(ELEVATION_MIN_DEG) + dt * (np.arange(ELEVATION_NODES + 2) - 1.0)  # a node beyond each end
    heights = np.linspace(0.0, max(float(z_top_m), 0.0) + TOP_ABOVE_BOX_M, HEIGHT_SAMPLES)
    mu = np.sin(np.radians(t * t))
    xyz = sun_xyz(atm, heights[None, :], mu[:, None], samples=COLUMN_SAMPLES)
    return t, heights, np.log(np.maximum(xyz, 1e-300))


def sun_rows(spec, z_top_m: float):
    """``sun_by_height(spec, z_top_m)``, read off ``elevation_table`` by cubic (Catmull-Rom) interpolation of log XYZ
    in t = sqrt(elevation), then linear sRGB (``spectrum.linear_srgb``), for a sun at least ``ELEVATION_MIN_DEG``
    high; computed for the sun itself below."""
    from ..optics.spectrum import linear_srgb
    if float(spec.sun.mu0) < MU_MIN:
        return sun_by_height(spec, z_top_m)
    t, heights, log_xyz = elevation_table(spec.atmosphere, float(z_top_m))
    i, u = _node(spec, t)
    log = sum(w * log_xyz[i - 1 + k] for k, w in enumerate(_catmull_rom(u)))
    return heights, linear_srgb(np.exp(log))


@functools.lru_cache(maxsize=4)
def _fine_heights(h0: float, h1: float) -> np.ndarray:
    """The ``FINE_ROWS`` heights from h0 to h1 (m) that the kernels' table holds."""
    return np.linspace(h0, h1, FINE_ROWS)


def sun_air_input(mi, spec, grid_box, reuse=None) -> SunAir | SunAirSource | None:
    """The frame's ``SunAir`` for ``spec`` in the box ``grid_box`` ((lo, hi) corners, m); None without an
    atmosphere. ``reuse``: None, or the renderer's ``SliceRenderer._reuse``: a sun at least
    ``ELEVATION_MIN_DEG`` high then gives its ``SunAirSource``, whose table the frame's kernels compute from the
    atmosphere's elevation table (``as_sun_air``: no host array per new sun)."""
    if getattr(spec, "atmosphere", None) is None:
        return None
    import drjit as dr
    if reuse is not None and spec.sun.mu0 >= MU_MIN:
        return sun_source(mi, spec, float(grid_box[1][2]), FINE_ROWS, reuse)
    heights, rgb = sun_rows(spec, grid_box[1][2])
    fine = _fine_heights(float(heights[0]), float(heights[-1]))
    step = float(fine[1] - fine[0])
    rows = mi.Color3f(*(aligned_float(mi, np.interp(fine, heights, rgb[:, c]).astype(np.float32)) for c in range(3)))
    return sun_air_of_rows(mi, dr.opaque(mi.Float, float(fine[0])), dr.opaque(mi.Float, 1.0 / step), rows)


def _catmull_rom(u: float) -> tuple[float, float, float, float]:
    """The weights of p0..p3 in the Catmull-Rom cubic through p1 (u = 0) and p2 (u = 1)."""
    return (0.5 * (-u + 2.0 * u * u - u ** 3), 1.0 + 0.5 * (-5.0 * u * u + 3.0 * u ** 3),
            0.5 * (u + 4.0 * u * u - 3.0 * u ** 3), 0.5 * (-u * u + u ** 3))


def _node(spec, t) -> tuple[int, float]:
    """(i, u): the sun's elevation between nodes i and i + 1 of ``elevation_table``'s grid t, at fraction u."""
    elevation = float(np.degrees(np.arcsin(np.clip(float(spec.sun.mu0), -1.0, 1.0))))
    f = (np.sqrt(min(elevation, 90.0)) - t[0]) / (t[1] - t[0])
    i = min(max(int(f), 1), t.size - 3)
    return i, f - i


@dataclass
class SunAirSource:
    """A new sun's ``sun_air.SunAir`` before its table: what ``as_sun_air`` computes the table from inside the
    frame's kernels (recorded with them: a new sun traces nothing; opaque values, the ints part of the structure)."""

    h0: object        # mi.Float: the table's lowest height (m above sea level)
    inv_dh: object    # mi.Float: 1 / its height step (1/m)
    table: object     # mi.Float: ``elevation_table``'s log XYZ, packed (nodes x n_h x 4)
    weights: tuple    # 4 mi.Float: the Catmull-Rom weights of the sun's four nodes
    base: object      # mi.UInt32: the first of those nodes' rows
    n_h: int          # heights of ``elevation_table``
    rows: int         # heights of the frame's table (``sun_air.FINE_ROWS``)


def sun_source(mi, spec, z_top_m: float, rows: int, reuse) -> SunAirSource:
    """The ``SunAirSource`` of ``spec``'s sun (at least ``ELEVATION_MIN_DEG`` high) for a box whose top is
    ``z_top_m``: ``sun_rows`` on ``rows`` uniform heights (linear between its own, as ``np.interp``) once
    ``as_sun_air`` computes it; the atmosphere's ``elevation_table`` uploaded once through ``reuse`` (the renderer's
    ``SliceRenderer._reuse``)."""
    import drjit as dr
    key = (spec.atmosphere, float(z_top_m))
    t, heights, log_xyz = elevation_table(*key)
    table = reuse("sun air table", key, lambda: aligned_float(mi, packed(log_xyz)))
    i, u = _node(spec, t)
    h0, h1 = float(heights[0]), float(heights[-1])
    return SunAirSource(dr.opaque(mi.Float, h0), dr.opaque(mi.Float, (rows - 1) / (h1 - h0)), table,
                        tuple(dr.opaque(mi.Float, w) for w in _catmull_rom(u)),
                        dr.opaque(mi.UInt32, (i - 1) * heights.size), int(heights.size), int(rows))


def as_sun_air(mi, sun_air):
    """``sun_air`` (None, a ``sun_air.SunAir``) as it is, or the ``SunAir`` of a ``SunAirSource``: its table computed
    (inside a kernel: ``source_rows``, one word a row)."""
    if not isinstance(sun_air, SunAirSource):
        return sun_air
    return sun_air_of_rows(mi, sun_air.h0, sun_air.inv_dh, source_rows(mi, sun_air))


def source_rows(mi, sun_air: SunAirSource):
    """The rows (mi.Color3f) of a ``SunAirSource``'s table (inside a kernel: Catmull-Rom in log XYZ, exp, linear
    sRGB, linear in height)."""
    import drjit as dr
    from ..optics.spectrum import linear_srgb
    s, n_h = sun_air, sun_air.n_h
    cols = linear_srgb(np.eye(3))  # XYZ's unit vectors in linear sRGB (its matrix's columns)
    f = mi.Float(dr.arange(mi.UInt32, s.rows)) * ((n_h - 1) / (s.rows - 1))
    j = dr.minimum(mi.UInt32(f), n_h - 2)
    a = f - mi.Float(j)

    def srgb(row):  # the sun's linear sRGB at height row ``row`` of the elevation table
        log = mi.Color3f(0.0)
        for k, w in enumerate(s.weights):
            log += w * packet(mi, dr, s.table, s.base + k * n_h + row)
        xyz = dr.exp(log)
        return sum((xyz[c] * mi.Color3f(*(float(x) for x in cols[c])) for c in range(1, 3)),
                   xyz[0] * mi.Color3f(*(float(x) for x in cols[0])))
    lo, hi = srgb(j), srgb(j + 1)
    return lo * (1.0 - a) + hi * a


__all__ = ["ELEVATION_MIN_DEG", "SunAirSource", "as_sun_air", "elevation_table", "source_rows", "sun_air_input",
           "sun_rows", "sun_source"]
