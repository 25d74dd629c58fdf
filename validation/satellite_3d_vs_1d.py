"""3-D against 1-D: synthetic satellite images by the path tracer beside the independent-pixel approximation
(every column a plane-parallel stack solved by DISORT, ``weather_mi.satellite.ipa``), on real model output.

    .venv/bin/python validation/satellite_3d_vs_1d.py [--spp N] [--quick] [--out docs/images] [--json out.json]

Cases: the WRF quarter-circle supercell (../shared/data/wrf/wrfout_quarter_ss_0130.nc, an ideal case,
placed at 35.2 N 97.4 W on 2013-05-20) seen by GOES-East at 1 km, and the Tibetan-plateau wrfout
(wrf_d01_allvars_cropped.nc, its own Lambert grid and terrain) seen by Himawari at 2 km, each under a high
and a low sun (the sun of two times over the same clouds). Band 0.64 um, no Rayleigh (the 1-D side has
the same optics: ``ipa`` uses the path tracer's delta-M tables). Per case: the table row of R_3D - R_1D
over cloud pixels (eye-ray transmittance below 1/2 in the 3-D view): mean, percentiles 5/25/50/75/95,
and a figure (3-D | 1-D | difference) in ``--out``.

The 1-D image has no parallax (each pixel the column below its ground point), as 1-D operators have
none: the difference map holds shadows, lit and shaded cloud sides, side leakage and parallax together.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
DATA = ROOT.parent / "shared" / "data" / "wrf"

CASES = [  # (label, file, time index, place or None, satellite, resolution km, sun time)
    ("supercell, high sun", "wrfout_quarter_ss_0130.nc", None, (35.2, -97.4), "goes-east", 1.0, "2013-05-20T18:30"),
    ("supercell, low sun", "wrfout_quarter_ss_0130.nc", None, (35.2, -97.4), "goes-east", 1.0, "2013-05-20T23:40"),
    ("plateau, high sun", "wrf_d01_allvars_cropped.nc", 1, None, "himawari", 2.0, "2005-09-21T06:00"),
    ("plateau, low sun", "wrf_d01_allvars_cropped.nc", 1, None, "himawari", 2.0, "2005-09-21T01:00"),
]


def open_case(file, time_index, place):
    import weather_mi as wm
    from weather_mi.scene.place import assume_place
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        hyd = wm.open_wrf(DATA / file, **({} if time_index is None else {"time": time_index}))
    return hyd if place is None else assume_place(hyd, *place, "2013-05-20T20:00")


def run_case(case, spp: int, resolution_scale: float = 1.0) -> tuple[dict, dict]:
    import weather_mi as wm
    from weather_mi.satellite.ipa import ipa_reflectance
    from weather_mi.satellite.imagery import render_satellite, satellite_scene
    label, file, t_index, place, sat, res, sun_time = case
    hyd = open_case(file, t_index, place)
    vol = wm.optical_volume(hyd, species="physical")
    scene = satellite_scene(hyd, vol, sat, "0.64", res * resolution_scale, sun_time=sun_time)
    t0 = time.perf_counter()
    ds, _ = render_satellite(scene, spp=spp, progress=False)
    t3 = time.perf_counter() - t0
    t0 = time.perf_counter()
    r1 = ipa_reflectance(scene, progress=False)
    t1 = time.perf_counter() - t0
    r3 = ds.reflectance.values.astype(np.float64)
    cloud = ds.cloud.values.astype(bool) & ds.in_domain.values.astype(bool)
    d = (r3 - r1)[cloud]
    p = np.percentile(d, [5, 25, 50, 75, 95]) if d.size else [np.nan] * 5
    row = {"case": label, "satellite": sat, "pixels": f"{r3.shape[1]}x{r3.shape[0]}", "resolution_km": res * resolution_scale,
           "sza_deg": 90.0 - scene.spec.sun.elevation, "vza_deg": float(np.mean(ds.sensor_zenith_angle.values[cloud])) if d.size else np.nan,
           "cloud_pixels": int(cloud.sum()), "R3_mean": float(r3[cloud].mean()), "R1_mean": float(r1[cloud].mean()),
           "diff_mean": float(d.mean()), "p5": p[0], "p25": p[1], "p50": p[2], "p75": p[3], "p95": p[4],
           "rse_3d": float(ds.attrs["cloud_rse_mean"]), "spp": spp, "seconds_3d": t3, "seconds_1d": t1}
    return row, {"r3": r3, "r1": r1, "cloud": cloud}


def figure(label, images, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    r3, r1 = images["r3"], images["r1"]
    fig, ax = plt.subplots(1, 3, figsize=(12, 4.2), constrained_layout=True)
    for a, img, title in ((ax[0], r3, "3-D (path traced)"), (ax[1], r1, "1-D (IPA, DISORT)")):
        im = a.imshow(np.clip(img, 0, None) ** 0.5, cmap="gray", vmin=0, vmax=1.1)
        a.set_title(title)
    fig.colorbar(im, ax=ax[:2], shrink=0.8, label="sqrt(reflectance)")
    lim = float(np.nanpercentile(np.abs(r3 - r1), 99)) or 0.1
    im = ax[2].imshow(r3 - r1, cmap="RdBu_r", vmin=-lim, vmax=lim)
    ax[2].set_title("R_3D - R_1D")
    fig.colorbar(im, ax=ax[2], shrink=0.8)
    for a in ax:
        a.set_xticks([]), a.set_yticks([])
    fig.suptitle(f"{label}: 0.64 um reflectance on the fixed grid")
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--quick", action="store_true", help="4x coarser pixels, 16 spp")
    ap.add_argument("--out", default=None, help="folder of the figures (none without)")
    ap.add_argument("--json", default=None)
    ap.add_argument("--only", default="", help="the cases whose label contains this text (e.g. plateau)")
    args = ap.parse_args(argv)
    import weather_mi as wm
    wm.set_variant("llvm_ad_rgb")
    spp, scale = (16, 4.0) if args.quick else (args.spp, 1.0)
    rows = []
    print(f"{'case':22s} {'px':>8s} {'SZA':>5s} {'VZA':>5s} {'cloud':>6s} {'R3D':>6s} {'R1D':>6s} {'mean':>7s} "
          f"{'p5':>7s} {'p25':>7s} {'p50':>7s} {'p75':>7s} {'p95':>7s} {'RSE':>5s} {'s 3D':>6s} {'s 1D':>6s}")
    for case in (c for c in CASES if args.only in c[0]):
        row, images = run_case(case, spp, scale)
        rows.append(row)
        print(f"{row['case']:22s} {row['pixels']:>8s} {row['sza_deg']:5.1f} {row['vza_deg']:5.1f} {row['cloud_pixels']:6d} "
              f"{row['R3_mean']:6.3f} {row['R1_mean']:6.3f} {row['diff_mean']:+7.3f} " +
              " ".join(f"{row[k]:+7.3f}" for k in ("p5", "p25", "p50", "p75", "p95")) +
              f" {row['rse_3d']:5.3f} {row['seconds_3d']:6.1f} {row['seconds_1d']:6.1f}", flush=True)
        if args.out:
            Path(args.out).mkdir(parents=True, exist_ok=True)
            name = row["case"].replace(", ", "_").replace(" ", "_")
            figure(row["case"], images, Path(args.out) / f"satellite_3d_vs_1d_{name}.png")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
