"""Residuals of the slicer against path-traced references, by region of the picture (back-lit rims and cores,
sunlit faces, shaded faces, cloud bases, thin edges, ice anvils, the ground in and out of cloud shadow;
weather_mi/study/regions.py).

    .venv/bin/python validation/slicer_residuals.py [-o out/slicer_calibration] [--views train|held-out|all]
        [--lightings front,side,back]
        [--target-rse 0.02] [--max-seconds 300] [--size 64x48] [--slices 128] [--params fitted.json]
        [--modes per-species/multiple,per-species/translucent] [--supersample 2] [--slab-jitter 1]

References: the views of validation/calibrate_slicer.py (the same cache folder and file names), rendered
to --target-rse (mean relative standard error over cloud pixels) or --max-seconds each. Prints, per mode
and region, pooled over the views: pixels, bias (mean signed luminance error / the reference's mean
luminance there; > 0: the slicer is brighter), relative RMS luminance error and mean CIEDE2000; then the
views' own worst regions. --params: a JSON of SliceParams fields for the "multiple" model (default: the
shipped defaults). --lightings: only the views of these lightings (e.g. back). --supersample / --slab-jitter: the frames as validation/calibrate_slicer.py renders them
(each pixel the mean of n x n points with slab jitter; 1 and 0: pixel centres, aligned slabs).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from validation.calibrate_slicer import DEFAULT_DATA, HELD_OUT, TRAIN, read_fitted, reference  # noqa: E402
from weather_mi.slicing import MODES, SliceParams, SliceRenderer  # noqa: E402
from weather_mi.study.regions import REGIONS, pixel_regions, region_residuals  # noqa: E402
from weather_mi.study.runs import StudyConfig, load_scene, view  # noqa: E402


def pooled(rows_per_view):
    """Pixel-weighted means of bias, relative RMS (as RMS) and CIEDE2000 per region over views."""
    out = {}
    for name in REGIONS:
        rs = [r for rows in rows_per_view for r in rows if r["region"] == name and r["pixels"] > 0]
        n = sum(r["pixels"] for r in rs)
        if n == 0:
            out[name] = (0, np.nan, np.nan, np.nan)
            continue
        w = np.array([r["pixels"] for r in rs], dtype=np.float64) / n
        out[name] = (n, float(np.sum(w * [r["bias"] for r in rs])),
                     float(np.sqrt(np.sum(w * np.square([r["rel_rms"] for r in rs])))),
                     float(np.sum(w * [r["ciede2000"] for r in rs])))
    return out


def add_view_options(ap, views: str) -> None:
    """The options the residual scripts share: output folder, data, views, references, frame size and slicing."""
    ap.add_argument("-o", "--output", default="out/slicer_calibration")
    ap.add_argument("--data", default=str(DEFAULT_DATA))
    ap.add_argument("--views", default=views, choices=("train", "held-out", "all"))
    ap.add_argument("--params", default=None, help="a fitted.json (default: the shipped defaults)")
    ap.add_argument("--target-rse", type=float, default=0.02)
    ap.add_argument("--max-seconds", type=float, default=300.0)
    ap.add_argument("--size", default="64x48")
    ap.add_argument("--slices", type=int, default=128)
    ap.add_argument("--supersample", type=int, default=2)
    ap.add_argument("--slab-jitter", type=float, default=1.0)


def view_setup(args):
    """(output folder (made), StudyConfig of --size, the fitted or default SliceParams, the views' names)."""
    width, height = (int(v) for v in args.size.lower().split("x"))
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    cfg = StudyConfig(width=width, height=height, phase_quality="test")
    params = SliceParams() if args.params is None else SliceParams().updated(**read_fitted(Path(args.params)))
    names = {"train": TRAIN, "held-out": HELD_OUT, "all": TRAIN + HELD_OUT}[args.views]
    return out, cfg, params, names


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_view_options(ap, "train")
    ap.add_argument("--lightings", default="front,side,back", help="only the views of these lightings")
    ap.add_argument("--modes", default="per-species/multiple,per-species/translucent")
    args = ap.parse_args(argv)
    out, cfg, fitted, names = view_setup(args)
    names = [(s, l) for s, l in names if l in args.lightings.split(",")]
    modes = args.modes.split(",")
    per_mode = {m: [] for m in modes}
    worst = []
    vols, renderers = {}, {}
    for scene, lighting in names:
        if scene not in vols:
            vols[scene] = load_scene(scene, cfg, data_dir=args.data)
        if vols[scene] is None:
            print(f"{scene}: data absent, skipped")
            continue
        vol = vols[scene][0]
        spec = view(vol, lighting, cfg)
        ref = reference(out, scene, lighting, vol, spec, 128, args.target_rse, args.max_seconds).radiance
        for m in modes:
            if (scene, m) not in renderers:  # one per storm and mode: its lightings reuse textures and kernels
                renderers[(scene, m)] = SliceRenderer(vol, MODES[m], slices=args.slices)
            r = renderers[(scene, m)]
            params = fitted if MODES[m].light == "multiple" else SliceParams()
            img = r.frame(spec, params.updated(slab_jitter=args.slab_jitter), supersample=args.supersample).radiance
            rows = region_residuals(ref, img, pixel_regions(r, spec))
            per_mode[m].append(rows)
            big = max((x for x in rows if x["pixels"] >= 20), key=lambda x: x["ciede2000"], default=None)
            if big is not None:
                worst.append((m, scene, lighting, big))
    for m in modes:
        print(f"\n{m}: residuals by region, pooled over {len(per_mode[m])} views ({args.size}, {args.slices} slices)")
        print(f"{'region':<18}{'pixels':>8}{'bias':>9}{'rel RMS':>9}{'CIEDE2000':>11}")
        for name, (n, bias, rms, de) in pooled(per_mode[m]).items():
            print(f"{name:<18}{n:>8}{bias:>+9.3f}{rms:>9.3f}{de:>11.2f}")
    print("\nworst region per view (at least 20 pixels)")
    for m, scene, lighting, x in worst:
        print(f"{m:<24}{scene:<20}{lighting:<7}{x['region']:<18}{x['pixels']:>6}{x['bias']:>+9.3f}{x['ciede2000']:>8.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
