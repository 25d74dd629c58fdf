"""The eye pass: every pixel ray visits the slice planes it crosses and composites the light scattered
towards the camera (Eq. 9 with the Eq. 8 mixture phase), then adds the background seen through the
cloud (the sky, or the ground lit by the light volume).

At a sample with extinction beta, scattering coefficients beta_sca,g per group of species that scatter
alike (same phase table and colour), light-volume values (A, B) and path length de across the slab:
    C += T (1 - exp(-beta de)) / beta  sum_g beta_sca,g [P_g(Theta) A + B / (4 pi)] colour_g E_sun
         + T (1 - exp(-beta de)) / beta  beta_sca  L_amb  occlusion,          T *= exp(-beta de)
with (A, B) = (direct, forward-scattered) light for the paper's modes (the direct beam scattered with
the phase function, the blurred forward light as if diffuse, as in Kniss et al.), and for the
"multiple" model the scattering octaves of Wrenninge et al. (2013), driven by the optical depth tau
towards the sun read from the same light volume (direct light D = exp(-tau)):
    A = D + (1 - D_col) sum_{i>=1} (b c)^i D^(a^i),
    B = (1 - D_col) sum_{i>=1} b^i (1 - c^i) D^(a^i) + k J(tau, tau_col)
(octave i: optical depth a^i tau, weight b^i, phase c^i P + (1 - c^i) / (4 pi); octave 0 is single
scattering; D_col = exp(-tau_col): the sunlight that crosses the whole cloud column along the sun ray, so
that thin clouds, which scatter light once rather than many times, get little multiple scattering), plus
a diffusion term beyond the octaves: k (``diffusion_gain``) times the 1-D diffusion profile J of that
column (``diffusion_profile``), which, unlike the octaves, is not capped by a geometric sum and does not
decay exponentially into a thick cloud (in a conservative cloud diffused light falls linearly with depth,
and it is brighter just inside a sunlit face than at it), while thin clouds get little of it; and
``leak_gain`` times the diffused light of a finite cloud that loses light through its sides
(``leaking_diffusion``: exp(-leak_rate x) in the same transport depths), bright at sunlit faces and dark
in shadowed parts, which the 1-D profile of an infinite slab is not (residuals by region on the training
storms, validation/slicer_residuals.py: the sunlit faces' luminance bias went from -19% to -11% with it,
refitted). Both diffusion terms are scattered towards the eye with their flux along the sun ray
(``diffused_towards_eye``: the P1 radiance (phi + 3 F . w) / (4 pi), weight ``flux``): light flowing through a
cloud away from the sun brightens its shadowed side seen against the sun (back-lit rims and cores, which
the residuals by region found 23% and 11% too dark in the held-out back-lit views); at a thick cloud's faces
it is Eddington's law I(mu) / I(0) = 1 + 3/2 mu. In a cloud of
asymmetry g ~ 0.85 the diffused light keeps travelling along the sunlight for about a transport mean free
path before its direction is forgotten: a part ``diffusion_lobe`` x exp(-x) of it (x: transport depth from
the sun's side) is scattered with the phase function instead of isotropically (moved from B to A, the
energy unchanged), so that front- and side-lit faces, where P(Theta) < 1 / (4 pi), are dimmer and back-lit
rims and thin cores brighter (issue 41: the held-out front- and side-lit cumuli were 12-15% too bright, the
back-lit ones 18-19% too dark; median CIEDE2000 4.34 -> see validation/README.md). The diffused light
entered its cloud through a lit face, and the flux through a face is E cos i, i the sun's angle from its
normal (``diffusion_incidence``, ``incidence_cosine``, Eq. D2: cos i from the optical depths towards the sun and
the zenith, mu0 throughout a horizontal layer): the diffusion runs along that normal, depths x cos i, and
carries cos i of the face-on light (``diffusion_profile``, Eq. D1; the exponential source's exact solution
beyond its mean depth). Without it, a wide layer under a 6 deg sun is lit as if its top faced the sun:
its interior diffused light ~20x the plane-parallel value (mu0 (mu0 + z0) / (1 + z0) = 0.046), which made the
held-out storms at a low sun too bright and, with the air's reddened sun, too red (issue 38). The medium is the one the path tracer renders: phase-function peaks within 3 deg count as
unscattered light (delta-M, ``weather_mi.optics.forward_peak``; ``SliceRenderer(forward_peak_deg=)``). The model reads optical depths from the
light volumes interpolated as depths (``LightVolume.lookup(log_direct=True)``: linear between two planes of a
homogeneous slab, where the light is not), and takes the diffusion profile, which is linear in depth, at the
eye-weighted mean position of the eye's segment (``SlabAverage.mean_offset``); in the eye pass it takes the
sunlight carried from the plane before the sample through the medium (``LightVolume.carried``: a cloud's
lit face between two planes lies where it is) and the decay rate from the local extinction. The paper's
translucent light interpolates all forward light as its logarithm (``lookup(log_forward=True)``). Slabs
that are optically thick along the eye ray are composited in sub-segments (``EYE_SPLIT``). L_amb is the
sky's mean radiance times ``ambient`` (paper modes, unshadowed). The "multiple" model's diffuse light is
``sky_gain`` x [the sky's mean radiance x T(k tau_up) + the lit ground's radiance rho / pi (E_sun mu0 + E_sky) x
T(k tau_down)], tau_up the optical depth towards the zenith (the zenith light volume), tau_down the column
below (that volume's whole column less tau_up), T the delta-Eddington transmission of diffuse light
(``ground_transmission`` at the diffusivity cosine) and k = ``sky_extinction``: the sky lights a cloud from
above and the ground from below (cloud bases; with ``below_shadow``, the ground beneath the point, dimmed
by the same column transmission that lights the ground the eye sees: a cloud's base looks down on its own
shadow), and inside a cloud both dim as diffuse light does, slowly in
the optical depth (an exponential exp(-k tau) was refitted to k ~ 0.006, no occlusion at all). Held-out
median CIEDE2000 4.72 -> 4.31 with it, refitted (validation/calibrate_slicer.py).

The ground: rho / pi x (E_sun mu0 x sunlight factor + E_sky x occlusion). The paper's modes take A + B
there too. The "multiple" model takes the total (direct + diffuse) transmission of the cloud column
above the point towards the sun, as a plane-parallel delta-Eddington layer of the column's optical
depth (``ground_transmission``): the octaves describe light scattered towards the eye inside a cloud and
leave a cloud's shadow on the ground far too bright (tau = 50: octaves ~0.4 of the sunlight, a layer
0.1); the layer is checked against DISORT in tests/test_slicing_ground.py. Its skylight passes the column
above the point (the zenith light volume) as diffuse light: the same layer at the diffusivity cosine
1/1.66 (within 4% of DISORT's transmission of isotropic light for tau 0.5-60).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .light import LightVolume, LookupFrame
from .sun_air import sun_colour_at


@dataclass
class LightModel:
    """How the eye pass turns light-volume values into in-scattered light (see the module docstring).
    ``octaves`` None: the paper's (direct, forward-scattered) pair; otherwise the "multiple" model with
    Dr.Jit scalars a, b, c, sky_extinction; ``sky``: the zenith light volume (or None)."""

    sun: LightVolume
    sky: LightVolume | None = None
    octaves: int | None = None
    a: object = None
    b: object = None
    c: object = None
    sky_extinction: object = None
    diffusion_gain: object = 0.0
    diffusion_scale: object = 0.15
    g: float = 0.85  # the cloud's asymmetry parameter, for the ground's transmission ("multiple")
    mu0: object = 1.0  # the sun's zenith cosine (an opaque Dr.Jit scalar)
    carry: object = None  # None, or (light-source texture, (its lo corner, 1 / span)): ``LightVolume.carried``
    log_forward: bool = False  # translucent light: all forward light, interpolated as its logarithm
    leak_gain: object = 0.0    # the diffused light a finite cloud loses through its sides ("multiple")
    leak_rate: object = 1.0
    below: bool = False        # the lit ground lights the medium from below, through the column under it
    flux: object = 0.0         # the diffused light's flux term towards the eye (diffusion_flux, "multiple")
    below_shadow: object = 0.0   # the light from below comes from the shadowed ground beneath ("multiple")
    ground_z: object = 0.0       # the ground's height (m), where the light from below is read
    diffusion_lobe: object = 0.0  # the part of the diffused light scattered with the phase function ("multiple")
    diffusion_incidence: object = None  # None, or the weight of the lit face's slope on the diffused light

    def terms(self, p, slab=None, ext=None, active=True, mu=None):
        """(A, B, occlusion of the sky, occlusion of the ground below) at world points p (mi.Point3f),
        inside a kernel. With ``slab`` (a ``SlabAverage``), the light at the sample becomes its average over
        the eye's segment, with decay rates read from the light volume one slice further towards the sun,
        or, with ``carry``, the light carried from the plane before p and the local extinction ``ext``
        (1/m) at p. ``active``: lanes whose light is used (the others read nothing). ``mu``: None, or the
        cosine between the sunlight's and the eye ray's directions (to_sun . eye direction; > 0: back-lit)
        per lane, for the diffused light's flux term (``diffused_towards_eye``)."""
        import drjit as dr
        factor, k_d, k_f, cap = (lambda kappa: 1.0), 0.0, 0.0, None  # noqa: E731
        # the "multiple" model reads optical depths, translucent light its forward light's: interpolated as such
        log = self.octaves is not None or self.log_forward
        if slab is not None and self.carry is not None and self.sun.frame.jitter is None:  # ("multiple": no forward light)
            direct, indirect = self.sun.carried(p, *self.carry, samples=CARRY_SAMPLES, active=active)
            k_d = ext * self.sun.frame.light_step     # optical depth per slice unit along the light at p
            # the local rate need not hold across the whole segment (it may reach clear air towards the
            # sun): an average of the sunlight is at most the sun's
            factor, cap = slab.factor, 1.0
        elif slab is None:
            direct, indirect = self.sun.lookup(p, log_direct=log, log_forward=self.log_forward, active=active)
        elif self.log_forward:  # translucent: the decay rates straight from the interpolated logarithms
            (log_d, log_f), (log_d_prev, log_f_prev) = self.sun.lookup(p, with_previous=True, log_forward=True,
                                                                       logs=True, active=active)
            d_avg = slab.mean_light(log_d, dr.maximum(log_d_prev - log_d, 0.0))  # one slice's depth, direct
            forward = slab.mean_light(log_f, dr.maximum(log_f_prev - log_f, 0.0))  # and all forward light
            return d_avg, dr.maximum(forward - d_avg, 0.0), 1.0, 0.0
        else:
            (direct, indirect), (d_prev, i_prev) = self.sun.lookup(p, with_previous=True, log_direct=log,
                                                                   log_forward=self.log_forward, active=active)
            k_d = _depth_between(dr, direct, d_prev)                   # one slice's depth, direct beam
            k_f = _depth_between(dr, direct + indirect, d_prev + i_prev)  # and all forward light
            factor = slab.factor
        if self.octaves is None:
            d_avg = direct * factor(k_d)
            if not self.log_forward:  # low-albedo light: no forward-scattered light (I = 0)
                return d_avg, 0.0, 1.0, 0.0
            return d_avg, dr.maximum((direct + indirect) * factor(k_f) - d_avg, 0.0), 1.0, 0.0
        log_d = dr.log(dr.maximum(direct, 1e-30))      # -tau
        A, B = 0.0 * direct, 0.0 * direct
        ai, bi, ci = 1.0, 1.0, 1.0
        for _ in range(1, self.octaves):
            ai, bi, ci = ai * self.a, bi * self.b, ci * self.c
            t = _capped(dr, dr.exp(ai * log_d) * factor(ai * k_d), cap)
            A += bi * ci * t
            B += bi * (1.0 - ci) * t
        # multiple scattering needs a cloud to scatter in: the octaves are weighted by the fraction of
        # the sunlight that the whole cloud column along the sun ray through p intercepts
        column, _ = self.sun.lookup(p, exit_plane=True, log_direct=True, active=active)
        A = _capped(dr, direct * factor(k_d), cap) + (1.0 - column) * A
        tau_col = -dr.log(dr.maximum(column, 1e-30))
        tau = -log_d
        if slab is not None:  # the profile is linear in tau: its eye-weighted mean over the segment is its value
            tau = dr.clip(tau + slab.sigma * k_d * slab.mean_offset(), 0.0, tau_col)  # at the mean position
        up = None
        incidence = None
        if self.diffusion_incidence is not None and self.sky is not None:  # the lit face's slope (Eq. D2)
            up, _ = self.sky.lookup(p, log_direct=True, active=active)
            incidence = incidence_cosine(dr, -log_d, -dr.log(dr.maximum(up, 1e-30)), self.mu0,
                                         self.diffusion_incidence)
        diffused = diffused_towards_eye(dr, tau, tau_col, self.diffusion_scale, self.diffusion_gain,
                                        self.leak_gain, self.leak_rate, self.flux, mu, incidence)
        lobe = self.diffusion_lobe * dr.exp(-self.diffusion_scale * tau)
        A = A + lobe * diffused
        B = (1.0 - column) * B + (1.0 - lobe) * diffused
        occ, occ_below = 1.0, 0.0
        if self.sky is not None:  # the sky through the column above p, the lit ground through the column below
            if up is None:
                up, _ = self.sky.lookup(p, log_direct=True, active=active)
            tau_up = -dr.log(dr.maximum(up, 1e-30))
            occ = ground_transmission(dr, self.sky_extinction * tau_up, DIFFUSE_MU, self.g)
            if self.below:
                through, _ = self.sky.lookup(p, exit_plane=True, log_direct=True, active=active)
                tau_down = dr.maximum(-dr.log(dr.maximum(through, 1e-30)) - tau_up, 0.0)
                occ_below = ground_transmission(dr, self.sky_extinction * tau_down, DIFFUSE_MU, self.g)
                shadow = self.ground_sun(self.sun.mi.Point3f(p.x, p.y, self.ground_z), active)  # the ground beneath
                occ_below = occ_below * (1.0 - self.below_shadow * (1.0 - shadow))
        return A, B, occ, occ_below


    def ground_light(self, p):
        """(sunlight factor, sky occlusion) on the ground at world points p: A + B for the paper's modes,
        the column's delta-Eddington transmission for the "multiple" model."""
        import drjit as dr
        A, B, occ, _ = self.terms(p)
        if self.octaves is None:
            return A + B, occ
        if self.sky is not None:  # skylight through the column above: diffuse light at the diffusivity cosine
            up, _ = self.sky.lookup(p, log_direct=True)
            occ = ground_transmission(dr, -dr.log(dr.maximum(up, 1e-30)), DIFFUSE_MU, self.g)
        return self.ground_sun(p), occ

    def ground_sun(self, p, active=True):
        """The "multiple" model's sunlight factor on the ground at world points p: the delta-Eddington
        total transmission of the column towards the sun (``ground_transmission``)."""
        import drjit as dr
        direct, _ = self.sun.lookup(p, log_direct=True, active=active)
        tau_vertical = -dr.log(dr.maximum(direct, 1e-30)) * self.mu0
        return ground_transmission(dr, tau_vertical, self.mu0, self.g)


def diffusion_profile(dr, tau, tau_col, scale, incidence=None):
    """Diffuse light inside a conservative cloud column lit along the sun ray (optical depth ``tau`` from
    the sun's side, ``tau_col`` the whole column's), relative to the lit face of a semi-infinite cloud:
    1-D diffusion in transport optical depths x = scale x tau (scale ~ 1 - g), X = scale x tau_col,
    with extrapolated boundaries z0 beyond both faces and the sunlight turned diffuse at x_s = min(1, X/2):
        J(x) = (1 - exp(-X)) (min(x, x_s) + z0) (X + z0 - max(x, x_s)) / ((X + 2 z0) z0)
    (the Green's function of the slab; 1 - exp(-X): the part of the beam that the column turns diffuse,
    so that thin clouds get little), rising from 1 at a thick cloud's lit face to (1 + z0) / z0 at
    depth and falling linearly to the shadowed face.
    ``incidence``: None (the cloud's lit face normal to the sun ray), or the cosine i of the angle between
    the sun and the lit face's normal (``incidence_cosine``): the same diffusion along that normal, depths
    x cos i (the column's too) and the flux that enters the face E cos i, the beam turned diffuse at x_s =
    min(cos i, X cos i / 2) -- (D1) J = cos i J_normal(x cos i, X cos i, x_s). Beyond x_s it is exact for the
    sunlight's exponential source in a slab lit at cos i (the Green's function is linear in the source's
    depth there, and the source's mean depth is cos i): deep in a thick layer 3 F0 cos i (cos i + z0)."""
    x, X, xs, Xn = _transport_depths(dr, tau, tau_col, scale, incidence)
    near, far = dr.minimum(x, xs), dr.maximum(x, xs)
    g = (near + DIFFUSION_Z0) * dr.maximum(Xn + DIFFUSION_Z0 - far, 0.0) / ((Xn + 2.0 * DIFFUSION_Z0) * DIFFUSION_Z0)
    return (1.0 - dr.exp(-X)) * (g if incidence is None else g * incidence)


def incidence_cosine(dr, tau_sun, tau_up, mu0, weight):
    """The cosine of the angle between the sun and the normal of the lit face through which the diffused
    light at a point entered its cloud, from the optical depths from the point towards the sun (``tau_sun``)
    and towards the zenith (``tau_up``) and the sun's zenith cosine ``mu0``:
        cos i = clip((tau_up + mu0) / (tau_sun + 1), mu0, 1)                      (D2)
    exactly mu0 at every depth of a horizontal layer (tau_sun = tau_up / mu0: its top is the lit face), 1
    beside a sunlit side under a tall cloud (tau_up >> tau_sun); blended by ``weight`` in [0, 1]:
    1 - weight (1 - cos i) (0: the face normal to the sun, as without it)."""
    cos_i = dr.clip((tau_up + mu0) / (tau_sun + 1.0), mu0, 1.0)
    return 1.0 - weight * (1.0 - cos_i)


def _transport_depths(dr, tau, tau_col, scale, incidence):
    """(x, X, x_s, X_n): the point's and the column's transport depths along the sun ray, where the beam
    turns diffuse and the column's along the lit face's normal (``diffusion_profile``)."""
    X = scale * tau_col
    if incidence is None:
        return scale * tau, X, dr.minimum(1.0, 0.5 * X), X
    Xn = X * incidence
    return scale * tau * incidence, X, dr.minimum(incidence, 0.5 * Xn), Xn


def diffusion_flux(dr, tau, tau_col, scale, incidence=None):
    """-dJ/dx of ``diffusion_profile`` J in transport depths x = scale x tau: the profile's diffuse flux
    along the sun ray (Fick's law, 3 F = -dJ/dx), > 0 beyond the depth x_s where the sunlight turns
    diffuse (the light flows on, away from the sun), < 0 before it (out through the sunlit face), 0 past
    the extrapolated far face. ``incidence``: ``diffusion_profile``'s (the flux along the face's normal)."""
    x, X, xs, Xn = _transport_depths(dr, tau, tau_col, scale, incidence)
    slope = dr.select(x < xs, -(Xn + DIFFUSION_Z0 - xs), xs + DIFFUSION_Z0)
    if incidence is not None:
        slope = slope * incidence
    inside = x < Xn + DIFFUSION_Z0
    return dr.select(inside, (1.0 - dr.exp(-X)) * slope / ((Xn + 2.0 * DIFFUSION_Z0) * DIFFUSION_Z0), 0.0)


def diffused_towards_eye(dr, tau, tau_col, scale, gain, leak_gain, leak_rate, flux=0.0, mu=None, incidence=None):
    """The diffused sunlight scattered towards the eye (relative to E_sun / (4 pi)): gain J + leak_gain Q
    (``diffusion_profile`` J, ``leaking_diffusion`` Q) as isotropic radiance, plus their flux: in the
    diffusion (P1) approximation the radiance is (phi + 3 F . w) / (4 pi), and a phase function of
    asymmetry g scatters it towards the eye as (phi + 3 g F . w_eye) / (4 pi); with 3 F = -d phi / dx along
    the sun ray (x: transport depths) and w_eye . sun ray = ``mu``,
        gain (J + flux mu (-dJ/dx)) + leak_gain Q (1 + flux mu leak_rate),   each at least 0
    (``flux`` ~ g: the fitted weight). Back-lit (mu > 0) the light flowing through a cloud away from the sun
    brightens its shadowed side (the dark cores' and thin edges' forward lobe); front-lit the light leaving
    by the sunlit face brightens it and the leak's inflow darkens it. ``incidence``: ``diffusion_profile``'s,
    for both terms."""
    J = diffusion_profile(dr, tau, tau_col, scale, incidence)
    Q = leaking_diffusion(dr, tau, tau_col, scale, leak_rate, incidence)
    if mu is None:
        return gain * J + leak_gain * Q
    return gain * dr.maximum(J + flux * mu * diffusion_flux(dr, tau, tau_col, scale, incidence), 0.0) \
        + leak_gain * Q * dr.maximum(1.0 + flux * mu * leak_rate, 0.0)


def leaking_diffusion(dr, tau, tau_col, scale, rate, incidence=None):
    """Diffused sunlight in a finite cloud that loses light through its sides: in transport optical depths
    x = scale x tau along the sun ray (X = scale x tau_col for the column), (1 - exp(-X)) exp(-rate x) --
    brightest at the sunlit face and decaying into the cloud, where the 1-D profile (``diffusion_profile``)
    of an infinite slab does not. ``incidence``: ``diffusion_profile``'s (depths along the face's normal)."""
    if incidence is not None:  # along the face's normal, the flux into it cos i (diffusion_profile's Eq. D1)
        return (1.0 - dr.exp(-scale * tau_col)) * dr.exp(-rate * scale * tau * incidence) * incidence
    return (1.0 - dr.exp(-scale * tau_col)) * dr.exp(-rate * scale * tau)


DIFFUSION_Z0 = 2.0 / 3.0  # extrapolation length of the diffusion approximation, transport optical depths
DIFFUSE_MU = 1.0 / 1.66  # the diffusivity approximation: diffuse light crosses a layer like a beam at this cosine


def ground_transmission(xp, tau, mu0, g):
    """Total (direct + diffuse) transmission of a conservative plane-parallel layer of vertical optical
    depth ``tau`` for sunlight at zenith cosine ``mu0``, asymmetry parameter ``g``: the delta-Eddington
    approximation (Joseph, Wiscombe and Weinman 1976): f = g^2, tau' = (1 - f) tau, g' = g / (1 + g),
        R = [3/4 (1 - g') tau' + (1/2 - 3/4 mu0)(1 - exp(-tau' / mu0))] / [1 + 3/4 (1 - g') tau'],
        T = 1 - R, kept within [exp(-tau' / mu0), 1]
    (the layer's reflection R; the clamp covers Eddington's negative R for thin layers and a high sun).
    ``xp``: numpy or drjit."""
    f = g * g
    tp = (1.0 - f) * tau
    gp = g / (1.0 + g)
    direct = xp.exp(-tp / mu0)
    k = 0.75 * (1.0 - gp) * tp
    R = (k + (0.5 - 0.75 * mu0) * (1.0 - direct)) / (1.0 + k)
    return xp.minimum(xp.maximum(1.0 - R, direct), 1.0)


# an eye segment across a slab whose optical depth (at its middle's extinction) exceeds EYE_SPLIT_DEPTH is
# composited again as EYE_SPLIT sub-segments: a cloud's face then lies where it is to a quarter slab, not
# at a slab plane (the dense stratocumulus deck seen against a low sun: 128 vs 256 slices 4.4 -> 1.3)
EYE_SPLIT = 4
EYE_SPLIT_DEPTH = 0.1
CARRY_SAMPLES = 2  # extinction samples of ``LightVolume.carried`` ("multiple" model)
# an eye ray stops where its transmittance falls below this: what lies behind adds at most this fraction
# of the light it would add unattenuated (at 1e-4 instead: images within 1e-3 of the brightest pixel,
# 8% slower in the uniform low-albedo mode)
OPAQUE_T = 1e-3


def _capped(dr, light, cap):
    return light if cap is None else dr.minimum(light, cap)


def _depth_between(dr, light, light_nearer_sun):
    """Optical depth between two points on a light ray from the light they receive (>= 0)."""
    return dr.maximum(dr.log(dr.maximum(light_nearer_sun, 1e-30)) - dr.log(dr.maximum(light, 1e-30)), 0.0)


class SlabAverage:
    """Average over an eye segment of light that decays exponentially away from the sun.

    Inside a slab, light whose optical depth towards the sun grows by kappa per slice unit (read from
    the light volume: the log-ratio of the light one slice nearer the sun to the light at the sample;
    for octave i, a^i times the direct beam's) varies along the eye ray as L_m exp(-sigma kappa u) (u:
    slice units from the sample, sigma = +-1: whether the ray goes away from the sun), while the eye's
    transmittance falls as exp(-x u) (x: the extinction times the eye path across a slice). The exact
    in-scattering over a segment of half-length h, against the midpoint rule's (1 - exp(-2 x h)) L_m,
    is L_m times
        factor(kappa) = x exp(-x h) 2 sinh(q h) / q / (1 - exp(-2 x h)),   q = x + sigma kappa
    (1 when kappa = 0; for a thick slab lit on the eye's side, the light at its face times x / q, never
    more than the light one slice nearer the sun), so thick slabs are not rendered with the light of
    their middle, and the image converges faster in the slice count."""

    def __init__(self, x, sigma, h):
        import drjit as dr
        self.dr, self.x, self.sigma, self.h = dr, x, sigma, h
        xh = x * h
        self.thin = xh < 1e-4
        self.e2 = dr.exp(-2.0 * xh)                          # exp(-2 x h), shared by every factor
        self.norm = x / dr.maximum(1.0 - self.e2, 1e-30)    # x / (1 - exp(-2 x h))

    def mean_offset(self):
        """The eye-weighted mean position in the segment, in slice units from the sample: u_bar with
        weights exp(-x (u + h)) on [-h, h], = 1/x - 2 h exp(-2 x h) / (1 - exp(-2 x h)) - h (0 for a thin
        segment, -h + 1/x for a thick one: one optical depth past the face the eye enters by)."""
        dr, x, h, e = self.dr, self.x, self.h, self.e2
        thick = 1.0 / dr.maximum(x, 1e-30) - 2.0 * h * e / dr.maximum(1.0 - e, 1e-30) - h
        return dr.select(x * h < 1e-3, -x * h * h / 3.0, thick)

    def factor(self, kappa):
        """factor(kappa) = x (exp((q - x) h) - exp(-(q + x) h)) / (q (1 - exp(-2 x h))), the class
        docstring's expression with exp(-x h) 2 sinh(q h) written as two exponentials (the first <= e^30),
        -> x 2 h exp(-x h) / (1 - exp(-2 x h)) as q h -> 0; at most e^30."""
        dr, h = self.dr, self.h
        q = dr.abs(self.x + self.sigma * kappa)
        grow = dr.exp(dr.minimum((q - self.x) * h, 30.0))   # exp((q - x) h)
        two_sinh = dr.select(q * h < 1e-4, 2.0 * h * grow, (grow - dr.exp(-(q + self.x) * h)) / dr.maximum(q, 1e-30))
        return dr.select(self.thin, 1.0, dr.minimum(self.norm * two_sinh, FACTOR_CAP))

    def mean_light(self, log_light, kappa):
        """exp(log_light) x factor(kappa) with the light's exponential folded into factor's two (one
        exponential fewer), uncapped (the larger exponential is at most e^30 for light <= 1)."""
        dr, h = self.dr, self.h
        q = dr.abs(self.x + self.sigma * kappa)
        grow = dr.exp(log_light + dr.select(self.thin, 0.0, dr.minimum((q - self.x) * h, 30.0)))
        small = self.thin | (q * h < 1e-4)
        two_sinh = dr.select(small, 2.0 * h * grow,
                             (grow - dr.exp(log_light - (q + self.x) * h)) / dr.maximum(q, 1e-30))
        return dr.select(self.thin, grow, self.norm * two_sinh)


FACTOR_CAP = math.exp(30.0)  # SlabAverage.factor's largest value


class _InScattering:
    """The light scattered towards the eye at a sample (``composite``'s arguments of the same names)."""

    def __init__(self, mi, dr, model, tex_eye, phase_colour, diffuse_colour, ambient, sca_ratio, ambient_below, tile,
                 sun_air=None, eye_first: int = 1):
        self.mi, self.dr, self.model, self.tex_eye = mi, dr, model, tex_eye
        self.eye_first = eye_first  # the eye texture's channel of the first group (1: after beta; 0: groups alone)
        self.phase_colour, self.diffuse_colour, self.ambient = phase_colour, diffuse_colour, ambient
        self.sca_ratio, self.ambient_below, self.tile, self.sun_air = sca_ratio, ambient_below, tile, sun_air

    def seen(self, tex, tc):
        """``tex``'s values at texture coordinates tc (periodic "transport": 0 outside the domain's own tile)."""
        dr, tile = self.dr, self.tile
        vals = tex.eval(tc)
        if tile is not None:
            inside = (tc.x >= tile[0]) & (tc.x <= tile[1]) & (tc.y >= tile[0]) & (tc.y <= tile[1])
            vals = [dr.select(inside, v, 0.0) for v in vals]
        return vals

    def __call__(self, p, tc, ext, lit, slab, vals=None, mu=None):
        """Per unit of the sample's weight: sum_g beta_sca,g [P_g A + B / (4 pi)] colour_g E_sun + beta_sca L_amb
        occlusion (``vals``: the eye texture's values at tc, or None: read here; ``mu``: ``LightModel.terms``')."""
        mi, dr = self.mi, self.dr
        A, B, occ, occ_below = self.model.terms(p, slab, ext, lit, mu)
        if vals is None and self.sca_ratio is None:
            vals = self.seen(self.tex_eye, tc)
        src = mi.Color3f(0.0)
        sca = mi.Float(0.0)
        for gi in range(len(self.phase_colour)):
            bs = ext * self.sca_ratio if self.sca_ratio is not None else dr.maximum(vals[self.eye_first + gi], 0.0)
            sca += bs
            src += bs * (self.phase_colour[gi] * A + self.diffuse_colour[gi] * B)
        if self.sun_air is not None:  # the sun after the air above p (sun_air.py)
            src = src * sun_colour_at(mi, self.sun_air, p.z)
        amb = occ * self.ambient if self.ambient_below is None else \
            occ * self.ambient + occ_below * self.ambient_below
        return src + sca * amb


def _background(mi, dr, model: LightModel, rays, ground, sun_air):
    """What each ray sees behind the medium: the lit ground where it meets it (``composite``'s ``ground``),
    else the sky (``rays.background``)."""
    if ground is None:
        return rays.background
    sun_factor, occ = model.ground_light(rays.ground)
    if getattr(rays, "ground_sun", None) is not None:  # a terrain: its albedo and slope per ray
        sun_factor, occ = sun_factor * rays.ground_sun, occ * rays.ground_sky
    if sun_air is not None:
        sun_factor = sun_factor * sun_colour_at(mi, sun_air, rays.ground.z)
    lit = ground[0] * sun_factor + ground[1] * occ
    return dr.select(rays.hit_ground, lit, rays.background)


def composite(mi, f: LookupFrame, n_slices: int, rays, tex_eye, grid_box, phase_colour, diffuse_colour, model: LightModel,
              ambient, ground, differentiable: bool = False, offset=None, sca_ratio=None, ambient_below=None,
              tile=None, tex_ext=None, sun_air=None, depth: bool = False):
    """Radiance (mi.Color3f) and transmittance of every pixel ray through the slices of ``f`` (the sun's
    light volume's frame: the slice planes of the frame's geometry); with ``depth``, also the background
    (mi.Color3f: the radiance behind the medium, seen through T) and the ray's cloud depth (mi.Float, m along
    the ray: the mean distance of its samples weighted by the opacity each adds, T_before (1 - exp(-beta de));
    ``eye_air.seen_through_air``).

    phase_colour   : per group, P_g(Theta) colour_g E_sun along each ray (mi.Color3f, one per pixel)
    diffuse_colour : per group, colour_g E_sun / (4 pi) (mi.Color3f)
    ambient        : mi.Color3f, L_amb before occlusion
    ground         : None, or (rho E_sun mu0 / pi, rho E_sky / pi) as two mi.Color3f (over a terrain rho = 1
                     and ``rays.ground_sun``/``ground_sky`` carry each ray's albedo and slope)
    offset         : None, or each ray's slab offset j in slice units (mi.Float, |j| <= 1/2, see jitter.py):
                     its slabs are [k + j - 1/2, k + j + 1/2] instead of [k - 1/2, k + 1/2], so that the
                     terraces the slab planes leave on lit faces fall at a different depth in every pixel
    sca_ratio      : None, or beta_sca / beta of the one group where ``tex_eye`` holds no beta_sca
    ambient_below  : None, or mi.Color3f: the light from the ground below, before occlusion ("multiple")
    tile           : None, or (lo, hi): the medium is seen only where x and y's texture coordinates lie in
                     [lo, hi] (a periodic volume's own tile, slicing/periodic.py)
    tex_ext        : None, or a texture whose first channel is the extinction (the light pass's source): every
                     sample reads it, and only samples that scatter light read ``tex_eye``, which then holds
                     the groups' beta_sca alone (none with ``sca_ratio``); None (``differentiable``): ``tex_eye``
                     holds beta first, then the groups'
    sun_air        : None, or a ``sun_air.SunAir``: the sunlight (and the ground's) times the sun's colour
                     after the air above the point (``spec.atmosphere``)
    depth          : return (radiance, transmittance, background, cloud depth) (module docstring above)
    """
    import drjit as dr
    op = lambda v: dr.opaque(mi.Float, float(v))  # noqa: E731
    s, d_first, spacing = f.axis, f.d_first, f.spacing
    glo = mi.Point3f(*(op(c) for c in grid_box[0]))
    inv_span = mi.Vector3f(*(op(1.0 / (h - l)) for l, h in zip(*grid_box)))
    o, d = rays.origin, rays.direction
    sd = dr.dot(d, s)
    sd = dr.select(dr.abs(sd) < 1e-9, -1e-9, sd)                    # rays within a slice plane
    os_ = dr.dot(o, s)
    ka = (d_first - (os_ + rays.t0 * sd)) / spacing                 # the ray's span in slice units
    kb = (d_first - (os_ + rays.t1 * sd)) / spacing
    k_step = dr.select(sd < 0, 1.0, -1.0)                           # k grows along the ray when s . d < 0
    j = 0.0 if offset is None else offset
    k_start = dr.round(ka - j)                                      # slab holding the entry point
    count = dr.select(rays.t1 > rays.t0, mi.UInt32(dr.abs(dr.round(kb - j) - k_start) + 1.5), 0)
    span_a = getattr(rays, "span_a", None)
    if span_a is not None:  # only the slabs of the ray's occupied span (occupancy.py): the others are empty
        ka_s = (d_first - (os_ + span_a * sd)) / spacing
        kb_s = (d_first - (os_ + rays.span_b * sd)) / spacing
        k_start = dr.round(ka_s - j)
        count = dr.select((rays.t1 > rays.t0) & (rays.span_b >= span_a),
                          mi.UInt32(dr.abs(dr.round(kb_s - j) - k_start) + 1.5), 0)
    k_lo, k_hi = dr.minimum(ka, kb), dr.maximum(ka, kb)
    de = spacing / dr.abs(sd)
    mu = dr.dot(d, f.to_light) if model.octaves is not None else None  # the eye ray against the sunlight

    M = EYE_SPLIT

    scattering = _InScattering(mi, dr, model, tex_eye, phase_colour, diffuse_colour, ambient, sca_ratio,
                               ambient_below, tile, sun_air, eye_first=1 if tex_ext is None else 0)
    seen, in_scattered = scattering.seen, scattering

    def body(i, part, T, C, active, *dist):
        kc = k_start + k_step * mi.Float(i) + j
        # slab [k + j - 1/2, k + j + 1/2] clipped to the ray's span in the box, whole (part 0) or its
        # sub-segment part - 1 of M in the ray's order; sample at the middle
        a = dr.clip(kc - 0.5, k_lo, k_hi)
        b = dr.clip(kc + 0.5, k_lo, k_hi)
        sub = part > 0
        w_sub = (b - a) * (1.0 / M)
        m = mi.Float(part) - 1.0
        a_sub = dr.select(k_step > 0, a + m * w_sub, b - (m + 1.0) * w_sub)
        a, b = dr.select(sub, a_sub, a), dr.select(sub, a_sub + w_sub, b)
        kf = 0.5 * (a + b)
        p = o + ((d_first - kf * spacing - os_) / sd) * d
        tc = (p - glo) * inv_span
        # the extinction from the texture with the fewest channels (the light pass's source: beta first)
        vals = seen(tex_eye if tex_ext is None else tex_ext, tc)
        ext = dr.maximum(vals[0], 0.0)
        # an optically thick slab is done again in M sub-segments (this sample only decides that)
        split = ~sub & (ext * de * (b - a) > EYE_SPLIT_DEPTH)
        # the light is read where it is scattered towards the eye (not in clear air, nor to decide a split)
        slab = SlabAverage(ext * de, k_step, 0.5 * (b - a))
        lit = (ext > 0) & ~split
        group_vals = vals if tex_ext is None else None
        if differentiable:
            add = in_scattered(p, tc, ext, lit, slab, group_vals, mu)
        else:  # a packet of lanes that all see clear air here (or split the slab) skips the light model and the
            # eye's texture: LLVM branches per packet; their zero adds nothing, as the light read for them did
            add = dr.if_stmt((p, tc, ext, lit), lit, lambda *x: in_scattered(*x, slab, group_vals, mu),
                             lambda *x: mi.Color3f(0.0))
        alpha = dr.select(split, 0.0, 1.0 - slab.e2)    # 1 - exp(-ext de (b - a))
        w = dr.select(ext > 0, T * alpha / dr.maximum(ext, 1e-30), 0.0)
        C = C + w * add
        if dist:  # the opacity-weighted distance of the sample along the ray (its depth)
            dist = (dist[0] + T * alpha * ((d_first - kf * spacing - os_) / sd),)
        T = T * (1.0 - alpha)
        done = ~split & (~sub | (part == M))        # the slab is done: on to the next
        i = dr.select(done, i + 1, i)
        part = dr.select(done, 0, part + 1)
        return (i, part, T, C, (i < count) & (T > OPAQUE_T)) + dist

    n = rays.n
    state = (dr.zeros(mi.UInt32, n), dr.zeros(mi.UInt32, n), dr.full(mi.Float, 1.0, n), dr.zeros(mi.Color3f, n),
             count > 0) + ((dr.zeros(mi.Float, n),) if depth else ())
    kw = dict(max_iterations=(M + 1) * (n_slices + 2), mode="evaluated") if differentiable else {}
    _, _, T, C, _, *dist = dr.while_loop(state, lambda *st: st[4], body, **kw)

    bg = _background(mi, dr, model, rays, ground, sun_air)
    if depth:
        return C + T * bg, T, bg, dist[0] / dr.maximum(1.0 - T, 1e-30)
    return C + T * bg, T
