"""Land or water at any latitude/longitude from an offline global mask: ``global-land-mask`` (MIT; the GLOBE
1 km digital elevation project's land mask, 30 arc seconds, 21600 x 43200, lakes counted as land), for model
grids whose file has no LANDMASK, XLAND or LU_INDEX.

The package ships its mask as a compressed ``.npz`` that expands to 0.93 GB of booleans, which its own
``globe`` module loads whole at import. Here it is decompressed once, streamed a block of rows at a time, into
a bit-packed copy (117 MB, 8 columns a byte) in the user's cache directory (``platformdirs``; or
``WEATHER_MI_CACHE``), which later calls read through a memory map: only the pages under the grid are read.
The cell convention is the package's (``globe.lat_to_index``, ``lon_to_index``): row
floor((90 - lat) x 120), column floor((lon + 180) x 120), clamped to the grid.
"""
from __future__ import annotations

import os
import zipfile
from pathlib import Path

import numpy as np

CELLS_PER_DEGREE = 120       # 30 arc seconds
SHAPE = (180 * CELLS_PER_DEGREE, 360 * CELLS_PER_DEGREE)
SOURCE = "global-land-mask 1.0.0 (GLOBE 1 km land mask, MIT)"
_ROWS_PER_BLOCK = 480        # 480 x 43200 booleans: 21 MB decompressed at a time


def cache_dir() -> Path:
    """Where the packed mask is kept: ``$WEATHER_MI_CACHE`` or the user's cache directory (platformdirs)."""
    env = os.environ.get("WEATHER_MI_CACHE")
    if env:
        return Path(env)
    import platformdirs
    return Path(platformdirs.user_cache_dir("weather-mi"))


def _package_npz() -> Path:
    import importlib.util
    spec = importlib.util.find_spec("global_land_mask")  # not imported: its globe module loads 0.93 GB
    if spec is None or not spec.submodule_search_locations:
        raise ModuleNotFoundError("the global land mask needs the package global-land-mask (pip install "
                                  "global-land-mask): the file has no LANDMASK, XLAND or LU_INDEX")
    return Path(list(spec.submodule_search_locations)[0]) / "globe_combined_mask_compressed.npz"


def packed_path() -> Path:
    """The packed land mask (``uint8`` (21600, 5400), bit 7 - k of byte c: column 8 c + k, 1 = land), made on
    the first call from the package's ``.npz``, streamed (peak memory a few tens of MB)."""
    out = cache_dir() / "global_land_mask_packed_v1.npy"
    if out.is_file():
        return out
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f"{out.stem}.{os.getpid()}.tmp.npy")
    with zipfile.ZipFile(_package_npz()) as z, z.open("mask.npy") as f:
        version = np.lib.format.read_magic(f)
        read_header = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        shape, fortran, dtype = read_header(f)
        if shape != SHAPE or fortran or dtype != np.bool_:
            raise ValueError(f"global-land-mask: expected a C-ordered boolean mask {SHAPE}, found {shape} {dtype}")
        with open(tmp, "wb") as out_f:  # written a block at a time: nothing of it held in memory
            np.lib.format.write_array_header_1_0(out_f, {"descr": "|u1", "fortran_order": False,
                                                          "shape": (SHAPE[0], SHAPE[1] // 8)})
            for r0 in range(0, SHAPE[0], _ROWS_PER_BLOCK):
                n = min(_ROWS_PER_BLOCK, SHAPE[0] - r0)
                ocean = np.frombuffer(f.read(n * SHAPE[1]), dtype=np.uint8).reshape(n, SHAPE[1])
                out_f.write(np.packbits(ocean == 0, axis=1).tobytes())  # the package stores the ocean (True)
    os.replace(tmp, out)  # whole or not at all: a concurrent first call writes its own and renames
    return out


def cell_index(lat_deg, lon_deg) -> tuple[np.ndarray, np.ndarray]:
    """(row, column) of the mask's cells holding points (degrees), the package's convention (module doc)."""
    lat = np.asarray(lat_deg, float)
    lon = (np.asarray(lon_deg, float) + 180.0) % 360.0 - 180.0
    row = np.clip(np.floor((90.0 - lat) * CELLS_PER_DEGREE), 0, SHAPE[0] - 1).astype(np.int64)
    col = np.clip(np.floor((lon + 180.0) * CELLS_PER_DEGREE), 0, SHAPE[1] - 1).astype(np.int64)
    return row, col


def is_land(lat_deg, lon_deg) -> np.ndarray:
    """Whether each point (degrees, any shape) is land in the global mask (lakes are land there)."""
    lat = np.asarray(lat_deg, float)
    if not np.all(np.isfinite(lat)) or np.any(np.abs(lat) > 90.0):
        raise ValueError("global land mask: latitudes must be finite and within [-90, 90] degrees")
    row, col = cell_index(lat, lon_deg)
    packed = np.load(packed_path(), mmap_mode="r")
    r0, r1 = int(row.min()), int(row.max()) + 1  # read only the window's rows
    window = np.asarray(packed[r0:r1])
    byte = window[row - r0, col >> 3]
    return ((byte >> (7 - (col & 7))) & 1).astype(bool)


__all__ = ["is_land", "cell_index", "packed_path", "cache_dir", "SOURCE"]
