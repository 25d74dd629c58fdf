"""The slicer's drag with the clear atmosphere against without it, frame by frame (issue 38 part 3: whether
``view``'s default can be ``--atmosphere clear``).

    .venv/bin/python benchmarks/slicing_air.py [--frames 12] [--rounds 2] [--modes MODE,...] [--sky view|air]

Per mode, three renderers on the demo supercell at 300 x 300, 128 slices: without an atmosphere, with the
clear one (the sun's colour by height and the eye rays' air, ``slicing/eye_air.py``), and with the clear one on
the sun's path alone (``SliceRenderer(eye_air=False)``), each frame of ``benchmarks/slicing.py``'s drag (the
camera and the sun moving) rendered by the three in turn, so that a loaded machine's changes fall on all alike.
Printed: the median wall and CPU (process time, all threads) milliseconds per frame, the ratios of the rates
with the air to without it, the drag's rate with the air as measured (``fps air``: what the target is judged on
where the machine is quiet), and the drag with the air estimated for an idle machine as the ratio times the idle
rate without it (``IDLE_FPS``, benchmarks/README.md; for a loaded machine, and only as long as the frame without
the air runs at that rate) against the target of ten times the paper's rate.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import slicing as drag  # noqa: E402  (benchmarks/slicing.py: the drag's views, the paper's rates)

# the drag without the air on an idle machine (benchmarks/README.md, issue 41), frames per second
IDLE_FPS = {"uniform/low-albedo": 56.0, "uniform/translucent": 45.0, "per-species/translucent": 34.0,
            "per-species/translucent/detail": 34.0, "per-species/multiple": 28.0}


def measure(vol, name: str, frames: int, rounds: int) -> dict:
    """{setting: (wall ms, CPU ms)} medians per frame of mode ``name`` (module docstring)."""
    import weather_mi as wm  # noqa: F401
    from weather_mi.optics.air import Atmosphere
    from weather_mi.slicing import MODES, SliceRenderer
    mode = MODES[name]
    detail = drag.detail_field(vol) if mode.detail else None
    settings = {"none": (None, True), "air": (Atmosphere(), True), "sun only": (Atmosphere(), False)}
    renderers = {k: SliceRenderer(vol, mode, slices=128, light_res=128, detail_field=detail, eye_air=e)
                 for k, (_, e) in settings.items()}
    wall, cpu = ({k: [] for k in settings} for _ in range(2))
    for r in range(rounds):
        for i in range(frames + 3):
            for k, renderer in renderers.items():
                drag.ATMOSPHERE = settings[k][0]
                spec, params = drag.moving_view(vol, 300, 300, "drag", i, start=1000 * r)
                t0, c0 = time.perf_counter(), time.process_time()
                renderer.frame(spec, params)
                if i >= 3:  # after the warm-up (compiling, recording)
                    wall[k].append(time.perf_counter() - t0)
                    cpu[k].append(time.process_time() - c0)
    drag.ATMOSPHERE = None
    return {k: (1e3 * statistics.median(wall[k]), 1e3 * statistics.median(cpu[k])) for k in settings}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=12)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--modes", default=",".join(IDLE_FPS))
    ap.add_argument("--variant", default=None)
    ap.add_argument("--sky", default="view", choices=("view", "air"),
                    help="the sky of the frames with the air: the drag's view's (sunsky), or the air's own (Sky(\"air\"), "
                         "view's default with the air)")
    args = ap.parse_args()
    import weather_mi as wm
    variant = wm.set_variant(args.variant)
    drag.SKY_WITH_AIR = wm.Sky("air") if args.sky == "air" else None
    vol = wm.optical_volume(wm.synthetic.supercell(), species="physical")
    print(f"variant {variant}; demo supercell {vol.shape}; 300 x 300, 128 slices, drag; medians of "
          f"{args.rounds} x {args.frames} frames, the three settings in turn")
    print(f"{'mode':<32}{'ms none':>9}{'ms air':>8}{'ms sun':>8}{'CPU none':>10}{'CPU air':>9}{'ratio wall':>12}"
          f"{'ratio CPU':>11}{'fps air':>9}{'idle est.':>11}{'target':>8}")
    for name in args.modes.split(","):
        m = measure(vol, name, args.frames, args.rounds)
        wall, cpu = m["none"][0] / m["air"][0], m["none"][1] / m["air"][1]
        est = min(wall, cpu) * IDLE_FPS[name]
        print(f"{name:<32}{m['none'][0]:>9.1f}{m['air'][0]:>8.1f}{m['sun only'][0]:>8.1f}{m['none'][1]:>10.1f}"
              f"{m['air'][1]:>9.1f}{wall:>12.3f}{cpu:>11.3f}{1000.0 / m['air'][0]:>9.1f}{est:>11.1f}"
              f"{10 * drag.PAPER_FPS[name]:>8.0f}", flush=True)


if __name__ == "__main__":
    main()
