"""What the goal benchmarks share (``les_read.py``, ``viewer_pick.py``, ``domain_refusal.py``): wall-clock rounds
of a call after a warm-up. Not a benchmark itself."""
from __future__ import annotations

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
