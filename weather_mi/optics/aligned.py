"""Grids in 64-byte aligned memory: what Dr.Jit's LLVM backend uses in place (``mi.TensorXf(numpy)`` shares
it; a 3-channel ``gridvolume`` copies a grid whose data are not 64-byte aligned, 12 bytes per cell, measured),
so that optics built for the kernels are not copied there (``forward_peak.delta_scaled``; ``kernel.jitarrays``)."""
from __future__ import annotations

import numpy as np


def aligned_empty(n: int) -> np.ndarray:
    """An uninitialised float32 array of ``n`` values whose data start on a 64-byte boundary (a view into a
    buffer 16 values longer)."""
    buf = np.empty(int(n) + 16, dtype=np.float32)
    off = (-buf.ctypes.data % 64) // 4
    return buf[off:off + int(n)]


def aligned_grid(shape) -> np.ndarray:
    """An uninitialised float32 array of ``shape`` in 64-byte aligned memory."""
    shape = tuple(int(s) for s in shape)
    return aligned_empty(int(np.prod(shape, dtype=np.int64))).reshape(shape)
