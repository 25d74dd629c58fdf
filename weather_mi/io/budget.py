"""The memory a grid will need, checked before it is allocated: a domain that cannot fit raises
``errors.DomainTooLargeError`` (the estimate in GB and what to do) instead of swapping or being killed.

The estimates are peak bytes per cell of the (z, y, x) grid, measured on the real WRF supercell tiled to
800 x 800 x 51 (``benchmarks/cli_memory.py``): reading a wrfout (the float32 Hydrometeors, 24 bytes per
cell, and the reader's working set), and building an OpticalVolume beside the Hydrometeors (its grids,
56 bytes per cell, and two grids of temporaries); the memory already in use (the interpreter, the
libraries, the Hydrometeors) is not counted, as the memory available excludes it. The memory available is
the environment's ``WEATHER_MI_MAX_MEMORY_GB`` where set, else the smaller of the system's available memory
and the room left under the memory limits of the process's cgroup (v1 or v2) and its ancestors.
"""
from __future__ import annotations

import os
from pathlib import Path

from ..errors import DomainTooLargeError

BYTES_PER_CELL = {"reading": 48, "reading_sizes": 72, "optics": 64}  # beyond what is allocated before the step
# (the Hydrometeors for optics); "reading_sizes": reading with the scheme's radii (io.particle_sizes; 20 bytes per
# cell held: five radius grids): 72 = the reader's peak over the memory at its start on 800 x 800 x 51
# (benchmarks/memory_phases.py, issue 39: 7 -> 79 bytes per cell; 76 before each grid was freed as soon as used).
# "optics": its grids (56) and temporaries, as the library allocates them (the command line's release=True frees
# the input as it goes: +36 over the Hydrometeors measured there)


UNLIMITED = 1 << 60  # cgroup v1 writes "no limit" as a page-rounded 2^63 - 1; v2 writes "max"


def available_bytes(proc: str = "/proc", cgroup_root: str = "/sys/fs/cgroup") -> float:
    """The memory this process may plan for (bytes): ``WEATHER_MI_MAX_MEMORY_GB``, else the system's
    available memory (``MemAvailable``), capped by the room left under every memory limit of the process's
    cgroup and its ancestors (v2 ``memory.max`` - ``memory.current``, v1 ``memory.limit_in_bytes`` -
    ``memory.usage_in_bytes``); unreadable files are skipped, and infinity where nothing is known."""
    env = os.environ.get("WEATHER_MI_MAX_MEMORY_GB")
    if env:
        return float(env) * 1e9
    sizes = [kb * 1024.0 for kb in _meminfo_kb(Path(proc) / "meminfo", "MemAvailable")]
    sizes += _cgroup_room(Path(proc) / "self" / "cgroup", Path(cgroup_root))
    return max(min(sizes), 0.0) if sizes else float("inf")


def _read(path: Path) -> str | None:
    try:
        return path.read_text()
    except (OSError, UnicodeDecodeError):
        return None


def _meminfo_kb(path: Path, key: str) -> list[float]:
    for line in (_read(path) or "").splitlines():
        if line.startswith(key + ":"):
            try:
                return [float(line.split()[1])]
            except (IndexError, ValueError):
                return []
    return []


def _cgroup_room(self_cgroup: Path, root: Path) -> list[float]:
    """limit - usage of each memory-limited cgroup from the process's own up to the hierarchy's root."""
    rooms = []
    for line in (_read(self_cgroup) or "").splitlines():
        parts = line.strip().split(":", 2)
        if len(parts) != 3:
            continue
        if parts[0] == "0" and parts[1] == "":  # v2 unified hierarchy
            base, limit_file, usage_file = root, "memory.max", "memory.current"
        elif "memory" in parts[1].split(","):  # v1 memory controller
            base, limit_file, usage_file = root / "memory", "memory.limit_in_bytes", "memory.usage_in_bytes"
        else:
            continue
        rel = Path(parts[2].lstrip("/"))
        for d in [base / rel, *[base / p for p in rel.parents]]:
            limit, usage = _read(d / limit_file), _read(d / usage_file)
            try:
                if limit is not None and usage is not None and float(limit) < UNLIMITED:
                    rooms.append(float(limit) - float(usage))
            except ValueError:  # "max"
                pass
    return rooms


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
