"""Readers that turn model output into the Hydrometeors contract (see weather_mi.io.hydrometeors)."""
from .les import open_les
from .series import time_steps
from .wrf import open_wrf

__all__ = ["open_les", "open_wrf", "time_steps"]
