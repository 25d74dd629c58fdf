"""The single-scattering albedo of the hydrometeors and the box's air together, where ``majorant_volpath`` adds the
air per level to a grey sigma_t grid (``air_levels``): the medium then holds no albedo grid of its own, and the
integrator reads the hydrometeors' albedo grid in place (``air_albedo``, (z, y, x, C), C = 1 or 3) with the air's
scattering per level and channel (``air_scattering``, (levels, 3), 1/m, molecules and aerosol summed).

In each of the 8 corners of a point the mixture's albedo is what ``optics.air.inside.medium_grids`` put into that
voxel of the albedo grid before (float32, the same operations), clip((omega_h beta + beta_sca,air) / (beta +
beta_ext,air), 0, 1) (1 where nothing attenuates), blended trilinearly as the grid volume blended its texels:
the same albedo to float rounding, without a 3-channel grid of it (nor Mitsuba's copy of one)."""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

from ..jitarrays import aligned_float
from . import grid_lookup

ALBEDO_PROPERTY, SCATTERING_PROPERTY = "air_albedo", "air_scattering"


class MixtureAlbedo:
    """The albedo grid (held as given: a TensorXf made from numpy shares its memory on LLVM) and the air's tables."""

    def __init__(self, albedo, scattering: np.ndarray, extinction: np.ndarray):
        self.shape = tuple(int(n) for n in albedo.shape[:3])
        self.channels = int(albedo.shape[3]) if len(albedo.shape) == 4 else 1
        self.albedo = albedo.array
        self.sca = aligned_float(mi, np.asarray(scattering, np.float32))
        self.ext = aligned_float(mi, np.asarray(extinction, np.float32))

    def at(self, p_local, beta, periodic: bool, active):
        """The albedo (Color3f) at the unit-cube point ``p_local``; ``beta`` the grey sigma_t grid's data (flat)."""
        corner, frac = grid_lookup.corners(p_local, self.shape, periodic)
        _, ny, nx = self.shape
        n_c = self.channels
        levels = corner[0]
        # the air's values of the point's two levels, gathered once (not at each of the 4 corners of a level)
        air = [[(dr.gather(mi.Float, self.ext, mi.UInt32(z * 3 + c), active),
                 dr.gather(mi.Float, self.sca, mi.UInt32(z * 3 + c), active)) for c in range(3)] for z in levels]

        def texel(level, y, x):  # level: 0 or 1, the point's lower or upper level (z0, z1)
            i = mi.UInt32((levels[level] * ny + y) * nx + x)
            b = dr.gather(mi.Float, beta, i, active)
            out = []
            for c, (ext, sca_air) in enumerate(air[level]):
                a = dr.gather(mi.Float, self.albedo, i * n_c + (c if n_c == 3 else 0), active)
                sigma_t = b + ext
                sca = a * b + sca_air
                out.append(dr.clip(dr.select(sigma_t > 0.0, sca / dr.select(sigma_t > 0.0, sigma_t, 1.0), 1.0), 0.0, 1.0))
            return mi.Color3f(*out)

        return grid_lookup.trilinear(texel, ((0, 1),) + tuple(corner[1:]), frac)


def parse(props, extinction, check):
    """``air_albedo`` and ``air_scattering`` as a :class:`MixtureAlbedo` (None without them; both or neither)."""
    if ALBEDO_PROPERTY not in props and SCATTERING_PROPERTY not in props:
        return None
    check(ALBEDO_PROPERTY in props and SCATTERING_PROPERTY in props and extinction is not None,
          f"'{ALBEDO_PROPERTY}' and '{SCATTERING_PROPERTY}' go together, with 'air_extinction'")
    albedo = props[ALBEDO_PROPERTY]
    sca = np.asarray(props[SCATTERING_PROPERTY], np.float32)
    check(len(albedo.shape) == 4 and int(albedo.shape[3]) in (1, 3),
          f"'{ALBEDO_PROPERTY}' must be a (z, y, x, 1 or 3) tensor, got {tuple(albedo.shape)}")
    check(sca.shape == tuple(extinction.shape) and np.all(np.isfinite(sca)) and sca.min() >= 0.0,
          f"'{SCATTERING_PROPERTY}' must be finite, non-negative and shaped as 'air_extinction' "
          f"{tuple(extinction.shape)}, got {sca.shape}")
    return MixtureAlbedo(albedo, sca, extinction)
