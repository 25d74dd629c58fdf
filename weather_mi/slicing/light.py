"""The light volume: the light pass of half-angle slicing and the one lookup that every reader (the
eye pass, the ground, ``SliceRenderer.light_at``, tests) uses.

The light pass visits the slice planes from the light's side, one light ray per texel of a buffer
perpendicular to the light, and stores at every plane k (the middle of slab k) the light arriving
there, as fractions of the light's irradiance: direct light D and forward-scattered light I.

Per half slab (extinction beta and forward-scattering coefficient beta_f = sum_s beta_s omega_s f_s
averaged over the half slab from LIGHT_SUBSAMPLES samples; f_s: the fraction of species s's scattered
energy within the forward cone), over a light path dl:
    D' = D exp(-beta dl)                  the direct beam
    F' = F exp(-(beta - beta_f) dl)       F = D + I: all light still travelling forward
which is exact for a homogeneous slab, so that thick slabs are handled and the limit does not depend on
the slice count (a per-slice survival factor omega f would compound once per slice). In translucent mode
I also spreads sideways like a diffusion: a Gaussian whose variance grows by ``variance_per_m`` (m^2 per
metre of light path), applied by operator splitting (slabs in chunks, then the chunk's accumulated
variance with separable taps of exactly that variance, blur.py: no bilinear-tap diffusion), so the spread after a
given distance is the same for any number of slices.

A light ray reads the medium only in the slabs of its occupied span (occupancy.py, ``_slab_range``): at the
other planes the loop kernel stores the light unchanged (a branch that LLVM takes per packet of lanes), the
same floats as reading the empty texture there, at about half the light pass's cost on the demo storm.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..kernel.jitarrays import aligned_float, kernel_scalar
from .blur import _blur, blur_weights
from .geometry import SliceGeometry
from .jitter import texel_offsets
from .light_slabs import (LIGHT_SUBSAMPLES, LOG_FLOOR, _hold_step, _slab_range, _slab_step,  # noqa: F401 (re-exported)
                          source_extinction, store_light, word_pair)
from .rays import f32, light_rays

# variance (texels^2) that forward-scattered light accumulates between two blur steps at the reference
# spread (see LightVolume.sweep); larger spreads up to MAX_TEXEL_VARIANCE / BLUR_STEP_VARIANCE times the
# reference (cone angles up to ~30 deg for a 20 deg reference) are still blurred exactly. Each step is one
# kernel launch over the light buffer: at the demo's default spread (300 x 300, 128 slices) 1.5 blurs every
# 4 slabs with a 13-tap kernel (0.5 with the 5-tap kernel, whose exact range ends at 4/3, blurred every slab:
# 127 launches instead of 31, ~17% more frame time in uniform/translucent; slice convergence unchanged)
BLUR_STEP_VARIANCE = 1.5


def auto_light_res(box, spacing, low: int = 128, high: int = 256) -> int:
    """Light-buffer texels per side for a slicing ``box`` ((lo, hi) world corners) and grid ``spacing``
    (dz, dy, dx): enough that a texel spans at most three of the grid's thinnest cells across the box's
    horizontal diagonal, rounded up to a multiple of 16, between ``low`` and ``high``. A flat grid with
    thin layers (30 km columns of 500 m levels) needs a finer buffer than its width suggests, or the
    image keeps changing with the slice count."""
    lo, hi = (np.asarray(p, dtype=np.float64) for p in box)
    diagonal = float(np.hypot(hi[0] - lo[0], hi[1] - lo[1]))
    n = diagonal / (3.0 * float(min(spacing)))
    return int(np.clip(16 * math.ceil(n / 16), low, high))


@dataclass
class LookupFrame:
    """A light volume's geometry as kernel values (opaque scalars, a Dr.Jit PyTree): buffer axes e1, e2
    and the slice axis (unit), buffer texel coordinates x = (p . e1 - u0) u_scale (likewise y), and the
    slice index k = (d_first - p . axis) inv_spacing = (d_first - p . axis) / spacing. With ``jitter``, texel
    t's planes (and slabs) are offset by j_t = jitter.texel_offsets(...) slice units along its light ray."""

    e1: object
    e2: object
    axis: object
    u0: object
    u_scale: object
    v0: object
    v_scale: object
    d_first: object
    inv_spacing: object
    spacing: object
    jitter: object = None      # None, or the texels' plane offsets: amplitude and rotation (jitter.py)
    rotation: object = None
    to_light: object = None    # the unit vector towards the light, and the light path across a slab (m)
    light_step: object = None


def lookup_frame(mi, g: SliceGeometry, res: int, jitter=None) -> LookupFrame:
    """``LookupFrame`` of geometry ``g`` with a ``res`` x ``res`` buffer (values rounded from float64);
    ``jitter``: None or (amplitude, rotation) of the texels' plane offsets, opaque scalars."""
    vec = lambda v: mi.Vector3f(*(kernel_scalar(mi, c) for c in v))  # noqa: E731
    return LookupFrame(vec(g.e1), vec(g.e2), vec(g.axis), kernel_scalar(mi, g.u_range[0]),
                       kernel_scalar(mi, res / (g.u_range[1] - g.u_range[0])), kernel_scalar(mi, g.v_range[0]),
                       kernel_scalar(mi, res / (g.v_range[1] - g.v_range[0])), kernel_scalar(mi, g.d_first),
                       kernel_scalar(mi, 1.0 / g.spacing), kernel_scalar(mi, g.spacing), *(jitter or (None, None)),
                       to_light=vec(g.to_light), light_step=kernel_scalar(mi, g.light_step_m))


@dataclass
class SweepPlan:
    """Inputs of ``LightVolume.run`` (a Dr.Jit PyTree; the ints and the flag set the kernels' structure):
    the light rays (q0, qs, kin, kout of ``LightVolume._light_rays``), the light path across a slab dl (m),
    the blur's variance per slab (m^2) and inverse squared texel sizes (1/m^2; None unless translucent),
    the store's ``LookupFrame``, the slice count and the slabs per blur step."""

    q0: object
    qs: object
    kin: object
    kout: object
    dl: object
    var: object
    inv_du2: object
    inv_dv2: object
    frame: LookupFrame
    n_slices: int
    chunk: int
    translucent: bool
    ka: object = None   # None, or each light ray's occupied span in slice units (occupancy.py): outside it
    kb: object = None   # the medium is empty, and the light pass reads nothing there
    keep: object = None  # None, or (beta - beta_f) / beta where the source holds beta alone (translucent)


class LightVolume:
    """Light arriving at every slice plane of a sweep from one light direction (the sun, or the
    zenith for skylight): ``sweep`` fills it, ``lookup`` reads it inside kernels, ``light_at`` from
    numpy. Storage: (planes, R, R) floats of direct light D where no light is scattered forward; for
    translucent light (``log_store``) (planes, R, R, 2): log D and log(D + I) (I: forward-scattered), which
    its lookups interpolate (as logarithms: ``lookup(log_forward=True)``) without taking a logarithm per
    texel read; the pair as one 64-bit word a texel (planes, R, R) unless differentiated (``light_slabs``)."""

    def __init__(self, mi, box, res: int, differentiable: bool = False, occupancy=None):
        self.mi = mi
        self.lo, self.hi = (np.asarray(p, dtype=np.float64) for p in box)  # slicing box (world)
        self.res = int(res)
        self.differentiable = differentiable
        self.words = not differentiable  # translucent light's pair as one 64-bit word a texel (light_slabs.py)
        self.store = None
        self.log_store = False  # the store holds log D, log(D + I) (translucent light)
        self.frame: LookupFrame | None = None   # the geometry of the store, as kernel values
        self.n_slices = 0
        self._rays, self._rays_key = None, None
        self.occupancy = occupancy  # an occupancy.OccupancyMap of the medium, or None

    # ------------------------------------------------------------------ the light pass
    def sweep(self, g: SliceGeometry, source, grid_box, translucent: bool, variance_per_m=None,
              reference_variance_per_m: float | None = None):
        """Carry the light through the slices of ``g``: ``plan`` then ``run`` (which the renderer's
        recorded frame launches without tracing).

        Parameters
        ----------
        g : SliceGeometry
            The slice planes and the light direction.
        source : mi.Texture3f
            (extinction, forward-scattering coefficient) in 1/m over ``grid_box``.
        grid_box : tuple of 2 array_like
            (lo, hi) world corners (m) of the texture.
        translucent : bool
            Forward-scattered light is carried (and spread sideways) too.
        variance_per_m : drjit Float or float, optional
            The sideways diffusion of forward-scattered light (m^2 per metre of light path).
        reference_variance_per_m : float, optional
            Sets how many slabs run between two blur steps (BLUR_STEP_VARIANCE at this spread); default
            ``variance_per_m``. Keeping it independent of the interactive parameters keeps the image a
            smooth function of them (finite differences and reverse-mode gradients agree).
        """
        plan = self.plan(g, grid_box, translucent, variance_per_m, reference_variance_per_m)
        self.bind(plan, self.run(plan, source))

    def plan(self, g: SliceGeometry, grid_box, translucent: bool, variance_per_m=None,
             reference_variance_per_m: float | None = None, jitter=None, keep=None) -> "SweepPlan":
        """Everything ``run`` needs from ``g`` and the parameters, as kernel inputs (see ``sweep``);
        ``jitter``: None, or (amplitude, rotation) of per-texel plane offsets (opaque scalars, jitter.py);
        ``keep``: None, or the ratio (beta - beta_f) / beta (a Dr.Jit Float) of translucent light whose
        ``source`` holds beta alone (one forward fraction over the whole medium)."""
        mi = self.mi
        key = (g.axis.tobytes(), g.to_light.tobytes(), g.d_first, g.spacing, g.n_slices, g.u_range, g.v_range,
               tuple(np.asarray(grid_box, dtype=np.float64).ravel()))
        if self._rays_key != key:  # a slider move keeps the light rays and the geometry's kernel scalars
            du = (g.u_range[1] - g.u_range[0]) / self.res
            dv = (g.v_range[1] - g.v_range[0]) / self.res
            self._rays = (self._light_rays(g, grid_box), lookup_frame(mi, g, self.res),
                          kernel_scalar(mi, g.light_step_m), kernel_scalar(mi, 1.0 / du ** 2), kernel_scalar(mi, 1.0 / dv ** 2))
            self._rays_key = key
        (q0, qs, kin, kout, span), frame, dl, inv_du2, inv_dv2 = self._rays
        if jitter is not None:
            frame = replace(frame, jitter=jitter[0], rotation=jitter[1])
        chunk, var = g.n_slices, None
        if translucent:
            chunk, var = self._blur_plan(g, variance_per_m, reference_variance_per_m, dl)
        else:
            inv_du2 = inv_dv2 = None
        return SweepPlan(q0, qs, kin, kout, dl, var, inv_du2, inv_dv2, frame,
                         g.n_slices, int(chunk), bool(translucent), *span, keep=keep)

    def run(self, plan: "SweepPlan", source):
        """The light pass's kernels: the store (see the class docstring)."""
        mi = self.mi
        import drjit as dr
        R, N = self.res, plan.n_slices
        C = 2 if plan.translucent else 1  # stored channels: (log D, log(D + I)), or D alone (I = 0)
        # every plane of every lane is written (the exit plane too); only a differentiated pass starts from zeros
        words = plan.translucent and self.words
        store = dr.empty(mi.UInt64, (N + 1) * R * R) if words else \
            (dr.zeros if self.differentiable else dr.empty)(mi.Float, (N + 1) * R * R * C)
        lane = dr.arange(mi.UInt32, R * R)
        offset = None
        if plan.frame.jitter is not None:
            offset = texel_offsets(dr, mi, lane % R, lane // R, plan.frame.jitter, plan.frame.rotation)
        plane = dr.opaque(mi.UInt32, R * R)
        through_slab = _slab_step(mi, source, (plan.q0, plan.qs, plan.kin, plan.kout), plan.dl, store, lane,
                                  plane, plan.translucent, offset, N, (plan.ka, plan.kb), plan.keep, words)
        # the slabs that may read the medium per light ray, and the store of those that do not
        hold = _hold_step(mi, dr, store, lane, plane, plan.translucent, words)
        span = None if plan.ka is None else _slab_range(mi, dr, plan.ka, plan.kb, N)
        if plan.translucent:  # (log D, log F), F = D + I: a slab subtracts optical depths, nothing more
            state = (dr.zeros(mi.Float, R * R), dr.zeros(mi.Float, R * R))
        else:  # (D, I = 0)
            state = (dr.full(mi.Float, 1.0, R * R), dr.zeros(mi.Float, R * R))
        starts = list(range(0, N, plan.chunk))
        weights = {}  # per step length (all steps but the last have the same): the blur's weights per axis
        for j, k0 in enumerate(starts):
            k1 = min(k0 + plan.chunk, N)
            if plan.translucent and j > 0:  # the blur step spreads I = F - D
                n_prev = k0 - starts[j - 1]
                if n_prev not in weights:
                    var = plan.var * dr.opaque(mi.Float, float(n_prev))
                    weights[n_prev] = (blur_weights(dr, var * plan.inv_du2), blur_weights(dr, var * plan.inv_dv2))
                D = dr.exp(state[0])
                blurred = _blur(mi, dr, state[2], R, *weights[n_prev])
                state = (state[0], dr.log(dr.maximum(D + blurred, 1e-30)))
            state = self._through_slabs(through_slab, state, k0, k1, lane, store,
                                        plan.translucent and k1 < N, hold, span)  # (I for the next blur step)
        at = lane + dr.opaque(mi.UInt32, N * R * R)
        if plan.translucent:
            D, I = (dr.maximum(v, LOG_FLOOR) for v in state[:2])
        else:
            D, I = state
        store_light(mi, dr, store, at, D, I, plan.translucent, words)
        dr.eval(store)
        return store

    def bind(self, plan: "SweepPlan", store):
        """Make ``store`` (of ``run(plan, ...)``) the light that ``lookup`` reads."""
        self.store, self.frame, self.n_slices = store, plan.frame, plan.n_slices
        self.log_store = plan.translucent

    def unbind(self):
        """Forget the bound light: lookups fail until the next ``bind`` (a frame's kernels bind the light
        of their own inputs; none reads the last frame's)."""
        self.store, self.frame, self.n_slices = None, None, 0

    def _light_rays(self, g: SliceGeometry, grid_box):
        """One light ray per buffer texel: (q0, qs, kin, kout), its point on plane 0 and its step to the
        next plane in texture coordinates of ``grid_box``, and where it is inside the slicing box, in
        slice units: k in [kin, kout]."""
        mi = self.mi
        import drjit as dr
        p0, step, q0, q_step, k_in, k_out = light_rays(mi, g, self.res, grid_box, (self.lo, self.hi))  # float64 kernels
        qs = mi.Vector3f(*(dr.opaque(mi.Float, float(v)) for v in q_step))
        q0 = mi.Point3f(*(f32(mi, v) for v in q0))
        span = (None, None)
        if self.occupancy is not None:  # the occupied part of each light ray, in slice units
            L = float(np.linalg.norm(step))
            o = mi.Point3f(*(f32(mi, v) for v in p0))
            direction = mi.Vector3f(*(dr.opaque(mi.Float, float(c) / L) for c in step))
            L64 = dr.opaque(mi.Float64, L)
            ta, tb = self.occupancy.spans(o, direction, f32(mi, k_in * L64), f32(mi, k_out * L64))
            inv_L = dr.opaque(mi.Float, 1.0 / L)
            span = (ta * inv_L, tb * inv_L)
        return q0, qs, f32(mi, k_in), f32(mi, k_out), span

    def _blur_plan(self, g: SliceGeometry, variance_per_m, reference_variance_per_m, dl):
        """(slabs per chunk, variance per slab (m^2)) of the operator splitting.

        Slabs run in chunks (one kernel each: light rays are independent within a chunk), and the
        sideways diffusion of the chunk's path is applied at the start of the next one; a chunk spans the
        light path over which the reference spread accumulates BLUR_STEP_VARIANCE, so its length in
        metres, and the image, converge as slices increase."""
        mi = self.mi
        import drjit as dr
        R = self.res
        texel = min(g.u_range[1] - g.u_range[0], g.v_range[1] - g.v_range[0]) / R   # m
        var = kernel_scalar(mi, variance_per_m) * dl                 # m^2 per slab
        ref = float(dr.detach(kernel_scalar(mi, variance_per_m))[0]) if reference_variance_per_m is None \
            else float(reference_variance_per_m)
        per_slab = ref * g.light_step_m / texel ** 2   # texels^2 per slab at the reference
        chunk = int(np.clip(BLUR_STEP_VARIANCE / max(per_slab, 1e-12), 1, g.n_slices))
        return chunk, var

    def _through_slabs(self, through_slab, state, k0: int, k1: int, lane, store, forward: bool = False,
                       hold=None, span=None):
        """Carry the light's ``state`` ((D, I), or (log D, log(D + I)) for translucent light) through slabs
        k0 .. k1 - 1: one loop kernel, or slab by slab when differentiable. With ``forward`` (translucent
        light before a blur step) the state comes back with I = (D + I) - D as a third value, evaluated in
        the same kernel. ``span``: None, or each lane's slabs [first, end) that may read the medium
        (``_slab_range``): the loop kernel reads the medium in those alone and only stores the light at the
        others' planes (``hold``, of ``_hold_step``: the same floats)."""
        mi = self.mi
        import drjit as dr
        if self.differentiable:
            for k in range(k0, k1):
                state = through_slab(dr.opaque(mi.UInt32, k), *state)
                dr.eval(*state, store)  # AD keeps its graph across evaluations
                # identity gathers: their adjoints are scatters, so the reverse pass stores the
                # adjoints of D and I at every slice instead of rebuilding the whole chain of later
                # slices in each kernel (O(N^2) operations, minutes of LLVM time at 96 slices)
                state = tuple(dr.gather(mi.Float, v, lane) for v in state)
        else:
            stop = dr.opaque(mi.UInt32, k1)

            def body(k, *st):
                if span is None:
                    return (k + 1, *through_slab(k, *st))
                # a slab outside the lane's occupied range only stores the light unchanged (a branch
                # that LLVM takes per packet: packets of lanes that all skip the medium read nothing)
                return (k + 1, *dr.if_stmt((k, *st), (k >= span[0]) & (k < span[1]), through_slab, hold))

            out = dr.while_loop((dr.zeros(mi.UInt32, self.res * self.res) + dr.opaque(mi.UInt32, k0), *state),
                                lambda k, *st: k < stop, body)
            state = tuple(out[1:])
        if forward:
            state = (*state, dr.exp(state[1]) - dr.exp(state[0]))
        dr.eval(*state, store)
        return state

    # ------------------------------------------------------------------ the lookup
    def lookup(self, p, exit_plane: bool = False, with_previous: bool = False, log_direct: bool = False,
               log_forward: bool = False, logs: bool = False, active=True):
        """(direct, indirect) light at world points ``p`` (mi.Point3f) inside a kernel: bilinear in
        the buffer, linear between the two nearest planes; (1, 0) on the light's side of the box and
        outside the buffer's footprint (light rays that miss the box). With ``exit_plane``: the light
        leaving the box on the same light ray (the last plane). With ``with_previous``: also the light
        one slice nearer the light on the same light ray (at p + l x light step), sharing the
        buffer's interpolation weights: ((direct, indirect), (direct, indirect) nearer the light). With
        ``log_direct``: the direct light is interpolated as its logarithm (the optical depth towards the
        light, which is linear inside a homogeneous slab where the light itself is not: between two planes
        of a dense tower, D falls from 1 to exp(-50), and a linear interpolation of D leaves most of the
        slab unshadowed and then drops). With ``log_forward``: all forward light D + I is interpolated as
        its logarithm too (it decays exponentially, at the extinction less the forward scattering), and
        I = (D + I) - D; with ``logs`` as well, the interpolated logarithms themselves: (log D, log(D + I))
        instead of (D, I), 0 where unlit. ``active``: lanes that need the light (the others read nothing)."""
        mi = self.mi
        import drjit as dr
        f, R, n_slices = self.frame, self.res, self.n_slices
        logs = logs and log_forward
        unlit_value = (0.0, 0.0) if logs else (1.0, 0.0)
        kf, x0, y0, fx, fy, outside = self._coordinates(p)
        if exit_plane:
            kf = mi.Float(float(n_slices))
        kc = dr.clip(kf, 0.0, float(n_slices))
        k0 = dr.minimum(mi.UInt32(kc), max(n_slices - 1, 0))
        fk = kc - mi.Float(k0)

        def texel(at):
            v = self._gather(at, active)
            if self.log_store:  # (log D, log(D + I)) stored
                if log_forward:
                    return v
                d, f = dr.exp(v[0]), dr.exp(v[1])
                return mi.Array2f(v[0] if log_direct else d, dr.maximum(f - d, 0.0))
            if log_forward:
                return mi.Array2f(dr.log(dr.maximum(v[0], 1e-30)), dr.log(dr.maximum(v[0] + v[1], 1e-30)))
            return mi.Array2f(dr.log(dr.maximum(v[0], 1e-30)), v[1]) if log_direct else v

        def plane(k):
            base = (k * R + y0) * R + x0
            a, b, c, d = texel(base), texel(base + 1), texel(base + R), texel(base + R + 1)
            return (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy

        def light(v):
            if logs:
                return v
            if log_forward:
                d = dr.exp(v[0])
                return mi.Array2f(d, dr.maximum(dr.exp(v[1]) - d, 0.0))
            return mi.Array2f(dr.exp(v[0]), v[1]) if log_direct else v

        if f.jitter is not None:
            return self._lookup_offset(kf, x0, y0, fx, fy, outside, texel, light, with_previous, exit_plane,
                                       unlit_value)
        last = exit_plane and not with_previous  # the last plane alone (the same floats as at weights 0 and 1)
        here, after = (None, plane(n_slices)) if last else (plane(k0), plane(k0 + 1))
        val = light(after if last else (1.0 - fk) * here + fk * after)
        u0, u1 = unlit_value
        unlit = (kf < -0.5) | outside
        out = (dr.select(unlit, u0, val[0]), dr.select(unlit, u1, val[1]))
        if not with_previous:
            return out
        # one plane nearer the light: planes k0 - 1 and k0 (plane 0 where k0 = 0: the clamp of kf - 1)
        before = plane(dr.select(k0 > 0, k0 - 1, 0))
        prev = light(dr.select(k0 > 0, (1.0 - fk) * before + fk * here, here))
        unlit = (kf < 0.5) | outside
        return out, (dr.select(unlit, u0, prev[0]), dr.select(unlit, u1, prev[1]))

    def _gather(self, at, active):
        """The stored pair at texel-plane index ``at``; where no light is scattered forward (I = 0, not
        translucent) only D is read."""
        mi = self.mi
        import drjit as dr
        if isinstance(self.store, mi.UInt64):  # one word a texel: (log D, log(D + I)) (light_slabs.pair_word)
            return word_pair(mi, dr, dr.gather(mi.UInt64, self.store, at, active))
        if self.log_store:
            return dr.gather(mi.Array2f, self.store, at, active)
        return mi.Array2f(dr.gather(mi.Float, self.store, at, active), 0.0)

    def _coordinates(self, p):
        """(k, x0, y0, fx, fy, outside) of world points p: the slice index k (real), the buffer texel
        (x0, y0) below p and the bilinear weights (fx, fy), and whether p's light ray misses the buffer."""
        mi = self.mi
        import drjit as dr
        f, R = self.frame, self.res
        fR = float(R)
        x = (dr.dot(p, f.e1) - f.u0) * f.u_scale
        y = (dr.dot(p, f.e2) - f.v0) * f.v_scale
        kf = (f.d_first - dr.dot(p, f.axis)) * f.inv_spacing
        outside = (x < 0.0) | (x > fR) | (y < 0.0) | (y > fR)
        x = dr.clip(x - 0.5, 0.0, fR - 1.0)
        y = dr.clip(y - 0.5, 0.0, fR - 1.0)
        x0, y0 = dr.minimum(mi.UInt32(x), R - 2), dr.minimum(mi.UInt32(y), R - 2)
        return kf, x0, y0, x - mi.Float(x0), y - mi.Float(y0), outside

    def carried(self, p, source, grid, samples: int = 2, active=True):
        """(direct, indirect) light at world points p carried from the last plane before p on its light
        ray (bilinear in the buffer; before plane 0: the unattenuated light at slab 0's outer face):
            D = D_k exp(-tau),   D + I = (D_k + I_k) exp(-tau_keep)
        with the optical depths tau (extinction) and tau_keep (extinction less forward scattering) of the
        path from the plane to p, from ``samples`` midpoint samples of ``source`` ((extinction, forward
        scattering) in 1/m; ``grid``: its (lo corner, 1 / span) as kernel vectors, zero outside it; periodic:
        and (lo, hi) texture coordinates where it is read, slicing/periodic.py). Unlike
        an interpolation between two planes, this puts a cloud's face that lies between them where it is
        (to the sampling's resolution), and the light decays across the face at the local extinction. The
        plane's value is bilinear in its logarithm (the old interpolation across the buffer: linear in D
        made the small trade cumuli's edges too bright, BOMEX side-lit 6.0 -> 7.2 CIEDE2000).
        Needs the frame's light direction and step (``lookup_frame``); ignores plane offsets (jitter).
        ``active``: lanes that need the light."""
        mi = self.mi
        import drjit as dr
        f, R, N = self.frame, self.res, self.n_slices
        kf, x0, y0, fx, fy, outside = self._coordinates(p)
        first = kf < 0.0                                    # between slab 0's outer face and plane 0
        k0 = dr.minimum(mi.UInt32(dr.clip(kf, 0.0, float(N))), N)
        base = (k0 * R + y0) * R + x0
        def texel(i):  # as (log D, log(D + I))
            v = self._gather(i, active)
            if self.log_store:
                return v
            return mi.Array2f(dr.log(dr.maximum(v[0], 1e-30)), dr.log(dr.maximum(v[0] + v[1], 1e-30)))

        a, b, c, d = (texel(i) for i in (base, base + 1, base + R, base + R + 1))
        v = (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy
        D0, F0 = dr.select(first, 1.0, dr.exp(v[0])), dr.select(first, 1.0, dr.exp(v[1]))
        u = dr.select(first, kf + 0.5, kf - mi.Float(k0))   # slice units from there to p
        ds = u * f.light_step * (1.0 / samples)             # metres per sample
        glo, inv_span = grid[:2]
        tlo, thi = grid[2:] if len(grid) > 2 else (0.0, 1.0)  # periodic: any x and y, the grid's own levels
        tau, tau_keep = mi.Float(0.0), mi.Float(0.0)
        for i in range(samples):
            t = (p + f.to_light * (ds * (i + 0.5)) - glo) * inv_span
            inside = active & dr.all((t >= tlo) & (t <= thi)) if len(grid) > 2 else \
                active & (t.x >= 0.0) & (t.x <= 1.0) & (t.y >= 0.0) & (t.y <= 1.0) & (t.z >= 0.0) & (t.z <= 1.0)
            e, keep = source_extinction(dr, source, t, inside)
            tau += dr.select(inside, e, 0.0) * ds
            tau_keep += dr.select(inside, keep, 0.0) * ds
        D, F = D0 * dr.exp(-tau), F0 * dr.exp(-tau_keep)
        unlit = (kf < -0.5) | outside
        return dr.select(unlit, 1.0, D), dr.select(unlit, 0.0, dr.maximum(F - D, 0.0))

    def _lookup_offset(self, kf, x0, y0, fx, fy, outside, texel, light, with_previous, exit_plane,
                       unlit_value=(1.0, 0.0)):
        """``lookup`` where every texel's planes are offset (``LookupFrame.jitter``): linear between the
        two nearest of each corner texel's planes, then bilinear between the four corners."""
        mi = self.mi
        import drjit as dr
        f, R, N = self.frame, self.res, self.n_slices
        val, prev = 0.0, 0.0
        for dx, dy, w in ((0, 0, (1 - fx) * (1 - fy)), (1, 0, fx * (1 - fy)), (0, 1, (1 - fx) * fy), (1, 1, fx * fy)):
            xt, yt = x0 + dx, y0 + dy
            kt = kf if exit_plane else kf - texel_offsets(dr, mi, xt, yt, f.jitter, f.rotation)
            kc = dr.clip(kt, 0.0, float(N))
            k0 = dr.minimum(mi.UInt32(kc), max(N - 1, 0))
            fk = kc - mi.Float(k0)
            base = (k0 * R + yt) * R + xt
            here, after = texel(base), texel(base + R * R)
            val = val + w * ((1.0 - fk) * here + fk * after)
            if with_previous:
                before = texel(dr.select(k0 > 0, base - R * R, base))
                prev = prev + w * dr.select(k0 > 0, (1.0 - fk) * before + fk * here, here)
        val = light(val)
        u0, u1 = unlit_value
        unlit = (kf < -0.5) | outside
        out = (dr.select(unlit, u0, val[0]), dr.select(unlit, u1, val[1]))
        if not with_previous:
            return out
        prev = light(prev)
        unlit = (kf < 0.5) | outside
        return out, (dr.select(unlit, u0, prev[0]), dr.select(unlit, u1, prev[1]))

    def light_at(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Direct and indirect light (fractions of the light's irradiance) at world points (N, 3)."""
        mi = self.mi
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        direct, indirect = self.lookup(mi.Point3f(*(aligned_float(mi, p[:, i]) for i in range(3))))
        return np.asarray(direct, dtype=np.float64), np.asarray(indirect, dtype=np.float64)
