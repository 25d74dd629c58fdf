"""The command line's shared options: the input (FILE or --demo, the place of an ideal case), the scene
(camera, sun, sky, ground, size), particle sizes, the surface, Dask; and their parsing."""
from __future__ import annotations

from ..errors import WeatherDataError
from ..io.sources import DEMOS, open_source
from ..io.times import parse_time
from . import air_option
from .periodic_option import add_periodic_option


def parse_scale(items: list[str]) -> dict[str, float]:
    out = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            sep = ""
        if not sep:
            raise WeatherDataError("--scale", item, "SPECIES=FACTOR, e.g. ice=2")
    return out


def parse_size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError as exc:
        raise WeatherDataError("--size", text, "WIDTHxHEIGHT, e.g. 512x512") from exc
    if w < 1 or h < 1:
        raise WeatherDataError("--size", text, "WIDTHxHEIGHT of positive integers, e.g. 512x512")
    return w, h


def check_unfinished(ckpt, resume: bool) -> None:
    """A ValueError where a checkpoint of an unfinished render is there and ``--resume`` is not given."""
    if ckpt.is_file() and not resume:
        raise ValueError(f"{ckpt} holds an unfinished render: add --resume to continue it, or delete it to "
                         "render afresh")


def open_placed(args):
    """The input of ``info``/``render``, placed and dated by ``--lat/--lon/--date`` where given (ideal cases)."""
    hyd = open_source(args.file, args.demo, parse_time(args.time), sizes=args.sizes not in ("physical", "paper"))
    if args.lat is None and args.lon is None and args.date is None:
        return hyd
    from ..scene.place import assume_place
    return assume_place(hyd, args.lat, args.lon, args.date)


def add_surface_options(p, default: str) -> None:
    """``--surface`` and ``--wind``: the ground under a domain with its own (``scene.surface``)."""
    from ..scene.surface import SURFACES
    p.add_argument("--surface", default=default, choices=SURFACES,
                   help="the ground of a file with one (HGT, land, albedo): file: each column's land use and albedo "
                        "in the band(s), the sea and lakes with their sun glint (Cox-Munk); albedo: the file's "
                        "broadband albedo, Lambertian; flat: one flat ground (--ground-albedo)"
                        f" (default {default})")
    p.add_argument("--wind", type=float, default=None,
                   help="wind speed 10 m above the sea (m/s) for the glint; default the file's U10/V10, else 5")


def surface_kw(args) -> dict:
    """The ``satellite_scene`` keywords of ``--surface`` and ``--wind``."""
    return {"surface": args.surface, "wind_m_s": args.wind}


def add_place_options(p) -> None:
    """``--lat/--lon/--date``: the place and valid time of an ideal case (one without latitude/longitude)."""
    p.add_argument("--lat", type=float, default=None, help="ideal cases: latitude of the grid's centre (deg N)")
    p.add_argument("--lon", type=float, default=None, help="ideal cases: longitude of the grid's centre (deg E)")
    p.add_argument("--date", default=None, help="ideal cases: the valid time (UTC), e.g. 2024-05-20T21:00")


def add_scene_options(p) -> None:
    """Volume and scene options of ``render`` and ``animate``: species, phase, periodic boundaries, camera,
    sun, sky, ground."""
    p.add_argument("--preset", default="physical", choices=("paper", "physical"), help="species table")
    add_sizes_option(p)
    p.add_argument("--phase", default="per_species", choices=("per_species", "paper"))
    add_periodic_option(p)
    p.add_argument("--scale", action="append", metavar="SPECIES=FACTOR", help="e.g. --scale ice=2")
    p.add_argument("--sun-azimuth", type=float, default=290.0, help="degrees clockwise from north")
    p.add_argument("--sun-elevation", type=float, default=35.0)
    p.add_argument("--sun-diameter", type=float, default=0.53,
                   help="angular diameter of the sun disk (degrees); 0: a point sun")
    p.add_argument("--camera", default="auto", choices=("auto", "ground", "orbit"),
                   help="ground: a photographer's view from near the ground (Camera.ground_view); "
                        "orbit: on a sphere around the cloud (Camera.orbit); auto (default): ground, and for "
                        "a domain wider than 300 km an aerial oblique (orbit at 50 degrees elevation)")
    p.add_argument("--camera-azimuth", type=float, default=200.0,
                   help="where the camera stands, seen from the storm (degrees clockwise from north)")
    p.add_argument("--camera-elevation", type=float, default=8.0, help="orbit camera: elevation (degrees)")
    p.add_argument("--distance", type=float, default=None,
                   help="orbit camera: distance (m); default fits the box")
    p.add_argument("--camera-distance-km", type=float, default=None,
                   help="ground camera: horizontal distance from the storm's core (km); default from its size")
    p.add_argument("--camera-height", type=float, default=1500.0, help="ground camera: height above ground (m)")
    p.add_argument("--fov", type=float, default=None,
                   help="horizontal field of view (degrees; default 70 ground, 45 orbit)")
    air_option.add_options(p)  # --sky, --atmosphere, --aod, --ozone, --water-vapour
    p.add_argument("--ground-albedo", type=float, default=0.15, help="negative: no ground")
    p.add_argument("--size", default="320x240", help="WIDTHxHEIGHT")


SIZES_HELP = ("particle sizes: scheme (default where the file names a microphysics scheme weather-mi knows, or "
              "carries effective radii: each voxel's effective radius from the scheme's size distributions, "
              "weather_mi.io.microphysics; elsewhere the preset's radii), physical or paper (that preset's "
              "fixed radius per species)")


def add_sizes_option(p, classes: bool = True) -> None:
    """``--sizes scheme|physical|paper`` (``optical_volume(sizes=...)``; None: the scheme's where known) and,
    where ``classes``, ``--size-classes N``."""
    p.add_argument("--sizes", default=None, choices=("scheme", "physical", "paper"), help=SIZES_HELP)
    if classes:
        p.add_argument("--size-classes", type=int, default=None, metavar="N",
                       help="with the scheme's sizes: each species as up to N size classes with their own phase "
                            "functions (weather_mi.optics.size_classes; tables built once and cached); default one")


def add_dask_options(p) -> None:
    where = p.add_mutually_exclusive_group()
    where.add_argument("--scheduler", metavar="ADDR", default=None,
                       help="render on a Dask cluster: its scheduler's address, e.g. tcp://host:8786")
    where.add_argument("--workers", type=int, metavar="N", default=None,
                       help="render on a Dask LocalCluster of N worker processes on this machine")


def add_source(parser) -> None:
    """FILE or --demo (exclusive, checked after parsing so that an unknown option is named as such)."""
    parser.add_argument("file", nargs="?", help="wrfout NetCDF or LES text file")
    parser.add_argument("--demo", choices=DEMOS, help="a built-in demo storm")
    parser.add_argument("--time", default=None, help="time index or timestamp (WRF files; default the last)")


def refuse_for_tiles(args, bad, what: str) -> None:
    """ValueError naming every option in ``bad`` ((condition, option text) pairs) that a ``--tile-size`` render
    (``what``: what it renders) cannot take, and an input that is not a wrfout file (tiles read WRF sub-boxes)."""
    found = [why for cond, why in bad if cond]
    if found:
        raise ValueError(f"--tile-size {args.tile_size}: not with {', '.join(found)}; {what}")
    from ..io.sources import kind
    if kind(args.file) != "wrf":
        raise ValueError(f"--tile-size: {args.file} is not a wrfout file (a tiled render reads WRF sub-boxes)")
