"""The species' optics as functions of wavelength, for the spectral ground truth (``llvm_ad_spectral``).

* Extinction: Eq. 4, beta_ext = 3 q rho_air / (2 rho_p r_e) with Q_ext = 2, has no wavelength in it: the
  geometric-optics limit (size parameter 2 pi r / lambda >= 80 for a 10 um droplet at 830 nm). Kept grey.
* Single-scattering co-albedo 1 - omega(lambda): weak-absorption geometric optics (``species``' formula,
  Q_abs = 8/3 x k (n^3 - (n^2 - 1)^(3/2)), x = 2 pi r / lambda) with the absorption index k(lambda) of
  liquid water from Hale & Querry (1973, Appl. Opt. 12, 555, Table 1; ``phase.mie.WATER_HALE_QUERRY``,
  350-900 nm)
  and of ice from Warren & Brandt (2008, J. Geophys. Res. 113, D14220) at 450 / 550 / 650 nm
  (``species.ICE_K``), log-linear in wavelength between them and extrapolated beyond (ice's k rises
  steadily from its minimum near 400 nm into the near infrared). Each species' spectrum is scaled to its
  own albedo at 550 nm (``Species.albedo_rgb[1]``), so presets and overrides carry over.
* The sun: the ASTM G173-03 top-of-atmosphere spectrum (``spectrum.solar_toa_w_m2_nm``) over its luminance
  (Y = 1 above the air, as ``air.sunlight.sun_xyz``), times the air's transmittance by height and cos(zenith)
  (``air.sunlight.transmittance``) with an atmosphere: :func:`sun_spectrum`, :func:`sun_spectral_table`.
* Phase functions: each species' tables every 25 nm over 350-850 nm (``phase.spectral_tables``: Mie for cloud
  and rain with water's index at each wavelength, the ice habits' ray tally with the diffraction of each
  wavelength), which the kernel interpolates linearly in wavelength at each path's wavelengths
  (``kernel.plugins.spectral_phase``); tables without a spectral form (Rayleigh, given ones) as their R, G, B
  channels linear in wavelength, held beyond 450 and 650 nm.
"""
from __future__ import annotations

import numpy as np

from . import spectrum
from .species import ICE_K, ICE_N, RGB_WAVELENGTHS_M, RHO_ICE

COALBEDO_NM = np.arange(360.0, 830.0 + 0.1, 10.0)   # the kernel's co-albedo grid (uniform, nm)
REFERENCE_NM = 550.0                                 # the wavelength at which a species' albedo is its own


def water_nk(wavelength_nm) -> tuple[np.ndarray, np.ndarray]:
    """(n, k) of liquid water (Hale & Querry 1973) at wavelengths (nm), held at 350 nm below 350 nm."""
    from .phase.mie import WATER_HALE_QUERRY
    wl, n, k = (np.array(c, np.float64) for c in zip(*WATER_HALE_QUERRY))
    lam = np.clip(np.asarray(wavelength_nm, np.float64) * 1e-9, wl[0], wl[-1])
    return np.interp(lam, wl, n), np.exp(np.interp(lam, wl, np.log(k)))


def ice_nk(wavelength_nm) -> tuple[np.ndarray, np.ndarray]:
    """(n, k) of ice (Warren & Brandt 2008 at 450 / 550 / 650 nm): n linear, log k linear in wavelength
    (extrapolated beyond 450-650 nm from the nearest pair)."""
    lam = np.asarray(wavelength_nm, np.float64)
    wl = np.array(RGB_WAVELENGTHS_M)[::-1] * 1e9          # 450, 550, 650
    n, logk = np.array(ICE_N)[::-1], np.log(np.array(ICE_K)[::-1])
    seg = np.clip(np.searchsorted(wl, lam) - 1, 0, wl.size - 2)
    t = (lam - wl[seg]) / (wl[seg + 1] - wl[seg])
    return (np.clip(n[seg] + t * (n[seg + 1] - n[seg]), n.min(), n.max()),
            np.exp(logk[seg] + t * (logk[seg + 1] - logk[seg])))


def weak_absorption_coalbedo(radius_m, n, k, wavelength_nm) -> np.ndarray:
    """1 - omega = Q_abs / 2 = 4/3 x k (n^3 - (n^2 - 1)^1.5), x = 2 pi r / lambda (k x << 1 << x)."""
    x = 2.0 * np.pi * radius_m / (np.asarray(wavelength_nm, np.float64) * 1e-9)
    return np.minimum(4.0 / 3.0 * x * k * (n ** 3 - (n * n - 1.0) ** 1.5), 0.5)


def species_coalbedo(sp, wavelength_nm=COALBEDO_NM) -> np.ndarray:
    """The co-albedo spectrum 1 - omega(lambda) of one species (``name``, ``radius_m``, ``density_kg_m3``,
    ``phase_class``, ``albedo_rgb``) at ``wavelength_nm``: the weak-absorption shape, scaled to the species'
    own co-albedo at 550 nm (0 where that is 0)."""
    lam = np.asarray(wavelength_nm, np.float64)
    grid = np.append(lam, REFERENCE_NM)
    if sp.phase_class == "water":
        n, k = water_nk(grid)
        radius = sp.radius_m
    else:
        n, k = ice_nk(grid)
        radius = sp.radius_m * min(sp.density_kg_m3 / RHO_ICE, 1.0)
    shape = weak_absorption_coalbedo(radius, n, k, grid)
    own = 1.0 - float(sp.albedo_rgb[1])
    return np.clip(shape[:-1] / shape[-1] * own, 0.0, 1.0)


def coalbedo_table(species, wavelength_nm=COALBEDO_NM) -> np.ndarray:
    """(S, K + 1): the co-albedo spectra of the species objects ``species`` (in the volume's order) at the K
    wavelengths, and each one's co-albedo at REFERENCE_NM in the last column."""
    grid = np.append(np.asarray(wavelength_nm, np.float64), REFERENCE_NM)
    return np.stack([species_coalbedo(sp, grid) for sp in species])


def sun_spectrum(wavelength_nm=spectrum.WAVELENGTHS_NM) -> np.ndarray:
    """The top-of-atmosphere sun's spectral irradiance over its luminance (1/nm: Y = sum E ybar dlambda = 1)."""
    e = spectrum.solar_toa_w_m2_nm(wavelength_nm)
    return e / float(spectrum.xyz(e, wavelength_nm)[1])


def sun_spectral_table(atm, mu0: float, top_m: float, half_width_m: float = 0.0,
                       wavelength_nm=spectrum.WAVELENGTHS_NM):
    """(heights (n_h,) m, mu (n_mu,), table (n_mu, n_h, n_lambda)): :func:`sun_spectrum` times the direct
    beam's transmittance on the grids of ``air.sun_air_table`` (same arguments), float32."""
    from .air.sunlight import sun_air_table, transmittance
    grid = sun_air_table(atm, mu0, top_m, half_width_m)
    t = transmittance(atm, wavelength_nm, grid.heights_m[None, :], grid.mu[:, None])
    return grid.heights_m, grid.mu, (t * sun_spectrum(wavelength_nm)).astype(np.float32)


__all__ = ["sun_spectrum", "sun_spectral_table", "COALBEDO_NM", "water_nk", "ice_nk", "weak_absorption_coalbedo", "species_coalbedo", "coalbedo_table"]
