"""Trilinear lookups of a grid on the unit cube as Mitsuba's ``gridvolume`` makes them (texel centres at
(i + 0.5) / n, clamped at the edges; periodic in x and y: indices modulo n, as its ``wrap_mode`` "repeat"), for
the plugins that read grids of their own: the 8 corners and fractions of a point (:func:`corners`) and the blend
of any per-corner value (:func:`trilinear`: the same operations on a packet of 4 and on one value)."""
from __future__ import annotations

import drjit as dr
import mitsuba as mi


def corners(p, shape, periodic: bool = False):
    """(((z0, z1), (y0, y1), (x0, x1)) Int32 indices, (fz, fy, fx) fractions) of the unit-cube point ``p`` on a
    grid of ``shape`` (nz, ny, nx)."""
    nz, ny, nx = shape
    corner, frac = [], []
    for axis, (coord, n) in enumerate(((p.z, nz), (p.y, ny), (p.x, nx))):
        u = coord * n - 0.5
        u0 = dr.floor(u)
        i0 = mi.Int32(u0)
        if periodic and axis > 0:  # indices modulo n (as the grid volumes' wrap_mode "repeat")
            i0 = i0 % n
            i0 = dr.select(i0 < 0, i0 + n, i0)
            corner.append((i0, dr.select(i0 + 1 == n, 0, i0 + 1)))
        else:
            corner.append((dr.clip(i0, 0, n - 1), dr.clip(i0 + 1, 0, n - 1)))
        frac.append(u - u0)
    return tuple(corner), tuple(frac)


def lerp(a, b, t):
    return dr.fma(b - a, t, a)


def trilinear(texel, corner, frac):
    """The trilinear blend of ``texel(z, y, x)`` (any Dr.Jit value per corner) at ``corners``' result."""
    (z0, z1), (y0, y1), (x0, x1) = corner
    fz, fy, fx = frac
    c00 = lerp(texel(z0, y0, x0), texel(z0, y0, x1), fx)
    c01 = lerp(texel(z0, y1, x0), texel(z0, y1, x1), fx)
    c10 = lerp(texel(z1, y0, x0), texel(z1, y0, x1), fx)
    c11 = lerp(texel(z1, y1, x0), texel(z1, y1, x1), fx)
    return lerp(lerp(c00, c01, fy), lerp(c10, c11, fy), fz)
