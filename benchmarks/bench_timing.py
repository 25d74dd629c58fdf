"""What the goal benchmarks share (``les_read.py``, ``viewer_pick.py``, ``domain_refusal.py``): wall-clock rounds
of a call after a warm-up, and their table's row (the goal judged on the median). Not a benchmark itself."""
from __future__ import annotations

import statistics
import time


def timed(fn, rounds: int) -> list:
    """Wall seconds of ``rounds`` calls of ``fn`` after one warm-up call."""
    fn()
    out = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return out


def goal_header(baseline: str, measured: str, unit: str = "s") -> str:
    """The header of :func:`goal_row`'s table: ``baseline`` and ``measured`` name the two timed calls."""
    return (f"| case | baseline: {baseline} ({unit}) | {measured} median ({unit}) | {measured} best ({unit}) | ratio | "
            f"goal ({unit}) | met |\n|---|---|---|---|---|---|---|")


def goal_row(case: str, baseline: list, measured: list, goal_s: float, unit: str = "s") -> str:
    """The table row ``| case | baseline median | median | best | ratio | goal | met |`` of wall-clock rounds
    (seconds), printed in ``unit`` ("s" or "ms"); met when the median is under ``goal_s``."""
    k, digits = (1e3, 2) if unit == "ms" else (1.0, 3)
    base, med = statistics.median(baseline), statistics.median(measured)
    return (f"| {case} | {k * base:.{digits}f} | {k * med:.{digits}f} | {k * min(measured):.{digits}f} | "
            f"{med / base:.3g}x | {k * goal_s:g} | {'yes' if med < goal_s else 'NO'} |")
