"""The halo of a tiled satellite render (``satellite.tiles``) against the one-process render of the same
image: the real WRF supercell (placed at 35 N 97 W, 2024-05-20 20:00 UTC, GOES-East, 0.64 um), tiles of
``--tile-size`` pixels rendered in this process with halos of 0 to 20 km, each compared with the
one-process image (independent seeds) in units of their combined standard error
(``display.metrics.agreement_in_noise``: mean_z within +-3 and block_chi2 ~1 where they agree), over the
whole image and over the pixels next to a tile seam.

``--view aerial``: the aerial ``render --tile-size`` (``reference.tiled_render``) instead: the orbit camera at
50 deg elevation framing the domain's box (``--size`` pixels, the sun at ``--sun-elevation``), the tiles with
seed 0 against the one-process render with seed 1000 (independent noise) as above, and against the one-process
render with the same seed 0 (the same random numbers per pixel: what differs is the light the sub-boxes lose),
as the fraction of pixels bit for bit the same and the mean relative radiance difference.

    .venv/bin/python validation/tile_halo.py [--data ../shared/data] [--resolution 2] [--spp 64]
    .venv/bin/python validation/tile_halo.py --view aerial [--size 48x36] [--spp 32] [--tile-size 12]
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

PLACE = dict(lat=35.0, lon=-97.0, date="2024-05-20T20:00")


def seam_mask(plan, width: int = 2) -> np.ndarray:
    """(H, W) pixels within ``width`` of an inner tile edge."""
    w, h = plan.scene.view.size if hasattr(plan, "scene") else (plan.spec.width, plan.spec.height)
    m = np.zeros((h, w), bool)
    for t in plan.tiles:
        for r in (t.rows.start, t.rows.stop):
            if 0 < r < h:
                m[max(r - width, 0):r + width, t.cols] = True
        for c in (t.cols.start, t.cols.stop):
            if 0 < c < w:
                m[t.rows, max(c - width, 0):c + width] = True
    return m


def in_noise(a, b, mask) -> dict:
    """``mean_z`` (the difference of the means over ``mask`` over its standard error) and ``block_chi2`` (here
    per pixel: the mean of (difference / combined standard error)^2) over the pixels of ``mask``."""
    d = (np.asarray(a.radiance, np.float64) - np.asarray(b.radiance, np.float64)).mean(axis=2)[mask]
    v = (np.asarray(a.stderr, np.float64) ** 2 + np.asarray(b.stderr, np.float64) ** 2).mean(axis=2)[mask]
    ok = v > 0
    return {"mean_z": float(d.sum() / np.sqrt(v.sum())), "block_chi2": float(np.mean(d[ok] ** 2 / v[ok]))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default="../shared/data")
    ap.add_argument("--resolution", type=float, default=2.0, help="km")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--tile-size", type=int, default=12)
    ap.add_argument("--halos", default="0,2,5,10,20")
    ap.add_argument("--view", default="satellite", choices=("satellite", "aerial"))
    ap.add_argument("--size", default="48x36", help="--view aerial: WIDTHxHEIGHT")
    ap.add_argument("--sun-elevation", type=float, default=35.0, help="--view aerial: degrees")
    a = ap.parse_args()
    if a.view == "aerial":
        return aerial(a)
    from weather_mi.display.metrics import agreement_in_noise
    from weather_mi.io.wrf import open_wrf
    from weather_mi.optics.volume import default_sizes, optical_volume
    from weather_mi.satellite import imagery as si, tiles as T
    from weather_mi.scene.place import assume_place
    path = Path(a.data) / "wrf" / "wrfout_quarter_ss_0130.nc"
    t0 = time.perf_counter()
    hyd = assume_place(open_wrf(path), **PLACE)
    vol = optical_volume(hyd, species="physical", sizes=default_sizes(hyd))
    scene = si.satellite_scene(hyd, vol, "goes-east", "0.64", a.resolution, seed=1000)
    _, one = si.render_satellite(scene, spp=a.spp, progress=False)
    print(f"one process: {scene.view.size[0]} x {scene.view.size[1]} px of {a.resolution} km, {a.spp} spp, "
          f"grid {vol.beta_total.shape}, {time.perf_counter() - t0:.1f} s")
    print("| halo (km) | tiles | mean sub-box columns | seconds | mean_z (all) | block_chi2 (all) | mean_z (seams) "
          "| pixel chi2 (seams) | mean reflectance difference |")
    print("|---|---|---|---|---|---|---|---|---|")
    for halo in (float(h) for h in a.halos.split(",")):
        t0 = time.perf_counter()
        plan = T.tiled_satellite(path, None, "goes-east", "0.64", a.resolution, tile_px=a.tile_size, halo_km=halo,
                                 **PLACE)
        _, img, figs = T.render_tiles(plan, optics=dict(species="physical"), spp=a.spp)
        secs = time.perf_counter() - t0
        seams = seam_mask(plan)
        all_ = agreement_in_noise(img, one, block=2)
        a_s = in_noise(img, one, seams)
        cols = np.mean([t.cells for t in plan.tiles])
        diff = float(np.mean(img.radiance) - np.mean(one.radiance))
        print(f"| {halo:g} | {len(plan.tiles)} | {cols:.0f} | {secs:.1f} | {all_['mean_z']:+.2f} | "
              f"{all_['block_chi2']:.2f} | {a_s['mean_z']:+.2f} | {a_s['block_chi2']:.2f} | {diff:+.4f} |", flush=True)


def aerial(a) -> None:
    """The halo table of the aerial render (module docstring)."""
    from dataclasses import replace

    from weather_mi.display.metrics import agreement_in_noise
    from weather_mi.io.outline import domain_outline
    from weather_mi.io.wrf import open_wrf
    from weather_mi.optics.volume import default_sizes, optical_volume
    from weather_mi.reference import tiled_render as tr
    from weather_mi.reference.render import render_reference
    from weather_mi.scene.framing import scene_spec
    from weather_mi.scene.surface import RGB_UM, with_surface
    path = Path(a.data) / "wrf" / "wrfout_quarter_ss_0130.nc"
    width, height = (int(v) for v in a.size.split("x"))
    t0 = time.perf_counter()
    outline = domain_outline(path)
    spec = scene_spec(tr.OutlineBox(outline.bbox), (width, height), camera="orbit", camera_elevation=50.0,
                      sun_elevation=a.sun_elevation)
    hyd = open_wrf(path)
    vol = with_surface(optical_volume(hyd, species="physical", sizes=default_sizes(hyd)), RGB_UM, "albedo", None)
    one = render_reference(replace(spec, seed=1000), vol, spp=a.spp, progress=False)
    same = render_reference(spec, vol, spp=a.spp, progress=False)
    del hyd, vol
    print(f"one process: {width} x {height} px, orbit camera at 50 deg, sun at {a.sun_elevation:g} deg, {a.spp} spp, "
          f"{time.perf_counter() - t0:.1f} s (two renders)")
    print("| halo (km) | tiles | mean sub-box columns (of 10000) | seconds | mean_z (all) | block_chi2 (all) | "
          "mean_z (seams) | pixel chi2 (seams) | same seed: pixels identical | same seed: mean relative difference |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for halo in (float(h) for h in a.halos.split(",")):
        t0 = time.perf_counter()
        plan = tr.plan_render(outline, spec, tile_px=a.tile_size, halo_km=halo)
        img, _ = tr.render_tiles(plan, optics=dict(species="physical"), spp=a.spp)
        secs = time.perf_counter() - t0
        all_, a_s = agreement_in_noise(img, one, block=2), in_noise(img, one, seam_mask(plan))
        identical = float(np.mean(np.all(img.radiance == same.radiance, axis=2)))
        rel = float(np.mean(img.radiance, dtype=np.float64) / np.mean(same.radiance, dtype=np.float64) - 1.0)
        print(f"| {halo:g} | {len(plan.tiles)} | {np.mean([t.cells for t in plan.tiles]):.0f} | {secs:.1f} | "
              f"{all_['mean_z']:+.2f} | {all_['block_chi2']:.2f} | {a_s['mean_z']:+.2f} | {a_s['block_chi2']:.2f} | "
              f"{identical:.3f} | {rel:+.5f} |", flush=True)


if __name__ == "__main__":
    main()
