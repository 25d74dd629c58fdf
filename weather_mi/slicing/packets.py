"""RGB tables as packets of 4 floats for the slicer's kernels: a row's colour is one gather of 4 contiguous floats
(LLVM: one vector load per lane) instead of three scalar gathers. The air's tables by height and the sun's colour
by height and zenith (``eye_air``), and the sun's colour by height that every scattering sample of the eye pass
reads (``sun_air``, as one 64-bit word a row: ``rgb_words``)."""
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


WORD_BITS = 21  # bits a channel of ``rgb_words``: the float32's exponent and the top 13 bits of its mantissa
WORD_DROP = 31 - WORD_BITS  # the mantissa's bits dropped (rounded to nearest): relative error <= 2^-14 (6.1e-5)


def rgb_words(mi, dr, rgb):
    """Non-negative colours (mi.Color3f) as one mi.UInt64 each: per channel the float32's bits (no sign) rounded
    to their top ``WORD_BITS``, R in the low bits. A table of them is read with one scalar 64-bit gather a lane
    (``word_rgb``) where a packet of 4 floats costs ~4x as much (the eye pass's sun colour at every lit sample:
    0.7 ms of a 300 x 300 drag frame's CPU, benchmarks/README.md)."""
    word = mi.UInt64(0)
    for c in range(3):
        bits = dr.reinterpret_array(mi.UInt32, dr.maximum(rgb[c], 0.0))
        word = word | (mi.UInt64((bits + (1 << (WORD_DROP - 1))) >> WORD_DROP) << (WORD_BITS * c))
    return word


def word_rgb(mi, dr, table, i):
    """Row i of a table of ``rgb_words`` (mi.UInt64) as a mi.Color3f (one gather)."""
    v = dr.gather(mi.UInt64, table, i)
    mask = (1 << WORD_BITS) - 1
    return mi.Color3f(*(dr.reinterpret_array(mi.Float, mi.UInt32((v >> (WORD_BITS * c)) & mask) << WORD_DROP)
                        for c in range(3)))


__all__ = ["WORD_BITS", "lerp_rows", "packed", "packet", "rgb_words", "word_rgb"]
