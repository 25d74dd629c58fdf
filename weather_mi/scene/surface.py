"""The ground the renderers draw under a domain with a ground of its own (``satellite_scene``'s and
``render``'s ``surface``):

- ``"file"`` (default): each column's own surface in the rendered band(s): land, sea and lakes from the file
  (LANDMASK, XLAND, LU_INDEX, else the global land mask: ``io.terrain``), land albedo per band from the
  file's ALBEDO and its land use (``io.land_use``), snow where the file says so, the water as the sea
  surface with its Cox-Munk sun glint (``kernel.sea_surface``; wind from the file's U10/V10 over the water,
  else ``wind_m_s``, else 5 m/s);
- ``"albedo"``: the file's broadband albedo per column, Lambertian everywhere (weather-mi before the surface);
- ``"flat"``: no terrain, one flat Lambertian ground of ``ground_albedo``.

``render --surface file`` draws the same surface in the camera's red, green and blue (``RGB_UM``, the phase
tables' channel wavelengths, 0.65, 0.55, 0.45 um); the slicer, handed the same volume, its albedo per channel
(``Terrain.albedo_rgb``; the water Lambertian, without the glint).

A domain without a ground of its own (a demo storm, an LES field, arrays) has the flat ground whatever the
choice.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..optics.phase.table import RGB_WAVELENGTHS_M

SURFACES = ("file", "albedo", "flat")
RGB_UM = tuple(w * 1e6 for w in RGB_WAVELENGTHS_M)  # ``render``'s channels: the phase tables' wavelengths


def check_surface(surface: str) -> str:
    """``surface`` if it is one of ``SURFACES``; a ValueError naming the option otherwise."""
    if surface not in SURFACES:
        raise ValueError(f"--surface {surface!r}: expected one of {', '.join(SURFACES)}")
    return surface


def with_surface(vol, wavelengths_um, surface: str = "file", wind_m_s: float | None = None):
    """``vol`` with its terrain as ``surface`` (module docstring) at ``wavelengths_um`` (one, all channels
    alike, or one per render channel): each column's albedo there and the sea surface for ``"file"``;
    unchanged for ``"albedo"``; no terrain for ``"flat"``."""
    check_surface(surface)
    terrain = getattr(vol, "terrain", None)
    if terrain is None or surface == "albedo":
        return vol
    if surface == "flat":
        return replace(vol, terrain=None)
    um = [float(w) for w in np.atleast_1d(wavelengths_um)]
    terrain = terrain.in_band(um[0]) if len(um) == 1 else terrain.in_bands(um)
    return replace(vol, terrain=terrain.with_sea(wind_m_s))


__all__ = ["SURFACES", "RGB_UM", "check_surface", "with_surface"]
