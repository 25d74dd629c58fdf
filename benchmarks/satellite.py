"""Cost of a synthetic satellite image: time to a cloud RSE, and what a large domain would take.

    .venv/bin/python benchmarks/satellite.py [--target-rse 0.05] [--max-seconds 600] [--workers-projection 16]

Case (issue 23's target): 100 x 100 km at 1 km pixels to 5% mean relative standard error over cloud
pixels: the WRF quarter-circle supercell (../shared/data/wrf/wrfout_quarter_ss_0130.nc, 100 x 100 km,
placed at 35.2 N 97.4 W, 2013-05-20 20 UTC) seen by GOES-East in the 0.64 um band
(``satellite_scene`` + ``render_satellite`` with ``target_rse``). Baseline in the same process: the same
volume, sun and pixel count through an orthographic nadir camera (``render_reference`` to the same
target): the ratio is the cost of the table's slanted rays (longer paths through the storm) over
nadir ones.

Projection: a 1000 x 1000 km domain at 0.5 km (4 M pixels) from the measured cost per pixel at the
target (seconds x cores / pixel), over ``--workers-projection`` Dask workers of 2 cores each, with the
passes spread over them (``render_reference(..., client=...)``: bit-identical to one process); the cloud
fraction is the measured one, so the projection holds for a storm-like cloud cover.
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--target-rse", type=float, default=0.05)
    ap.add_argument("--max-seconds", type=float, default=600.0)
    ap.add_argument("--spp", type=int, default=16, help="samples of the first estimate")
    ap.add_argument("--workers-projection", type=int, default=16)
    args = ap.parse_args(argv)
    import weather_mi as wm
    from weather_mi.scene.place import assume_place
    from weather_mi.satellite.imagery import render_satellite, satellite_scene
    wm.set_variant("llvm_ad_rgb")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        hyd = assume_place(wm.open_wrf(ROOT.parent / "shared" / "data" / "wrf" / "wrfout_quarter_ss_0130.nc"),
                           35.2, -97.4, "2013-05-20T20:00")
    vol = wm.optical_volume(hyd, species="physical")
    scene = satellite_scene(hyd, vol, "goes-east", "0.64", 1.0)
    w, h = scene.spec.width, scene.spec.height
    kw = dict(target_rse=args.target_rse, max_seconds=args.max_seconds, progress=False)
    rows = []
    t0 = time.perf_counter()
    ds, img = render_satellite(scene, spp=args.spp, **kw)
    rows.append(("satellite (GOES-East rays)", w * h, img.metadata, time.perf_counter() - t0))
    (x0, y0, _), (x1, y1, _) = scene.vol.bbox
    cam = wm.Camera.orthographic(center=((x0 + x1) / 2, (y0 + y1) / 2, 25000.0), direction=(0.0, 0.0, -1.0),
                                 width=x1 - x0, height=y1 - y0)
    nadir = dataclasses.replace(scene.spec, camera=cam, rays=None, width=100, height=int(round(100 * (y1 - y0) / (x1 - x0))))
    t0 = time.perf_counter()
    base = wm.render_reference(nadir, scene.vol, spp=args.spp, normalize="reflectance", **kw)
    rows.append(("baseline: orthographic nadir", nadir.width * nadir.height, base.metadata, time.perf_counter() - t0))
    print(f"{'view':30s} {'pixels':>7s} {'cloud px':>8s} {'spp':>5s} {'cloud RSE':>9s} {'render s':>8s} {'wall s':>7s} "
          f"{'ms/px':>6s}")
    for name, px, m, wall in rows:
        noise = m.get("noise") or {}
        print(f"{name:30s} {px:7d} {noise.get('cloud_pixels', 0):8d} {m['spp']:5d} {noise.get('rse_mean', np.nan):9.3f} "
              f"{m['seconds']:8.1f} {wall:7.1f} {1e3 * m['seconds'] / px:6.2f}")
    ratio = (rows[0][2]["seconds"] / rows[0][1]) / (rows[1][2]["seconds"] / rows[1][1])
    print(f"satellite / nadir cost per pixel at the same target: {ratio:.2f}x")
    per_px = rows[0][2]["seconds"] / rows[0][1]  # s per pixel on this machine's 2 cores
    big = 2000 * 2000
    n = args.workers_projection
    print(f"projection, 1000 x 1000 km at 0.5 km ({big / 1e6:.0f} M pixels) to RSE {args.target_rse:g}, this storm's cloud "
          f"cover: {per_px * big / 3600:.1f} h on 2 cores; {per_px * big / n / 60:.0f} min on {n} Dask workers of 2 cores")
    return 0


if __name__ == "__main__":
    sys.exit(main())
