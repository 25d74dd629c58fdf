"""Issue 38 part 2: how far the RGB mode's colours are from the spectral ground truth, and what the spectral
mode costs, on the validation study's views (``study.runs.view``) at three sun elevations.

    .venv/bin/python validation/spectral_vs_rgb.py [--size 64x48] [--spp 1024] [--passes 8] [--elevations 60,20,4]
        [--scenes demo-supercell] [--lightings front,side] [--atmosphere clear] [--checkpoint DIR]

Per view and sun elevation: the spectral mode (``llvm_ad_spectral``: 4 wavelengths a path, the species' phase
tables every 25 nm, ``optics.phase.spectral_tables``, the film's CIE XYZ as linear sRGB through colour-science)
and the RGB mode (``llvm_ad_rgb``: the three channels as single wavelengths 650 / 550 / 450 nm) render the same
scene (the study's camera, Hosek-Wilkie sky, ground; the sun's colour after ``--atmosphere``), the spectral mode
twice with independent seeds (A, B); then over the cloud pixels (eye-ray transmittance of A < 1/2), with one
display exposure for all (A's):

* dE RGB: mean and 95th percentile of the per-pixel CIEDE2000 of the RGB image against the mean of A and B
  (the spectral reference at twice the samples), and against A alone;
* dE noise (the noise floor): the same between A and B, the part of a difference that is only noise (an
  upper bound of the noise in "RGB against A", whose RGB image is no noisier than B);
* the same two over 4 x 4 pixel blocks (radiance averaged; cloud blocks: A's mean transmittance < 1/2), and
  between the cloud's mean colours (all cloud pixels averaged: what is left there is the modes' systematic
  difference in the cloud's overall colour);
* the cloud's mean colour of the RGB mode against A and against B alone (a firefly in one spectral render
  moves the A+B mean and the noise figure, not both of these);
* lit dE: CIEDE2000 at equal lightness between the two modes' lit-cloud chromaticities (the brightest 10%
  of the opaque cloud pixels, ``display.cloud_colour``, chosen on B), and its noise part (A against B);
* ms/spp (each mode's seconds per sample per pixel, kernels compiled beforehand) and the spectral mode's
  cost to the same luminance noise: (time x RSE^2) spectral / RGB, from A and the RGB render.

Every render is kept in ``--checkpoint`` (one .npz per view, mode and seed, named by the run's parameters), so
an interrupted run resumes where it stopped and the figures can be recomputed without rendering.
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
CLOUD_T = 0.5  # eye-ray transmittance below which a pixel is cloud
BIN = 4  # pixels per side of the blocks of the block figures (their noise is a quarter of a pixel's)


def render(spec, vol, variant: str, spp: int, passes: int, seed: int = 0) -> dict:
    """One render of ``spec`` in ``variant`` (its kernels compiled beforehand): radiance, transmittance,
    rse (the luminance RSE over cloud pixels) and seconds."""
    from weather_mi.reference.estimates import luminance_rse
    from weather_mi.reference.render import render_reference
    means = []
    t = time.perf_counter()
    img = render_reference(replace(spec, seed=seed), vol, spp=spp, passes=passes, progress=False, variant=variant,
                           on_pass=lambda im: means.append(np.asarray(im.radiance, np.float64).copy()))
    secs = time.perf_counter() - t
    trans = np.asarray(img.transmittance)
    return {"radiance": np.asarray(img.radiance, np.float64), "transmittance": trans,
            "rse": luminance_rse(means, trans < CLOUD_T) if passes > 1 else float("nan"), "seconds": secs}


def checkpointed(path: Path, make) -> dict:
    """The render stored at ``path``, else ``make()`` stored there (atomically) first."""
    if path.is_file():
        with np.load(path) as d:
            return {k: (d[k] if d[k].ndim else float(d[k])) for k in d.files}
    out = make()
    tmp = path.with_suffix(".tmp.npz")
    np.savez(tmp, **out)
    tmp.replace(path)
    return out


def lit_xy(radiance, mask):
    from weather_mi.display.cloud_colour import xy_of_linear_srgb
    return xy_of_linear_srgb(radiance[mask].mean(axis=0))


def delta_e(ref, other, exposure: float, mask) -> tuple[float, float]:
    """(mean, 95th percentile) of the per-pixel CIEDE2000 of ``other`` against ``ref`` over ``mask``."""
    from weather_mi.display.metrics import ciede2000_map, display_lab, display_srgb
    de = ciede2000_map(display_lab(display_srgb(ref, exposure)), display_lab(display_srgb(other, exposure)))[mask]
    return float(de.mean()), float(np.percentile(de, 95))


def mean_colour_de(ref, other, exposure: float, mask) -> float:
    """CIEDE2000 between the mean linear colours of ``ref`` and ``other`` over ``mask`` (the cloud's average
    colour: its noise is that of a single pixel over the square root of the number of cloud pixels)."""
    return delta_e(ref[mask].mean(axis=0)[None, None], other[mask].mean(axis=0)[None, None], exposure,
                   np.ones((1, 1), bool))[0]


def blocks(a: np.ndarray, k: int = BIN) -> np.ndarray:
    """``a`` (H, W, ...) averaged over k x k pixel blocks."""
    h, w = (n // k * k for n in a.shape[:2])
    return a[:h, :w].reshape(h // k, k, w // k, k, *a.shape[2:]).mean(axis=(1, 3))


def figures(rgb: dict, a: dict, b: dict) -> dict:
    """The figures of one view (module docstring) from its three renders."""
    from weather_mi.display.cloud_colour import delta_e_equal_lightness, lit_cloud_pixels
    from weather_mi.display.metrics import auto_exposure
    cloud = a["transmittance"] < CLOUD_T
    ref = 0.5 * (a["radiance"] + b["radiance"])
    exposure = auto_exposure(a["radiance"])
    lit = lit_cloud_pixels(b["radiance"], b["transmittance"])
    xy_a, xy_b, xy_r = lit_xy(a["radiance"], lit), lit_xy(b["radiance"], lit), lit_xy(rgb["radiance"], lit)
    return {"pixels": int(cloud.sum()),
            "dE_rgb_ab": delta_e(ref, rgb["radiance"], exposure, cloud),
            "dE_rgb_a": delta_e(a["radiance"], rgb["radiance"], exposure, cloud),
            "dE_noise": delta_e(a["radiance"], b["radiance"], exposure, cloud),
            "dE_rgb_blocks": delta_e(blocks(ref), blocks(rgb["radiance"]), exposure, blocks(a["transmittance"]) < CLOUD_T),
            "dE_noise_blocks": delta_e(blocks(a["radiance"]), blocks(b["radiance"]), exposure,
                                       blocks(a["transmittance"]) < CLOUD_T),
            "dE_mean_colour": mean_colour_de(ref, rgb["radiance"], exposure, cloud),
            "dE_mean_colour_noise": mean_colour_de(a["radiance"], b["radiance"], exposure, cloud),
            "dE_mean_colour_ab": tuple(mean_colour_de(x["radiance"], rgb["radiance"], exposure, cloud) for x in (a, b)),
            "lit_dE": delta_e_equal_lightness(xy_r, lit_xy(ref, lit)), "lit_dE_noise": delta_e_equal_lightness(xy_b, xy_a),
            "lit_xy_spectral": lit_xy(ref, lit), "lit_xy_rgb": xy_r,
            "rse_rgb": rgb["rse"], "rse_spectral": a["rse"],
            "ms_spp_rgb": 1e3 * rgb["seconds"], "ms_spp_spectral": 1e3 * a["seconds"],
            "cost_same_rse": a["seconds"] * a["rse"] ** 2 / (rgb["seconds"] * rgb["rse"] ** 2)}


def case(spec, vol, spp: int, passes: int, stem: Path) -> dict:
    """The three renders of one view (from the checkpoint where there) and their figures."""
    compiled = set()

    def make(mode, seed):
        def go():
            if mode not in compiled:
                render(spec, vol, MODES[mode], 1, 1, seed=99)  # compile
                compiled.add(mode)
            return render(spec, vol, MODES[mode], spp, passes, seed)
        return checkpointed(Path(f"{stem}-{mode}-s{seed}.npz"), go)

    rgb, a, b = make("rgb", 0), make("spectral", 0), make("spectral", 1)
    out = figures(rgb, a, b)
    out["ms_spp_rgb"] /= spp
    out["ms_spp_spectral"] /= spp
    return out


def main(argv=None):
    from weather_mi.optics.air import Atmosphere
    from weather_mi.study.runs import CONFIGS, load_scene, view
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="64x48")
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--passes", type=int, default=8)
    ap.add_argument("--elevations", default="60,20,4")
    ap.add_argument("--scenes", default="demo-supercell")
    ap.add_argument("--lightings", default="front,side")
    ap.add_argument("--atmosphere", default="clear", choices=("none", "clear"))
    ap.add_argument("--checkpoint", default="spectral_vs_rgb_renders", help="folder of the renders (resumed from)")
    args = ap.parse_args(argv)
    folder = Path(args.checkpoint)
    folder.mkdir(parents=True, exist_ok=True)
    w, h = (int(v) for v in args.size.split("x"))
    cfg = replace(CONFIGS["quick"], width=w, height=h)
    air = Atmosphere() if args.atmosphere == "clear" else None
    print(f"RGB mode against the spectral mode: {w}x{h}, {args.spp} spp ({args.passes} passes), --atmosphere "
          f"{args.atmosphere}; cloud pixels (transmittance < {CLOUD_T:g}); dE = per-pixel CIEDE2000, mean / 95th "
          "percentile, RGB against the spectral A+B mean (and against A); noise floor = spectral A against B; lit "
          "dE = lit cloud's chromaticity at equal lightness; cost = spectral/RGB time to the same luminance RSE")
    print("| scene | lighting | sun elev | pixels | dE RGB vs A+B | dE RGB vs A | dE noise A vs B | 4x4 blocks: dE RGB vs "
          "A+B | 4x4 blocks: dE noise | mean colour: dE RGB vs A+B | its noise | RGB vs A / vs B | lit dE | lit dE noise "
          "| lit xy spectral | lit xy RGB | RSE RGB | RSE spectral | ms/spp RGB | ms/spp spectral | cost |")
    print("|---" * 21 + "|")
    for name in args.scenes.split(","):
        vol, _ = load_scene(name, cfg)
        for lighting in args.lightings.split(","):
            for elev in (float(e) for e in args.elevations.split(",")):
                spec = view(vol, lighting, cfg)
                spec = replace(spec, sun=replace(spec.sun, elevation=elev), atmosphere=air)
                stem = folder / f"{name}-{lighting}-{elev:g}-{w}x{h}-{args.spp}spp-{args.atmosphere}"
                r = case(spec, vol, args.spp, args.passes, stem)
                print(f"| {name} | {lighting} | {elev:g} | {r['pixels']} | {r['dE_rgb_ab'][0]:.2f} / {r['dE_rgb_ab'][1]:.2f} "
                      f"| {r['dE_rgb_a'][0]:.2f} / {r['dE_rgb_a'][1]:.2f} | {r['dE_noise'][0]:.2f} / {r['dE_noise'][1]:.2f} "
                      f"| {r['dE_rgb_blocks'][0]:.2f} / {r['dE_rgb_blocks'][1]:.2f} "
                      f"| {r['dE_noise_blocks'][0]:.2f} / {r['dE_noise_blocks'][1]:.2f} "
                      f"| {r['dE_mean_colour']:.2f} | {r['dE_mean_colour_noise']:.2f} "
                      f"| {r['dE_mean_colour_ab'][0]:.2f} / {r['dE_mean_colour_ab'][1]:.2f} "
                      f"| {r['lit_dE']:.2f} | {r['lit_dE_noise']:.2f} "
                      f"| ({r['lit_xy_spectral'][0]:.3f}, {r['lit_xy_spectral'][1]:.3f}) "
                      f"| ({r['lit_xy_rgb'][0]:.3f}, {r['lit_xy_rgb'][1]:.3f}) | {r['rse_rgb']:.4f} | {r['rse_spectral']:.4f} "
                      f"| {r['ms_spp_rgb']:.0f} | {r['ms_spp_spectral']:.0f} | {r['cost_same_rse']:.2f} |", flush=True)


if __name__ == "__main__":
    main()
