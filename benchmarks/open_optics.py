"""Time of opening a WRF file and of its optics, as the command line does them (``wm.open_wrf``, then
``optical_volume`` with the tree's command-line defaults: the scheme's sizes where the tree has them, the input
released), tree against tree in one run: issue 39's "opening and optics at least 3x faster" on the real
supercell tiled to 800 x 800 (``benchmarks/cli_memory.py`` writes the tiled file).

    .venv/bin/python benchmarks/open_optics.py --repo /tmp/issue-base --repo /tmp/bytes-base --repo . \
        --file /tmp/weather-mi-tiles/wrfout_supercell_800x800.nc --rounds 2

Each round runs every tree in a child process of its own (the trees alternate), after one warm-up child per
tree on ``--warmup`` (a small file: numba's compiled kernels cached before the timed runs). The table gives the
best time of each step and its ratio to the first tree's (the machine is shared: only ratios count).
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve()
CHILD = r"""
import sys, time, json, inspect
sys.path.insert(0, sys.argv[1])
import weather_mi as wm
from weather_mi.optics import volume
path = sys.argv[2]
t0 = time.perf_counter()
hyd = wm.open_wrf(path)
t1 = time.perf_counter()
params = inspect.signature(volume.optical_volume).parameters
kw = {}
if "sizes" in params and hasattr(volume, "default_sizes"):
    kw["sizes"] = volume.default_sizes(hyd)
if "release" in params:
    kw.update(release=True, keep=("weights",))
vol = volume.optical_volume(hyd, **kw)
t2 = time.perf_counter()
print(json.dumps({"open": t1 - t0, "optics": t2 - t1, "file": wm.__file__, "kw": str(kw)}))
"""


def run(repo: Path, path: Path) -> dict:
    out = subprocess.run([sys.executable, "-c", CHILD, str(repo), str(path)], capture_output=True, text=True,
                         cwd=str(repo))
    if out.returncode != 0:
        raise RuntimeError(f"{repo}: {out.stderr[-2000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repo", type=Path, action="append", help="a tree whose weather_mi to run (repeatable)")
    ap.add_argument("--file", type=Path, default=Path("/tmp/weather-mi-tiles/wrfout_supercell_800x800.nc"))
    ap.add_argument("--warmup", type=Path, default=Path("/tmp/weather-mi-tiles/wrfout_supercell_400x400.nc"))
    ap.add_argument("--rounds", type=int, default=2)
    a = ap.parse_args(argv)
    repos = [r.resolve() for r in (a.repo or [HERE.parents[1]])]
    for repo in repos:
        if a.warmup.is_file():
            run(repo, a.warmup)
    best = {r: {"open": [], "optics": []} for r in repos}
    for rnd in range(a.rounds):
        for repo in repos:
            res = run(repo, a.file)
            print(f"  round {rnd} {str(repo):<28} open {res['open']:7.1f} s  optics {res['optics']:6.1f} s  "
                  f"({res['kw']})", flush=True)
            for k in ("open", "optics"):
                best[repo][k].append(res[k])
    print(f"\n{'tree':<28}{'open (s)':>10}{'optics (s)':>12}{'open: x faster':>16}{'optics: x faster':>18}")
    base = best[repos[0]]
    for repo in repos:
        o, p = min(best[repo]["open"]), min(best[repo]["optics"])
        print(f"{str(repo)[-27:]:<28}{o:>10.1f}{p:>12.1f}{min(base['open']) / o:>16.2f}{min(base['optics']) / p:>18.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
