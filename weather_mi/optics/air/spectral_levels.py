"""The box's air per level as tables over wavelength, for the spectral variants (``llvm_ad_spectral``): the same
air as the RGB mode's (``inside.BoxAir``, one value per level and channel at 650 / 550 / 450 nm), evaluated by
the same function (``inside.level_components``) on a uniform wavelength grid, read linearly in wavelength at a
path's wavelengths (``kernel.plugins.spectral_air``).

The grid is ``optics.spectrum.WAVELENGTHS_NM`` (360-830 nm every 5 nm, the grid of the spectral sun's air table;
450, 550 and 650 nm among its nodes, so there the tables hold exactly the RGB mode's values). Why 5 nm and not the
phase tables' 25 nm (``optics.phase.spectral_tables``): molecules' extinction goes as ~ lambda^-4, whose linear
interpolant between nodes h apart errs by about h^2 / 8 x 20 / lambda^2 of the value. Measured at every mid-node
against Bodhaine's Eq. 29 (molecules alone, ``tests/test_spectral_air.py``): 1.3 % on the 25 nm grid, 0.21 % on a
10 nm one, 0.053 % on the 5 nm one (worst at 362.5 nm). With ozone (SPCTRL2's table has knots between the grid's
nodes) and aerosol (AOD 0.1) the worst mid-node error on the 5 nm grid is 0.04 % below 3 km and 0.5 % at 15 km
near 767.5 nm, where ozone's share of the thin air's extinction is largest. The tables cost levels x 95 x 4 bytes.

The kernel reads the same air factored (:func:`factored_air_levels`): each of its three components (molecules,
ozone, aerosol: ``inside.components``) is a profile over the levels times a spectrum over the grid, so a path's
lanes read three values per level (as the RGB mode's three channels) and their wavelengths' three spectral
factors once per ray; linear in wavelength between nodes, as the tables (the same numbers to float rounding).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..spectrum import WAVELENGTHS_NM
from .inside import BoxAir, component_albedo, components, level_components


@dataclass(frozen=True)
class SpectralAirLevels:
    """The box's air on a wavelength grid: ``extinction`` (z, K) and ``scattering`` (2, z, K) of molecules and
    aerosol, 1/m, float32, at the uniform ascending ``wavelengths_nm`` (K,)."""

    extinction: np.ndarray
    scattering: np.ndarray
    wavelengths_nm: np.ndarray

    def at(self, wavelengths_nm):
        """(extinction (z, n), scattering (2, z, n)) at ``wavelengths_nm`` (n,): linear between the nodes, held
        beyond the grid's ends (float64), as the kernel reads them."""
        wl = np.asarray(wavelengths_nm, np.float64).ravel()
        grid = self.wavelengths_nm

        def lerp(table):
            t = np.asarray(table, np.float64)
            return np.stack([np.interp(wl, grid, row) for row in t.reshape(-1, grid.size)]).reshape(
                t.shape[:-1] + (wl.size,))
        return lerp(self.extinction), lerp(self.scattering)


def _grid(wavelengths_nm) -> np.ndarray:
    wl = np.asarray(wavelengths_nm, np.float64).ravel()
    step = np.diff(wl)
    if wl.size < 2 or np.any(step <= 0) or not np.allclose(step, step[0]):
        raise ValueError(f"the air's wavelength grid must be uniform and ascending with >= 2 nodes, got {wl.size} "
                         f"nodes from {wl.min(initial=np.nan)} to {wl.max(initial=np.nan)} nm")
    return wl


def _require_levels(air: BoxAir) -> None:
    if air.air_number_density_levels is None or air.heights_m is None:
        raise ValueError("the box's air has no air_number_density_levels / heights_m (a BoxAir not made by "
                         "optics.air.inside.box_air): its tables over wavelength cannot be evaluated")


def spectral_air_levels(air: BoxAir, wavelengths_nm=WAVELENGTHS_NM) -> SpectralAirLevels:
    """The air of ``air`` (a ``BoxAir`` built by ``inside.box_air``) at ``wavelengths_nm`` (uniform, ascending);
    a ValueError for a BoxAir without its levels' densities and heights or a grid that is not uniform."""
    wl = _grid(wavelengths_nm)
    _require_levels(air)
    ext, sca = level_components(air.atmosphere, air.air_number_density_levels, air.heights_m, wl)
    return SpectralAirLevels(extinction=np.ascontiguousarray(ext), scattering=np.ascontiguousarray(sca),
                             wavelengths_nm=wl)


@dataclass(frozen=True)
class FactoredAirLevels:
    """The box's air as components m (molecules, ozone, aerosol): extinction(z, lambda) = sum_m ``profiles``[z, m]
    ``spectra``[lambda, m]; ``profiles`` (z, 3) each component's extinction (1/m) at the grid's wavelength where its
    spectrum is largest, ``spectra`` (K, 3) <= 1 on the uniform ``wavelengths_nm`` (K,), float32; ``albedo`` (3,)
    each component's single-scattering albedo (1, 0, the aerosol's)."""

    profiles: np.ndarray
    spectra: np.ndarray
    albedo: np.ndarray
    wavelengths_nm: np.ndarray

    def extinction(self) -> np.ndarray:
        """(z, K) the extinction on the grid (1/m, float64)."""
        return np.asarray(self.profiles, np.float64) @ np.asarray(self.spectra, np.float64).T


def factored_air_levels(air: BoxAir, wavelengths_nm=WAVELENGTHS_NM) -> FactoredAirLevels:
    """``air`` (``inside.box_air``'s) as :class:`FactoredAirLevels` on ``wavelengths_nm`` (uniform, ascending)."""
    wl = _grid(wavelengths_nm)
    _require_levels(air)
    profiles, spectra = components(air.atmosphere, air.air_number_density_levels, air.heights_m, wl)
    peak = spectra.max(axis=0)
    peak = np.where(peak > 0.0, peak, 1.0)
    return FactoredAirLevels(profiles=np.ascontiguousarray(profiles * peak, np.float32),
                             spectra=np.ascontiguousarray(spectra / peak, np.float32),
                             albedo=component_albedo(air.atmosphere), wavelengths_nm=wl)


__all__ = ["SpectralAirLevels", "FactoredAirLevels", "spectral_air_levels", "factored_air_levels"]
