"""The air around (and later inside) the model's box, as functions of wavelength (nm) and height: a clear
1-D atmosphere (``atmosphere``: molecules, ozone, aerosol), ozone's Chappuis band (``ozone``), paths
through a spherical shell (``shell``) and the sun's transmittance and colour along them (``sunlight``)."""
from .atmosphere import Atmosphere
from .sunlight import SunAirTable, sun_air_table, sun_rgb, sun_xyz, transmittance

__all__ = ["Atmosphere", "SunAirTable", "sun_air_table", "sun_rgb", "sun_xyz", "transmittance"]
