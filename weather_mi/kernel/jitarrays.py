"""Host arrays and scalars handed to Dr.Jit kernels."""
from __future__ import annotations

import numpy as np

CHUNK = 1 << 20  # values converted at a time


def aligned_empty(n: int) -> np.ndarray:
    """An uninitialised float32 array of ``n`` values whose data start on a 64-byte boundary (a view into a
    buffer 16 values longer)."""
    buf = np.empty(int(n) + 16, dtype=np.float32)
    off = (-buf.ctypes.data % 64) // 4
    return buf[off:off + int(n)]


def aligned_float(mi, a) -> "mi.Float":
    """A Dr.Jit Float from numpy data held in 64-byte aligned memory. (The LLVM backend may use host
    memory in place, and a kernel's IR records the alignment it sees: unaligned arrays one frame and
    aligned ones the next would compile a new kernel.)"""
    big = np.finfo(np.float32).max
    a = np.asarray(a).ravel()
    out = aligned_empty(a.size)
    if a.dtype == np.float32:  # clipped where it lands: no float64 copy of a large grid
        np.clip(a, -big, big, out=out)
    else:  # beyond float32's range -> its largest value, in chunks
        for i in range(0, a.size, CHUNK):
            out[i:i + CHUNK] = np.clip(np.asarray(a[i:i + CHUNK], dtype=np.float64), -big, big)
    return mi.Float(out)


def aligned_uint(mi, a) -> "mi.UInt32":
    """A Dr.Jit UInt32 from integer data (bit patterns such as packed 16-bit codes, which must not pass
    through float copies: NaN and denormal patterns) in 64-byte aligned memory, as :func:`aligned_float`."""
    a = np.asarray(a, np.uint32).ravel()
    out = aligned_empty(a.size).view(np.uint32)
    out[:] = a
    return mi.UInt32(out)


def kernel_scalar(mi, value):
    """A per-frame scalar for a kernel: Dr.Jit arrays pass through (they may carry gradients), Python
    numbers become opaque values (a new value recompiles nothing; a literal would)."""
    import drjit as dr
    if dr.is_array_v(value):
        return value
    return dr.opaque(mi.Float, float(value))
