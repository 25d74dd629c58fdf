"""One direction drawn within a node segment of a piecewise-linear phase density (``hydrometeor_mixture``'s
draws by channel, ``lane_directions``' by wavelength): the versine v = 1 - cos(Theta) inverted from the
segment's linear density, then the direction about the incident one."""
from __future__ import annotations

import drjit as dr
import mitsuba as mi


def invert(v0, v1, f0, f1, r):
    """(v, t): the versine at which the segment's linear density (``f0`` at ``v0``, ``f1`` at ``v1``) reaches
    the fraction ``r`` in [0, 1] of its mass, and t = (v - v0) / (v1 - v0); the stable root of
    f0 x + (f1 - f0) x^2 / (2 dv) = r (f0 + f1) dv / 2, x in [0, dv] (uniform where both values are 0)."""
    dmu = v1 - v0
    rr = r * 0.5 * (f0 + f1) * dmu
    a = (f1 - f0) / (2.0 * dmu)
    disc = dr.maximum(f0 * f0 + 4.0 * a * rr, 0.0)
    x = dr.select(f0 + dr.sqrt(disc) > 0.0, 2.0 * rr / (f0 + dr.sqrt(disc)), r * dmu)
    x = dr.clip(x, 0.0, dmu)
    return dr.clip(v0 + x, 0.0, 2.0), dr.clip(x / dr.maximum(dmu, 1e-30), 0.0, 1.0)


def direction(mei, v, u_phi):
    """The world direction at versine ``v`` from the forward direction -``mei.wi``, at azimuth 2 pi ``u_phi``."""
    cos_theta = 1.0 - v
    sin_theta = dr.safe_sqrt(v * (2.0 - v))
    sin_phi, cos_phi = dr.sincos(2.0 * dr.pi * u_phi)
    return mei.to_world(mi.Vector3f(sin_theta * cos_phi, sin_theta * sin_phi, -cos_theta))
