"""Molecular (Rayleigh) scattering of dry air at one wavelength, as an extra species of a volume.

Cross section per molecule: Bodhaine et al. (1999, J. Atmos. Ocean. Tech. 16, 1854), Eq. 29 (their fit
for 360 ppm CO2, 0.25-1 um, within 0.01% of the full expression (Eq. 22-23, ``cross_section_physical_m2``)).
Number density n = rho_air N_A / M_air from the model's air density; the phase function is Chandrasekhar's
with the depolarisation factor rho_n = 0.0279 (Young 1980): p = 3 / (16 pi (1 + 2 gamma))
[(1 + 3 gamma) + (1 - gamma) cos^2] with gamma = rho_n / (2 - rho_n). No absorption (ozone's Chappuis band
absorbs about 2% of a 0.64 um vertical path; not modelled).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .volume import OpticalVolume

AVOGADRO = 6.02214076e23  # 1/mol
M_AIR_KG_MOL = 28.9595e-3  # dry air with 360 ppm CO2 (Bodhaine et al. 1999, Eq. 17)
DEPOLARISATION = 0.0279  # Young (1980)


def cross_section_m2(wavelength_m) -> np.ndarray:
    """Rayleigh cross section per molecule of air (m^2), Bodhaine et al. (1999) Eq. 29."""
    lam = np.asarray(wavelength_m, np.float64) * 1e6  # um
    s = (1.0455996 - 341.29061 * lam ** -2 - 0.90230850 * lam ** 2) / \
        (1.0 + 0.0027059889 * lam ** -2 - 85.968563 * lam ** 2)
    return s * 1e-28 * 1e-4  # 1e-28 cm^2 -> m^2


def cross_section_physical_m2(wavelength_m, co2_ppm: float = 360.0) -> np.ndarray:
    """The cross section from its definition (Bodhaine et al. 1999, Eq. 2): 24 pi^3 (n^2 - 1)^2 /
    (lambda^4 N_s^2 (n^2 + 2)^2) F_air, with the refractive index of standard air of Peck & Reeder (1972)
    (their Eq. 2, with Bodhaine's CO2 correction, Eq. 19), N_s = 2.546899e19 molecules/cm^3 and the King
    factor of Bates (1984) (Eq. 23 over N2, O2, Ar and CO2)."""
    lam = np.asarray(wavelength_m, np.float64) * 1e6
    inv2 = lam ** -2
    n300 = 1.0 + 1e-8 * (8060.51 + 2480990.0 / (132.274 - inv2) + 17455.7 / (39.32957 - inv2))
    n = 1.0 + (n300 - 1.0) * (1.0 + 0.54 * (co2_ppm * 1e-6 - 0.0003))
    f_n2 = 1.034 + 3.17e-4 * inv2
    f_o2 = 1.096 + 1.385e-3 * inv2 + 1.448e-4 * inv2 ** 2
    c = co2_ppm * 1e-4  # percent by volume
    f_air = (78.084 * f_n2 + 20.946 * f_o2 + 0.934 * 1.00 + c * 1.15) / (78.084 + 20.946 + 0.934 + c)
    ns = 2.546899e19  # 1/cm^3
    lam_cm = lam * 1e-4
    sigma_cm2 = 24.0 * np.pi ** 3 * (n * n - 1.0) ** 2 / (lam_cm ** 4 * ns ** 2 * (n * n + 2.0) ** 2) * f_air
    return sigma_cm2 * 1e-4


def beta_per_m(wavelength_m: float, rho_air_kg_m3) -> np.ndarray:
    """Rayleigh scattering coefficient (1/m): sigma n with n = rho N_A / M_air."""
    return float(cross_section_m2(wavelength_m)) * np.asarray(rho_air_kg_m3, np.float64) * AVOGADRO / M_AIR_KG_MOL


def phase_value(mu) -> np.ndarray:
    """Rayleigh phase function with depolarisation (1/sr) at cos(theta) ``mu`` (module docstring; ``mu`` may be a
    Dr.Jit array: ``phase.analytic.values_of``)."""
    from .phase.analytic import values_of
    gamma = DEPOLARISATION / (2.0 - DEPOLARISATION)
    mu = values_of(mu)
    return 3.0 / (16.0 * np.pi * (1.0 + 2.0 * gamma)) * ((1.0 + 3.0 * gamma) + (1.0 - gamma) * mu * mu)


def phase_table():
    """The Rayleigh phase function as a ``PhaseTable`` (the same in R, G, B)."""
    from .phase.table import PhaseTable
    return PhaseTable.from_function(lambda th: np.repeat(phase_value(np.cos(th))[:, None], 3, axis=1),
                                    name="rayleigh")


def with_rayleigh(vol: OpticalVolume, wavelength_m: float, rho_air_kg_m3: np.ndarray) -> OpticalVolume:
    """``vol`` with the air's molecular scattering added as a last species "rayleigh" (albedo 1): extinction
    beta_R, the mixture albedo and the Eq. 8 weights over the hydrometeors' and the air's scattering."""
    beta_r = beta_per_m(wavelength_m, rho_air_kg_m3).astype(np.float32)
    if beta_r.shape != vol.beta_total.shape:
        raise ValueError(f"air density grid {beta_r.shape} is not the volume's {vol.beta_total.shape}")
    beta_h = np.asarray(vol.beta_total, np.float32)
    sca_h = beta_h * np.asarray(vol.albedo, np.float32).mean(axis=-1)  # hydrometeor scattering (Eq. 8 weights' sum)
    sca = sca_h + beta_r
    weights = np.concatenate([np.asarray(vol.weights) * np.divide(sca_h, sca, out=np.zeros_like(sca), where=sca > 0),
                              np.divide(beta_r, sca, out=np.zeros_like(sca), where=sca > 0)[None]])
    total = beta_h + beta_r
    albedo = np.divide(np.asarray(vol.albedo) * beta_h[..., None] + beta_r[..., None], total[..., None],
                       out=np.ones_like(np.asarray(vol.albedo)), where=total[..., None] > 0)
    beta_ext = np.concatenate([np.asarray(vol.beta_ext), beta_r[None]])
    attrs = {**vol.attrs, "rayleigh_wavelength_m": float(wavelength_m)}
    return replace(vol, species=tuple(vol.species) + ("rayleigh",), beta_ext=beta_ext, beta_total=total,
                   albedo=albedo.astype(np.float32), weights=weights.astype(np.float32), species_set=None, components=None,
                   phase_tables=tuple(vol.require_phase_tables()) + (phase_table(),), attrs=attrs)


__all__ = ["cross_section_m2", "cross_section_physical_m2", "beta_per_m", "phase_value", "phase_table",
           "with_rayleigh"]
