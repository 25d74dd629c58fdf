"""Frames per second of the half-angle slicer on the demo supercell, per Table IV mode.

    .venv/bin/python benchmarks/slicing.py [--quick] [--variant cuda_ad_rgb]

Prints, for 300 x 300 with 128 slices and 1024 x 1024 with 256 slices: frames per second, time per
frame split into light pass and eye pass, and the ratio to the paper's rates on a 2003 GeForce FX
5800 (Table IV: 5.1 / 4.3 / 1.7 / 1.2 fps at 300 x 300, 128 slices; the "multiple" light model beyond
the paper is held to the per-species translucent rate), measured after a warm-up frame (compilation
excluded; later frames change a scaling, as an interactive user would).
"""
from __future__ import annotations

import argparse
import statistics

import weather_mi as wm
from weather_mi.slicing import MODES, SliceParams, SliceRenderer

PAPER_FPS = {"uniform/low-albedo": 5.1, "uniform/translucent": 4.3, "per-species/translucent": 1.7,
             "per-species/translucent/detail": 1.2,
             # beyond the paper: held to its per-species translucent rate (the same phase functions)
             "per-species/multiple": 1.7}


def detail_field(vol, seed=0):
    """The simulated turbulent detail of weather_mi.detail (a mean-one multiplier on the grid)."""
    from weather_mi import detail
    return detail.field(vol.shape, seed=seed, spacing_m=vol.spacing)


def bench(vol, size, slices, light_res, frames, phase_tables):
    spec = wm.scene.default_spec(vol, size, size)
    rows = []
    for name, mode in MODES.items():
        r = SliceRenderer(vol, mode, slices=slices, light_res=light_res,
                          detail_field=detail_field(vol) if mode.detail else None)
        r.frame(spec)  # warm-up: compiles
        t = []
        for i in range(frames):
            r.frame(spec, SliceParams(scale={"ice": 1.0 + 0.1 * (i + 1)}))
            t.append(dict(r.timing))
        med = {k: statistics.median(x[k] for x in t) for k in t[0]}
        rows.append((name, 1.0 / med["total_s"], med["light_s"], med["eye_s"], med["total_s"]))
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="300 x 300 only, 2 frames")
    ap.add_argument("--variant", default=None)
    ap.add_argument("--light-res", type=int, default=128)
    args = ap.parse_args()
    variant = wm.set_variant(args.variant)
    vol = wm.optical_volume(wm.synthetic.supercell(), species="physical")
    print(f"variant {variant}; demo supercell {vol.shape}; light buffer {args.light_res}^2")
    configs = [(300, 128)] if args.quick else [(300, 128), (1024, 256)]
    for size, slices in configs:
        rows = bench(vol, size, slices, args.light_res, 2 if args.quick else 5, None)
        print(f"\n{size} x {size}, {slices} slices")
        print(f"{'mode':<32}{'fps':>7}{'light (ms)':>12}{'eye (ms)':>10}{'frame (ms)':>12}{'vs paper':>10}")
        for name, fps, tl, te, tt in rows:
            ratio = f"{fps / PAPER_FPS[name]:.2f}x" if size == 300 else "-"
            print(f"{name:<32}{fps:>7.2f}{1e3 * tl:>12.1f}{1e3 * te:>10.1f}{1e3 * tt:>12.1f}{ratio:>10}")


if __name__ == "__main__":
    main()
