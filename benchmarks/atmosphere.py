"""The cost of the atmosphere (issue 38: at most 1.3x the time without it, to the same luminance RSE): the
reference renderer with ``--atmosphere clear`` (the sun's colour along its path and the air inside the box,
``optics.air.inside``; the air along the eye rays outside the box is added after the path tracer and is not
timed) against ``none``, on issue 38's headline view (demo supercell, sun at 4 deg elevation, azimuth 260,
camera azimuth 290), in one process, kernels compiled first, in paired rounds (the two orders alternate; each
round its own seed).

    .venv/bin/python benchmarks/atmosphere.py [--size 160x120] [--spp 32] [--rounds 3]

Per round: each render's seconds and the mean relative standard error of the luminance over the cloud pixels
(``noise_stats``' ``rse_mean``). Then the ratio of the median times and the ratio of the times to the same
RSE, sum(t) rse^2 (the RSE of a mean falls as 1 / sqrt(time)); and the time to build the per-scene table
(``optics.air.sun_air_table``).
"""
from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def main(argv=None):
    from validation.sun_colour import demo_volume, headline_scene
    from weather_mi.optics.air import Atmosphere, sun_air_table
    from weather_mi.optics.air.inside import with_box_air
    from weather_mi.reference.render import render_reference
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--elevation", type=float, default=4.0)
    args = ap.parse_args(argv)
    size = tuple(int(v) for v in args.size.split("x"))
    t0 = time.perf_counter()
    sun_air_table(Atmosphere(), np.sin(np.radians(args.elevation)), top_m=22e3, half_width_m=70e3)
    table_s = time.perf_counter() - t0
    hyd, vol = demo_volume(with_hyd=True)
    cases = {}
    for a in ("none", "clear"):
        spec = headline_scene(vol, size, args.elevation, a)
        cases[a] = (spec, vol if spec.atmosphere is None else with_box_air(vol, hyd, spec.atmosphere))
    for spec, v in cases.values():  # compile the kernels first
        render_reference(spec, v, spp=2, progress=False)
    times, rse = {a: [] for a in cases}, {a: [] for a in cases}
    for r in range(args.rounds):
        for a in (("none", "clear") if r % 2 == 0 else ("clear", "none")):
            spec, v = cases[a]
            img = render_reference(replace(spec, seed=spec.seed + r), v, spp=args.spp, progress=False)
            times[a].append(img.metadata["seconds"])
            rse[a].append(img.metadata["noise"]["rse_mean"])
        print(f"round {r + 1}: none {times['none'][-1]:.2f} s, RSE {rse['none'][-1]:.4f}; clear {times['clear'][-1]:.2f} s, "
              f"RSE {rse['clear'][-1]:.4f}; time ratio {times['clear'][-1] / times['none'][-1]:.2f}", flush=True)
    cost = {a: sum(times[a]) * float(np.mean(np.square(rse[a]))) for a in cases}
    print(f"{args.size}, {args.spp} spp, {args.rounds} rounds: time ratio clear / none (medians) "
          f"{np.median(times['clear']) / np.median(times['none']):.2f}; to the same luminance RSE "
          f"{cost['clear'] / cost['none']:.2f}; the table {table_s:.2f} s")


if __name__ == "__main__":
    main()
