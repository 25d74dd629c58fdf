"""Reading the real LES files (``io.les.open_les``: BOMEX and RICO, ../shared/data/les) against a baseline in the
same process: the file read and split into tokens (``Path.read_text().split()``, the least any reader of the text
must do). Median and best of --rounds after one warm-up read, wall clock, and the goal of 3 s a file (it was a
wall-clock assert in tests/test_les.py; speed goals live here).

    .venv/bin/python benchmarks/les_read.py [--data ../shared/data] [--rounds 5]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from bench_timing import goal_row, timed  # noqa: E402 (benchmarks/, the script's folder, is on sys.path)

GOAL_S = 3.0
FILES = ("bomex_50m.txt", "rico_20m.txt")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", type=Path, default=HERE.parents[1] / "shared" / "data")
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args(argv)
    from weather_mi.io.les import open_les
    print("| file | baseline median (s) | open_les median (s) | open_les best (s) | ratio | goal (s) | met |\n"
          "|---|---|---|---|---|---|---|")
    for name in FILES:
        path = args.data / "les" / name
        if not path.is_file():
            print(f"| {name} | absent ({path}) | | | | | |")
            continue
        print(goal_row(name, timed(lambda: path.read_text().split(), args.rounds),
                       timed(lambda: open_les(path), args.rounds), GOAL_S))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
