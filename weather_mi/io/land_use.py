"""What the ground is made of: WRF's land-use classes (LU_INDEX with the file's MMINLU table) grouped into a few
surface kinds, and each kind's spectral albedo at the imagers' visible/near-infrared bands.

Land-use tables (WRF ``run/LANDUSE.TBL``; the water, lake and snow/ice classes also from the file's ISWATER,
ISLAKE, ISICE attributes where it has them):

- ``USGS`` (24 classes, 28 with lakes): 16 water bodies, 24 snow or ice, 28 lakes.
- ``MODIFIED_IGBP_MODIS_NOAH`` (20 classes, 21 with lakes): 17 water, 15 snow and ice, 21 lakes.

Spectral albedo per kind (``SPECTRAL_ALBEDO``, at 0.47, 0.51, 0.64, 0.86 um and the kind's broadband shortwave
albedo): representative, rounded values of the spectra of the ECOSTRESS spectral library (formerly ASTER;
Baldridge et al. 2009, Remote Sens. Environ. 113, 711; Meerdink et al. 2019, RSE 230, 111196) for green
vegetation (conifer and broadleaf canopies, grasses), dry grass and shrubs, soils and sand, man-made
materials, and for snow the fine-grained pure snow of Wiscombe & Warren 1980 (J. Atmos. Sci. 37, 2712); the
broadband values are the summer albedos of WRF's USGS LANDUSE.TBL for the same classes (forest 12-16 %,
cropland/grassland 18-19 %, shrubland/savanna 20-25 %, barren 25 %, urban 15 %, wetland 14 %) and 0.80 for
fresh snow. Values chosen from these sources, not fitted here: a stand-in for a surface spectral
database, good for the contrast a true-colour picture shows (vegetation dark in the visible and bright at
0.86 um, deserts bright and red, snow white).

A column's albedo in a band (``band_albedo``): the file's broadband ALBEDO scaled by its kind's spectral shape
(value in the band / broadband value) where the file has an albedo, else the kind's value; snow-covered
fractions mixed in by their cover (SNOWC, or SNOWH / 0.1 m, or SNOW / 20 kg m-2, capped at 1).
"""
from __future__ import annotations

import numpy as np

# surface kinds (the ``surface_kind`` coordinate of a Hydrometeors Dataset, int8)
KINDS = ("sea", "lake", "forest", "grass_crop", "shrub_savanna", "barren", "urban", "wetland", "snow_ice", "land")
KIND = {name: k for k, name in enumerate(KINDS)}
WATER_KINDS = (KIND["sea"], KIND["lake"])

BAND_UM = (0.47, 0.51, 0.64, 0.86)
# kind -> (albedo at 0.47, 0.51, 0.64, 0.86 um, broadband shortwave); sources in the module docstring
SPECTRAL_ALBEDO = {
    "forest":        (0.03, 0.05, 0.03, 0.30, 0.13),
    "grass_crop":    (0.05, 0.09, 0.07, 0.35, 0.18),
    "shrub_savanna": (0.07, 0.10, 0.12, 0.28, 0.22),
    "barren":        (0.20, 0.26, 0.35, 0.42, 0.25),
    "urban":         (0.10, 0.12, 0.14, 0.20, 0.15),
    "wetland":       (0.04, 0.07, 0.05, 0.25, 0.14),
    "snow_ice":      (0.97, 0.97, 0.96, 0.89, 0.80),
    "land":          (0.06, 0.09, 0.09, 0.32, 0.20),  # land of unknown use: the mean of vegetated kinds
}
# the water-leaving part of the sea and lakes, a Lambertian term under the Fresnel interface (``kernel``'s sea
# surface): pure water's absorption (Pope & Fry 1997) leaves light only in the blue; chosen, not fitted
WATER_BODY_ALBEDO = (0.04, 0.03, 0.01, 0.0, 0.02)

# WRF LANDUSE.TBL classes -> kinds, for the tables weather-mi reads (water, lakes and snow from the table
# unless the file's ISWATER/ISLAKE/ISICE say otherwise)
_USGS = {1: "urban", 2: "grass_crop", 3: "grass_crop", 4: "grass_crop", 5: "grass_crop", 6: "forest",
         7: "grass_crop", 8: "shrub_savanna", 9: "shrub_savanna", 10: "shrub_savanna", 11: "forest", 12: "forest",
         13: "forest", 14: "forest", 15: "forest", 16: "sea", 17: "wetland", 18: "wetland", 19: "barren",
         20: "shrub_savanna", 21: "shrub_savanna", 22: "shrub_savanna", 23: "barren", 24: "snow_ice", 28: "lake"}
_MODIS = {1: "forest", 2: "forest", 3: "forest", 4: "forest", 5: "forest", 6: "shrub_savanna", 7: "shrub_savanna",
          8: "shrub_savanna", 9: "shrub_savanna", 10: "grass_crop", 11: "wetland", 12: "grass_crop", 13: "urban",
          14: "grass_crop", 15: "snow_ice", 16: "barren", 17: "sea", 18: "shrub_savanna", 19: "shrub_savanna",
          20: "barren", 21: "lake"}
TABLES = {"USGS": (_USGS, {"ISWATER": 16, "ISLAKE": 28, "ISICE": 24}),
          "MODIFIED_IGBP_MODIS_NOAH": (_MODIS, {"ISWATER": 17, "ISLAKE": 21, "ISICE": 15})}
SNOW_DEPTH_FULL_M = 0.1      # SNOWH at which a column counts as fully snow-covered
SNOW_WATER_FULL_KGM2 = 20.0  # SNOW (water equivalent) at which a column counts as fully snow-covered


def kinds_from_land_use(lu_index: np.ndarray, attrs, source: str) -> np.ndarray:
    """Surface kinds (int8, ``KINDS``) of LU_INDEX values under the file's MMINLU table.

    Raises
    ------
    WeatherDataError
        For a table weather-mi does not read, or a class outside it (both named with the file).
    """
    from ..errors import WeatherDataError
    name = str(attrs.get("MMINLU", "")).strip()
    if name not in TABLES:
        raise WeatherDataError(source, "MMINLU", f"a land-use table weather-mi reads ({', '.join(TABLES)})",
                               repr(name))
    table, special = TABLES[name]
    table = dict(table)
    for attr, kind in (("ISWATER", "sea"), ("ISLAKE", "lake"), ("ISICE", "snow_ice")):
        value = int(attrs.get(attr, special[attr]))
        if value > 0:  # WRF writes -1 where a table has no such class
            table[value] = kind
    lu = np.rint(np.asarray(lu_index, float)).astype(int)
    unknown = sorted(set(np.unique(lu).tolist()) - set(table))
    if unknown:
        raise WeatherDataError(source, "LU_INDEX", f"classes of the {name} table ({min(table)}..{max(table)})",
                               f"classes {unknown[:5]}")
    lookup = np.zeros(max(table) + 1, np.int8)
    for cls, kind in table.items():
        lookup[cls] = KIND[kind]
    return lookup[lu]


def snow_cover(read2d, has) -> tuple[np.ndarray | None, str | None]:
    """The snow-covered fraction of each column in [0, 1] from SNOWC, else SNOWH / ``SNOW_DEPTH_FULL_M``, else
    SNOW / ``SNOW_WATER_FULL_KGM2`` (capped at 1), and its source; (None, None) where the file has none."""
    if has("SNOWC"):
        return np.clip(read2d("SNOWC"), 0.0, 1.0), "SNOWC"
    if has("SNOWH"):
        return np.clip(read2d("SNOWH") / SNOW_DEPTH_FULL_M, 0.0, 1.0), f"SNOWH / {SNOW_DEPTH_FULL_M} m"
    if has("SNOW"):
        return np.clip(read2d("SNOW") / SNOW_WATER_FULL_KGM2, 0.0, 1.0), f"SNOW / {SNOW_WATER_FULL_KGM2} kg m-2"
    return None, None


def _table(wavelength_um: float) -> tuple[np.ndarray, np.ndarray]:
    """(albedo of every kind at ``wavelength_um``, broadband albedo of every kind), (len(KINDS),) each: linear
    in wavelength between the table's bands, flat beyond them."""
    rows = {**SPECTRAL_ALBEDO, "sea": WATER_BODY_ALBEDO, "lake": WATER_BODY_ALBEDO}
    a = np.array([rows[k] for k in KINDS], float)
    return np.array([np.interp(wavelength_um, BAND_UM, r[:4]) for r in a]), a[:, 4]


def band_albedo(kind: np.ndarray, wavelength_um: float, broadband=None, snow=None) -> np.ndarray:
    """Each column's albedo at ``wavelength_um`` (module docstring): the ``broadband`` albedo (the file's, or
    None) times its kind's spectral shape, else the kind's own value; ``snow``: the snow-covered fraction,
    mixed into the shape. Water columns get the water body's Lambertian part (their surface reflection is the
    sea surface's own, ``kernel``'s glint)."""
    value, bb = _table(float(wavelength_um))
    k = np.asarray(kind, int)
    v, b = value[k], bb[k]
    if snow is not None:
        f = np.where(np.isin(k, WATER_KINDS), 0.0, np.clip(np.asarray(snow, float), 0.0, 1.0))
        s = KIND["snow_ice"]
        v, b = (1 - f) * v + f * value[s], (1 - f) * b + f * bb[s]
    if broadband is not None:
        scaled = np.asarray(broadband, float) * v / b
        v = np.where(np.isin(k, WATER_KINDS), v, scaled)
    return np.clip(v, 0.0, 1.0)


__all__ = ["KINDS", "KIND", "WATER_KINDS", "SPECTRAL_ALBEDO", "WATER_BODY_ALBEDO", "TABLES", "kinds_from_land_use",
           "snow_cover", "band_albedo"]
