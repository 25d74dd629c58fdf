"""A keyframed camera path: views the user marked, and the views between them.

Between two keyframes, azimuths (camera and sun) turn the short way round, the distance changes
geometrically (a zoom looks steady), everything else numeric changes linearly, and the time index
and anything not numeric (mode, slice count) follow the nearer keyframe. Timing: ``seconds_per_key``
from one keyframe to the next.
"""
from __future__ import annotations

import math
from dataclasses import replace

from .state import ViewState


def _lerp_angle(a: float, b: float, t: float) -> float:
    d = (b - a + 180.0) % 360.0 - 180.0
    return (a + t * d) % 360.0


def _lerp(a: float, b: float, t: float) -> float:
    return a + t * (b - a)


def between(a: ViewState, b: ViewState, t: float) -> ViewState:
    """The view a fraction ``t`` (0..1) of the way from keyframe ``a`` to keyframe ``b``."""
    if a.camera.kind != b.camera.kind:  # no blend between camera kinds: cut at the midpoint
        return a if t < 0.5 else b
    ca, cb = a.camera, b.camera
    camera = replace(ca, azimuth=_lerp_angle(ca.azimuth, cb.azimuth, t),
                     distance_km=math.exp(_lerp(math.log(ca.distance_km), math.log(cb.distance_km), t)),
                     height_m=math.exp(_lerp(math.log(ca.height_m), math.log(cb.height_m), t)),
                     elevation_deg=_lerp(ca.elevation_deg, cb.elevation_deg, t), fov=_lerp(ca.fov, cb.fov, t))
    near = a if t < 0.5 else b
    scale_names = set(dict(a.scale)) | set(dict(b.scale))
    scale = tuple(sorted((n, math.exp(_lerp(math.log(max(dict(a.scale).get(n, 1.0), 1e-6)),
                                             math.log(max(dict(b.scale).get(n, 1.0), 1e-6)), t)))
                         for n in scale_names))
    return replace(near, camera=camera, sun_azimuth=_lerp_angle(a.sun_azimuth, b.sun_azimuth, t),
                   sun_elevation=_lerp(a.sun_elevation, b.sun_elevation, t), scale=scale,
                   exposure_ev=_lerp(a.exposure_ev, b.exposure_ev, t),
                   cone_angle_deg=_lerp(a.cone_angle_deg, b.cone_angle_deg, t),
                   ambient=_lerp(a.ambient, b.ambient, t),
                   time=int(round(_lerp(a.time, b.time, t))))


def path(keys: list[ViewState], fps: float, seconds_per_key: float = 2.0) -> list[ViewState]:
    """Every frame of the path through ``keys`` at ``fps`` (the last keyframe included)."""
    if len(keys) < 2:
        raise ValueError("a camera path needs at least two keyframes")
    per = max(1, int(round(fps * seconds_per_key)))
    out = []
    for a, b in zip(keys[:-1], keys[1:]):
        out += [between(a, b, k / per) for k in range(per)]
    out.append(keys[-1])
    return out
