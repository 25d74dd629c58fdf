"""The effect of the particle sizes (issue 39 part 3): the WRF supercell (WSM6) and the Tibetan Plateau file
(Thompson, QNICE/QNRAIN) with the scheme's effective radii against the "physical" and "paper" presets' fixed
radii: the vertical optical depth over cloudy columns and a GOES-East 0.64 um reflectance (path-traced, the
mean over cloud pixels), all with the "physical" species table otherwise (densities, phase functions).

    .venv/bin/python validation/particle_sizes.py [--data ../shared/data] [--spp 16] [--resolution 2]
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

CASES = {"supercell (WSM6)": ("wrf/wrfout_quarter_ss_0130.nc", dict(lat=35.0, lon=-97.0, date="2024-05-20T21:00:00Z")),
         "plateau (Thompson)": ("wrf/wrf_d01_allvars_cropped.nc", {})}
SIZES = ("scheme", "physical", "paper")


def column_depths(vol) -> dict:
    tau = vol.optical_depth_z()
    cloudy = tau > 0.1
    return {"tau_mean": float(tau[cloudy].mean()) if cloudy.any() else 0.0, "tau_max": float(tau.max()),
            "cloudy_columns": int(cloudy.sum())}


def reflectance(hyd, vol, spp: int, resolution_km: float) -> dict:
    from weather_mi.satellite.imagery import render_satellite, satellite_scene
    scene = satellite_scene(hyd, vol, "goes-east", "0.64", resolution_km=resolution_km, rayleigh=False)
    ds, _ = render_satellite(scene, spp=spp, progress=False)
    cloud = ds.cloud.values.astype(bool)
    return {"reflectance_cloud_mean": float(ds.reflectance.values[cloud].mean()) if cloud.any() else float("nan"),
            "cloud_pixels": int(cloud.sum())}


def main(argv=None) -> int:
    import weather_mi as wm
    from weather_mi.scene.place import assume_place
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path("../shared/data"))
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--resolution", type=float, default=2.0, help="satellite pixel size (km)")
    ap.add_argument("--no-render", action="store_true", help="optical depths only")
    a = ap.parse_args(argv)
    print(f"{'case':20s} {'sizes':9s} {'tau mean':>9s} {'tau max':>9s} {'cloudy cols':>11s} "
          f"{'R 0.64 cloud':>13s} {'cloud px':>9s} {'s':>6s}")
    for case, (rel, place) in CASES.items():
        hyd = wm.open_wrf(a.data / rel)
        if place:
            hyd = assume_place(hyd, place["lat"], place["lon"], place["date"])
        for sizes in SIZES:
            t0 = time.perf_counter()
            vol = wm.optical_volume(hyd, "physical", sizes=sizes)
            row = column_depths(vol)
            if not a.no_render:
                row.update(reflectance(hyd, vol, a.spp, a.resolution))
            print(f"{case:20s} {sizes:9s} {row['tau_mean']:9.2f} {row['tau_max']:9.1f} {row['cloudy_columns']:11d} "
                  f"{row.get('reflectance_cloud_mean', np.nan):13.4f} {row.get('cloud_pixels', 0):9d} "
                  f"{time.perf_counter() - t0:6.1f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
