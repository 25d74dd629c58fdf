"""The translucency blur of the light pass: forward-scattered light spreads sideways like a diffusion,
a Gaussian whose variance grows by ``variance_per_metre`` (m^2 per metre of light path); the light pass
applies it by operator splitting, every few slabs, with separable taps (BLUR_FOLDS) of exactly the variance
accumulated since the last step (light.py)."""
from __future__ import annotations

import math

from ..kernel.jitarrays import kernel_scalar

# the blur kernel: the 5-tap kernel of ``_five_tap`` convolved with itself BLUR_FOLDS - 1 times
# (4 BLUR_FOLDS + 1 taps per axis), and the largest variance per step, in texels^2, that it reproduces
# with weights >= 0
BLUR_FOLDS = 3
MAX_TEXEL_VARIANCE = BLUR_FOLDS * 4.0 / 3.0


def blur_weights(dr, var):
    """Weights (c0, c1, .., c_2F) of the symmetric kernel [c_2F, .., c1, c0, c1, .., c_2F] (F =
    BLUR_FOLDS) whose variance is ``var`` texels^2 (exact up to MAX_TEXEL_VARIANCE, clamped beyond): the
    5-tap kernel of ``_five_tap`` at var / F convolved F times, so that above 1/3 per fold its fourth
    moment is a Gaussian's (3 var^2: the folds' fourth cumulants are zero)."""
    w0, w1, w2 = _five_tap(dr, dr.clip(var, 0.0, MAX_TEXEL_VARIANCE) * (1.0 / BLUR_FOLDS))
    one = [w2, w1, w0, w1, w2]
    kernel = one
    for _ in range(BLUR_FOLDS - 1):  # polynomial product: taps at offsets -2F .. 2F
        out = [0.0] * (len(kernel) + 4)
        for i, a in enumerate(kernel):
            for j, b in enumerate(one):
                out[i + j] = out[i + j] + a * b
        kernel = out
    return tuple(kernel[len(kernel) // 2:])


def _five_tap(dr, v):
    """(w0, w1, w2) of the symmetric 5-tap kernel [w2, w1, w0, w1, w2] of variance v <= 4/3 texels^2
    whose fourth moment is a Gaussian's (3 v^2) above v = 1/3; below it the 3-tap [v/2, 1 - v, v/2]."""
    w2 = dr.maximum((3.0 * v * v - v) / 24.0, 0.0)
    w1 = 0.5 * (v - 8.0 * w2)
    return 1.0 - 2.0 * w1 - 2.0 * w2, w1, w2


def _blur(mi, dr, buf, R, wx, wy):
    """Separable convolution of an R x R buffer with per-axis weights (c0, c1, ..) of the taps at offsets
    0, +-1, .. (see ``blur_weights``); edges clamped. Two passes: along x (evaluated), then along y (left to
    the kernel that reads it)."""
    lane = dr.arange(mi.UInt32, R * R)
    yi = mi.Int32(lane // R)
    xi = mi.Int32(lane) - yi * R
    taps = lambda w: [(o, w[abs(o)]) for o in range(1 - len(w), len(w))]  # noqa: E731
    row = mi.UInt32(yi) * R
    along_x = mi.Float(0.0)
    for ox, wxv in taps(wx):
        along_x += wxv * dr.gather(mi.Float, buf, row + mi.UInt32(dr.clip(xi + ox, 0, R - 1)))
    dr.eval(along_x)
    out = mi.Float(0.0)
    for oy, wyv in taps(wy):
        out += wyv * dr.gather(mi.Float, along_x, mi.UInt32(dr.clip(yi + oy, 0, R - 1)) * R + mi.UInt32(xi))
    return out


def variance_per_metre(cone_angle_deg, blur_length_m, mi=None):
    """tan^2(cone) x blur length: the sideways variance (m^2) that forward-scattered light gains per
    metre of light path (a Dr.Jit Float with ``mi``, else a number)."""
    if mi is None:
        return math.tan(math.radians(float(cone_angle_deg))) ** 2 * float(blur_length_m)
    import drjit as dr
    t = dr.tan(kernel_scalar(mi, cone_angle_deg) * (math.pi / 180.0))
    return t * t * kernel_scalar(mi, blur_length_m)
