"""``satellite --tile-size PX [--halo KM] [--scheduler ADDR | --workers N] [--rgb] [--resume]``: the image in
tiles of pixels as Dask tasks, each worker reading only its tile's sub-box of the wrfout plus the halo
(``satellite.tiles``); the client writes the same NetCDF, EXR and PNG as the one-process command (``--rgb``: the
true-colour bands in one render per tile, the recipe of ``satellite.truecolor`` applied to the assembled bands).
Finished tiles are kept in OUT.nc.tiles/ until the products are written (``io.resumable.TileStore``):
``--resume`` renders only the missing ones, with the options recorded there (other options are refused)."""
from __future__ import annotations

from pathlib import Path

from .options import refuse_for_tiles


def add_tile_options(p) -> None:
    """``--tile-size`` and ``--halo`` on the ``satellite`` parser."""
    from ..satellite.tile_plan import DEFAULT_HALO_KM
    p.add_argument("--tile-size", type=int, default=None, metavar="PX",
                   help="render in tiles of PX x PX pixels, each reading only its sub-box of the file and a halo "
                        "(a domain larger than one machine: with --scheduler/--workers, a Dask task per tile)")
    p.add_argument("--halo", type=float, default=DEFAULT_HALO_KM, metavar="KM",
                   help=f"with --tile-size: the margin (km) around a tile's lines of sight and their sun paths "
                        f"for light scattered sideways (default {DEFAULT_HALO_KM:g}: the seams within noise)")


def check_tile_options(args) -> None:
    """What a tiled render cannot do, named before anything is read."""
    if args.tile_size is None:
        return
    from .satellite_loop import wants_loop
    bad = [(args.demo is not None, "--demo (a tiled render reads a wrfout file's sub-boxes)"),
           (args.demo is None and wants_loop(args), "several files or times"),
           (args.rgb and args.rayleigh, "--rgb --rayleigh (the Rayleigh correction needs the whole domain's air)"),
           (getattr(args, "periodic", None) not in (None, "off"), "--periodic")]
    refuse_for_tiles(args, bad, "a tiled render is one band (or --rgb) of one time of one wrfout file")


def satellite_tiles_command(args, resolution: float, nc: Path, exr: Path, png: Path, estimator: dict) -> Path:
    """Plan, render the tiles (on ``--scheduler``/``--workers`` or here), write the products."""
    from ..display.satellite_picture import shown_dataset, write_picture
    from ..reference.cluster import session
    from ..satellite import tiles as st
    from ..satellite.imagery import write_satellite
    from ..io.resumable import TileStore, tiles_folder
    from ..io.times import parse_time
    from .render_tiles import recorded_options, tiles_kept
    plan = st.tiled_satellite(args.file, parse_time(args.time), args.satellite, args.band or "0.64", resolution,
                              tile_px=args.tile_size, halo_km=args.halo, rayleigh=args.rayleigh,
                              ground_albedo=args.ground_albedo, seed=args.seed, lat=args.lat, lon=args.lon,
                              date=args.date, surface=args.surface, wind_m_s=args.wind, rgb=args.rgb)
    store = TileStore(tiles_folder(nc))
    store.check(dict(recorded_options(args), resolution_km=resolution), args.resume)
    w, h = plan.scene.view.size
    nz, ny, nx = plan.outline.shape
    cols = max(t.cells for t in plan.tiles)
    what = "true colour (" + ", ".join(b.name for b in plan.scene.bands) + " um)" if args.rgb else \
        f"band {plan.scene.band.name} um"
    print(f"{plan.scene.satellite.name}, {what}: {w} x {h} pixels of {resolution:g} km in "
          f"{len(plan.tiles)} tiles of up to {args.tile_size} px; grid {nx} x {ny} x {nz}, the largest sub-box "
          f"{cols} columns ({100 * cols / (nx * ny):.0f}% of the domain) with a {args.halo:g} km halo")
    optics = dict(species=args.preset, phase=args.phase, sizes=args.sizes, size_classes=args.size_classes)
    with session(args.scheduler, args.workers) as client, tiles_kept(store):
        ds, img, figs = st.render_tiles(plan, client, optics=optics, store=store,
                                        read_sizes=args.sizes not in ("physical", "paper"), **estimator,
                                        on_tile=lambda r: print(f"  tile {r['tile'].index + 1}/{len(plan.tiles)}: "
                                                                f"grid {r['grid_shape']}, {r['seconds']:.1f} s, "
                                                                f"worker peak {r['peak_rss_bytes'] / 1e9:.2f} GB",
                                                                flush=True))
    shown = shown_dataset(ds, img, args.denoise)
    write_satellite(ds, img, nc, exr)
    write_picture(shown, png, denoise=False)
    store.remove()
    print(f"wrote {nc}, {exr} and {png} ({img.metadata['spp']} spp, {img.metadata['seconds']:.1f} s, "
          f"{len(figs)} tiles; cloud pixels {int(ds.cloud.sum())}, mean relative standard error "
          f"{ds.attrs.get('cloud_rse_mean', float('nan')):.3f})")
    return nc
