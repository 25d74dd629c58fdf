"""The air outside the model's box along the eye rays (aerial perspective), put onto a reference image.

The slicer puts the same air on its frames itself, in its kernels (``slicing.eye_air``). Inside the box the
air is part of the path tracer's medium (``optics.air.inside``); outside it the 1-D
atmosphere of ``spec.atmosphere`` is horizontally homogeneous, and each pixel's ray (its centre,
``slicing.geometry.film_rays``) is split where it meets the box, the flat ground and the top of the air
(``optics.air.eye_path``; heights above sea level, the Earth's centre under the box's centre):

* A = [camera, box entry] (or [camera, ground or top] where the ray misses the box):
  L = E S_A + T_A L_render          (single scattering of the air; with ``sky_air`` all orders: S_A and S_B
  hold the air's multiple scattering too, its source beta_s J(h) with J the mean intensity of the 1-D
  atmosphere's diffuse light at the height (DISORT, ``skylight.diffuse_source_table``), scattered
  isotropically: against DISORT's sky radiance at the ground, single scattering alone is 39-95 % of it in the
  principal plane, with this 93-120 %, tests/test_air_skylight.py)
* ``sky_air`` (``--sky air``: the render's sky is the air's diffuse light into the box, ``kernel.air_sky``, not
  seen by the camera): the rays that miss the box and the ground see the air's single-scattering sky E S_A;
  behind the box B = [box exit, ground or top]:
      L = E S_A + T_A (L_render + T_box T_air (E S_B + T_B L_g - L_g'))            (ray through the box)
      L = E S_A + T_A (L_render + G)                                              (ray to the ground outside it)
  T_box the eye-ray transmittance of the box's hydrometeors (``Image.transmittance``), T_air the box's air's along
  the eye ray (the 1-D atmosphere's, as the box holds it), T_B segment B's (Beer-Lambert): the ground beyond the
  box is dimmed by the air of B. L_g' is the ground's radiance as the render lit it (the direct sun, E mu0 C(h, mu)
  through the storm's shadow, and the envmap's irradiance on a horizontal plane E_env), L_g as the open ground
  outside the box is lit (the full diffuse sky E_sky of the 1-D atmosphere, ``kernel.air_sky.open_ground_sky``,
  in place of E_env), both rho / pi times the irradiance (rho the flat ground's albedo); G = rho / pi (E_sky -
  E_env) is the sky the render's vacuum outside the box leaves out of the open ground (the envmap holds the
  light that reaches the box's walls, not the air above the open ground). Over a terrain none of the ground's
  terms (its albedo varies): E T_A T_box T_air S_B alone.
  Without it (``--sky sunsky``) the sky's pixels stay Hosek-Wilkie's, which holds the air already, and a ray
  through the box that ends on that sky takes the air of A in proportion to the box's opacity 1 - T_box
  (the render there is cloud over sky: the air is added to the cloud's part only, approximately).

E is the scene's sun irradiance above the air (the RGB mode's sun with an atmosphere, ``sun_rgb`` = 1 in
luminance there). The storm shadows the direct sun at the samples of A and B and on the ground
(``optics.air.storm_shadow``: the hydrometeors' chord towards the sun; not for a periodic field; not on the
diffuse light's source). Not included: the light the storm scatters into the outside air, the storm's blocking of
the open ground's sky and of the outside air's diffuse light.

A spectral render (``render --spectral``, ``eye_air(spectral=True)``): the same terms at DISORT's 13 wavelengths
(``SpectralChannels``), the radiances integrated to CIE XYZ and linear sRGB, the transmittances a factor per sRGB
channel on the render's pixels (exact for light of the sun's spectrum; docs/spectral.md measures the rest).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

CHUNK = 2048  # rays per call of ``segment_air`` (memory: CHUNK x 257 samples x 3 channels x a few arrays)
SMOOTH_SAMPLES = 65  # points per segment for the multiple scattering and the box's air (no storm shadow in them)


def eye_air(spec, vol, sky_air: bool, table=None, samples: int | None = None, spectral: bool = False):
    """Per pixel: (T_A, E S_A, E S_B (H, W, 3) of the module docstring, whether the ray ends on the sky
    model's sky, whether it meets the box (H, W), T_air (H, W, 3), the ground's terms (H, W, 3): T_B L_g - L_g'
    where the ray meets the box, G where it meets the ground outside it; 0 without ``sky_air``). ``table``: the
    sun's (``eye_path.wide_sun_table``);
    ``samples``: points per segment (default ``eye_path.SAMPLES``; 33 keep S within about 1%, at an eighth of
    the cost: a viewer's reference). ``spectral``: the terms per wavelength (``SpectralChannels``: a spectral
    render's), projected to the same linear sRGB after the march."""
    from ..optics.air.eye_path import SAMPLES, segment_air, top_distance
    samples = SAMPLES if samples is None else int(samples)
    from ..slicing.geometry import camera_rays, ray_box
    atm, sun = spec.atmosphere, spec.sun
    if spectral and table is not None:
        raise ValueError("eye_air: a sun table is the RGB mode's (650/550/450 nm); the spectral terms make their own")
    ch = SpectralChannels(spec, sky_air) if spectral else RgbChannels(spec, sky_air, table)
    table, ms = ch.sun_table, ch.diffuse  # ms: the outside air's multiple scattering (--sky air)
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
    n, c = o.shape[0], len(ch.wavelengths_nm)
    shadow = None
    if not vol.periodic:  # the storm's shadow on the air's single scattering (a periodic field: none)
        from ..optics.air.storm_shadow import storm_shadow
        sh = storm_shadow(vol.beta_total, vol.bbox, sun.to_sun)
        shadow = lambda p: sh.transmittance(p + centre)  # noqa: E731  (the frame's points in the volume's)
    t_a, s_a, s_b = np.ones((n, c)), np.zeros((n, c)), np.zeros((n, c))
    t_air, t_b = np.ones((n, c)), np.ones((n, c))
    for i in range(0, n, CHUNK):
        sl = slice(i, i + CHUNK)

        def seg(t0, t1, tab=table, n=samples, **kw):
            return segment_air(atm, sun.to_sun, o[sl], d[sl], t0, t1, tab, ch.wavelengths_nm, samples=n, **kw)
        coarse = min(samples, SMOOTH_SAMPLES)  # the diffuse source and the box's air: smooth along the ray
        t_a[sl], s = seg(np.zeros(a_end[sl].shape), a_end[sl], shadow=shadow)
        if ms is not None:
            s = s + seg(np.zeros(a_end[sl].shape), a_end[sl], ms, coarse, isotropic=True)[1]
        s_a[sl] = s
        if sky_air:
            b0, b1 = np.where(hit[sl], t_out[sl], 0.0), np.where(hit[sl], t_end[sl], 0.0)  # B: none where no box
            t_b[sl], s = seg(b0, b1, shadow=shadow)
            s_b[sl] = s + seg(b0, b1, ms, coarse, isotropic=True)[1]
            t_air[sl], _ = seg(np.where(hit[sl], t_in[sl], 0.0), b0, n=coarse)
    s_a, s_b = ch.radiance(s_a) * e, ch.radiance(s_b) * e
    t_a, t_air, t_b = ch.transmittance(t_a), ch.transmittance(t_air), ch.transmittance(t_b)
    ground = np.zeros((n, 3))
    if sky_air and floor is not None and getattr(vol, "terrain", None) is None:
        on_ground = np.isfinite(t_ground) & (t_ground <= t_end)
        q = o + np.where(on_ground, t_ground, 0.0)[:, None] * d       # the ground point (the frame's)
        on_ground &= ~np.all((q[:, :2] >= lo[:2]) & (q[:, :2] <= hi[:2]), axis=-1)  # under the box: the render's
        lit_g, lit_full, open_sky = _ground_radiance(spec, vol, ch, q, shadow)
        ground = np.where((hit & on_ground)[:, None], t_b * lit_full - lit_g,
                          np.where(on_ground[:, None], open_sky, 0.0))
    shape = (spec.height, spec.width)
    sky_end = ~np.isfinite(t_ground) & (not sky_air)  # ends on the sky model's sky
    return (t_a.reshape(shape + (3,)), s_a.reshape(shape + (3,)), s_b.reshape(shape + (3,)),
            sky_end.reshape(shape), hit.reshape(shape), t_air.reshape(shape + (3,)), ground.reshape(shape + (3,)))


class RgbChannels:
    """The RGB mode's channels: the air at 650/550/450 nm (``optics.air.inside.CHANNEL_NM``), the sun's and the
    diffuse light's tables in linear sRGB (their spectra projected), the march's results used as they are."""

    def __init__(self, spec, sky_air: bool, table=None):
        from ..optics.air.eye_path import wide_sun_table
        from ..optics.air.inside import CHANNEL_NM
        self.wavelengths_nm = CHANNEL_NM
        self.sun_table = wide_sun_table(spec.atmosphere, spec.sun.mu0) if table is None else table
        self.diffuse = _diffuse_table(spec) if sky_air else None

    def radiance(self, values):
        return values

    def transmittance(self, values):
        return values

    def sun(self, values):
        """The direct sun's colour (n, 3) from the sun's table's values (n, c)."""
        return values


class SpectralChannels:
    """A spectral render's channels: the air, the sun's transmittance and the diffuse light's mean intensity at
    DISORT's 13 wavelengths (``skylight.SKY_WAVELENGTHS_NM``, 400-700 nm); radiances (per unit irradiance of the
    sun above the air, per wavelength) projected to CIE XYZ and linear sRGB with the top-of-atmosphere sun's
    spectrum (``skylight.rgb``: log-linear between the wavelengths); a transmittance T(lambda) as the factor per
    sRGB channel it puts on that sun's light (``skylight.transmittance_rgb``, applied to the render's pixels)."""

    def __init__(self, spec, sky_air: bool):
        from ..optics.air.eye_path import wide_sun_table
        from ..optics.air.skylight import SKY_WAVELENGTHS_NM
        self.wavelengths_nm = SKY_WAVELENGTHS_NM
        self.sun_table = wide_sun_table(spec.atmosphere, spec.sun.mu0, band_nm=SKY_WAVELENGTHS_NM)
        self.diffuse = _diffuse_table(spec, SKY_WAVELENGTHS_NM) if sky_air else None

    def radiance(self, values):
        from ..optics.air.skylight import rgb
        return rgb(np.asarray(values, np.float64).T)

    def transmittance(self, values):
        from ..optics.air.skylight import transmittance_rgb
        return transmittance_rgb(np.asarray(values, np.float64).T)

    sun = radiance


def _diffuse_table(spec, band_nm=None):
    """The diffuse light's mean intensity by height (``optics.air.skylight.diffuse_source_table``) for ``spec``'s
    atmosphere, sun and ground (albedo: its channel mean); None with the sun below the horizon. ``band_nm``: at
    those wavelengths (None: linear sRGB). The sun's cosine is the raw mu0 (plane-parallel), where the slicer's J
    (``slicing.air_multiple.diffuse_input``) takes Kasten-Young's ``effective_mu0``: they differ by over 1 % below 20
    deg of elevation (0.113 against 0.105 at 6 deg)."""
    from ..kernel.air_sky import ground_boundary
    from ..optics.air.skylight import diffuse_source_table
    if spec.sun.mu0 <= 0.0:
        return None
    ground, albedo = ground_boundary(spec)
    return diffuse_source_table(spec.atmosphere, float(spec.sun.mu0), ground, albedo, band_nm)


def _ground_radiance(spec, vol, ch, points, shadow):
    """(The flat ground's radiance at ``points`` (n, 3) (the frame's: the box's centre at x = y = 0) as the render
    lit it, as the open ground is lit, the open ground's sky that the render leaves out (n, 3) each): module
    docstring. ``ch``: the channels (``RgbChannels``, ``SpectralChannels``)."""
    from ..kernel.air_sky import open_ground_sky
    from ..optics.air.shell import EARTH_RADIUS_M
    sun, e = spec.sun, np.asarray(spec.sun.irradiance, np.float64)
    rel = points + [0.0, 0.0, EARTH_RADIUS_M]                                 # from the Earth's centre
    mu = rel @ np.asarray(sun.to_sun, np.float64) / np.linalg.norm(rel, axis=-1)
    h = np.full(points.shape[0], max(float(spec.ground.height), 0.0))
    direct = e * sun.mu0 * ch.sun(ch.sun_table.at(h, mu))
    if shadow is not None:
        direct = direct * np.asarray(shadow(points), np.float64).reshape(-1)[:, None]
    e_env, e_sky = open_ground_sky(spec, vol.bbox)
    rho = np.asarray(spec.ground.albedo, np.float64) / np.pi
    return rho * (direct + e_env), rho * (direct + e_sky), np.broadcast_to(rho * (e_sky - e_env), points.shape)


def with_eye_air(img, spec, vol, sky_air: bool = False, air=None):
    """``img`` (a reference ``Image`` of ``spec`` and ``vol``) seen through the air outside the box (module
    docstring): radiance E S_A + T_A (L + T_box T_air (E S_B + T_B L_g - L_g')) or E S_A + T_A (L + G) (weighted by
    the box's opacity where the ray ends on a sky model's sky), the standard error scaled alike (the added terms
    are exact).
    Needs ``spec.atmosphere`` (a ValueError otherwise). ``air``: ``eye_air(spec, vol, sky_air)`` if already
    computed (a progressive render's passes share it; else computed here, per wavelength for a spectral render)."""
    if spec.atmosphere is None:
        raise ValueError("the air along the eye rays needs an atmosphere (--atmosphere clear)")
    if air is None:  # a spectral render's (img.xyz) terms per wavelength
        air = eye_air(spec, vol, sky_air, spectral=img.xyz is not None)
    t_a, s_a, s_b, sky_end, hit, t_air, ground = air
    t_box = np.ones(hit.shape) if img.transmittance is None else np.asarray(img.transmittance, np.float64)
    rad = np.asarray(img.radiance, np.float64)
    w = np.where(sky_end, np.where(hit, 1.0 - np.clip(t_box, 0.0, 1.0), 0.0), 1.0)[..., None]
    behind = np.where(hit[..., None], t_box[..., None] * t_air * (s_b + ground), ground)
    out = rad + w * (s_a + t_a * (rad + behind) - rad)
    se = None if img.stderr is None else (img.stderr * (1.0 + w * (t_a - 1.0))).astype(np.float32)
    meta = {**img.metadata, "eye_air": {"sky": "air" if sky_air else "model", "pixels_changed": int((w > 0).sum())}}
    xyz = None
    if img.xyz is not None:  # a spectral render's CIE XYZ: its linear sRGB's, as the render gave them
        from ..optics.spectrum import xyz_of_linear_srgb
        xyz = xyz_of_linear_srgb(out).astype(np.float32)
    return replace(img, radiance=out.astype(np.float32), stderr=se, metadata=meta, xyz=xyz)


__all__ = ["eye_air", "with_eye_air"]
