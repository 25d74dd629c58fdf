"""The per-view arrays of the slicer computed by Dr.Jit kernels instead of numpy: camera rays, their
entry and exit of the slicing box and the flat ground, the light buffer's rays, phase functions along the
rays. A drag of the camera or the sun redoes them every frame (the half-angle moves every slice plane and
light ray), and in numpy they cost more than the frame's kernels.

The arithmetic is numpy's, in float64 (``mi.Float64``), operation for operation (geometry.py's
``film_rays`` and ``ray_box``, ``scene.spec.ground_hits``, ``LightVolume``'s light rays, ``np.interp``), and
the results are rounded to float32 as ``jitarrays.aligned_float`` rounds them (clipped to float32's
range). A kernel's scalars enter as one array (``Scalars``): a new view compiles nothing, and the kernel
is the same whatever the values (separate opaque values that happen to be equal may share one variable,
which changes the kernel). Where numpy takes a dot product
through BLAS (``a @ b``, fused multiply-adds in an order of its own) the float64 result may differ in the
last bit; rounded to float32, such a difference changes a value with a probability of about 2^-29.
"""
from __future__ import annotations

import math

import numpy as np

from .geometry import camera_basis

FLOAT32_MAX = float(np.finfo(np.float32).max)


class Scalars:
    """Named float64 scalars of a kernel uploaded as one array; ``self[name]`` reads one inside the kernel."""

    def __init__(self, mi, **values):
        import drjit as dr
        names, flat = [], []
        for k, v in values.items():
            v = np.asarray(v, dtype=np.float64).ravel()
            names += [k] if v.size == 1 and np.ndim(values[k]) == 0 else [f"{k}{i}" for i in range(v.size)]
            flat += [float(x) for x in v]
        self.mi, self.index = mi, {k: i for i, k in enumerate(names)}
        self.array = mi.Float64(flat)
        dr.eval(self.array)

    def __getitem__(self, name):
        import drjit as dr
        return dr.gather(self.mi.Float64, self.array, self.index[name])


def f32(mi, x):
    """Float64 -> Float32 as ``aligned_float`` does: clipped to float32's finite range (NaN kept)."""
    import drjit as dr
    x = dr.select(x > FLOAT32_MAX, FLOAT32_MAX, x)
    return mi.Float(dr.select(x < -FLOAT32_MAX, -FLOAT32_MAX, x))


def camera_rays(mi, spec):
    """(origin, direction) of every pixel, each a list of 3 Float64 (N = width x height, row-major from the
    top left): ``geometry.film_rays`` at the pixel centres."""
    import drjit as dr
    cam = spec.camera
    w, h = int(spec.width), int(spec.height)
    fwd, left, up = camera_basis(cam)
    ortho = cam.kind == "orthographic"
    tan_x = 0.0 if ortho else math.tan(math.radians(cam.fov) / 2)
    half = (cam.ortho_width / 2, cam.ortho_height / 2) if ortho else (tan_x, tan_x * h / w)
    sc = Scalars(mi, w=w, h=h, half_x=half[0], half_y=half[1], fwd=fwd, left=left, up=up, origin=cam.origin)
    idx = dr.arange(mi.UInt32, w * h)
    row = idx // w  # (a literal divisor: a multiplication; the image size is part of the kernel anyway)
    col = idx - row * w
    gx = 1.0 - 2.0 * (mi.Float64(col) + 0.5) / sc["w"]
    gy = 1.0 - 2.0 * (mi.Float64(row) + 0.5) / sc["h"]
    a, b = gx * sc["half_x"], gy * sc["half_y"]
    zero = dr.zeros(mi.Float64, w * h)
    if ortho:
        origin = [(sc[f"origin{c}"] + a * sc[f"left{c}"]) + b * sc[f"up{c}"] for c in range(3)]
        return origin, [zero + sc[f"fwd{c}"] for c in range(3)]
    d = [(sc[f"fwd{c}"] + a * sc[f"left{c}"]) + b * sc[f"up{c}"] for c in range(3)]
    norm = dr.sqrt((d[0] * d[0] + d[1] * d[1]) + d[2] * d[2])
    return [zero + sc[f"origin{c}"] for c in range(3)], [v / norm for v in d]


def _nan_to_num(dr, x, nan):
    """numpy's ``nan_to_num(x, nan=nan)``: infinities become the largest finite float64 of their sign."""
    big = float(np.finfo(np.float64).max)
    y = dr.select(x == math.inf, big, dr.select(x == -math.inf, -big, x))
    return dr.select(dr.isnan(x), nan, y)


def ray_box(mi, origin, direction, bbox, clamp_start: bool = True):
    """``geometry.ray_box`` for Float64 rays (origin and direction: 3 Float64 each)."""
    import drjit as dr
    sc = Scalars(mi, lo=bbox[0], hi=bbox[1])
    t0, t1 = None, None
    for c in range(3):
        inv = 1.0 / direction[c]
        ta, tb = (sc[f"lo{c}"] - origin[c]) * inv, (sc[f"hi{c}"] - origin[c]) * inv
        either_nan = dr.isnan(ta) | dr.isnan(tb)
        tmin = _nan_to_num(dr, dr.select(either_nan, math.nan, dr.select(tb < ta, tb, ta)), -math.inf)
        tmax = _nan_to_num(dr, dr.select(either_nan, math.nan, dr.select(tb > ta, tb, ta)), math.inf)
        # (np.max / np.min over the axis propagate NaN: none is left here)
        t0 = tmin if t0 is None else dr.select(tmin > t0, tmin, t0)
        t1 = tmax if t1 is None else dr.select(tmax < t1, tmax, t1)
    return (dr.select(t0 > 0.0, t0, 0.0) if clamp_start else t0), t1


def ground_hits(mi, spec, origin, direction):
    """``scene.spec.ground_hits`` (the flat ground) for Float64 rays: distance along each ray, inf where
    it does not hit."""
    import drjit as dr
    if spec.ground is None:
        return dr.full(mi.Float64, math.inf, dr.width(direction[2]))
    dz = direction[2]
    t = (Scalars(mi, height=spec.ground.height)["height"] - origin[2]) / dz
    return dr.select((dz < 0.0) & (t > 0.0), t, math.inf)


def light_rays(mi, g, res: int, grid_box, box):
    """The light buffer's rays of ``LightVolume._light_rays``: (p0, step, q0, q_step, k_in, k_out), p0 each
    texel's point on plane 0 (3 Float64), step the way to the next plane (numpy (3,)), q0 and q_step p0 and
    step in texture coordinates of ``grid_box`` (3 Float64, numpy (3,)) and where the ray is inside the
    slicing ``box`` in slice units (Float64)."""
    import drjit as dr
    R = int(res)
    s, l = g.axis, g.to_light
    s_dot_l = float(s @ l)
    step = -g.spacing / s_dot_l * l
    glo, ghi = (np.asarray(p, dtype=np.float64) for p in grid_box)
    span = ghi - glo
    sc = Scalars(mi, R=R, u0=g.u_range[0], du=g.u_range[1] - g.u_range[0], v0=g.v_range[0],
                 dv=g.v_range[1] - g.v_range[0], e1=g.e1, e2=g.e2, s=s, l=l, d_first=g.d_first, s_dot_l=s_dot_l,
                 glo=glo, span=span, step=step)
    lane = dr.arange(mi.UInt32, R * R)
    y = lane // R  # (a literal divisor: the buffer's size is the renderer's)
    x = lane - y * R
    su = lambda i: (mi.Float64(i) + 0.5) / sc["R"]  # noqa: E731
    uu = sc["u0"] + su(x) * sc["du"]
    vv = sc["v0"] + su(y) * sc["dv"]
    base = [uu * sc[f"e1{c}"] + vv * sc[f"e2{c}"] for c in range(3)]
    along = (sc["d_first"] - ((base[0] * sc["s0"] + base[1] * sc["s1"]) + base[2] * sc["s2"])) / sc["s_dot_l"]
    p0 = [base[c] + along * sc[f"l{c}"] for c in range(3)]
    q0 = [(p0[c] - sc[f"glo{c}"]) / sc[f"span{c}"] for c in range(3)]
    k_in, k_out = ray_box(mi, p0, [sc[f"step{c}"] + dr.zeros(mi.Float64, R * R) for c in range(3)], box,
                          clamp_start=False)
    return p0, step, q0, step / span, k_in, k_out


def phase_table(mi, table):
    """A phase table's angles and values as Float64 arrays and its slopes (``np.interp``'s), for
    ``phase_values``."""
    theta = np.asarray(table.theta, dtype=np.float64)
    values = np.asarray(table.values, dtype=np.float64)
    slopes = (values[1:] - values[:-1]) / (theta[1:] - theta[:-1])[:, None]
    return (mi.Float64(theta), [mi.Float64(np.ascontiguousarray(values[:, c])) for c in range(3)],
            [mi.Float64(np.ascontiguousarray(slopes[:, c])) for c in range(3)])


def phase_index(mi, xp, theta):
    """Where scattering angles ``theta`` (Float64, radians) fall in a table's angles ``xp`` (Float64, increasing):
    (j, below, at_end), j the last table angle <= theta (0 .. K - 2), and whether theta lies before the
    first angle or at or after the last. Tables with the same angles share it (``phase_values``)."""
    import drjit as dr
    K = dr.width(xp)
    first_above = dr.binary_search(0, K - 1, lambda i: dr.gather(mi.Float64, xp, i) <= theta)
    j = mi.UInt32(dr.maximum(mi.Int32(first_above) - 1, 0))
    return j, theta < dr.gather(mi.Float64, xp, 0), theta >= dr.gather(mi.Float64, xp, K - 1)


def phase_values(mi, arrays, theta, index=None):
    """The phase function (3 Float64, 1/sr) at scattering angles ``theta`` (Float64, radians): ``np.interp``
    of ``table.eval`` over ``phase_table(table)``'s arrays (left and right of the table: its end values);
    ``index``: ``phase_index`` of the table's angles at theta, or None (found here)."""
    import drjit as dr
    xp, fp, slopes = arrays
    K = dr.width(xp)
    j, below, at_end = phase_index(mi, xp, theta) if index is None else index
    x_lo, x_hi = dr.gather(mi.Float64, xp, j), dr.gather(mi.Float64, xp, j + 1)
    out = []
    for c in range(3):
        f_lo, f_hi = dr.gather(mi.Float64, fp[c], j), dr.gather(mi.Float64, fp[c], j + 1)
        slope = dr.gather(mi.Float64, slopes[c], j)
        v = slope * (theta - x_lo) + f_lo
        again = slope * (theta - x_hi) + f_hi
        v = dr.select(dr.isnan(v), dr.select(dr.isnan(again) & (f_lo == f_hi), f_lo, again), v)
        v = dr.select(below, dr.gather(mi.Float64, fp[c], 0), v)
        out.append(dr.select(at_end, dr.gather(mi.Float64, fp[c], K - 1), v))
    return out
