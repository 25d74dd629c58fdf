"""The slicer's drag frame rate with two sets of the "multiple" model's parameters, in one process and one
renderer, frame by frame in turn (a, b, a, b, ...): what a change of the defaults costs (a parameter that
switches a term on, such as ``diffusion_incidence`` from 0, adds that term's work to the kernel).

    .venv/bin/python benchmarks/slicing_params.py --a A.json [--b B.json] [--rounds 6] [--size 300x300]
        [--slices 128] [--case drag]

A and B: JSON objects of ``SliceParams`` fields (a fitted.json of ``validation/calibrate_slicer.py``); B
defaults to the shipped parameters. Frames of ``benchmarks/slicing.py``'s ``moving_view`` (the camera and the
sun move every frame), 8 per parameter set a round, the first round's first 3 left out (warm-up); prints the
frames per second of each (wall clock and the process's CPU time, medians) and their ratio b / a.
"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import weather_mi as wm  # noqa: E402
from weather_mi.slicing import MODES, SliceParams, SliceRenderer  # noqa: E402
from slicing import moving_view  # noqa: E402


def params_of(path) -> SliceParams:
    """SliceParams with the fields of a JSON file (None: the shipped defaults)."""
    return SliceParams() if path is None else SliceParams().updated(**json.loads(Path(path).read_text()))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--a", required=True, help="JSON of the first parameter set (the baseline)")
    ap.add_argument("--b", default=None, help="JSON of the second (default: the shipped parameters)")
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--size", default="300x300")
    ap.add_argument("--slices", type=int, default=128)
    ap.add_argument("--case", default="drag", choices=("scaling", "camera", "sun", "drag"))
    args = ap.parse_args(argv)
    width, height = (int(v) for v in args.size.split("x"))
    sets = {"a": params_of(args.a), "b": params_of(args.b)}
    wm.set_variant(None)
    vol = wm.optical_volume(wm.synthetic.supercell(), species="physical")
    r = SliceRenderer(vol, MODES["per-species/multiple"], slices=args.slices)
    times = {k: ([], []) for k in sets}
    k = 0
    for rnd in range(args.rounds):
        for i in range(8):
            for name, params in sets.items():
                spec, view_params = moving_view(vol, width, height, args.case, k)
                k += 1
                wall, cpu = time.perf_counter(), time.process_time()
                r.frame(spec, params.updated(scale=view_params.scale))
                if rnd > 0 or i >= 3:
                    times[name][0].append(time.perf_counter() - wall)
                    times[name][1].append(time.process_time() - cpu)
    med = {n: (statistics.median(w), statistics.median(c)) for n, (w, c) in times.items()}
    for n, (w, c) in med.items():
        print(f"{n}: {1 / w:.2f} fps wall, {1 / c:.2f} fps CPU ({len(times[n][0])} frames)")
    print(f"b / a: {med['a'][0] / med['b'][0]:.3f}x wall, {med['a'][1] / med['b'][1]:.3f}x CPU "
          f"({args.size}, {args.slices} slices, {args.case})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
