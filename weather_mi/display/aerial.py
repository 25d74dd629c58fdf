"""The air outside the model's box along the eye rays (aerial perspective), put onto a reference image.

The slicer puts the same air on its frames itself, in its kernels (``slicing.eye_air``). Inside the box the
air is part of the path tracer's medium (``optics.air.inside``); outside it the 1-D
atmosphere of ``spec.atmosphere`` is horizontally homogeneous, and each pixel's ray (its centre,
``slicing.geometry.film_rays``) is split where it meets the box, the flat ground and the top of the air
(``optics.air.eye_path``; heights above sea level, the Earth's centre under the box's centre):

* A = [camera, box entry] (or [camera, ground or top] where the ray misses the box):
  L = E S_A + T_A L_render                                              (single scattering of the air)
* ``sky_air`` (``--sky air``: the render has no sky emitter): the rays that miss the box and the ground see
  the air's single-scattering sky E S_A; behind the box B = [box exit, ground or top] adds
  E T_A T_box S_B, T_box the eye-ray transmittance of the box's hydrometeors (``Image.transmittance``).
  Without it (``--sky sunsky``) the sky's pixels stay Hosek-Wilkie's, which holds the air already, and a ray
  through the box that ends on that sky takes the air of A in proportion to the box's opacity 1 - T_box
  (the render there is cloud over sky: the air is added to the cloud's part only, approximately).

E is the scene's sun irradiance above the air (the RGB mode's sun with an atmosphere, ``sun_rgb`` = 1 in
luminance there). The storm shadows the direct sun at the samples of A and B (``optics.air.storm_shadow``:
the hydrometeors' chord towards the sun; not for a periodic field). Not included: light scattered more than
once by the outside air, the light the storm scatters into the outside air, and the dimming of the ground
behind the box by segment B.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

CHUNK = 2048  # rays per call of ``segment_air`` (memory: CHUNK x 257 samples x 3 channels x a few arrays)


def eye_air(spec, vol, sky_air: bool, table=None, samples: int | None = None):
    """Per pixel: (T_A, E S_A, E S_B (H, W, 3) of the module docstring, whether the ray ends on the sky
    model's sky, whether it meets the box (H, W)). ``table``: the sun's (``eye_path.wide_sun_table``);
    ``samples``: points per segment (default ``eye_path.SAMPLES``; 33 keep S within about 1%, at an eighth of
    the cost: a viewer's reference)."""
    from ..optics.air.eye_path import SAMPLES, segment_air, top_distance, wide_sun_table
    samples = SAMPLES if samples is None else int(samples)
    from ..slicing.geometry import camera_rays, ray_box
    atm, sun = spec.atmosphere, spec.sun
    table = wide_sun_table(atm, sun.mu0) if table is None else table
    o, d = (a.reshape(-1, 3).astype(np.float64) for a in camera_rays(spec))
    (x0, y0, z0), (x1, y1, z1) = (np.asarray(p, np.float64) for p in vol.bbox)
    centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2, 0.0])
    o = o - centre
    floor = None if spec.ground is None else float(spec.ground.height)
    lo = np.array([x0, y0, max(z0, floor if floor is not None else z0)]) - centre
    hi = np.array([x1, y1, z1]) - centre
    t_in, t_out = ray_box(o, d, (lo, hi))  # the slab method, t_in >= 0
    hit = t_out > t_in
    with np.errstate(divide="ignore", invalid="ignore"):
        t_ground = np.where((d[:, 2] < 0) & (floor is not None), ((floor or 0.0) - o[:, 2]) / d[:, 2], np.inf)
    t_end = np.minimum(t_ground, top_distance(o, d))
    hit &= t_in < t_end
    a_end = np.where(hit, t_in, t_end)
    e = np.asarray(sun.irradiance, np.float64)
    n = o.shape[0]
    shadow = None
    if not vol.periodic:  # the storm's shadow on the air's single scattering (a periodic field: none)
        from ..optics.air.storm_shadow import storm_shadow
        sh = storm_shadow(vol.beta_total, vol.bbox, sun.to_sun)
        shadow = lambda p: sh.transmittance(p + centre)  # noqa: E731  (the frame's points in the volume's)
    t_a, s_a, s_b = np.ones((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))
    for i in range(0, n, CHUNK):
        sl = slice(i, i + CHUNK)
        t_a[sl], s = segment_air(atm, sun.to_sun, o[sl], d[sl], np.zeros(a_end[sl].shape), a_end[sl], table,
                                 shadow=shadow, samples=samples)
        s_a[sl] = s * e
        if sky_air:
            b0, b1 = np.where(hit[sl], t_out[sl], 0.0), np.where(hit[sl], t_end[sl], 0.0)  # B: none where no box
            _, s = segment_air(atm, sun.to_sun, o[sl], d[sl], b0, b1, table, shadow=shadow, samples=samples)
            s_b[sl] = s * e
    shape = (spec.height, spec.width)
    sky_end = ~np.isfinite(t_ground) & (not sky_air)  # ends on the sky model's sky
    return (t_a.reshape(shape + (3,)), s_a.reshape(shape + (3,)), s_b.reshape(shape + (3,)),
            sky_end.reshape(shape), hit.reshape(shape))


def with_eye_air(img, spec, vol, sky_air: bool = False, air=None):
    """``img`` (a reference ``Image`` of ``spec`` and ``vol``) seen through the air outside the box (module
    docstring): radiance E S_A + T_A (L + T_box E S_B) (weighted by the box's opacity where the ray ends on a
    sky model's sky), the standard error scaled alike (the added terms are exact).
    Needs ``spec.atmosphere`` (a ValueError otherwise). ``air``: ``eye_air(spec, vol, sky_air)`` if already
    computed (a progressive render's passes share it)."""
    if spec.atmosphere is None:
        raise ValueError("the air along the eye rays needs an atmosphere (--atmosphere clear)")
    t_a, s_a, s_b, sky_end, hit = eye_air(spec, vol, sky_air) if air is None else air
    t_box = np.ones(hit.shape) if img.transmittance is None else np.asarray(img.transmittance, np.float64)
    rad = np.asarray(img.radiance, np.float64)
    w = np.where(sky_end, np.where(hit, 1.0 - np.clip(t_box, 0.0, 1.0), 0.0), 1.0)[..., None]
    out = rad + w * (s_a + t_a * (rad + t_box[..., None] * s_b) - rad)
    se = None if img.stderr is None else (img.stderr * (1.0 + w * (t_a - 1.0))).astype(np.float32)
    meta = {**img.metadata, "eye_air": {"sky": "air" if sky_air else "model", "pixels_changed": int((w > 0).sum())}}
    return replace(img, radiance=out.astype(np.float32), stderr=se, metadata=meta)


__all__ = ["eye_air", "with_eye_air"]
