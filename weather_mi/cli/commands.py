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
from ..io.times import parse_times
from ..reference.options import ReferenceOptions, add_flags, flag_values
from ..io.sources import check_time
from . import air_option
from .options import add_dask_options, add_place_options, add_scene_options, add_sizes_option, add_source, \
    add_surface_options, check_unfinished, open_placed, parse_scale, parse_size
from .periodic_option import add_periodic_option, periodic_value
from .render_tiles import check_render_tile_options, render_tiles_command
from .satellite_command import add_satellite_parser, satellite_command
from .satellite_tiles import add_tile_options
from .spectral_option import add_spectral_options, check_spectral_options, save_png, variant_of
from .summary import info_text
from .sun_option import add_sun_from_time_option, with_sun_from_time
from ..optics.volume import default_sizes

ANIMATE_ESTIMATOR = ("spp", "target_rse", "max_seconds")  # per frame, with --renderer reference


def check_scene_options(args) -> None:
    """The scene options that can be judged without the input (``--size``, ``--fov``, the atmosphere's),
    checked before it is read; ``scene_spec`` builds from them."""
    from ..scene.framing import atmosphere_of
    from ..scene.spec import check_fov_deg
    air_option.resolve(args)  # --atmosphere, --sky: the command's defaults
    parse_size(args.size)
    if args.fov is not None:
        check_fov_deg(args.fov)
    air = atmosphere_of(args.atmosphere, args.aod, args.ozone, args.water_vapour)
    if air is not None and getattr(args, "integrator", None) == "volpath":
        raise ValueError("--atmosphere clear colours the sun of --integrator majorant (the default), not volpath's")
    check_spectral_options(args)


def render_command(args) -> Path:
    """Check the arguments and the outputs, build the volume and the scene, render the reference while
    holding the outputs' lock, write EXR + PNG."""
    from ..io.output_paths import OutputLock, check_writable_folder, render_outputs
    check_scene_options(args)
    check_render_tile_options(args)
    check_time(args.file, args.demo, args.time)
    if args.denoise and args.tile_size is None:
        from ..display.denoise import check_available
        check_available()
    exr, png, ckpt = render_outputs(args.output)
    check_writable_folder(exr)
    with OutputLock(exr):
        check_unfinished(ckpt, args.resume)
        if args.tile_size is not None:  # tiles as Dask tasks, no process reading the whole domain
            return render_tiles_command(args, exr, png)
        return _render(args, exr, png, ckpt)


def _render(args, out, png_path, ckpt) -> Path:
    from ..optics.volume import optical_volume
    from ..reference.render import render_reference
    hyd = open_placed(args)
    vol = optical_volume(hyd, species=args.preset, scale=parse_scale(args.scale), phase=args.phase,
                         sizes=args.sizes or default_sizes(hyd), size_classes=args.size_classes,
                         periodic=periodic_value(args), release=True, keep=("weights",))  # the path tracer's
    from ..scene.surface import RGB_UM, with_surface
    vol = with_surface(vol, RGB_UM, args.surface, args.wind)  # the ground's surface in red, green and blue
    spec, sun_meta = scene_spec(args, vol), None
    vol = air_option.in_box(vol, spec)  # the air inside the box (--atmosphere clear), from the model's rho_air
    hyd = hyd.drop_vars(list(hyd.data_vars))  # its fields are in vol now; the place and time stay
    if args.sun_from_time:
        spec, sun_meta = with_sun_from_time(spec, hyd)
    eye_air = air_option.eye_rays_air(spec, vol, args)  # before the render releases vol's grids
    from ..reference.cluster import session
    with session(args.scheduler, args.workers) as client:
        img = render_reference(spec, vol, options=ReferenceOptions(**flag_values(args)), checkpoint=ckpt,
                               resume=ckpt if args.resume else None, client=client, variant=variant_of(args),
                               release_volume=True)  # the kernel's grids replace vol's (read no more: bbox, air)
    if sun_meta:
        img.metadata["sun_from_time"] = sun_meta
    img = air_option.on_eye_rays(img, spec, vol, args, eye_air)  # and along the eye rays outside the box
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
    return scene_spec(vol, parse_size(args.size), **{k: getattr(args, k) for k in SCENE_OPTIONS})


def animate_command(args) -> Path:
    """Every time of the inputs rendered from one camera: EXR frames, an MP4 and a contact sheet."""
    from ..display.animate import animate
    from ..reference.cluster import session
    from ..scene.framing import largest
    from ..optics.volume import optical_volume
    from ..io.sources import open_times
    check_scene_options(args)
    scale = parse_scale(args.scale)
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
    add_source(info)
    info.add_argument("--species", default="paper", choices=("paper", "physical"))
    add_sizes_option(info, classes=False)
    add_place_options(info)
    _add_render_parser(sub)
    add_satellite_parser(sub)
    _add_animate_parser(sub)
    _add_view_parser(sub)
    _add_validate_parser(sub)
    parser.commands = sub.choices  # command -> its parser (for an error in the command's own usage)
    return parser


def _add_render_parser(sub) -> None:
    render = sub.add_parser("render", help="path-trace the ground-truth image (EXR + PNG)")
    add_source(render)
    add_scene_options(render)
    air_option.on_by_default(render)  # --atmosphere clear, --sky air unless given
    # the estimator's flags (--spp, --integrator, --target-rse, --max-seconds, --sun-guiding, --forward-peak,
    # --aureole-nee): declared with its options (weather_mi.reference.options)
    add_flags(render.add_argument_group("reference estimator"))
    add_place_options(render)
    add_sun_from_time_option(render)
    add_surface_options(render, "albedo")
    render.add_argument("--seed", type=int, default=0)
    render.add_argument("--exposure", type=float, default=None, help="PNG exposure (default: automatic)")
    add_spectral_options(render)
    render.add_argument("--denoise", action=argparse.BooleanOptionalAction, default=True,
                        help="the PNG shows the OIDN-denoised image (an extra EXR layer, denoised.R/G/B; the "
                             "EXR's radiance and standard error stay unbiased); --no-denoise: the raw radiance")
    render.add_argument("--resume", action="store_true", help="continue from OUTPUT.ckpt.npz (--tile-size: from "
                                                              "the finished tiles in OUTPUT.exr.tiles/)")
    add_dask_options(render)
    add_tile_options(render)
    render.add_argument("-o", "--output", default="weather-mi.exr",
                        help="OUT.exr (or OUT.png): writes OUT.exr and OUT.png; OUT.exr.ckpt.npz while rendering")


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
    add_source(viewp)
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
    air_option.add_view_options(viewp)


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
    air = air_option.view_air(args)
    recipe = VolumeRecipe(path=args.file, demo=args.demo, preset=args.preset, phase=args.phase, sizes=args.sizes,
                          periodic=periodic_value(args))
    serve(recipe, host=args.host, port=args.port, open_browser=not args.no_browser, time_option=args.time,
          size=parse_size(args.size), air=air)


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


def _resume_hint(args) -> str:
    if args.command not in ("render", "satellite"):
        return ""
    from ..io.output_paths import render_outputs
    from ..io.resumable import tiles_folder
    from ..satellite.imagery import satellite_outputs
    try:
        outs = render_outputs(args.output) if args.command == "render" else satellite_outputs(args.output)
    except ValueError:
        return ""
    ckpt, work = outs[-1], tiles_folder(outs[0])
    if getattr(args, "tile_size", None) is not None and work.is_dir():
        return f"; the finished tiles are kept in {work}: run the same command with --resume to continue"
    from ..display.satellite_loop import parts_folder
    if args.command == "satellite" and parts_folder(args.output).is_dir():
        return "; the finished times are kept: run the same command with --resume to continue"
    if not ckpt.is_file():
        return " before the first pass was finished (no checkpoint to resume from)"
    return f"; the finished passes are in {ckpt}: run the same command with --resume to continue"


if __name__ == "__main__":
    sys.exit(main())
