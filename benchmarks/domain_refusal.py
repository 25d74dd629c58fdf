"""How soon a domain too large for memory is refused (``wm.open_wrf`` raising ``DomainTooLargeError`` from the
file's dimensions, before reading or allocating its grid): a wrfout declared 100 x 200000 x 200000 (4e12 cells,
fields never written: a few KB on disk, tests/test_input_faults.py's ``huge_wrfout``), median and best of
--rounds after one warm-up, against a baseline in the same process: the file opened with netCDF4 and its
dimensions and attributes read (the least any reader does), and the goal of 5 s (it was a wall-clock assert
beside the memory bound in the test; speed goals live here).

    .venv/bin/python benchmarks/domain_refusal.py [--rounds 5]
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from bench_timing import goal_header, goal_row, timed  # noqa: E402 (benchmarks/, the script's folder, is on sys.path)

GOAL_S = 5.0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args(argv)
    import netCDF4
    import weather_mi as wm
    from test_input_faults import huge_wrfout
    os.environ.pop("WEATHER_MI_MAX_MEMORY_GB", None)  # the machine's own memory, as a user's run

    def refuse():
        try:
            wm.open_wrf(path)
        except wm.errors.DomainTooLargeError:
            return
        raise AssertionError(f"{path}: not refused")

    def metadata():
        with netCDF4.Dataset(path) as nc:
            return {k: len(v) for k, v in nc.dimensions.items()}, nc.__dict__

    with tempfile.TemporaryDirectory() as tmp:
        path = huge_wrfout(Path(tmp) / "huge.nc", 100, 200_000, 200_000)
        base = timed(metadata, args.rounds)
        refusals = timed(refuse, args.rounds)
    print(goal_header("netCDF4 metadata", "refusal", unit="ms"))
    print(goal_row("100 x 200000 x 200000 wrfout", base, refusals, GOAL_S, unit="ms"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
