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

True colour (``rgb_volume``): three bands in one render, each band's single-wavelength optics in one of the
renderers' channels (its phase tables and albedo there), one path set for all three. The extinction is
geometric (Q_ext = 2) and so the same in every band; the molecules' is not (lambda^-4), which one render with
one extinction cannot hold: ``satellite.truecolor`` renders the bands one at a time where the air is in.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..optics.volume import OpticalVolume
from ..optics.forward_peak import grey_albedo


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
    "0.51": Band("0.51", 510e-9, {"ahi": "B02"}, {"ahi": 1.0}),
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


# The true-colour bands of an imager in the order of the render's channels (red, green, blue): ABI has no green
# band, its green is made from 0.47, 0.64 and 0.86 (``truecolor.simulated_green``); AHI has one, B02 at 0.51 um
# The sea under a true-colour render where neither the file nor --ground-albedo gives the ground: a Lambertian
# stand-in, grey 0.02 of surface reflection plus the light from the water, which pure water's absorption
# (Pope & Fry 1997: 0.01/m at 0.47 um, 0.3/m at 0.64 um, several per metre at 0.86 um) leaves only in the blue;
# values chosen, not fitted (the single-band default, DEFAULT_GROUND_ALBEDO, is kept at 0.47 um)
DEFAULT_GROUND_ALBEDO = 0.06  # a satellite view's ground where neither the file nor --ground-albedo gives it: the sea
SEA_ALBEDO = {"0.47": DEFAULT_GROUND_ALBEDO, "0.51": 0.05, "0.64": 0.03, "0.86": 0.02}
IMAGERS = {"abi": "GOES-R ABI", "ahi": "Himawari AHI", "seviri": "MSG SEVIRI"}
TRUE_COLOR = {"abi": ("0.64", "0.86", "0.47"), "ahi": ("0.64", "0.51", "0.47")}


def check_band_on(b: Band, sat) -> None:
    """A ValueError where ``sat``'s imager has no channel at band ``b`` (SEVIRI has no 0.47 um band, ABI no 0.51)."""
    if sat.imager not in b.channels:
        have = ", ".join(k for k, v in BANDS.items() if sat.imager in v.channels)
        raise ValueError(f"--band {b.name}: {sat.name}'s imager ({IMAGERS[sat.imager]}) has no {b.name} um band; "
                         f"it has {have}")


def true_color_bands(sat) -> tuple:
    """The (red, green, blue) channel bands of a true-colour render from ``sat``; a ValueError where its imager
    has no blue band (SEVIRI)."""
    if sat.imager not in TRUE_COLOR:
        have = ", ".join(k for k, v in BANDS.items() if sat.imager in v.channels)
        raise ValueError(f"--rgb: {sat.name}'s imager ({IMAGERS[sat.imager]}) has no 0.47 um (blue) band, only "
                         f"{have}: true colour needs goes-east, goes-west or himawari")
    return tuple(BANDS[k] for k in TRUE_COLOR[sat.imager])


def _float(text: str):
    try:
        return float(text)
    except ValueError:
        return None


MIE_SHORTEST_M = 450e-9


def band_volume(vol: OpticalVolume, b: Band) -> OpticalVolume:
    """``vol``'s optics in band ``b`` (module docstring): phase tables at its wavelength, the albedo of the
    nearest channel, all three channels alike. Extinction is geometric (Eq. 4, Q_ext = 2) and unchanged.
    Below ``MIE_SHORTEST_M`` (Hale & Querry's water index starts at 450 nm; the natural view's 400-437 nm) the
    phase tables are those at 450 nm: cloud drops are grey there within the path tracer's noise."""
    from ..optics.phase.species_tables import for_species, nearest_channel
    from ..optics.phase.table import RGB_WAVELENGTHS_M
    c = int(np.argmin(np.abs(np.asarray(RGB_WAVELENGTHS_M) - b.wavelength_m)))
    if vol.species_set is not None:
        tables = for_species(list(vol.components or vol.species_set), vol.phase_mode, vol.phase_quality,
                             wavelength_m=max(b.wavelength_m, MIE_SHORTEST_M), sized=vol.components is not None)
    else:
        tables = [nearest_channel(t, b.wavelength_m) for t in vol.require_phase_tables()]
    albedo = grey_albedo(np.asarray(vol.albedo)[..., c])  # one channel held, read as three
    attrs = {**vol.attrs, "band": b.name, "band_wavelength_m": b.wavelength_m}
    return replace(vol, albedo=albedo, phase_tables=tuple(tables), attrs=attrs)


def rgb_volume(vol: OpticalVolume, bands) -> OpticalVolume:
    """``vol``'s optics with band ``bands[c]``'s (``band_volume``) in channel c: its phase tables there (on the
    union of the bands' angle grids, exact for piecewise-linear tables) and its albedo."""
    from ..optics.phase.table import PhaseTable
    bvols = [band_volume(vol, b) for b in bands]
    albedo = np.stack([np.asarray(bv.albedo)[..., c] for c, bv in enumerate(bvols)], axis=-1)
    tables = []
    for s in range(len(vol.species)):
        per = [bv.phase_tables[s] for bv in bvols]
        theta = np.unique(np.concatenate([t.theta for t in per]))
        values = np.stack([t.eval(theta)[:, c] for c, t in enumerate(per)], axis=-1)
        tables.append(PhaseTable(theta, values, tuple(b.wavelength_m for b in bands), f"{per[0].name} (true colour)"))
    attrs = {**vol.attrs, "band": " ".join(b.name for b in bands),
             "band_wavelength_m": [b.wavelength_m for b in bands]}
    return replace(vol, albedo=albedo.astype(np.float32), phase_tables=tuple(tables), attrs=attrs)


__all__ = ["Band", "BANDS", "IMAGERS", "TRUE_COLOR", "band", "band_volume", "check_band_on", "true_color_bands", "SEA_ALBEDO",
           "rgb_volume"]
