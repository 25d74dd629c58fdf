"""The eye rays' air on a coarse grid of the frame's pixels, read per pixel (issue 38 part 3: the air's cost in
a drag frame).

``eye_air.seen_through_air`` integrates the air on every pixel's ray (12 + 2 x 13 points, each a few table
lookups and a lookup of the storm's shadow): half the time of a uniform-mode frame at 300 x 300. The air seen
along neighbouring rays differs little (it varies with the direction over degrees, as the sky does); only the
cloud's depth and transmittance, which split the box's chord, change from pixel to pixel. So here the rays of
every ``STEP``-th pixel in x and in y (the last row and column included) integrate the air once:

* A: the segment outside the box, (S_A, T_A) over [camera, box entry] (or [camera, the ground or the air's
  top] where the ray misses the box), on Gauss-Legendre nodes as ``eye_air``'s (``eye_air_quadrature``);
* the box's chord [t_in, t_out] as cumulative (S, T) at ``BOX_POINTS`` uniform fractions x_k of it (trapezoids,
  the diffuse light and the storm's shadow as ``eye_air.segment``'s).

A pixel reads its four coarse neighbours bilinearly (one packet of 4 floats per value): A, and the box's
cumulative at its own cloud depth's fraction f_c = (t_c - t_in) / (t_out - t_in) of its own chord and at 1.
With S(f), T(f) the cumulative box air, the eye pass's radiance R = C + T_c L_bg (``eye_air``'s docstring,
T_c the cloud's transmittance):

    L_box = E S(f_c) + T(f_c) R + T_c (E (S(1) - S(f_c)) + (T(1) - T(f_c)) L_bg)
    L = L_box + w (E S_A + (T_A - 1) L_box)

(``eye_air.seen_through_air``'s with S_f = S(f_c), T_f = T(f_c), S_b = (S(1) - S(f_c)) / T(f_c), T_b = T(1) /
T(f_c)). The whole box's S(1), T(1) are the neighbours' scaled to the pixel's own chord length L from their mean
chord L' (each coarse ray stores its own): T(1)^(L / L'), S(1) (1 - T(1)^(L / L')) / (1 - T(1)), a uniform slab's
(near the box's side walls neighbouring chords differ by their whole length: with the air's multiple scattering the
worst pixel there was 21% off, 10% after). Neighbours whose ray meets the box where the pixel's does not (or the
reverse) are left out of its weights, and so are those that end on the sky where the pixel's ray ends on the ground
(or the reverse): the box's silhouette and the horizon stay sharp. Against every pixel's own integration
(``seen_through_air``) on the demo supercell's drag at 300 x 300: the mean within 0.03% per channel, 99% of pixels
within 1.8%, the worst 4.5% (with the air's multiple scattering and the chord's scaling; 1.7% and 6% before; the
rows just below the horizon, where the ground's distance grows faster than linearly;
tests/test_slicing_air_coarse.py: 99% within 4.8% at 160 px, 8% at 120). Pixels whose neighbours differ integrating
their own air (tried: 99% within 0.6% at 300 px) cost twice what the grid saves, even branched per packet. The
grid's size is part of the frame's structure (it changes with the frame's size only): a new view compiles nothing.
Frames smaller than ``MIN_PIXELS`` a side integrate every pixel (``eye_air.seen_through_air``).

Coarse rays that miss the box evaluate no point of its profile (their rows: T = 1, S = 0), those that end on
the sky model's sky without crossing the box integrate no air outside it (no pixel of their kind reads it), and
pixels of that kind keep the eye pass's radiance: each a branch LLVM takes per packet of lanes (the same floats);
a pixel reads the box's rows at its cloud's depth and at the box's end behind branches of the same kind (packets of
pixels on the ground or in a clear part of the box read none of them; Dr.Jit on one thread, the drag: the per-pixel
composite ~3 -> ~1.3 ms of CPU a frame).

The cost (benchmarks/slicing_air.py, the drag at 300 x 300, 128 slices, frame by frame against no air): the
rate with the air at 0.89-0.94 of the rate without it in the uniform modes (benchmarks/README.md, issue 38
part 3), 0.53-0.65 when every pixel integrated its own (and the box's rows were scattered one kernel each).
"""
from __future__ import annotations

from .eye import OPAQUE_T
from .eye_air import EyeAir, behind_box, outside_box, outside_weight, profile, ray_ends, source_at
from .eye_air_quadrature import NODES, gauss_segment

STEP = 4            # the coarse grid: every STEP-th pixel in x and y (the last row and column included)
BOX_POINTS = 17     # points on each coarse ray's box chord (uniform): the cloud's depth read between them
MIN_PIXELS = 96        # a side: smaller frames integrate every pixel's air (validation/slicer_air.py's 32 px: the
                       # box's air at its edges; the viewer's 160 x 120 draft uses the grid: 99% of pixels within 8%,
                       # the rows below the horizon, for a draft at 0.9-1.0 of the rate without air against 0.7)
ROW = 8             # floats per stored point: (S rgb, flag), (T rgb, 0)


def coarse_count(n: int, step: int = STEP) -> int:
    """Coarse points along a side of n pixels: 0, step, 2 step, ... and n - 1."""
    return -(-(n - 1) // step) + 1


def applies(air: EyeAir, width_rays: int) -> bool:
    """Whether the frame's air goes through the coarse grid (its rays are the width x height pixels)."""
    return (air.width >= MIN_PIXELS and air.height >= MIN_PIXELS
            and width_rays == air.width * air.height)


def coarse_air(mi, air: EyeAir, o, d, shadow=None):
    """The air of the coarse rays (module docstring) as a flat mi.Float: per coarse ray, ``BOX_POINTS`` rows
    of the box's cumulative (S, T) and one row of A's (S_A, T_A), ``ROW``
    floats each (A's with the ray's kind, ``_kind``); ``o``, ``d``: every pixel's ray."""
    import drjit as dr
    w, h = air.width, air.height
    nx, ny = coarse_count(w), coarse_count(h)
    j = dr.arange(mi.UInt32, nx * ny)
    jy = j // nx
    pixel = dr.minimum(jy * STEP, h - 1) * w + dr.minimum((j - jy * nx) * STEP, w - 1)
    o, d = dr.gather(mi.Point3f, o, pixel), dr.gather(mi.Vector3f, d, pixel)
    t_in, t_out, t_end, hit, t_ground = ray_ends(mi, air, o, d)
    kind = _kind(dr, hit, t_ground)
    # A: not where the ray ends on the sky model's sky without crossing the box (no pixel of that kind uses it);
    # with the air's own sky everywhere, and B behind the box (``eye_air.seen_through_air``)
    a_end = t_end if air.sky_air else dr.select(kind == 2.0, 0.0, t_end)
    t_a, s_a = gauss_segment(mi, source_at(mi, air, o, d, outside_box(shadow), air.sky_air), 0.0 * t_in,
                             dr.select(hit, t_in, a_end), NODES, True)
    rows = _rows(air)
    out = dr.empty(mi.Float, nx * ny * rows * ROW)  # (every float written below)
    base = j * (rows * 2)  # in packets of 4 floats

    chord = dr.select(hit, t_out - t_in, 0.0)

    def emit(k, t, s):  # row k of the box's cumulative air (with the chord's length, m); with the first, row 0
        dr.scatter(out, mi.Vector4f(s.x, s.y, s.z, 0.0), base + 2 * k)  # (T = 1, S = 0) and A's
        dr.scatter(out, mi.Vector4f(t.x, t.y, t.z, chord), base + 2 * k + 1)
        first = k == 1
        dr.scatter(out, mi.Vector4f(0.0, 0.0, 0.0, 0.0), base, first)
        dr.scatter(out, mi.Vector4f(1.0, 1.0, 1.0, 0.0), base + 1, first)
        dr.scatter(out, mi.Vector4f(s_a.x, s_a.y, s_a.z, kind), base + 2 * BOX_POINTS, first)
        dr.scatter(out, mi.Vector4f(t_a.x, t_a.y, t_a.z, 0.0), base + 2 * BOX_POINTS + 1, first)
    profile(mi, air, o, d, dr.select(hit, t_in, 0.0), dr.select(hit, t_out, 0.0), BOX_POINTS, emit, shadow, hit)
    if air.sky_air:  # B: its own row after A's
        t_b, s_b = gauss_segment(mi, source_at(mi, air, o, d, outside_box(shadow), True), dr.select(hit, t_out, 0.0),
                                 dr.select(hit, t_end, 0.0), NODES, True)
        dr.scatter(out, mi.Vector4f(s_b.x, s_b.y, s_b.z, 0.0), base + 2 * (BOX_POINTS + 1))
        dr.scatter(out, mi.Vector4f(t_b.x, t_b.y, t_b.z, 0.0), base + 2 * (BOX_POINTS + 1) + 1)
    return out


def _rows(air: EyeAir) -> int:
    """Rows per coarse ray: the box's ``BOX_POINTS``, A's, and with the air's own sky B's."""
    return BOX_POINTS + (2 if air.sky_air else 1)


def _kind(dr, hit, t_ground):
    """The ray's kind as a float: 1 where it crosses the box, + 2 where it ends on the sky model's sky (the
    pixels interpolate between neighbours of their own kind: the box's silhouette and the horizon stay sharp)."""
    return dr.select(hit, 1.0, 0.0) + dr.select(dr.isfinite(t_ground), 0.0, 2.0)


def _corners(mi, dr, w: int, h: int):
    """[(coarse ray index, weight)] of the four coarse neighbours of every pixel (bilinear)."""
    nx, ny = coarse_count(w), coarse_count(h)
    p = dr.arange(mi.UInt32, w * h)
    y = p // w
    x = p - y * w

    def axis(v, n, size):
        c = dr.minimum(v // STEP, n - 2)
        v0 = c * STEP
        return c, mi.Float(v - v0) / mi.Float(dr.minimum(v0 + STEP, size - 1) - v0)
    cx, fx = axis(x, nx, w)
    cy, fy = axis(y, ny, h)
    return [(((cy + b) * nx + cx + a), (fx if a else 1.0 - fx) * (fy if b else 1.0 - fy))
            for b in (0, 1) for a in (0, 1)]


def seen_through_coarse_air(mi, air: EyeAir, rays, radiance, transmittance, background, depth, shadow=None):
    """``eye_air.seen_through_air`` with the air read from the coarse grid (module docstring); the same
    arguments. Pixels whose ray ends on the sky model's sky without crossing the box see no air of ours: their
    radiance as it is (LLVM skips a packet of them)."""
    import drjit as dr
    o, d = rays.origin, rays.direction
    table = coarse_air(mi, air, o, d, shadow if air.shadow else None)
    t_in, t_out, t_end, hit, t_ground = ray_ends(mi, air, o, d)
    w = outside_weight(mi, air, transmittance, hit, t_ground)
    return dr.if_stmt((radiance, transmittance, background, depth), (w > 0) | hit,
                      lambda *a: _blend(mi, dr, air, table, *a, (t_in, t_out, hit, t_ground, w)),
                      lambda r, *_: mi.Color3f(r))


def _blend(mi, dr, air: EyeAir, table, radiance, transmittance, background, depth, ends):
    """``seen_through_coarse_air``'s pixels (module docstring): the coarse neighbours' air read at the pixel's
    cloud depth; ``ends``: (t_in, t_out, hit, t_ground, w) of the pixels' rays (``eye_air.ray_ends``)."""
    t_in, t_out, hit, t_ground, w = ends
    t_c = dr.clip(dr.select(transmittance < 1.0, depth, t_in), t_in, t_out)
    f = dr.clip((t_c - t_in) / dr.maximum(t_out - t_in, 1e-6), 0.0, 1.0) * (BOX_POINTS - 1)
    i0 = dr.minimum(mi.UInt32(f), BOX_POINTS - 2)
    f = f - mi.Float(i0)
    rows = _rows(air)
    corners = _corners(mi, dr, air.width, air.height)
    kind = _kind(dr, hit, t_ground)

    def read(c, k, active, chord=False):
        """(S, T, kind) of row k of coarse ray c (zeros where not ``active``: not read); ``chord``: and the
        ray's box chord (m)."""
        s = dr.gather(mi.Vector4f, table, c * (rows * 2) + 2 * k, active)
        t = dr.gather(mi.Vector4f, table, c * (rows * 2) + 2 * k + 1, active)
        return (mi.Color3f(s.x, s.y, s.z), mi.Color3f(t.x, t.y, t.z), s.w) + ((t.w,) if chord else ())
    zero = dr.zeros(mi.Color3f, dr.width(t_in))
    s_a, t_a, s_far, t_far = zero, zero, zero, zero
    total, plain = mi.Float(0.0), []
    # what each pixel reads: A where it counts (w > 0), the box at the cloud's depth where there is cloud, the
    # whole box where the cloud lets light through (elsewhere: S = 0, T = 1 in front of the cloud, nothing seen
    # behind it); the box's rows each behind a branch that LLVM takes per packet of lanes (packets of pixels
    # that need none of them read none)
    need_a, need_f, need_1 = w > 0, hit & (transmittance < 1.0), hit & (transmittance > OPAQUE_T)
    for c, wgt in corners:
        sa, ta, flag = read(c, BOX_POINTS, need_a | hit)
        wgt_same = dr.select(flag == kind, wgt, 0.0)  # the same side of the box's silhouette and the horizon
        plain.append((c, wgt, wgt_same, sa, ta))
        total += wgt_same
    use_all = total < 1e-3  # no neighbour on the pixel's side: all four
    norm = dr.select(use_all, 1.0, dr.rcp(dr.maximum(total, 1e-3)))
    cs, ks = [], []
    for c, wgt, wgt_same, sa, ta in plain:
        k = dr.select(use_all, wgt, wgt_same) * norm
        s_a, t_a = s_a + k * sa, t_a + k * ta
        if air.sky_air:  # B, where the pixel's ray crosses the box
            sb, tb, _ = read(c, BOX_POINTS + 1, hit)
            s_far, t_far = s_far + k * sb, t_far + k * tb
        cs.append(c)
        ks.append(k)

    def at_depth(i0, f, *ck):  # the box's cumulative air at the cloud's depth (rows i0 and i0 + 1)
        s_f, t_f = mi.Color3f(0.0), mi.Color3f(0.0)
        for c, k in zip(ck[:len(ck) // 2], ck[len(ck) // 2:]):
            sl, tl, _ = read(c, i0, True)
            su, tu, _ = read(c, i0 + 1, True)
            s_f, t_f = s_f + k * (sl + (su - sl) * f), t_f + k * (tl + (tu - tl) * f)
        return s_f, t_f

    def whole(s_f, t_f, *ck):  # ... and through the whole box (its last row), for the pixel's own chord: the
        s_1, t_1, chord = mi.Color3f(0.0), mi.Color3f(0.0), mi.Float(0.0)  # neighbours' as a uniform slab's of
        for c, k in zip(ck[:len(ck) // 2], ck[len(ck) // 2:]):           # their mean chord, scaled to it
            se, te, _, length = read(c, BOX_POINTS - 1, True, chord=True)
            s_1, t_1, chord = s_1 + k * se, t_1 + k * te, chord + k * length
        return own_chord(s_1, t_1, chord)

    def own_chord(s_1, t_1, chord):
        """(S, T) of a chord of the pixel's length t_out - t_in from those of the neighbours' mean ``chord``:
        tau in proportion to the length, S = J (1 - T) with the same J (exact for a uniform slab: the box's
        side walls, where neighbouring rays' chords differ by their whole length, and the coarse grid's worst
        pixels were; the same values where the chords are equal)."""
        r = (t_out - t_in) / dr.maximum(chord, 1e-3)
        t_own = dr.exp(r * dr.log(dr.maximum(t_1, 1e-30)))
        thin = 1.0 - t_1 < 1e-4
        return dr.select(thin, s_1 * r, s_1 * (1.0 - t_own) / dr.maximum(1.0 - t_1, 1e-4)), t_own
    s_f, t_f = dr.if_stmt((i0, f, *cs, *ks), need_f, at_depth, lambda *_: (mi.Color3f(0.0), mi.Color3f(1.0)))
    s_1, t_1 = dr.if_stmt((s_f, t_f, *cs, *ks), need_1, whole, lambda s, t, *_: (mi.Color3f(s), mi.Color3f(t)))
    e = air.irradiance
    if air.sky_air:
        radiance, background = behind_box(e, s_far, dr.select(hit, t_far, 1.0), radiance, transmittance, background)
    boxed = e * s_f + t_f * radiance + transmittance * (e * (s_1 - s_f) + (t_1 - t_f) * background)
    return boxed + w * (e * s_a + (t_a - 1.0) * boxed)


__all__ = ["BOX_POINTS", "STEP", "applies", "coarse_air", "coarse_count", "seen_through_coarse_air"]
