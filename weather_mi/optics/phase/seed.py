"""Regenerate the default-quality phase tables shipped with the package (weather_mi/phase/data/):
every table that ``for_species`` builds for the "paper" and "physical" presets in both modes.

    WEATHER_MI_CACHE=$(mktemp -d) python -m weather_mi.optics.phase.seed
"""
from __future__ import annotations

import shutil

from .. import species
from . import cache
from .species_tables import for_species


def main() -> None:
    cache.SHIPPED.mkdir(exist_ok=True)
    for preset in species.PRESETS:
        for mode in ("per_species", "paper"):
            for_species(list(species.preset(preset)), mode=mode, quality="default")
    for f in cache.cache_dir().glob("*.npz"):
        shutil.copy(f, cache.SHIPPED / f.name)
        print("shipped", f.name)


if __name__ == "__main__":
    main()
