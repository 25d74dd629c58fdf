"""Time of the turbulent-detail noise (weather_mi.optics.detail) per grid size, against a baseline run in the
same process.

    .venv/bin/python benchmarks/detail.py [--repeat 5]

Baseline: ``np.random.default_rng(seed).standard_normal(shape, dtype=np.float32)``, drawing as many
Gaussian numbers as the grid has cells (white noise, the least any seeded noise must generate).
Columns: the baseline; ``noise`` cold (first call: builds the spectral filter) and warm (the filter
is cached, as when an interactive user re-seeds or changes the amplitude); ``field`` (the slicer's
mean-one multiplier); ``add_detail`` on a Hydrometeors dataset with all five species (one shared noise,
report included); the ratio warm noise / baseline; and the goal of warm noise where there is one (1 s at
128^3: a re-seeded detail field must come at once; it was a wall-clock unit test, tests/test_detail.py, until
speed goals moved here). Times are the median of ``--repeat`` runs with a fresh seed each (so nothing but the
filter is cached).
"""
from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

import weather_mi as wm
from weather_mi.optics import detail

SHAPES = [(64, 64, 64), (128, 128, 128), (64, 256, 256)]  # (z, y, x); the last is 256 x 256 x 64
GOAL_WARM_S = {(128, 128, 128): 1.0}  # warm noise, seconds


def timed(fn, repeat):
    times = []
    for i in range(repeat):
        t0 = time.perf_counter()
        fn(i)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    r = args.repeat
    print(f"weather_mi.optics.detail: spectral synthesis, float32, scipy.fft on {os.cpu_count()} CPU threads; "
          f"median of {r} runs (ms)")
    print(f"{'grid (z, y, x)':<18}{'baseline':>10}{'noise cold':>12}{'noise warm':>12}{'field':>9}"
          f"{'add_detail':>12}{'noise/base':>12}{'goal (warm)':>14}")
    spacing = (250.0, 500.0, 500.0)
    for shape in SHAPES:
        base = timed(lambda i: np.random.default_rng(i).standard_normal(shape, dtype=np.float32), r)
        detail._spectral_filter.cache_clear()
        t0 = time.perf_counter()
        detail.noise(shape, spacing, seed=1000)
        cold = time.perf_counter() - t0
        warm = timed(lambda i: detail.noise(shape, spacing, seed=i), r)
        fld = timed(lambda i: detail.field(shape, seed=i, spacing_m=spacing), r)
        q = np.full(shape, 1e-3, np.float32)
        hyd = wm.from_arrays({n: q for n in wm.SPECIES_NAMES}, rho_air=np.linspace(1.2, 0.3, shape[0]),
                             spacing=spacing)
        add = timed(lambda i: detail.add_detail(hyd, seed=i), r)
        label = "x".join(str(n) for n in shape)
        print(f"{label:<18}{1e3 * base:>10.1f}{1e3 * cold:>12.1f}{1e3 * warm:>12.1f}{1e3 * fld:>9.1f}"
              f"{1e3 * add:>12.1f}{warm / base:>11.2f}x{_goal(shape, warm):>14}")


def _goal(shape, warm_s: float) -> str:
    """'< GOAL s: yes/NO' for a grid with a goal, else '-'."""
    goal = GOAL_WARM_S.get(tuple(shape))
    return "-" if goal is None else f"< {goal:g} s: {'yes' if warm_s < goal else 'NO'}"


if __name__ == "__main__":
    main()
