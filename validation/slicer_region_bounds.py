"""What a perfect model of one region of the picture would gain: the held-out CIEDE2000 / FLIP over cloud
pixels of the slicer's "multiple" model with one region's pixels (weather_mi/study/regions.py) replaced by the
path-traced reference's, per view and as the median / worst over the views.

    .venv/bin/python validation/slicer_region_bounds.py [-o out/slicer_calibration] [--views held-out|train|all]
        [--params fitted.json] [--target-rse 0.02] [--max-seconds 300] [--size 64x48] [--slices 128]
        [--supersample 2] [--slab-jitter 1]

References: validation/calibrate_slicer.py's (the same cache folder and file names). An upper bound on the
gain of improving the light model where a region is, e.g. whether the ground in cloud shadow is worth a term
of its own (issue 41).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from validation.calibrate_slicer import reference  # noqa: E402
from validation.slicer_residuals import add_view_options, view_setup  # noqa: E402
from weather_mi.display import metrics  # noqa: E402
from weather_mi.slicing import MODES, SliceRenderer  # noqa: E402
from weather_mi.study.regions import pixel_regions  # noqa: E402
from weather_mi.study.runs import eye_transmittance, load_scene, view  # noqa: E402

# the regions replaced together (a row each); "none": the model as it is
SETS = {"none": (), "ground in shadow": ("ground in shadow",), "back-lit rim": ("back-lit rim",),
        "back-lit core": ("back-lit core",), "shaded face + cloud base": ("shaded face", "cloud base"),
        "sunlit face": ("sunlit face",), "thin edge": ("thin edge",), "ice anvil": ("ice anvil",)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_view_options(ap, "held-out")
    args = ap.parse_args(argv)
    out, cfg, params, names = view_setup(args)
    params = params.updated(slab_jitter=args.slab_jitter)
    rows = {k: [] for k in SETS}
    vols, renderers = {}, {}
    for scene, lighting in names:
        if scene not in vols:
            loaded = load_scene(scene, cfg, data_dir=args.data)
            vols[scene] = None if loaded is None else loaded[0]
        if vols[scene] is None:
            print(f"{scene}: data absent, skipped")
            continue
        vol = vols[scene]
        if scene not in renderers:  # one per storm: its lightings reuse textures and kernels
            renderers[scene] = SliceRenderer(vol, MODES["per-species/multiple"], slices=args.slices)
        r = renderers[scene]
        spec = view(vol, lighting, cfg)
        ref = reference(out, scene, lighting, vol, spec, 128, args.target_rse, args.max_seconds).radiance
        mask = metrics.cloud_mask(eye_transmittance(vol, spec, 128))
        img = r.frame(spec, params, supersample=args.supersample).radiance
        regions = pixel_regions(r, spec)
        cells = []
        for key, members in SETS.items():
            perfect = img.copy()
            for n in members:
                perfect[regions[n]] = ref[regions[n]]
            m = metrics.compare(ref, perfect, mask=mask if mask.any() else "all")
            rows[key].append((m["ciede2000"], m["flip"]))
            px = sum(int(np.count_nonzero(regions[n] & mask)) for n in members)
            cells.append(f"{m['ciede2000']:.2f} / {m['flip']:.3f} ({px})")
        print(f"| {scene} {lighting} | " + " | ".join(cells) + " |", flush=True)
    print("\n| region made perfect | median CIEDE2000 / FLIP | worst CIEDE2000 |\n|---|---|---|")
    for key, v in rows.items():
        a = np.array(v).reshape(-1, 2)
        if len(a):
            print(f"| {key} | {np.median(a[:, 0]):.2f} / {np.median(a[:, 1]):.3f} | {a[:, 0].max():.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
