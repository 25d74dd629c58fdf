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
    """The BOMEX file's optics, the species it holds only (cloud water: the same render, a fifth of the
    memory once tiled)."""
    vol = wm.optical_volume(wm.open_les(data / "les" / "bomex_50m.txt"), species="physical", periodic=False)
    keep = [i for i in range(len(vol.species)) if vol.beta_ext[i].any()]
    return dataclasses.replace(vol, species=tuple(vol.species[i] for i in keep), beta_ext=vol.beta_ext[keep],
                               weights=vol.weights[keep], phase_tables=tuple(vol.phase_tables[i] for i in keep))


def tiled(vol, n: int = 3):
    """``vol`` as n x n copies (n odd; numpy tiling of every grid), an isolated box around the centre copy."""
    (x0, y0, z0), (x1, y1, z1) = vol.bbox
    w, d, k = x1 - x0, y1 - y0, (n - 1) // 2
    tile = lambda a, axes: np.tile(a, [n if i in axes else 1 for i in range(a.ndim)])  # noqa: E731
    return dataclasses.replace(vol, beta_ext=tile(vol.beta_ext, (2, 3)), beta_total=tile(vol.beta_total, (1, 2)),
                               albedo=tile(vol.albedo, (1, 2)), weights=tile(vol.weights, (2, 3)),
                               bbox=((x0 - k * w, y0 - k * d, z0), (x1 + k * w, y1 + k * d, z1)), periodic=False)


def spec_over(vol, pixels: int, seed: int, elevation: float):
    """Straight down at ``vol``'s tile (orthographic, square pixels), the sun in the west."""
    (x0, y0, _), (x1, y1, z1) = vol.bbox
    w, d = x1 - x0, y1 - y0
    h = max(pixels * d / w, 1.0)
    cam = wm.Camera.orthographic(center=((x0 + x1) / 2, (y0 + y1) / 2, z1 + 2000.0), width=w, height=d)
    return wm.SceneSpec(camera=cam, sun=wm.Sun(azimuth=270.0, elevation=elevation), sky=None,
                        ground=wm.Ground(albedo=0.3), width=pixels, height=int(round(h)), seed=seed)


def check(name, vol, args):
    """Rows (case, renderer, what vs the n x n tiling, mean z, block chi2, relative difference, seconds,
    seconds of the tiled render): the path tracer's periodic and isolated renders against 3 x 3 tiles, and
    its periodic render against every tiling of ``args.tiles`` (light from beyond one period: a 3 x 3
    tiling misses the copies farther away, the periodic render has them); the slicer's against 3 x 3."""
    per, tiles = dataclasses.replace(vol, periodic=True), tiled(vol)
    opts = dict(spp=args.spp, passes=args.passes, progress=False)
    rows = []
    imgs = {}
    for label, v, seed in (("periodic", per, 1), ("isolated box", vol, 3)):
        t = time.time()
        imgs[label] = wm.render_reference(spec_over(vol, args.pixels, seed, args.elevation), v, **opts), time.time() - t
    for n in args.tiles:
        t = time.time()
        ref = wm.render_reference(spec_over(vol, args.pixels, 10 + n, args.elevation), tiled(vol, n), **opts)
        t_ref = time.time() - t
        for label in ("periodic", "isolated box") if n == 3 else ("periodic",):
            a = agreement_in_noise(imgs[label][0], ref)
            rel = float(imgs[label][0].radiance.mean() / ref.radiance.mean() - 1.0)
            rows.append((name, "path tracer", f"{label} {n}x{n}", a["mean_z"], a["block_chi2"], rel, imgs[label][1],
                         t_ref))
    from weather_mi.slicing import SliceRenderer
    t = time.time()
    sref = SliceRenderer(tiles).frame(spec_over(vol, args.pixels, 0, args.elevation)).radiance
    t_sref = time.time() - t
    for label, v in (("periodic", per), ("isolated box", vol)):
        t = time.time()
        img = SliceRenderer(v).frame(spec_over(vol, args.pixels, 0, args.elevation)).radiance
        rel = float(np.abs(img - sref).mean() / sref.mean())
        rows.append((name, "slicer", f"{label} 3x3", float("nan"), float("nan"), rel, time.time() - t, t_sref))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(Path(__file__).resolve().parents[2] / "shared" / "data"))
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--passes", type=int, default=8)
    ap.add_argument("--pixels", type=int, default=32)
    ap.add_argument("--elevation", type=float, default=30.0, help="sun elevation (degrees), from the west")
    ap.add_argument("--tiles", default="3,5", help="path tracer: the n x n tilings to compare with (odd n)")
    args = ap.parse_args(argv)
    args.tiles = [int(n) for n in args.tiles.split(",")]
    cases = [("synthetic 8x8x6", synthetic())]
    data = Path(args.data)
    if (data / "les" / "bomex_50m.txt").is_file():
        cases.append(("BOMEX 115x146x52", bomex(data)))
    print(f"{'case':18s} {'renderer':12s} {'vs tiling':18s} {'mean z':>8s} {'block chi2':>10s} {'rel':>9s} "
          f"{'time s':>7s} {'tiled s':>7s}")
    for name, vol in cases:
        for r in check(name, vol, args):
            print(f"{r[0]:18s} {r[1]:12s} {r[2]:18s} {r[3]:8.3g} {r[4]:10.3g} {r[5]:9.2g} {r[6]:7.1f} {r[7]:7.1f}")
    print("path tracer: mean z = difference of the tile's means / combined standard error (agreement: |z| < 3), "
          "block chi2 over 4 x 4 pixel blocks (~1), rel = mean / tiled mean - 1; slicer: rel = mean |difference| / "
          "mean of the tiled frame")


if __name__ == "__main__":
    main()
