"""``--sky air``'s light into the box: the clear atmosphere's diffuse sky (``optics.air.skylight``: DISORT, all
orders of scattering) as a Mitsuba ``envmap`` (a lat-long bitmap, ``ENV_SIZE``; row i at zenith angle
i 180 / (H - 1) deg, column j at azimuth (j + 1/2) 360 / W deg clockwise from north, as Mitsuba's envmap reads its
bitmap under ``TO_WORLD``).

Outside the box the air is horizontally homogeneous; the path tracer has the box's own air (``optics.air.inside``)
and vacuum outside it. What a ray that leaves the box should meet is the 1-D atmosphere's downward radiance at the
height where it leaves, L(h_exit, direction): the air above the top for a ray through the top, the air beside the
box for a ray through a side. An envmap depends on the direction only, so h_exit is taken from the box's
reference point, its horizontal centre at ``reference_m`` (the ground by default): h_exit = min(top, h_ref +
D(azimuth) tan(elevation)), D the distance to the box's wall in that azimuth. So the box's own air is not counted
twice along the steep directions (the air below the top is the path tracer's), and the light beside the box
comes in through the sides. Directions below the horizon meet the ground (``scene_dict.ground_dict`` reaches the
horizon): the bitmap is 0 there (the first row below the horizon repeats the horizon's, so that the bilinear
lookup does not darken the horizon). The ground's albedo (channel mean) is DISORT's surface.

Radiance: the table's per unit luminance irradiance of the sun above the air, times ``spec.sun.irradiance``
(the RGB mode's sun above the air, as ``optics.air.sunlight``). The envmap is not seen directly by the camera
(``scene_dict`` hides the scene's emitters from camera rays where it is in the scene: the air's sky along the eye
rays is ``display.aerial``'s). The spectral variants take the same envmap: Mitsuba's ``envmap`` turns each
pixel's linear sRGB into a smooth spectrum (Jakob & Hanika 2019's sRGB model times D65), whose CIE XYZ is the
pixel's (within 0.3 %); its shape differs from DISORT's sky spectrum, which matters only where the light is
filtered by wavelength on its way to the eye: ``docs/spectral.md`` measures it (CIEDE2000 under 0.3 through the
box's air and a cloud), so no spectral emitter is built.

What renders outside Mitsuba's path loop (the slicer's skylight on its cloud and ground, ``kernel.sky``) takes
this sky's irradiance on a horizontal plane at the envmap's reference point (:func:`sky_irradiance`): the 1-D
atmosphere's diffuse downward flux (DISORT's) at the ground, the skylight the reference's open ground gets
(the envmap's and ``display.aerial``'s, ``open_ground_sky``), nodes over the sun's cosine cached per atmosphere
and ground (a sun drag costs a node when it crosses into a new interval: 13 DISORT solves, ~0.1 s).
"""
from __future__ import annotations

import functools

import numpy as np

ENV_SIZE = (256, 129)     # (W, H): 1.4 deg a pixel; H odd, a row at the horizon
LEVEL_STEP_M = 1500.0     # the sky's table: a level every 1.5 km from the reference height to the box's top
EMITTER_NEE = 0.03        # the share of shadow rays towards this sky (majorant_volpath's emitter_nee; its default
                          # 0.1 is for a sky model): it lights the storm with 1-20 % of the sun's irradiance, and
                          # the phase function's own directions find a sky this broad (MIS: unbiased at any share)
TO_WORLD = [[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]  # +Y up -> +Z


def pixel_directions(size=ENV_SIZE) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(zenith angle (H,), azimuth clockwise from north (W,) in deg, world directions (H, W, 3)) of the bitmap's
    pixels, as Mitsuba's ``envmap`` looks them up under ``TO_WORLD``."""
    w, h = size
    zen = np.arange(h) * 180.0 / (h - 1)
    az = (np.arange(w) + 0.5) * 360.0 / w
    t, p = np.radians(zen)[:, None], np.radians(az)[None, :]
    dirs = np.stack(np.broadcast_arrays(np.sin(t) * np.sin(p), np.sin(t) * np.cos(p), np.cos(t)), axis=-1)
    return zen, az, dirs


def exit_heights(bbox, reference_m: float, zenith_deg, azimuth_deg) -> np.ndarray:
    """Where a ray from the box's horizontal centre at ``reference_m`` leaves the box (m above sea level), per
    (zenith (H,), azimuth (W,)) of the upper hemisphere: (H, W) (module docstring)."""
    (x0, y0, _), (x1, y1, z1) = bbox
    hx, hy = (x1 - x0) / 2.0, (y1 - y0) / 2.0
    a = np.radians(np.asarray(azimuth_deg, np.float64))[None, :]
    with np.errstate(divide="ignore"):
        wall = np.minimum(hx / np.abs(np.sin(a)), hy / np.abs(np.cos(a)))  # horizontal distance to the wall
        rise = np.tan(np.radians(90.0 - np.asarray(zenith_deg, np.float64)))[:, None] * wall
    return np.minimum(float(reference_m) + np.nan_to_num(rise, nan=np.inf, posinf=np.inf), float(z1))


def ground_boundary(spec) -> tuple[float, float]:
    """(The flat ground's height (m), at least sea level; its mean albedo; (0, 0) without a ground): the 1-D
    atmosphere's lower boundary (DISORT's surface), the same for the path tracer's sky and the slicer's."""
    if spec.ground is None:
        return 0.0, 0.0
    return max(float(spec.ground.height), 0.0), float(np.mean(spec.ground.albedo))


def _sky(spec, bbox, reference_m: float | None = None, size=ENV_SIZE):
    """(The envmap's bitmap, as :func:`sky_bitmap`; the ``skylight.SkyTable`` it was read from, its first level
    the reference height; None with the sun below the horizon)."""
    from ..optics.air.skylight import sky_table
    atm, sun = spec.atmosphere, spec.sun
    if atm is None:
        raise ValueError("--sky air is the clear atmosphere's own sky: it needs an atmosphere (--atmosphere clear)")
    ground, albedo = ground_boundary(spec)
    ref = ground if reference_m is None else max(float(reference_m), ground)
    top = max(float(bbox[1][2]), ref)
    levels = np.unique(np.r_[np.arange(ref, top, LEVEL_STEP_M), top])
    zen, az, _ = pixel_directions(size)
    w, h = size
    out = np.zeros((h, w, 3))
    if sun.mu0 <= 0.0:  # the sun below the horizon: no sky from this model (the render's sun is off too)
        return out.astype(np.float32), None
    table = sky_table(atm, float(sun.mu0), levels, ground_m=ground, albedo=albedo)
    up = zen <= 90.0
    h_exit = exit_heights(bbox, ref, zen[up], az)
    rel = az[None, :] - float(sun.azimuth)
    out[up] = table.at(h_exit, np.broadcast_to(zen[up][:, None], h_exit.shape), np.broadcast_to(rel, h_exit.shape))
    horizon = int(np.flatnonzero(up)[-1])
    out[horizon + 1] = out[horizon]
    return (out * np.asarray(sun.irradiance, np.float64)).astype(np.float32), table


def sky_bitmap(spec, bbox, reference_m: float | None = None, size=ENV_SIZE) -> np.ndarray:
    """The envmap's linear RGB radiance (H, W, 3), float32 (module docstring) for ``spec`` (its atmosphere, sun and
    ground) and a box ``bbox``."""
    return _sky(spec, bbox, reference_m, size)[0]


def air_sky_dict(spec, bbox, reference_m: float | None = None) -> dict:
    """The Mitsuba ``envmap`` of :func:`sky_bitmap`."""
    import mitsuba as mi
    return {"type": "envmap", "bitmap": mi.Bitmap(sky_bitmap(spec, bbox, reference_m)),
            "to_world": mi.ScalarTransform4f(mi.ScalarMatrix4f(TO_WORLD))}


def open_ground_sky(spec, bbox) -> tuple[np.ndarray, np.ndarray]:
    """(The envmap's irradiance on the open ground (a horizontal plane, nothing in the way), the 1-D atmosphere's
    diffuse irradiance there (DISORT's flux)), RGB, times the sun's irradiance: the second less the first is the
    skylight that the render's vacuum outside the box leaves out of the open ground (``display.aerial``). One
    DISORT table: the envmap's, whose first level is the ground."""
    if spec.sun.mu0 <= 0.0:
        return np.zeros(3), np.zeros(3)
    bitmap, table = _sky(spec, bbox)
    return horizontal_irradiance(bitmap), table.diffuse_rgb[0] * np.asarray(spec.sun.irradiance, np.float64)


@functools.lru_cache(maxsize=64)
def _skylight_node(atm, mu0: float, ground_m: float, albedo: float) -> np.ndarray:
    """DISORT's diffuse downward flux at the ground (RGB, per unit luminance irradiance of the sun above the air)
    with the sun at cos(zenith) ``mu0``: ``skylight.sky_table``'s ``diffuse_rgb`` there."""
    from ..optics.air.skylight import rgb, spectral_sky
    _, down, _ = spectral_sky(atm, mu0, np.array([ground_m]), [0.0], [0.0], ground_m, albedo)
    return rgb(down)[0]


def sky_irradiance(spec) -> np.ndarray:
    """The air's sky's irradiance (RGB, W/m^2: times ``spec.sun.irradiance``) on a horizontal plane at the envmap's
    reference point (the ground, at least sea level; module docstring): linear in the sun's cos(zenith) between
    ``optics.air.sun_nodes.MU_NODES`` (``between_nodes``: under the lowest node its value times mu0 / the
    node's; 0 with the sun below the horizon, as the envmap's)."""
    from ..optics.air.sun_nodes import between_nodes
    if spec.atmosphere is None:
        raise ValueError("--sky air is the clear atmosphere's own sky: it needs an atmosphere (--atmosphere clear)")
    mu0 = float(spec.sun.mu0)
    if mu0 <= 0.0:
        return np.zeros(3)
    ground, albedo = ground_boundary(spec)
    e = between_nodes(mu0, lambda node: _skylight_node(spec.atmosphere, node, round(ground, 3), round(albedo, 6)))
    return e * np.asarray(spec.sun.irradiance, np.float64)


def horizontal_irradiance(bitmap: np.ndarray) -> np.ndarray:
    """Irradiance (RGB) of an envmap's bitmap (H, W, 3) (``pixel_directions``' layout) on an upward-facing
    horizontal plane: the integral of L cos(theta) over the upper hemisphere (trapezoidal in theta, the
    bitmap's columns' mean in azimuth; linear between rows, as Mitsuba's lookup)."""
    b = np.asarray(bitmap, np.float64)
    h = b.shape[0]
    zen = np.radians(np.arange(h) * 180.0 / (h - 1))
    up = zen <= np.pi / 2 + 1e-9
    ring = b[up].mean(axis=1) * (np.cos(zen[up]) * np.sin(zen[up]))[:, None]
    return 2.0 * np.pi * np.trapezoid(ring, zen[up], axis=0)


__all__ = ["EMITTER_NEE", "ground_boundary", "sky_irradiance", "air_sky_dict", "sky_bitmap", "open_ground_sky",
           "exit_heights", "pixel_directions", "horizontal_irradiance", "ENV_SIZE"]
