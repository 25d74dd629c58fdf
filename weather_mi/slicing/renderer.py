"""Half-angle slicing with translucent light transport (Kniss et al. 2003, as adapted by Riley et al.),
in Dr.Jit.

A frame has two passes over the same slices (planes perpendicular to the half-angle axis, visited
from the light's side, see geometry.py):

light pass  one kernel launch per slice over the light buffer (a grid perpendicular to the light):
            the light arriving at slice k is stored in a light volume (slices x buffer), then carried
            through the slice. Direct light D is attenuated by T = exp(-beta dl); in translucent mode
            the scattered light that stays within the forward cone, (1 - T) omega f (f: cone fraction
            of the phase function), joins an indirect part I that is blurred over the cone radius
            dl tan(theta0) at every slice. Each slice is integrated in two half steps, so that the
            light stored at a slice plane is the light at that plane.
eye pass    one kernel: every pixel ray visits the slice planes it crosses, front to back (the light
            volume is complete, so the order is free), and composites in-scattered sunlight
                C += T (1 - exp(-beta de)) sum_s beta_sca,s [P_s(Theta) D + I / (4 pi)] E_sun / beta,
                T *= exp(-beta de)
            (Eq. 9 with the Eq. 8 mixture phase, de = spacing / |s . d|), then adds T x background.
            As in Kniss et al., the direct light is scattered with the phase function and the blurred
            indirect (multiply forward-scattered) light as if it were diffuse (isotropic phase).

Everything that changes between frames (scalings, sun, albedo, cone angle, forward fraction, slice
count) enters kernels as opaque values or data, so frames after the first compile nothing.
"""
from __future__ import annotations

import math
import time

import numpy as np

from ..imageio import Image
from ..optics import OpticalVolume
from ..scene import SceneSpec
from ..jitarrays import aligned_float as _aligned_float
from .background import ground_hits, sky_irradiance_horizontal, sky_radiance
from .geometry import SliceGeometry, camera_rays, slice_geometry
from .modes import SliceMode, SliceParams


def _phase_value(table, cos_theta: np.ndarray) -> np.ndarray:
    """Per-channel phase function (1/sr) of a table at scattering cosines (N,) -> (N, 3)."""
    theta = np.arccos(np.clip(cos_theta, -1.0, 1.0))
    tt = np.asarray(table.theta, dtype=np.float64)
    vals = np.asarray(table.values, dtype=np.float64).reshape(tt.size, -1)
    if vals.shape[1] == 1:
        vals = np.repeat(vals, 3, axis=1)
    return np.stack([np.interp(theta, tt, vals[:, c]) for c in range(3)], axis=1)


def _cone_fraction(table, theta0_rad: float) -> float:
    """Channel-mean fraction of scattered energy within theta0 of forward (2 pi int p sin dtheta)."""
    if hasattr(table, "cone_fraction"):
        return float(np.mean(table.cone_fraction(theta0_rad)))
    theta = np.linspace(0.0, theta0_rad, 4001)
    p = _phase_value(table, np.cos(theta)).mean(axis=1)
    return float(np.trapezoid(2 * np.pi * p * np.sin(theta), theta))


def _ray_box(origins, dirs, bbox, clamp_start: bool = True):
    """Entry and exit parameters (N,) of rays o + t d with the box (t0 > t1 where they miss); with
    ``clamp_start`` the entry is not before t = 0 (the camera)."""
    lo, hi = (np.asarray(p, dtype=np.float64) for p in bbox)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / dirs
        ta, tb = (lo - origins) * inv, (hi - origins) * inv
    tmin = np.nan_to_num(np.minimum(ta, tb), nan=-np.inf)
    tmax = np.nan_to_num(np.maximum(ta, tb), nan=np.inf)
    t0, t1 = tmin.max(axis=-1), tmax.min(axis=-1)
    return (np.maximum(t0, 0.0) if clamp_start else t0), t1


class SliceRenderer:
    """An interactive half-angle slicing renderer bound to one OpticalVolume and image size.

    ``frame(spec, params)`` renders; textures and kernels are reused from frame to frame."""

    def __init__(self, vol: OpticalVolume, mode: SliceMode = SliceMode(), slices: int = 128,
                 light_res: int = 128, detail_field: np.ndarray | None = None, uniform_phase=None,
                 differentiable: bool = False):
        from ..variant import ensure_registered
        ensure_registered()
        import mitsuba as mi
        self.mi = mi
        if slices < 2 or light_res < 4:
            raise ValueError(f"need at least 2 slices and a 4 x 4 light buffer, got {slices}, {light_res}")
        if mode.detail and detail_field is None:
            raise ValueError("SliceMode(detail=True) needs a detail_field: a (z, y, x) multiplier of the "
                             "extinction, e.g. from weather_mi.detail")
        self.vol, self.mode = vol, mode
        self.slices, self.light_res = int(slices), int(light_res)
        self.differentiable = differentiable
        self.n_species = len(vol.species)
        self.shape = tuple(vol.beta_total.shape)
        beta_s = np.moveaxis(vol.beta_ext, 0, -1).astype(np.float32)
        if detail_field is not None and mode.detail:
            detail = np.asarray(detail_field, dtype=np.float32)
            if detail.shape != self.shape:
                raise ValueError(f"detail_field must have the volume's shape {self.shape}, got {detail.shape}")
            beta_s = beta_s * detail[..., None]
        self.beta_s = mi.Float(np.ascontiguousarray(beta_s).ravel())  # (z, y, x, S) flattened
        self.lo = np.asarray(vol.bbox[0], dtype=np.float64)   # the grid's box (texture coordinates)
        self.hi = np.asarray(vol.bbox[1], dtype=np.float64)
        self.occ_lo, self.occ_hi = _occupied_box(beta_s.sum(axis=-1), self.lo, self.hi)  # where slices go
        tables = list(vol.phase_tables)
        if mode.phase == "uniform":
            u = uniform_phase if uniform_phase is not None else tables[0]
            tables = [u] * self.n_species
        self.tables = tables
        sp = vol.species_set
        if sp is not None:
            self.albedo_rgb = np.array([sp[n].albedo_rgb for n in vol.species])          # (S, 3)
            self.colors = np.array([sp[n].color_rgb for n in vol.species])
        else:
            mean_alb = vol.albedo.reshape(-1, 3)[vol.beta_total.ravel() > 0].mean(axis=0) \
                if np.any(vol.beta_total > 0) else np.ones(3)
            self.albedo_rgb = np.broadcast_to(mean_alb, (self.n_species, 3)).copy()
            self.colors = np.ones((self.n_species, 3))
        # species that scatter alike into the eye (same phase table and colour) share one channel
        keys = []
        for si in range(self.n_species):
            colour = self.colors[si] if mode.species_colors else np.round(
                self.albedo_rgb[si] / max(self.albedo_rgb[si].mean(), 1e-12), 3)
            keys.append((_table_key(self.tables[si]), tuple(np.round(colour, 3))))
        self.groups = [[si for si in range(self.n_species) if keys[si] == k] for k in dict.fromkeys(keys)]
        self.tex_eye = mi.Texture3f(mi.TensorXf(np.zeros(self.shape + (1 + len(self.groups),), np.float32)),
                                    use_accel=False)
        self.tex_light_src = mi.Texture3f(mi.TensorXf(np.zeros(self.shape + (2,), np.float32)), use_accel=False)
        self.tex_light = mi.Texture3f(mi.TensorXf(np.zeros((self.slices + 1, light_res, light_res, 2), np.float32)),
                                      use_accel=False)  # channels: direct D, indirect I
        self.timing = {}
        self._sky_cache: dict = {}

    # ------------------------------------------------------------------ per-frame volume data
    def _species_vectors(self, params: SliceParams):
        """Per-species scaling, mean albedo, RGB tint ratio and forward fraction (numpy)."""
        names = self.vol.species
        scale = np.array([float(params.scale.get(n, 1.0)) for n in names])
        for n in params.scale:
            if n not in names:
                raise ValueError(f"unknown species {n!r} in scale; expected one of {names}")
        albedo = self.albedo_rgb if params.albedo is None else np.full((self.n_species, 3), params.albedo)
        omega = albedo.mean(axis=1)
        tint = albedo / np.maximum(omega[:, None], 1e-12)
        cone = params.cone_angle_deg
        theta0 = math.radians(float(cone[0]) if __import__("drjit").is_array_v(cone) else float(cone))
        if self.mode.light == "low_albedo":
            fwd = np.zeros(self.n_species)
        elif params.forward_fraction is not None:
            fwd = [params.forward_fraction] * self.n_species  # may be a Dr.Jit Float with gradients
        else:
            fwd = np.array([_cone_fraction(t, theta0) for t in self.tables])
        return scale, omega, tint, fwd

    def _build_textures(self, scale, omega, fwd):
        """Eye texture [beta_ext, beta_sca,1..S] and light texture [beta_ext, beta_forward] (1/m)."""
        mi, dr = self.mi, __import__("drjit")
        S = self.n_species
        n_vox = int(np.prod(self.shape))
        sc = [_param(mi, v) for v in scale]
        om = [_param(mi, v) for v in omega]
        fw = [_param(mi, v) for v in fwd]
        self._grad_inputs = {"scale": sc, "omega": om, "forward": fw}
        vox = dr.arange(mi.UInt32, n_vox)
        ext = mi.Float(0.0)
        sca = []
        beta_fwd = mi.Float(0.0)
        for s in range(S):
            b = dr.gather(mi.Float, self.beta_s, vox * S + s) * sc[s]
            ext += b
            sca.append(b * om[s])
            beta_fwd += b * om[s] * fw[s]
        grouped = []
        for members in self.groups:
            g_sca = sca[members[0]]
            for si in members[1:]:
                g_sca = g_sca + sca[si]
            grouped.append(g_sca)
        eye = mi.TensorXf(_interleave(mi, [ext] + grouped), shape=self.shape + (1 + len(self.groups),))
        light = mi.TensorXf(_interleave(mi, [ext, beta_fwd]), shape=self.shape + (2,))
        self.tex_eye.set_tensor(eye)
        self.tex_light_src.set_tensor(light)

    # ------------------------------------------------------------------ light pass
    def _light_pass(self, g: SliceGeometry, params: SliceParams):
        mi, dr = self.mi, __import__("drjit")
        R = self.light_res
        N = g.n_slices
        s, l = g.axis, g.to_light
        su = (np.arange(R) + 0.5) / R
        uu, vv = np.meshgrid(g.u_range[0] + su * (g.u_range[1] - g.u_range[0]),
                             g.v_range[0] + su * (g.v_range[1] - g.v_range[0]))
        base = uu.ravel()[:, None] * g.e1 + vv.ravel()[:, None] * g.e2          # points on the buffer plane
        s_dot_l = float(s @ l)
        p0 = base + ((g.d_first - base @ s) / s_dot_l)[:, None] * l             # on slice 0
        step = -g.spacing / s_dot_l * l                                         # to the next slice
        span = self.hi - self.lo
        q0 = (p0 - self.lo) / span
        qs = step / span
        # where each light ray is inside the box, in slice units: k in [k_in, k_out]
        k_in, k_out = _ray_box(p0, np.broadcast_to(step, p0.shape), (self.occ_lo, self.occ_hi), clamp_start=False)
        q0x, q0y, q0z = (_aligned_float(mi, q0[:, i]) for i in range(3))
        qsx, qsy, qsz = (dr.opaque(mi.Float, float(qs[i])) for i in range(3))
        kin, kout = _aligned_float(mi, k_in), _aligned_float(mi, k_out)
        dl = dr.opaque(mi.Float, g.light_step_m)
        du = (g.u_range[1] - g.u_range[0]) / R
        dv = (g.v_range[1] - g.v_range[0]) / R
        radius = _param(mi, g.light_step_m) * dr.tan(_param(mi, params.cone_angle_deg) * (math.pi / 180.0))
        rx, ry = radius * _param(mi, 1.0 / du), radius * _param(mi, 1.0 / dv)
        translucent = self.mode.light == "translucent"

        store = dr.zeros(mi.Float, (N + 1) * R * R * 2)
        lane = dr.arange(mi.UInt32, R * R)
        plane = dr.opaque(mi.UInt32, R * R)

        def through_slab(k, D, I):
            """Carry the light through slab k in two halves, [k - 1/2, k] and [k, k + 1/2] clipped to
            the box (slice units); store the light at plane k."""
            kf = mi.Float(k)
            a = dr.clip(kf - 0.5, kin, kout)
            m = dr.clip(kf, kin, kout)
            b = dr.clip(kf + 0.5, kin, kout)
            km = 0.5 * (a + b)  # sample at the middle of the clipped slab
            ext, bfwd = self.tex_light_src.eval(mi.Point3f(q0x + km * qsx, q0y + km * qsy, q0z + km * qsz))
            ext = dr.maximum(ext, 0.0)
            ratio = dr.select(ext > 0, bfwd / dr.maximum(ext, 1e-30), 0.0)   # omega f
            t1 = dr.exp(-ext * dl * (m - a))                                  # first half transmittance
            t2 = dr.exp(-ext * dl * (b - m))
            D_mid = D * t1
            I_mid = I * t1 + (D + I) * (1.0 - t1) * ratio
            at = (lane + k * plane) * 2
            dr.scatter(store, D_mid, at)
            dr.scatter(store, I_mid, at + 1)
            return D_mid * t2, I_mid * t2 + (D_mid + I_mid) * (1.0 - t2) * ratio

        D = dr.full(mi.Float, 1.0, R * R)
        I = dr.zeros(mi.Float, R * R)
        if translucent or self.differentiable:
            # the blur reads neighbouring texels of the previous slice: one launch per slice
            for k in range(N):
                D, I = through_slab(dr.opaque(mi.UInt32, k), D, I)
                if translucent:
                    dr.eval(D, I, store)
                    I = _blur(mi, dr, I, R, rx, ry)
                dr.eval(D, I, store)  # also when differentiable: AD keeps its graph across evaluations
                if self.differentiable:
                    # identity gathers: their adjoints are scatters, so the reverse pass stores the
                    # adjoints of D and I at every slice instead of rebuilding the whole chain of later
                    # slices in each kernel (O(N^2) operations, minutes of LLVM time at 96 slices)
                    D = dr.gather(mi.Float, D, lane)
                    if not translucent:
                        I = dr.gather(mi.Float, I, lane)
        else:
            # no blur: every light ray is independent, so all slices run in one kernel
            n_slices = dr.opaque(mi.UInt32, N)

            def body(k, D, I):
                D, I = through_slab(k, D, I)
                return k + 1, D, I

            _, D, I = dr.while_loop((dr.zeros(mi.UInt32, R * R), D, I), lambda k, D, I: k < n_slices, body)
            dr.eval(D, I)  # one kernel for the loop and its stores
        at = (lane + dr.opaque(mi.UInt32, N * R * R)) * 2
        dr.scatter(store, D, at)
        dr.scatter(store, I, at + 1)
        dr.eval(store)
        self.tex_light.set_tensor(mi.TensorXf(store, shape=(N + 1, R, R, 2)))
        self._light_store = store
        self._light_frame = (g, du, dv)

    # ------------------------------------------------------------------ eye pass
    def _eye_pass(self, g: SliceGeometry, spec: SceneSpec, params: SliceParams, scale, omega, tint):
        mi, dr = self.mi, __import__("drjit")
        S = self.n_species
        H, W = spec.height, spec.width
        ray_key = ("rays", spec.camera, spec.width, spec.height)
        if ray_key not in self._sky_cache:
            origins, dirs = camera_rays(spec)
            o, d = origins.reshape(-1, 3), dirs.reshape(-1, 3)
            self._sky_cache[ray_key] = (o, d, _ray_box(o, d, (self.occ_lo, self.occ_hi)))
        o, d, (t0, t1) = self._sky_cache[ray_key]
        s = g.axis
        # scattering angle of sunlight into each pixel ray: cos Theta = l . d
        cos_t = d @ g.to_light
        sun = np.asarray(spec.sun.irradiance)
        K, tints = [], []  # per species group and channel: P(Theta) x tint x E_sun (per unit beta_sca)
        for members in self.groups:
            p = _phase_value(self.tables[members[0]], cos_t)
            colour = self.colors[members[0]] if self.mode.species_colors else np.mean(tint[members], axis=0)
            K.append(p * colour[None] * sun[None])
            tints.append(colour)
        G = len(self.groups)
        # ray extent in the volume, clipped by the ground
        tg = ground_hits(spec, o, d)
        t1 = np.minimum(t1, tg)
        sd = d @ s
        sd = np.where(np.abs(sd) < 1e-9, -1e-9, sd)                     # rays within a slice plane
        k_of = lambda t: (g.d_first - (o @ s + t * sd)) / g.spacing  # noqa: E731
        t1c = np.where(np.isfinite(t1), t1, t0)
        ka, kb = k_of(t0), k_of(t1c)                                     # the ray's span in slice units
        inc = sd < 0                                                     # k grows along the ray
        k_step = np.where(inc, 1.0, -1.0)
        k_start = np.round(ka)                                           # slab holding the entry point
        count = np.where(t1 > t0, np.abs(np.round(kb) - k_start) + 1, 0).astype(np.uint32)
        k_lo, k_hi = np.minimum(ka, kb), np.maximum(ka, kb)

        # background: sky along the ray, or the lit ground
        hit_ground = np.isfinite(tg)
        bg_key = ("background", spec.camera, spec.sun, spec.sky, spec.ground, spec.width, spec.height)
        if bg_key not in self._sky_cache:  # the sky seen by each pixel: only when view or sun change
            self._sky_cache = {k: v for k, v in self._sky_cache.items() if not (isinstance(k, tuple) and k
                                                                              and k[0] == "background")}
            bg = np.zeros_like(d)
            bg[~hit_ground] = sky_radiance(spec, d[~hit_ground], self._sky_cache)
            self._sky_cache[bg_key] = bg
        bg = self._sky_cache[bg_key]
        pg = o + np.where(hit_ground, tg, 0.0)[:, None] * d

        F = lambda a: _aligned_float(mi, a)  # noqa: E731
        ox, oy, oz = F(o[:, 0]), F(o[:, 1]), F(o[:, 2])
        dx_, dy_, dz_ = F(d[:, 0]), F(d[:, 1]), F(d[:, 2])
        span = self.hi - self.lo
        lo = [dr.opaque(mi.Float, float(v)) for v in self.lo]
        inv_span = [dr.opaque(mi.Float, float(1.0 / v)) for v in span]
        sx, sy, sz = (dr.opaque(mi.Float, float(v)) for v in s)
        d_first = dr.opaque(mi.Float, g.d_first)
        spacing = dr.opaque(mi.Float, g.spacing)
        e1 = [dr.opaque(mi.Float, float(v)) for v in g.e1]
        e2 = [dr.opaque(mi.Float, float(v)) for v in g.e2]
        u0, v0 = dr.opaque(mi.Float, g.u_range[0]), dr.opaque(mi.Float, g.v_range[0])
        inv_du = dr.opaque(mi.Float, 1.0 / (g.u_range[1] - g.u_range[0]))
        inv_dv = dr.opaque(mi.Float, 1.0 / (g.v_range[1] - g.v_range[0]))
        n_planes = dr.opaque(mi.Float, float(g.n_slices + 1))
        Kd = [[F(K[gi][:, c]) for c in range(3)] for gi in range(G)]
        Ki = [[dr.opaque(mi.Float, float(tints[gi][c] * sun[c] / (4 * np.pi))) for c in range(3)] for gi in range(G)]
        e_amb = sky_irradiance_horizontal(spec, cache=self._sky_cache) / np.pi if spec.sky is not None else np.zeros(3)
        amb = [_param(mi, params.ambient) * _param(mi, a) for a in e_amb]
        sdotd = F(sd)
        de = spacing / dr.abs(sdotd)

        def light_at(px, py, pz, kf):
            u = (px * e1[0] + py * e1[1] + pz * e1[2] - u0) * inv_du
            v = (px * e2[0] + py * e2[1] + pz * e2[2] - v0) * inv_dv
            direct, indirect = self.tex_light.eval(mi.Point3f(u, v, (kf + 0.5) / n_planes))
            before = kf < 0  # between the light and the first slice: unattenuated sunlight
            return dr.select(before, 1.0, direct), dr.select(before, 0.0, indirect)

        R = self.light_res
        store = self._light_store
        fR = float(R)

        def light_on_plane(px, py, pz, kf):
            """Bilinear lookup in the light buffer of the nearest slice plane (eye samples lie on the
            planes except for clipped end segments): 4 packed gathers instead of a trilinear fetch."""
            x = dr.clip((px * e1[0] + py * e1[1] + pz * e1[2] - u0) * inv_du * fR - 0.5, 0.0, fR - 1.0)
            y = dr.clip((px * e2[0] + py * e2[1] + pz * e2[2] - v0) * inv_dv * fR - 0.5, 0.0, fR - 1.0)
            x0 = dr.minimum(mi.UInt32(x), R - 2)
            y0 = dr.minimum(mi.UInt32(y), R - 2)
            fx, fy = x - mi.Float(x0), y - mi.Float(y0)
            k = mi.UInt32(dr.clip(dr.round(kf), 0.0, n_planes - 1.0))
            base = (k * R + y0) * R + x0
            a = dr.gather(mi.Array2f, store, base)
            b = dr.gather(mi.Array2f, store, base + 1)
            c = dr.gather(mi.Array2f, store, base + R)
            d = dr.gather(mi.Array2f, store, base + R + 1)
            val = (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy
            before = kf < -0.5
            return dr.select(before, 1.0, val[0]), dr.select(before, 0.0, val[1])

        def body(i, T, C0, C1, C2, active):
            kc = F_start + F_step * mi.Float(i)
            # slab [k - 1/2, k + 1/2] clipped to the ray's span in the box; sample at its middle
            a = dr.clip(kc - 0.5, K_lo, K_hi)
            b = dr.clip(kc + 0.5, K_lo, K_hi)
            kf = 0.5 * (a + b)
            seg = b - a
            t = (d_first - kf * spacing - (ox * sx + oy * sy + oz * sz)) / sdotd
            px, py, pz = ox + t * dx_, oy + t * dy_, oz + t * dz_
            q = mi.Point3f((px - lo[0]) * inv_span[0], (py - lo[1]) * inv_span[1], (pz - lo[2]) * inv_span[2])
            vals = self.tex_eye.eval(q)
            ext = dr.maximum(vals[0], 0.0)
            direct, indirect = light_on_plane(px, py, pz, kf)
            alpha = 1.0 - dr.exp(-ext * de * seg)
            w = dr.select(ext > 0, T * alpha / dr.maximum(ext, 1e-30), 0.0)
            src = [mi.Float(0.0), mi.Float(0.0), mi.Float(0.0)]     # sum_s beta_sca,s P_s tint E
            diffuse = [mi.Float(0.0), mi.Float(0.0), mi.Float(0.0)]  # sum_s beta_sca,s tint E / (4 pi)
            sca_total = mi.Float(0.0)
            for gi in range(G):
                b = dr.maximum(vals[1 + gi], 0.0)
                sca_total += b
                for c in range(3):
                    src[c] += b * Kd[gi][c]
                    diffuse[c] += b * Ki[gi][c]
            C0 = C0 + w * (src[0] * direct + diffuse[0] * indirect + sca_total * amb[0])
            C1 = C1 + w * (src[1] * direct + diffuse[1] * indirect + sca_total * amb[1])
            C2 = C2 + w * (src[2] * direct + diffuse[2] * indirect + sca_total * amb[2])
            T = T * (1.0 - alpha)
            i = i + 1
            active = (i < n_count) & (T > 1e-4)
            return i, T, C0, C1, C2, active

        F_start, F_step = F(k_start), F(k_step)
        K_lo, K_hi = F(k_lo), F(k_hi)
        n_count = mi.UInt32(_aligned_float(mi, count))
        n = o.shape[0]
        state = (dr.zeros(mi.UInt32, n), dr.full(mi.Float, 1.0, n), dr.zeros(mi.Float, n),
                 dr.zeros(mi.Float, n), dr.zeros(mi.Float, n), n_count > 0)
        kw = dict(max_iterations=g.n_slices + 1, mode="evaluated") if self.differentiable else {}
        i, T, C0, C1, C2, _ = dr.while_loop(state, lambda *st: st[-1], body, **kw)

        # ground radiance: Lambertian, sun attenuated by the light volume, plus skylight
        gx, gy, gz = F(pg[:, 0]), F(pg[:, 1]), F(pg[:, 2])
        kg = (d_first - (gx * sx + gy * sy + gz * sz)) / spacing
        sun_d, sun_i = light_at(gx, gy, gz, dr.minimum(kg, float(g.n_slices)))
        sun_t = sun_d + sun_i
        if spec.ground is not None:
            e_sky = sky_irradiance_horizontal(spec, cache=self._sky_cache)
            rho = np.asarray(spec.ground.albedo)
            mu0 = max(float(spec.sun.to_sun[2]), 0.0)
            ground = [dr.opaque(mi.Float, float(rho[c] / np.pi * sun[c] * mu0)) * sun_t
                      + dr.opaque(mi.Float, float(rho[c] / np.pi * e_sky[c])) for c in range(3)]
            hit = F(hit_ground) > 0.5
            bgc = [dr.select(hit, ground[c], F(bg[:, c])) for c in range(3)]
        else:
            bgc = [F(bg[:, c]) for c in range(3)]
        out = [C0 + T * bgc[0], C1 + T * bgc[1], C2 + T * bgc[2]]
        return out, T

    # ------------------------------------------------------------------ public
    def light_at(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Direct and indirect sunlight (fractions of the sun's irradiance) at world points (N, 3),
        read from the last frame's light volume (points between the sun and the first slice: 1, 0)."""
        mi, dr = self.mi, __import__("drjit")
        g, _, _ = self._light_frame
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        k = np.minimum(g.slice_of(p @ g.axis), g.n_slices)
        u = (p @ g.e1 - g.u_range[0]) / (g.u_range[1] - g.u_range[0])
        v = (p @ g.e2 - g.v_range[0]) / (g.v_range[1] - g.v_range[0])
        F = lambda a: _aligned_float(mi, a)  # noqa: E731
        direct, indirect = self.tex_light.eval(mi.Point3f(F(u), F(v), F((k + 0.5) / (g.n_slices + 1))))
        before = k < 0
        return (np.where(before, 1.0, np.asarray(direct, dtype=np.float64)),
                np.where(before, 0.0, np.asarray(indirect, dtype=np.float64)))

    def frame(self, spec: SceneSpec, params: SliceParams = SliceParams(), return_arrays: bool = False):
        """Render one frame. Returns an Image (or the Dr.Jit channel arrays when ``return_arrays``,
        for differentiation)."""
        dr = __import__("drjit")
        t_start = time.perf_counter()
        scale, omega, tint, fwd = self._species_vectors(params)
        self._build_textures(scale, omega, fwd)
        g = slice_geometry(spec.camera.forward, spec.sun.to_sun, (self.occ_lo, self.occ_hi), self.slices)
        self._light_pass(g, params)
        if not self.differentiable:
            dr.eval(self.tex_light.tensor())
        dr.sync_thread()  # kernels run asynchronously: wait before reading the clock
        t_light = time.perf_counter()
        out, transmittance = self._eye_pass(g, spec, params, scale, omega, tint)
        if return_arrays:
            return out, transmittance
        dr.eval(out, transmittance)
        dr.sync_thread()
        t_eye = time.perf_counter()
        H, W = spec.height, spec.width
        rgb = np.stack([np.asarray(c, dtype=np.float32) for c in out], axis=-1).reshape(H, W, 3)
        self.transmittance = np.asarray(transmittance, dtype=np.float32).reshape(H, W)
        self.timing = {"light_s": t_light - t_start, "eye_s": t_eye - t_light, "total_s": t_eye - t_start}
        meta = {"renderer": "slicing", "mode": self.mode.__dict__, "slices": self.slices,
                "light_res": self.light_res, "params": {k: (v if not __import__("drjit").is_array_v(v) else "drjit") for k, v in params.__dict__.items()}, "seconds": t_eye - t_start,
                "back_to_front": g.back_to_front, "scene": spec.to_dict(),
                "species_preset": self.vol.attrs.get("species_preset"), "source": self.vol.attrs.get("source"),
                "forward_fraction_per_species": [float(v) if not __import__("drjit").is_array_v(v) else None for v in fwd]}
        return Image(rgb, np.zeros_like(rgb), meta)


def _table_key(table) -> str:
    """Content hash of a phase table (equal tables scatter alike, whichever object holds them)."""
    import hashlib
    h = hashlib.sha1(np.ascontiguousarray(table.theta, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(table.values, dtype=np.float64).tobytes())
    return h.hexdigest()


def _param(mi, value):
    """A per-frame scalar for a kernel: Dr.Jit arrays pass through (they may carry gradients),
    Python numbers become opaque values (so a new value does not recompile)."""
    import drjit as dr
    if dr.is_array_v(value):
        return value
    return dr.opaque(mi.Float, float(value))


def _occupied_box(beta_total: np.ndarray, lo: np.ndarray, hi: np.ndarray):
    """World box around the voxels with extinction, widened by the reach of trilinear interpolation
    (half a voxel beyond the neighbouring centres) and clipped to the grid's box."""
    nz, ny, nx = beta_total.shape
    cell = (hi - lo) / np.array([nx, ny, nz])
    occ = beta_total > 0
    if not occ.any():
        return lo.copy(), lo + cell  # an empty volume: one cell, nothing in it
    idx = []
    for axis in (2, 1, 0):  # x, y, z
        other = tuple(a for a in range(3) if a != axis)
        nz_idx = np.nonzero(occ.any(axis=other))[0]
        idx.append((nz_idx[0], nz_idx[-1]))
    i0 = np.array([a for a, _ in idx], dtype=np.float64)
    i1 = np.array([b for _, b in idx], dtype=np.float64)
    return np.maximum(lo + (i0 - 1.0) * cell, lo), np.minimum(lo + (i1 + 2.0) * cell, hi)


def _interleave(mi, channels):
    """Flat array with the channels interleaved (voxel-major), as a (..., C) tensor's storage."""
    import drjit as dr
    C = len(channels)
    n = dr.width(channels[0])
    idx = dr.arange(mi.UInt32, n * C)
    vox = idx // C
    ch = idx - vox * C
    out = dr.gather(mi.Float, channels[0], vox)
    for c in range(1, C):
        out = dr.select(ch == c, dr.gather(mi.Float, channels[c], vox), out)
    return out


def _bilinear(mi, dr, buf, R, x, y):
    """Bilinear lookup in an R x R buffer at continuous texel coordinates (clamped to the edges)."""
    x = dr.clip(x - 0.5, 0.0, R - 1.0)
    y = dr.clip(y - 0.5, 0.0, R - 1.0)
    x0 = dr.minimum(mi.UInt32(x), R - 2) if R > 1 else mi.UInt32(0)
    y0 = dr.minimum(mi.UInt32(y), R - 2) if R > 1 else mi.UInt32(0)
    fx, fy = x - mi.Float(x0), y - mi.Float(y0)
    i00 = y0 * R + x0
    a = dr.gather(mi.Float, buf, i00)
    b = dr.gather(mi.Float, buf, i00 + 1)
    c = dr.gather(mi.Float, buf, i00 + R)
    d = dr.gather(mi.Float, buf, i00 + R + 1)
    return (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy


def _blur(mi, dr, buf, R, rx, ry):
    """Spread a light buffer over a disc of radius (rx, ry) texels: centre + 6 taps on a ring at 2/3
    of the radius (bilinear taps, weights summing to one: energy is kept)."""
    lane = dr.arange(mi.UInt32, R * R)
    yi = lane // R
    xi = lane - yi * R
    x = mi.Float(xi) + 0.5
    y = mi.Float(yi) + 0.5
    out = 0.25 * _bilinear(mi, dr, buf, R, x, y)
    for j in range(6):
        a = 2 * math.pi * j / 6
        out += 0.125 * _bilinear(mi, dr, buf, R, x + (2 / 3) * math.cos(a) * rx, y + (2 / 3) * math.sin(a) * ry)
    return out
