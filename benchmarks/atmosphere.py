"""The cost of the atmosphere (issue 38: at most 1.3x the time without it, to the same luminance RSE): the
reference renderer with ``--atmosphere clear`` (the sun's colour along its path and the air inside the box,
``optics.air.inside``; the air along the eye rays outside the box is added after the path tracer and is not
timed) against ``none``, with the sky model, with ``--sky air`` (render's default: the air's diffuse sky as an envmap
into the box, ``kernel.air_sky``) and with ``--sky none`` (no sky emitter: ``--sky air``'s render before its envmap),
on issue 38's headline view (demo supercell, sun at 4 deg elevation, azimuth 260,
camera azimuth 290), in one process, kernels compiled first, in paired rounds (the order reverses each round;
each round its own seed). The air along the eye rays (``display.aerial.with_eye_air``) is timed once apart.

    .venv/bin/python benchmarks/atmosphere.py [--size 160x120] [--spp 32] [--rounds 3]

Per round: each render's seconds and the mean relative standard error of the luminance over the cloud pixels
(``noise_stats``' ``rse_mean``). Then, against ``none``, the ratio of the median times, of each round's times
and of the times to the same RSE, sum(t) mean(rse^2) (the RSE of a mean falls as 1 / sqrt(time)); and the time
to build the per-scene table (``optics.air.sun_air_table``).
"""
from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

CASES = {"none": ("none", "sunsky"), "clear": ("clear", "sunsky"), "clear, --sky air": ("clear", "air"),
         "clear, --sky none": ("clear", "none")}  # --sky air's render before its envmap (kernel.air_sky)


def main(argv=None):
    from validation.sun_colour import demo_volume
    from weather_mi.scene.framing import scene_spec
    from weather_mi.optics.air import Atmosphere, sun_air_table
    from weather_mi.optics.air.inside import scene_air
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
    vol = demo_volume()
    cases = {}
    for name, (atmosphere, sky) in CASES.items():
        spec = scene_spec(vol, size, sun_elevation=args.elevation, sun_azimuth=260.0, camera_azimuth=290.0,
                          atmosphere=atmosphere, sky=sky)
        cases[name] = (spec, scene_air(vol, spec.atmosphere))  # the air in the box from the model's rho_air
    for spec, v in cases.values():  # compile the kernels first
        render_reference(spec, v, spp=2, progress=False)
    times, rse, last = {a: [] for a in cases}, {a: [] for a in cases}, {}
    names = list(cases)
    for r in range(args.rounds):
        for a in (names if r % 2 == 0 else names[::-1]):
            spec, v = cases[a]
            img = render_reference(replace(spec, seed=spec.seed + r), v, spp=args.spp, progress=False)
            times[a].append(img.metadata["seconds"])
            rse[a].append(img.metadata["noise"]["rse_mean"])
            last[a] = img
        print(f"round {r + 1}: " + "; ".join(f"{a} {times[a][-1]:.2f} s, RSE {rse[a][-1]:.4f}" for a in names), flush=True)
    cost = {a: sum(times[a]) * float(np.mean(np.square(rse[a]))) for a in cases}
    base = names[0]
    for a in names[1:]:
        print(f"{args.size}, {args.spp} spp, {args.rounds} rounds, {a} / {base}: time ratio (medians) "
              f"{np.median(times[a]) / np.median(times[base]):.2f}, per round "
              + ", ".join(f"{x / y:.2f}" for x, y in zip(times[a], times[base]))
              + f"; time to the same luminance RSE {cost[a] / cost[base]:.2f}")
    from weather_mi.display.aerial import with_eye_air
    for a in names[1:]:
        t0 = time.perf_counter()
        with_eye_air(last[a], cases[a][0], cases[a][1], sky_air=CASES[a][1] == "air")
        print(f"{a}: the air along the eye rays {time.perf_counter() - t0:.2f} s")
    print(f"the sun's table {table_s:.2f} s")


if __name__ == "__main__":
    main()
