"""The memory a grid will need, checked before it is allocated: a domain that cannot fit raises
``errors.DomainTooLargeError`` (the estimate in GB and what to do) instead of swapping or being killed.

The estimates are peak bytes per cell of the (z, y, x) grid, measured on the real WRF supercell tiled to
800 x 800 x 51 (``benchmarks/cli_memory.py``): reading a wrfout (the float32 Hydrometeors, 24 bytes per
cell, and the reader's working set), and building an OpticalVolume beside the Hydrometeors (its grids,
56 bytes per cell, and two grids of temporaries); the memory already in use (the interpreter, the
libraries, the Hydrometeors) is not counted, as the memory available excludes it. The memory available is the environment's
``WEATHER_MI_MAX_MEMORY_GB`` where set, else the smaller of the system's available memory and the
cgroup's limit.
"""
from __future__ import annotations

import os
from pathlib import Path

from ..errors import DomainTooLargeError

BYTES_PER_CELL = {"reading": 48, "optics": 64}  # beyond what is allocated before the step (the Hydrometeors for optics)


def available_bytes() -> float:
    """The memory this process may plan for (bytes): ``WEATHER_MI_MAX_MEMORY_GB``, else the system's available
    memory, capped by a cgroup (v2) limit."""
    env = os.environ.get("WEATHER_MI_MAX_MEMORY_GB")
    if env:
        return float(env) * 1e9
    sizes = []
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                sizes.append(int(line.split()[1]) * 1024.0)
    except OSError:
        pass
    try:
        limit = Path("/sys/fs/cgroup/memory.max").read_text().strip()
        if limit != "max":
            used = float(Path("/sys/fs/cgroup/memory.current").read_text())
            sizes.append(float(limit) - used)
    except (OSError, ValueError):
        pass
    if not sizes:
        try:
            sizes.append(float(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")))
        except (ValueError, OSError, AttributeError):
            return float("inf")
    return max(min(sizes), 0.0)


def estimate_bytes(shape, step: str) -> float:
    """Peak bytes that ``step`` ("reading", "optics") allocates on a grid of ``shape`` (z, y, x)."""
    cells = 1
    for n in shape:
        cells *= int(n)
    return BYTES_PER_CELL[step] * float(cells)


def check_fits(source: str, shape, step: str) -> None:
    """Raise DomainTooLargeError, before any allocation, where ``step`` on a ``shape`` grid needs more memory
    than is available."""
    needed, available = estimate_bytes(shape, step), available_bytes()
    if needed > available:
        raise DomainTooLargeError(source, tuple(int(n) for n in shape), step, needed, available)
