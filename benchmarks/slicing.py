"""Frames per second of the half-angle slicer on the demo supercell, per mode, as the user drags: the
headline table moves the camera AND the sun every frame (the half-angle changes, so slice planes, light
rays, eye rays, occupied spans and the background are all redone); beside it the scaling-only case (a
slider: the textures are rebuilt every frame, the view kept), camera-only and sun-only, and the ratio of
the drag to the paper's rates on a 2003 GeForce FX 5800 (Table IV: 5.1 / 4.3 / 1.7 / 1.2 fps at 300 x 300,
128 slices; the "multiple" light model beyond the paper is held to the per-species translucent rate).

    .venv/bin/python benchmarks/slicing.py [--quick] [--rounds 3] [--frames 12] [--variant cuda_ad_rgb]
                                           [--traced] [--fixed] [--large] [--atmosphere clear]

Medians over ``--frames`` frames after three warm-up frames (compilation and recording excluded) per case,
the cases taking turns round after round (``--rounds``; the median over rounds is printed), frames
recorded by ``dr.freeze`` (``--traced``: also every frame traced in Python, "traced" against "frozen").
``--atmosphere clear``: every frame with the clear 1-D atmosphere (issue 38: the sun's colour by height, the
eye rays' air inside the box and out, ``slicing/eye_air.py``), measured in turn with frames without it
(paired, the same rounds): the table gets a row per mode and atmosphere. ``--fixed``: the fixed cost per frame (a 64 x 48 frame with 8 slices and an 8 x 8 light buffer, where the
kernels have almost nothing to do), traced vs recorded. ``--large``: 1024 x 768 with 256 slices too.
The rates before issue 41's drag work are recorded in benchmarks/README.md; measure them again in one
run with ``benchmarks/slicing_vs_commit.py --commit 831c980 --case drag`` (the two trees in turn).
"""
from __future__ import annotations

import argparse
import statistics
import time

import weather_mi as wm
from weather_mi.slicing import MODES, SliceParams, SliceRenderer

PAPER_FPS = {"uniform/low-albedo": 5.1, "uniform/translucent": 4.3, "per-species/translucent": 1.7,
             "per-species/translucent/detail": 1.2,
             # beyond the paper: held to its per-species translucent rate (the same phase functions)
             "per-species/multiple": 1.7}


def detail_field(vol, seed=0):
    """The simulated turbulent detail of weather_mi.optics.detail (a mean-one multiplier on the grid)."""
    from weather_mi.optics import detail
    return detail.field(vol.shape, seed=seed, spacing_m=vol.spacing)


CASES = ("drag", "scaling", "camera", "sun")  # the headline first


def default_spec(vol, width: int, height: int, **kw):
    """``weather_mi.scene.spec.default_spec``, or ``weather_mi.scene.default_spec`` in trees from before the
    package's layout (benchmarks/slicing_vs_commit.py runs this module on an earlier commit too)."""
    return getattr(wm.scene, "spec", wm.scene).default_spec(vol, width, height, **kw)


ATMOSPHERE = None  # --atmosphere clear: an optics.air.Atmosphere on every frame's scene
SKY_WITH_AIR = None  # a Sky for the frames with ATMOSPHERE (slicing_air.py --sky air: the air's own); None: the view's


def moving_view(vol, width: int, height: int, case: str, i: int, start: int = 0):
    """(SceneSpec, SliceParams) of frame ``i`` of a drag ``case``: "scaling" (a species' scaling changes,
    the view is kept: the textures are rebuilt), "camera" (the camera swings back and forth around the
    default view, up to 8 deg in azimuth and 3 deg in elevation, a few degrees a frame), "sun" (the sun
    likewise around azimuth 240, elevation 35), "drag" (camera and sun both). The moves stay near the view of
    the scaling case, so the cases compare the same kind of picture; views never repeat within a run
    (``start``: the first frame's index)."""
    import math
    k = start + i
    swing = lambda rate, phase: math.sin(rate * k + phase)  # noqa: E731  (incommensurate rates: no repeats)
    cam, sun = case in ("camera", "drag"), case in ("sun", "drag")
    spec = default_spec(vol, width, height, camera_azimuth=200.0 + (8.0 * swing(0.31, 0.0) if cam else 0.0),
                        camera_elevation=8.0 + (3.0 * swing(0.23, 1.0) if cam else 0.0))
    sun_dir = wm.Sun(240.0 + 8.0 * swing(0.27, 2.0), 35.0 + 3.0 * swing(0.19, 3.0)) if sun else wm.Sun(240.0, 35.0)
    sky = spec.sky if ATMOSPHERE is None or SKY_WITH_AIR is None else SKY_WITH_AIR
    spec = wm.SceneSpec(camera=spec.camera, sun=sun_dir, sky=sky, ground=spec.ground, width=width,
                        height=height, **({} if ATMOSPHERE is None else {"atmosphere": ATMOSPHERE}))
    params = SliceParams(scale={"ice": 1.0 + 0.1 * (k % 97 + 1)}) if case == "scaling" else SliceParams()
    return spec, params


def seconds_per_frame(r: SliceRenderer, spec, frames: int, case: str = "scaling", vol=None, start: int = 0) -> float:
    """Median seconds per frame of ``case`` (``moving_view``) after three warm-up frames; ``spec``: the
    view's size (and, for "scaling", the view)."""
    def view(i):
        if case == "scaling" and vol is None:
            return spec, SliceParams(scale={"ice": 1.0 + 0.1 * (start + i + 1)})
        return moving_view(vol, spec.width, spec.height, case, i, start)
    for i in range(3):  # warm-up: compiles, records
        r.frame(*view(i))
    t = []
    for i in range(3, 3 + frames):
        s, p = view(i)
        t0 = time.perf_counter()
        r.frame(s, p)
        t.append(time.perf_counter() - t0)
    return statistics.median(t)


def change(kind: str, i: int) -> SliceParams:
    """The parameters of frame i of a fixed-cost run: the light parameters change ("parameter": the textures
    are kept), or a scaling ("scaling": the textures are rebuilt over the whole grid)."""
    if kind == "scaling":
        return SliceParams(scale={"ice": 1.0 + 0.1 * i})
    return SliceParams(ms_contribution=0.1 + 0.01 * i, blur_length_m=100.0 + i)


def fixed_cost(vol, frames):
    """[(mode, change, ms traced, ms frozen, CPU ms traced, CPU ms frozen)] for a 64 x 48 frame with 8 slices and an 8 x 8 light buffer
    (kernels with almost nothing to do), traced and frozen renderers alternating frame by frame (the
    2 shared cores' load falls on both alike); the change between frames: light parameters
    (textures kept), or a scaling (textures rebuilt: kernels over the grid). CPU ms: the process's CPU
    time (all threads) per frame, which other users of the cores do not inflate."""
    spec = default_spec(vol, 64, 48)
    rows = []
    for name in ("per-species/translucent", "per-species/multiple"):
        rs = [SliceRenderer(vol, MODES[name], slices=8, light_res=8) for _ in range(2)]
        rs[0].frozen = False
        for kind in ("parameter", "scaling"):
            t, c = [[], []], [[], []]
            for i in range(frames + 3):
                p = change(kind, i)
                for j, r in enumerate(rs):
                    t0, c0 = time.perf_counter(), time.process_time()
                    r.frame(spec, p)
                    if i >= 3:  # after the warm-up (compiling, recording)
                        t[j].append(time.perf_counter() - t0)
                        c[j].append(time.process_time() - c0)
            rows.append((name, kind, *(1e3 * statistics.median(x) for x in (t[0], t[1], c[0], c[1]))))
    return rows


def bench(vol, width, height, slices, light_res, frames, rounds=1, traced=False, air=False, modes=None, cases=CASES):
    """{mode: {(case, frozen): seconds per frame}}: the median over ``rounds`` of each case's median
    (``seconds_per_frame``), the cases (and traced / frozen) taking turns round after round; with ``air``,
    also {mode + " + air": ...}: the same with the clear atmosphere, in turn with the frames without it;
    ``cases``: those of ``CASES`` to measure."""
    global ATMOSPHERE
    spec = default_spec(vol, width, height)
    out = {}
    from weather_mi.optics.air import Atmosphere
    for name, mode in MODES.items():
        if modes is not None and name not in modes:
            continue
        airs = (None, Atmosphere()) if air else (None,)
        rs = [SliceRenderer(vol, mode, slices=slices, light_res=light_res,
                            detail_field=detail_field(vol) if mode.detail else None) for _ in airs]
        t = {}
        for k in range(rounds):
            for case in cases:
                for frozen in ((False, True) if traced else (True,)):
                    for a, r in zip(airs, rs):
                        ATMOSPHERE = a
                        r.frozen = frozen
                        t.setdefault((a is not None, case, frozen), []).append(
                            seconds_per_frame(r, spec, frames, case, vol, start=1000 * k))
        ATMOSPHERE = None
        for a in airs:
            out[name + (" + air" if a is not None else "")] = {key[1:]: statistics.median(v) for key, v in t.items()
                                                               if key[0] == (a is not None)}
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one round of 5 frames")
    ap.add_argument("--variant", default=None)
    ap.add_argument("--light-res", type=int, default=128)
    ap.add_argument("--frames", type=int, default=12)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--traced", action="store_true", help="also frames traced in Python every frame")
    ap.add_argument("--fixed", action="store_true", help="also the fixed cost per frame (64 x 48, 8 slices)")
    ap.add_argument("--large", action="store_true", help="also 1024 x 768 with 256 slices")
    ap.add_argument("--atmosphere", default="none", choices=("none", "clear"),
                    help="clear: also every mode with the clear atmosphere (paired rounds)")
    ap.add_argument("--modes", default=None, help="comma-separated modes (default all)")
    ap.add_argument("--cases", default=",".join(CASES), help=f"comma-separated cases of {CASES} (default all)")
    args = ap.parse_args()
    variant = wm.set_variant(args.variant)
    vol = wm.optical_volume(wm.synthetic.supercell(), species="physical")
    frames, rounds = (5, 1) if args.quick else (args.frames, args.rounds)
    print(f"variant {variant}; demo supercell {vol.shape}; light buffer {args.light_res}^2 unless stated")
    if args.fixed:
        print("\nfixed cost: 64 x 48, 8 slices, 8^2 light buffer (ms per frame, median)")
        print(f"{'mode':<28}{'change':<12}{'traced':>9}{'frozen':>9}{'ratio':>8}{'CPU traced':>12}{'CPU frozen':>12}"
              f"{'ratio':>8}")
        for name, kind, a, b, ca, cb in fixed_cost(vol, max(frames, 10)):
            print(f"{name:<28}{kind:<12}{a:>9.1f}{b:>9.1f}{a / b:>7.2f}x{ca:>12.1f}{cb:>12.1f}{ca / cb:>7.2f}x")
    configs = [(300, 300, 128)] + ([(1024, 768, 256)] if args.large else [])
    for w, h, slices in configs:
        paper = (w, h, slices) == (300, 300, 128)
        print(f"\n{w} x {h}, {slices} slices, frames per second (frozen; median of {rounds} rounds of "
              f"{frames}-frame medians)")
        print(f"{'mode':<32}{'drag':>8}{'scaling':>9}{'camera':>8}{'sun':>8}{'drag vs paper':>15}{'target':>8}")
        cases = tuple(c for c in CASES if c in args.cases.split(","))
        rows = bench(vol, w, h, slices, args.light_res, frames, rounds, args.traced, args.atmosphere == "clear",
                     None if args.modes is None else args.modes.split(","), cases)
        for name, t in rows.items():
            fps = {c: 1.0 / t[(c, True)] if (c, True) in t else float("nan") for c in CASES}
            ratio = f"{fps['drag'] / PAPER_FPS[name.split(' + ')[0]]:.1f}x" if paper else "-"
            target = f"{10 * PAPER_FPS[name.split(' + ')[0]]:.0f}" if paper else "-"
            print(f"{name:<32}{fps['drag']:>8.1f}{fps['scaling']:>9.1f}{fps['camera']:>8.1f}{fps['sun']:>8.1f}"
                  f"{ratio:>15}{target:>8}")
        if args.traced:
            print(f"\ntraced every frame (fps): {'mode':<32}" + "".join(f"{c:>9}" for c in CASES))
            for name, t in rows.items():
                print(f"{'':<26}{name:<32}" + "".join(f"{1.0 / t[(c, False)]:>9.1f}" for c in cases))


if __name__ == "__main__":
    main()
