"""Issue 38 part 2: how far apart the spectral mode's phase-table wavelengths may be.

    .venv/bin/python validation/spectral_tables_spacing.py [--quality default] [--steps 25,50,100]
        [--midpoints 425,525,625,725]

For node spacings of 25, 50 and 100 nm, the tables at mid - step/2 and mid + step/2 are interpolated
linearly in wavelength at the midpoint (what the kernel does between nodes) and compared with the table
computed at the midpoint itself: Mie theory (miepython, Hale & Querry's water index) for cloud droplets
(r_eff 10 um, v_eff 0.1) and 1 mm rain drops, the ice recipe (``ice.band_values``: the column's ray tally,
the diffraction at the wavelength) for ice columns. Figures per species and spacing (worst over midpoints):

* TV: the phase function's total-variation distance 1/2 integral |p_interp - p_true| dOmega over the angles
  outside the 3 deg forward cone (what the delta-M truncation leaves to the path tracer): the fraction of the
  scattered light sent in a wrong direction;
* dg: the asymmetry parameter's error;
* bow: rain's primary bow, its angle in the interpolated table against the true one (deg).

The single-scattering albedo is not on these nodes: its co-albedo spectra sit on their own 10 nm grid
(``optics.spectral.COALBEDO_NM``, the weak-absorption formula with the same water index).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

CONE_DEG = 3.0


def tv_outside_cone(p_a, p_b, theta, cone_deg: float = CONE_DEG) -> float:
    """1/2 integral over theta > cone of |p_a - p_b| dOmega (trapezoid on ``theta``, rad)."""
    keep = theta >= np.radians(cone_deg)
    th, d = theta[keep], np.abs(p_a - p_b)[keep]
    return float(0.5 * np.trapezoid(2 * np.pi * d * np.sin(th), th))


def asymmetry(p, theta) -> float:
    return float(np.trapezoid(2 * np.pi * p * np.cos(theta) * np.sin(theta), theta)
                 / np.trapezoid(2 * np.pi * p * np.sin(theta), theta))


def primary_bow_deg(p, theta) -> float:
    """Antisolar angle (deg) of the maximum of p in 39.5-44 deg (the primary bow)."""
    alpha = 180.0 - np.degrees(theta)
    w = (alpha >= 39.5) & (alpha <= 44.0)
    return float(alpha[w][np.argmax(p[w])])


def fine_theta() -> np.ndarray:
    return np.radians(np.unique(np.r_[np.geomspace(1e-3, 5.0, 400), np.arange(5.0, 180.0, 0.02), 180.0]))


def species_tables(kind: str, wavelength_nm: float, quality: str):
    from weather_mi.optics.phase import ice, mie
    lam = wavelength_nm * 1e-9
    if kind == "cloud":
        return mie.mie_cloud(quality=quality, wavelength_m=lam)
    if kind == "rain":
        return mie.mie_rain(radius=1e-3, quality=quality, wavelength_m=lam)
    return ice.ice_crystals("column", quality=quality, wavelength_m=lam)


def spacing_rows(kinds, steps, midpoints, quality: str):
    theta = fine_theta()
    rows = []
    for kind in kinds:
        for step in steps:
            worst = {"tv": 0.0, "dg": 0.0, "bow": 0.0}
            for mid in midpoints:
                lo, hi, true = (species_tables(kind, w, quality).eval(theta)[:, 1]
                                for w in (mid - step / 2, mid + step / 2, mid))
                interp = 0.5 * (lo + hi)
                worst["tv"] = max(worst["tv"], tv_outside_cone(interp, true, theta))
                worst["dg"] = max(worst["dg"], abs(asymmetry(interp, theta) - asymmetry(true, theta)))
                if kind == "rain":
                    worst["bow"] = max(worst["bow"], abs(primary_bow_deg(interp, theta) - primary_bow_deg(true, theta)))
            rows.append((kind, step, worst))
            print(f"| {kind} | {step:g} | {worst['tv']:.4f} | {worst['dg']:.5f} | "
                  + (f"{worst['bow']:.2f} |" if kind == "rain" else "- |"), flush=True)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quality", default="default")
    ap.add_argument("--steps", default="25,50,100")
    ap.add_argument("--midpoints", default="425,525,625,725")
    ap.add_argument("--kinds", default="cloud,ice,rain")
    args = ap.parse_args(argv)
    steps = [float(s) for s in args.steps.split(",")]
    mids = [float(m) for m in args.midpoints.split(",")]
    print(f"phase tables interpolated at midpoints {mids} nm ({args.quality} quality); TV outside {CONE_DEG:g} deg")
    print("| species | node spacing (nm) | TV (worst) | dg (worst) | rain bow shift (deg, worst) |")
    print("|---|---|---|---|---|")
    spacing_rows(args.kinds.split(","), steps, mids, args.quality)


if __name__ == "__main__":
    main()
