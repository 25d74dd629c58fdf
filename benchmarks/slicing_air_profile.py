"""What the air adds to a slicer drag frame, part by part (issue 38 part 3): renderers with parts of the air
switched off, each frame of ``benchmarks/slicing.py``'s drag rendered by all of them in turn.

    .venv/bin/python benchmarks/slicing_air_profile.py [--mode uniform/low-albedo] [--frames 16] [--threads 1]

Settings (the demo supercell, 300 x 300, 128 slices, the camera and the sun moving every frame): ``none`` (no
atmosphere); ``air`` (the clear one: the sun's colour by height and the eye rays' air); ``sun only`` (the sun's
colour by height alone, ``SliceRenderer(eye_air=False)``); ``air no shadow`` (the storm's shadow on the air off);
``air no sun colour`` (the eye rays' air without the sun's colour by height: ``sun_air_input`` gives None);
``coarse only`` (the coarse rays' air integrated but not composited per pixel); ``composite only`` (the
per-pixel composite reading an all-zero coarse table: no coarse integration). Printed: median wall and CPU
(process time, all threads) ms per frame and the CPU added to ``none``'s. ``--threads 1``: Dr.Jit on one
thread, where the CPU time is the work (on a loaded 2-core machine two threads add their waits to it).
"""
from __future__ import annotations

import argparse
import contextlib
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import slicing as drag  # noqa: E402  (benchmarks/slicing.py: the drag's views)

SETTINGS = ("none", "air", "sun only", "air no shadow", "air no sun colour", "coarse only", "composite only")


@contextlib.contextmanager
def switched_off(setting: str):
    """The renderer module's air functions with the part that ``setting`` leaves out replaced (a renderer
    records its kernels inside this on its first frames, and replays them after)."""
    import drjit as dr
    import weather_mi.slicing.eye_air_coarse as coarse
    import weather_mi.slicing.renderer as renderer
    saved = (renderer.eye_air_input, renderer.sun_air_input, renderer.seen_through_coarse_air)
    eye_air_input, seen_through = saved[0], saved[2]

    def coarse_only(mi, air, rays, radiance, transmittance, background, depth, shadow=None):
        table = coarse.coarse_air(mi, air, rays.origin, rays.direction, shadow if air.shadow else None)
        return radiance + 0.0 * dr.gather(mi.Float, table, dr.arange(mi.UInt32, dr.width(depth)) % 64)

    def composite_only(*args, **kwargs):
        coarse_air = coarse.coarse_air
        # an evaluated table of zeros (a dr.zeros literal would let Dr.Jit fold the gathers away: no composite)
        coarse.coarse_air = lambda mi, air, *_a, **_k: dr.opaque(
            mi.Float, 0.0, coarse.coarse_count(air.width) * coarse.coarse_count(air.height) * (coarse.BOX_POINTS + 1)
            * coarse.ROW)
        try:
            return seen_through(*args, **kwargs)
        finally:
            coarse.coarse_air = coarse_air
    if setting == "air no shadow":
        renderer.eye_air_input = lambda *a: eye_air_input(*a[:4], shadow=False)
    elif setting == "air no sun colour":
        renderer.sun_air_input = lambda *a, **k: None
    elif setting == "coarse only":
        renderer.seen_through_coarse_air = coarse_only
    elif setting == "composite only":
        renderer.seen_through_coarse_air = composite_only
    try:
        yield
    finally:
        renderer.eye_air_input, renderer.sun_air_input, renderer.seen_through_coarse_air = saved


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mode", default="uniform/low-albedo")
    ap.add_argument("--frames", type=int, default=16)
    ap.add_argument("--size", type=int, default=300)
    ap.add_argument("--threads", type=int, default=None, help="Dr.Jit's thread count (default: its own)")
    ap.add_argument("--settings", default=",".join(SETTINGS))
    args = ap.parse_args()
    import drjit as dr
    import weather_mi as wm
    from weather_mi.optics.air import Atmosphere
    from weather_mi.slicing import MODES, SliceRenderer
    if args.threads:
        dr.set_thread_count(args.threads)
    vol = wm.optical_volume(wm.synthetic.supercell(), species="physical")
    mode = MODES[args.mode]
    detail = drag.detail_field(vol) if mode.detail else None
    settings = args.settings.split(",")
    renderers = {k: SliceRenderer(vol, mode, slices=128, light_res=128, detail_field=detail,
                                  eye_air=k != "sun only") for k in settings}
    wall, cpu = ({k: [] for k in settings} for _ in range(2))
    for i in range(args.frames + 3):
        for k, r in renderers.items():
            drag.ATMOSPHERE = None if k == "none" else Atmosphere()
            spec, params = drag.moving_view(vol, args.size, args.size, "drag", i)
            with switched_off(k):
                t0, c0 = time.perf_counter(), time.process_time()
                r.frame(spec, params)
                t1, c1 = time.perf_counter(), time.process_time()
            if i >= 3:  # after the warm-up (compiling, recording)
                wall[k].append(t1 - t0)
                cpu[k].append(c1 - c0)
    drag.ATMOSPHERE = None
    med = lambda v: 1e3 * statistics.median(v)  # noqa: E731
    print(f"{args.mode}, {args.size} x {args.size}, 128 slices, drag; medians of {args.frames} frames, "
          f"Dr.Jit threads {dr.thread_count()}")
    print(f"{'setting':<20}{'ms':>8}{'CPU ms':>8}{'+CPU':>8}")
    for k in settings:
        print(f"{k:<20}{med(wall[k]):>8.1f}{med(cpu[k]):>8.1f}{med(cpu[k]) - med(cpu[settings[0]]):>8.1f}")


if __name__ == "__main__":
    main()
