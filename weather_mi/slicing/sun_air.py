"""The sun's colour after the air above each height, for the slicer (``spec.atmosphere``, issue 38 part 3).

The light volume holds the sunlight as fractions of the light's irradiance (``light.py``); with a clear
atmosphere the sun reaching a point at height h (m above sea level, the slicer's world z as the path
tracer's) is E_sun C(h, mu0), C the direct sun's linear sRGB after the air above h along the sun
(``optics.air.sunlight.SunAirTable.by_height``: 1 in luminance above the air). The eye pass multiplies the
sunlight it scatters (and the ground's) by C at the sample's height: a 1-D table over heights, an input of
the frame (``SunAir``: a new sun's, ``sun_air_table.sun_air_input``, computed in a small kernel from a table kept
per atmosphere; nothing recompiles). Without an atmosphere it is None
and the eye pass is unchanged. C is the transmittance through all the air above the point (the box's
included); the air along the eye rays, inside the box and out, is ``eye_air.py``'s.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .packets import rgb_words, word_rgb

TOP_ABOVE_BOX_M = 2000.0  # the table reaches this far above the box (as the path tracer's, kernel.scene_dict)
COLUMN_SAMPLES = 128  # the slant columns' points per segment (``shell.slant_columns``: the colour within 1e-3)
# the table the kernels read: the linear interpolant of ``sun_by_height``'s rows on this many heights (every 2.7 m
# for a 20 km box), read at the nearest row (one gather a sample, no interpolation: 0.8-1.6 ms less of a drag
# frame's CPU in the uniform modes); within 0.15% of the interpolant (of the brightest channel) at a 4 deg sun,
# 0.3% at 2 deg, 0.02% at 35 deg
FINE_ROWS = 8192


@dataclass
class SunAir:
    """The table the eye pass reads (opaque Dr.Jit values; ``n`` is part of a recording's structure)."""

    h0: object      # mi.Float: the table's lowest height (m above sea level)
    inv_dh: object  # mi.Float: 1 / its height step (1/m)
    words: object   # mi.UInt64 (n): the sun's linear sRGB per height (``FINE_ROWS``), a word a row (``rgb_words``)
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


def sun_at_height(spec, z_m: float) -> np.ndarray:
    """The sun's linear sRGB (3,) at height ``z_m`` (m above sea level) after ``spec.atmosphere``'s air (as
    ``sun_by_height``'s rows); (1, 1, 1) without an atmosphere."""
    if getattr(spec, "atmosphere", None) is None:
        return np.ones(3)
    from ..optics.air import sun_rgb
    return np.asarray(sun_rgb(spec.atmosphere, np.array([float(z_m)]), np.array([float(spec.sun.mu0)]),
                              samples=COLUMN_SAMPLES), dtype=np.float64).reshape(3)


def sun_colour_at(mi, air: SunAir, z):
    """The sun's colour (mi.Color3f) at heights z (mi.Float, m above sea level): the table's nearest row
    (``FINE_ROWS``), clamped to its ends (inside a kernel; within 6.1e-5 of the row's colour, ``rgb_words``)."""
    import drjit as dr
    return word_rgb(mi, dr, air.words, mi.UInt32(dr.clip((z - air.h0) * air.inv_dh + 0.5, 0.0, float(air.n - 1))))


def sun_air_of_rows(mi, h0, inv_dh, rgb) -> SunAir:
    """The ``SunAir`` of the rows ``rgb`` (mi.Color3f, one per height from h0 every 1 / inv_dh m)."""
    import drjit as dr
    return SunAir(h0, inv_dh, rgb_words(mi, dr, rgb), dr.width(rgb))


__all__ = ["SunAir", "sun_air_of_rows", "sun_by_height", "sun_at_height", "sun_colour_at"]
