"""``satellite``'s ``--atmosphere none|clear``, ``--aod``, ``--ozone``, ``--water-vapour`` (the clear 1-D atmosphere in, above and
around the model's box, on the sun's path: ``satellite.air``) and ``--view reflectance|natural`` (what an
astronaut's eye would see: ``satellite.natural``)."""
from __future__ import annotations

from .air_option import add_aod_ozone

# clear costs about 1.1x (one band) and 1.2x (--rgb) the time to the same noise; the target is 1.3x (docs/satellite_air.md)
DEFAULT_ATMOSPHERE = "clear"


def add_satellite_air_options(p) -> None:
    p.add_argument("--atmosphere", default=None, choices=("none", "clear"),
                   help="clear (default): a clear 1-D atmosphere (molecules, ozone, aerosol) in the band(s), inside the "
                        "model's box from its own air density, above its top and around it, and on the sun's path "
                        "through a spherical shell (about 1.1-1.2x the time to the same noise without it); none (the "
                        "default with --rayleigh or --tile-size): vacuum between the hydrometeors, the sun as it is "
                        "above the air")
    add_aod_ozone(p)
    p.add_argument("--view", default="reflectance", choices=("reflectance", "natural"),
                   help="reflectance (default): the imager's band(s) as reflectance factors; natural: what an "
                        "astronaut's eye would see, the reflectance at 9 wavelengths from 400 to 700 nm (three "
                        "renders) under the ASTM G173 sun, as CIE X, Y, Z and linear sRGB (D65) (NetCDF, EXR) and a "
                        "PNG white-balanced for daylight")


def atmosphere_kind(args) -> str:
    """``--atmosphere`` as given, else the default: ``DEFAULT_ATMOSPHERE``, but "none" with ``--rayleigh`` (the
    old option: the molecules in the box only) or ``--tile-size`` (tiles render without it)."""
    if args.atmosphere is not None:
        return args.atmosphere
    if args.rayleigh or getattr(args, "tile_size", None) is not None:
        return "none"
    return DEFAULT_ATMOSPHERE


def satellite_atmosphere(args):
    """The ``optics.air.Atmosphere`` of the options (None for none), checked before the input is read: a
    ValueError naming the options that exclude each other."""
    from ..scene.framing import atmosphere_of
    kind = atmosphere_kind(args)
    if args.rayleigh and kind == "clear":
        raise ValueError("--rayleigh (the molecules in the model's box only, the old option) and --atmosphere clear "
                         "(molecules, ozone and aerosol in, above and around the box, on the sun's path) exclude "
                         "each other: drop --rayleigh")
    if kind == "clear" and getattr(args, "tile_size", None) is not None:
        raise ValueError("--tile-size: a tiled render has no clear atmosphere yet: give --atmosphere none, or render "
                         "without tiles")
    return atmosphere_of(kind, args.aod, args.ozone, args.water_vapour)


def check_natural_view(args, loop: bool) -> None:
    """``--view natural`` renders its own wavelengths, one time (``loop``: several), in one process: a ValueError
    naming --band, --rgb, --rayleigh, --tile-size or a loop."""
    if args.view != "natural":
        return
    found = [why for cond, why in ((args.band is not None, f"--band {args.band}"), (args.rgb, "--rgb"),
                                   (args.rayleigh, "--rayleigh"),
                                   (getattr(args, "tile_size", None) is not None, "--tile-size"),
                                   (loop, "several files or times"))
             if cond]
    if found:
        raise ValueError(f"--view natural: not with {', '.join(found)}; it renders its own wavelengths (400-700 nm) "
                         "of one time in one process")


def air_options(args) -> dict:
    """What a loop records of its atmosphere (``satellite_loop.loop_options``): the clear one with its aerosol and
    ozone, and its water vapour where given; nothing for none (so that a loop recorded before the option resumes)."""
    if atmosphere_kind(args) == "none":
        return {}
    water = {} if args.water_vapour is None else {"water_vapour": args.water_vapour}
    return {"atmosphere": "clear", "aod": args.aod, "ozone": args.ozone, **water}


__all__ = ["DEFAULT_ATMOSPHERE", "add_satellite_air_options", "atmosphere_kind", "satellite_atmosphere",
           "check_natural_view", "air_options"]
