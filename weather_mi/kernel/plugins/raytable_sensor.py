"""Mitsuba 3 sensor ``raytable``: every pixel's rays from a table, for views no pinhole or orthographic
camera makes (a geostationary imager: each pixel seen from the satellite's real position, so the view
zenith and azimuth vary across the image and parallax is real).

The table holds a ray at every pixel corner: ``origins`` and ``directions``, tensors of shape
(H + 1, W + 1, 3) in the scene's frame (m; row 0 is the film's top edge, column 0 its left edge). A
sample at film position (u, v) in [0, 1]^2 gets the bilinear interpolation of the four corners of its
pixel (origin, and direction normalised), so a pixel with a box filter is the mean radiance over its
footprint, as a real detector integrates it. Ray weight 1 (radiance).

A geostationary satellite is 35,786 km away: its rays start where they enter the scene (the top of the
medium's box, say), with the direction from the satellite there; float32 origins thousands of km away
would lose the metres the cloud needs.
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

PLUGIN_NAME = "raytable"


def _corner_texture(values) -> "mi.Texture2f":
    t = mi.TensorXf(np.ascontiguousarray(np.asarray(values, np.float32)))
    return mi.Texture2f(t, use_accel=False, filter_mode=dr.FilterMode.Linear, wrap_mode=dr.WrapMode.Clamp)


class RayTableSensor(mi.Sensor):
    """Rays from a table of pixel-corner origins and directions (module docstring)."""

    def __init__(self, props):
        super().__init__(props)
        origins, directions = props["origins"], props["directions"]
        size = self.film().size()
        shape = (int(size[1]) + 1, int(size[0]) + 1, 3)
        for name, t in (("origins", origins), ("directions", directions)):
            if tuple(t.shape) != shape:
                raise ValueError(f"{PLUGIN_NAME}: {name} must have shape (H + 1, W + 1, 3) = {shape} for a "
                                 f"{size[0]} x {size[1]} film, got {tuple(t.shape)}")
        self.origins = _corner_texture(np.array(origins))
        self.directions = _corner_texture(np.array(directions))
        w, h = int(size[0]), int(size[1])
        # film position u in [0, 1] -> texel coordinate of corner u * W: (u W + 1/2) / (W + 1)
        self.scale = mi.ScalarPoint2f(w / (w + 1.0), h / (h + 1.0))
        self.offset = mi.ScalarPoint2f(0.5 / (w + 1.0), 0.5 / (h + 1.0))

    def sample_ray(self, time, wavelength_sample, position_sample, aperture_sample, active=True):
        uv = mi.Point2f(position_sample) * self.scale + self.offset
        o = self.origins.eval(uv)
        d = self.directions.eval(uv)
        ray = mi.Ray3f(mi.Point3f(o[0], o[1], o[2]), dr.normalize(mi.Vector3f(d[0], d[1], d[2])), time, [])
        return ray, mi.Color3f(1.0)

    def sample_ray_differential(self, time, wavelength_sample, position_sample, aperture_sample, active=True):
        ray, weight = self.sample_ray(time, wavelength_sample, position_sample, aperture_sample, active)
        return mi.RayDifferential3f(ray), weight

    def bbox(self):
        return mi.ScalarBoundingBox3f()

    def traverse(self, callback):
        super().traverse(callback)

    def to_string(self):
        size = self.film().size()
        return f"RayTableSensor[{size[0]} x {size[1]} pixels]"


def register() -> None:
    """Register ``raytable`` with the current Mitsuba variant."""
    mi.register_sensor(PLUGIN_NAME, lambda props: RayTableSensor(props))


def sensor_dict(origins_m: np.ndarray, directions: np.ndarray, film: dict) -> dict:
    """A ``raytable`` sensor dict: corner ``origins_m`` and ``directions`` (H + 1, W + 1, 3) and ``film``
    (an ``hdrfilm`` dict of W x H pixels; a box filter makes a pixel its footprint's mean)."""
    return {"type": PLUGIN_NAME, "film": film,
            "origins": mi.TensorXf(np.ascontiguousarray(np.asarray(origins_m, np.float32))),
            "directions": mi.TensorXf(np.ascontiguousarray(np.asarray(directions, np.float32)))}


__all__ = ["RayTableSensor", "register", "sensor_dict", "PLUGIN_NAME"]
