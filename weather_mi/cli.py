"""Command line.

    weather-mi info FILE | --demo supercell|cumulus
    weather-mi render FILE | --demo supercell|cumulus [options] -o out.exr
    weather-mi validate -o DIR [--quick]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from .errors import WeatherDataError
from .hydrometeors import SPECIES_NAMES, spacing_of

DEMOS = ("supercell", "cumulus")


LES_SUFFIXES = (".txt", ".dat", ".csv")


def load_input(path: str | None, demo: str | None, time=None):
    """Hydrometeors from a file (wrfout NetCDF or LES text) or a built-in demo storm. ``time`` (a WRF
    file's time, default the last) is refused for inputs that have one time only."""
    from . import synthetic
    from .io import open_les, open_wrf
    check_time_option(path, demo, time)
    if path is None:
        return getattr(synthetic, demo or "supercell")()
    p = Path(path)
    if p.suffix.lower() in LES_SUFFIXES:
        return open_les(p)
    return open_wrf(p, time=-1 if time is None else time)


def check_time_option(path: str | None, demo: str | None, time) -> None:
    if time is None:
        return
    if path is None:
        raise ValueError(f"--time {time} selects a time of a WRF file; the demo storm {demo or 'supercell'} "
                         "has one time: leave --time out")
    if Path(path).suffix.lower() in LES_SUFFIXES:
        raise ValueError(f"--time {time} selects a time of a WRF file; {path} (an LES text file) has one time: "
                         "leave --time out")


def _parse_time(s: str | None):
    if s is None:
        return None
    try:
        return int(s)
    except ValueError:
        return s


def info_text(hyd, species: str = "paper") -> str:
    """Dimensions, spacing, per-species max/mean mixing ratio, max extinction, densest column's tau."""
    from .optics import optical_volume
    vol = optical_volume(hyd, species=species)
    dz, dy, dx = spacing_of(hyd)
    nz, ny, nx = vol.shape
    (x0, y0, z0), (x1, y1, z1) = vol.bbox
    lines = [f"source      : {hyd.attrs.get('source', '?')}",
             f"time        : {hyd.attrs.get('time', '-')}    microphysics: {hyd.attrs.get('microphysics', '-')}",
             f"grid (z,y,x): {nz} x {ny} x {nx}    spacing dz, dy, dx = {dz:.1f}, {dy:.1f}, {dx:.1f} m",
             f"extent      : x {x0 / 1e3:.2f}..{x1 / 1e3:.2f} km, y {y0 / 1e3:.2f}..{y1 / 1e3:.2f} km, "
             f"z {z0 / 1e3:.2f}..{z1 / 1e3:.2f} km",
             f"species preset: {species}",
             f"{'species':<9}{'max q (g/kg)':>14}{'mean q (g/kg)':>15}{'max beta (1/km)':>17}"]
    for i, name in enumerate(SPECIES_NAMES):
        q = hyd[f"q_{name}"].values
        lines.append(f"{name:<9}{1e3 * float(q.max()):>14.4g}{1e3 * float(q.mean()):>15.4g}"
                     f"{1e3 * float(vol.beta_ext[i].max()):>17.4g}")
    tau = vol.optical_depth_z()
    j, i = np.unravel_index(int(np.argmax(tau)), tau.shape)
    lines.append(f"max extinction: {1e3 * float(vol.beta_total.max()):.4g} 1/km")
    lines.append(f"vertical optical depth through the densest column (x={float(hyd.x[i]) / 1e3:.1f} km, "
                 f"y={float(hyd.y[j]) / 1e3:.1f} km): {float(tau[j, i]):.4g}")
    if hyd.attrs.get("n_negative_clipped"):
        lines.append(f"negative mixing ratios clipped: {hyd.attrs['n_negative_clipped']}")
    return "\n".join(lines)


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
    return w, h


def default_ground_distance_km(vol) -> float:
    """How far a photographer stands from a storm: 0.55 x the cloud's horizontal extent, and at least
    1.2 x the height of its top (40 km for the demo supercell, 5.6 km for the demo cumulus)."""
    (x0, y0, _), (x1, y1, z1) = vol.occupied_bbox()
    return max(0.55 * max(x1 - x0, y1 - y0), 1.2 * z1) / 1000.0


def output_paths(output) -> tuple[Path, Path, Path]:
    """(EXR, PNG, checkpoint) of ``-o`` (a .exr or .png name; ValueError for another extension)."""
    from .output_paths import image_format
    out = Path(output)
    image_format(out)
    exr = out.with_suffix(".exr")
    return exr, out.with_suffix(".png"), exr.with_name(exr.name + ".ckpt.npz")


def render_command(args) -> Path:
    """Check the arguments and the outputs, build the volume and the scene, render the reference while
    holding the outputs' lock, write EXR + PNG."""
    from .output_paths import OutputLock, check_writable_folder
    from .scene import check_fov_deg
    width, height = _parse_size(args.size)
    if args.fov is not None:
        check_fov_deg(args.fov)
    check_time_option(args.file, args.demo, args.time)
    exr, png, ckpt = output_paths(args.output)
    check_writable_folder(exr)
    with OutputLock(exr):
        if ckpt.is_file() and not args.resume:
            raise ValueError(f"{ckpt} holds an unfinished render: add --resume to continue it, or delete it to "
                             "render afresh")
        return _render(args, width, height, exr, png, ckpt)


def _render(args, width, height, out, png_path, ckpt) -> Path:
    from .optics import optical_volume
    from .reference import render_reference
    from .scene import Camera, Ground, SceneSpec, Sky, Sun
    hyd = load_input(args.file, args.demo, _parse_time(args.time))
    vol = optical_volume(hyd, species=args.preset, scale=_parse_scale(args.scale), phase=args.phase)
    sky = None if args.sky == "none" else Sky(args.sky)
    ground = None if args.ground_albedo < 0 else Ground(albedo=args.ground_albedo,
                                                        height=min(0.0, vol.bbox[0][2]))
    if args.camera == "orbit":
        camera = Camera.orbit(vol, azimuth=args.camera_azimuth, elevation=args.camera_elevation,
                              distance=args.distance, fov=45.0 if args.fov is None else args.fov)
    else:
        camera = Camera.ground_view(vol, azimuth=args.camera_azimuth, fov=70.0 if args.fov is None else args.fov,
                                    aspect=width / height,
                                    distance_km=args.camera_distance_km or default_ground_distance_km(vol),
                                    height_m=args.camera_height, ground_m=0.0 if ground is None else ground.height)
    spec = SceneSpec(camera=camera, sun=Sun(args.sun_azimuth, args.sun_elevation, angular_diameter_deg=args.sun_diameter),
                     sky=sky, ground=ground, width=width, height=height, seed=args.seed)
    img = render_reference(spec, vol, spp=args.spp, integrator=args.integrator, checkpoint=ckpt,
                           resume=ckpt if args.resume else None, target_rse=args.target_rse,
                           max_seconds=args.max_seconds, sun_guiding=args.sun_guiding,
                           forward_peak_deg=args.forward_peak, aureole_nee=args.aureole_nee)
    img.save(out)
    png = img.save_png(png_path, exposure=args.exposure)
    ckpt.unlink(missing_ok=True)
    noise = img.metadata.get("noise") or {}
    cloud = (f", over cloud pixels: mean relative standard error {noise['rse_mean']:.3f}, RMS standard error / "
             f"mean {noise['rms_se_over_mean']:.3f}, worst {noise['worst_se_over_mean']:.2f}") if noise.get("cloud_pixels") \
        else f", mean relative standard error {img.relative_stderr():.3f}"
    print(f"wrote {out} and {png} ({img.metadata['spp']} spp, {img.metadata['seconds']:.1f} s{cloud})")
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="weather-mi", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    info = sub.add_parser("info", help="summarise a data file or a demo storm")
    _add_source(info)
    info.add_argument("--species", default="paper", choices=("paper", "physical"))
    render = sub.add_parser("render", help="path-trace the ground-truth image (EXR + PNG)")
    _add_source(render)
    render.add_argument("--preset", default="physical", choices=("paper", "physical"), help="species table")
    render.add_argument("--phase", default="per_species", choices=("per_species", "paper"))
    render.add_argument("--scale", action="append", metavar="SPECIES=FACTOR", help="e.g. --scale ice=2")
    render.add_argument("--sun-azimuth", type=float, default=290.0, help="degrees clockwise from north")
    render.add_argument("--sun-elevation", type=float, default=35.0)
    render.add_argument("--sun-diameter", type=float, default=0.53,
                        help="angular diameter of the sun disk (degrees); 0: a point sun")
    render.add_argument("--camera", default="ground", choices=("ground", "orbit"),
                        help="ground: a photographer's view from near the ground (Camera.ground_view); "
                             "orbit: on a sphere around the cloud (Camera.orbit)")
    render.add_argument("--camera-azimuth", type=float, default=200.0,
                        help="where the camera stands, seen from the storm (degrees clockwise from north)")
    render.add_argument("--camera-elevation", type=float, default=8.0, help="orbit camera: elevation (degrees)")
    render.add_argument("--distance", type=float, default=None,
                        help="orbit camera: distance (m); default fits the box")
    render.add_argument("--camera-distance-km", type=float, default=None,
                        help="ground camera: horizontal distance from the storm's core (km); default from its size")
    render.add_argument("--camera-height", type=float, default=1500.0, help="ground camera: height above ground (m)")
    render.add_argument("--fov", type=float, default=None,
                        help="horizontal field of view (degrees; default 70 ground, 45 orbit)")
    render.add_argument("--sky", default="sunsky", choices=("sunsky", "constant", "none"))
    render.add_argument("--ground-albedo", type=float, default=0.15, help="negative: no ground")
    render.add_argument("--size", default="320x240", help="WIDTHxHEIGHT")
    render.add_argument("--spp", type=int, default=48,
                        help="samples per pixel (with --target-rse: of the first estimate)")
    render.add_argument("--target-rse", type=float, default=None,
                        help="add passes until the mean relative standard error over cloud pixels is this")
    render.add_argument("--max-seconds", type=float, default=None, help="with --target-rse: time limit")
    render.add_argument("--sun-guiding", type=float, default=None,
                        help="probability of sun-guided scattering directions (default: the renderer's)")
    render.add_argument("--forward-peak", type=float, default=None, metavar="DEG",
                        help="count scattering by less than DEG degrees (the forward peaks of the phase "
                             "functions) as unscattered light, delta-M (default: the renderer's, 3; 0: off)")
    render.add_argument("--aureole-nee", type=float, default=None, metavar="P",
                        help="probability of the aureole estimator (sun light reaching a vertex through one more "
                             "forward scattering) at each scattering (default: the renderer's, 0: off)")
    render.add_argument("--seed", type=int, default=0)
    render.add_argument("--integrator", default="majorant", choices=("majorant", "volpath"))
    render.add_argument("--exposure", type=float, default=None, help="PNG exposure (default: automatic)")
    render.add_argument("--resume", action="store_true", help="continue from OUTPUT.ckpt.npz")
    render.add_argument("-o", "--output", default="weather-mi.exr",
                        help="OUT.exr (or OUT.png): writes OUT.exr and OUT.png; OUT.exr.ckpt.npz while rendering")
    val = sub.add_parser("validate", help="the validation study: slicer against path-traced ground truth")
    val.add_argument("-o", "--output", default="validation-report", help="report folder")
    val.add_argument("--quick", action="store_true", help="small images and samples: a few minutes")
    val.add_argument("--config", choices=("full", "quick", "tiny"), default=None)
    val.add_argument("--data", default=None, help="folder of real model output (wrf/..., les/..., e.g. "
                     "../shared/data); without it only the built-in demo storms are studied")
    args = parser.parse_args(argv)
    if args.command in ("info", "render") and (args.file is None) == (args.demo is None):
        sub.choices[args.command].error("give a data FILE or --demo NAME (one of them)")
    try:
        if args.command == "info":
            hyd = load_input(args.file, args.demo, _parse_time(args.time))
            print(info_text(hyd, args.species))
        elif args.command == "render":
            render_command(args)
        elif args.command == "validate":
            from .study import run
            report = run(args.output, args.config or ("quick" if args.quick else "full"), data_dir=args.data)
            print(f"wrote {report}")
    except (WeatherDataError, ValueError) as exc:
        print(f"weather-mi: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"weather-mi: interrupted{_resume_hint(args)}", file=sys.stderr)
        return 130
    return 0


def _add_source(parser) -> None:
    """FILE or --demo (exclusive, checked after parsing so that an unknown option is named as such)."""
    parser.add_argument("file", nargs="?", help="wrfout NetCDF or LES text file")
    parser.add_argument("--demo", choices=DEMOS, help="a built-in demo storm")
    parser.add_argument("--time", default=None, help="time index or timestamp (WRF files; default the last)")


def _resume_hint(args) -> str:
    if args.command != "render":
        return ""
    try:
        _, _, ckpt = output_paths(args.output)
    except ValueError:
        return ""
    if not ckpt.is_file():
        return " before the first pass was finished (no checkpoint to resume from)"
    return f"; the finished passes are in {ckpt}: run the same command with --resume to continue"


if __name__ == "__main__":
    sys.exit(main())
