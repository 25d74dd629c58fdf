"""The viewer's path-traced reference with the air (issue 38): how noisy its sky and its cloud are after the same
seconds, and the page's A-vs-B line, for the passes past the first estimate over the cloud pixels only
(``target_pixels="cloud"``, the renderer's default) against every pixel ("all", the viewer's).

    nice -n 5 .venv/bin/python benchmarks/viewer_reference_noise.py [--demo supercell] [--seconds 45] [--rounds 2]
                                                                    [--size 320x240] [--atmosphere clear]

The viewer's first view (``serve.prepare``) and its reference as ``ReferenceJob`` renders it (``with_air``: the air
in the box in the medium, the eye rays' air outside it; 2 spp first, then passes to cloud RSE 0.02 or
``--seconds``), rendered here in this process, the two settings alternating within each round (paired: the same
machine state). Per render: passes and spp of the cloud pixels and of the others, the mean relative standard error
over the cloud pixels (eye-ray transmittance < 1/2, the page's "cloud RSE"), the top quarter's pixel-to-pixel
noise ("top sky noise", from the picture alone) and over the other pixels (sky and
ground, "sky RSE"; and their RMS standard error over their mean radiance, which counts the rare bright samples
that a mean of per-pixel ratios estimated from two passes misses), and the page's A-vs-B line (``display.metrics.compare`` of the slicer's refined frame against
the reference over the cloud pixels, transmittance < 0.99) against the raw reference and its denoised radiance.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

SETTINGS = ("cloud", "all")


def reference(recipe, spec, seconds: float, target_pixels: str):
    """The viewer's reference of ``spec`` (``ReferenceJob``'s defaults but in this process) after ``seconds``."""
    from weather_mi.reference.render import render_reference
    from weather_mi.viewer.reference_job import with_air
    vol, seen = with_air(recipe, None, spec)
    t0, c0 = time.perf_counter(), time.process_time()
    img = render_reference(spec, vol, 2, progress=False, target_rse=0.02, max_seconds=seconds,
                           target_pixels=target_pixels)
    return seen(img), time.perf_counter() - t0, time.process_time() - c0


def neighbour_noise(radiance, clear) -> float:
    """The noise of the top quarter of the picture (a smooth sky) without any standard error: the standard deviation
    of the luminance difference between horizontal neighbours that are both clear (not cloud) over sqrt(2), over
    their mean luminance (the sky's own gradient across one pixel is far below its noise)."""
    y = np.asarray(radiance, np.float64).mean(axis=2)
    top = slice(0, y.shape[0] // 4)
    both = clear[top, 1:] & clear[top, :-1]
    d = (y[top, 1:] - y[top, :-1])[both]
    return float(d.std() / np.sqrt(2) / y[top][clear[top]].mean()) if d.size else float("nan")


def figures(img, frame) -> dict:
    from weather_mi.display.denoise import denoise_radiance
    from weather_mi.display.metrics import compare
    from weather_mi.reference.estimates import noise_stats
    cloud = img.transmittance < 0.5
    m = img.metadata
    sky = noise_stats(img.radiance, img.stderr, ~cloud)
    out = {"passes": m["passes"], "spp cloud": m["spp"], "spp other": m["spp_background"],
           "cloud RSE": noise_stats(img.radiance, img.stderr, cloud)["rse_mean"],
           "sky RSE": sky["rse_mean"], "sky RMS se / mean": sky["rms_se_over_mean"],
           "top sky noise": neighbour_noise(img.radiance, ~cloud)}
    for name, ref in (("raw", img), ("denoised", denoise_radiance(np.nan_to_num(img.radiance)))):
        c = compare(ref, frame.radiance, mask="cloud", transmittance=frame.transmittance, exposure=frame.exposure)
        out[f"CIEDE2000 {name}"], out[f"FLIP {name}"] = c["ciede2000"], c["flip"]
        if name == "raw":
            out["noise floor"] = c["noise_floor"]
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--demo", default="supercell")
    ap.add_argument("--seconds", type=float, default=45.0, help="rendering seconds of each reference")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--size", default="320x240")
    ap.add_argument("--atmosphere", default="clear", choices=("none", "clear"))
    ap.add_argument("--save", default=None, help="folder for each render's PNG (the page's B view)")
    args = ap.parse_args()
    from weather_mi.io.image import to_srgb8
    from weather_mi.viewer.frames import FrameLoop
    from weather_mi.viewer.recipe import VolumeRecipe
    from weather_mi.viewer.serve import prepare
    w, h = (int(v) for v in args.size.split("x"))
    recipe = VolumeRecipe(demo=args.demo)
    storm, state = prepare(recipe, progress=lambda *a: None, size=(w, h), warm=False,
                           air={"atmosphere": args.atmosphere})
    loop = FrameLoop(storm, publish=lambda f: None)
    try:
        frame = loop.render(state)
    finally:
        loop.stop()
    spec = state.spec(storm.frame, storm.ground_m)
    rows = {s: [] for s in SETTINGS}
    for r in range(args.rounds):
        for s in (SETTINGS if r % 2 == 0 else SETTINGS[::-1]):
            img, wall, cpu = reference(recipe, spec, args.seconds, s)
            f = figures(img, frame)
            f["seconds"], f["wall s"] = img.metadata["seconds"], wall
            f["CPU s / pass"] = cpu / img.metadata["passes"]  # the process's, scene build and compile included
            rows[s].append(f)
            print(f"round {r + 1}, target_pixels={s}: " + ", ".join(
                f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}" for k, v in f.items()), flush=True)
            if args.save:
                out = Path(args.save)
                out.mkdir(parents=True, exist_ok=True)
                from PIL import Image as PILImage
                PILImage.fromarray(to_srgb8(img.radiance, frame.exposure)).save(out / f"b_{s}_round{r + 1}.png")
    print(f"\n{args.demo} {w}x{h}, --atmosphere {args.atmosphere}, {args.seconds:g} s of rendering, "
          f"{args.rounds} rounds (medians)")
    keys = list(rows[SETTINGS[0]][0])
    print("| target_pixels | " + " | ".join(keys) + " |")
    print("|" + "---|" * (len(keys) + 1))
    for s in SETTINGS:
        print(f"| {s} | " + " | ".join(f"{statistics.median(f[k] for f in rows[s]):.3g}" for k in keys) + " |")


if __name__ == "__main__":
    main()
