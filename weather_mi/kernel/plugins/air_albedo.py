"""The single-scattering albedo of the hydrometeors and the box's air together, where ``majorant_volpath`` adds the
air per level to a grey sigma_t grid (``air_levels``): the medium then holds no albedo grid of its own, and the
integrator reads the hydrometeors' albedo grid in place (``air_albedo``, (z, y, x, C), C = 1 or 3) with the air's
scattering per level and channel (``air_scattering``, (levels, 3), 1/m, molecules and aerosol summed).

At a point p, with beta(p) the grid's extinction and omega_h(p) the hydrometeors' albedo (both trilinear, as
Mitsuba's grid volumes blend them) and the air's extinction e(z) and scattering s(z) (linear between the level
centres, as the trackers read the air):

    sigma_t = beta + e,   omega = (omega_h beta + s) / sigma_t  (1 where nothing attenuates),

the point-wise mixture, as ``spectral_air_albedo`` has it at the lanes' wavelengths. (It blended the 8 corners'
mixture albedos before: near a cloud's edge the empty corners' albedo is the air's, far under 1 in the upper air
where ozone's absorption is a large share of its thin extinction, and it was applied to the cloud's collisions
there, which darkened the cloud in red and green.) Without air (e = s = 0) it is omega_h, the medium's own albedo.
"""
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
        """The albedo (Color3f) at the unit-cube point ``p_local``; ``beta`` the grey sigma_t grid's data (flat):
        the point-wise mixture (omega_h beta + s) / (beta + e), omega_h and beta trilinear, e and s linear between
        the level centres (as ``air_levels.AirLevels.sigma_at``, so sigma_s / sigma_t of the trackers' medium)."""
        corner, frac = grid_lookup.corners(p_local, self.shape, periodic)
        _, ny, nx = self.shape
        n_c = self.channels

        def texel(z, y, x):  # (beta, omega_h R, G, B) of a corner, blended as one packet
            i = mi.UInt32((z * ny + y) * nx + x)
            a = [dr.gather(mi.Float, self.albedo, i * n_c + c, active) for c in range(n_c)]
            return mi.Vector4f(dr.gather(mi.Float, beta, i, active), *(a if n_c == 3 else a * 3))

        v = grid_lookup.trilinear(texel, corner, frac)
        (z0, z1), fz = corner[0], frac[0]
        out = []
        for c in range(3):
            e, s = (grid_lookup.lerp(dr.gather(mi.Float, t, mi.UInt32(z0 * 3 + c), active),
                                     dr.gather(mi.Float, t, mi.UInt32(z1 * 3 + c), active), fz)
                    for t in (self.ext, self.sca))
            sigma_t = v[0] + e
            sca = v[1 + c] * v[0] + s
            out.append(dr.clip(dr.select(sigma_t > 0.0, sca / dr.select(sigma_t > 0.0, sigma_t, 1.0), 1.0), 0.0, 1.0))
        return mi.Color3f(*out)


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
