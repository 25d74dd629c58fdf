"""The sun glint where each column's own sun puts it, under the one sun the renderer lights a domain with.

The renderer's frame is flat and its sun the domain centre's (``place.sun_from_time``), while each pixel's
line of sight is the column's own (``rays``): a Lambertian surface then errs by the cosine of a few degrees,
but the glint, a lobe a few degrees wide on the sea's slopes (``kernel.sea_surface``), would land where the
centre's sun and the column's view are mirror images, hundreds of km from the specular point of a wide
domain (70 km for a specular point 90 km off a 1800 km domain's centre, measured). Each sea column's shading
normal is therefore turned by the rotation that takes the half vector of its own sun and view, h = (s + v) / |s
+ v|, to the half vector of the render's sun and the view: the facet slopes' angle to the render's half vector
is then the true one, the glint's shape and place those of the column's own sun (the Fresnel and 1 / mu terms
see the tilted normal, off by the cosine of its tilt, about the angle between the two suns over two).
"""
from __future__ import annotations

import numpy as np


def _unit(a):
    return a / np.linalg.norm(a, axis=-1, keepdims=True)


def rotate_towards(z, a, b):
    """``z`` (..., 3) turned by the smallest rotation taking unit vectors ``a`` to ``b`` (Rodrigues)."""
    axis = np.cross(a, b)
    sin = np.linalg.norm(axis, axis=-1, keepdims=True)
    cos = np.sum(a * b, axis=-1, keepdims=True)
    k = np.where(sin > 1e-12, axis / np.maximum(sin, 1e-300), 0.0)
    return z * cos + np.cross(k, z) * sin + k * np.sum(k * z, axis=-1, keepdims=True) * (1 - cos)


def sea_normals(place, sat, sun_meta: dict, render_sun) -> np.ndarray:
    """(ny, nx, 3) unit shading normals of the sea columns of ``place`` (module docstring): the column's own
    sun (``solar.sun_angles_at`` from the centre's, turned into the grid's frame by the meridian convergence),
    its view towards ``sat`` (``rays.to_satellite``) and ``render_sun`` (a ``Sun``: the render's)."""
    from ..scene.solar import SolarPosition, sun_angles_at, sun_vector
    from .rays import to_satellite
    lat, lon = place.lat, place.lon
    centre = SolarPosition(sun_meta["solar_zenith_deg"], sun_meta["solar_zenith_geometric_deg"],
                           sun_meta["solar_azimuth_true_deg"])
    zen, az = sun_angles_at(centre, sun_meta["centre_lat"], sun_meta["centre_lon"], lat, lon)
    zen = zen + (sun_meta["solar_zenith_deg"] - sun_meta["solar_zenith_geometric_deg"])  # the render's refraction
    own = _unit(np.asarray(sun_vector(zen, az - place.georef.grid_north_deg(lat, lon))))
    view = _unit(to_satellite(place, sat, lat, lon)[0])
    one = np.broadcast_to(_unit(np.asarray(render_sun.to_sun, float)), own.shape)
    z = np.broadcast_to(np.array([0.0, 0.0, 1.0]), own.shape)
    return _unit(rotate_towards(z, _unit(own + view), _unit(one + view)))


__all__ = ["sea_normals", "rotate_towards"]
