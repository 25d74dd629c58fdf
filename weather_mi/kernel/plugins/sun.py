"""The integrator's own sun: a uniform disk of angular diameter ``sun_angular_diameter`` (or a point),
sampled at every vertex and weighted by MIS against the path's continuation; optional sun guiding and
aureole next-event estimation.

* :func:`sun_disk`: v_max = 1 - cos r (held as a versine for float32) and the disk's radiance
  L = E / (pi sin^2 r), E the irradiance normal to the beam, so that the disk's irradiance equals the
  point sun's. A direction uniform in the disk has pdf p_sun = 1 / (2 pi v_max).
* :func:`continuation_pdf`: the pdf q with which a medium vertex continues the path: history-aware
  channel sampling (Kutz et al. 2017: channel c with probability alpha_c = T_c / sum T, so
  q = sum_c alpha_c p_c(d)) and sun guiding (detector-directional importance sampling as in MYSTIC's
  VROOM, Buras & Mayer 2011): q = (1 - eps) q_phase + eps (q_phase,sun + U_disk) / 2.
* :func:`aureole_nee`: sun light that reaches a vertex A through one more, forward, scattering at B,
  sampled from A about the sun; balance heuristic against the path's own draw.
* :func:`parse_air`, :func:`radiance_at`: the air on the sun's path (``sun_air``, optional): the sun's
  value at a point is multiplied by the colour of the direct sun there, bilinear in a table over the
  point's height above a spherical Earth and the sun's cos(zenith) at it (``optics.air.sunlight``), the
  Earth's centre at (0, 0, -``sun_air_radius``) in the kernel's frame.

``sun`` is the integrator (its ``sun_dir``, ``sun_vmax``, ``sun_value``, ``sun_mode``, ``guiding``);
measurements of these estimators: ``docs/reference-estimator.md``.
"""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

from . import air
from .medium_setup import phase_ctx, scattering_event
from .spectral_sun import SpectrumTable
from .trackers import delta_tracking


def sun_disk(diameter_deg: float, irradiance) -> tuple[float, np.ndarray]:
    """The versine and the radiance of a uniform sun disk.

    Parameters
    ----------
    diameter_deg : float
        Angular diameter of the disk, degrees (0: a point sun).
    irradiance : array_like
        Irradiance E on a plane normal to the disk's centre, RGB (W m^-2, or any unit).

    Returns
    -------
    v_max : float
        1 - cos(radius), computed as 2 sin^2(r/2) (float32 cannot hold 1 - cos of a quarter degree).
    radiance : numpy.ndarray
        L = E / (pi sin^2 r) (E per steradian), because the disk gives integral_cap L cos(theta) d omega
        = pi sin^2(r) L on that plane. (0, E) for a point sun.
    """
    e = np.asarray(irradiance, np.float64)
    r = np.radians(float(diameter_deg)) / 2.0
    if r <= 0.0:
        return 0.0, e
    return float(2.0 * np.sin(r / 2.0) ** 2), e / (np.pi * np.sin(r) ** 2)


AIR_PROPERTIES = ("sun_air", "sun_air_h0", "sun_air_h1", "sun_air_mu0", "sun_air_mu1", "sun_air_radius")
LIGHT_PROPERTIES = AIR_PROPERTIES + ("sun_spectrum", "sun_spectrum_nm", air.BOX_PROPERTY)  # all need the integrator's sun


def parse_air(sun, props, check) -> None:
    """The air's table on the sun's path: ``sun_air`` (n_mu, n_h, 3) RGB transmittance colours (>= 0) on
    the uniform grids h0..h1 (m above sea level) by mu0..mu1 (cos zenith), ``sun_air_radius`` the Earth's
    (m); ``sun.air`` None without it. Spectral variants: ``sun_spectrum`` (:func:`parse_spectrum`) and
    ``sun_air`` (n_mu, n_h, n_lambda) the sun's spectrum after the air on the same grid."""
    sun.air, sun.air_box = None, None
    parse_spectrum(sun, props, check)
    if "sun_air" not in props:
        check(air.BOX_PROPERTY not in props, f"'{air.BOX_PROPERTY}' needs the air's table 'sun_air'")
        return
    for name in AIR_PROPERTIES:
        check(name in props, f"'sun_air' needs '{name}'")
    t = np.asarray(props["sun_air"], np.float32)
    n_c = sun.spectrum_shape[2] if sun.spectrum is not None else 3
    check(t.ndim == 3 and t.shape[2] == n_c and min(t.shape[:2]) >= 2 and np.all(np.isfinite(t)) and t.min() >= 0.0,
          f"'sun_air' must be a finite, non-negative (n_mu >= 2, n_h >= 2, {n_c}) tensor, got shape {t.shape}")
    h0, h1, mu0, mu1, radius = (float(props[n]) for n in AIR_PROPERTIES[1:])
    check(h1 > h0 and mu1 > mu0 and radius > 0.0, "'sun_air' needs h1 > h0, mu1 > mu0 and a positive radius")
    if sun.spectrum is not None:  # one table over (mu, h, lambda) in place of the top-of-atmosphere one
        sun.spectrum_air = True
    else:
        sun.air = mi.Texture2f(mi.TensorXf(t), use_accel=False,  # CUDA: float interpolation weights, not 8-bit
                               filter_mode=dr.FilterMode.Linear, wrap_mode=dr.WrapMode.Clamp)
    n_mu, n_h = t.shape[:2]
    # texel centres at (i + 0.5) / n: coordinate = (v - v0) / (v1 - v0) (n - 1) / n + 0.5 / n
    sun.air_map = [mi.Float(v) for v in (h0, (n_h - 1) / (n_h * (h1 - h0)), 0.5 / n_h,
                                         mu0, (n_mu - 1) / (n_mu * (mu1 - mu0)), 0.5 / n_mu, radius)]
    dr.make_opaque(*sun.air_map)
    if sun.spectrum is not None:
        sun.spectrum = SpectrumTable(t, sun.spectrum_nm, (h0, h1), (mu0, mu1))
    air.parse_box(sun, props, check)  # the air inside the box is tracked: the table where the sun ray leaves it


def parse_spectrum(sun, props, check) -> None:
    """Spectral variants: ``sun_spectrum`` (n_lambda,) the sun's spectral irradiance (any unit) on the uniform
    grid ``sun_spectrum_nm`` (first, last wavelength in nm), times ``sun_value``; ``sun.spectrum`` None in
    RGB variants (where it must not be given)."""
    sun.spectrum, sun.spectrum_air = None, False
    if not mi.is_spectral:
        check("sun_spectrum" not in props, f"'sun_spectrum' needs a spectral variant, not {mi.variant()!r}")
        return
    check("sun_spectrum" in props and "sun_spectrum_nm" in props,
          f"the integrator's sun in {mi.variant()!r} needs 'sun_spectrum' and 'sun_spectrum_nm'")
    e = np.asarray(props["sun_spectrum"], np.float32).ravel()
    nm = np.asarray(props["sun_spectrum_nm"], np.float64).ravel()
    check(e.size >= 2 and np.all(np.isfinite(e)) and e.min() >= 0.0 and nm.size == 2 and nm[1] > nm[0],
          f"'sun_spectrum' must be >= 2 finite values >= 0 on 'sun_spectrum_nm' = (first, last) nm; got {e.size}, {nm}")
    sun.spectrum_shape = (1, 1, e.size)
    sun.spectrum_nm = (float(nm[0]), float(nm[1]))
    sun.spectrum = SpectrumTable(e.reshape(1, 1, -1), sun.spectrum_nm)


def _height_mu(sun, p):
    """(The height of p above the sphere, the sun's cos(zenith) at p) (``sun_air_radius``); with the air in
    the box (``sun_air_box``) at the point where the sun ray from p leaves the box."""
    *_, radius = sun.air_map
    if sun.air_box is not None:
        p = air.sun_exit_point(sun, p)
    q = mi.Vector3f(p.x, p.y, p.z + radius)  # from the Earth's centre
    r = dr.norm(q)
    h = (dr.square(p.x) + dr.square(p.y) + p.z * (p.z + 2.0 * radius)) * dr.rcp(r + radius)  # r - R, no cancellation
    return h, dr.dot(q, sun.sun_dir) * dr.rcp(r)


def _spectral_radiance(sun, p, wavelengths):
    """The sun's value at the lanes' ``wavelengths``: ``sun_value`` x the spectrum (after the air at p)."""
    if not sun.spectrum_air:  # the top-of-atmosphere spectrum only: one row in height and mu
        hm = mi.Float(0.0), mi.Float(0.0)
    else:
        hm = _height_mu(sun, p)
    return mi.Spectrum(*sun.spectrum.eval(hm[0], hm[1], wavelengths)) * sun.sun_value


def radiance_at(sun, p, wavelengths=None):
    """The sun's value (radiance of the disk, or irradiance of a point sun) at point ``p``: ``sun_value``,
    times the air's colour at p's height and the sun's cos(zenith) there where ``sun_air`` is given
    (spectral variants: at the lanes' ``wavelengths``, :func:`parse_spectrum`)."""
    if sun.spectrum is not None:
        return _spectral_radiance(sun, p, wavelengths)
    value = mi.Spectrum(sun.sun_value)
    if sun.air is None:
        return value
    h0, h_scale, h_off, mu0, mu_scale, mu_off, radius = sun.air_map
    h, mu = _height_mu(sun, p)
    c = sun.air.eval(mi.Point2f((h - h0) * h_scale + h_off, (mu - mu0) * mu_scale + mu_off))
    return value * mi.Spectrum(c[0], c[1], c[2])


def sample_disk(sun, sample):
    """A direction uniform in the sun's disk (a cap of versine v_max about ``sun_dir``), built from
    the versine so that float32 keeps its angle (pdf 1 / (2 pi v_max))."""
    v = sample.x * sun.sun_vmax
    sin_t = dr.safe_sqrt(v * (2.0 - v))
    s, c = dr.sincos(dr.two_pi * sample.y)
    return mi.Frame3f(sun.sun_dir).to_world(mi.Vector3f(sin_t * c, sin_t * s, 1.0 - v))


def sun_direction(sun, sampler, active):
    """The direction of a sun next-event estimate: uniform in the disk, or the point sun's."""
    return sample_disk(sun, sampler.next_2d(active)) if sun.sun_mode == "disk" else mi.Vector3f(sun.sun_dir)


def in_disk(sun, d):
    """Whether unit direction d lies in the sun's disk: versine |d - s|^2 / 2 <= v_max."""
    return dr.squared_norm(d - sun.sun_dir) * 0.5 <= sun.sun_vmax


def about_sun(sun, mei, toward_sun):
    """``mei`` whose incident direction is replaced, where ``toward_sun``, by the one for which the
    phase function's forward direction is the sun's direction (wi = -sun_dir)."""
    m = mi.MediumInteraction3f(mei)
    m.wi = dr.select(toward_sun, -mi.Vector3f(sun.sun_dir), mei.wi)
    m.sh_frame = mi.Frame3f(m.wi)
    return m


def continuation_pdf(sun, phase, sampler, mei, d, value, pdf, alpha, eps, active):
    """pdf with which a medium vertex continues the path in direction d, given the phase function's
    per-channel ``value`` and its own ``pdf`` there:
    * history-aware channels (``alpha`` not None): sum_c alpha_c p_c(d), channel c drawn with
      probability alpha_c and d from its density;
    * sun guiding (detector-directional importance sampling, Buras & Mayer 2011): d drawn about the
      path's direction with probability 1 - eps and towards the sun with probability eps (eps per
      vertex, see ``sample``), half of these uniform in the sun's disk U and half from the phase
      function about the sun: (1 - eps) q(d | wi) + eps (q(d | -sun) + U(d)) / 2."""
    def q(val, p):
        return p if alpha is None else dr.sum(alpha * val)
    out = q(value, pdf)
    if sun.guiding > 0.0 and sun.sun_mode != "none":
        val_s, pdf_s = phase.eval_pdf(phase_ctx(sampler), about_sun(sun, mei, mi.Bool(True)), d, active)
        guide = q(val_s, pdf_s)
        if sun.sun_mode == "disk":  # half of the guided draws are uniform in the disk
            disk = dr.select(in_disk(sun, d), dr.rcp(dr.two_pi * sun.sun_vmax), 0.0)
            guide = 0.5 * (guide + disk)
        out = (1.0 - eps) * out + eps * guide
    return out


def aureole_pdf(sun, phase, sampler, mei, d, active):
    """Density of the aureole estimator's direction at vertex ``mei``: the phase function (channel
    mean) about the sun's direction, with half of it uniform in the disk for a disk sun."""
    _, g = phase.eval_pdf(phase_ctx(sampler), about_sun(sun, mei, mi.Bool(True)), d, active)
    if sun.sun_mode == "disk":
        disk = dr.select(in_disk(sun, d), dr.rcp(dr.two_pi * sun.sun_vmax), 0.0)
        g = 0.5 * (g + disk)
    return g


def aureole_nee(sun, tk, transmittance, scene, sampler, phase, mei, medium, throughput, alpha, eps, active,
                result, sun_mis, c_sun, sun_pdf):
    """The aureole estimator at medium vertex A (``mei``): direction d about the sun (density g,
    :func:`aureole_pdf`), free flight to B, sun next-event estimation at B weighted as the path
    itself weights it there. Balance heuristic against the path's own draw (density q, sum over
    channels of alpha_c p_c): this contributes T f_A(d) / (q(d) + eps g(d)) x (NEE at B), and the
    path's own sun NEE at B is weighted q / (q + eps g) (``aur_w``)."""
    ctx = phase_ctx(sampler)
    d, _, _ = phase.sample(ctx, about_sun(sun, mei, active), sampler.next_1d(active), sampler.next_2d(active),
                           active)
    if sun.sun_mode == "disk":
        u = sampler.next_1d(active)
        d = dr.select(u < 0.5, sample_disk(sun, sampler.next_2d(active)), d)
    f_a, p_a = phase.eval_pdf(ctx, mei, d, active)
    q = p_a if alpha is None else dr.sum(alpha * f_a)
    g = aureole_pdf(sun, phase, sampler, mei, d, active)
    denom = q + eps * g
    active &= denom > 0.0
    weight = throughput * f_a * dr.rcp(dr.select(active, denom, 1.0))
    ray = mei.spawn_ray(d)
    si = scene.ray_intersect(ray, active)
    found, t, weight = delta_tracking(tk, ray, dr.minimum(si.t, ray.maxt), sampler, active, weight)
    act_b = active & found
    mei_b, albedo = scattering_event(tk.ms, ray, t, act_b)
    wo = sun_direction(sun, sampler, act_b)
    f_b, _ = phase.eval_pdf(ctx, mei_b, wo, act_b)
    if sun.sun_mode == "disk":  # the MIS weight the path's own NEE has at B, times 1 / pdf_sun
        w_b = sun_mis(c_sun * sun_pdf, dr.mean(f_b)) * dr.rcp(sun_pdf)
    else:
        w_b = mi.Float(1.0)
    tr = transmittance(scene, sampler, mei_b.spawn_ray(wo), medium, act_b)
    return dr.select(act_b, result + weight * albedo * f_b * w_b * tr * radiance_at(sun, mei_b.p, mei_b.wavelengths),
                     result)
