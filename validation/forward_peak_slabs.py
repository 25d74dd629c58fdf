"""How large a forward-peak cone the reference may count as unscattered light (delta-M,
``weather_mi.forward_peak``), judged against DISORT (``disortpp``) on slabs of the real hydrometeor
phase tables.

    .venv/bin/python validation/forward_peak_slabs.py [--tau 4] [--mu0 0.5] [--species cloud ice snow]
                                                      [--cones 0 0.1 1 3] [--spp 256] [--quick]

For each species' table (green channel; albedo 1, a slab 1000 x as wide as thick, black surface,
point sun at zenith cosine mu0): the flux reflectance R, the reflected radiance at nadir and the
diffuse transmitted radiance at zenith (pi L / (mu0 E)), from ``majorant_volpath`` with the peak
within each cone moved into the transmittance (0: the full table), against DISORT with the table's
own Legendre moments (2048; delta-M and the Nakajima-Tanaka intensity correction inside the
solver). DISORT's fluxes are exact for every table; its intensities only where the moments converge
(the cloud droplet table; for ice and snow they are printed as "-").

Each MC number is given with its standard error and its deviation from DISORT in standard errors.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import weather_mi as wm  # noqa: E402
from weather_mi.fluxes import disort_slab, slab_fluxes, slab_radiance  # noqa: E402
from weather_mi.phase.species import table_for  # noqa: E402


def _cell(mc, se, ref):
    if ref is None or not np.isfinite(ref):
        return f"{mc:8.4f} +- {se:6.4f}       "
    return f"{mc:8.4f} +- {se:6.4f} {(mc - ref) / se:+5.1f}s"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tau", type=float, default=4.0)
    ap.add_argument("--mu0", type=float, default=0.5)
    ap.add_argument("--species", nargs="+", default=["cloud", "ice", "snow"])
    ap.add_argument("--cones", nargs="+", type=float, default=[0.0, 0.1, 1.0, 3.0])
    ap.add_argument("--spp", type=int, default=256, help="radiance: samples per pixel (16 x 16 pixels)")
    ap.add_argument("--paths", type=int, default=1 << 18, help="flux: paths per measurement")
    ap.add_argument("--quick", action="store_true", help="a quarter of the samples")
    args = ap.parse_args(argv)
    spp, paths = (args.spp // 4, args.paths // 4) if args.quick else (args.spp, args.paths)
    wm.set_variant("llvm_ad_rgb")
    species = {s.name: s for s in wm.species.preset("physical")}
    print(f"slab tau {args.tau}, albedo 1, mu0 {args.mu0}; MC: majorant_volpath, {paths} paths (R), "
          f"{spp} spp x 256 pixels (radiances)")
    print(f"{'table':8s} {'cone':>5s} {'R':>27s} {'L nadir':>27s} {'L zenith':>27s}")
    for name in args.species:
        table = table_for(species[name], "per_species")
        ref = disort_slab(args.tau, 1.0, table, args.mu0, n_moments=2048)
        radiances_ok = name == "cloud"
        l_nadir = ref["L_nadir"] if radiances_ok else None
        l_zenith = ref["L_zenith"] if radiances_ok else None
        print(f"{name:8s} {'DISORT':>5s} {ref['R']:8.4f}{'':19s} "
              f"{(f'{l_nadir:8.4f}' if radiances_ok else '       -'):>27s} "
              f"{(f'{l_zenith:8.4f}' if radiances_ok else '       -'):>27s}", flush=True)
        for cone in args.cones:
            fl = slab_fluxes(args.tau, 1.0, table, args.mu0, spp=paths, integrator="majorant",
                             forward_peak_deg=cone, seed=11)
            ln = slab_radiance(args.tau, 1.0, table, args.mu0, spp=spp, view="nadir", integrator="majorant",
                               forward_peak_deg=cone, seed=12)
            lz = slab_radiance(args.tau, 1.0, table, args.mu0, spp=spp, view="zenith", integrator="majorant",
                               forward_peak_deg=cone, seed=13)
            print(f"{'':8s} {cone:5.2g} {_cell(fl['R'], fl['R_stderr'], ref['R'])} "
                  f"{_cell(*ln, l_nadir)} {_cell(*lz, l_zenith)}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
