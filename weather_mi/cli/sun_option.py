"""The command line's ``--sun-from-time`` (``render``, tiled or not): the sun where and when the data is."""
from __future__ import annotations


def add_sun_from_time_option(p) -> None:
    """``--sun-from-time``: the sun at the data's centre at its valid time (``scene.place.sun_from_time``)."""
    p.add_argument("--sun-from-time", action="store_true",
                   help="the sun where and when the data is (its centre, its valid time; NREL SPA), instead "
                        "of --sun-azimuth/--sun-elevation")


def with_sun_from_time(spec, data):
    """``spec`` lit by the sun at ``data``'s centre at its valid time (``place.sun_from_time``; ``data``: the
    Hydrometeors, or a tiled render's outline), and the metadata the image keeps of it."""
    import dataclasses
    from ..io.projection import latlon_text
    from ..scene.place import sun_from_time
    azimuth, elevation, meta = sun_from_time(data)
    sun = dataclasses.replace(spec.sun, azimuth=azimuth, elevation=elevation)
    print(f"sun from the time: {meta['valid_time']} at {latlon_text(meta['centre_lat'], meta['centre_lon'], 3)}: "
          f"elevation {elevation:.2f} deg, azimuth {azimuth:.2f} deg in the grid's frame; one sun for the domain, "
          f"up to {meta['one_sun_max_error_deg']:.2f} deg from a column's own")
    return dataclasses.replace(spec, sun=sun), meta
