"""Imager bands: a single-wavelength stand-in for a geostationary imager's visible/near-infrared channel, and
the optics of a volume in it.

A band is rendered at its central wavelength, monochromatically, in all three channels of the renderers
(R = G = B). Across a channel's response (about 0.1 um wide for ABI C02) the cloud phase functions and
albedos change by far less than the path tracer's noise; the Rayleigh optical depth, proportional to
lambda^-4.08, changes by +-30% across ABI C02, and its response-weighted mean lies within a few percent
of its value at the central wavelength (the responses are nearly symmetric): a band-mean Rayleigh
optical depth is not modelled.

Per species: water (cloud, rain) phase functions by Mie theory at the band's wavelength (miepython,
Hale & Querry water); ice species from the table channel nearest the band
(``weather_mi.optics.phase.species_tables.nearest_channel``); single-scattering albedos from the volume's nearest
channel (1 - omega < 1e-4 for cloud drops at 0.47-0.86 um).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..optics.volume import OpticalVolume


@dataclass(frozen=True)
class Band:
    """A visible/near-infrared imager band.

    Attributes
    ----------
    name : str
        Its central wavelength in micrometres as text ("0.64").
    wavelength_m : float
        Central wavelength (m).
    channels : dict
        The imagers' names of the channel: {"abi": "C02", "ahi": "B03", "seviri": "VIS0.6"}.
    resolution_km : dict
        Native pixel size at the sub-satellite point per imager (km).
    """

    name: str
    wavelength_m: float
    channels: dict
    resolution_km: dict


# GOES-R ABI (PUG vol. 3, Table 3.3.1), Himawari AHI (JMA), MSG SEVIRI (EUMETSAT) visible channels
BANDS = {
    "0.47": Band("0.47", 470e-9, {"abi": "C01", "ahi": "B01"}, {"abi": 1.0, "ahi": 1.0}),
    "0.64": Band("0.64", 640e-9, {"abi": "C02", "ahi": "B03", "seviri": "VIS0.6"},
                 {"abi": 0.5, "ahi": 0.5, "seviri": 3.0}),
    "0.86": Band("0.86", 865e-9, {"abi": "C03", "ahi": "B04", "seviri": "VIS0.8"},
                 {"abi": 1.0, "ahi": 1.0, "seviri": 3.0}),
}


def band(name) -> Band:
    """The ``Band`` of a central wavelength ("0.64", 0.64 or "0.64um"); a ValueError naming the bands."""
    key = str(name).lower().removesuffix("um").strip()
    for k in BANDS:
        if key == k or _float(key) == float(k):
            return BANDS[k]
    raise ValueError(f"--band {name!r}: expected one of {', '.join(BANDS)} (micrometres)")


def _float(text: str):
    try:
        return float(text)
    except ValueError:
        return None


def band_volume(vol: OpticalVolume, b: Band) -> OpticalVolume:
    """``vol``'s optics in band ``b`` (module docstring): phase tables at its wavelength, the albedo of the
    nearest channel, all three channels alike. Extinction is geometric (Eq. 4, Q_ext = 2) and unchanged."""
    from ..optics.phase.species_tables import for_species, nearest_channel
    from ..optics.phase.table import RGB_WAVELENGTHS_M
    c = int(np.argmin(np.abs(np.asarray(RGB_WAVELENGTHS_M) - b.wavelength_m)))
    if vol.species_set is not None:
        tables = for_species(list(vol.species_set), vol.phase_mode, vol.phase_quality, wavelength_m=b.wavelength_m)
    else:
        tables = [nearest_channel(t, b.wavelength_m) for t in vol.require_phase_tables()]
    albedo = np.repeat(np.asarray(vol.albedo)[..., c:c + 1], 3, axis=-1)
    attrs = {**vol.attrs, "band": b.name, "band_wavelength_m": b.wavelength_m}
    return replace(vol, albedo=albedo, phase_tables=tuple(tables), attrs=attrs)


__all__ = ["Band", "BANDS", "band", "band_volume"]
