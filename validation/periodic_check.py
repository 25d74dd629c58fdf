"""Periodic boundaries against 3 x 3 tiled copies (issue 39 part 4): both renderers render a field with
``periodic=True`` and the same field tiled 3 x 3 with numpy (periodic off), looking straight down at the
centre tile with a low sun (light crosses the side walls); the centre tile must agree within noise (path
tracer: independent seeds, differences in combined standard errors) or to a tolerance (slicer), while the
isolated box (periodic off) must not.

    .venv/bin/python validation/periodic_check.py [--data ../shared/data] [--spp 64] [--passes 8]

Cases: a small synthetic field (clouds across the walls) and, with --data, the BOMEX LES file (a crop of
its run with clear edges: the check is of the boundaries, not of the file being periodic).
"""
from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np

import weather_mi as wm
from weather_mi.display.metrics import agreement_in_noise


def synthetic():
    beta = np.zeros((6, 8, 8), np.float32)
    beta[1:4, 2:6, 6:8] = 0.02
    beta[2:5, 6:8, 7:8] = 0.01
    beta[2:5, 0:1, 0:2] = 0.01
    return wm.OpticalVolume.from_arrays(beta, 0.95, wm.phase.henyey_greenstein(0.7), ((0, 0, 0), (1000, 1000, 600)))


def bomex(data: Path):
    return wm.optical_volume(wm.open_les(data / "les" / "bomex_50m.txt"), species="physical", periodic=False)


def tiled(vol):
    """``vol`` as 3 x 3 copies (numpy tiling of every grid), an isolated box around the centre copy."""
    (x0, y0, z0), (x1, y1, z1) = vol.bbox
    w, d = x1 - x0, y1 - y0
    tile = lambda a, axes: np.tile(a, [3 if k in axes else 1 for k in range(a.ndim)])  # noqa: E731
    return dataclasses.replace(vol, beta_ext=tile(vol.beta_ext, (2, 3)), beta_total=tile(vol.beta_total, (1, 2)),
                               albedo=tile(vol.albedo, (1, 2)), weights=tile(vol.weights, (2, 3)),
                               bbox=((x0 - w, y0 - d, z0), (x1 + w, y1 + d, z1)), periodic=False)


def spec_over(vol, pixels: int, seed: int, elevation: float):
    """Straight down at ``vol``'s tile (orthographic, square pixels), the sun in the west."""
    (x0, y0, _), (x1, y1, z1) = vol.bbox
    w, d = x1 - x0, y1 - y0
    h = max(pixels * d / w, 1.0)
    cam = wm.Camera.orthographic(center=((x0 + x1) / 2, (y0 + y1) / 2, z1 + 2000.0), width=w, height=d)
    return wm.SceneSpec(camera=cam, sun=wm.Sun(azimuth=270.0, elevation=elevation), sky=None,
                        ground=wm.Ground(albedo=0.3), width=pixels, height=int(round(h)), seed=seed)


def check(name, vol, args):
    per, tiles = dataclasses.replace(vol, periodic=True), tiled(vol)
    opts = dict(spp=args.spp, passes=args.passes, progress=False)
    rows = []
    t = time.time()
    ref = wm.render_reference(spec_over(vol, args.pixels, 2, args.elevation), tiles, **opts)
    t_ref = time.time() - t
    for label, v, seed in (("periodic", per, 1), ("isolated box", vol, 3)):
        t = time.time()
        img = wm.render_reference(spec_over(vol, args.pixels, seed, args.elevation), v, **opts)
        a = agreement_in_noise(img, ref)
        rows.append((name, "path tracer", label, a["mean_z"], a["block_chi2"], time.time() - t, t_ref))
    from weather_mi.slicing import SliceRenderer
    t = time.time()
    sref = SliceRenderer(tiles).frame(spec_over(vol, args.pixels, 0, args.elevation)).radiance
    t_sref = time.time() - t
    for label, v in (("periodic", per), ("isolated box", vol)):
        t = time.time()
        img = SliceRenderer(v).frame(spec_over(vol, args.pixels, 0, args.elevation)).radiance
        rel = float(np.abs(img - sref).mean() / sref.mean())
        rows.append((name, "slicer", label, rel, float("nan"), time.time() - t, t_sref))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(Path(__file__).resolve().parents[2] / "shared" / "data"))
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--passes", type=int, default=8)
    ap.add_argument("--pixels", type=int, default=32)
    ap.add_argument("--elevation", type=float, default=30.0, help="sun elevation (degrees), from the west")
    args = ap.parse_args(argv)
    cases = [("synthetic 8x8x6", synthetic())]
    data = Path(args.data)
    if (data / "les" / "bomex_50m.txt").is_file():
        cases.append(("BOMEX 115x146x52", bomex(data)))
    print(f"{'case':18s} {'renderer':12s} {'vs 3x3 tiling':14s} {'mean z / rel':>13s} {'block chi2':>10s} "
          f"{'time s':>7s} {'tiled s':>7s}")
    for name, vol in cases:
        for r in check(name, vol, args):
            print(f"{r[0]:18s} {r[1]:12s} {r[2]:14s} {r[3]:13.4g} {r[4]:10.3g} {r[5]:7.1f} {r[6]:7.1f}")
    print("path tracer: mean z = difference of the tile's means / combined standard error (agreement: |z| < 3), "
          "block chi2 over 4 x 4 pixel blocks (~1); slicer: mean |difference| / mean of the tiled frame")


if __name__ == "__main__":
    main()
