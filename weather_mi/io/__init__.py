"""Readers that turn model output into the Hydrometeors contract (see weather_mi.hydrometeors)."""
from .wrf import open_wrf

__all__ = ["open_wrf"]
