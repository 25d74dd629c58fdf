"""Command line.

    weather-mi info FILE | --demo supercell|cumulus|stratocumulus [--lat LAT --lon LON --date UTC]
    weather-mi render FILE | --demo supercell|cumulus|stratocumulus [options] [--scheduler ADDR | --workers N] -o out.exr
    weather-mi satellite FILE... | --demo NAME [--time all|A:B|I,J] [--satellite goes-east|goes-west|himawari|meteosat] [--band 0.64 | --rgb]
               [--resolution 1km] [--rayleigh] [--lat LAT --lon LON --date UTC] [--surface file|albedo|flat]
               [--wind M/S] [--tile-size PX [--halo KM] [--scheduler ADDR | --workers N]] -o out/sat.nc
    weather-mi animate WRFOUT... [--renderer slices|reference] [options] [--scheduler ADDR | --workers N] -o DIR
    weather-mi validate -o DIR [--quick]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import OutputWriteError, WeatherDataError
from ..io.times import parse_time, parse_times
from ..reference.options import ReferenceOptions, add_flags, flag_values
from ..io.sources import DEMOS, check_time, open_source
from . import air_option
from .periodic_option import add_periodic_option, periodic_value
from .satellite_tiles import add_tile_options, check_tile_options, satellite_tiles_command
from .spectral_option import add_spectral_options, check_spectral_options, save_png, variant_of
from .summary import info_text
from ..optics.volume import default_sizes

SATELLITE_ESTIMATOR = ("spp", "target_rse", "max_seconds")  # the rest: render_satellite's (reflectance)
ANIMATE_ESTIMATOR = ("spp", "target_rse", "max_seconds")  # per frame, with --renderer reference


def _parse_scale(items: list[str]) -> dict[str, float]:
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


def _parse_size(text: str) -> tuple[int, int]:
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


def check_scene_options(args) -> None:
    """The scene options that can be judged without the input (``--size``, ``--fov``, the atmosphere's),
    checked before it is read; ``scene_spec`` builds from them."""
    from ..scene.framing import atmosphere_of
    from ..scene.spec import check_fov_deg
    _parse_size(args.size)
    if args.fov is not None:
        check_fov_deg(args.fov)
    air = atmosphere_of(args.atmosphere, args.aod, args.ozone)
    if air is not None and getattr(args, "integrator", None) == "volpath":
        raise ValueError("--atmosphere clear colours the sun of --integrator majorant (the default), not volpath's")
    check_spectral_options(args)


def render_command(args) -> Path:
    """Check the arguments and the outputs, build the volume and the scene, render the reference while
    holding the outputs' lock, write EXR + PNG."""
    from ..io.output_paths import OutputLock, check_writable_folder, render_outputs
    check_scene_options(args)
    check_time(args.file, args.demo, args.time)
    if args.denoise:
        from ..display.denoise import check_available
        check_available()
    exr, png, ckpt = render_outputs(args.output)
    check_writable_folder(exr)
    with OutputLock(exr):
        check_unfinished(ckpt, args.resume)
        return _render(args, exr, png, ckpt)


def _render(args, out, png_path, ckpt) -> Path:
    from ..optics.volume import optical_volume
    from ..reference.render import render_reference
    hyd = open_placed(args)
    vol = optical_volume(hyd, species=args.preset, scale=_parse_scale(args.scale), phase=args.phase,
                         sizes=args.sizes or default_sizes(hyd), size_classes=args.size_classes,
                         periodic=periodic_value(args), release=True, keep=("weights",))  # the path tracer's
    from ..scene.surface import RGB_UM, with_surface
    vol = with_surface(vol, RGB_UM, args.surface, args.wind)  # the ground's surface in red, green and blue
    spec, sun_meta = scene_spec(args, vol), None
    vol = air_option.in_box(vol, hyd, spec)  # the air inside the box (--atmosphere clear)
    hyd = hyd.drop_vars(list(hyd.data_vars))  # its fields are in vol now; the place and time stay
    if args.sun_from_time:
        spec, sun_meta = _sun_from_time(spec, hyd)
    from ..reference.cluster import session
    with session(args.scheduler, args.workers) as client:
        img = render_reference(spec, vol, options=ReferenceOptions(**flag_values(args)), checkpoint=ckpt,
                               resume=ckpt if args.resume else None, client=client, variant=variant_of(args),
                               release_volume=True)  # the kernel's grids replace vol's (read no more: bbox, air)
    if sun_meta:
        img.metadata["sun_from_time"] = sun_meta
    img = air_option.on_eye_rays(img, spec, vol, args)  # and along the eye rays outside the box
    if args.denoise:
        from ..display.denoise import denoise_image
        denoise_image(img, spec, vol)
    img.save(out)
    png = save_png(img, png_path, args, spec, vol)
    ckpt.unlink(missing_ok=True)
    noise = img.metadata.get("noise") or {}
    cloud = (f", over cloud pixels: mean relative standard error {noise['rse_mean']:.3f}, RMS standard error / "
             f"mean {noise['rms_se_over_mean']:.3f}, worst {noise['worst_se_over_mean']:.2f}") if noise.get("cloud_pixels") \
        else f", mean relative standard error {img.relative_stderr():.3f}"
    spp, background = img.metadata["spp"], img.metadata.get("spp_background", img.metadata["spp"])
    spp_text = f"{spp} spp" if background == spp else f"{spp} spp on cloud pixels, {background} elsewhere"
    shows = (f"the PNG shows the {img.metadata['display']} image; the EXR's R, G, B stay the unbiased radiance, "
             "denoised.R/G/B the display layer") if args.denoise else "the PNG shows the raw (unbiased) radiance"
    print(f"wrote {out} and {png} ({spp_text}, {img.metadata['seconds']:.1f} s{cloud}); {shows}")
    return out


def scene_spec(args, vol):
    """The SceneSpec of the scene options (camera, sun, sky, ground, size, seed) for ``vol``."""
    from ..scene.framing import SCENE_OPTIONS, scene_spec
    return scene_spec(vol, _parse_size(args.size), **{k: getattr(args, k) for k in SCENE_OPTIONS})


def _sun_from_time(spec, hyd):
    """``spec`` lit by the sun at ``hyd``'s centre at its valid time (``place.sun_from_time``), and the
    metadata the image keeps of it."""
    import dataclasses
    from ..io.projection import latlon_text
    from ..scene.place import sun_from_time
    azimuth, elevation, meta = sun_from_time(hyd)
    sun = dataclasses.replace(spec.sun, azimuth=azimuth, elevation=elevation)
    print(f"sun from the time: {meta['valid_time']} at {latlon_text(meta['centre_lat'], meta['centre_lon'], 3)}: "
          f"elevation {elevation:.2f} deg, azimuth {azimuth:.2f} deg in the grid's frame; one sun for the domain, "
          f"up to {meta['one_sun_max_error_deg']:.2f} deg from a column's own")
    return dataclasses.replace(spec, sun=sun), meta


def satellite_command(args) -> Path:
    """A synthetic geostationary image (``satellite.imagery``): checked (outputs, an unfinished render, place,
    visibility) before rendering, written as NetCDF + EXR + PNG."""
    from ..io.output_paths import OutputLock, check_writable_folder
    from ..satellite import imagery as si
    resolution = si.parse_resolution_km(args.resolution)
    nc, exr, png, ckpt = si.satellite_outputs(args.output)
    check_satellite_bands(args)
    check_tile_options(args)
    if args.denoise:
        from ..display.denoise import check_available
        check_available()
    from .satellite_loop import satellite_loop_command, wants_loop
    if wants_loop(args):  # several times: one NetCDF with a time dimension, a PNG per time, an MP4
        check_writable_folder(nc)
        with OutputLock(nc):
            return satellite_loop_command(args, resolution, nc, flag_values(args, SATELLITE_ESTIMATOR))
    check_time(args.file, args.demo, args.time)
    check_writable_folder(nc)
    with OutputLock(nc):
        from ..satellite.truecolor import band_checkpoints
        for c in band_checkpoints(ckpt):  # --rgb --rayleigh: a checkpoint per band
            check_unfinished(c, args.resume)
        if args.tile_size is not None:  # tiles as Dask tasks, no process reading the whole domain
            return satellite_tiles_command(args, resolution, nc, exr, png, flag_values(args, SATELLITE_ESTIMATOR))
        return _satellite(args, resolution, nc, exr, png, ckpt)


def check_satellite_bands(args) -> None:
    """The band options against the satellite, before the input is read: ``--rgb`` or one ``--band`` (not
    both), a band the satellite's imager has."""
    from ..satellite.bands import band, check_band_on, true_color_bands
    from ..satellite.geostationary import satellite
    sat = satellite(args.satellite)
    if args.rgb and args.band is not None:
        raise ValueError(f"--rgb renders the true-colour bands ({', '.join(b.name for b in true_color_bands(sat))} "
                         f"um on {sat.name}) in one run: drop --band {args.band}, or drop --rgb for one band")
    if args.rgb:
        true_color_bands(sat)
    else:
        check_band_on(band(args.band or "0.64"), sat)


def _satellite(args, resolution, nc, exr, png, ckpt) -> Path:
    from ..satellite import imagery as si
    from ..reference.cluster import session
    from ..optics.volume import optical_volume
    hyd = open_placed(args)
    vol = optical_volume(hyd, species=args.preset, phase=args.phase, sizes=args.sizes or default_sizes(hyd),
                         size_classes=args.size_classes,
                         periodic=periodic_value(args), release=True,
                         keep=("beta_ext", "weights") if args.rgb or args.rayleigh else ("weights",))  # the air: beta_s
    air = args.rgb or args.rayleigh  # the air's density stays for Rayleigh (true colour: its own scenes)
    hyd = hyd.drop_vars([v for v in hyd.data_vars if v != "rho_air" or not air])  # in vol now
    if args.rgb:
        return _satellite_rgb(args, hyd, vol, resolution, nc, exr, png, ckpt)
    scene = si.satellite_scene(hyd, vol, args.satellite, args.band or "0.64", resolution, rayleigh=args.rayleigh,
                               ground_albedo=0.06 if args.ground_albedo is None else args.ground_albedo,
                               seed=args.seed, **surface_kw(args))
    del vol  # the scene holds the band's volume (its own albedo): the RGB albedo goes
    w, h = scene.view.size
    print(f"{scene.satellite.name} (sub-satellite longitude {scene.satellite.sub_lon_deg}), band {scene.band.name} um: "
          f"{w} x {h} pixels of {resolution:g} km, view zenith {scene.view.view_zenith_deg.min():.1f}-"
          f"{scene.view.view_zenith_deg.max():.1f} deg, solar zenith {90 - scene.spec.sun.elevation:.2f} deg at the "
          f"centre ({scene.sun_meta['valid_time']}; one sun, up to {scene.sun_meta['one_sun_max_error_deg']:.2f} deg "
          "from a column's own)")
    with session(args.scheduler, args.workers) as client:
        ds, img = si.render_satellite(scene, **flag_values(args, SATELLITE_ESTIMATOR), checkpoint=ckpt,
                                      resume=ckpt if args.resume else None, client=client,
                                      release_volume=True)  # the kernel's grids replace the band volume's
    from ..display.satellite_picture import shown_dataset, write_picture
    shown = shown_dataset(ds, img, args.denoise)
    si.write_satellite(ds, img, nc, exr)
    write_picture(shown, png, denoise=False)
    ckpt.unlink(missing_ok=True)
    print(f"wrote {nc}, {exr} and {png} ({img.metadata['spp']} spp, {img.metadata['seconds']:.1f} s; cloud pixels "
          f"{int(ds.cloud.sum())}, mean relative standard error {ds.attrs['cloud_rse_mean']:.3f}; reflectance "
          f"{float(ds.reflectance.where(ds.in_domain == 1).mean()):.3f} mean over the domain)")
    return nc


def _satellite_rgb(args, hyd, vol, resolution, nc, exr, png, ckpt) -> Path:
    """``satellite --rgb``: the true-colour bands in one render (per band with --rayleigh), the NetCDF with a
    band dimension, the EXR (the bands in R, G, B) and the PNG of the operational recipe
    (``satellite.truecolor``)."""
    from ..satellite import truecolor as tc
    from ..reference.cluster import session
    scenes = tc.true_color_scenes(hyd, vol, args.satellite, resolution, rayleigh=args.rayleigh,
                                  ground_albedo=args.ground_albedo, seed=args.seed, **surface_kw(args))
    s = scenes[0]
    w, h = s.view.size
    names = ", ".join(sc.band.name for sc in scenes) if len(scenes) > 1 else ", ".join(b.name for b in s.bands)
    how = "one render per band (the air's extinction differs)" if len(scenes) > 1 else "one render, one band per channel"
    print(f"{s.satellite.name} (sub-satellite longitude {s.satellite.sub_lon_deg}), true colour from {names} um, "
          f"{how}: {w} x {h} pixels of {resolution:g} km, solar zenith {90 - s.spec.sun.elevation:.2f} deg at the "
          f"centre ({s.sun_meta['valid_time']})")
    with session(args.scheduler, args.workers) as client:
        ds, img = tc.render_true_color(scenes, **flag_values(args, SATELLITE_ESTIMATOR), checkpoint=ckpt,
                                       resume=ckpt if args.resume else None, client=client,
                                      release_volume=True)  # the kernel's grids replace the band volume's
    from ..display.satellite_picture import shown_dataset, write_picture
    from ..satellite.imagery import write_satellite
    shown = shown_dataset(ds, img, args.denoise)
    write_satellite(ds, img, nc, exr)
    write_picture(shown, png, denoise=False)
    for c in tc.band_checkpoints(ckpt):
        c.unlink(missing_ok=True)
    means = ", ".join(f"{b} {float(ds.reflectance.sel(band=b).where(ds.in_domain == 1).mean()):.3f}"
                      for b in ds.band.values)
    print(f"wrote {nc}, {exr} and {png} ({img.metadata['spp']} spp, {img.metadata['seconds']:.1f} s; cloud pixels "
          f"{int(ds.cloud.sum())}; reflectance over the domain {means}; the PNG: sun-zenith"
          f"{', Rayleigh' if args.rayleigh else ''} corrected, CIRA-stretched true colour)")
    return nc


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
    air_option.add_options(p)  # --sky, --atmosphere, --aod, --ozone
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


def animate_command(args) -> Path:
    """Every time of the inputs rendered from one camera: EXR frames, an MP4 and a contact sheet."""
    from ..display.animate import animate
    from ..reference.cluster import session
    from ..scene.framing import largest
    from ..optics.volume import optical_volume
    from ..io.sources import open_times
    check_scene_options(args)
    scale = _parse_scale(args.scale)
    hyds = open_times(args.inputs, time=parse_times(args.time), sizes=args.sizes not in ("physical", "paper"))
    vols = [optical_volume(h, species=args.preset, scale=scale, phase=args.phase, sizes=args.sizes or default_sizes(h),
                           size_classes=args.size_classes,
                           periodic=periodic_value(args)) for h in hyds]
    spec = scene_spec(args, largest(vols))  # frame the largest storm
    reference_kw = flag_values(args, ANIMATE_ESTIMATOR)
    with session(args.scheduler, args.workers) as client:
        anim = animate(vols, spec, args.output, renderer=args.renderer, labels=[h.attrs["time"] for h in hyds],
                       orbit_deg=args.orbit, client=client, fps=args.fps, exposure=args.exposure,
                       slices=args.slices, mode=args.mode, reference_kw=reference_kw)
    print(f"wrote {len(anim.frames)} frames in {Path(args.output) / 'frames'}, {anim.mp4} and {anim.contact_sheet}")
    return anim.mp4


def build_parser() -> argparse.ArgumentParser:
    """The parser of every command (``info``, ``render``, ``animate``, ``view``, ``validate``)."""
    parser = argparse.ArgumentParser(prog="weather-mi", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    info = sub.add_parser("info", help="summarise a data file or a demo storm")
    _add_source(info)
    info.add_argument("--species", default="paper", choices=("paper", "physical"))
    add_sizes_option(info, classes=False)
    add_place_options(info)
    _add_render_parser(sub)
    _add_satellite_parser(sub)
    _add_animate_parser(sub)
    _add_view_parser(sub)
    _add_validate_parser(sub)
    parser.commands = sub.choices  # command -> its parser (for an error in the command's own usage)
    return parser


def _add_render_parser(sub) -> None:
    render = sub.add_parser("render", help="path-trace the ground-truth image (EXR + PNG)")
    _add_source(render)
    add_scene_options(render)
    # the estimator's flags (--spp, --integrator, --target-rse, --max-seconds, --sun-guiding, --forward-peak,
    # --aureole-nee): declared with its options (weather_mi.reference.options)
    add_flags(render.add_argument_group("reference estimator"))
    add_place_options(render)
    render.add_argument("--sun-from-time", action="store_true",
                        help="the sun where and when the data is (its centre, its valid time; NREL SPA), instead "
                             "of --sun-azimuth/--sun-elevation")
    add_surface_options(render, "albedo")
    render.add_argument("--seed", type=int, default=0)
    render.add_argument("--exposure", type=float, default=None, help="PNG exposure (default: automatic)")
    add_spectral_options(render)
    render.add_argument("--denoise", action=argparse.BooleanOptionalAction, default=True,
                        help="the PNG shows the OIDN-denoised image (an extra EXR layer, denoised.R/G/B; the "
                             "EXR's radiance and standard error stay unbiased); --no-denoise: the raw radiance")
    render.add_argument("--resume", action="store_true", help="continue from OUTPUT.ckpt.npz")
    add_dask_options(render)
    render.add_argument("-o", "--output", default="weather-mi.exr",
                        help="OUT.exr (or OUT.png): writes OUT.exr and OUT.png; OUT.exr.ckpt.npz while rendering")


def _add_satellite_parser(sub) -> None:
    from ..satellite.bands import BANDS
    from ..satellite.geostationary import SATELLITES
    sat = sub.add_parser("satellite", help="synthetic geostationary imagery: reflectance on the satellite's fixed "
                                           "grid, 3-D path-traced (NetCDF + EXR + PNG)")
    sat.add_argument("file", nargs="*", help="wrfout NetCDF or LES text file; several wrfout files: a loop of "
                                             "their times in order")
    sat.add_argument("--demo", choices=DEMOS, help="a built-in demo storm")
    sat.add_argument("--time", default=None, help="time index or timestamp (WRF files; default the last); "
                     '"all", START:STOP[:STEP] or a comma list: a loop (a time dimension, a PNG per time, an MP4)')
    sat.add_argument("--fps", type=float, default=4.0, help="a loop's MP4: frames per second")
    add_place_options(sat)
    sat.add_argument("--satellite", default="goes-east", choices=tuple(SATELLITES))
    sat.add_argument("--band", default=None, choices=tuple(BANDS), help="central wavelength (um), rendered "
                                                                      "monochromatically (default 0.64)")
    sat.add_argument("--rgb", action="store_true",
                     help="true colour: the 0.47, 0.64, 0.86 um bands (himawari: 0.47, 0.51, 0.64) in one render, "
                          "a NetCDF with a band dimension and the operational products' RGB as the PNG")
    sat.add_argument("--resolution", default="1km", help="pixel size at the sub-satellite point (e.g. 1km, 500m)")
    sat.add_argument("--rayleigh", action="store_true", help="molecular scattering of the air in the domain")
    sat.add_argument("--preset", default="physical", choices=("paper", "physical"), help="species table")
    add_sizes_option(sat)
    sat.add_argument("--phase", default="per_species", choices=("per_species", "paper"))
    add_periodic_option(sat)
    sat.add_argument("--ground-albedo", type=float, default=None,
                     help="surface albedo where the file has none (default 0.06, the sea; with --rgb the sea "
                          "per band, 0.06 at 0.47 um to 0.02 at 0.86 um)")
    add_surface_options(sat, "file")
    add_flags(sat, SATELLITE_ESTIMATOR)
    sat.add_argument("--seed", type=int, default=0)
    sat.add_argument("--denoise", action=argparse.BooleanOptionalAction, default=True,
                     help="the PNG shows the OIDN-denoised reflectance (the EXR's denoised.R/G/B; the NetCDF and the "
                          "EXR's R, G, B stay the unbiased reflectance); --no-denoise: the raw reflectance")
    sat.add_argument("--resume", action="store_true", help="continue from OUTPUT.exr.ckpt.npz (--rgb --rayleigh: "
                                                           "OUTPUT.exr.<band>.ckpt.npz)")
    add_dask_options(sat)
    add_tile_options(sat)
    sat.add_argument("-o", "--output", default="weather-mi-satellite.nc", help="output NetCDF (.nc)")


def _add_animate_parser(sub) -> None:
    anim = sub.add_parser("animate", help="render every time of a storm: EXR frames, an MP4 and a contact sheet")
    anim.add_argument("inputs", nargs="+", help="wrfout NetCDF file(s); their times in order")
    anim.add_argument("--time", default="all", help='"all", START:STOP[:STEP] or a comma list of indices or timestamps')
    anim.add_argument("--renderer", default="slices", choices=("slices", "reference"))
    add_scene_options(anim)
    add_flags(anim.add_argument_group("reference estimator (--renderer reference), per frame"), ANIMATE_ESTIMATOR,
              defaults={"spp": 16})
    anim.add_argument("--slices", type=int, default=128, help="slicer: number of slices")
    anim.add_argument("--mode", default="per-species/multiple", choices=list(_slicer_modes()),
                      help="slicer: the light/phase mode (Table IV modes or the multiple-scattering model)")
    anim.add_argument("--orbit", type=float, default=0.0, metavar="DEG",
                      help="the camera turns this many degrees about the storm from the first frame to the last")
    anim.add_argument("--fps", type=float, default=4.0, help="frames per second of the MP4")
    anim.add_argument("--seed", type=int, default=0)
    anim.add_argument("--exposure", type=float, default=None, help="MP4/contact-sheet exposure (default: automatic, one for all frames)")
    add_dask_options(anim)
    anim.add_argument("-o", "--output", default="weather-mi-animation", help="output folder")


def _add_view_parser(sub) -> None:
    viewp = sub.add_parser("view", help="explore a storm in the browser: the slicer live, the ground truth one "
                           "click away")
    _add_source(viewp)
    viewp.add_argument("--preset", default="physical", choices=("paper", "physical"), help="species table")
    add_sizes_option(viewp, classes=False)
    viewp.add_argument("--phase", default="per_species", choices=("per_species", "paper"))
    add_periodic_option(viewp)
    viewp.add_argument("--port", type=int, default=5006, help="port (0: a free one)")
    viewp.add_argument("--host", default="127.0.0.1",
                       help="address to bind (default 127.0.0.1, this machine only; another address is reachable "
                       "from the network, without authentication)")
    viewp.add_argument("--no-browser", action="store_true", help="do not open a browser")
    viewp.add_argument("--size", default="320x240", help="WIDTHxHEIGHT of the rendered view (shown at twice that)")


def _add_validate_parser(sub) -> None:
    val = sub.add_parser("validate", help="the validation study: slicer against path-traced ground truth")
    val.add_argument("-o", "--output", default="validation-report", help="report folder")
    val.add_argument("--quick", action="store_true", help="small images and samples: a few minutes")
    val.add_argument("--config", choices=("full", "quick", "tiny"), default=None)
    val.add_argument("--data", default=None, help="folder of real model output (wrf/..., les/..., e.g. "
                     "../shared/data); without it only the built-in demo storms are studied")


def info_command(args) -> None:
    hyd = open_placed(args)
    print(info_text(hyd, args.species, args.sizes or default_sizes(hyd)))


def view_command(args) -> None:
    from ..viewer.recipe import VolumeRecipe
    from ..viewer.serve import serve
    check_time(args.file, args.demo, args.time)
    recipe = VolumeRecipe(path=args.file, demo=args.demo, preset=args.preset, phase=args.phase, sizes=args.sizes,
                          periodic=periodic_value(args))
    serve(recipe, host=args.host, port=args.port, open_browser=not args.no_browser, time_option=args.time,
          size=_parse_size(args.size))


def validate_command(args) -> None:
    from ..study import run
    report = run(args.output, args.config or ("quick" if args.quick else "full"), data_dir=args.data)
    print(f"wrote {report}")


COMMANDS = {"info": info_command, "render": render_command, "satellite": satellite_command,
            "animate": animate_command, "view": view_command, "validate": validate_command}


def release_freed_memory(threshold: int = 1 << 20) -> None:
    """Large blocks freed go back to the system at once (glibc: a fixed mmap threshold). By default glibc
    raises its threshold to the largest block freed (up to 32 MiB), after which the regridding's and the
    optics' blocks come from the heap and their memory stays with the process; the peak of ``info`` and
    ``render`` grew by about 0.5 GB on a 400 x 400 x 51 grid. Nothing where the C library is not glibc."""
    import ctypes
    import ctypes.util
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        libc.mallopt(-3, int(threshold))  # M_MMAP_THRESHOLD
    except (OSError, AttributeError):
        pass


def main(argv: list[str] | None = None) -> int:
    release_freed_memory()
    parser = build_parser()
    args = parser.parse_args(argv)
    if isinstance(getattr(args, "file", None), list):  # satellite: none, one or several files
        args.file = args.file[0] if len(args.file) == 1 else (args.file or None)
    if args.command in ("info", "render", "satellite", "view") and (args.file is None) == (args.demo is None):
        parser.commands[args.command].error("give a data FILE or --demo NAME (one of them)")
    try:
        COMMANDS[args.command](args)
    except OutputWriteError as exc:  # a full disk: the file named, the checkpoint kept, how to resume
        print(f"weather-mi: error: {exc}{_resume_hint(args)}", file=sys.stderr)
        return 2
    except (WeatherDataError, ValueError, ConnectionError, RuntimeError) as exc:
        print(f"weather-mi: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"weather-mi: interrupted{_resume_hint(args)}", file=sys.stderr)
        return 130
    return 0


def _slicer_modes():
    from ..slicing.modes import MODES
    return MODES


def _add_source(parser) -> None:
    """FILE or --demo (exclusive, checked after parsing so that an unknown option is named as such)."""
    parser.add_argument("file", nargs="?", help="wrfout NetCDF or LES text file")
    parser.add_argument("--demo", choices=DEMOS, help="a built-in demo storm")
    parser.add_argument("--time", default=None, help="time index or timestamp (WRF files; default the last)")


def _resume_hint(args) -> str:
    if args.command not in ("render", "satellite"):
        return ""
    from ..io.output_paths import render_outputs
    from ..satellite.imagery import satellite_outputs
    try:
        ckpt = (render_outputs(args.output) if args.command == "render" else satellite_outputs(args.output))[-1]
    except ValueError:
        return ""
    from ..display.satellite_loop import parts_folder
    if args.command == "satellite" and parts_folder(args.output).is_dir():
        return "; the finished times are kept: run the same command with --resume to continue"
    if not ckpt.is_file():
        return " before the first pass was finished (no checkpoint to resume from)"
    return f"; the finished passes are in {ckpt}: run the same command with --resume to continue"


if __name__ == "__main__":
    sys.exit(main())
