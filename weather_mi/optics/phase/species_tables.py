"""Phase tables for a set of hydrometeor species (duck-typed: ``name``, ``radius_m``, ``phase_class``).

Modes
-----
"per_species" (physical): cloud -> :func:`mie_cloud` (r_eff 10 um, v_eff 0.1); rain -> :func:`mie_rain`
    at the species' ``radius_m``; ice -> :func:`ice_crystals` ("column"); snow -> :func:`snow`;
    graupel -> :func:`graupel`.
"paper" (Riley et al., section 5.2): one water table for every ``phase_class == "water"`` species and
    one ice table for every ``"ice"`` species, as the paper used Wendling et al.'s water and ice
    curves; here :func:`mie_cloud` and :func:`ice_crystals` ("column").
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .ice import graupel, ice_crystals, snow
from .mie import mie_cloud, mie_rain
from .table import PhaseTable

MODES = ("per_species", "paper")
QUALITIES = ("test", "default", "high")


def _attr(sp, name):
    try:
        return getattr(sp, name)
    except AttributeError:
        raise TypeError(f"species object {sp!r} has no attribute {name!r} (needs name, radius_m, phase_class)") from None


def nearest_channel(table: PhaseTable, wavelength_m: float) -> PhaseTable:
    """``table``'s channel nearest ``wavelength_m`` in all three channels (ice tables at one band: the
    geometric optics depends on the wavelength only through the refractive index, which changes by 0.3%
    from 450 to 650 nm, and the diffraction peak's width, proportional to the wavelength)."""
    c = int(np.argmin(np.abs(np.asarray(table.wavelengths_m) - float(wavelength_m))))
    return table.gray(c)


def table_for(sp, mode: str = "per_species", quality: str = "default",
              wavelength_m: float | None = None, sized: bool = False, ice_bands: bool = False) -> PhaseTable:
    """The phase table of one species object: R, G, B, or one band's (``wavelength_m``) in all three
    channels (water by Mie theory at that wavelength, ice from its nearest channel, ``nearest_channel``, or
    with ``ice_bands``, the spectral mode's tables, its own table at that wavelength: ``_ice_band``).
    ``sized`` (a size class, ``optics.size_classes``): every "per_species" table at the object's
    ``radius_m`` (Mie cloud at that r_eff, the ice habits' diffraction by that population), not only rain's."""
    if mode not in MODES:
        raise ValueError(f"mode must be one of {', '.join(map(repr, MODES))}, got {mode!r}")
    if quality not in QUALITIES:
        raise ValueError(f"quality must be one of {', '.join(map(repr, QUALITIES))}, got {quality!r}")
    if wavelength_m is not None:
        cloud_like = _attr(sp, "phase_class") == "water" if mode == "paper" else _attr(sp, "name") == "cloud"
        if cloud_like:
            r_eff = float(_attr(sp, "radius_m")) if sized and mode != "paper" else 10e-6
            return mie_cloud(r_eff, quality=quality, wavelength_m=wavelength_m)
        if mode != "paper" and _attr(sp, "name") == "rain":
            return mie_rain(radius=float(_attr(sp, "radius_m")), quality=quality, wavelength_m=wavelength_m)
        if ice_bands:
            return _ice_band(sp, mode, quality, sized, wavelength_m)
        return nearest_channel(table_for(sp, mode, quality, sized=sized), wavelength_m)
    if mode == "paper":
        cls = _attr(sp, "phase_class")
        if cls == "water":
            return mie_cloud(quality=quality)
        if cls == "ice":
            return ice_crystals("column", quality=quality)
        raise ValueError(f"phase_class must be 'water' or 'ice', got {cls!r}")
    name = _attr(sp, "name")
    if sized and name != "rain":
        return _sized_table(name, float(_attr(sp, "radius_m")), quality)
    if name == "cloud":
        return mie_cloud(quality=quality)
    if name == "rain":
        return mie_rain(radius=float(_attr(sp, "radius_m")), quality=quality)
    if name == "ice":
        return ice_crystals("column", quality=quality)
    if name == "snow":
        return snow(quality=quality)
    if name == "graupel":
        return graupel(quality=quality)
    raise ValueError(f"species name must be one of cloud, ice, rain, snow, graupel; got {name!r}")


def _ice_band(sp, mode: str, quality: str, sized: bool, wavelength_m: float) -> PhaseTable:
    """An ice species' table at one wavelength (``ice.band_values``: the habit's ray tally, the diffraction
    of that wavelength), with the parameters of its R, G, B table."""
    kw = {"quality": quality, "wavelength_m": float(wavelength_m)}
    if mode == "paper":
        return ice_crystals("column", **kw)
    name = _attr(sp, "name")
    if sized:
        kw["radius_m"] = float(_attr(sp, "radius_m"))
    makers = {"ice": lambda: ice_crystals("column", **kw), "snow": lambda: snow(**kw), "graupel": lambda: graupel(**kw)}
    if name not in makers:
        raise ValueError(f"species name must be one of cloud, ice, rain, snow, graupel; got {name!r}")
    return makers[name]()


def _sized_table(name: str, radius_m: float, quality: str) -> PhaseTable:
    """The "per_species" table of species ``name`` at ``radius_m`` (m) for cloud, ice, snow and graupel."""
    if name == "cloud":
        return mie_cloud(radius_m, quality=quality)
    if name == "ice":
        return ice_crystals("column", radius_m=radius_m, quality=quality)
    if name == "snow":
        return snow(radius_m, quality=quality)
    if name == "graupel":
        return graupel(radius_m, quality=quality)
    raise ValueError(f"species name must be one of cloud, ice, rain, snow, graupel; got {name!r}")


def for_species(species: Sequence, mode: str = "per_species", quality: str = "default",
                wavelength_m: float | None = None, sized: bool = False) -> list[PhaseTable]:
    """One :class:`PhaseTable` per entry of ``species``, in order (see the module doc for the
    mapping; ``wavelength_m``: one band's tables, ``sized``: size classes' tables, ``table_for``). Tables are
    cached on disk and in memory, so repeated species cost nothing."""
    return [table_for(sp, mode, quality, wavelength_m, sized) for sp in species]


__all__ = ["for_species", "table_for", "nearest_channel", "MODES"]
