"""The slicer's frame rate now against an earlier commit, measured in one run: the two trees take turns,
case after case, round after round, so that the shared cores' load falls on both alike.

    .venv/bin/python benchmarks/slicing_vs_commit.py [--commit c73a480] [--rounds 3] [--size 300x300]
                                                     [--slices 128] [--frames 5] [--fixed]
                                                     [--case scaling camera sun drag]

The earlier commit is extracted into a temporary directory (``git archive``; where its pyproject.toml maps a
package to another directory, as trees before the package layout mapped ``weather_mi.plugins`` to a top-level
``plugins/``, that directory is linked in place, ``link_mapped_packages``; later trees keep their plugins in
``weather_mi/kernel/plugins`` and need nothing); one measuring process per tree, kept for the run, renders the frames of
each mode and case in turn with the other (frozen frames after three warm-up frames; every frame changes
a scaling as a slider drag does, or with ``--case`` the camera, the sun or both move every frame,
benchmarks/slicing.py's ``moving_view``) on the demo supercell. Prints the median over rounds per mode,
case and tree, their ratio, and the same for frames per second of the process's CPU time (all threads:
less sensitive to the other users of the shared cores than the wall clock). With
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
import sys, time, statistics, weather_mi as wm
from weather_mi.slicing import MODES, SliceRenderer
sys.path.insert(0, {bench!r})
from slicing import detail_field, moving_view
wm.set_variant(None)
vol = wm.optical_volume(wm.synthetic.supercell(), species="physical")
renderers = {{}}
print("READY", flush=True)
for line in sys.stdin:  # "mode case start": frames of one case, answered with wall and CPU medians
    name, case, start = line.split()
    if name not in renderers:
        mode = MODES[name]
        renderers[name] = SliceRenderer(vol, mode, slices={slices}, light_res=128,
                                        detail_field=detail_field(vol) if mode.detail else None)
    r, t, c = renderers[name], [], []
    for i in range(3 + {frames}):
        spec, params = moving_view(vol, {w}, {h}, case, i, int(start))
        t0, c0 = time.perf_counter(), time.process_time()
        r.frame(spec, params)
        if i >= 3:  # after the warm-up (compiling, recording)
            t.append(time.perf_counter() - t0)
            c.append(time.process_time() - c0)
    print("FPS", 1.0 / statistics.median(t), 1.0 / statistics.median(c), flush=True)
"""

FIXED = """
import sys, time, statistics, weather_mi as wm
from weather_mi.slicing import MODES, SliceRenderer
sys.path.insert(0, {bench!r})
from slicing import change, default_spec
wm.set_variant(None)
vol = wm.optical_volume(wm.synthetic.supercell(), species="physical")
spec = default_spec(vol, 64, 48)
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


def link_mapped_packages(tree: Path) -> list[str]:
    """Link the packages that ``tree``'s pyproject.toml maps to other directories
    (``[tool.setuptools.package-dir]``, e.g. ``"weather_mi.plugins" = "plugins"`` before the package layout)
    where the import system looks for them, as its editable install would map them: the packages linked."""
    import tomllib
    pyproject = tree / "pyproject.toml"
    mapped = {}
    if pyproject.is_file():
        mapped = tomllib.loads(pyproject.read_text()).get("tool", {}).get("setuptools", {}).get("package-dir", {})
    linked = []
    for package, directory in mapped.items():
        if not package:  # ("": a source root, not a package)
            continue
        target, link = tree / directory, tree.joinpath(*package.split("."))
        if target.is_dir() and not link.exists() and not link.is_symlink():
            link.symlink_to(target.resolve(), target_is_directory=True)
            linked.append(package)
    return linked


def measure(tree: Path, w: int, h: int, slices: int, frames: int, fixed: bool = False) -> dict:
    """The fixed cost per frame (``--fixed``), in a fresh process on ``tree``."""
    code = FIXED.format(bench=str(ROOT / "benchmarks"), w=w, h=h, slices=slices, frames=frames)
    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run([sys.executable, "-c", code], cwd=tree, capture_output=True, text=True, env=env,
                         check=True).stdout
    return {line.split()[1]: float(line.split()[2]) for line in out.splitlines() if line.startswith("FPS ")}


class Tree:
    """A measuring process on one tree (``MEASURE``), kept for the whole run: the two trees answer case by
    case, so that a change of the shared cores' load falls on both alike."""

    def __init__(self, tree: Path, w: int, h: int, slices: int, frames: int):
        code = MEASURE.format(bench=str(ROOT / "benchmarks"), w=w, h=h, slices=slices, frames=frames)
        self.proc = subprocess.Popen([sys.executable, "-c", code], cwd=tree, stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True, env={**os.environ, "PYTHONPATH": str(tree)})
        assert self.proc.stdout.readline().startswith("READY")

    def fps(self, name: str, case: str, start: int) -> tuple[float, float]:
        """(frames per second, frames per CPU second of the process) of ``case`` for mode ``name``."""
        self.proc.stdin.write(f"{name} {case} {start}\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line.startswith("FPS"):
            raise RuntimeError(f"the measuring process stopped: {line!r}")
        return float(line.split()[1]), float(line.split()[2])

    def close(self):
        self.proc.stdin.close()
        self.proc.wait()


def fixed_costs(args, old: Path, w: int, h: int) -> None:
    """``--fixed``: the fixed cost per frame (ms) in fresh processes, the trees in turn, round by round."""
    ms = {"old": [], "new": []}
    for k in range(args.rounds):
        for label, tree in (("old", old), ("new", ROOT)):
            ms[label].append(measure(tree, w, h, args.slices, 4 * args.frames, True))
        print(f"round {k + 1}/{args.rounds} done", flush=True)
    print(f"\nfixed cost per frame, ms (64 x 48, 8 slices, 8^2 light buffer) (median of {args.rounds} rounds)")
    print(f"{'mode: change':<34}{args.commit:>10}{'now':>10}{'ratio':>8}")
    for name in ms["new"][0]:
        a = statistics.median(r[name] for r in ms["old"] if name in r)
        b = statistics.median(r[name] for r in ms["new"])
        print(f"{name:<34}{a:>10.2f}{b:>10.2f}{a / b:>7.2f}x")  # how many times faster now


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
        link_mapped_packages(old)  # (trees before the package layout: weather_mi.plugins -> plugins/)
        if args.fixed:
            fixed_costs(args, old, w, h)
            return 0
        from weather_mi.slicing import MODES
        trees = {"old": Tree(old, w, h, args.slices, args.frames), "new": Tree(ROOT, w, h, args.slices, args.frames)}
        fps = {}  # (mode, case, tree) -> [(fps, CPU fps)] per round
        try:
            for k in range(args.rounds):
                for name in MODES:
                    for case in args.case:
                        for label in (("old", "new") if k % 2 == 0 else ("new", "old")):
                            fps.setdefault((name, case, label), []).append(trees[label].fps(name, case, 1000 * k))
                print(f"round {k + 1}/{args.rounds} done", flush=True)
        finally:
            for t in trees.values():
                t.close()
    print(f"\n{w} x {h}, {args.slices} slices, frames per second (median of {args.rounds} rounds of "
          f"{args.frames}-frame medians; CPU: frames per second of the process's CPU time, all threads)")
    print(f"{'mode':<32}{'case':<9}{args.commit:>9}{'now':>9}{'ratio':>8}{'CPU ' + args.commit:>13}{'CPU now':>9}"
          f"{'ratio':>8}")
    for name in MODES:
        for case in args.case:
            a = [statistics.median(v[i] for v in fps[(name, case, "old")]) for i in (0, 1)]
            b = [statistics.median(v[i] for v in fps[(name, case, "new")]) for i in (0, 1)]
            print(f"{name:<32}{case:<9}{a[0]:>9.2f}{b[0]:>9.2f}{b[0] / a[0]:>7.2f}x{a[1]:>13.2f}{b[1]:>9.2f}"
                  f"{b[1] / a[1]:>7.2f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
