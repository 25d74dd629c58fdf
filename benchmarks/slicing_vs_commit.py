"""The slicer's frame rate now against an earlier commit, measured in one run: the two trees take turns,
round after round, so that the shared cores' load falls on both alike.

    .venv/bin/python benchmarks/slicing_vs_commit.py [--commit c73a480] [--rounds 3] [--size 300x300]
                                                     [--slices 128] [--frames 5] [--fixed]
                                                     [--case scaling camera sun drag]

The earlier commit is extracted into a temporary directory (``git archive``; its plugins linked in, as
validation/bit_identity.py does); each round runs, in a fresh process per tree, the frames-per-second
measurement of benchmarks/slicing.py (frozen frames, every frame changing a scaling as a slider drag
does; ``--case``: the camera, the sun or both moving every frame instead, ``moving_view``) on the demo
supercell. Prints the median over rounds per mode and tree and their ratio. With
``--fixed``: the fixed cost per frame instead, in ms (a 64 x 48 frame, 8 slices, an 8 x 8 light buffer:
kernels with almost nothing to do), for a change of the light parameters and of a scaling (which rebuilds
the textures over the whole grid), in each tree's own default (traced, or recorded where it has dr.freeze).
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MEASURE = """
import sys, weather_mi as wm
from weather_mi.slicing import MODES, SliceRenderer
sys.path.insert(0, {bench!r})
from slicing import detail_field, seconds_per_frame
wm.set_variant(None)
vol = wm.optical_volume(wm.synthetic.supercell(), species="physical")
spec = wm.scene.spec.default_spec(vol, {w}, {h})
for name, mode in MODES.items():
    r = SliceRenderer(vol, mode, slices={slices}, light_res=128, detail_field=detail_field(vol) if mode.detail else None)
    for case in {cases!r}:
        print("FPS", name + ("" if case == "scaling" else ":" + case),
              1.0 / seconds_per_frame(r, spec, {frames}, case, vol, start={start}), flush=True)
"""

FIXED = """
import sys, time, statistics, weather_mi as wm
from weather_mi.slicing import MODES, SliceRenderer
sys.path.insert(0, {bench!r})
from slicing import change
wm.set_variant(None)
vol = wm.optical_volume(wm.synthetic.supercell(), species="physical")
spec = wm.scene.spec.default_spec(vol, 64, 48)
for name in ("per-species/translucent", "per-species/multiple"):
    r = SliceRenderer(vol, MODES[name], slices=8, light_res=8)
    for kind in ("parameter", "scaling"):
        t = []
        for i in range(5 + {frames}):
            t0 = time.perf_counter()
            r.frame(spec, change(kind, i))
            if i >= 5:  # after the warm-up (compiling, recording)
                t.append(time.perf_counter() - t0)
        print("FPS", name + ":" + kind, 1e3 * statistics.median(t), flush=True)
"""


def measure(tree: Path, w: int, h: int, slices: int, frames: int, fixed: bool = False, cases=("scaling",),
            start: int = 0) -> dict:
    code = (FIXED if fixed else MEASURE).format(bench=str(ROOT / "benchmarks"), w=w, h=h, slices=slices,
                                                frames=frames, cases=tuple(cases), start=start)
    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run([sys.executable, "-c", code], cwd=tree, capture_output=True, text=True, env=env,
                         check=True).stdout
    return {line.split()[1]: float(line.split()[2]) for line in out.splitlines() if line.startswith("FPS ")}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--commit", default="c73a480")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--size", default="300x300")
    ap.add_argument("--slices", type=int, default=128)
    ap.add_argument("--frames", type=int, default=5)
    ap.add_argument("--fixed", action="store_true", help="the fixed cost per frame (ms, 64 x 48) instead of fps")
    ap.add_argument("--case", nargs="+", default=["scaling"], choices=("scaling", "camera", "sun", "drag"),
                    help="what changes every frame (benchmarks/slicing.py moving_view): a scaling (default), the "
                         "camera, the sun, or both (drag)")
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.lower().split("x"))
    with tempfile.TemporaryDirectory() as tmp:
        old = Path(tmp) / "old"
        old.mkdir()  # the earlier tree as files (git archive: no worktree to add or remove)
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.commit], check=True, capture_output=True)
        subprocess.run(["tar", "-x", "-C", str(old)], input=archive.stdout, check=True)
        if not (old / "weather_mi" / "plugins").exists():  # as the editable install maps them
            (old / "weather_mi" / "plugins").symlink_to("../plugins")
        fps = {"old": [], "new": []}
        for k in range(args.rounds):
            for label, tree in (("old", old), ("new", ROOT)):
                fps[label].append(measure(tree, w, h, args.slices, 4 * args.frames if args.fixed else args.frames,
                                          args.fixed, args.case, start=1000 * k))
            print(f"round {k + 1}/{args.rounds} done", flush=True)
    what = "fixed cost per frame, ms (64 x 48, 8 slices, 8^2 light buffer)" if args.fixed else \
        f"{w} x {h}, {args.slices} slices, frames per second"
    print(f"\n{what} (median of {args.rounds} rounds)")
    print(f"{'mode' + (': change' if args.fixed else ''):<34}{args.commit:>10}{'now':>10}{'ratio':>8}")
    for name in fps["new"][0]:
        a = statistics.median(r[name] for r in fps["old"] if name in r)
        b = statistics.median(r[name] for r in fps["new"])
        ratio = a / b if args.fixed else b / a  # how many times faster now
        print(f"{name:<34}{a:>10.2f}{b:>10.2f}{ratio:>7.2f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
