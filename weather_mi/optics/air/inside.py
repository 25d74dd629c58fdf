"""The air inside the model's box, per colour channel (the RGB mode's wavelengths, ``RGB_WAVELENGTHS_M``:
650, 550, 450 nm): extra components of the medium that the path tracer tracks (``kernel.medium``).

* Molecules: the model's own air density, n = rho_air N_A / M_air, Rayleigh cross section of Bodhaine et
  al. (1999) (``optics.rayleigh``): scattering beta_R,c = sigma_R(lambda_c) n, phase function Rayleigh's
  with depolarisation.
* Ozone: the 1-D atmosphere's profile at the voxels' heights (``Atmosphere.ozone_number_density_m3``),
  Chappuis-band absorption (``air.ozone``): absorbs only.
* Aerosol: the 1-D atmosphere's profile and Angstrom law (``Atmosphere.aerosol_extinction_550_per_m``),
  single-scattering albedo ``aerosol_ssa``, Henyey-Greenstein phase function of asymmetry ``aerosol_g``.

The extinction differs by channel (Rayleigh ~ lambda^-4): spectral extinction, tracked by history-aware spectral
tracking (Kutz et al. 2017, ``kernel.plugins.trackers``). ``majorant_volpath`` adds the air per level itself (the
medium's sigma_t grid stays the hydrometeors' grey one, the air's Eq. 8 coefficients a table per level,
``kernel.plugins.air_levels``, the mixture's albedo at a point ``kernel.plugins.air_albedo``); for stock
``volpath`` :func:`medium_grids` puts it into RGB grids (``kernel.medium.medium_dict(air_in_grid=True)``; their
albedo the texels' mixtures, blended: at a cloud's edge in absorbing air not the point-wise mixture the integrator
has).
The phase functions enter the Eq. 8 mixture as two more components, weighted by their scattering
coefficients per colour channel (``kernel.medium.air_weights``: each channel's mixture its own, as Eq. 8 holds
per wavelength; the hydrometeors' coefficients are one for all channels). With channel means a cloud inside a
Rayleigh column was 5% too bright in red and 3% too dark in blue against DISORT (``tests/test_clear_sky_disort.py``).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..phase.table import RGB_WAVELENGTHS_M
from ..rayleigh import AVOGADRO, M_AIR_KG_MOL, cross_section_m2 as rayleigh_cross_section_m2
from ..scattering_coefficients import scattering_coefficients
from ..volume import level_density
from .atmosphere import Atmosphere
from .ozone import channel_cross_section_m2 as ozone_cross_section_m2

CHANNEL_NM = tuple(float(w * 1e9) for w in RGB_WAVELENGTHS_M)  # R, G, B: 650, 550, 450 nm
NAMES = ("air_molecules", "air_aerosol")


@dataclass(frozen=True)
class BoxAir:
    """The air in the box, one value per level (the air is horizontally homogeneous in the box, as it is
    outside it): ``extinction_levels`` (z, 3) and ``scattering_levels`` (2, z, 3) of molecules and aerosol
    per channel R, G, B, in 1/m, float32, on a grid of ``shape`` (z, y, x); ``phase_tables`` the Rayleigh
    and the aerosol's Henyey-Greenstein tables; ``atmosphere`` the 1-D atmosphere of ozone and aerosol;
    ``band_nm`` the wavelength of each channel where each is one wavelength (a satellite's bands,
    ``band_box_air``: the sun on its path is then the transmittance there), None for the RGB mode's colours;
    ``air_number_density_levels`` (z,) molecules per m^3 and ``heights_m`` (z,) the levels' heights, from which
    :func:`level_components` gives the same air at any wavelength (the spectral variants' tables,
    ``optics.air.spectral_levels``).
    ``extinction`` and ``scattering`` are the same broadcast onto the grid (read-only views, no memory)."""

    extinction_levels: np.ndarray
    scattering_levels: np.ndarray
    shape: tuple
    atmosphere: Atmosphere
    phase_tables: tuple = field(repr=False, default=())
    band_nm: tuple | None = None
    air_number_density_levels: np.ndarray | None = field(repr=False, default=None)
    heights_m: np.ndarray | None = field(repr=False, default=None)

    @property
    def extinction(self) -> np.ndarray:
        """(z, y, x, 3) the extinction on the grid, 1/m (a broadcast view)."""
        return np.broadcast_to(self.extinction_levels[:, None, None, :], tuple(self.shape) + (3,))

    @property
    def scattering(self) -> np.ndarray:
        """(2, z, y, x, 3) the components' scattering coefficients on the grid, 1/m (a broadcast view)."""
        return np.broadcast_to(self.scattering_levels[:, :, None, None, :], (2,) + tuple(self.shape) + (3,))

    def scattering_mean(self) -> np.ndarray:
        """(2, z, y, x) the components' scattering coefficients, channel mean (the Eq. 8 weights)."""
        return np.broadcast_to(self.scattering_levels.mean(axis=-1)[:, :, None, None], (2,) + tuple(self.shape))


def box_air(atm: Atmosphere, rho_air_kg_m3, z_m, wavelengths_nm=CHANNEL_NM, shape=None) -> BoxAir:
    """The air of the box at cell-centre heights ``z_m`` (z,) (m above mean sea level): molecules from the
    dry-air density ``rho_air_kg_m3`` (z, y, x, its mean per level: :func:`level_density`; or (z,)), ozone and
    aerosol from ``atm``'s profiles; on a grid of ``shape`` (z, y, x) (default: ``rho_air_kg_m3``'s). A ValueError
    for a density that is not positive and finite, or heights that do not match."""
    rho_in = np.asarray(rho_air_kg_m3)
    rho = level_density(rho_in)
    z = np.asarray(z_m, np.float64).ravel()
    shape = tuple(int(v) for v in (shape if shape is not None else rho_in.shape))
    if len(shape) != 3 or z.size != rho.size or shape[0] != rho.size:
        raise ValueError(f"rho_air must be (z, y, x) or (z,) with one height per level on a (z, y, x) grid; got "
                         f"{rho_in.shape}, {z.size} heights and the grid {shape}")
    n_air = rho * (AVOGADRO / M_AIR_KG_MOL)
    extinction, scattering = level_components(atm, n_air, z, wavelengths_nm)
    from ..phase.analytic import henyey_greenstein
    from ..rayleigh import phase_table
    return BoxAir(extinction_levels=extinction, scattering_levels=scattering, shape=shape, atmosphere=atm,
                  phase_tables=(phase_table(), henyey_greenstein(atm.aerosol_g)), air_number_density_levels=n_air,
                  heights_m=z)


def components(atm: Atmosphere, n_air_m3, z_m, wavelengths_nm):
    """(profiles (z, 3), spectra (n, 3)), float64: the air's three components, molecules, ozone and aerosol, as a
    density per level times a cross section per wavelength, whose products are their extinctions (1/m): molecules
    ``n_air_m3`` (z,) per m^3 x Bodhaine's cross section (m^2), ozone ``atm``'s number density at ``z_m`` (z,) (m) x
    the Chappuis band's cross section (m^2; for the RGB mode's channels each one's band average,
    ``ozone.channel_cross_section_m2``), aerosol its extinction at 550 nm (1/m) x Angstrom's factor."""
    wl = np.asarray(wavelengths_nm, np.float64)
    z = np.asarray(z_m, np.float64)
    profiles = np.stack([np.asarray(n_air_m3, np.float64), atm.ozone_number_density_m3(z),
                         atm.aerosol_extinction_550_per_m(z)], axis=1)
    spectra = np.stack([rayleigh_cross_section_m2(wl * 1e-9), ozone_cross_section_m2(wl), atm.aerosol_factor(wl)],
                       axis=1)
    return profiles, spectra


def component_albedo(atm: Atmosphere) -> np.ndarray:
    """(3,) the single-scattering albedo of :func:`components`' molecules (1), ozone (0) and aerosol."""
    return np.array([1.0, 0.0, atm.aerosol_ssa])


def level_components(atm: Atmosphere, n_air_m3, z_m, wavelengths_nm):
    """(extinction (z, n), scattering of molecules and aerosol (2, z, n)), float32, 1/m: the air of levels with
    ``n_air_m3`` (z,) molecules per m^3 at heights ``z_m`` (z,) (m) at ``wavelengths_nm`` (n,): molecules
    (Bodhaine's cross section), ozone and aerosol from ``atm``'s profiles (module docstring; :func:`components`)."""
    profiles, spectra = components(atm, n_air_m3, z_m, wavelengths_nm)
    molecules, ozone, aerosol = (profiles[:, m][:, None] * spectra[:, m] for m in range(3))   # (z, n) each
    return ((molecules + ozone + aerosol).astype(np.float32),
            np.stack([molecules, aerosol * atm.aerosol_ssa]).astype(np.float32))


def with_box_air(vol, hyd, atm: Atmosphere, band_nm=None):
    """``vol`` (an ``OpticalVolume``) with the air of :func:`box_air` on its grid (``OpticalVolume.air``): molecules
    from the Hydrometeors ``hyd``'s ``rho_air`` (its mean per level) where given, else from the volume's own
    ``air_density`` (the model's, kept by ``optical_volume``), else from the US 1976 standard atmosphere at the
    levels' heights; ``band_nm`` (3,): the channels at these wavelengths (nm; a satellite's bands,
    ``BoxAir.band_nm``), else the RGB mode's. A ValueError naming ``rho_air`` where its grid is not the volume's."""
    from dataclasses import replace
    z_m = vol.level_heights_m()
    if hyd is not None and "rho_air" in hyd:
        rho = np.asarray(hyd["rho_air"].values)
        if rho.shape != tuple(vol.shape):
            raise ValueError(f"rho_air's grid {rho.shape} is not the optical volume's {tuple(vol.shape)}: the air in "
                             "the box needs the model's air density on the volume's grid")
    elif getattr(vol, "air_density", None) is not None:
        rho = vol.air_density
    else:
        from ...io.standard_atmosphere import standard_density
        rho = standard_density(z_m)
    if band_nm is None:
        return replace(vol, air=box_air(atm, rho, z_m, shape=vol.shape))
    band_nm = tuple(float(w) for w in band_nm)
    return replace(vol, air=replace(box_air(atm, rho, z_m, band_nm, shape=vol.shape), band_nm=band_nm))


def scene_air(vol, atm):
    """The one place that puts the scene's air into the box: ``vol`` with the air of ``atm`` (a SceneSpec's
    ``atmosphere``) where it has none yet (:func:`with_box_air` from the volume's own ``air_density``); ``vol``
    itself without an atmosphere or with its air already in it."""
    if atm is None or getattr(vol, "air", None) is not None:
        return vol
    return with_box_air(vol, None, atm)


def medium_extinction(beta_total, air: BoxAir) -> np.ndarray:
    """sigma_t (z, y, x, 3), 1/m: the hydrometeors' grey ``beta_total`` (z, y, x) plus the air's extinction."""
    return np.asarray(beta_total, np.float32)[..., None] + air.extinction


SLAB_CELLS = 1 << 21  # cells of the grid at a time in ``medium_grids`` (its temporaries: a slab of levels)


def medium_grids(beta_total, albedo, weights, air: BoxAir, want=("sigma_t", "albedo", "coeffs")):
    """The medium with the air added: (sigma_t (z, y, x, 3), albedo (z, y, x, 3), Eq. 8 scattering
    coefficients of the hydrometeors' species and the air's two components (z, y, x, S + 2), channel mean),
    from the hydrometeors' grey ``beta_total`` (z, y, x), ``albedo`` (z, y, x, 3 or 1) and weights (S, z, y, x;
    or ``optics.forward_peak.ScaledWeights``). Only the grids named in ``want`` are built (None for the
    others), a slab of levels at a time into float32 outputs, so that the temporaries are a slab's."""
    beta = np.asarray(beta_total, np.float32)
    nz = beta.shape[0]
    cells = int(np.prod(beta.shape[1:]))
    n_s = len(weights)
    out = {"sigma_t": np.empty(beta.shape + (3,), np.float32) if "sigma_t" in want else None,
           "albedo": np.empty(beta.shape + (3,), np.float32) if "albedo" in want else None,
           "coeffs": np.empty(beta.shape + (n_s + 2,), np.float32) if "coeffs" in want else None}
    step = max(1, SLAB_CELLS // max(cells, 1))
    for z0 in range(0, nz, step):
        lv = slice(z0, min(nz, z0 + step))
        b = beta[lv]
        alb = np.asarray(albedo[lv], np.float32)
        ext = air.extinction_levels[lv][:, None, None, :]                      # (k, 1, 1, 3)
        sca_air = air.scattering_levels[:, lv][:, :, None, None, :]           # (2, k, 1, 1, 3)
        if out["sigma_t"] is not None or out["albedo"] is not None:
            sigma_t = b[..., None] + ext                                      # Eq. 4 plus the air's
            if out["sigma_t"] is not None:
                out["sigma_t"][lv] = sigma_t
            if out["albedo"] is not None:
                sca = alb * b[..., None] + sca_air.sum(axis=0)
                a = np.divide(sca, sigma_t, out=np.ones_like(sigma_t), where=sigma_t > 0)
                out["albedo"][lv] = np.clip(a, 0.0, 1.0)
        if out["coeffs"] is not None:
            c = out["coeffs"][lv].reshape(-1, n_s + 2)                       # Eq. 8's w_s beta omega, the air's
            scattering_coefficients(beta, albedo, weights, [c[:, s] for s in range(n_s)], z0 * cells, lv.stop * cells)
            c[:, n_s:] = np.broadcast_to(sca_air.mean(axis=-1)[:, :, 0, 0][:, :, None],
                                         (2, lv.stop - z0, cells)).reshape(2, -1).T
    return out["sigma_t"], out["albedo"], out["coeffs"]


__all__ = ["BoxAir", "CHANNEL_NM", "NAMES", "box_air", "components", "component_albedo", "level_components", "level_density", "medium_extinction", "medium_grids", "scene_air",
           "with_box_air"]
