"""The viewer's hover read-out (``viewer.pick.first_dense_voxel``): a long diagonal ray through a 300 x 300 x 128
grid (a 150 km x 150 km x 20 km storm box, ~600 cells before its dense block), the median of --rounds picks
against a baseline in the same process: one numpy pass over the grid's cells (``beta_total > threshold``,
what a pick that scanned the grid would cost at least), and the goal of 20 ms a pick (it was a wall-clock assert
in tests/test_viewer_pick.py; speed goals live here).

    .venv/bin/python benchmarks/viewer_pick.py [--rounds 20]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench_timing import goal_header, goal_row, timed  # noqa: E402 (benchmarks/, the script's folder, is on sys.path)

GOAL_S = 0.02
W, H = 32, 24


def big_grid():
    """What ``first_dense_voxel`` reads of an OpticalVolume: 300 x 300 x 128 cells, a dense block in a corner."""
    beta = np.zeros((128, 300, 300), np.float32)
    beta[60:, 200:, 250:] = 1e-2
    bbox = ((0.0, 0.0, 0.0), (150e3, 150e3, 20e3))
    spacing = tuple((bbox[1][a] - bbox[0][a]) / n for a, n in zip((2, 1, 0), beta.shape))  # (dz, dy, dx)
    return SimpleNamespace(species=("cloud",), bbox=bbox, beta_total=beta, beta_ext=beta[None], spacing=spacing)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=20)
    args = ap.parse_args(argv)
    import weather_mi as wm
    from weather_mi.viewer.pick import default_threshold_per_m, first_dense_voxel
    vol = big_grid()
    spec = wm.SceneSpec(camera=wm.Camera(origin=(-1000.0, -3000.0, 500.0), target=(150e3, 150e3, 18e3), fov=40.0),
                        sky=wm.Sky("constant"), width=W, height=H)
    hit = first_dense_voxel(None, vol, spec, W / 2, H / 2)
    assert hit is not None and tuple(hit["index"][1:]) == (249, 250), hit  # the block's west face
    thr = default_threshold_per_m(vol)
    base = timed(lambda: np.flatnonzero(vol.beta_total > thr), args.rounds)
    picks = timed(lambda: first_dense_voxel(None, vol, spec, W / 2, H / 2), args.rounds)
    print(goal_header("one pass over the grid", "pick", unit="ms"))
    print(goal_row("diagonal through 300 x 300 x 128", base, picks, GOAL_S, unit="ms"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
