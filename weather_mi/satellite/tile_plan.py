"""A satellite image cut into tiles of pixels, each with the sub-box of the model grid it needs: the plan
that ``satellite.tiles`` renders as Dask tasks (``reference.tile_plan``'s, by the imager's ray set).

The domain's outline (``domain_outline``: ``io.outline``'s, placed by ``--lat/--lon/--date`` for an ideal
case) is what the client reads of a wrfout without its 3-D fields. From it come the satellite's view, the one
sun and every tile's sub-box, so that each worker reads only its sub-box and renders its pixels in the whole
domain's frame, height grid and light.

The halo (``tile_box``). A tile's pixels see the medium along their lines of sight between the top and
the bottom of the height grid (parallax: a slant view crosses the cloud layer up to (top - bottom)
tan(VZA) from where it meets the ground); the sun lights each point along those lines through the medium
between it and the top, (top - z) / tan(elevation) towards the sun (the slant sun path). The sub-box is
the box holding the lines' ends at the top and the bottom and the sun path of the bottom end (their convex
hull holds every point's sun path), widened on every side by ``halo_km`` for the light that scatters
sideways into those paths (the diffusion margin), and clipped to the domain.
"""
from __future__ import annotations

from dataclasses import replace

from ..io.outline import Outline
from ..reference.tile_plan import DEFAULT_HALO_KM, DEFAULT_TILE_PX, Tile, index_range, pixel_blocks, rays_box
from ..reference import tile_plan as _generic


def domain_outline(path, time=None, *, lat=None, lon=None, date=None) -> Outline:
    """The outline of one time of the wrfout ``path`` (``io.outline.domain_outline``: 2-D fields and two
    w-levels read, no 3-D field). ``lat``, ``lon``, ``date``: an ideal case placed as ``place.assume_place``
    places it."""
    from ..io.outline import domain_outline as outline_of
    out = outline_of(path, time)
    if lat is not None or lon is not None or date is not None:
        from ..scene.place import assume_place
        out = replace(out, dataset=assume_place(out.dataset, lat, lon, date))
    return out


def tile_box(rays, rows: slice, cols: slice, bottom_m: float, top_m: float, sun_azimuth_deg: float,
             sun_elevation_deg: float, halo_m: float) -> tuple[float, float, float, float]:
    """(x0, x1, y0, y1) (m) of the region the pixels ``rows`` x ``cols`` of ``rays`` (corner rays, a
    ``RayTable``) need: their lines of sight between heights ``top_m`` and ``bottom_m``, the sun path (azimuth
    in the grid's frame, clockwise from +y; elevation, degrees) from their bottom ends up to ``top_m``, and
    ``halo_m`` around (see the module; ``reference.tile_plan.rays_box``)."""
    corners = (slice(rows.start, rows.stop + 1), slice(cols.start, cols.stop + 1))
    return rays_box(rays.origins_m[corners], rays.directions[corners], bottom_m, top_m, sun_azimuth_deg,
                    sun_elevation_deg, halo_m)


def plan_tiles(outline: Outline, rays, sun_azimuth_deg: float, sun_elevation_deg: float, tile_px: int,
               halo_km: float) -> list[Tile]:
    """The tiles of an image of ``rays`` (corner rays (H + 1, W + 1)) over ``outline``'s domain; tiles whose
    region misses the domain keep a one-column sub-box (their pixels see the ground only)."""
    return _generic.plan_tiles(outline, rays.origins_m, rays.directions, sun_azimuth_deg, sun_elevation_deg,
                               tile_px, halo_km)


__all__ = ["Outline", "domain_outline", "Tile", "pixel_blocks", "tile_box", "index_range", "plan_tiles",
           "DEFAULT_TILE_PX", "DEFAULT_HALO_KM"]
