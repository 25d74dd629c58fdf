"""Time and peak memory of loading the real WRF supercell and of optical_volume on a 500 x 500 x 100
grid (the size of the Hurricane Isabel data set), each with a baseline run in the same process, and the
peak per grid cell of the result (bytes per cell: issue 39's measure; the whole CLI's, by peak RSS on tiled
domains, is ``benchmarks/cli_memory.py``).

    .venv/bin/python benchmarks/load_optics.py [--shape 100 500 500]

Baselines: reading the same variables raw with netCDF4 (for the reader), and one float32 pass that
computes Eq. 4 for a single species (for optical_volume: the least any implementation must do per species).
"""
from __future__ import annotations

import argparse
import gc
import time
import tracemalloc
from pathlib import Path

import netCDF4
import numpy as np

import weather_mi as wm

WRF = Path(__file__).resolve().parents[2] / "shared" / "data" / "wrf" / "wrfout_quarter_ss_0130.nc"


def measure(fn, repeat=3):
    """(best wall time in s, peak traced memory in MiB, grid cells of the result) of fn()."""
    times, peak, cells = [], 0, 0
    for _ in range(repeat):
        gc.collect()
        tracemalloc.start()
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
        peak = max(peak, tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
        cells = grid_cells(out)
        del out
    return min(times), peak / 2 ** 20, cells


def grid_cells(out) -> int:
    """The (z, y, x) cells of a result: a Hydrometeors Dataset, an OpticalVolume, an array or arrays."""
    if hasattr(out, "beta_total"):
        return int(np.asarray(out.beta_total).size)
    if hasattr(out, "data_vars"):
        return int(out["q_cloud"].size)
    if isinstance(out, (list, tuple)):
        return max(grid_cells(o) for o in out)
    return int(np.asarray(out).size)


def raw_read():
    names = ("P", "PB", "T", "QVAPOR", "PH", "PHB", "QCLOUD", "QRAIN", "QICE", "QSNOW", "QGRAUP")
    with netCDF4.Dataset(WRF) as nc:
        return [nc[n][0] for n in names]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--shape", type=int, nargs=3, default=(100, 500, 500), metavar=("NZ", "NY", "NX"))
    args = ap.parse_args()
    rows = []
    if WRF.is_file():
        base = measure(raw_read)
        load = measure(lambda: wm.open_wrf(WRF))
        rows.append(("netCDF4 raw read of 11 variables (baseline)", *base, 1.0, 1.0))
        rows.append(("wm.open_wrf(wrfout_quarter_ss_0130.nc)", *load, load[0] / base[0], load[1] / base[1]))
    else:
        print(f"(skipping the WRF rows: {WRF} is absent)")

    shape = tuple(args.shape)
    rng = np.random.default_rng(0)
    field = (rng.random(shape, dtype=np.float32) * 1e-3).astype(np.float32)
    hyd = wm.from_arrays({s: field for s in wm.SPECIES_NAMES}, np.linspace(1.2, 0.2, shape[0]),
                         (200.0, 1000.0, 1000.0))
    rho = hyd.rho_air.values
    cloud = wm.species.preset("paper")["cloud"]
    base = measure(lambda: cloud.beta_ext_per_m(rho, field), repeat=2)
    opt = measure(lambda: wm.optical_volume(hyd), repeat=2)
    label = "x".join(map(str, shape))
    rows.append((f"Eq. 4 for one species on {label} (baseline)", *base, 1.0, 1.0))
    rows.append((f"wm.optical_volume on {label}", *opt, opt[0] / base[0], opt[1] / base[1]))

    print(f"{'case':<52}{'time (s)':>10}{'peak (MiB)':>12}{'B/cell':>8}{'time ratio':>12}{'mem ratio':>11}")
    for name, t, m, cells, rt, rm in rows:
        print(f"{name:<52}{t:>10.3f}{m:>12.1f}{m * 2 ** 20 / max(cells, 1):>8.0f}{rt:>12.2f}{rm:>11.2f}")
    import resource
    print(f"process max RSS: {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")


if __name__ == "__main__":
    main()
