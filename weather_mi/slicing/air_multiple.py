"""The air's multiple scattering along the slicer's eye rays in the box (issue 38 part 3): the source of the light
the air scatters more than once, a table by height for the frame's sun, read per point as the sun's colour is.

In a horizontally homogeneous clear atmosphere the radiance the air adds along a ray obeys the radiative transfer
equation with the source beta_s(h) [P(theta) C(h, mu) + J(h)] (per unit irradiance of the sun above the air):
the direct sun scattered once (``eye_air.source_at``) and the diffuse light (sun and ground, all orders) scattered
again, approximated as isotropic: J(h) = (1/4 pi) int L_diffuse dOmega, the diffuse light's mean intensity (the
isotropic part of any phase function's in-scattering; Rayleigh's second moment and the aerosol's forward lobe act
on the anisotropic part). J is DISORT's (``optics.air.skylight.diffuse_source_table``: the 1-D atmosphere's layers,
a Lambertian ground of the scene's albedo, per unit irradiance of the sun) at the slicer's channels' wavelengths
(``optics.air.inside.CHANNEL_NM``) times the top-of-atmosphere sun's colour (the channels' unit, as ``sun_table``'s
C(h, mu)): Hillaire (2020)'s multiple-scattering term, with the mean intensity solved by DISORT instead of his
isotropic geometric series (plane-parallel, the sun at the cosine whose air mass is the spherical Earth's,
``effective_mu0``; a spherical Earth's twilight is not in it: below the horizon J is 0).

The table: nodes over cos(zenith) ``MU_NODES``, each a DISORT solve per channel (0.05 s) cached per atmosphere,
ground height and albedo (computed when a frame first needs them: an atmosphere costs a frame the two nodes
around its sun, a sun drag a node when it crosses into a new interval); the frame's J(h) is linear between the
two nodes, on ``eye_air``'s height grid (``HEIGHT_STEP_M``), uploaded as one packet of 4 floats a row (a frame
input: a new sun uploads values and compiles nothing).

Against DISORT's own path radiance (``validation/seen_through_air.py``'s independent atmosphere, Eq. 2: I(camera)
- T I(end)) on 30-100 km near-level rays at 1-13 km under a 35 deg and a 6 deg sun: tests/test_slicing_air_multiple.py.
"""
from __future__ import annotations

import functools

import numpy as np

from ..optics.air.sun_nodes import MU_NODES, between_nodes  # the sun's cosines of the table's nodes, J linear between


@functools.lru_cache(maxsize=64)
def _node(atm, mu0: float, ground_m: float, albedo: float) -> tuple[np.ndarray, np.ndarray]:
    """(heights (m), J (n, 3)): DISORT's mean intensity of the diffuse light per unit irradiance of the sun above
    the air at the channels' wavelengths (``diffuse_source_table``: every 500 m from the ground to 30 km)."""
    from ..optics.air.inside import CHANNEL_NM
    from ..optics.air.skylight import diffuse_source_table
    table = diffuse_source_table(atm, mu0, ground_m, albedo, CHANNEL_NM)
    return table.heights_m, table.rgb[0].astype(np.float64)


def mean_intensity(atm, mu0: float, heights_m, ground_m: float = 0.0, albedo: float = 0.15) -> np.ndarray:
    """(n, 3): the diffuse light's mean intensity J at ``heights_m`` (m above sea level; held at the DISORT
    table's ends beyond it) per unit irradiance of the sun above the air, at the channels' wavelengths, for a sun
    at cos(zenith) ``mu0`` (linear between ``MU_NODES``; under the lowest node the lowest node's value times
    mu0 / MU_NODES[0], 0 below the horizon), a ground at ``ground_m`` of ``albedo`` (one number: DISORT's
    surface is grey)."""
    h = np.asarray(heights_m, np.float64)
    key = (round(float(ground_m), 3), round(float(albedo), 6))

    def at(node):
        z, j = _node(atm, float(node), *key)
        return np.stack([np.interp(h, z, j[:, c]) for c in range(3)], axis=-1)
    return between_nodes(mu0, at)


def effective_mu0(mu0: float) -> float:
    """The plane-parallel sun's cosine whose slant column through the air is the spherical Earth's: 1 / m, m
    Kasten & Young (1989)'s relative air mass, m = 1 / (mu0 + 0.50572 (96.07995 - theta)^-1.6364), theta the zenith
    angle in degrees (0.113 at a 6 deg sun for mu0 0.105; the same within 0.1% above 30 deg); 0 below the horizon."""
    if mu0 <= 0.0:
        return 0.0
    theta = float(np.degrees(np.arccos(min(float(mu0), 1.0))))
    return float(mu0 + 0.50572 * (96.07995 - theta) ** -1.6364)


def diffuse_input(mi, spec, reuse, heights_m, sun_top):
    """The frame's J table (mi.Float, n x 4: one packet a row, ``packets.packed``; 64-byte aligned, a frame
    input) on ``heights_m`` for ``spec``'s atmosphere, sun and ground (none: albedo 0 at sea level; no sky: J = 0,
    as the path tracer's scene without a sky has no diffuse light from the air around the box), times
    ``sun_top`` (the sun's colour above the air: the unit of ``eye_air.sun_table``'s C(h, mu)); ``reuse``: the
    renderer's (kept while the atmosphere, the sun's cosine and the ground are the same). The ground is the
    reference's (``kernel.air_sky.ground_boundary``: at least sea level); the sun's cosine is ``effective_mu0``
    (Kasten-Young) where the reference's aerial J (``display.aerial._diffuse_table``) takes the raw mu0: they
    differ by over 1 % below 20 deg of elevation (0.113 against 0.105 at 6 deg)."""
    from ..kernel.air_sky import ground_boundary
    from ..kernel.jitarrays import aligned_float
    from .packets import packed
    ground_m, albedo = ground_boundary(spec)  # the reference's DISORT ground: at least sea level
    lit = spec.sky is not None  # no sky: the scene has no diffuse light from the air around the box (J = 0)
    key = (spec.atmosphere, float(spec.sun.mu0), ground_m, albedo, lit)
    mu = effective_mu0(key[1]) if lit else 0.0
    j = lambda: mean_intensity(spec.atmosphere, mu, heights_m, ground_m, albedo) * sun_top  # noqa: E731
    return reuse("air multiple", key, lambda: aligned_float(mi, packed(j().astype(np.float32))))


__all__ = ["MU_NODES", "diffuse_input", "effective_mu0", "mean_intensity"]
