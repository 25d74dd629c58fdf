"""Frames per second of the half-angle slicer on the demo supercell, per mode, with every frame traced
in Python ("traced") and with the frame's recorded kernels launched (``dr.freeze``, "frozen", the
default), in one process.

    .venv/bin/python benchmarks/slicing.py [--quick] [--variant cuda_ad_rgb] [--frames 5]

Prints: the fixed cost per frame (``fixed_cost``: a 64 x 48 frame with 8 slices and an 8 x 8 light
buffer, where the kernels have almost nothing to do), then frames
per second at 300 x 300 with 128 slices and 1024 x 768 with 256 slices, and the ratio to the paper's
rates on a 2003 GeForce FX 5800 (Table IV: 5.1 / 4.3 / 1.7 / 1.2 fps at 300 x 300, 128 slices; the
"multiple" light model beyond the paper is held to the per-species translucent rate). Medians over
``--frames`` frames after two warm-up frames (compilation and recording excluded); every frame changes
a scaling, as a slider drag does (the textures are rebuilt each frame).
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


def seconds_per_frame(r: SliceRenderer, spec, frames: int) -> float:
    for i in range(2):  # warm-up: compiles, records
        r.frame(spec, SliceParams(scale={"ice": 1.0 + 0.01 * i}))
    t = []
    for i in range(frames):
        t0 = time.perf_counter()
        r.frame(spec, SliceParams(scale={"ice": 1.0 + 0.1 * (i + 1)}))
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
    spec = wm.scene.spec.default_spec(vol, 64, 48)
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


def bench(vol, width, height, slices, light_res, frames):
    """[(mode, seconds traced, seconds frozen)]."""
    spec = wm.scene.spec.default_spec(vol, width, height)
    rows = []
    for name, mode in MODES.items():
        r = SliceRenderer(vol, mode, slices=slices, light_res=light_res,
                          detail_field=detail_field(vol) if mode.detail else None)
        out = []
        for frozen in (False, True):
            r.frozen = frozen
            out.append(seconds_per_frame(r, spec, frames))
        rows.append((name, *out))
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="no 1024 x 768, 3 frames")
    ap.add_argument("--variant", default=None)
    ap.add_argument("--light-res", type=int, default=128)
    ap.add_argument("--frames", type=int, default=5)
    args = ap.parse_args()
    variant = wm.set_variant(args.variant)
    vol = wm.optical_volume(wm.synthetic.supercell(), species="physical")
    frames = 3 if args.quick else args.frames
    print(f"variant {variant}; demo supercell {vol.shape}; light buffer {args.light_res}^2 unless stated")
    print("\nfixed cost: 64 x 48, 8 slices, 8^2 light buffer (ms per frame, median)")
    print(f"{'mode':<28}{'change':<12}{'traced':>9}{'frozen':>9}{'ratio':>8}{'CPU traced':>12}{'CPU frozen':>12}"
          f"{'ratio':>8}")
    for name, kind, a, b, ca, cb in fixed_cost(vol, max(frames, 10)):
        print(f"{name:<28}{kind:<12}{a:>9.1f}{b:>9.1f}{a / b:>7.2f}x{ca:>12.1f}{cb:>12.1f}{ca / cb:>7.2f}x")
    configs = [(300, 300, 128)] if args.quick else [(300, 300, 128), (1024, 768, 256)]
    for w, h, slices in configs:
        print(f"\n{w} x {h}, {slices} slices (frames per second)")
        print(f"{'mode':<32}{'traced':>9}{'frozen':>9}{'ratio':>8}{'frozen vs paper':>17}")
        for name, a, b in bench(vol, w, h, slices, args.light_res, frames):
            ratio = f"{1.0 / b / PAPER_FPS[name]:.2f}x" if (w, h) == (300, 300) else "-"
            print(f"{name:<32}{1.0 / a:>9.2f}{1.0 / b:>9.2f}{a / b:>7.2f}x{ratio:>17}")


if __name__ == "__main__":
    main()
