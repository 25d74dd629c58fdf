"""Geometry of half-angle slicing (Kniss et al. 2003): camera rays, slice axis and planes, light frame.

With v the camera's forward direction and l the unit vector towards the light:
  v . l > 0 (looking towards the light, back-lit): slice axis s = normalize(v + l), eye composited back to front;
  otherwise (front-lit):                          s = normalize(l - v), eye composited front to back.
In both cases s . l > 0, so slices are visited from the light's side (decreasing s . x) and the
light buffer advances away from the light. Path length across one slice: spacing / |s . d| along a
ray of direction d (the same for eye and light rays when d is v or l: spacing / cos(half angle)).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..scene.spec import Camera, SceneSpec


def camera_rays(spec: SceneSpec) -> tuple[np.ndarray, np.ndarray]:
    """Pixel-centre rays (origins, unit directions), each (H, W, 3), row 0 at the top of the picture,
    matching Mitsuba's ``perspective`` (horizontal fov) and ``orthographic`` sensors."""
    w, h = int(spec.width), int(spec.height)
    px, py = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
    return film_rays(spec, px, py)


def film_rays(spec: SceneSpec, px, py) -> tuple[np.ndarray, np.ndarray]:
    """Rays (origins, unit directions; shape of ``px`` + (3,)) through pixel coordinates (px, py) of the
    picture: x to the right, y down, origin at the top-left corner (pixel centres at half-integers)."""
    cam: Camera = spec.camera
    w, h = int(spec.width), int(spec.height)
    fwd, left, up = camera_basis(cam)
    gx = 1.0 - 2.0 * np.asarray(px, float) / w           # +1 at the left edge (Mitsuba's camera x axis: left)
    gy = 1.0 - 2.0 * np.asarray(py, float) / h           # +1 at the top edge
    if cam.kind == "orthographic":
        origins = (np.asarray(cam.origin, float) + gx[..., None] * (cam.ortho_width / 2) * left
                   + gy[..., None] * (cam.ortho_height / 2) * up)
        return origins, np.broadcast_to(fwd, origins.shape).copy()
    tan_x = math.tan(math.radians(cam.fov) / 2)
    tan_y = tan_x * h / w
    dirs = fwd + gx[..., None] * tan_x * left + gy[..., None] * tan_y * up
    dirs /= np.linalg.norm(dirs, axis=-1, keepdims=True)
    return np.broadcast_to(np.asarray(cam.origin, float), dirs.shape).copy(), dirs


def camera_basis(cam: Camera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(forward, left, up) unit vectors of the camera (Mitsuba's camera frame: x to the left)."""
    fwd = cam.forward
    left = np.cross(np.asarray(cam.up, float), fwd)
    left /= np.linalg.norm(left)
    return fwd, left, np.cross(fwd, left)


def orthonormal_frame(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing n to a right-handed orthonormal frame (e1, e2, n)."""
    a = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(a, n)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(n, e1)


def bbox_corners(bbox) -> np.ndarray:
    (x0, y0, z0), (x1, y1, z1) = bbox
    return np.array([[x, y, z] for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)], dtype=np.float64)


@dataclass(frozen=True)
class SliceGeometry:
    """Slice planes s . x = d_k, k = 0..n-1, from the light's side, and the light-buffer frame."""

    axis: np.ndarray          # s, unit
    to_light: np.ndarray      # l, unit
    back_to_front: bool       # eye compositing order (informational: compositing is order-free here)
    d_first: float            # d_0 (the slice nearest the light), metres along s
    spacing: float            # metres between slices along s
    n_slices: int
    e1: np.ndarray            # light-buffer axes (perpendicular to l)
    e2: np.ndarray
    u_range: tuple[float, float]
    v_range: tuple[float, float]

    @property
    def light_step_m(self) -> float:
        """Path length of a light ray across one slice: spacing / (s . l)."""
        return self.spacing / float(np.dot(self.axis, self.to_light))

    def slice_of(self, d: np.ndarray) -> np.ndarray:
        """Continuous slice index of points with s . x = d (0 at the first slice)."""
        return (self.d_first - d) / self.spacing


def slice_geometry(view_dir: np.ndarray, to_light: np.ndarray, bbox, n_slices: int) -> SliceGeometry:
    v = np.asarray(view_dir, float) / np.linalg.norm(view_dir)
    l = np.asarray(to_light, float) / np.linalg.norm(to_light)
    back_to_front = float(np.dot(v, l)) > 0.0
    s = v + l if back_to_front else l - v
    if np.linalg.norm(s) < 1e-6:  # looking exactly away from the light: slice along the light
        s = l.copy()
    s /= np.linalg.norm(s)
    corners = bbox_corners(bbox)
    d = corners @ s
    spacing = (d.max() - d.min()) / n_slices
    e1, e2 = orthonormal_frame(l)
    u, w = corners @ e1, corners @ e2
    return SliceGeometry(s, l, back_to_front, float(d.max() - spacing / 2), float(spacing), int(n_slices),
                         e1, e2, (float(u.min()), float(u.max())), (float(w.min()), float(w.max())))


def ray_box(origins, dirs, bbox, clamp_start: bool = True):
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


def slicing_box(vol) -> tuple[np.ndarray, np.ndarray]:
    """Where the slices go: the volume's occupied box (``OpticalVolume.occupied_bbox``) widened by
    one cell on each side (the reach of trilinear interpolation), clipped to the grid's box."""
    lo, hi = (np.asarray(p, dtype=np.float64) for p in vol.bbox)
    if not np.any(vol.beta_total > 0):
        cell = np.asarray(vol.spacing[::-1], dtype=np.float64)
        return lo.copy(), lo + cell  # an empty volume: one cell, nothing in it
    olo, ohi = (np.asarray(p, dtype=np.float64) for p in vol.occupied_bbox())
    cell = np.asarray(vol.spacing[::-1], dtype=np.float64)  # (dx, dy, dz)
    return np.maximum(olo - cell, lo), np.minimum(ohi + cell, hi)
