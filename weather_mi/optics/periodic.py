"""Periodic horizontal boundaries (doubly periodic LES domains such as BOMEX and RICO): what both renderers
share about them.

A doubly periodic domain stands for an infinite horizontal tiling of its grid. Both renderers render that
tiling exactly where it matters and cheaply:

* The grids are looked up with their horizontal indices wrapped (``wrap_mode: repeat`` in Mitsuba's grid
  volumes, indices modulo the grid size in ``majorant_volpath``'s DDA and in ``hydrometeor_mixture``), so
  the trilinear interpolant between the last and the first column is that of the tiling. Mitsuba wraps all
  three axes, so the grids get one copy of their bottom and top level below and above (:func:`pad_levels`,
  the box grown by one level each way: :func:`padded_bbox`): inside the original box every lookup then
  clamps vertically as before.
* The medium's box is extended horizontally over ``tiles`` periods on each side (:func:`extended_box`); the
  camera, the ground, the sky and the sun are unchanged (they are invariant under horizontal translations
  by a period: a flat ground, directions only). Free flights, shadow rays and the sun's slant path then
  cross the periodic copies as straight lines, with no teleporting of path vertices: exact within the
  extended box, whose reach (``PATH_TILES`` periods, ``SLICER_TILES`` for the slicer) bounds the horizontal
  length of a straight segment through the medium.

What the camera sees: ``periodic=True`` ("view"), the periodic continuation (a cloud field to the edge of
the extended box, the physical meaning of a periodic LES); ``periodic="transport"``, the centre tile only
(camera rays interact with the medium only inside the domain's own box) with light transport still
periodic (its ground shadowed by the neighbours' clouds, light entering its sides through them): the
default for a dataset that says it is periodic (:func:`periodic_of_attrs`). docs/periodic.md has the design
and the check against tiled copies.
"""
from __future__ import annotations

import numpy as np

from ..errors import WeatherDataError

PATH_TILES = 10    # the path tracer's medium box reaches this many periods beyond the domain on each side
SLICER_TILES = 1   # the slicer's slicing box: one period on each side (3 x 3 tiles)


def check_periodic(value, what: str = "periodic"):
    """``value`` as one of False, True ("view" too) or "transport"; None is False. Anything else raises."""
    if value is None:
        return False
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if value == "view":
        return True
    if value == "transport":
        return "transport"
    raise WeatherDataError("render options", what, 'False, True ("view") or "transport"', repr(value))


DEFAULT_PERIODIC = "transport"  # a dataset that says it is periodic: the light periodic, the camera on its own tile


def periodic_of_attrs(attrs):
    """The default boundaries of a dataset: DEFAULT_PERIODIC where its attributes say it is doubly periodic
    (``attrs["periodic"]``: 1, True or "xy", as the LES reader writes it; netCDF attributes cannot be
    booleans), else False. "transport" rather than True: the default camera frames the domain's own clouds
    as before, with the light of the tiling, and both renderers show the same scene (the copies reach 10
    periods in the path tracer, one in the slicer; ``periodic=True`` shows them)."""
    value = attrs.get("periodic", 0)
    return DEFAULT_PERIODIC if str(value).strip().lower() in ("1", "true", "xy") else False


def pad_levels(a: np.ndarray, axis: int = 0) -> np.ndarray:
    """``a`` with a copy of its first and last level (along ``axis``, the grid's z) added below and above:
    under a wrapping lookup the padded grid clamps vertically inside the original box."""
    a = np.asarray(a)
    pad = [(0, 0)] * a.ndim
    pad[axis] = (1, 1)
    return np.pad(a, pad, mode="edge")


def padded_bbox(bbox, nz: int):
    """The box of :func:`pad_levels`' grid: ``bbox`` ((lo, hi), m) grown by one level of its ``nz`` levels
    below and above."""
    lo, hi = (np.asarray(p, dtype=np.float64) for p in bbox)
    dz = (hi[2] - lo[2]) / int(nz)
    lo[2] -= dz
    hi[2] += dz
    return tuple(map(float, lo)), tuple(map(float, hi))


def extended_box(lo, hi, tiles: int) -> tuple[np.ndarray, np.ndarray]:
    """The box (lo, hi) grown horizontally by ``tiles`` periods (its own width and depth) on each side."""
    lo, hi = np.array(lo, dtype=np.float64), np.array(hi, dtype=np.float64)
    span = hi[:2] - lo[:2]
    lo[:2] -= tiles * span
    hi[:2] += tiles * span
    return lo, hi


def require_flat_ground(vol, periodic) -> None:
    """A periodic volume over a terrain grid raises (a terrain is not periodic)."""
    if periodic and getattr(vol, "terrain", None) is not None:
        raise WeatherDataError("render options", "periodic", "a volume without terrain (periodic boundaries "
                               "tile the grid; a terrain height field is not periodic)", "a volume with terrain")
