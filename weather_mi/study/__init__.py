"""The validation study, in three parts: ``runs`` (scenes, views, renders and comparisons),
``weather_mi.slicing.calibrate`` (fitting the slicer by reverse-mode AD) and ``report`` (tables,
figures, findings)."""
from __future__ import annotations

from .report import side_by_side
from .runs import CONFIGS, DATA_SCENES, DATA_TIMES, DEMO_SCENES, METRIC_KEYS, StudyConfig, eye_transmittance, load_scene, load_scenes, run, view

__all__ = ["CONFIGS", "DATA_SCENES", "DATA_TIMES", "DEMO_SCENES", "METRIC_KEYS", "StudyConfig", "eye_transmittance", "load_scene", "load_scenes",
           "run", "side_by_side", "view"]
