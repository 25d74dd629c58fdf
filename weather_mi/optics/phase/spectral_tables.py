"""The spectral mode's phase tables: every species' phase function at wavelengths over the CIE range.

The RGB mode's tables hold three wavelengths (650 / 550 / 450 nm). The spectral ground truth
(``render --spectral``, 4 wavelengths a path anywhere in 360-830 nm) reads each species' table on the
wavelength grid :data:`SPECTRAL_NM` (350-850 nm every 25 nm: 21 nodes, 450, 550 and 650 nm among them)
and interpolates linearly in wavelength between nodes (``kernel.plugins.spectral_phase``):

* cloud and rain: Mie theory (miepython) at each node with liquid water's index from Hale & Querry (1973)
  (``mie.water_index``: n linear, log k linear between their 25 nm rows);
* ice, snow and graupel: the habit's ray tally (geometric optics at ice's index, Warren & Brandt 2008, at
  450 / 550 / 650 nm, linear in wavelength between them and held beyond: the index changes by 0.3%) plus the
  Fraunhofer diffraction recomputed at each node (width ~ wavelength / radius): ``ice.band_values``;
* any other table (Rayleigh, a given table): its R, G, B channels linear in wavelength, held beyond
  (:func:`lerp_stack`), as the spectral mode did for every species before.

Each node's table is cached on disk like every other table (``cache``: ``mie_cloud-*``, ``mie_rain-*``,
``ice_crystals_band-*`` with the wavelength in the key); the first spectral render of a species set builds
them (about 10 s a node for cloud and rain at "default" quality, one ray trace per ice habit).

Why 25 nm: ``validation/spectral_tables_spacing.py`` interpolates the tables of nodes 25, 50 and 100 nm
apart at their midpoints and compares with Mie theory (and the ice recipe) computed there (its table is in
``docs/spectral.md``); ``tests/test_spectral_tables.py`` holds the 25 nm grid's error against miepython
summed in the test.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .species_tables import table_for
from .table import PhaseTable

STEP_NM = 25.0
SPECTRAL_NM = np.arange(350.0, 850.0 + 0.5 * STEP_NM, STEP_NM)  # nm, uniform (the kernel indexes it)
MIN_NM, MAX_NM = 360.0, 830.0  # the CIE range the spectral variants draw wavelengths from


def check_grid(wavelengths_nm) -> np.ndarray:
    """``wavelengths_nm`` as a float64 array: uniform, ascending, covering 360-830 nm; else ValueError."""
    wl = np.asarray(wavelengths_nm, np.float64).ravel()
    if wl.size < 2 or not np.all(np.diff(wl) > 0) or not np.allclose(np.diff(wl), wl[1] - wl[0]):
        raise ValueError(f"spectral phase-table wavelengths must be uniform and ascending (nm), got {wl}")
    if wl[0] > MIN_NM or wl[-1] < MAX_NM:
        raise ValueError(f"spectral phase-table wavelengths must cover {MIN_NM:g}-{MAX_NM:g} nm, "
                         f"got {wl[0]:g}-{wl[-1]:g} nm")
    return wl


def has_spectral_tables(sp, mode: str) -> bool:
    """Whether species object ``sp`` has its own tables by wavelength (a hydrometeor of the known kinds)."""
    if mode == "paper":
        return getattr(sp, "phase_class", None) in ("water", "ice")
    return mode == "per_species" and getattr(sp, "name", None) in ("cloud", "rain", "ice", "snow", "graupel")


def species_stack(sp, mode: str = "per_species", quality: str = "default", sized: bool = False,
                  wavelengths_nm=SPECTRAL_NM) -> list[PhaseTable]:
    """The tables of species object ``sp`` (as ``table_for`` makes its R, G, B one) at ``wavelengths_nm``,
    each with its wavelength in all three channels."""
    wl = check_grid(wavelengths_nm)
    return [table_for(sp, mode, quality, wavelength_m=float(lam) * 1e-9, sized=sized, ice_bands=True) for lam in wl]


def lerp_stack(table: PhaseTable, wavelengths_nm=SPECTRAL_NM) -> list[PhaseTable]:
    """An R, G, B table as tables at ``wavelengths_nm``: the channels linear in wavelength, held beyond the
    first and last channel (for tables without a spectral form)."""
    wl_c = np.asarray(table.wavelengths_m, np.float64) * 1e9
    order = np.argsort(wl_c)
    out = []
    for lam in np.asarray(wavelengths_nm, np.float64):
        j = np.clip(np.searchsorted(wl_c[order], lam) - 1, 0, 1)
        lo, hi = order[j], order[j + 1]
        t = float(np.clip((lam - wl_c[lo]) / (wl_c[hi] - wl_c[lo]), 0.0, 1.0))
        vals = (1 - t) * table.values[:, lo] + t * table.values[:, hi]
        out.append(PhaseTable.from_values(table.theta, vals, name=f"{table.name} at {lam:g} nm",
                                          wavelengths_m=(lam * 1e-9,) * 3))
    return out


def stacks_for(species: Sequence, tables: Sequence[PhaseTable], mode: str = "per_species",
               quality: str = "default", sized: bool = False, wavelengths_nm=SPECTRAL_NM) -> list[list[PhaseTable]]:
    """Per entry of ``species`` (objects, or None where unknown) with its R, G, B table in ``tables``: the
    tables at ``wavelengths_nm`` (:func:`species_stack`, or :func:`lerp_stack` of its table)."""
    return [species_stack(sp, mode, quality, sized, wavelengths_nm) if sp is not None and has_spectral_tables(sp, mode)
            else lerp_stack(t, wavelengths_nm) for sp, t in zip(species, tables)]


def interpolated(stack: Sequence[PhaseTable], wavelengths_nm, wavelength_nm: float, theta) -> np.ndarray:
    """p (1/sr) at angles ``theta`` (rad) and ``wavelength_nm`` from the tables of ``stack`` at
    ``wavelengths_nm``, linear in wavelength (held beyond the ends): what the kernel evaluates."""
    wl = np.asarray(wavelengths_nm, np.float64)
    u = float(np.clip((wavelength_nm - wl[0]) / (wl[1] - wl[0]), 0.0, wl.size - 1.0001))
    j = int(u)
    t = u - j
    return (1 - t) * stack[j].eval(theta)[..., 1] + t * stack[j + 1].eval(theta)[..., 1]


__all__ = ["SPECTRAL_NM", "STEP_NM", "check_grid", "has_spectral_tables", "species_stack", "lerp_stack", "stacks_for",
           "interpolated"]
