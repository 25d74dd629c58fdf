"""Where the slicer's error at a low sun comes from (issue 38 part 3): the views of
``validation/slicer_low_sun.py`` (the held-out storms, the sun at --elevation, with the clear atmosphere and
without it, the same cached references), residuals by region of the picture (``study.regions``: sunlit and
shaded faces, bases, thin edges, back-lit rims and cores, the ground) and, over the whole cloud, the colour
apart from the lightness.

Per view, atmosphere and slicer variant, pooled over the views: per region the luminance bias (> 0: the slicer
brighter), CIEDE2000, CIEDE2000 at equal lightness (the slicer's region scaled to the reference's mean
luminance there: what is left is colour), and the slicer's channel means over the reference's (R, G, B each
divided by the luminance ratio: > 1 in R and < 1 in B is too red). Variants (--variants, SliceParams fields
``name=value``, ';' between variants): the light model's terms switched off one at a time, to see which one
holds the error.

    python validation/slicer_low_sun_residuals.py [--data ../shared/data] [--elevation 6] [--lightings front,side]
        [--scenes ...] [--out validation-low-sun] [--target-rse 0.03] [--variants "ms_contribution=0;..."]
        [--fitted fitted.json]
"""
from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from validation.calibrate_slicer import read_fitted  # noqa: E402
from validation.slicer_low_sun import DEFAULT_DATA, reference, storm  # noqa: E402
from weather_mi.display import metrics  # noqa: E402
from weather_mi.io.image import auto_exposure  # noqa: E402
from weather_mi.optics.air import Atmosphere  # noqa: E402
from weather_mi.slicing import MODES, SliceParams, SliceRenderer  # noqa: E402
from weather_mi.study.regions import pixel_regions  # noqa: E402
from weather_mi.study.runs import DATA_SCENES, StudyConfig, eye_transmittance, low_sun_view  # noqa: E402

LUMA = np.array([0.2126, 0.7152, 0.0722])


def colour_rows(ref: np.ndarray, img: np.ndarray, regions: dict) -> dict:
    """{region: (pixels, bias, CIEDE2000, CIEDE2000 at equal lightness, (R, G, B) ratio at equal luminance)}."""
    e = auto_exposure(ref)
    lab_r = metrics.display_lab(metrics.display_srgb(ref, e))
    de = metrics.ciede2000_map(lab_r, metrics.display_lab(metrics.display_srgb(img, e)))
    out = {}
    for name, m in regions.items():
        n = int(np.count_nonzero(m))
        if n == 0:
            continue
        y_ref, y_img = float((ref[m] @ LUMA).mean()), float((img[m] @ LUMA).mean())
        k = y_ref / max(y_img, 1e-30)
        de_eq = metrics.ciede2000_map(lab_r, metrics.display_lab(metrics.display_srgb(img * k, e)))
        rgb = img[m].mean(axis=0) * k / np.maximum(ref[m].mean(axis=0), 1e-30)
        out[name] = (n, y_img / max(y_ref, 1e-30) - 1.0, float(de[m].mean()), float(de_eq[m].mean()), rgb)
    return out


def pool(rows: list[dict]) -> dict:
    """Pixel-weighted means over views per region."""
    out = {}
    for name in sorted({k for r in rows for k in r}):
        rs = [r[name] for r in rows if name in r]
        w = np.array([x[0] for x in rs], float)
        w /= w.sum()
        out[name] = (int(sum(x[0] for x in rs)), *(float(np.sum(w * [x[i] for x in rs])) for i in (1, 2, 3)),
                     np.sum(w[:, None] * np.array([x[4] for x in rs]), axis=0))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(DEFAULT_DATA))
    ap.add_argument("--size", default="64x48")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--target-rse", type=float, default=0.03)
    ap.add_argument("--max-seconds", type=float, default=150.0)
    ap.add_argument("--elevation", type=float, default=6.0)
    ap.add_argument("--scenes", default="wrf-supercell,wrf-plateau,bomex,rico")
    ap.add_argument("--lightings", default="front,side")
    ap.add_argument("--out", default="validation-low-sun", help="the references' cache (slicer_low_sun.py's --out)")
    ap.add_argument("--fitted", default=None, help="a fitted.json (default: the shipped defaults)")
    ap.add_argument("--variants", default="", help="';'-separated SliceParams overrides, e.g. 'ms_contribution=0'")
    args = ap.parse_args(argv)
    width, height = (int(v) for v in args.size.split("x"))
    cfg = replace(StudyConfig(), width=width, height=height)
    base = SliceParams(slab_jitter=1.0)
    if args.fitted:
        base = base.updated(**read_fitted(Path(args.fitted)))
    variants = {"defaults": base}
    for v in filter(None, args.variants.split(";")):
        variants[v] = base.updated(**{k: float(x) for k, x in (kv.split("=") for kv in v.split(","))})
    rows = {(label, name): [] for label in ("clear", "none") for name in variants}
    whole = {(label, name): [] for label in ("clear", "none") for name in variants}
    for scene in args.scenes.split(","):
        if not (Path(args.data) / DATA_SCENES[scene][0]).is_file():
            continue
        hyd, vol = storm(scene, Path(args.data), cfg)
        r = SliceRenderer(vol, MODES["per-species/multiple"], slices=128)
        for lighting in args.lightings.split(","):
            for label, atm in (("clear", Atmosphere()), ("none", None)):
                spec = low_sun_view(vol, lighting, cfg, args.elevation, atm)
                tag = f"{scene}_{lighting}_{args.elevation:g}deg_{label}"
                ref = reference(Path(args.out), tag, spec, vol, hyd, args.spp, args.target_rse, args.max_seconds)
                mask = metrics.cloud_mask(eye_transmittance(vol, spec, 128))
                for name, params in variants.items():
                    img = r.frame(spec, params, supersample=2).radiance
                    regions = pixel_regions(r, spec)
                    regions = {k: m & mask for k, m in regions.items() if not k.startswith("ground")}
                    rows[(label, name)].append(colour_rows(ref.radiance, img, regions))
                    w = colour_rows(ref.radiance, img, {"cloud": mask})["cloud"]
                    whole[(label, name)].append(w)
                    print(f"{scene:<14}{lighting:<6}{label:<6}{name:<28} cloud: bias {w[1]:+.3f} dE {w[2]:.2f} "
                          f"dE(equal L) {w[3]:.2f} rgb/ref {np.round(w[4], 3)}", flush=True)
    for (label, name), rs in rows.items():
        print(f"\n{label} atmosphere, {name}: by region, pooled over {len(rs)} views")
        print(f"{'region':<16}{'pixels':>7}{'bias':>8}{'dE':>7}{'dE(eqL)':>8}   rgb/ref at equal luminance")
        for reg, (n, b, de, deq, rgb) in {**pool(rs), **{"(whole cloud)": pool([{'c': w} for w in whole[(label, name)]])['c']}}.items():
            print(f"{reg:<16}{n:>7}{b:>+8.3f}{de:>7.2f}{deq:>8.2f}   {np.round(rgb, 3)}")
        des = [w[2] for w in whole[(label, name)]]
        print(f"median CIEDE2000 over views {np.median(des):.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
