"""The spectral ground truth's cost (issue 38 part 2): the reference renderer in ``llvm_ad_spectral`` (4
wavelengths a path, the phase tables every 25 nm) against ``llvm_ad_rgb`` on the demo supercell (the study's
front view, ``study.runs.view``, --atmosphere clear in both), paired: the two modes alternate in one process,
kernels compiled first, and each round's ratio is taken between renders run next to each other.

    .venv/bin/python benchmarks/spectral.py [--size 64x48] [--spp 64] [--passes 4] [--rounds 3] [--elevation 20]

Per round: each mode's seconds and luminance RSE over the cloud pixels (``Image.metadata["noise"]``), and the
spectral mode's time to the same RSE over the RGB mode's, (t RSE^2)_spectral / (t RSE^2)_RGB (RSE falls as
1 / sqrt(samples), so time x RSE^2 is the time to a fixed RSE). Target: at most 1.5x. The median over rounds
is printed last.
"""
from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

MODES = {"rgb": "llvm_ad_rgb", "spectral": "llvm_ad_spectral"}


def main(argv=None):
    from weather_mi.optics.air import Atmosphere
    from weather_mi.reference.render import render_reference
    from weather_mi.study.runs import CONFIGS, load_scene, view
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="64x48")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--passes", type=int, default=4)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--elevation", type=float, default=20.0)
    ap.add_argument("--lighting", default="front")
    args = ap.parse_args(argv)
    w, h = (int(v) for v in args.size.split("x"))
    cfg = replace(CONFIGS["quick"], width=w, height=h)
    vol, _ = load_scene("demo-supercell", cfg)
    spec = view(vol, args.lighting, cfg)
    spec = replace(spec, sun=replace(spec.sun, elevation=args.elevation), atmosphere=Atmosphere())
    for variant in MODES.values():  # compile (and build the spectral tables) first
        render_reference(replace(spec, seed=99), vol, spp=1, passes=1, progress=False, variant=variant)
    print(f"demo supercell, {args.lighting} view, sun {args.elevation:g} deg, {w}x{h}, {args.spp} spp in "
          f"{args.passes} passes, --atmosphere clear")
    print("| round | RGB s | RGB RSE | spectral s | spectral RSE | time ratio | time to the same RSE |")
    print("|---|---|---|---|---|---|---|")
    ratios = []
    for r in range(args.rounds):
        got = {}
        for mode, variant in (MODES.items() if r % 2 == 0 else reversed(MODES.items())):  # alternate the order
            t = time.perf_counter()
            img = render_reference(replace(spec, seed=r), vol, spp=args.spp, passes=args.passes, progress=False,
                                   variant=variant)
            got[mode] = (time.perf_counter() - t, float(img.metadata["noise"]["rse_mean"]))
        (tr, er), (ts, es) = got["rgb"], got["spectral"]
        ratios.append(ts * es ** 2 / (tr * er ** 2))
        print(f"| {r} | {tr:.1f} | {er:.4f} | {ts:.1f} | {es:.4f} | {ts / tr:.2f} | {ratios[-1]:.2f} |", flush=True)
    print(f"median time to the same RSE, spectral / RGB: {np.median(ratios):.2f} (target <= 1.5)")


if __name__ == "__main__":
    main()
