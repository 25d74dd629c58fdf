"""The sun's colour after the air above each height, for the slicer (``spec.atmosphere``, issue 38 part 3).

The light volume holds the sunlight as fractions of the light's irradiance (``light.py``); with a clear
atmosphere the sun reaching a point at height h (m above sea level, the slicer's world z as the path
tracer's) is E_sun C(h, mu0), C the direct sun's linear sRGB after the air above h along the sun
(``optics.air.sunlight.SunAirTable.by_height``: 1 in luminance above the air). The eye pass multiplies the
sunlight it scatters (and the ground's) by C at the sample's height: a 1-D table over heights, an input of
the frame (``SunAir``: a new sun uploads new values, nothing recompiles). Without an atmosphere it is None
and the eye pass is unchanged. C is the transmittance through all the air above the point (the box's
included); the air along the eye rays, inside the box and out, is ``eye_air.py``'s.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..kernel.jitarrays import aligned_float
from .packets import packet

TOP_ABOVE_BOX_M = 2000.0  # the table reaches this far above the box (as the path tracer's, kernel.scene_dict)
COLUMN_SAMPLES = 128  # the slant columns' points per segment (``shell.slant_columns``: the colour within 1e-3)
# the table the kernels read: the linear interpolant of ``sun_by_height``'s rows on this many heights (every 2.7 m
# for a 20 km box), read at the nearest row (one gather a sample, no interpolation: 0.8-1.6 ms less of a drag
# frame's CPU in the uniform modes); within 0.15% of the interpolant (of the brightest channel) at a 4 deg sun,
# 0.3% at 2 deg, 0.02% at 35 deg
FINE_ROWS = 8192
# a new sun (a drag of the sun) reads its rows off a table over sun elevations built once per atmosphere and box
# (``elevation_table``: log XYZ, cubic in t = sqrt(elevation) on ``ELEVATION_NODES`` columns from
# ``ELEVATION_MIN_DEG`` to 90 deg, one more beyond each end; 0.1 s once) instead of computing its slant columns:
# ``sun_air_input`` 0.21 ms of the calling thread's CPU a new sun instead of 1.0; within 4.6e-5 of
# ``sun_by_height``'s rows (of each row's brightest channel) at 2-90 deg, 1.8e-4 with AOD 0.4, 4.1e-4 with AOD 1
# (at the dimmest heights of a low sun); below ``ELEVATION_MIN_DEG`` (the terminator's heights) computed for the
# sun itself
ELEVATION_MIN_DEG, ELEVATION_NODES = 2.0, 92


@dataclass
class SunAir:
    """The table the eye pass reads (opaque Dr.Jit values; ``n`` is part of a recording's structure)."""

    h0: object      # mi.Float: the table's lowest height (m above sea level)
    inv_dh: object  # mi.Float: 1 / its height step (1/m)
    rgb: object     # mi.Float (n x 4): the sun's linear sRGB per height (``FINE_ROWS``), padded (``packets.packed``)
    n: int          # the number of heights


def sun_by_height(spec, z_top_m: float):
    """(heights (n,) m above sea level, the sun's RGB (n, 3)) of ``spec.atmosphere`` for its sun, heights
    from sea level to ``TOP_ABOVE_BOX_M`` above ``z_top_m`` (the box's top): ``optics.air.sun_rgb`` at the
    sun's zenith cosine on the heights of ``sun_air_table`` (the path tracer's table; computed at that one
    cosine alone, its slant columns on ``COLUMN_SAMPLES`` points: 100 times less work than the table, for a sun
    dragged in the viewer)."""
    from ..optics.air import sun_rgb
    from ..optics.air.sunlight import HEIGHT_SAMPLES
    heights = np.linspace(0.0, max(float(z_top_m), 0.0) + TOP_ABOVE_BOX_M, HEIGHT_SAMPLES)
    return heights, sun_rgb(spec.atmosphere, heights, np.full(heights.shape, float(spec.sun.mu0)), samples=COLUMN_SAMPLES)


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
    elevation = float(np.degrees(np.arcsin(np.clip(float(spec.sun.mu0), -1.0, 1.0))))
    if elevation < ELEVATION_MIN_DEG:
        return sun_by_height(spec, z_top_m)
    t, heights, log_xyz = elevation_table(spec.atmosphere, float(z_top_m))
    f = (np.sqrt(min(elevation, 90.0)) - t[0]) / (t[1] - t[0])
    i = min(max(int(f), 1), t.size - 3)
    u = f - i
    p0, p1, p2, p3 = (log_xyz[k] for k in (i - 1, i, i + 1, i + 2))
    log = p1 + 0.5 * u * (p2 - p0 + u * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3 + u * (3.0 * (p1 - p2) + p3 - p0)))
    return heights, linear_srgb(np.exp(log))


@functools.lru_cache(maxsize=4)
def _fine_heights(h0: float, h1: float) -> np.ndarray:
    """The ``FINE_ROWS`` heights from h0 to h1 (m) that the kernels' table holds."""
    return np.linspace(h0, h1, FINE_ROWS)


def sun_at_height(spec, z_m: float) -> np.ndarray:
    """The sun's linear sRGB (3,) at height ``z_m`` (m above sea level) after ``spec.atmosphere``'s air (as
    ``sun_by_height``'s rows); (1, 1, 1) without an atmosphere."""
    if getattr(spec, "atmosphere", None) is None:
        return np.ones(3)
    from ..optics.air import sun_rgb
    return np.asarray(sun_rgb(spec.atmosphere, np.array([float(z_m)]), np.array([float(spec.sun.mu0)]),
                              samples=COLUMN_SAMPLES), dtype=np.float64).reshape(3)


def sun_air_input(mi, spec, grid_box) -> SunAir | None:
    """The frame's ``SunAir`` for ``spec`` in the box ``grid_box`` ((lo, hi) corners, m); None without an
    atmosphere."""
    if getattr(spec, "atmosphere", None) is None:
        return None
    import drjit as dr
    heights, rgb = sun_rows(spec, grid_box[1][2])
    fine = _fine_heights(float(heights[0]), float(heights[-1]))
    table = np.zeros((FINE_ROWS, 4), np.float32)  # packed rows (``packets.packed``)
    for c in range(3):
        table[:, c] = np.interp(fine, heights, rgb[:, c])
    step = float(fine[1] - fine[0])
    return SunAir(dr.opaque(mi.Float, float(fine[0])), dr.opaque(mi.Float, 1.0 / step), aligned_float(mi, table),
                  int(fine.size))


def sun_colour_at(mi, air: SunAir, z):
    """The sun's colour (mi.Color3f) at heights z (mi.Float, m above sea level): the table's nearest row
    (``FINE_ROWS``), clamped to its ends (inside a kernel)."""
    import drjit as dr
    return packet(mi, dr, air.rgb, mi.UInt32(dr.clip((z - air.h0) * air.inv_dh + 0.5, 0.0, float(air.n - 1))))


__all__ = ["SunAir", "elevation_table", "sun_by_height", "sun_rows", "sun_at_height", "sun_air_input", "sun_colour_at"]
