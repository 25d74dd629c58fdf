"""Build every phase table at a given quality in a fresh cache folder and report compute time, asymmetry
g per channel (R, G, B), the energy fraction within 10 deg of forward, and the rainbow / halo angles.

    .venv/bin/python benchmarks/phase_tables.py [--quality default] [--cache DIR]

Without --cache a temporary folder is used, so every table is computed from scratch.
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np


def peak_deg(table, lo, hi, channel):
    th = np.degrees(table.theta)
    m = (th >= lo) & (th <= hi)
    return round(float(th[m][np.argmax(table.values[m, channel])]), 2)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quality", default="default", choices=("test", "default", "high"))
    ap.add_argument("--cache", default=None, help="cache folder (default: a new temporary folder)")
    args = ap.parse_args()
    folder = args.cache or tempfile.mkdtemp(prefix="weather-mi-phase-")
    os.environ["WEATHER_MI_CACHE"] = folder
    from weather_mi.optics import phase  # after setting the cache folder

    q = args.quality
    builds = [
        ("henyey_greenstein(0.85)", lambda: phase.henyey_greenstein(0.85)),
        ("cornette_shanks(0.825)", lambda: phase.cornette_shanks(0.825)),
        ("mie_cloud()", lambda: phase.mie_cloud(quality=q)),
        ("mie_rain(1 mm)", lambda: phase.mie_rain(quality=q)),
        ("ice_crystals('column')", lambda: phase.ice_crystals("column", quality=q)),
        ("ice_crystals('plate')", lambda: phase.ice_crystals("plate", quality=q)),
        ("snow()", lambda: phase.snow(quality=q)),
        ("graupel()", lambda: phase.graupel(quality=q)),
    ]
    print(f"quality={q}, cache={folder}")
    for name, build in builds:
        t0 = time.perf_counter()
        table = build()
        dt = time.perf_counter() - t0
        g = " ".join(f"{x:.4f}" for x in table.g)
        cone = " ".join(f"{x:.3f}" for x in table.cone_fraction(np.radians(10)))
        line = f"{name:26s} {dt:7.1f} s  {table.theta.size:5d} angles  g (R G B) {g}  F(10 deg) {cone}"
        if "rain" in name:
            line += (f"\n{'':28s}primary bow {[peak_deg(table, 130.5, 145, c) for c in range(3)]} deg, "
                     f"secondary {[peak_deg(table, 123, 133, c) for c in range(3)]} deg")
        if "column" in name or "plate" in name:
            line += (f"\n{'':28s}22 deg halo {[peak_deg(table, 18, 26, c) for c in range(3)]} deg, "
                     f"46 deg halo {[peak_deg(table, 42, 50, c) for c in range(3)]} deg")
        print(line, flush=True)


if __name__ == "__main__":
    main()
