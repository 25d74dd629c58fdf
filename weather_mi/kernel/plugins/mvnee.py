"""Multiple-vertex next-event estimation towards the integrator's sun (after Weber, Hanika & Dachsbacher
2017, "Multiple Vertex Next Event Estimation for Lighting in dense, forward-scattering Media", CGF
36(2)): from a medium vertex A, with probability eps, a chain of up to K further vertices A -> X_1 ->
... -> X_K is built towards the sun, every direction drawn about the sun (density g, as the aureole
estimator: :func:`.sun.aureole_pdf`) and every distance by free flight (delta tracking), with a sun
next-event estimate at each X_j. For a sun at infinity Weber's seed path (a straight line to a light
point, perturbed) has no end point; here each chain vertex turns the path towards the sun's
direction instead, the chain's length is K (``mvnee_length``), and K = 1 is the aureole estimator's
chain (with different MIS weights).

MIS (balance heuristic over the techniques "the path's own sun NEE at X_n" and "the chain of length
j launched at X_{n-j}", j = 1..K). Their densities differ only in the last j directions (distances are
sampled alike): with rho_i = g_i(d_i) / fbar_i(d_i) (fbar: the channel mean of the phase function, a
function of the vertex and the two directions only, so path and chains compute the same weights),
R_j(n) = eps prod_{i=n-j}^{n-1} rho_i, the path's sun NEE at X_n is weighted 1 / (1 + sum_j R_j) and a
chain's at X_n, launched j vertices back, R_j / (1 + sum_j R_j). These weights sum to one for every
path whatever the path's own sampling (channels by history, roulette), so the sum is unbiased. The
path carries R_1..R_K (``mv_r``, a Vector4f: K <= MAX_LENGTH): R_1(n+1) = eps rho_n, R_{j+1}(n+1) =
R_j(n) rho_n; a surface vertex sets them to 0 (a chain does not cross surfaces).
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .medium_setup import phase_ctx, scattering_event
from .sun import about_sun, aureole_pdf, radiance_at, sample_disk, sun_direction
from .trackers import delta_tracking

MAX_LENGTH = 4  # chain vertices at most (the path state holds R_1..R_4)
DEFAULT_LENGTH = 2


def parse(props, check) -> tuple[float, int]:
    """(eps, K) from the properties ``mvnee`` (probability in [0, 1]) and ``mvnee_length`` (1..MAX_LENGTH);
    ``check(ok, message)`` raises."""
    eps = float(props.get("mvnee", 0.0))
    check(0.0 <= eps <= 1.0, f"'mvnee' must be a probability in [0, 1], got {eps}")
    length = props.get("mvnee_length", DEFAULT_LENGTH)
    check(isinstance(length, int) and not isinstance(length, bool) and 1 <= length <= MAX_LENGTH,
          f"'mvnee_length' must be an integer in [1, {MAX_LENGTH}], got {length!r}")
    return eps, int(length)


def zeros():
    """R_1..R_MAX_LENGTH of a path with no medium vertex since its last surface."""
    return mi.Vector4f(0.0)


def direction(sun, phase, ctx, sampler, mei, active):
    """A direction about the sun at ``mei``: half from its phase function centred on the sun, half uniform
    in the disk (all from the phase function for a point sun); density :func:`.sun.aureole_pdf`."""
    d, _, _ = phase.sample(ctx, about_sun(sun, mei, active), sampler.next_1d(active), sampler.next_2d(active),
                           active)
    if sun.sun_mode == "disk":
        u = sampler.next_1d(active)
        d = dr.select(u < 0.5, sample_disk(sun, sampler.next_2d(active)), d)
    return d


def ratio(g, f):
    """rho = g / fbar (0 where the phase function vanishes)."""
    fbar = dr.mean(f)
    return dr.select(fbar > 0.0, g * dr.rcp(dr.select(fbar > 0.0, fbar, 1.0)), 0.0)


def advance(r, eps, rho, length: int):
    """R_1..R_K at the next vertex: R_1 = eps rho, R_{j+1} = R_j rho (components past K stay 0)."""
    c = [eps * rho] + [r[j - 1] * rho for j in range(1, length)] + [mi.Float(0.0)] * (MAX_LENGTH - length)
    return mi.Vector4f(*c)


def path_weight(r):
    """MIS weight of the path's own sun NEE: 1 / (1 + sum_j R_j)."""
    return dr.rcp(1.0 + r[0] + r[1] + r[2] + r[3])


def path_update(sun, phase, sampler, mei, wo, ph_val, eps, length, r, active):
    """The path's R after it continued from medium vertex ``mei`` in direction ``wo`` (phase value
    ``ph_val`` per channel)."""
    g = aureole_pdf(sun, phase, sampler, mei, wo, active)
    return dr.select(active, advance(r, eps, ratio(g, ph_val), length), r)


def chain(loop, sampler, v, p, eps: float, length: int, active):
    """The chain's contributions added to the path's ``result``: launched at medium vertex ``v.mei``
    (where ``active``, drawn with probability eps), up to ``length`` vertices, a sun NEE at each."""
    integ, phase, ctx = loop.integ, loop.phase, phase_ctx(sampler)
    mei, r, act = v.mei, mi.Vector4f(p.mv_r), mi.Bool(active)
    weight = p.throughput * (1.0 / eps)  # the chain is launched with probability eps
    result = mi.Spectrum(p.result)
    for j in range(length):
        act &= p.depth + (j + 1) < loop.max_depth
        d = direction(integ, phase, ctx, sampler, mei, act)
        f, _ = phase.eval_pdf(ctx, mei, d, act)
        g = aureole_pdf(integ, phase, sampler, mei, d, act)
        act &= g > 0.0
        r = dr.select(act, advance(r, eps, ratio(g, f), length), r)
        weight = weight * f * dr.rcp(dr.select(act, g, 1.0))
        ray = mei.spawn_ray(d)
        si = loop.scene.ray_intersect(ray, act)
        found, t, weight = delta_tracking(loop.tk, ray, dr.minimum(si.t, ray.maxt), sampler, act, weight)
        act &= found
        mei, albedo = scattering_event(loop.ms, ray, t, act)
        weight = weight * albedo
        wo = sun_direction(integ, sampler, act)
        f_x, _ = phase.eval_pdf(ctx, mei, wo, act)
        if integ.sun_mode == "disk":  # the sun MIS weight the path's own NEE has there, over pdf_sun
            w_x = loop.sun_mis(loop.c_sun * loop.sun_pdf, dr.mean(f_x)) * dr.rcp(loop.sun_pdf)
        else:
            w_x = mi.Float(1.0)
        w_x *= r[j] * path_weight(r)  # this chain's share: R_{j+1} / (1 + sum R)
        tr = loop.transmittance(loop.scene, sampler, mei.spawn_ray(wo), p.medium, act)
        result = dr.select(act, result + weight * f_x * w_x * tr * radiance_at(integ, mei.p, mei.wavelengths), result)
    return result
