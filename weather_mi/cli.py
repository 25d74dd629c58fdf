"""Command line: ``weather-mi info FILE | --demo supercell|cumulus``."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from .errors import WeatherDataError
from .hydrometeors import SPECIES_NAMES, spacing_of

DEMOS = ("supercell", "cumulus")


def load_input(path: str | None, demo: str | None, time=-1):
    """Hydrometeors from a file (wrfout NetCDF or LES text) or a built-in demo storm."""
    from . import synthetic
    from .io import open_les, open_wrf
    if path is None:
        return getattr(synthetic, demo or "supercell")()
    p = Path(path)
    if p.suffix.lower() in (".txt", ".dat", ".csv"):
        return open_les(p)
    return open_wrf(p, time=time)


def _parse_time(s: str):
    try:
        return int(s)
    except ValueError:
        return s


def info_text(hyd, species: str = "paper") -> str:
    """Dimensions, spacing, per-species max/mean mixing ratio, max extinction, densest column's tau."""
    from .optics import optical_volume
    vol = optical_volume(hyd, species=species)
    dz, dy, dx = spacing_of(hyd)
    nz, ny, nx = vol.shape
    (x0, y0, z0), (x1, y1, z1) = vol.bbox
    lines = [f"source      : {hyd.attrs.get('source', '?')}",
             f"time        : {hyd.attrs.get('time', '-')}    microphysics: {hyd.attrs.get('microphysics', '-')}",
             f"grid (z,y,x): {nz} x {ny} x {nx}    spacing dz, dy, dx = {dz:.1f}, {dy:.1f}, {dx:.1f} m",
             f"extent      : x {x0 / 1e3:.2f}..{x1 / 1e3:.2f} km, y {y0 / 1e3:.2f}..{y1 / 1e3:.2f} km, "
             f"z {z0 / 1e3:.2f}..{z1 / 1e3:.2f} km",
             f"species preset: {species}",
             f"{'species':<9}{'max q (g/kg)':>14}{'mean q (g/kg)':>15}{'max beta (1/km)':>17}"]
    for i, name in enumerate(SPECIES_NAMES):
        q = hyd[f"q_{name}"].values
        lines.append(f"{name:<9}{1e3 * float(q.max()):>14.4g}{1e3 * float(q.mean()):>15.4g}"
                     f"{1e3 * float(vol.beta_ext[i].max()):>17.4g}")
    tau = vol.optical_depth_z()
    j, i = np.unravel_index(int(np.argmax(tau)), tau.shape)
    lines.append(f"max extinction: {1e3 * float(vol.beta_total.max()):.4g} 1/km")
    lines.append(f"vertical optical depth through the densest column (x={float(hyd.x[i]) / 1e3:.1f} km, "
                 f"y={float(hyd.y[j]) / 1e3:.1f} km): {float(tau[j, i]):.4g}")
    if hyd.attrs.get("n_negative_clipped"):
        lines.append(f"negative mixing ratios clipped: {hyd.attrs['n_negative_clipped']}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="weather-mi", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    info = sub.add_parser("info", help="summarise a data file or a demo storm")
    src = info.add_mutually_exclusive_group(required=True)
    src.add_argument("file", nargs="?", help="wrfout NetCDF or LES text file")
    src.add_argument("--demo", choices=DEMOS, help="a built-in demo storm")
    info.add_argument("--time", default="-1", help="time index or timestamp (WRF)")
    info.add_argument("--species", default="paper", choices=("paper", "physical"))
    args = parser.parse_args(argv)
    try:
        if args.command == "info":
            hyd = load_input(args.file, args.demo, _parse_time(args.time))
            print(info_text(hyd, args.species))
    except WeatherDataError as exc:
        print(f"weather-mi: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
