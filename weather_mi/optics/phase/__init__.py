"""Phase-function tables per hydrometeor (paper section 5.2), per RGB channel (650 / 550 / 450 nm).

    from weather_mi import phase
    t = phase.mie_cloud()          # PhaseTable: theta (rad), values (N, 3) in 1/sr, g, cdf, ...
    t.g, t.cone_fraction(np.radians(10)), t.legendre(32)
    tables = phase.for_species(species_set, mode="per_species")

Modules: ``table`` (PhaseTable, angle grid, mixtures), ``analytic`` (Henyey-Greenstein,
Cornette-Shanks, isotropic), ``mie`` (cloud and rain drops, miepython), ``ice`` (ray-traced hexagonal
crystals, snow, graupel), ``cache`` (disk cache), ``species`` (tables for a species set).
Expensive tables are cached in ``$WEATHER_MI_CACHE`` or ``~/.cache/weather-mi/phase/``.
"""
from __future__ import annotations

from .analytic import (cornette_shanks, cornette_shanks_cone_fraction, cornette_shanks_mean_cosine,
                       henyey_greenstein, hg_cone_fraction, isotropic)
from .cache import cache_dir
from .ice import graupel, ice_crystals, snow
from .mie import mie_cloud, mie_rain
from .species_tables import for_species
from .table import RGB_WAVELENGTHS_M, PhaseTable, angle_grid, mixture

__all__ = ["PhaseTable", "angle_grid", "mixture", "RGB_WAVELENGTHS_M", "henyey_greenstein", "cornette_shanks",
           "isotropic", "cornette_shanks_cone_fraction", "cornette_shanks_mean_cosine", "hg_cone_fraction",
           "mie_cloud", "mie_rain", "ice_crystals", "snow", "graupel", "for_species", "cache_dir"]
