"""What the eye pass needs from a view that does not depend on the volume's data: the camera rays
(clipped to the slicing box and the ground) and the background along each of them (sky radiance where
the ray misses the ground), kept for the last few views in a bounded cache. Over the flat ground they are
computed by kernels (rays.py: float64, numpy's floats), not in numpy: a dragged camera or sun asks for a
new view every frame."""
from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np

from ..kernel.jitarrays import aligned_float
from ..scene.spec import SceneSpec
from ..kernel.sky import sky_radiance_arrays
from . import rays
from .geometry import camera_rays, ray_box
from .jitter import offset_pattern
from .rays import f32



class BoundedCache(OrderedDict):
    """A dict that keeps its ``maxsize`` most recently used entries (least recently used evicted)."""

    def __init__(self, maxsize: int):
        super().__init__()
        self.maxsize = int(maxsize)

    def __getitem__(self, key):
        value = super().__getitem__(key)
        self.move_to_end(key)
        return value

    def get(self, key, default=None):
        return self[key] if key in self else default

    def __setitem__(self, key, value):
        super().__setitem__(key, value)
        self.move_to_end(key)
        while len(self) > self.maxsize:
            self.popitem(last=False)


@dataclass
class ViewRays:
    """Pixel rays of one view as Dr.Jit arrays (N = width x height, row-major from the top left).
    ``t0``/``t1``: where each ray is inside the slicing box (t1 clipped by the ground; t0 > t1:
    misses), ``ground``: where it hits the ground (``hit_ground``), ``background``: sky radiance
    along the ray (zero where it hits the ground, which the eye pass lights), ``pattern``: the
    pixel's slab-offset pattern in [0, 1) (jitter.py), ``phase_colour``: a cache of the renderer's
    per-pixel phase colours (they depend on the view, the sun and the colour only)."""

    origin: object       # mi.Point3f
    direction: object    # mi.Vector3f
    t0: object
    t1: object
    hit_ground: object   # mi.Bool
    ground: object       # mi.Point3f
    background: object   # mi.Color3f
    theta: object        # mi.Float64 (N): the angle between the ray and the direction to the sun (radians)
    n: int
    pattern: object = None    # mi.Float
    ground_sun: object = None  # mi.Float over a terrain (mi.Color3f: per channel): albedo max(n . s, 0) / mu0
    ground_sky: object = None  # mi.Float (Color3f) over a terrain: albedo (1 + n_z) / 2 (a tilted plane's sky)
    span_a: object = None      # mi.Float: where each ray's occupied span begins and ends (occupancy.py; the
    span_b: object = None      # whole [t0, t1] without an occupancy map)
    phase_colour: dict = field(default_factory=lambda: BoundedCache(8))  # per-pixel phase colours by (group, colour)


class ViewCache:
    """Camera rays and background radiance for the most recent views (``maxsize`` of each: an orbiting
    camera or a moving sun does not grow memory), and the sky emitters they were made with."""

    def __init__(self, box, maxsize: int = 4, terrain=None, occupancy=None, surround_m=None):
        self.box = tuple(np.asarray(p, dtype=np.float64) for p in box)
        self.terrain = terrain  # weather_mi.io.terrain.Terrain: the ground is its surface, not the flat plane
        self.surround_m = surround_m  # over a terrain: the height of the ground beyond its apron (m)
        self.occupancy = occupancy  # occupancy.OccupancyMap of the medium: each ray's occupied span
        self.rays = BoundedCache(maxsize)
        self.backgrounds = BoundedCache(maxsize)
        self.sky = BoundedCache(4 * maxsize)  # sky emitters and sky irradiance (kernel/sky.py)
        self.patterns = BoundedCache(maxsize)  # the slab-offset pattern per image size

    def get(self, mi, spec: SceneSpec) -> ViewRays:
        ray_key = (spec.camera, spec.width, spec.height, spec.ground)
        terrain = None if spec.ground is None else self.terrain
        if ray_key not in self.rays:
            self.rays[ray_key] = self._rays(mi, spec) if terrain is None else self._terrain_rays(mi, spec, terrain)
        d, hit, surface, fixed = self.rays[ray_key]
        bg_key = ray_key + (spec.sun.azimuth, spec.sun.elevation, spec.sun.irradiance, spec.sky, spec.atmosphere)
        if bg_key not in self.backgrounds:
            import drjit as dr
            sky = sky_radiance_arrays(spec, fixed["direction"], self.sky, active=~hit)
            dr.eval(sky)  # (a kernel of its own, as Mitsuba's emitter gives it: the same kernel every frame)
            s = rays.Scalars(mi, s=spec.sun.to_sun)  # (new values compile nothing)
            cos = (d[0] * s["s0"] + d[1] * s["s1"]) + d[2] * s["s2"]
            pattern = self.patterns.get((spec.width, spec.height))
            if pattern is None:
                pattern = self.patterns[(spec.width, spec.height)] = aligned_float(
                    mi, offset_pattern(spec.width, spec.height))
            weights = (None, None) if surface is None else \
                _terrain_weights(mi, lambda a: aligned_float(mi, a), spec, surface, np.asarray(hit))
            if "span_a" not in fixed:  # queued after the sky's wait on the rays (compress), not before it
                fixed["span_a"], fixed["span_b"] = (fixed["t0"], fixed["t1"]) if self.occupancy is None else \
                    self.occupancy.spans(fixed["origin"], fixed["direction"], fixed["t0"], fixed["t1"])
            view = ViewRays(**fixed, background=dr.select(hit, mi.Color3f(0.0), sky),
                            theta=dr.acos(dr.clip(cos, -1.0, 1.0)),  # the scattering angle, for the phase functions
                            pattern=pattern, ground_sun=weights[0], ground_sky=weights[1])
            # evaluated here, whatever the caches kept: the same kernels every frame (none compiled anew)
            dr.eval(view.background, view.theta)
            self.backgrounds[bg_key] = view
        return self.backgrounds[bg_key]

    def _rays(self, mi, spec: SceneSpec):
        """``_view_arrays`` of a view over the flat ground (or none), computed by kernels (rays.py; float64
        as numpy's)."""
        import drjit as dr
        o, d = rays.camera_rays(mi, spec)
        t0, t1 = rays.ray_box(mi, o, d, self.box)
        tg = rays.ground_hits(mi, spec, o, d)
        t1 = dr.select(tg < t1, tg, t1)  # (np.minimum: tg is never NaN)
        hit = tg < math.inf
        at = dr.select(hit, tg, 0.0)
        ground = [o[c] + at * d[c] for c in range(3)]
        dr.eval(o, d, t0, t1, hit, ground)  # once: the spans, the sky and the frame's arrays read them
        return self._view_arrays(mi, o, d, t0, t1, hit, ground, None)

    def _terrain_rays(self, mi, spec: SceneSpec, terrain):
        """``_rays`` over a terrain: the path tracer's ground (the mesh, its apron and skirt, the surround
        beyond) in numpy, with its albedo and normal where the rays meet it (per view, not per sun)."""
        origins, dirs = camera_rays(spec)
        o, d = origins.reshape(-1, 3), dirs.reshape(-1, 3)
        t0, t1 = ray_box(o, d, self.box)
        tg, *surface = terrain.scene_hits(o, d, floor_m=self.surround_m, rgb=terrain.albedo_rgb is not None)
        t1 = np.minimum(t1, tg)
        hit = np.isfinite(tg)
        pg = o + np.where(hit, tg, 0.0)[:, None] * d
        F64 = lambda a: mi.Float64(np.ascontiguousarray(a))  # noqa: E731
        cols = lambda a: [F64(a[:, c]) for c in range(3)]  # noqa: E731
        return self._view_arrays(mi, cols(o), cols(d), F64(t0), F64(t1), mi.Bool(hit), cols(pg), surface)

    def _view_arrays(self, mi, o, d, t0, t1, hit, ground, surface):
        """What a view keeps whatever the sun: (d, hit, surface, fixed), ``d`` the directions (3 Float64,
        for the phase functions' angles), ``hit`` the rays that meet the ground (mi.Bool), ``surface`` the
        terrain's (albedo, normal) there or None, ``fixed`` the ``ViewRays`` fields of the view in float32
        (rounded once per view, not per sun); ``get`` adds the occupied spans (``span_a``, ``span_b``)."""
        import drjit as dr
        P = lambda v: [f32(mi, c) for c in v]  # noqa: E731
        t1 = f32(mi, dr.select(dr.isfinite(t1), t1, t0))
        fixed = dict(origin=mi.Point3f(*P(o)), direction=mi.Vector3f(*P(d)), t0=f32(mi, t0), t1=t1,
                     hit_ground=hit, ground=mi.Point3f(*P(ground)), n=dr.width(t0))
        dr.eval(fixed["origin"], fixed["direction"], fixed["t0"], fixed["t1"], fixed["ground"])
        return d, hit, surface, fixed  # (the occupied spans are added by ``get``)


def _terrain_weights(mi, F, spec: SceneSpec, surface, hit: np.ndarray):
    """(ground_sun, ground_sky) of ``ViewRays`` from the terrain's (albedo, normal) where the rays meet it,
    else (None, None): albedo max(n . s, 0) / mu0 and albedo (1 + n_z) / 2; mi.Float, or mi.Color3f where the
    albedo is per channel ((N, 3): ``Terrain.albedo_rgb``, the surface of ``scene.surface``)."""
    if surface is None:
        return None, None
    albedo, n = surface
    s = spec.sun.to_sun
    mu0 = max(float(s[2]), 1e-3)
    sun = np.where(hit, np.maximum(n @ s, 0.0) / mu0, 0.0)
    sky = np.where(hit, (1.0 + n[:, 2]) / 2.0, 0.0)
    if np.ndim(albedo) == 1:
        return F(albedo * sun), F(albedo * sky)
    return tuple(mi.Color3f(*(F(albedo[:, c] * w) for c in range(3))) for w in (sun, sky))
