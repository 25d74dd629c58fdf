"""Per-pixel slab offsets of the eye pass: no terraces on lit faces.

The eye pass composites slabs [k - 1/2, k + 1/2] between slice planes; on the lit faces of a coarsely
gridded cloud the slab boundaries show as steps that follow the planes ("terraces"). Shifting every
pixel's slabs by its own offset j (slice units) moves the steps to a different depth in each pixel, so
their coherent pattern turns into fine, unstructured grain (benchmarks/banding.py measures the
difference). The light pass does the same per texel of the light buffer (``texel_offsets``: texel t's slabs and
stored planes at k + j_t), so that the kinks of the light's interpolation between planes do not line up
either. The offsets are interleaved gradient noise (Jimenez 2014), a fixed function of the pixel (texel),
so the image does not crawl between frames; ``SliceParams.jitter_frame`` rotates them by the golden ratio
(Cranley-Patterson rotation), so that frames averaged with successive indices converge to the smooth
slab average.

Measured (benchmarks/banding.py, demo supercell, 640 x 480, 128 slices): the banding energy falls 6.1x
("multiple") and 4.6x (per-species translucent) at equal frame time (0.8-1.04x), the slice convergence
is no worse, but the grain raises the per-pixel RMS error against 1024 slices by 28% in the "multiple"
model. The default stays 0 (aligned: images, the calibration and the study's per-pixel metrics as
before); the viewer, where the terraces are seen, can ask for ``SliceParams(slab_jitter=1.0)``.
"""
from __future__ import annotations

import numpy as np

GOLDEN = 0.6180339887498949  # rotation of the offsets per frame index (a low-discrepancy sequence)


def offset_pattern(width: int, height: int) -> np.ndarray:
    """Interleaved gradient noise in [0, 1) per pixel, (height x width) flattened row-major from the top
    left: frac(52.9829189 frac(0.06711056 x + 0.00583715 y)) at pixel (x, y) (Jimenez 2014, "Next
    generation post processing in Call of Duty: Advanced Warfare"): any 3 x 3 block of pixels holds well
    spread values, so the grain it leaves has little low-frequency energy."""
    y, x = np.mgrid[0:int(height), 0:int(width)].astype(np.float64)
    return np.mod(52.9829189 * np.mod(0.06711056 * x + 0.00583715 * y, 1.0), 1.0).ravel()


def jitter_rotation(frame_index: int) -> float:
    """The rotation of the offsets for ``SliceParams.jitter_frame`` (a plain number in [0, 1))."""
    return (GOLDEN * float(frame_index)) % 1.0


def slab_offsets(dr, pattern, amplitude, rotation):
    """Each pixel's slab offset j (slice units) inside a kernel: amplitude x (frac(pattern + rotation) -
    1/2), in [-amplitude / 2, amplitude / 2); ``amplitude`` (0: none, 1: spread over a whole slab) and
    ``rotation`` are opaque kernel scalars (changing them recompiles nothing)."""
    u = pattern + rotation
    u = dr.select(u >= 1.0, u - 1.0, u)
    return amplitude * (u - 0.5)


def texel_offsets(dr, mi, x, y, amplitude, rotation):
    """The light buffer's per-texel plane offsets (slice units) inside a kernel, for integer texel
    coordinates (x, y) (mi.UInt32): the same interleaved gradient noise, rotated and scaled as
    ``slab_offsets``. The light pass stores texel t's light at planes k + j_t, so that the kinks of the
    light's interpolation between planes do not line up with the slab planes either."""
    fx, fy = mi.Float(x), mi.Float(y)
    t = 0.06711056 * fx + 0.00583715 * fy
    t = 52.9829189 * (t - dr.floor(t))
    return slab_offsets(dr, t - dr.floor(t), amplitude, rotation)
