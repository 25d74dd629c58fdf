"""Resident memory (bytes per grid cell) of ``weather-mi view FILE`` by phase, in one process: the input read and
its optics (``Storm``), the slicer warmed up for the first 320 x 240 view, a hover read-out (the first dense voxel
under a pixel and its mixing ratios), and Dr.Jit's freed buffers handed back. "rss" is the process's resident set
after the phase, "peak" its high-water mark so far (VmHWM), both over the cells of the storm's grid, the
interpreter and its libraries included.

    .venv/bin/python benchmarks/view_memory_phases.py /tmp/weather-mi-tiles/wrfout_supercell_800x800.nc
    .venv/bin/python benchmarks/view_memory_phases.py FILE --repo /tmp/viewmem-base     # another tree's weather_mi

The tiled files are those of ``benchmarks/cli_memory.py`` (it writes them).
"""
from __future__ import annotations

import argparse
import gc
import sys
import time


def resident() -> tuple[int, int]:
    """(VmRSS, VmHWM) of this process in bytes."""
    got = {}
    with open("/proc/self/status") as f:
        for line in f:
            key, _, value = line.partition(":")
            if key in ("VmRSS", "VmHWM"):
                got[key] = int(value.split()[0]) * 1024
    return got["VmRSS"], got["VmHWM"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("file")
    ap.add_argument("--repo", help="a tree whose weather_mi to import (default: the installed one)")
    args = ap.parse_args(argv)
    if args.repo:
        sys.path.insert(0, args.repo)
    import weather_mi
    from weather_mi.cli.commands import release_freed_memory
    from weather_mi.viewer.recipe import VolumeRecipe
    from weather_mi.viewer.serve import prepare
    print("weather_mi from", weather_mi.__file__)
    release_freed_memory()
    cells = None

    def phase(name, seconds):
        gc.collect()
        rss, hwm = resident()
        print(f"{name:24s} {seconds:7.1f} s  rss {rss / cells:6.1f} B/cell  peak {hwm / cells:6.1f} B/cell", flush=True)

    t = time.perf_counter()
    storm, state = prepare(VolumeRecipe(path=args.file), None, size=(320, 240), warm=False, progress=lambda s: None)
    cells = int(storm.shape[0]) * int(storm.shape[1]) * int(storm.shape[2])
    print(f"grid {storm.shape} (z, y, x): {cells} cells")
    phase("storm (read, optics)", time.perf_counter() - t)
    t = time.perf_counter()
    storm.warm_up(state)
    phase("slicer warmed up", time.perf_counter() - t)
    from weather_mi.viewer.pick import first_dense_voxel
    spec = state.spec(storm.frame, storm.ground_m)
    t = time.perf_counter()  # before: reopening the Hydrometeors is part of the read-out
    readout = storm.mixing_ratios(state.time) if hasattr(storm, "mixing_ratios") else storm.hydrometeors(state.time)
    first_dense_voxel(readout, storm.volume(state.time), spec, state.width / 2, state.height / 2)
    phase("hover read-out", time.perf_counter() - t)
    import drjit as dr
    dr.flush_malloc_cache()
    phase("Dr.Jit cache handed back", 0.0)
    return 0


if __name__ == "__main__":
    sys.exit(main())
