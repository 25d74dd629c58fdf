"""A grid refit of the slicer's "multiple" model on the TRAINING views of ``validation/calibrate_slicer.py`` (its
high-sun views and its low-sun views with the clear atmosphere; ``check_held_out`` refuses held-out fields): the
lit face's slope on the diffused light (``diffusion_incidence``) against one factor on the diffused light's gains
(``diffusion_gain`` and ``leak_gain`` together), the other parameters at the shipped defaults, every frame as
the evaluation renders it (128 slices, 2 x 2 points per pixel, slab jitter 1). For a machine too busy for the
reverse-mode fit (``calibrate_slicer.py --fit-only``: one iteration over the 25 training views took 747 s of wall
time at a ~15% share of a core). Prints, per grid point, the median and mean CIEDE2000 over the high-sun views,
the low-sun views and all of them, and writes the grid point with the lowest mean over all training views (the
fit's loss is a mean too; the median of all lies among the 18 high-sun views) as a
fitted.json (``calibrate_slicer.py --fitted``).

    .venv/bin/python validation/slicer_param_scan.py -o OUT [--incidence 0,0.5,1] [--gain 1,1.3,1.6]
        (OUT: the training references, as calibrate_slicer.py caches them)
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from validation.calibrate_slicer import (DEFAULT_DATA, HELD_OUT, LOW_SUN, TRAIN, check_held_out,  # noqa: E402
                                         load_views)
from weather_mi.display import metrics  # noqa: E402
from weather_mi.slicing import MODES, SliceParams, SliceRenderer  # noqa: E402
from weather_mi.slicing.calibrate import MULTIPLE_PARAMS  # noqa: E402
from weather_mi.study.runs import StudyConfig  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--data", default=str(DEFAULT_DATA))
    ap.add_argument("--incidence", default="0,0.5,1")
    ap.add_argument("--gain", default="1,1.3,1.6")
    args = ap.parse_args(argv)
    out = Path(args.output)
    check_held_out(TRAIN, HELD_OUT, args.data)
    views = load_views(TRAIN, out, StudyConfig(width=64, height=48, phase_quality="test"), args.data, 128)
    renderers = {}
    base = SliceParams(slab_jitter=1.0)
    rows = []
    for w in (float(v) for v in args.incidence.split(",")):
        for k in (float(v) for v in args.gain.split(",")):
            params = base.updated(diffusion_incidence=w, diffusion_gain=base.diffusion_gain * k,
                                  leak_gain=base.leak_gain * k)
            de = {}
            for (scene, lighting), v in views.items():
                if id(v.vol) not in renderers:
                    renderers[id(v.vol)] = SliceRenderer(v.vol, MODES["per-species/multiple"], slices=128)
                img = renderers[id(v.vol)].frame(v.spec, params, supersample=2)
                de[(scene, lighting)] = metrics.compare(v.reference, img, mask=v.mask if v.mask.any() else "all")["ciede2000"]
            low = [d for (s, l), d in de.items() if l.endswith(LOW_SUN)]
            high = [d for (s, l), d in de.items() if not l.endswith(LOW_SUN)]
            row = (w, k, np.median(high), np.mean(high), np.median(low), np.mean(low), np.median(list(de.values())),
                   np.mean(list(de.values())), params)
            rows.append(row)
            print(f"incidence {w:g}, gain x {k:g}: high sun median {row[2]:.2f} mean {row[3]:.2f}; low sun median "
                  f"{row[4]:.2f} mean {row[5]:.2f}; all median {row[6]:.2f} mean {row[7]:.2f}", flush=True)
    best = min(rows, key=lambda r: (r[7], r[6]))
    fit = {n: round(float(getattr(best[8], n)), 4) for n in MULTIPLE_PARAMS}
    (out / "fitted.json").write_text(json.dumps(fit, indent=1))
    print(f"best (lowest training mean): incidence {best[0]:g}, gain x {best[1]:g}: {json.dumps(fit)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
