"""A text summary of Hydrometeors (``weather-mi info``): the grid, the per-species mixing ratios and
extinction, the densest column's optical depth."""
from __future__ import annotations

import numpy as np

from .hydrometeors import SPECIES_NAMES, spacing_of


def info_text(hyd, species: str = "paper") -> str:
    """Dimensions, spacing (m), per-species max/mean mixing ratio (g/kg), max extinction (1/km) and the
    densest column's vertical optical depth of ``hyd`` with the species table ``species``."""
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
