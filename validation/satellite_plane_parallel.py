"""The satellite view of a horizontally uniform cloud layer against DISORT (issue 23's plane-parallel check).

    .venv/bin/python validation/satellite_plane_parallel.py [--spp N] [--quick] [--json out.json]

A layer of cloud droplets 1 km thick (cloud base 1 km, tau 2, 10 or 50; 400 x 400 km, black surface, no
Rayleigh) is placed where a GOES-East pixel sees it at three view zenith angles and lit by three suns, and
rendered by the ``satellite`` pipeline (fixed-grid pixels of 10 km, ``satellite_scene`` +
``render_satellite``: the table's rays, the 0.64 um band's Mie table, reflectance pi L / (E0 mu0)). The
mean reflectance of the pixels whose ground point lies within 50 km of the centre (far from the layer's
edges) is compared with DISORT (``weather_mi.satellite.ipa.disort_reflectance``: 64 streams, delta-M,
Nakajima-Tanaka with 2048 Legendre moments of the same table), solved for every one of those pixels with
its own sun and view directions in the domain's frame and averaged alike.

Criterion per case: |R_MC - R_DISORT| <= max(1% of R_DISORT, 3 combined standard errors) (the DISORT
side's error, from the moments' truncation, is below 0.2% here: 1024 vs 2048 moments).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

# (label, latitude, longitude of the layer's centre, sun azimuth, sun elevation in the domain's frame)
GEOMETRIES = [("near nadir, high sun", 5.0, -75.0, 120.0, 60.0),
              ("VZA ~45, sun opposite", 35.0, -100.0, 300.0, 40.0),
              ("VZA ~65, low sun", 50.0, -120.0, 150.0, 25.0)]
TAUS = (2.0, 10.0, 50.0)
N_MOMENTS = 2048
PIXEL_KM = 10.0


def layer(tau: float, lat: float, lon: float):
    """Hydrometeors of the uniform layer (tau over 1 km of cloud water), placed at (lat, lon) on 2024-06-21."""
    import weather_mi as wm
    from weather_mi.scene.place import assume_place
    from weather_mi.optics.species import preset
    nz, n, dz, dx = 12, 40, 100.0, 10000.0
    rho = 1.0
    r = preset("physical")["cloud"].radius_m
    q = np.zeros((nz, n, n), np.float32)
    q[1:11] = tau / 1000.0 * 2.0 * 1000.0 * r / (3.0 * rho)  # beta = 3 rho q / (2 rho_w r) = tau / 1 km (Eq. 4)
    hyd = wm.hydrometeors.from_arrays({"cloud": q}, rho, (dz, dx, dx), origin=(950.0, 0.0, 0.0),
                                      source=f"uniform layer tau {tau:g}")
    return assume_place(hyd, lat, lon, "2024-06-21T17:00")


def run_case(tau, geometry, spp, seed=1) -> dict:
    import weather_mi as wm
    from weather_mi.satellite.ipa import disort_reflectance, pixel_directions, scattering_geometry
    from weather_mi.satellite.imagery import render_satellite, satellite_scene
    label, lat, lon, sun_az, sun_el = geometry
    hyd = layer(tau, lat, lon)
    vol = wm.optical_volume(hyd, species="physical")
    scene = satellite_scene(hyd, vol, "goes-east", "0.64", PIXEL_KM, ground_albedo=0.0, seed=seed)
    sun = wm.Sun(sun_az, sun_el, (1.0, 1.0, 1.0))
    scene = dataclasses.replace(scene, spec=dataclasses.replace(scene.spec, sun=sun))
    t0 = time.perf_counter()
    ds, _ = render_satellite(scene, spp=spp, progress=False)
    seconds = time.perf_counter() - t0
    (x0, y0, _), (x1, y1, _) = vol.bbox
    v = scene.view
    centre = np.hypot(v.x_m - (x0 + x1) / 2, v.y_m - (y0 + y1) / 2) < 50e3
    tab = scene.vol.phase_tables[0]
    moments = np.asarray(tab.legendre(N_MOMENTS), np.float64)[:, 0]
    ssa = float(np.asarray(scene.vol.albedo)[5, 20, 20, 0])
    ref = [disort_reflectance([tau], [ssa], moments[None], *scattering_geometry(sun.to_sun, u), n_streams=64)
           for u in pixel_directions(scene)[centre]]
    refl = ds.reflectance.values[centre].astype(np.float64)
    se = ds.reflectance_standard_error.values[centre].astype(np.float64)
    mc, mc_se, r = float(refl.mean()), float(np.sqrt(np.sum(se ** 2)) / se.size), float(np.mean(ref))
    ok = abs(mc - r) <= max(0.01 * r, 3.0 * mc_se)
    return {"tau": tau, "geometry": label, "vza_deg": float(ds.sensor_zenith_angle.values[centre].mean()),
            "sza_deg": 90.0 - sun_el, "pixels": int(centre.sum()), "R_mc": mc, "se": mc_se, "R_disort": r,
            "rel_diff": (mc - r) / r, "ok": bool(ok), "spp": spp, "seconds": seconds}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--quick", action="store_true", help="tau 10, the first geometry only")
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    import weather_mi as wm
    wm.set_variant("llvm_ad_rgb")
    cases = [(10.0, GEOMETRIES[0])] if args.quick else [(t, g) for g in GEOMETRIES for t in TAUS]
    rows = []
    print(f"{'geometry':24s} {'tau':>5s} {'VZA':>5s} {'SZA':>5s} {'px':>4s} {'R 3-D MC':>16s} {'R DISORT':>9s} "
          f"{'diff':>7s} {'s':>6s}  ok")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        for tau, g in cases:
            row = run_case(tau, g, args.spp)
            rows.append(row)
            print(f"{row['geometry']:24s} {tau:5g} {row['vza_deg']:5.1f} {row['sza_deg']:5.1f} {row['pixels']:4d} "
                  f"{row['R_mc']:.4f} +- {row['se']:.4f} {row['R_disort']:9.4f} {100 * row['rel_diff']:+6.2f}% "
                  f"{row['seconds']:6.1f}  {'yes' if row['ok'] else 'NO'}", flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0 if all(r["ok"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
