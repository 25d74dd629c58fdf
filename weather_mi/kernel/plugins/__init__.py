"""Mitsuba 3 plugins of weather-mi, shipped as ``weather_mi.kernel.plugins``.

Each module registers one plugin with Mitsuba (``mi.register_phase`` ...) when imported.
"""
