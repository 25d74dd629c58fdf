"""The air along the slicer's eye rays, inside the model's box and outside it (issue 38 part 3), in the frame's
kernels: what ``optics.air.inside`` puts into the path tracer's medium and ``display.aerial`` onto its image.

Each pixel's ray (``EyeRays``) is split where it meets the model's box (``vol.bbox``, its floor raised to the
ground), the flat ground and the top of the air (``optics.air.eye_path.TOP_M``; heights above a spherical
Earth whose centre lies under the box's centre, as ``display.aerial``'s):

* A = [camera, box entry] (or [camera, ground or top] where the ray misses the box): the air outside, as
  ``display.aerial.with_eye_air`` with the sky model's sky: L = E S_A + T_A L_box, weighted by the box's
  cloud opacity 1 - T where the ray ends on the sky model's sky (which holds the air already);
* the box [t_in, t_out], split at the eye ray's cloud depth t_c (the opacity-weighted mean distance of the
  eye pass's samples, ``eye.composite(depth=True)``; for an opaque cloud its face): the air in front of the
  cloud dims it and adds its own light, the air behind it is seen through the cloud:
      L_box = E S_f + T_f (C + T (E S_b + (T_b - 1) L_bg))
  with C + T L_bg the eye pass's radiance, T its cloud transmittance, L_bg the background (sky or ground).

T_x, S_x: the segment's transmittance and single-scattered sunlight per unit irradiance above the air
(``optics.air.eye_path``'s integrals: molecules with Rayleigh's phase function, aerosol with its albedo and
Henyey-Greenstein's, ozone absorbing, the direct sun's colour C(h, mu) at each point), here by Gauss-Legendre
on ``eye_air_quadrature.NODES`` points outside the box (dense near the camera: s = t0 + L x^2; 33 trapezoids
before, 5x less accurate) and trapezoidal on ``SAMPLES_BOX`` points (uniform) per box segment, from 1-D tables
by height. The air in the box is the 1-D atmosphere's (US 1976 molecules; the
path tracer takes the model's own rho_air, within a few per cent of it for the storms here).

The storm's shadow on the air (``display.aerial``'s is ``optics.air.storm_shadow``'s map): the sunlight at
each point of every segment, in the box and out, is dimmed by the slicer's own direct light there (the sun's
light volume, ``light_shadow``: exp(-tau) of the hydrometeors' chord towards the sun; outside the slicing
box, the light leaving it on the point's sun ray, 1 where that ray misses the box). The light pass runs
every frame for the frame's sun, so the shadow follows the sun and the sliders with no pass of its own,
compiles nothing new when the sun moves, and is the shadow the slicer's cloud and ground get. Against the
map on the same segments: within 0.5-2.8% (tests/test_slicing_air.py; 2.4-4.4% lighter with the trapezoids
before the Gauss nodes: the light volume's penumbra at a cloud's rim is lighter, and the step where a ray
enters the shadow falls between points either way). None for a periodic field (as ``display.aerial``).
The air in the box also scatters the diffuse light (sun and ground, all orders: its multiple scattering,
``air_multiple``'s DISORT mean intensity J(h) for the frame's sun, isotropic), not the air outside it (as
``display.aerial`` with the sky model's sky). With the air's own sky (``Sky("air")``, ``EyeAir.sky_air``: no sky
model, ``kernel.sky``) the air to the top is the sky, as ``display.aerial``'s with ``sky_air``: A on every ray (w = 1)
with its multiple scattering, and behind the box B = [box exit, ground or top] (Gauss nodes, the same source) in
the background's place, L_bg' = E S_B + T_B L_bg. Not included: the light the storm scatters into its shadow, and
(with a sky model) the air behind the box (as ``display.aerial`` without ``--sky air``). Everything is an input of the frame
(``EyeAir``): a new sun, camera or atmosphere uploads values and recompiles nothing. Frames of 96 px a side or
more integrate all this on every 4th pixel's ray and read it per pixel (``eye_air_coarse``); the tables' rows
are packets of 4 floats (one gather each, ``packets.packed``): the air's by height holds its three profiles
(molecules, ozone, aerosol), which per-channel cross sections turn into its coefficients (``cross_sections``), and
the segments outside the box read the storm's shadow from the light volume's last plane (``light_shadow``).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..kernel.jitarrays import aligned_float
from ..optics.air.shell import EARTH_RADIUS_M
from .air_multiple import diffuse_input
from .eye import OPAQUE_T
from .eye_air_quadrature import NODES, gauss_segment
from .packets import lerp_rows, packed, packet

HEIGHT_STEP_M = 250.0   # the height table's step (m): the aerosol's 1.2 km scale height within 0.5%
SAMPLES_BOX = 13        # points on each segment inside the box (uniform)
# the sun's colour by (cos zenith, height) for every sun, once per atmosphere (``sun_table``): cosines from below
# the horizon of the air's top to the zenith, heights to the air's top; slant columns on 64 points a segment
SUN_MU_RANGE, SUN_MU_SAMPLES, SUN_HEIGHT_SAMPLES, SUN_COLUMN_SAMPLES = (-0.15, 1.0), 257, 121, 64


@dataclass
class EyeAir:
    """The air's tables and the scene's values, as the frame's kernels read them (opaque Dr.Jit values; the
    ints and bools are part of a recording's structure)."""

    air: object         # mi.Float (n_h x 4): per height, the profiles (molecules, ozone, aerosol; ``height_table``),
                        # padded to a packet of 4 (``packets.packed``): one packet a row
    cross: tuple        # mi.Color3f each: (molecules' extinction, ozone's, aerosol's, aerosol's scattering) per unit of
                        # the profiles (``cross_sections``): the table's columns times these are the coefficients, 1/m
    h_step: object      # mi.Float: 1 / the height table's step (1/m); its heights start at sea level
    n_h: int            # rows of the height table
    sun_rgb: object     # mi.Float (n_mu x n_s x 4): the direct sun's linear sRGB by (mu, height), padded (``sun_table``)
    sun_mu: object      # (mi.Float lowest mu, mi.Float 1 / mu step, mi.Float 1 / height step (1/m))
    n_mu: int
    n_s: int
    to_sun: object      # mi.Vector3f: unit vector towards the sun
    irradiance: object  # mi.Color3f: the sun's irradiance above the air, W/m^2
    aerosol_g: object   # mi.Float: the aerosol's asymmetry
    centre: object      # mi.Point3f: (box centre x, y, 0): the Earth's centre lies R below it
    box: tuple          # (mi.Point3f lo, mi.Point3f hi): the model's box, its floor at the ground (m)
    floor: object       # mi.Float: the ground's height (m)
    ground: bool        # whether there is a ground
    diffuse: object     # mi.Float (n_h x 4): the diffuse light's mean intensity J(h) per unit irradiance of the sun,
                        # on the height table's rows, padded (``air_multiple``): the air's multiple scattering
    shadow: bool = True  # whether the storm shadows the air (False for a periodic field, as ``display.aerial``)
    sky_air: bool = False  # the air's own sky (``Sky("air")``): the air to the top is the sky (``seen_through_air``)
    width: int = 0      # the frame's pixels (row-major rays): the coarse grid of ``eye_air_coarse``; 0: none
    height: int = 0


@functools.lru_cache(maxsize=4)
def sun_table(atm):
    """The direct sun's linear sRGB over cos(zenith) in ``SUN_MU_RANGE`` and heights 0 to ``eye_path.TOP_M``, both
    uniform (a ``SunAirTable``): the same for every sun, so that a sun dragged in elevation recomputes nothing
    (bilinear lookups within 1.1% of ``optics.air.sun_rgb`` of the brightest channel, 5e-5 median, at the
    heights and cosines of a low sun; below the horizon of the air's top the sun is 0)."""
    from ..optics.air.eye_path import TOP_M
    from ..optics.air.sunlight import SunAirTable, sun_rgb
    mu = np.linspace(*SUN_MU_RANGE, SUN_MU_SAMPLES)
    heights = np.linspace(0.0, TOP_M, SUN_HEIGHT_SAMPLES)
    rgb = sun_rgb(atm, heights[None, :], mu[:, None], samples=SUN_COLUMN_SAMPLES)
    return SunAirTable(heights_m=heights, mu=mu, rgb=rgb.astype(np.float32))


PROFILE_SCALE = 1e-25  # the table's number densities (1/m^3) times this (the cross sections over it: float32 both)


def height_grid() -> np.ndarray:
    """The height tables' heights (m): 0 to ``eye_path.TOP_M`` every ``HEIGHT_STEP_M``."""
    from ..optics.air.eye_path import TOP_M
    return np.arange(0.0, TOP_M + HEIGHT_STEP_M / 2, HEIGHT_STEP_M)


def height_table(atm) -> np.ndarray:
    """(n_h, 3): the air's profiles at heights 0 to ``eye_path.TOP_M`` every ``HEIGHT_STEP_M``: molecules and ozone
    (number densities, 1/m^3, times ``PROFILE_SCALE``) and the aerosol's extinction at 550 nm (1/m)
    (``optics.air.inside.components``' profiles). The air's extinction is linear in them, so one packet a row,
    interpolated, gives all of its coefficients at every channel (``cross_sections``): 2 gathers a point instead
    of 6."""
    from ..optics.air.inside import CHANNEL_NM, components
    h = height_grid()
    profiles, _ = components(atm, atm.air_number_density_m3(h), h, CHANNEL_NM)
    return profiles * np.array([PROFILE_SCALE, PROFILE_SCALE, 1.0])


def cross_sections(atm) -> np.ndarray:
    """(4, 3): per unit of ``height_table``'s columns, the molecules' extinction (= their scattering), ozone's
    (absorption; the RGB channels' band averages), the aerosol's extinction and its scattering at R, G, B
    (``optics.air.inside.components``' spectra)."""
    from ..optics.air.inside import CHANNEL_NM, components
    _, spectra = components(atm, np.zeros(1), np.zeros(1), CHANNEL_NM)
    return np.stack([spectra[:, 0] / PROFILE_SCALE, spectra[:, 1] / PROFILE_SCALE, spectra[:, 2],
                     spectra[:, 2] * atm.aerosol_ssa])


def eye_air_input(mi, spec, bbox, reuse, shadow: bool = True) -> EyeAir | None:
    """The frame's ``EyeAir`` for ``spec`` (None without ``spec.atmosphere``) and the model's box ``bbox``
    ((lo, hi) corners, m); ``reuse``: the renderer's ``SliceRenderer._reuse`` (the tables and values of the last
    atmosphere and ground kept; a frame uploads the sun's values and, for a new sun, the diffuse light's table
    (``air_multiple.diffuse_input``) alone); ``shadow``: whether the storm shadows the air (``EyeAir.shadow``)."""
    atm = getattr(spec, "atmosphere", None)
    if atm is None:
        return None
    import drjit as dr
    op = lambda v: dr.opaque(mi.Float, float(v))  # noqa: E731
    floor = None if spec.ground is None else float(spec.ground.height)
    # per atmosphere and ground: the uploaded tables, and the J table's heights and unit (the sun above the air)
    fixed, heights, sun_top = reuse("eye air", (atm, floor), lambda: (_fixed_inputs(mi, atm, bbox, floor),
                                                                      height_grid(), sun_table(atm).rgb[-1, -1]))
    return EyeAir(**fixed, to_sun=mi.Vector3f(*(op(v) for v in spec.sun.to_sun)),
                  irradiance=mi.Color3f(*(op(v) for v in spec.sun.irradiance)),
                  diffuse=diffuse_input(mi, spec, reuse, heights, sun_top),
                  shadow=bool(shadow), sky_air=spec.has_air_sky,
                  width=int(spec.width), height=int(spec.height))


def _fixed_inputs(mi, atm, bbox, floor) -> dict:
    """The ``EyeAir`` fields of an atmosphere, a box and a ground height (None: no ground), uploaded once."""
    import drjit as dr
    op = lambda v: dr.opaque(mi.Float, float(v))  # noqa: E731
    table = sun_table(atm)
    air, rgb = aligned_float(mi, packed(height_table(atm))), aligned_float(mi, packed(table.rgb))
    cross = tuple(mi.Color3f(*(op(v) for v in row)) for row in cross_sections(atm))
    (x0, y0, z0), (x1, y1, z1) = (np.asarray(p, np.float64) for p in bbox)
    lo = (x0, y0, max(z0, floor) if floor is not None else z0)
    return dict(air=air, cross=cross, h_step=op(1.0 / HEIGHT_STEP_M), n_h=dr.width(air) // 4, sun_rgb=rgb,
                sun_mu=(op(table.mu[0]), op((table.mu.size - 1) / (table.mu[-1] - table.mu[0])),
                        op((table.heights_m.size - 1) / (table.heights_m[-1] - table.heights_m[0]))),
                n_mu=int(table.mu.size), n_s=int(table.heights_m.size), aerosol_g=op(atm.aerosol_g),
                centre=mi.Point3f(op((x0 + x1) / 2), op((y0 + y1) / 2), op(0.0)),
                box=(mi.Point3f(*(op(v) for v in lo)), mi.Point3f(op(x1), op(y1), op(z1))),
                floor=op(0.0 if floor is None else floor), ground=floor is not None)


def _sun_colour(mi, dr, air: EyeAir, h, mu):
    """The direct sun's colour at heights h and local zenith cosines mu (bilinear, clamped)."""
    mu_lo, inv_dmu, inv_dh = air.sun_mu

    def cell(f, n):
        f = dr.clip(f, 0.0, float(n - 1))
        i = dr.minimum(mi.UInt32(f), n - 2)
        return i, f - mi.Float(i)
    im, tm = cell((mu - mu_lo) * inv_dmu, air.n_mu)
    ih, th = cell(h * inv_dh, air.n_s)

    def at(row, col):
        return packet(mi, dr, air.sun_rgb, row * air.n_s + col)
    lo = at(im, ih) * (1.0 - th) + at(im, ih + 1) * th
    hi = at(im + 1, ih) * (1.0 - th) + at(im + 1, ih + 1) * th
    return lo * (1.0 - tm) + hi * tm


def _phases(dr, air: EyeAir, cos_t):
    """(Rayleigh's phase function with depolarisation, the aerosol's Henyey-Greenstein) at cos_t, 1/sr."""
    from ..optics.phase.analytic import hg_value
    from ..optics.rayleigh import phase_value
    return phase_value(cos_t), hg_value(air.aerosol_g, cos_t)


def source_at(mi, air: EyeAir, o, d, shadow=None, diffuse: bool = False):
    """point(s) -> (extinction, source) (mi.Color3f, 1/m and 1/m/sr per unit irradiance above the air) at o + s d:
    the integrand of ``segment`` (its arguments)."""
    import drjit as dr
    p_r, p_a = _phases(dr, air, dr.dot(d, air.to_sun))
    q0 = o - air.centre + mi.Vector3f(0.0, 0.0, EARTH_RADIUS_M)  # from the Earth's centre

    def at(s):
        q = q0 + s * d
        r = dr.norm(q)
        h = dr.maximum(r - EARTH_RADIUS_M, 0.0)
        fh = h * air.h_step
        prof = lerp_rows(mi, dr, air.air, fh, air.n_h)  # (molecules, ozone, aerosol): one packet a row
        mol, ozone, aer, aer_sca = air.cross
        sca_r, sca_a = prof.x * mol, prof.z * aer_sca
        ext = sca_r + prof.y * ozone + prof.z * aer
        src = (sca_r * p_r + sca_a * p_a) * _sun_colour(mi, dr, air, h, dr.dot(q, air.to_sun) / r)
        if shadow is not None:  # the storm's shadow on the direct sun
            src *= shadow(o + s * d)
        if diffuse:  # the air's multiple scattering: beta_s J(h), isotropic (``air_multiple``)
            src += (sca_r + sca_a) * lerp_rows(mi, dr, air.diffuse, fh, air.n_h)
        return ext, src
    return at


def segment(mi, air: EyeAir, o, d, t0, t1, samples: int, squared: bool, diffuse: bool = False, shadow=None):
    """(T, S) (mi.Color3f) of the rays o + s d over [t0, t1] (module docstring; S per unit irradiance above
    the air, 1/sr; T = 1, S = 0 where t1 <= t0); o in the scene's frame. ``diffuse``: S also holds the
    air's multiple scattering (its scattering coefficient times ``EyeAir.diffuse``'s J(h), ``air_multiple``).
    ``shadow``: None, or the direct sun's transmittance through the storm at world points (mi.Point3f ->
    mi.Float), a factor on the sun's colour C(h, mu) (``eye_path.segment_air``'s ``shadow``)."""
    import drjit as dr
    length = dr.maximum(t1 - t0, 0.0)
    source = source_at(mi, air, o, d, shadow, diffuse)

    def point(i):
        x = mi.Float(i) * (1.0 / (samples - 1))
        s = t0 + length * (x * x if squared else x)
        return (s, *source(s))

    n = dr.width(t0)
    s, ext, src = point(mi.UInt32(0))
    state = (dr.full(mi.UInt32, 1, n), s, ext, src, dr.zeros(mi.Color3f, n), dr.full(mi.Color3f, 1.0, n),
             dr.zeros(mi.Color3f, n), length > 0)

    def body(i, s_prev, ext_prev, src_prev, tau, trans, S, active):  # trans = exp(-tau), carried: one exp a point
        s, ext, src = point(i)
        ds = s - s_prev
        tau_next = tau + 0.5 * (ext + ext_prev) * ds
        trans_next = dr.exp(-tau_next)
        S = S + 0.5 * (src_prev * trans + src * trans_next) * ds
        return i + 1, s, ext, src, tau_next, trans_next, S, active & (i + 1 < samples)

    trans, S = dr.while_loop(state, lambda *st: st[-1], body)[5:7]
    return trans, S


def profile(mi, air: EyeAir, o, d, t0, t1, samples: int, emit, shadow=None, active=None) -> None:
    """The cumulative ``segment`` (uniform, with the diffuse light, the same trapezoids) of the rays o + s d over
    [t0, t0 + x_k (t1 - t0)] at each of its points x_k = k / (samples - 1): ``emit(k, T_k, S_k)`` for k = 1 ..
    samples - 1 (k a mi.UInt32; T_0 = 1, S_0 = 0), called inside a symbolic loop (side effects only, e.g.
    ``dr.scatter``: all of them one kernel). ``active``: None, or the rays whose segment may be longer than 0
    (the others evaluate no point past t0: T = 1, S = 0 as their empty segment's; LLVM skips a packet of them)."""
    import drjit as dr
    length = dr.maximum(t1 - t0, 0.0)
    source = source_at(mi, air, o, d, shadow, True)
    if active is not None:
        zero = mi.Color3f(0.0)
        source_all = source
        source = lambda s: dr.if_stmt((s,), active, source_all, lambda s: (zero, zero))  # noqa: E731
    n = dr.width(t0)
    ext, src = source(t0)
    ds = length * (1.0 / (samples - 1))

    def body(k, ext, src, tau, trans, S):  # trans = exp(-tau), carried: one exp a point
        ext_next, src_next = source(t0 + length * (mi.Float(k) * (1.0 / (samples - 1))))
        tau_next = tau + 0.5 * (ext + ext_next) * ds
        trans_next = dr.exp(-tau_next)
        S = S + 0.5 * (src * trans + src_next * trans_next) * ds
        emit(k, trans_next, S)
        return k + 1, ext_next, src_next, tau_next, trans_next, S
    dr.while_loop((dr.full(mi.UInt32, 1, n), ext, src, dr.zeros(mi.Color3f, n), dr.full(mi.Color3f, 1.0, n),
                   dr.zeros(mi.Color3f, n)), lambda k, *_: k < samples, body)


def box_interval(mi, air: EyeAir, o, d):
    """(t_in, t_out) of the rays against the model's box (t >= 0; t_out <= t_in: a miss)."""
    import drjit as dr
    lo, hi = air.box
    inv = dr.rcp(dr.select(dr.abs(d) < 1e-12, 1e-12, d))
    t0, t1 = (lo - o) * inv, (hi - o) * inv
    a, b = dr.minimum(t0, t1), dr.maximum(t0, t1)
    return dr.maximum(dr.maximum(dr.maximum(a.x, a.y), a.z), 0.0), dr.minimum(dr.minimum(b.x, b.y), b.z)


def ray_ends(mi, air: EyeAir, o, d):
    """(t_in, t_out, t_end, hit, t_ground) of the rays: the box's chord (t_out clipped to t_end), where the
    ray ends (the ground or the top of the air), whether it crosses the box before it ends, the ground's
    distance (inf where the ray misses the ground)."""
    import drjit as dr
    t_in, t_out = box_interval(mi, air, o, d)
    q = o - air.centre + mi.Vector3f(0.0, 0.0, EARTH_RADIUS_M)
    b = dr.dot(q, d)
    c = dr.squared_norm(q) - (EARTH_RADIUS_M + _top_m()) ** 2
    t_top = dr.maximum(-b + dr.sqrt(dr.maximum(b * b - c, 0.0)), 0.0)
    t_ground = dr.full(mi.Float, dr.inf, dr.width(t_in))
    if air.ground:
        t_ground = dr.select(d.z < 0, (air.floor - o.z) / dr.select(d.z < 0, d.z, -1.0), dr.inf)
    t_end = dr.minimum(t_ground, t_top)
    hit = (t_out > t_in) & (t_in < t_end)
    return t_in, dr.minimum(t_out, t_end), t_end, hit, t_ground


def seen_through_air(mi, air: EyeAir, rays, radiance, transmittance, background, depth, shadow=None):
    """The eye pass's ``radiance`` (C + T L_bg, mi.Color3f) of ``rays`` seen through the air (module
    docstring), from its cloud ``transmittance`` T, ``background`` L_bg and cloud ``depth`` t_c (m);
    ``shadow``: the sun's direct light through the storm at world points (``segment``), used where
    ``air.shadow``."""
    import drjit as dr
    o, d = rays.origin, rays.direction
    t_in, t_out, t_end, hit, t_ground = ray_ends(mi, air, o, d)
    # the box: split at the cloud's depth (the box's entry where the ray meets no cloud)
    t_c = dr.clip(dr.select(transmittance < 1.0, depth, t_in), t_in, t_out)
    shadow = shadow if air.shadow else None
    t_f, s_f = segment(mi, air, o, d, dr.select(hit, t_in, 0.0), dr.select(hit, t_c, 0.0), SAMPLES_BOX, False, True,
                       shadow)
    behind = hit & (transmittance > OPAQUE_T)  # (behind an opaque cloud the air adds nothing seen: not integrated)
    t_b, s_b = segment(mi, air, o, d, dr.select(behind, t_c, 0.0), dr.select(behind, t_out, 0.0), SAMPLES_BOX,
                       False, True, shadow)
    e = air.irradiance
    if air.sky_air:  # the air behind the box, B = [box exit, ground or top], seen through the box and the cloud
        t_far, s_far = gauss_segment(mi, source_at(mi, air, o, d, outside_box(shadow), True), dr.select(behind, t_out, 0.0),
                                     dr.select(behind, t_end, 0.0), NODES, True)
        radiance, background = behind_box(e, s_far, t_far, radiance, transmittance, background)
    boxed = e * s_f + t_f * (radiance + transmittance * (e * s_b + (t_b - 1.0) * background))
    # outside: camera to the box (or to the ground or the top); none where the ray ends on the sky model's sky
    # without crossing the box (w = 0: not integrated); with the air's own sky, everywhere
    w = outside_weight(mi, air, transmittance, hit, t_ground)
    t_a, s_a = gauss_segment(mi, source_at(mi, air, o, d, outside_box(shadow), air.sky_air),
                             mi.Float(0.0) + 0.0 * t_in, dr.select(w > 0, dr.select(hit, t_in, t_end), 0.0), NODES, True)
    return boxed + w * (e * s_a + (t_a - 1.0) * boxed)


def outside_weight(mi, air: EyeAir, transmittance, hit, t_ground):
    """The weight w of the air outside the box in front of it (A, module docstring): 1, but where the ray ends on
    the sky model's sky (which holds its air) the box's cloud opacity 1 - T (0 where it misses the box); with the
    air's own sky (``EyeAir.sky_air``, whose sky is the air to the top) 1 everywhere."""
    import drjit as dr
    if air.sky_air:
        return mi.Float(1.0) + 0.0 * transmittance
    sky_end = ~dr.isfinite(t_ground)
    return dr.select(sky_end, dr.select(hit, 1.0 - dr.clip(transmittance, 0.0, 1.0), 0.0), 1.0)


def behind_box(e, s_far, t_far, radiance, transmittance, background):
    """(Radiance, background) of the eye pass with the air behind the box (S_B, T_B) in the background's place:
    L_bg' = E S_B + T_B L_bg, seen through the cloud (C + T L_bg'), as ``display.aerial``'s with ``sky_air``."""
    far = e * s_far + (t_far - 1.0) * background
    return radiance + transmittance * far, background + far


def light_shadow(mi, light, to_sun):
    """The storm's shadow at world points (mi.Point3f -> mi.Float) from the sun's bound light volume
    ``light`` (``LightVolume``, its direct light D): a point outside the slicing box reads D where its sun ray
    enters the box (where the sunlight leaves it towards the point, nudged 0.1% of the chord inside), 1 where
    the sun ray misses the box or leaves it behind the point; a point inside reads D there. Its ``outside``
    attribute: the same for points known to lie outside the slicing box (the eye rays' segments before the
    model's box), read from the light leaving the box on the point's light ray (the light volume's last plane:
    one bilinear read of a plane instead of two; the same light, as the planes beyond a light ray's last
    occupied slab hold it unchanged)."""
    import drjit as dr
    lo, hi = (mi.Point3f(*(float(v) for v in c)) for c in (light.lo, light.hi))

    inv = dr.rcp(dr.select(dr.abs(to_sun) < 1e-12, 1e-12, to_sun))  # once per frame, not per sample

    def towards_sun(p):
        """(t_in, t_out) of the sun rays from p against the slicing box (t_in >= 0)."""
        t0, t1 = (lo - p) * inv, (hi - p) * inv
        a, b = dr.minimum(t0, t1), dr.maximum(t0, t1)
        return dr.maximum(dr.maximum(dr.maximum(a.x, a.y), a.z), 0.0), dr.minimum(dr.minimum(b.x, b.y), b.z)

    def shadow(p):
        t_in, t_out = towards_sun(p)
        ahead = t_out > t_in
        t = t_in + 1e-3 * dr.maximum(t_out - t_in, 0.0)
        # D as the store holds it (its logarithm where it holds logarithms): no log or exp per texel; a packet
        # of lanes whose sun rays all miss the box reads nothing (LLVM branches per packet)
        return dr.if_stmt((p + t * to_sun, ahead), ahead,
                          lambda q, a: light.lookup(q, log_direct=light.log_store, active=a)[0],
                          lambda q, a: mi.Float(1.0))

    def outside(p):
        t_in, t_out = towards_sun(p)
        ahead = t_out > t_in
        return dr.if_stmt((p, ahead), ahead,
                          lambda q, a: light.lookup(q, exit_plane=True, log_direct=light.log_store, active=a)[0],
                          lambda q, a: mi.Float(1.0))
    shadow.outside = outside
    return shadow


def outside_box(shadow):
    """``light_shadow``'s function for points outside the slicing box (None stays None)."""
    return getattr(shadow, "outside", shadow)


def _top_m() -> float:
    from ..optics.air.eye_path import TOP_M
    return TOP_M


__all__ = ["EyeAir", "HEIGHT_STEP_M", "SAMPLES_BOX", "box_interval", "eye_air_input", "source_at",
           "behind_box", "cross_sections", "height_grid", "outside_weight", "height_table", "light_shadow", "outside_box", "profile", "ray_ends",
           "seen_through_air", "segment"]
