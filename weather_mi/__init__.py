"""weather-mi: physically based rendering of numerical-weather-model hydrometeors.

    import weather_mi as wm
    hyd = wm.open_wrf("wrfout_d01_....nc", time=-1)      # Hydrometeors (xarray.Dataset)
    hyd = wm.open_source("cloud.txt")                      # any input: WRF, LES, a demo (demo="cumulus")
    hyd = wm.synthetic.supercell()
    vol = wm.optical_volume(hyd, species=wm.species.preset("paper"), scale={"ice": 2.0})
"""
from __future__ import annotations

from .errors import WeatherDataError
from .io import hydrometeors, open_les, open_wrf, synthetic
from .io.hydrometeors import SPECIES_NAMES, from_arrays, validate
from .io.sources import open_source, open_times
from .io.image import Image
from .optics import species
from .optics.volume import OpticalVolume, optical_volume
from .optics.air.atmosphere import Atmosphere
from .kernel.variant import ensure_registered, register_lazily, set_variant
from .kernel.medium import medium_dict, phase_dict
from .scene.spec import Camera, Ground, RayTable, SceneSpec, Sky, Sun
from .reference.render import render_reference, render_transmittance
from .slicing import SliceMode, SliceParams, SliceRenderer, render_slices

register_lazily()  # the plugins usable from dict and XML scenes in any variant selected, now or later

__version__ = "0.1.0"

# the subpackages, one per concept along the data flow, and the modules a script reaches for by short names
SUBPACKAGES = ("io", "optics", "scene", "kernel", "reference", "slicing", "plane_parallel", "satellite", "display",
               "study", "viewer", "cli")
SHORT_NAMES = {"hydrometeors": "io.hydrometeors", "sources": "io.sources", "synthetic": "io.synthetic",
               "species": "optics.species", "phase": "optics.phase", "detail": "optics.detail",
               "terrain": "io.terrain", "place": "scene.place", "metrics": "display.metrics",
               "denoise": "display.denoise", "air": "optics.air", "spectrum": "optics.spectrum"}

__all__ = ["WeatherDataError", "SPECIES_NAMES", "from_arrays", "validate", "open_wrf", "open_les", "open_source",
           "open_times", "optical_volume", "OpticalVolume", "set_variant", "medium_dict", "phase_dict",
           "Camera", "Ground", "RayTable", "SceneSpec", "Sky", "Sun", "Atmosphere", "Image", "render_reference", "render_transmittance",
           "SliceMode", "SliceParams", "SliceRenderer", "render_slices", "view", *SUBPACKAGES, *SHORT_NAMES]

# imported on first use (the phase tables pull in miepython/numba, the metrics FLIP)
_LAZY = {**{name: name for name in SUBPACKAGES}, **SHORT_NAMES}


def view(source, **kw):
    """Explore a storm interactively in a Jupyter notebook (``weather_mi.viewer.app.view``): ``source`` is a
    Hydrometeors Dataset, a file or a demo name. ``weather-mi view`` serves the same app in a browser."""
    from .viewer.app import view as _view
    return _view(source, **kw)


def __getattr__(name):
    import importlib
    if name in _LAZY:
        return importlib.import_module(f".{_LAZY[name]}", __name__)
    raise AttributeError(f"module 'weather_mi' has no attribute {name!r}")
