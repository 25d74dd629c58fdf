"""The single-scattering albedo of the hydrometeors and the box's air together at a path's 4 wavelengths (spectral
variants), where ``majorant_volpath`` adds the air per level (``spectral_air``: the tables over wavelength) to the
hydrometeors' grey sigma_t grid: the spectral counterpart of ``air_albedo`` (the RGB mode's three channels).

At a point p and a lane's wavelength lambda, with beta(p) the grid's extinction (trilinear), omega_550(p) the
hydrometeors' albedo at 550 nm (``air_albedo``, the volume's 550 nm channel (z, y, x, 1), trilinear), omega_h its
spectral form (``HydrometeorMixture.albedo_at``: the species' co-albedo spectra; grey without them) and the air's
extinction e(z, lambda) and scattering s(z, lambda) (``spectral_air.ComponentAirLevels``: its components' profiles
read once, e = sum_m p_m F_m, s = sum_m omega_m p_m F_m, linear between level centres and the 5 nm grid's nodes):

    sigma_t = beta + e,   omega = (omega_h beta + s) / sigma_t  (0 where sigma_t = 0),

the point-wise mixture (the RGB mode blends the per-texel mixture's albedo, as its grids did before the air was
added per level; without air both are the medium's own albedo). Where the air is absent (e = s = 0) this is the
spectral mode's albedo without air exactly.
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

from . import grid_lookup
from .air_albedo import ALBEDO_PROPERTY
from .medium_setup import medium_interaction


class SpectralMixtureAlbedo:
    """The hydrometeors' 550 nm albedo grid (held as given); the air's is ``MediumSetup.air``'s."""

    def __init__(self, albedo):
        self.shape = tuple(int(n) for n in albedo.shape[:3])
        self.albedo = albedo.array

    def omega_550(self, p_local, periodic: bool, active):
        """The hydrometeors' albedo at 550 nm (Float) at the unit-cube point ``p_local``, trilinear."""
        corner, frac = grid_lookup.corners(p_local, self.shape, periodic)
        _, ny, nx = self.shape
        return grid_lookup.trilinear(lambda z, y, x: dr.gather(mi.Float, self.albedo, mi.UInt32((z * ny + y) * nx + x),
                                                               active), corner, frac)

    def event(self, ms, ray, t, active):
        """(The medium interaction at distance ``t`` along ``ray``, sigma_s and sigma_t set; its albedo, mi.Spectrum)
        with the air at the lanes' wavelengths (``medium_setup.scattering_event``'s)."""
        mei = medium_interaction(ms, ray, ray.o + ray.d * t, t, active)
        wl = ray.wavelengths
        p_local = ms.air_to_local @ mei.p
        q = p_local.z * ms.air_levels - 0.5
        beta = ms.volume.eval_1(mei, active)
        ext, sca_air = ms.air.extinction_scattering(q, active, ms.air.factors(wl))
        omega = self.omega_550(p_local, ms.air_periodic, active)
        omega_h = ms.medium.phase_function().albedo_at(mei, omega) if ms.spectral_albedo else mi.Spectrum(omega)
        sigma_t = ext + beta
        albedo = dr.select(sigma_t > 0.0, dr.clip((omega_h * beta + sca_air) / dr.select(sigma_t > 0.0, sigma_t, 1.0),
                                                  0.0, 1.0), 0.0)
        mei.sigma_s, mei.sigma_t = albedo * sigma_t, sigma_t
        return mei, mi.Spectrum(albedo)


def parse(props, check):
    """``air_albedo`` (z, y, x, 1: the hydrometeors' 550 nm albedo) as a :class:`SpectralMixtureAlbedo`; required with
    the spectral air."""
    check(ALBEDO_PROPERTY in props, f"the spectral air needs '{ALBEDO_PROPERTY}'")
    albedo = props[ALBEDO_PROPERTY]
    check(len(albedo.shape) == 4 and int(albedo.shape[3]) == 1,
          f"'{ALBEDO_PROPERTY}' with the spectral air must be (z, y, x, 1) (the 550 nm albedo), got {tuple(albedo.shape)}")
    return SpectralMixtureAlbedo(albedo)


__all__ = ["SpectralMixtureAlbedo", "parse"]
