"""The cost of the air on the sun's path (issue 38 part 1): the reference renderer with ``--atmosphere
clear`` against ``none`` on issue 38's headline view (demo supercell, sun at 4 deg elevation, azimuth
260, camera azimuth 290), in one process, kernels compiled first.

    .venv/bin/python benchmarks/atmosphere.py [--size 160x120] [--spp 32] [--repeats 2]

Prints each render's seconds and the ratio of the best times (target: at most 1.3x), and the time to
build the per-scene table (``optics.air.sun_air_table``).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def main(argv=None):
    from validation.sun_colour import demo_volume, headline_scene
    from weather_mi.optics.air import Atmosphere, sun_air_table
    from weather_mi.reference.render import render_reference
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args(argv)
    size = tuple(int(v) for v in args.size.split("x"))
    t0 = time.perf_counter()
    sun_air_table(Atmosphere(), np.sin(np.radians(4.0)), top_m=22e3, half_width_m=70e3)
    table_s = time.perf_counter() - t0
    vol = demo_volume()
    specs = {a: headline_scene(vol, size, 4.0, a) for a in ("none", "clear")}
    for spec in specs.values():  # compile the kernels first
        render_reference(spec, vol, spp=4, progress=False)
    times = {a: [] for a in specs}
    for _ in range(args.repeats):
        for a, spec in specs.items():
            times[a].append(render_reference(spec, vol, spp=args.spp, progress=False).metadata["seconds"])
    print(f"{args.size}, {args.spp} spp: --atmosphere none " + ", ".join(f"{t:.1f}" for t in times["none"])
          + " s; clear " + ", ".join(f"{t:.1f}" for t in times["clear"])
          + f" s; ratio of the best {min(times['clear']) / min(times['none']):.2f}; the table {table_s:.2f} s")


if __name__ == "__main__":
    main()
