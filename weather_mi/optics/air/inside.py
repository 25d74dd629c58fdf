"""The air inside the model's box, per colour channel (the RGB mode's wavelengths, ``RGB_WAVELENGTHS_M``:
650, 550, 450 nm): extra components of the medium that the path tracer tracks (``kernel.medium``).

* Molecules: the model's own air density, n = rho_air N_A / M_air, Rayleigh cross section of Bodhaine et
  al. (1999) (``optics.rayleigh``): scattering beta_R,c = sigma_R(lambda_c) n, phase function Rayleigh's
  with depolarisation.
* Ozone: the 1-D atmosphere's profile at the voxels' heights (``Atmosphere.ozone_number_density_m3``),
  Chappuis-band absorption (``air.ozone``): absorbs only.
* Aerosol: the 1-D atmosphere's profile and Angstrom law (``Atmosphere.aerosol_extinction_550_per_m``),
  single-scattering albedo ``aerosol_ssa``, Henyey-Greenstein phase function of asymmetry ``aerosol_g``.

The extinction differs by channel (Rayleigh ~ lambda^-4): the medium's sigma_t becomes an RGB grid (spectral
extinction, tracked by history-aware spectral tracking, Kutz et al. 2017, ``kernel.plugins.trackers``).
The phase functions enter the Eq. 8 mixture as two more components, weighted by their scattering
coefficients (channel mean, as the hydrometeors' weights are: within a channel the mixture of air and
aerosol is then that of the channel mean, exact for molecules alone or a cloud with molecules).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..phase.table import RGB_WAVELENGTHS_M
from ..rayleigh import AVOGADRO, M_AIR_KG_MOL, cross_section_m2 as rayleigh_cross_section_m2
from .atmosphere import Atmosphere
from .ozone import cross_section_m2 as ozone_cross_section_m2

CHANNEL_NM = tuple(float(w * 1e9) for w in RGB_WAVELENGTHS_M)  # R, G, B: 650, 550, 450 nm
NAMES = ("air_molecules", "air_aerosol")


@dataclass(frozen=True)
class BoxAir:
    """The air in the box on the volume's grid (z, y, x), per channel R, G, B: ``extinction`` (z, y, x, 3)
    and ``scattering`` (2, z, y, x, 3) of molecules and aerosol, in 1/m, float32; ``phase_tables`` the
    Rayleigh and the aerosol's Henyey-Greenstein tables; ``atmosphere`` the 1-D atmosphere of ozone and
    aerosol; ``band_nm`` the wavelength of each channel where each is one wavelength (a satellite's bands,
    ``band_box_air``: the sun on its path is then the transmittance there), None for the RGB mode's colours."""

    extinction: np.ndarray
    scattering: np.ndarray
    atmosphere: Atmosphere
    phase_tables: tuple = field(repr=False, default=())
    band_nm: tuple | None = None

    def scattering_mean(self) -> np.ndarray:
        """(2, z, y, x) the components' scattering coefficients, channel mean (the Eq. 8 weights)."""
        return self.scattering.mean(axis=-1)


def box_air(atm: Atmosphere, rho_air_kg_m3, z_m, wavelengths_nm=CHANNEL_NM) -> BoxAir:
    """The air of the box whose dry-air density is ``rho_air_kg_m3`` (z, y, x) at cell-centre heights ``z_m``
    (z,) (m above mean sea level); molecules from that density, ozone and aerosol from ``atm``'s profiles.
    A ValueError for a density that is not positive and finite, or heights that do not match."""
    rho = np.asarray(rho_air_kg_m3, np.float64)
    z = np.asarray(z_m, np.float64).ravel()
    if rho.ndim != 3 or z.size != rho.shape[0]:
        raise ValueError(f"rho_air must be (z, y, x) with one height per level; got {rho.shape} and {z.size} heights")
    if not np.all(np.isfinite(rho)) or np.any(rho < 0):
        raise ValueError("rho_air (dry-air density, kg/m^3) must be finite and >= 0 for the air in the box")
    wl = np.asarray(wavelengths_nm, np.float64)
    n_air = rho * (AVOGADRO / M_AIR_KG_MOL)
    molecules = n_air[..., None] * rayleigh_cross_section_m2(wl * 1e-9)                    # (z, y, x, 3)
    ozone = atm.ozone_number_density_m3(z)[:, None] * ozone_cross_section_m2(wl)            # (z, 3)
    aerosol = atm.aerosol_extinction_550_per_m(z)[:, None] * atm.aerosol_factor(wl)         # (z, 3)
    ext = molecules + (ozone + aerosol)[:, None, None, :]
    aer_sca = np.broadcast_to((aerosol * atm.aerosol_ssa)[:, None, None, :], ext.shape)
    from ..phase.analytic import henyey_greenstein
    from ..rayleigh import phase_table
    return BoxAir(extinction=ext.astype(np.float32), scattering=np.stack([molecules, aer_sca]).astype(np.float32),
                  atmosphere=atm, phase_tables=(phase_table(), henyey_greenstein(atm.aerosol_g)))


def with_box_air(vol, hyd, atm: Atmosphere, band_nm=None):
    """``vol`` (an ``OpticalVolume``) with the air of :func:`box_air` on its grid (``OpticalVolume.air``) from
    the Hydrometeors ``hyd``'s ``rho_air`` and heights ``z``; ``band_nm`` (3,): the channels at these
    wavelengths (nm; a satellite's bands, ``BoxAir.band_nm``), else the RGB mode's. A ValueError naming
    ``rho_air`` where its grid is not the volume's."""
    from dataclasses import replace
    rho, z_m = np.asarray(hyd["rho_air"].values), np.asarray(hyd["z"].values)
    if rho.shape != tuple(vol.shape):
        raise ValueError(f"rho_air's grid {rho.shape} is not the optical volume's {tuple(vol.shape)}: the air in "
                         "the box needs the model's air density on the volume's grid")
    if band_nm is None:
        return replace(vol, air=box_air(atm, rho, z_m))
    band_nm = tuple(float(w) for w in band_nm)
    return replace(vol, air=replace(box_air(atm, rho, z_m, band_nm), band_nm=band_nm))


def medium_extinction(beta_total, air: BoxAir) -> np.ndarray:
    """sigma_t (z, y, x, 3), 1/m: the hydrometeors' grey ``beta_total`` (z, y, x) plus the air's extinction."""
    return np.asarray(beta_total, np.float32)[..., None] + air.extinction


def medium_grids(beta_total, albedo, weights, air: BoxAir):
    """The medium with the air added: (sigma_t (z, y, x, 3), albedo (z, y, x, 3), Eq. 8 scattering
    coefficients of the hydrometeors' species and the air's two components (z, y, x, S + 2), channel mean),
    from the hydrometeors' grey ``beta_total`` (z, y, x), ``albedo`` (z, y, x, 3) and weights (S, z, y, x)."""
    beta = np.asarray(beta_total, np.float32)
    alb = np.asarray(albedo, np.float32)
    sigma_t = medium_extinction(beta, air)
    sca = alb * beta[..., None] + air.scattering.sum(axis=0)
    out_albedo = np.divide(sca, sigma_t, out=np.ones_like(sigma_t), where=sigma_t > 0)
    sca_h = beta * alb.mean(axis=-1)
    coeffs = np.concatenate([np.asarray(weights, np.float32) * sca_h[None], air.scattering_mean()])
    return sigma_t, np.clip(out_albedo, 0.0, 1.0).astype(np.float32), np.moveaxis(coeffs, 0, -1).astype(np.float32)


__all__ = ["BoxAir", "CHANNEL_NM", "NAMES", "box_air", "medium_extinction", "medium_grids", "with_box_air"]
