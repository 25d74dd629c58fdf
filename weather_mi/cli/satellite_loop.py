"""``weather-mi satellite`` over several times (``--time all|A:B|I,J`` or several wrfout files): the times
opened and checked (the selection, the place, the sun of every time) before anything is rendered, then
``display.satellite_loop`` renders and writes the loop (one band, or ``--rgb``).

An ideal case's ``--date`` is the valid time of the first selected time; the others follow by their model
times (a loop of 00:30-02:00 with --date 2024-05-20T21:00 runs 21:00-22:30 UTC), so the sun moves with the
storm.
"""
from __future__ import annotations

from pathlib import Path


def wants_loop(args) -> bool:
    """Whether ``satellite``'s arguments select several times: several files or a ``--time`` series."""
    from ..io.times import parse_times
    if isinstance(args.file, list):
        return True
    t = args.time
    return t is not None and args.file is not None and (t == "all" or "," in t or isinstance(parse_times(t), slice))


def open_placed_times(args) -> list:
    """Every selected time of the input(s) (``io.sources.open_times``, the one time rule), placed and dated by
    ``--lat/--lon/--date`` where given (the date: of the first time, the others by their model times); the sun
    of each checked (a ValueError where it is below the horizon at one of them)."""
    from ..io.sources import open_times
    from ..io.times import normalise_time, parse_times
    from ..scene.place import assume_place, sun_from_time
    from ..scene.solar import as_utc
    hyds = open_times(args.file, time=parse_times(args.time or "all"), sizes=args.sizes not in ("physical", "paper"))
    if args.lat is not None or args.lon is not None or args.date is not None:
        t0 = normalise_time(hyds[0].attrs["time"])
        dates = [None if args.date is None else
                 as_utc(args.date) + (normalise_time(h.attrs["time"]) - t0).astype("timedelta64[s]").item()
                 for h in hyds]
        hyds = [assume_place(h, args.lat, args.lon, d) for h, d in zip(hyds, dates)]
    for h in hyds:
        sun_from_time(h)
    return hyds


def loop_options(args, resolution: float, reference_kw: dict) -> dict:
    """What a loop's times depend on (``display.satellite_loop.check_loop_options``): the inputs, the place,
    the satellite, the band(s), the optics, the ground and the estimator; not --fps, --denoise, --time (a
    time is one time whatever the selection) or where it renders."""
    from .periodic_option import periodic_value
    from .satellite_air_option import air_options
    files = args.file if isinstance(args.file, list) else [args.file]
    return {"inputs": [str(Path(f).resolve()) for f in files if f is not None], "lat": args.lat, "lon": args.lon,
            "date": args.date, "satellite": args.satellite, "band": "rgb" if args.rgb else (args.band or "0.64"),
            "rayleigh": bool(args.rayleigh), "resolution_km": resolution, "preset": args.preset, "phase": args.phase,
            "ground_albedo": args.ground_albedo, "surface": args.surface, "wind": args.wind, "sizes": args.sizes,
            "size_classes": args.size_classes, "periodic": periodic_value(args), "seed": args.seed,
            **air_options(args), **reference_kw}


def satellite_loop_command(args, resolution: float, nc: Path, reference_kw: dict) -> Path:
    """Open and check every time, then render the loop (``display.satellite_loop``) holding a Dask session."""
    from ..display.satellite_loop import check_unfinished_loop, satellite_loop
    from ..optics.volume import default_sizes, optical_volume
    from ..reference.cluster import session
    from ..satellite import imagery as si
    from ..satellite.bands import DEFAULT_GROUND_ALBEDO
    from .periodic_option import periodic_value
    from ..satellite import truecolor as tc
    from .options import surface_kw
    from .satellite_air_option import satellite_atmosphere
    check_unfinished_loop(nc, args.resume)
    atm = satellite_atmosphere(args)
    surface = surface_kw(args)
    hyds = open_placed_times(args)
    albedo = DEFAULT_GROUND_ALBEDO if args.ground_albedo is None else args.ground_albedo
    what = "true colour" if args.rgb else f"band {args.band or '0.64'} um"
    print(f"{args.satellite}, {what}, {resolution:g} km: a loop of {len(hyds)} times "
          f"({hyds[0].attrs.get('valid_time')} to {hyds[-1].attrs.get('valid_time')})")

    with session(args.scheduler, args.workers) as client:
        def render_time(hyd, ckpt, resume):
            vol = optical_volume(hyd, species=args.preset, phase=args.phase, sizes=args.sizes or default_sizes(hyd),
                                 size_classes=args.size_classes,
                                 periodic=periodic_value(args))
            hyd = hyd.drop_vars([v for v in hyd.data_vars if v != "rho_air"])
            kw = dict(reference_kw, checkpoint=ckpt, resume=ckpt if resume else None, client=client)
            if args.rgb:
                scenes = tc.true_color_scenes(hyd, vol, args.satellite, resolution, rayleigh=args.rayleigh,
                                              ground_albedo=args.ground_albedo, seed=args.seed,
                                              atmosphere=atm, **surface)
                return tc.render_true_color(scenes, **kw)
            scene = si.satellite_scene(hyd, vol, args.satellite, args.band or "0.64", resolution,
                                       rayleigh=args.rayleigh, ground_albedo=albedo, seed=args.seed,
                                       atmosphere=atm, **surface)
            return si.render_satellite(scene, **kw)
        loop = satellite_loop(hyds, render_time, nc, resume=args.resume, fps=args.fps, denoise=args.denoise,
                              options=loop_options(args, resolution, reference_kw))
    print(f"wrote {loop.netcdf} ({len(hyds)} times; {loop.rendered} rendered now), {loop.mp4}, {loop.contact_sheet} "
          f"and {len(loop.pngs)} PNGs ({loop.pngs[0].name} ...)")
    return nc
