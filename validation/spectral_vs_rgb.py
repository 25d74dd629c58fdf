"""Issue 38 part 2: how far the RGB mode's colours are from the spectral ground truth, and what the spectral
mode costs, on the validation study's views (``study.runs.view``) at three sun elevations.

    .venv/bin/python validation/spectral_vs_rgb.py [--size 64x48] [--spp 32] [--elevations 60,20,4]
        [--scenes demo-supercell,demo-cumulus] [--lightings front,side] [--atmosphere clear]

Per view and sun elevation: the spectral mode (``llvm_ad_spectral``: 4 wavelengths a path, the film's CIE
XYZ as linear sRGB through colour-science) and the RGB mode (``llvm_ad_rgb``: the three channels as single
wavelengths 650 / 550 / 450 nm) render the same scene (the study's camera, Hosek-Wilkie sky, ground; the
sun's colour after ``--atmosphere``); then over the cloud pixels (eye-ray transmittance < 1/2):

* dE RGB: mean CIEDE2000 of the RGB image against the spectral one over 4 x 4 pixel blocks (cloud blocks:
  mean transmittance < 1/2; ``display.metrics.compare``, one exposure for both), and dE noise: the same
  between two spectral renders of other seeds (the part of dE RGB that is only noise);
* lit dE: CIEDE2000 at equal lightness between the two modes' lit-cloud chromaticities (the brightest 10%
  of the opaque cloud pixels, ``display.cloud_colour``, chosen on a third, independent render), and its
  noise part (the same between the two spectral renders);
* ms/spp (each mode's seconds per sample per pixel, kernels compiled beforehand) and the spectral mode's
  cost to the same luminance noise: (time x RSE^2) spectral / RGB.
"""
from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

MODES = {"rgb": "llvm_ad_rgb", "spectral": "llvm_ad_spectral"}
BIN = 4  # pixels per side of the blocks over which colours are compared (the noise of single pixels hides dE)


def render(spec, vol, variant: str, spp: int, seed: int = 0):
    """(Image, seconds) of one render of ``spec`` in ``variant`` (its kernels compiled beforehand)."""
    from weather_mi.reference.render import render_reference
    t = time.perf_counter()
    img = render_reference(replace(spec, seed=seed), vol, spp=spp, passes=4, progress=False, variant=variant)
    return img, time.perf_counter() - t


def lit_xy(img, mask):
    from weather_mi.display.cloud_colour import xy_of_linear_srgb
    return xy_of_linear_srgb(img.radiance[mask].mean(axis=0))


def rse(img) -> float:
    noise = img.metadata.get("noise") or {}
    return float(noise.get("rse_mean", float("nan")))


def binned(img, k: int = BIN):
    """(radiance averaged over k x k blocks, the blocks' mean eye-ray transmittance)."""
    h, w = (n // k * k for n in img.radiance.shape[:2])
    rad = img.radiance[:h, :w].reshape(h // k, k, w // k, k, 3).mean(axis=(1, 3))
    return rad, img.transmittance[:h, :w].reshape(h // k, k, w // k, k).mean(axis=(1, 3))


def case(spec, vol, spp: int) -> dict:
    """The figures of one view (module docstring)."""
    from weather_mi.display.cloud_colour import delta_e_equal_lightness, lit_cloud_pixels
    from weather_mi.display.metrics import compare
    imgs, secs = {}, {}
    for mode, variant in MODES.items():
        render(spec, vol, variant, 1, seed=99)  # compile
        imgs[mode], secs[mode] = render(spec, vol, variant, spp)
    other, _ = render(spec, vol, MODES["spectral"], spp, seed=1)
    ref = imgs["spectral"]
    (ref_b, t_b), (rgb_b, _), (other_b, _) = binned(ref), binned(imgs["rgb"]), binned(other)
    cloud = t_b < 0.5
    rgb = compare(ref_b, rgb_b, mask=cloud)
    noise = compare(ref_b, other_b, exposure=rgb["exposure"], mask=cloud)
    # the lit cloud chosen on an independent render: choosing on the image measured picks the pixels whose
    # noise is bright, and a spectral image's noise is coloured (4 wavelengths a path)
    lit = lit_cloud_pixels(other.radiance, other.transmittance)
    xy_s, xy_r = lit_xy(ref, lit), lit_xy(imgs["rgb"], lit)
    eff = secs["spectral"] * rse(ref) ** 2 / (secs["rgb"] * rse(imgs["rgb"]) ** 2)
    return {"dE_rgb": rgb["ciede2000"], "dE_noise": noise["ciede2000"], "pixels": rgb["n_pixels"],
            "lit_dE": delta_e_equal_lightness(xy_r, xy_s), "lit_dE_noise": delta_e_equal_lightness(lit_xy(other, lit), xy_s),
            "lit_xy_spectral": xy_s, "lit_xy_rgb": xy_r,
            "ms_spp_rgb": 1e3 * secs["rgb"] / spp, "ms_spp_spectral": 1e3 * secs["spectral"] / spp,
            "cost_same_rse": eff}


def main(argv=None):
    from weather_mi.optics.air import Atmosphere
    from weather_mi.study.runs import CONFIGS, load_scene, view
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="64x48")
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--elevations", default="60,20,4")
    ap.add_argument("--scenes", default="demo-supercell,demo-cumulus")
    ap.add_argument("--lightings", default="front,side")
    ap.add_argument("--atmosphere", default="clear", choices=("none", "clear"))
    args = ap.parse_args(argv)
    w, h = (int(v) for v in args.size.split("x"))
    cfg = replace(CONFIGS["quick"], width=w, height=h)
    air = Atmosphere() if args.atmosphere == "clear" else None
    print(f"RGB mode against the spectral mode: {w}x{h}, {args.spp} spp, --atmosphere {args.atmosphere}; cloud "
          "pixels (transmittance < 1/2); dE = mean CIEDE2000 (noise: two spectral seeds), lit dE = lit cloud's "
          "chromaticity at equal lightness; cost = spectral/RGB time to the same luminance RSE")
    print("| scene | lighting | sun elev | dE RGB | dE noise | lit dE | lit dE noise | lit xy spectral | lit xy RGB "
          "| ms/spp RGB | ms/spp spectral | cost |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in args.scenes.split(","):
        vol, _ = load_scene(name, cfg)
        for lighting in args.lightings.split(","):
            for elev in (float(e) for e in args.elevations.split(",")):
                spec = view(vol, lighting, cfg)
                spec = replace(spec, sun=replace(spec.sun, elevation=elev), atmosphere=air)
                r = case(spec, vol, args.spp)
                print(f"| {name} | {lighting} | {elev:g} | {r['dE_rgb']:.2f} | {r['dE_noise']:.2f} | {r['lit_dE']:.2f} "
                      f"| {r['lit_dE_noise']:.2f} "
                      f"| ({r['lit_xy_spectral'][0]:.3f}, {r['lit_xy_spectral'][1]:.3f}) "
                      f"| ({r['lit_xy_rgb'][0]:.3f}, {r['lit_xy_rgb'][1]:.3f}) | {r['ms_spp_rgb']:.0f} "
                      f"| {r['ms_spp_spectral']:.0f} | {r['cost_same_rse']:.2f} |", flush=True)


if __name__ == "__main__":
    main()
