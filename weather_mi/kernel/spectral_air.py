"""The box's air for the spectral variants' plugins (issue 38 part 2): the RGB mode's per-level air
(``optics.air.inside.BoxAir``) evaluated over wavelength (``optics.air.spectral_levels``, the 5 nm grid) and handed
to ``majorant_volpath`` (its extinction and scattering per level, ``kernel.plugins.spectral_air``,
``spectral_air_albedo``) and to ``hydrometeor_mixture`` (the air's Eq. 8 weights by wavelength,
``kernel.plugins.spectral_air_weights``; its two phase tables, Rayleigh's and the aerosol's Henyey-Greenstein, by
wavelength as every table without a spectral form: R, G, B linear in wavelength). The RGB variants' dicts are
``kernel.medium``'s and do not come here."""
from __future__ import annotations

import numpy as np

from ..optics.air.spectral_levels import factored_air_levels, spectral_air_levels
from ..optics.periodic import pad_levels
from ..optics.volume import OpticalVolume


def _levels(a: np.ndarray, periodic) -> np.ndarray:
    return np.ascontiguousarray(pad_levels(a) if periodic else a, np.float32)


def integrator_properties(vol: OpticalVolume, air) -> dict:
    """``majorant_volpath``'s spectral air (``optics.air.spectral_levels.factored_air_levels``): ``air_extinction``
    (levels, 3) the profiles of molecules, ozone and aerosol (1/m), ``air_spectra`` (K, 3) their spectra on the
    wavelengths ``air_nm`` (K,), ``air_component_albedo`` (3,), and ``air_albedo`` the hydrometeors' 550 nm albedo
    (z, y, x, 1); levels padded where periodic."""
    import mitsuba as mi
    f = factored_air_levels(air)
    albedo = np.asarray(vol.albedo)
    albedo = albedo[..., None] if albedo.ndim == 3 else albedo
    albedo = albedo[..., 1:2] if albedo.shape[-1] == 3 else albedo[..., :1]  # 650 / 550 / 450 nm: the 550 nm one
    return {"air_extinction": mi.TensorXf(_levels(f.profiles, vol.periodic)),
            "air_spectra": mi.TensorXf(f.spectra), "air_nm": mi.TensorXf(f.wavelengths_nm.astype(np.float32)),
            "air_component_albedo": mi.TensorXf(f.albedo.astype(np.float32)),
            "air_albedo": mi.TensorXf(_levels(albedo, vol.periodic))}


def extinction_levels(vol: OpticalVolume, air) -> np.ndarray:
    """(levels, K) the air's extinction over wavelength (1/m; levels padded where periodic), as the kernel's
    ``spectral_air.ComponentAirLevels`` holds it: the trackers' majorants bound it at every wavelength of the grid
    (molecules at 360 nm are 2.4x those at 450 nm)."""
    return _levels(factored_air_levels(air).extinction(), vol.periodic)


def phase_properties(vol: OpticalVolume, air) -> dict:
    """``hydrometeor_mixture``'s air weights by wavelength: ``air_weights_spectral`` (levels, K, 2), the scattering
    coefficients of molecules and aerosol, 1/m, on ``air_weights_nm`` (K,)."""
    import mitsuba as mi
    tables = spectral_air_levels(air)
    w = np.transpose(tables.scattering, (1, 2, 0))  # (levels, K, 2)
    return {"air_weights_spectral": mi.TensorXf(_levels(w, vol.periodic)),
            "air_weights_nm": mi.TensorXf(tables.wavelengths_nm.astype(np.float32))}


def air_stacks(air, wavelengths_nm) -> list:
    """The air's two phase tables (``BoxAir.phase_tables``) at ``wavelengths_nm``, as the mixture's tables by
    wavelength take them (``optics.phase.spectral_tables.lerp_stack``)."""
    from ..optics.phase.spectral_tables import lerp_stack
    return [lerp_stack(t, wavelengths_nm) for t in air.phase_tables]


__all__ = ["integrator_properties", "extinction_levels", "phase_properties", "air_stacks"]
