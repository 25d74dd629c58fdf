"""The effect of the particle sizes (issue 39 part 3): the WRF supercell (WSM6) and the Tibetan Plateau file
(Thompson, QNICE/QNRAIN) with the scheme's effective radii against the "physical" and "paper" presets' fixed
radii: the vertical optical depth over cloudy columns (tau > 0.1), a geostationary 0.64 um reflectance
(path-traced, the mean over the product's cloud pixels; GOES-East over the supercell placed in Oklahoma,
Himawari over the plateau) and the mean luminance over the cloud pixels of the command line's default ground
view, all with the "physical" species table otherwise (densities, phase functions).

    .venv/bin/python validation/particle_sizes.py [--data ../shared/data] [--spp 16] [--resolution 2]
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

CASES = {"supercell (WSM6)": ("wrf/wrfout_quarter_ss_0130.nc", "goes-east",
                              dict(lat=35.0, lon=-97.0, date="2024-05-20T21:00:00Z")),
         "plateau (Thompson)": ("wrf/wrf_d01_allvars_cropped.nc", "himawari", {})}
SIZES = ("scheme", "physical", "paper")


def column_depths(vol) -> dict:
    tau = vol.optical_depth_z()
    cloudy = tau > 0.1
    return {"tau_mean": float(tau[cloudy].mean()) if cloudy.any() else 0.0, "tau_max": float(tau.max()),
            "cloudy_columns": int(cloudy.sum())}


def luminance(vol, spp: int) -> dict:
    """The mean luminance (Rec. 709 Y of the radiance, W/m^2/sr for a unit sun) over the cloud pixels of the
    command line's default view (a photographer on the ground, ``scene.framing``), 96 x 72 pixels."""
    import weather_mi as wm
    from weather_mi.reference.estimates import cloud_mask
    from weather_mi.scene.framing import scene_spec
    spec = scene_spec(vol, (96, 72))
    img = wm.render_reference(spec, vol, spp=spp, progress=False)
    y = np.asarray(img.radiance)[..., :3] @ np.array([0.2126, 0.7152, 0.0722])
    mask = cloud_mask(spec, vol)
    return {"luminance_cloud_mean": float(y[mask].mean()) if mask.any() else float("nan")}


def reflectance(hyd, vol, sat: str, spp: int, resolution_km: float) -> dict:
    from weather_mi.satellite.imagery import render_satellite, satellite_scene
    scene = satellite_scene(hyd, vol, sat, "0.64", resolution_km=resolution_km, rayleigh=False)
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
    ap.add_argument("--size-classes", type=int, default=None, metavar="N",
                    help="also the scheme's sizes as N size classes with their own phase tables (row scheme+N)")
    a = ap.parse_args(argv)
    print(f"{'case':20s} {'sizes':9s} {'tau mean':>9s} {'tau max':>9s} {'cloudy cols':>11s} "
          f"{'R 0.64 cloud':>13s} {'cloud px':>9s} {'Y ground view':>14s} {'s':>6s}")
    for case, (rel, sat, place) in CASES.items():
        hyd = wm.open_wrf(a.data / rel)
        if place:
            hyd = assume_place(hyd, place["lat"], place["lon"], place["date"])
        rows = [(s, None) for s in SIZES] + ([("scheme", a.size_classes)] if a.size_classes else [])
        for sizes, classes in rows:
            t0 = time.perf_counter()
            vol = wm.optical_volume(hyd, "physical", sizes=sizes, size_classes=classes)
            row = column_depths(vol)
            if not a.no_render:
                row.update(reflectance(hyd, vol, sat, a.spp, a.resolution))
                row.update(luminance(vol, a.spp))
            label = sizes if classes is None else f"{sizes}+{classes}"
            print(f"{case:20s} {label:9s} {row['tau_mean']:9.2f} {row['tau_max']:9.1f} {row['cloudy_columns']:11d} "
                  f"{row.get('reflectance_cloud_mean', np.nan):13.4f} {row.get('cloud_pixels', 0):9d} "
                  f"{row.get('luminance_cloud_mean', np.nan):14.4f} "
                  f"{time.perf_counter() - t0:6.1f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
