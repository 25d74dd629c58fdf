"""What the eye pass needs from a view that does not depend on the volume's data: the camera rays
(clipped to the slicing box and the ground) and the background along each of them (sky radiance where
the ray misses the ground), kept for the last few views in a bounded cache."""
from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np

from ..kernel.jitarrays import aligned_float
from ..scene.spec import SceneSpec
from ..kernel.sky import sky_radiance
from ..scene.spec import ground_hits
from .geometry import camera_rays, ray_box
from .jitter import offset_pattern



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
    cos_to_light: np.ndarray  # (N,) numpy, for the phase functions
    n: int
    pattern: object = None    # mi.Float
    ground_sun: object = None  # mi.Float over a terrain: albedo max(n . s, 0) / mu0 at the ground point
    ground_sky: object = None  # mi.Float over a terrain: albedo (1 + n_z) / 2 (a tilted plane's share of the sky)
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

    def get(self, mi, spec: SceneSpec) -> ViewRays:
        ray_key = (spec.camera, spec.width, spec.height, spec.ground)
        if ray_key not in self.rays:
            origins, dirs = camera_rays(spec)
            o, d = origins.reshape(-1, 3), dirs.reshape(-1, 3)
            t0, t1 = ray_box(o, d, self.box)
            terrain = None if spec.ground is None else self.terrain
            surface = None  # over a terrain: albedo and normal where the rays meet it (per view, not per sun)
            if terrain is None:
                tg = ground_hits(spec, o, d)
            else:  # the path tracer's ground: the mesh, its apron and skirt, the surround beyond
                tg, *surface = terrain.scene_hits(o, d, floor_m=self.surround_m)
            self.rays[ray_key] = (o, d, t0, np.minimum(t1, tg), tg, surface, self._spans(mi, o, d, t0, np.minimum(t1, tg)))
        o, d, t0, t1, tg, surface, spans = self.rays[ray_key]
        hit = np.isfinite(tg)
        bg_key = ray_key + (spec.sun.azimuth, spec.sun.elevation, spec.sun.irradiance, spec.sky)
        if bg_key not in self.backgrounds:
            F = lambda a: aligned_float(mi, a)  # noqa: E731
            bg = np.zeros_like(d)
            bg[~hit] = sky_radiance(spec, d[~hit], self.sky)
            pg = o + np.where(hit, tg, 0.0)[:, None] * d
            self.backgrounds[bg_key] = ViewRays(
                mi.Point3f(*(F(o[:, i]) for i in range(3))), mi.Vector3f(*(F(d[:, i]) for i in range(3))),
                F(t0), F(np.where(np.isfinite(t1), t1, t0)), F(hit) > 0.5,
                mi.Point3f(*(F(pg[:, i]) for i in range(3))), mi.Color3f(*(F(bg[:, i]) for i in range(3))),
                d @ spec.sun.to_sun, o.shape[0], F(offset_pattern(spec.width, spec.height)),
                *_terrain_weights(F, spec, surface, hit), *spans)
        return self.backgrounds[bg_key]

    def _spans(self, mi, o, d, t0, t1):
        """(span_a, span_b) of ``ViewRays`` (once per view, not per sun)."""
        F = lambda a: aligned_float(mi, a)  # noqa: E731
        t1 = np.where(np.isfinite(t1), t1, t0)
        if self.occupancy is None:
            return F(t0), F(t1)
        return self.occupancy.spans(mi.Point3f(*(F(o[:, i]) for i in range(3))),
                                    mi.Vector3f(*(F(d[:, i]) for i in range(3))), F(t0), F(t1))


def _terrain_weights(F, spec: SceneSpec, surface, hit: np.ndarray):
    """(ground_sun, ground_sky) of ``ViewRays`` from the terrain's (albedo, normal) where the rays meet it,
    else (None, None): albedo max(n . s, 0) / mu0 and albedo (1 + n_z) / 2."""
    if surface is None:
        return None, None
    albedo, n = surface
    s = spec.sun.to_sun
    mu0 = max(float(s[2]), 1e-3)
    sun = np.where(hit, albedo * np.maximum(n @ s, 0.0) / mu0, 0.0)
    sky = np.where(hit, albedo * (1.0 + n[:, 2]) / 2.0, 0.0)
    return F(sun), F(sky)
