"""Each species as a few size classes, Eq. 8 components of their own: the phase function (and its forward
peak, rainbow, halo widths) follows the voxel's effective radius instead of one radius per species.

A species with per-voxel radii (``r_eff_<species>``, m) is split at fixed log-spaced radii over ``RANGE_M``
(the clipping ranges of the WRF schemes, ``weather_mi.io.microphysics``): a voxel's extinction and Eq. 8
weight go whole to the class holding its radius, so beta_total, the albedo and the sum of the weights are
those of the species unsplit. Each class with any extinction becomes a component named ``<species>#<k>`` (k
counting from 1 at the small end; the species' name alone where it keeps one class) whose phase table is the
species' table at the class's geometric-centre radius (3 significant digits): the edges do not depend on the
data, so the tables are built once and cached on disk (``optics.phase.cache``) for every storm and time.
The component's ``Species`` is the species' with that radius (``species_tables.table_for(..., sized=True)``:
Mie cloud at r_eff, Mie rain at the radius, the ice habits' diffraction by a population of that radius).
"""
from __future__ import annotations

import numpy as np
from dataclasses import replace

RANGE_M = {"cloud": (2.5e-6, 50e-6), "ice": (2.5e-6, 125e-6), "rain": (15e-6, 2.5e-3), "snow": (5e-6, 2e-3),
           "graupel": (20e-6, 3e-3)}
SEPARATOR = "#"


def base_name(component: str) -> str:
    """The species of a component name ("rain#2" -> "rain")."""
    return component.split(SEPARATOR, 1)[0]


def class_radii_m(name: str, n_classes: int) -> tuple[np.ndarray, np.ndarray]:
    """(the n + 1 log-spaced class edges, the n geometric-centre radii rounded to 3 significant digits), m."""
    lo, hi = RANGE_M[name]
    edges = np.geomspace(lo, hi, n_classes + 1)
    centres = np.sqrt(edges[:-1] * edges[1:])
    return edges, np.array([float(f"{c:.3g}") for c in centres])


def split(hyd, sp, beta_ext: np.ndarray, weights: np.ndarray, n_classes: int):
    """(component names, beta_ext (C, z, y, x), weights (C, z, y, x), one Species per component) of the
    species' ``beta_ext`` and ``weights`` ((S, z, y, x), 1/m and Eq. 8) split by the radii of ``hyd``; beyond
    the outputs, one byte per cell per split species (its class grid)."""
    plan = []  # (species index, class grid or None, class k or None, name, Species)
    for i, s in enumerate(sp):
        var = f"r_eff_{s.name}"
        if n_classes < 2 or var not in hyd or s.name not in RANGE_M:
            plan.append((i, None, None, s.name, s))
            continue
        edges, centres = class_radii_m(s.name, n_classes)
        r = np.asarray(hyd[var].values, np.float32)
        r = np.where(r > 0, r, np.float32(s.radius_m))  # the species table's radius where the model has none
        cls = np.searchsorted(edges[1:-1], r, side="right").astype(np.uint8)
        del r
        occupied = beta_ext[i] > 0
        used = [k for k in range(n_classes) if np.any(occupied & (cls == k))]
        del occupied
        if len(used) <= 1:
            k = used[0] if used else min(int(np.searchsorted(edges[1:-1], s.radius_m)), n_classes - 1)
            plan.append((i, None, None, s.name, replace(s, radius_m=float(centres[k]))))
            continue
        plan += [(i, cls, k, f"{s.name}{SEPARATOR}{k + 1}", replace(s, radius_m=float(centres[k]))) for k in used]
    out_beta = np.zeros((len(plan),) + beta_ext.shape[1:], np.float32)
    out_w = np.zeros_like(out_beta)
    for c, (i, cls, k, _, _) in enumerate(plan):
        inside = True if cls is None else cls == k
        np.copyto(out_beta[c], beta_ext[i], where=inside)
        np.copyto(out_w[c], weights[i], where=inside)
    return tuple(p[3] for p in plan), out_beta, out_w, tuple(p[4] for p in plan)
