"""Slab terraces of the half-angle slicer: a banding metric on the demo supercell tower, before and
after the per-pixel slab offsets (``SliceParams.slab_jitter``, weather_mi/slicing/jitter.py).

    .venv/bin/python benchmarks/banding.py [--size 640x480] [--slices 128] [--modes per-species/multiple]
                                           [--out out/banding] [--variant llvm_ad_rgb]

The metric. A terrace is an error that is periodic, with a period of one slab, in the slice coordinate
of the surface the pixel sees. For every pixel: k = the continuous slice index (geometry.py,
``SliceGeometry.slice_of``) of the point where the optical depth along the eye ray reaches 1 (found
by marching the extinction texture in steps of a quarter voxel), and r = (Y - Y_ref) / mean(Y_ref),
the luminance error against the same mode with ``--ref-slices`` aligned slices (whose own terraces
have 8x the frequency in k, orthogonal to the one measured). In tiles of 32 x 32 pixels (cloud pixels
with a total optical depth > 2 only), the first Fourier coefficient of r in the slab phase,
c1 = mean(r exp(2 pi i k)), is the terraces' amplitude there; the banding energy is the mean over
tiles of 2 |c1|^2 - 2 var(r) / n (n pixels in the tile: incoherent grain, which has no preferred slab
phase, contributes var(r) / n to |c1|^2 and is subtracted), in units of (mean luminance)^2. The table
also gives the RMS of r (terraces and grain together), and the frame time (median of 3 frames).

Saves, under --out (not committed): the crop of the tile with the strongest terraces (aligned slabs,
offsets, reference), 3x enlarged, and the full frames, all at the reference's exposure.
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

import weather_mi as wm
from weather_mi.io.image import auto_exposure, write_png
from weather_mi.slicing import MODES, SliceParams, SliceRenderer
from weather_mi.slicing.geometry import slice_geometry
from weather_mi.study.regions import eye_surface

TILE = 32


def surface_slice_index(r: SliceRenderer, spec, slices: int):
    """(k, tau_total): the slice index (of a ``slices``-plane geometry) where the eye ray's optical depth
    reaches 1 (``study.regions.eye_surface``; 0 where it does not), and the ray's total optical depth
    through the slicing box, both (H, W)."""
    g = slice_geometry(spec.camera.forward, spec.sun.to_sun, r.box, slices)
    p1, tau = eye_surface(r, spec)
    k = g.slice_of(p1.reshape(-1, 3) @ g.axis).reshape(tau.shape)
    return np.where(np.isfinite(k), k, 0.0), tau


def luminance(rgb):
    return rgb @ np.array([0.2126, 0.7152, 0.0722])


def banding(img, ref, k, mask):
    """(banding energy, RMS error, the tile (y, x) with the strongest terraces) as in the docstring."""
    y_ref = luminance(ref)
    r = (luminance(img) - y_ref) / float(y_ref[mask].mean())
    phase = np.exp(2j * np.pi * k)
    energies, best = [], (-1.0, (0, 0))
    H, W = mask.shape
    for y0 in range(0, H - TILE + 1, TILE):
        for x0 in range(0, W - TILE + 1, TILE):
            m = mask[y0:y0 + TILE, x0:x0 + TILE]
            n = int(m.sum())
            if n < TILE * TILE // 4:
                continue
            rr = r[y0:y0 + TILE, x0:x0 + TILE][m]
            c1 = np.mean(rr * phase[y0:y0 + TILE, x0:x0 + TILE][m])
            e = 2.0 * abs(c1) ** 2 - 2.0 * float(np.var(rr)) / n
            energies.append(e)
            if e > best[0]:
                best = (e, (y0, x0))
    return float(np.mean(energies)), float(np.sqrt(np.mean(r[mask] ** 2))), best[1]


def timed_frame(r, spec, params, frames=3):
    r.frame(spec, params)  # warm-up (compiles)
    t = []
    for i in range(frames):
        t0 = time.perf_counter()
        img = r.frame(spec, params)
        t.append(time.perf_counter() - t0)
    return img.radiance, statistics.median(t)


def crop(rgb, y0, x0, scale=3):
    c = rgb[max(y0 - TILE, 0):y0 + 2 * TILE, max(x0 - TILE, 0):x0 + 2 * TILE]
    return np.repeat(np.repeat(c, scale, axis=0), scale, axis=1)


def run_mode(vol, name, spec, slices, ref_slices, out: Path):
    mode = MODES[name]
    rows, images = [], {}
    ref_r = SliceRenderer(vol, mode, slices=ref_slices)
    ref = ref_r.frame(spec).radiance
    k, tau = surface_slice_index(ref_r, spec, slices)
    mask = tau > 2.0
    configs = [(f"aligned, {slices} slices", slices, 0.0), (f"offsets, {slices} slices", slices, 1.0),
               (f"aligned, {2 * slices} slices", 2 * slices, 0.0)]
    renderers = {}
    for label, n, jitter in configs:
        r = renderers.get(n) or renderers.setdefault(n, SliceRenderer(vol, mode, slices=n))
        img, seconds = timed_frame(r, spec, SliceParams(slab_jitter=jitter))
        images[label] = img
        rows.append((label, *banding(img, ref, k, mask), seconds))
    base_e, base_t = rows[0][1], rows[0][4]
    print(f"\n{name}: {spec.width} x {spec.height}, reference {ref_slices} aligned slices, "
          f"{int(mask.sum())} cloud pixels")
    print(f"{'render':<26}{'banding':>10}{'vs aligned':>12}{'RMS err':>9}{'frame (s)':>11}{'time ratio':>12}")
    for label, e, rms, _, seconds in rows:
        ratio = f"{base_e / e:>11.1f}x" if e > 1e-3 * base_e else f"{'> 1000':>11}x"  # e < 0: grain only
        print(f"{label:<26}{e:>10.2e}{ratio}{rms:>9.4f}{seconds:>11.3f}"
              f"{seconds / base_t:>11.2f}x")
    exposure = auto_exposure(ref)
    y0, x0 = rows[0][3]
    crop_exposure = auto_exposure(crop(ref, y0, x0), 99.9)  # the lit faces unclipped
    tag = name.replace("/", "_")
    for label, img in images.items():
        slug = label.replace(", ", "_").replace(" ", "")
        write_png(out / f"{tag}_{slug}_crop.png", crop(img, y0, x0), crop_exposure)
        write_png(out / f"{tag}_{slug}.png", img, exposure)
    write_png(out / f"{tag}_reference_crop.png", crop(ref, y0, x0), crop_exposure)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="640x480")
    ap.add_argument("--slices", type=int, default=128)
    ap.add_argument("--ref-slices", type=int, default=1024)
    ap.add_argument("--modes", default="per-species/multiple,per-species/translucent")
    ap.add_argument("--out", default="out/banding")
    ap.add_argument("--variant", default=None)
    args = ap.parse_args()
    variant = wm.set_variant(args.variant)
    width, height = (int(v) for v in args.size.lower().split("x"))
    vol = wm.optical_volume(wm.synthetic.supercell(), species="physical")
    spec = wm.scene.spec.default_spec(vol, width, height)
    print(f"variant {variant}; demo supercell {vol.shape}; banding energy in (mean luminance)^2 (see docstring)")
    for name in args.modes.split(","):
        run_mode(vol, name, spec, args.slices, args.ref_slices, Path(args.out))


if __name__ == "__main__":
    main()
