"""weather-mi: physically based rendering of numerical-weather-model hydrometeors.

    import weather_mi as wm
    hyd = wm.open_wrf("wrfout_d01_....nc", time=-1)      # Hydrometeors (xarray.Dataset)
    hyd = wm.open_source("cloud.txt")                      # any input: WRF, LES, a demo (demo="cumulus")
    hyd = wm.synthetic.supercell()
    vol = wm.optical_volume(hyd, species=wm.species.preset("paper"), scale={"ice": 2.0})
"""
from __future__ import annotations

from . import atmosphere, hydrometeors, species, synthetic
from .errors import WeatherDataError
from .hydrometeors import SPECIES_NAMES, from_arrays, validate
from .io import open_les, open_wrf
from .sources import open_source, open_times
from .optics import OpticalVolume, optical_volume
from .variant import ensure_registered, register_lazily, set_variant
from .medium import medium_dict, phase_dict
from .scene import Camera, Ground, RayTable, SceneSpec, Sky, Sun
from .imageio import Image
from .reference import render_reference, render_transmittance
from .slicing import SliceMode, SliceParams, SliceRenderer, render_slices
from . import imageio, scene

register_lazily()  # the plugins usable from dict and XML scenes in any variant selected, now or later

__version__ = "0.1.0"

__all__ = ["WeatherDataError", "SPECIES_NAMES", "from_arrays", "validate", "open_wrf", "open_les", "open_source",
           "open_times", "sources",
           "optical_volume", "OpticalVolume", "set_variant", "medium_dict", "phase_dict",
           "Camera", "Ground", "RayTable", "SceneSpec", "Sky", "Sun", "Image", "render_reference", "render_transmittance",
           "SliceMode", "SliceParams", "SliceRenderer", "render_slices", "species", "synthetic", "hydrometeors",
           "atmosphere", "phase", "metrics", "reference", "slicing", "io", "imageio", "scene", "view"]

# submodules imported on first use (the phase tables pull in miepython/numba, the metrics FLIP)
_LAZY_SUBMODULES = ("phase", "metrics", "study", "cli", "detail", "fluxes", "forward_peak", "mitsuba_scene",
                    "framing", "summary", "animate", "dask_passes", "cluster", "geo", "solar", "place", "terrain",
                    "denoise")


def view(source, **kw):
    """Explore a storm interactively in a Jupyter notebook (``weather_mi.viewer.app.view``): ``source`` is a
    Hydrometeors Dataset, a file or a demo name. ``weather-mi view`` serves the same app in a browser."""
    from .viewer.app import view as _view
    return _view(source, **kw)


def __getattr__(name):
    import importlib
    if name in _LAZY_SUBMODULES:
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'weather_mi' has no attribute {name!r}")
