"""Dr.Jit's LLVM block size (lanes per work unit of the CPU thread pool) against the time of a reference
pass, in one process: the estimator of issue 10 and the legacy one (before issue 10), each at Dr.Jit's
default 16384 and at smaller blocks, alternating rounds. weather-mi sets ``variant.LLVM_BLOCK_SIZE``.

    .venv/bin/python benchmarks/llvm_block_size.py [--size 160x120] [--spp 4] [--passes 3] [--rounds 2]

Scene: the demo supercell, ``Camera.ground_view``, side-lit (sun 290/35), sunsky + ground. Columns:
median seconds per spp over the rounds, ratio to the same estimator at 16384, and whether the images are
bit-identical to those at 16384 (the block size changes the work split, not the arithmetic). The last
line gives the issue 10 figure: the new estimator's time per spp at LLVM_BLOCK_SIZE over the legacy
one's at Dr.Jit's default (today's configuration before this change).
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--spp", type=int, default=4, help="samples per pixel per pass")
    ap.add_argument("--passes", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args()
    import weather_mi as wm
    import weather_mi.reference.passes as P
    from weather_mi.optics.forward_peak import DEFAULT_CONE_DEG
    from weather_mi.reference.options import ReferenceOptions
    from weather_mi.kernel.variant import LLVM_BLOCK_SIZE, llvm_block_size, tune_llvm
    w, h = (int(v) for v in args.size.split("x"))
    vol = wm.optical_volume(wm.synthetic.supercell(), species="physical")
    spec = wm.SceneSpec(camera=wm.Camera.ground_view(vol, aspect=w / h), sun=wm.Sun(290, 35), width=w, height=h)
    wm.set_variant("llvm_ad_rgb")
    scenes = {}
    for name, legacy in (("issue 10", False), ("legacy", True)):
        # resolved by hand (not ReferenceOptions.resolved, which refuses legacy with this disk sun)
        estimator = ReferenceOptions(legacy=legacy, sun_guiding=P.DEFAULT_SUN_GUIDING, mvnee=0.0,
                                     aureole_nee=0.0 if legacy else P.DEFAULT_AUREOLE_NEE,
                                     forward_peak_deg=0.0 if legacy else DEFAULT_CONE_DEG)
        job = P.PassScene(spec, vol, P.PassOptions(estimator, planned=1), name)
        scenes[name] = job.build()
        P.render_pass(scenes[name], args.spp, 1)  # compile
    sizes = [16384, 4096, LLVM_BLOCK_SIZE, 256]
    sizes = sorted(set(sizes), reverse=True)
    times = {(n, b): [] for n in scenes for b in sizes}
    images = {}
    for _ in range(args.rounds):
        for b in sizes:
            tune_llvm(b)
            for n, scene in scenes.items():
                t0 = time.perf_counter()
                imgs = [P.render_pass(scene, args.spp, 100 + i) for i in range(args.passes)]
                times[(n, b)].append((time.perf_counter() - t0) / (args.spp * args.passes))
                images.setdefault((n, b), imgs)
    tune_llvm(LLVM_BLOCK_SIZE)
    print(f"\ndemo supercell, {w}x{h}, {args.passes} passes of {args.spp} spp, {args.rounds} rounds; "
          f"block size now {llvm_block_size()}\n")
    print("| estimator | block size | s per spp | ratio to 16384 | bit-identical to 16384 |")
    print("|---|---|---|---|---|")
    med = {k: statistics.median(v) for k, v in times.items()}
    for n in scenes:
        for b in sizes:
            same = all(np.array_equal(a, c) for a, c in zip(images[(n, b)], images[(n, 16384)]))
            print(f"| {n} | {b} | {med[(n, b)]:.3f} | {med[(n, b)] / med[(n, 16384)]:.3f} | {'yes' if same else 'NO'} |")
    print(f"\nissue 10 time per spp: new at {LLVM_BLOCK_SIZE} / legacy at 16384 = "
          f"{med[('issue 10', LLVM_BLOCK_SIZE)] / med[('legacy', 16384)]:.2f} "
          f"(new / legacy both at 16384: {med[('issue 10', 16384)] / med[('legacy', 16384)]:.2f})")


if __name__ == "__main__":
    main()
