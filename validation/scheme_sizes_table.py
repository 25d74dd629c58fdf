"""The effective-radius test table of issue 39 part 3: for each scheme and category added (NSSL two-moment,
Milbrandt-Yau, Kessler, P3, Thompson graupel by WRF version), points spanning each threshold and clipping
range, the Fortran transcribed in ``tests/test_scheme_sizes.py`` (the independent formula), weather-mi's
value and the relative difference. Prints a Markdown table.

    .venv/bin/python validation/scheme_sizes_table.py
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from test_scheme_sizes import (N, NSSL_RE_BOUNDS, Q, my_fortran, nssl_fortran,  # noqa: E402
                               thompson_n0_fortran)
from weather_mi.io import microphysics as mp, milbrandt_sizes, nssl_sizes, thompson_graupel  # noqa: E402


def _row(scheme, cat, point, regime, expected, got):
    diff = (got - expected) / expected if expected else float("nan")
    return f"| {scheme} | {cat} | {point} | {regime} | {expected * 1e6:.4g} | {got * 1e6:.4g} | {diff:+.1e} |"


def nssl_rows():
    rho0 = 0.9
    for cat in ("cloud", "ice", "snow", "rain", "graupel", "hail"):
        lo, hi = NSSL_RE_BOUNDS[cat]
        seen = {}
        for qx in Q:
            for cx in N:
                e = nssl_fortran(cat, qx, cx, rho0)
                g = float(nssl_sizes.radius(cat, np.array([qx * rho0]), np.array([cx]), np.array([rho0]))[0])
                thresh = 1e-13 if cat in ("cloud", "ice", "snow") else 1e-8
                regime = ("below q/N threshold" if qx <= thresh or (cat not in ("graupel", "hail") and cx <= 1e-8)
                          else "lower clip" if e <= lo * 1.000001 else "upper clip" if e >= hi * 0.999999
                          else "inside")
                seen.setdefault(regime, (qx, cx, e, g))
        for regime, (qx, cx, e, g) in sorted(seen.items()):
            yield _row("NSSL 2-moment", cat, f"q {qx:.0e} kg/kg, N {cx:.0e} m^-3", regime, e, g)


def my_rows():
    for cat in ("cloud", "ice", "rain", "snow", "graupel", "hail"):
        for qx, nx in ((1e-5, 1e7), (1e-3, 1e3), (1e-12, 1e9)):
            e = my_fortran(cat, qx, nx, 0.8)
            g = float(milbrandt_sizes.radius(cat, np.array([qx * 0.8]), np.array([nx]))[0])
            regime = "iLAMmin floor" if abs(e - 1.5e-6) < 1e-12 or abs(e - 1.5e-10) < 1e-16 else "inside"
            yield _row("Milbrandt-Yau", cat, f"q {qx:.0e} kg/kg, N {nx:.0e} m^-3, rho 0.8", regime, e, g)


def other_rows():
    for rq in (1e-6, 1e-3):
        e = 1.5 / (np.pi * 1000.0 * 8e6 / rq) ** 0.25
        yield _row("Kessler", "rain", f"rho q {rq:.0e} kg/m^3", "Marshall-Palmer", e,
                   float(mp.kessler_rain(np.array([rq]))[0]))
    for qc, nc, regime in ((1e-4, 3e8, "inside"), (1e-9, 1e6, "lambda max"), (5e-3, 1e6, "lambda min"),
                           (1e-3, None, "nccnst")):
        ncc = 200e6 if nc is None else nc
        mu = min(max(1.0 / (0.0005714 * ncc * 1e-6 + 0.2714) ** 2 - 1.0, 2.0), 15.0)
        lam = (np.pi / 6 * 997.0 * ncc * (mu + 3) * (mu + 2) * (mu + 1) / qc) ** (1 / 3)
        lam = min(max(lam, (mu + 1) * 2.5e4), (mu + 1) * 1e6)
        g = float(mp.p3_cloud(np.array([qc]), None if nc is None else np.array([nc]))[0])
        yield _row("P3", "cloud", f"rho q {qc:.0e}, N {ncc:.0e}", regime, 0.5 * (mu + 3) / lam, g)
    for qr, nr, regime in ((1e-3, 1e3, "inside"), (1e-2, 1.0, "lambda min (2 mm)"), (1e-9, 1e7, "lambda max")):
        lam = min(max((np.pi / 6 * 997.0 * nr * 6.0 / qr) ** (1 / 3), 500.0), 1e5)
        yield _row("P3", "rain", f"rho q {qr:.0e}, N {nr:.0e}", regime, 1.5 / lam,
                   float(mp.p3_rain(np.array([qr]), np.array([nr]))[0]))


def thompson_rows():
    temp = np.array([290, 280, 272, 270, 265, 255, 240, 225], float)
    rho = np.linspace(1.2, 0.4, 8)
    rg = np.array([1e-9, 1e-6, 1e-4, 2e-3, 5e-3, 2e-2, 1e-3, 1e-5])
    rr = np.array([2e-3, 1e-3, 8e-4, 5e-4, 3e-4, 1e-4, 0, 0])
    nr = np.array([1e3, 5e2, 3e2, 2e2, 1e2, 1e3, 0, 0])
    rc = np.array([1e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 0, 0])
    for v in thompson_graupel.VERSIONS:
        n0 = thompson_n0_fortran(v, rg, temp, rr, nr, rc, rho)
        got = thompson_graupel.radius(v, rg[:, None], temp[:, None], rho[:, None], rr[:, None], nr[:, None],
                                      rc[:, None])[:, 0]
        rho_g = 400.0 if v in ("3.3", "4.5") else 500.0
        for k in (0, 3, 5):
            lam = (n0[k] * np.pi * rho_g / rg[k]) ** 0.25
            if v == "4.5":
                lam = min(max(lam, 3.672 / 25.4e-3), 3.672 / 50e-6)
            yield _row(f"Thompson V{v}", "graupel", f"level {k}, rho q {rg[k]:.0e}, T {temp[k]:.0f} K",
                       f"N0 {n0[k]:.3g}", 1.5 / lam, float(got[k]))


def main():
    print("| scheme | category | point | regime | Fortran transcribed (um) | weather-mi (um) | rel. diff |")
    print("|---|---|---|---|---|---|---|")
    for rows in (nssl_rows(), my_rows(), other_rows(), thompson_rows()):
        for r in rows:
            print(r)


if __name__ == "__main__":
    main()
