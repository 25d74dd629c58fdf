"""``render --tile-size PX [--halo KM] [--scheduler ADDR | --workers N] [--resume]``: the aerial render in tiles
of pixels as Dask tasks, each worker reading only its tile's sub-box of the wrfout plus the halo
(``reference.tiled_render``); the client writes the EXR (radiance, standard error, transmittance) and the PNG.
Finished tiles are kept in OUT.exr.tiles/ until the image is written (``io.resumable.TileStore``): ``--resume``
renders only the missing ones, with the options recorded there (other options are refused)."""
from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

from .options import refuse_for_tiles
from .sun_option import with_sun_from_time

# what does not change a tiled product's pixels: not recorded for --resume
NOT_RECORDED = ("scheduler", "workers", "resume", "output", "denoise", "exposure", "func", "command", "fps")


def recorded_options(args) -> dict:
    """The command's options a resumed tiled render must share with the run it continues (every option but
    ``NOT_RECORDED``; the input file by its absolute path)."""
    out = {k: v for k, v in sorted(vars(args).items()) if k not in NOT_RECORDED and not callable(v)}
    files = args.file if isinstance(args.file, list) else [args.file]
    out["file"] = [str(Path(f).resolve()) for f in files if f is not None]
    return out


@contextmanager
def tiles_kept(store):
    """An error while the tiles render (a worker's budget too small for a sub-box, a lost cluster) named with the
    finished tiles ``store`` keeps and how to continue (a RuntimeError); others as they are."""
    from ..errors import WeatherDataError
    try:
        yield
    except (WeatherDataError, ValueError, ConnectionError, RuntimeError) as exc:
        done = len(list(store.folder.glob("tile-*.npz")))
        if not done:
            raise
        raise RuntimeError(f"{exc}\n{done} finished tiles are kept in {store.folder}: run the same command with "
                           "--resume to render only the missing ones (--workers, --scheduler and "
                           "WEATHER_MI_MAX_MEMORY_GB may change)") from exc


def check_render_tile_options(args) -> None:
    """What a tiled ``render`` cannot do, named before anything is read."""
    if args.tile_size is None:
        return
    from .periodic_option import periodic_value
    bad = [(args.demo is not None, "--demo (a tiled render reads a wrfout file's sub-boxes)"),
           (args.camera == "ground", "--camera ground (its rays cross the whole domain: every tile would read most "
                                     "of the file)"),
           (args.atmosphere != "none", "--atmosphere clear"), (getattr(args, "spectral", False), "--spectral"),
           (periodic_value(args) not in (None, False), "--periodic"),
           (getattr(args, "target_rse", None) is not None, "--target-rse"),
           (getattr(args, "max_seconds", None) is not None, "--max-seconds")]
    refuse_for_tiles(args, bad, "a tiled render is an aerial view (a camera above the grid) of one time of one "
                                "wrfout file, at --spp")


def render_tiles_command(args, exr: Path, png: Path) -> Path:
    """Plan (the outline, the camera framing the domain's box), render the tiles (on ``--scheduler``/``--workers``
    or here, the finished ones read back with ``--resume``), write the EXR and PNG."""
    from ..io.resumable import TileStore, tiles_folder
    from ..io.times import parse_time
    from ..reference import tiled_render as tr
    from ..reference.cluster import session
    from ..reference.options import flag_values
    from ..satellite.tile_plan import domain_outline
    from ..scene.framing import SCENE_OPTIONS, scene_spec
    from .options import parse_scale, parse_size
    outline = domain_outline(args.file, parse_time(args.time), lat=args.lat, lon=args.lon, date=args.date)
    spec = scene_spec(tr.OutlineBox(outline.bbox), parse_size(args.size), **{k: getattr(args, k) for k in SCENE_OPTIONS})
    sun_meta = None
    if args.sun_from_time:
        spec, sun_meta = with_sun_from_time(spec, outline.dataset)
    plan = tr.plan_render(outline, spec, args.tile_size, args.halo)
    store = TileStore(tiles_folder(exr))
    store.check(recorded_options(args), args.resume)
    nz, ny, nx = outline.shape
    cols = max(t.cells for t in plan.tiles)
    print(f"{spec.width} x {spec.height} pixels in {len(plan.tiles)} tiles of up to {args.tile_size} px (camera at "
          f"{spec.camera.origin[2] / 1e3:.0f} km framing the domain's box); grid {nx} x {ny} x {nz}, the largest "
          f"sub-box {cols} columns ({100 * cols / (nx * ny):.0f}% of the domain) with a {args.halo:g} km halo")
    optics = dict(species=args.preset, scale=parse_scale(args.scale), phase=args.phase, sizes=args.sizes,
                  size_classes=args.size_classes, release=True, keep=("weights",))
    with session(args.scheduler, args.workers) as client, tiles_kept(store):
        img, figs = tr.render_tiles(plan, client, store=store, optics=optics, surface=args.surface, wind_m_s=args.wind,
                                    read_sizes=args.sizes not in ("physical", "paper"), **flag_values(args),
                                    on_tile=lambda r: print(f"  tile {r['tile'].index + 1}/{len(plan.tiles)}: grid "
                                                            f"{r['grid_shape']}, {r['seconds']:.1f} s, worker peak "
                                                            f"{r['peak_rss_bytes'] / 1e9:.2f} GB", flush=True))
    if sun_meta:
        img.metadata["sun_from_time"] = sun_meta
    img.save(exr)
    img.save_png(png, exposure=args.exposure)
    store.remove()
    print(f"wrote {exr} and {png} ({img.metadata['spp']} spp, {img.metadata['seconds']:.1f} s, {len(figs)} tiles; "
          "the PNG shows the raw radiance: the denoiser's features need the whole volume)")
    return exr
