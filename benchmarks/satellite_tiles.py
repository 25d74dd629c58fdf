"""Tiles of a satellite image (``satellite --tile-size``): the peak memory and time of one tile, measured,
and what they project for a 1-km national run (5000 x 3000 x 60) on a cluster.

The real WRF supercell tiled to ``--size`` x ``--size`` (``cli_memory.tiled_wrfout``: a large file whose
sub-boxes are read for real), the satellite image at ``--resolution`` planned in tiles of ``--tile-size``
pixels with a ``--halo`` (``satellite.tiles.tiled_satellite``); ``--samples`` tiles from the image's interior
each rendered in a child process of its own (``render_tile``), measured by ``os.wait4`` (peak RSS, the
interpreter and Mitsuba included; the baseline of a child that only loads them is printed beside) and by
the task's own clock (reading + optics, then path tracing). The projection: the national image's tiles
(its pixels over the tile size), each tile's sub-box cells in proportion to the measured tile's (60
levels against 51, the same pixel size), bytes as the measured bytes per sub-box cell, seconds as the
measured read + optics per cell and path tracing per pixel at ``--spp``, spread over ``--workers``.

    .venv/bin/python benchmarks/satellite_tiles.py [--size 400] [--resolution 1] [--tile-size 128] [--halo 10]
"""
from __future__ import annotations

import argparse
import json
import os
import pickle
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve()
CHILD = ("import sys, json, pickle, time; job = pickle.load(open(sys.argv[1], 'rb')); "
         "from weather_mi.satellite.tiles import render_tile; "
         "r = render_tile(job) if job is not None else None; "
         "print('RESULT ' + json.dumps(None if r is None else {k: r[k] for k in "
         "('seconds', 'read_seconds', 'grid_shape', 'volume_bytes', 'spp')}))")
BASELINE = ("import weather_mi.satellite.tiles, weather_mi.reference.render, weather_mi.optics.volume; "
            "from weather_mi.kernel.variant import set_variant; set_variant(); print('RESULT null')")
NATIONAL = (5000, 3000, 60)   # nx, ny, nz of a 1-km national run
PLACE = dict(lat=35.0, lon=-97.0, date="2024-05-20T20:00")


def child(job) -> tuple[dict | None, int, float]:
    """(render_tile's figures, peak RSS bytes, wall seconds) of ``job`` in a child process (None: only the
    imports and the variant)."""
    with tempfile.NamedTemporaryFile(suffix=".pkl", delete=False) as f:
        pickle.dump(job, f)
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-c", CHILD if job is not None else BASELINE, f.name], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                            cwd=str(HERE.parents[1]))
    out = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    os.unlink(f.name)
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"tile child failed: {out[-2000:]}")
    line = next(x for x in out.splitlines() if x.startswith("RESULT "))
    return json.loads(line[7:]), usage.ru_maxrss * 1024, time.perf_counter() - t0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=400, help="the tiled supercell's width (a multiple of 100)")
    ap.add_argument("--tmp", type=Path, default=Path("/tmp/weather-mi-tiles"))
    ap.add_argument("--resolution", type=float, default=1.0, help="pixel size (km)")
    ap.add_argument("--tile-size", type=int, default=128)
    ap.add_argument("--halo", type=float, default=30.0, help="km")
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--samples", type=int, default=2)
    ap.add_argument("--workers", type=int, nargs="+", default=[64, 256], help="cluster sizes to project for")
    a = ap.parse_args(argv)
    sys.path.insert(0, str(HERE.parent))
    from cli_memory import tiled_wrfout  # noqa: E402  (a benchmark beside this one)
    sys.path.pop(0)   # benchmarks/distributed.py would shadow the package
    from weather_mi.kernel.variant import set_variant
    from weather_mi.satellite import tiles as st
    path = tiled_wrfout(a.size, a.tmp)
    t0 = time.perf_counter()
    plan = st.tiled_satellite(path, None, resolution_km=a.resolution, tile_px=a.tile_size, halo_km=a.halo, **PLACE)
    t_plan = time.perf_counter() - t0
    nz, ny, nx = plan.outline.shape
    w, h = plan.scene.view.size
    jobs = st.tile_jobs(plan, variant=set_variant(), spp=a.spp)
    full = [j for j in jobs if j.tile.rows.stop - j.tile.rows.start == a.tile_size
            and j.tile.cols.stop - j.tile.cols.start == a.tile_size]
    ranked = sorted(full or jobs, key=lambda j: -j.tile.cells)
    sample = ranked[:a.samples]
    print(f"domain {nx} x {ny} x {nz} ({path}), image {w} x {h} px of {a.resolution:g} km, {len(jobs)} tiles of "
          f"{a.tile_size} px, halo {a.halo:g} km; plan (outline: 2-D fields, two w-levels) {t_plan:.1f} s")
    _, base_rss, _ = child(None)
    print(f"baseline child (Python, weather_mi, Mitsuba, variant set): {base_rss / 1e9:.2f} GB peak RSS\n")
    print("| tile | pixels | sub-box (z, y, x) | cells | peak RSS GB | net GB | net bytes/cell | read + optics s "
          "| render s | wall s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    rows = []
    for j in sample:
        r, rss, wall = child(j)
        cells = int(np.prod(r["grid_shape"]))
        px = (j.tile.rows.stop - j.tile.rows.start) * (j.tile.cols.stop - j.tile.cols.start)
        net = rss - base_rss
        rows.append((cells, px, net, r["read_seconds"], r["seconds"] - r["read_seconds"]))
        print(f"| {j.tile.index} | {px} | {tuple(r['grid_shape'])} | {cells / 1e6:.2f} M | {rss / 1e9:.2f} | "
              f"{net / 1e9:.2f} | {net / cells:.0f} | {r['read_seconds']:.1f} | {r['seconds'] - r['read_seconds']:.1f} "
              f"| {wall:.1f} |", flush=True)
    project(rows, plan, a, base_rss)
    return 0


def project(rows, plan, a, base_rss) -> None:
    """The national run's tiles, bytes and seconds from the measured tiles (see the module)."""
    cells, px, net, t_read, t_render = (np.mean([r[k] for r in rows]) for k in range(5))
    nz = plan.outline.shape[0]
    tile_cols = cells / nz
    nat_x, nat_y, nat_z = NATIONAL
    # the national image: the domain's pixels at the same resolution, plus the parallax margin in proportion
    w, h = plan.scene.view.size
    _, ny, nx = plan.outline.shape
    nat_w, nat_h = int(np.ceil(w * nat_x / nx)), int(np.ceil(h * nat_y / ny))
    tiles = int(np.ceil(nat_w / a.tile_size) * np.ceil(nat_h / a.tile_size))
    nat_cells = tile_cols * (nat_z + 1)  # 60 native levels: about 61 regridded (the supercell's 50: 51)
    nat_bytes = base_rss + net / cells * nat_cells
    nat_tile_s = t_read / cells * nat_cells + t_render / px * a.tile_size ** 2
    whole_cells = nat_x * nat_y * (nat_z + 1)
    print(f"\nprojection for the 1-km national run {nat_x} x {nat_y} x {nat_z} ({whole_cells / 1e9:.2f} G cells "
          f"regridded; one process would need about {whole_cells * net / cells / 1e9:.0f} GB): image "
          f"{nat_w} x {nat_h} px of {a.resolution:g} km, {tiles} tiles of {a.tile_size} px, each a sub-box of "
          f"{nat_cells / 1e6:.1f} M cells: {nat_bytes / 1e9:.2f} GB peak per worker, {nat_tile_s:.1f} s per tile "
          f"at {a.spp} spp ({t_read / cells * 1e9:.0f} ns per cell reading and optics, "
          f"{t_render / px * 1e6:.0f} us per pixel path tracing)")
    print("| workers | tiles per worker | wall time (min) | cluster memory (GB) |")
    print("|---|---|---|---|")
    for n in a.workers:
        per = int(np.ceil(tiles / n))
        print(f"| {n} | {per} | {per * nat_tile_s / 60:.1f} | {n * nat_bytes / 1e9:.0f} |")


if __name__ == "__main__":
    sys.exit(main())
