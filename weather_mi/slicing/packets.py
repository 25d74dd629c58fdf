"""RGB tables as packets of 4 floats for the slicer's kernels: a row's colour is one gather of 4 contiguous floats
(LLVM: one vector load per lane) instead of three scalar gathers. The air's tables by height and the sun's colour
by height and zenith (``eye_air``), and the sun's colour by height that every scattering sample of the eye pass
reads (``sun_air``)."""
from __future__ import annotations

import numpy as np


def packed(table) -> np.ndarray:
    """``table`` (..., 3 k) as float32 with each group of 3 padded to 4 (a packet the kernels gather at once),
    flat."""
    t = np.asarray(table, np.float32)
    t = t.reshape(t.shape[:-1] + (t.shape[-1] // 3, 3))
    return np.ascontiguousarray(np.concatenate([t, np.zeros(t.shape[:-1] + (1,), np.float32)], axis=-1)).ravel()


def packet(mi, dr, table, i):
    """Packet i of a ``packed`` table (a mi.Color3f)."""
    v = dr.gather(mi.Vector4f, table, i)
    return mi.Color3f(v.x, v.y, v.z)


def lerp_rows(mi, dr, table, f, n: int, width: int = 1, offset: int = 0):
    """Linear interpolation between the n rows of the ``packed`` ``table`` (rows of ``width`` packets) at
    fractional rows f (clamped to the table), packet ``offset`` of each row (a mi.Color3f)."""
    f = dr.clip(f, 0.0, float(n - 1))
    i = dr.minimum(mi.UInt32(f), n - 2)
    t = f - mi.Float(i)
    a = packet(mi, dr, table, i * width + offset)
    b = packet(mi, dr, table, (i + 1) * width + offset)
    return a * (1.0 - t) + b * t


__all__ = ["lerp_rows", "packed", "packet"]
