"""Periodic horizontal boundaries in the slicer (:mod:`weather_mi.optics.periodic`).

The slicer's textures wrap in x and y (``wrap_mode`` repeat, their levels padded with a copy of the bottom
and top level, so that inside the grid's own box they clamp vertically as before), and its slicing box is
the domain's box widened by ``SLICER_TILES`` periods on each side: the light pass then carries the sunlight
through the neighbouring copies before it reaches the domain (exact while the sun's path through the
occupied layers crosses at most ``SLICER_TILES`` periods: for a layer of depth h in a domain of width w,
a sun above atan(h / (SLICER_TILES w))), and the eye pass sees the copies within that box
(``periodic=True``), or the domain's own tile only (``"transport"``: the eye texture reads 0 outside it).
"""
from __future__ import annotations

import numpy as np

from ..optics.periodic import SLICER_TILES, extended_box, pad_levels, padded_bbox, require_flat_ground


class PeriodicSlicing:
    """What a periodic volume changes in ``SliceRenderer``: ``box`` (the slicing box over the copies),
    ``grid_box`` (the padded grid's world box), ``pad`` (an array's levels padded: (z, y, x, ...)),
    ``texture`` (a wrapping texture), ``inside_z`` (texture coordinates of the grid's own levels: where the
    carried light samples the medium) and ``tile`` (None, or for "transport" the texture coordinates (lo,
    hi) of the domain's own x and y, where the eye sees the medium)."""

    def __init__(self, vol, slicing_box):
        require_flat_ground(vol, vol.periodic)
        self.mode = vol.periodic
        nz = vol.shape[0]
        lo, hi = extended_box(*vol.bbox, SLICER_TILES)
        lo[2], hi[2] = slicing_box[0][2], slicing_box[1][2]
        self.box = (lo, hi)
        self.grid_box = tuple(np.asarray(p, dtype=np.float64) for p in padded_bbox(vol.bbox, nz))
        self.inside_z = (1.0 / (nz + 2), (nz + 1.0) / (nz + 2))
        self.tile = (0.0, 1.0) if self.mode == "transport" else None

    @staticmethod
    def pad(a: np.ndarray) -> np.ndarray:
        return pad_levels(a, axis=0)

    @staticmethod
    def texture(mi, tensor):
        import drjit as dr
        return mi.Texture3f(tensor, use_accel=False, wrap_mode=dr.WrapMode.Repeat)

    def carried_bounds(self, mi):
        """(lo, hi) texture coordinates (kernel vectors) where ``LightVolume.carried`` samples the medium:
        any x and y, the grid's own levels."""
        from ..kernel.jitarrays import kernel_scalar
        big = 1e30
        z0, z1 = self.inside_z
        return (mi.Vector3f(-big, -big, kernel_scalar(mi, z0)), mi.Vector3f(big, big, kernel_scalar(mi, z1)))
