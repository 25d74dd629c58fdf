"""The slicer's medium grids: the per-species extinction grids as Dr.Jit arrays (detail applied), their box
in texture coordinates and the grid as kernel vectors, set on a ``SliceRenderer`` as it is built
(``renderer.py``; periodic volumes: padded levels, ``periodic.py``)."""
from __future__ import annotations

import numpy as np

from ..kernel.jitarrays import aligned_float, kernel_scalar


def set_grids(renderer, vol, mode, detail_field, detail_noise):
    """Set on ``renderer`` (a ``SliceRenderer`` being built): the per-species extinction grids
    (detail applied), their box in texture coordinates and the detail noise (periodic: levels padded,
    slicing/periodic.py)."""
    mi = renderer.mi
    renderer.shape = tuple(vol.beta_total.shape)
    # a (z, y, x, S) float32 copy of the grids only where detail or padding changes them, or they are not float32
    own = vol.beta_ext.dtype == np.float32 and not (detail_field is not None and mode.detail) and \
        renderer.periodic is None
    beta_s = None if own else np.moveaxis(vol.beta_ext, 0, -1).astype(np.float32)
    if detail_field is not None and mode.detail:
        detail = np.asarray(detail_field, dtype=np.float32)
        if detail.shape != renderer.shape:
            raise ValueError(f"detail_field must have the volume's shape {renderer.shape}, got {detail.shape}")
        beta_s = beta_s * detail[..., None]
    renderer.detail_noise = None  # unit-variance noise n: species s's extinction x exp(a_s n - a_s^2 / 2)
    if detail_noise is not None and mode.detail:
        n = np.asarray(detail_noise, dtype=np.float32)
        if n.shape != renderer.shape:
            raise ValueError(f"detail_noise must have the volume's shape {renderer.shape}, got {n.shape}")
        renderer.detail_noise = aligned_float(mi, n)
    # 1/m, over all voxels (numpy sums each species' voxels in the same order from either layout)
    renderer.beta_sum_s = vol.beta_ext.reshape(renderer.n_species, -1).sum(axis=1, dtype=np.float64) if own else \
        beta_s.reshape(-1, renderer.n_species).sum(axis=0, dtype=np.float64)
    renderer.grid_box = tuple(np.asarray(p, dtype=np.float64) for p in vol.bbox)  # texture coordinates
    if renderer.periodic is not None:  # the grids' levels padded (slicing/periodic.py)
        beta_s, renderer.grid_box = renderer.periodic.pad(beta_s), renderer.periodic.grid_box
        renderer.shape = tuple(beta_s.shape[:3])
        if renderer.detail_noise is not None:
            renderer.detail_noise = aligned_float(mi, renderer.periodic.pad(np.asarray(detail_noise, np.float32)))
    # (z, y, x) each; unchanged by detail or padding: the volume's own float32 grids
    renderer.beta_s = [mi.Float(np.ascontiguousarray(vol.beta_ext[si] if own else beta_s[..., si]).ravel())
                       for si in range(renderer.n_species)]
    # the grid as kernel vectors (lo corner, 1 / span), for the light carried through the medium (periodic:
    # and the texture coordinates where it samples the medium)
    renderer._grid_scalars = (mi.Point3f(*(kernel_scalar(mi, c) for c in renderer.grid_box[0])),
                          mi.Vector3f(*(kernel_scalar(mi, 1.0 / (h - l)) for l, h in zip(*renderer.grid_box))))
    if renderer.periodic is not None:
        renderer._grid_scalars += renderer.periodic.carried_bounds(mi)
    renderer.tile_box = None if renderer.periodic is None else renderer.periodic.tile  # "transport": the eye's own tile


__all__ = ["set_grids"]
