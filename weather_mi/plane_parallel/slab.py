"""Plane-parallel checks of the path tracer: a wide, thin homogeneous slab lit by the sun, measured
with Mitsuba (fluxes and radiances) and solved with DISORT (``disortpp``) for comparison.

Geometry (units of the slab thickness H): the slab fills x, y in [-A H/2, A H/2], z in [0, H]
(A = ``aspect``, 1000 by default, so that light leaking through the sides is negligible at the centre),
in vacuum, with no ground and no sky; the sun is a ``directional`` emitter of irradiance E = 1 normal
to its beam at zenith cosine mu0.

Measured quantities (all normalised by the incident flux mu0 E):

R     flux reflectance F_up(top) / (mu0 E): an ``irradiancemeter`` on a small rectangle facing down,
      just above the slab top (null BSDF, so it neither occludes nor scatters). It measures the
      irradiance arriving at the rectangle's front side, i.e. from below.
T     total transmittance (F_down,diffuse + F_direct)(bottom) / (mu0 E). The direct beam is a delta
      in direction: a ray leaving an ``irradiancemeter`` never hits a ``directional`` emitter and the
      meter does no emitter sampling at its own vertex, so ``volpath`` + ``irradiancemeter`` returns
      the diffuse part only (checked: ``transmittance_method="meter"``). The total is measured on a
      small white Lambertian patch (reflectance 1) facing up, 2 H below the slab, seen by an
      orthographic camera: its radiance is E_down / pi, and emitter sampling at the patch carries
      the direct beam through the slab (shadow-ray transmittance) while BSDF sampling carries the
      diffuse light. Below an infinite slab in vacuum the irradiance does not depend on the depth,
      and at 2 H the light the patch (1% of H wide) sends up and gets back from the slab is of order
      1e-5 of T (estimate); a patch just under the slab would see its own reflection (measured +4e-4 in T for
      tau = 1, albedo 1, g = 0, mu0 = 0.5). The slab's finite width (aspect 1000) cuts off only
      directions within 0.25 degrees of the horizon there.
L_up  reflected radiance at nadir view pi L / (mu0 E): orthographic camera above the slab looking
      straight down (``render_reference(..., normalize="reflectance")``).
L_dn  diffuse transmitted radiance at zenith view pi L / (mu0 E): orthographic camera below the slab
      looking up (a camera ray can never hit the directional sun, so this is the diffuse part even
      for an overhead sun).

Standard errors are the spread of independent passes (consecutive seeds) over sqrt(passes).
"""
from __future__ import annotations

import math

import numpy as np

from ..optics.volume import OpticalVolume

#: in units of H: meter rectangle half-size, patch half-size, half-width of the patch camera's view,
#: depth of the patch below the slab, gap between a sensor and what it looks at
METER_HALF = 0.05
PATCH_HALF = 0.005
PATCH_VIEW_HALF = 0.002
PATCH_DEPTH = 2.0
GAP = 1e-3


# ---------------------------------------------------------------- slab geometry

def slab_volume(tau: float, albedo: float, phase_table, thickness: float = 1.0,
                aspect: float = 1000.0) -> OpticalVolume:
    """A homogeneous slab of vertical optical depth ``tau``: z in [0, H], x, y in +-aspect H / 2."""
    if tau <= 0:
        raise ValueError(f"optical depth must be positive, got {tau}")
    half = 0.5 * aspect * thickness
    beta = np.full((2, 2, 2), tau / thickness, dtype=np.float32)
    return OpticalVolume.from_arrays(beta, albedo, phase_table,
                                     ((-half, -half, 0.0), (half, half, thickness)), name="slab")


def sun_for(mu0: float, irradiance: float = 1.0, azimuth: float = 0.0):
    from ..scene.spec import Sun
    if not 0.0 < mu0 <= 1.0:
        raise ValueError(f"mu0 must be in (0, 1], got {mu0}")
    return Sun(azimuth=azimuth, elevation=math.degrees(math.asin(mu0)), irradiance=irradiance,
               angular_diameter_deg=0.0)  # plane-parallel solvers (DISORT) have a point sun


def _film(width=1, height=1) -> dict:
    return {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"},
            "pixel_format": "rgb", "component_format": "float32"}


def _meter_shape(z: float, half: float, facing_up: bool) -> dict:
    """An ``irradiancemeter`` on a rectangle at height z (normal +z when facing up, -z otherwise),
    with a null BSDF so that it is invisible to light."""
    import mitsuba as mi
    to_world = mi.ScalarTransform4f().translate([0.0, 0.0, z]).scale([half, half, 1.0])
    if not facing_up:
        to_world = to_world @ mi.ScalarTransform4f().rotate([1.0, 0.0, 0.0], 180.0)
    return {"type": "rectangle", "to_world": to_world, "bsdf": {"type": "null"},
            "sensor": {"type": "irradiancemeter", "film": _film()}}


def _patch_scene_parts(thickness: float) -> dict:
    """White Lambertian patch below the slab facing up, and an orthographic camera looking at it."""
    import mitsuba as mi
    h = thickness
    z_patch = -PATCH_DEPTH * h
    z_cam = z_patch + GAP * h
    patch = {"type": "rectangle",
             "to_world": mi.ScalarTransform4f().translate([0.0, 0.0, z_patch]).scale([PATCH_HALF * h] * 2 + [1.0]),
             "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}}}
    look = mi.ScalarTransform4f().look_at(origin=[0.0, 0.0, z_cam], target=[0.0, 0.0, z_cam - 1.0], up=[0.0, 1.0, 0.0])
    cam = {"type": "orthographic", "to_world": look @ mi.ScalarTransform4f().scale([PATCH_VIEW_HALF * h] * 2 + [1.0]),
           "near_clip": 0.1 * GAP * h, "far_clip": 10.0 * GAP * h, "film": _film()}
    return {"patch": patch, "patch_camera": cam}


def _measure(scene_parts: dict, vol: OpticalVolume, sun, integrator: str, max_depth: int, rr_depth,
             spp: int, passes: int, seed: int) -> tuple[float, float]:
    """Mean and standard error (over passes) of the 1-pixel sensor's channel-mean value."""
    import mitsuba as mi

    from ..kernel.medium import air_by_integrator
    from ..kernel.scene_dict import integrator_dict, medium_shape_dict, sun_dict
    from ..reference.passes import pass_seed
    integ = integrator_dict(vol, integrator, max_depth, rr_depth)
    d = {"type": "scene", "integrator": integ, "sun": sun_dict(sun),
         "slab": medium_shape_dict(vol, None, not air_by_integrator(integ))}
    d.update(scene_parts)
    scene = mi.load_dict(d)
    per = max(1, -(-spp // passes))
    vals = np.empty(passes)
    for i in range(passes):
        img = np.array(mi.render(scene, spp=per, seed=pass_seed(seed, i)), dtype=np.float64)
        vals[i] = img[..., :3].mean()
    se = float(vals.std(ddof=1) / math.sqrt(passes)) if passes > 1 else float("nan")
    return float(vals.mean()), se


def slab_fluxes(tau: float, albedo: float, phase_table, mu0: float, spp: int = 1 << 20, *, passes: int = 16,
                seed: int = 0, integrator: str = "volpath", max_depth: int = -1, rr_depth: int | None = None,
                thickness: float = 1.0, aspect: float = 1000.0, transmittance_method: str = "patch",
                variant: str | None = None, forward_peak_deg: float = 0.0) -> dict:
    """Flux reflectance R and total transmittance T of a slab (see the module docstring).

    spp     : paths per measurement in total (split over ``passes`` independent passes).
    rr_depth: Russian roulette start depth (None: the integrator's default, as ``render_reference``).
    transmittance_method : "patch" (total T, direct beam included by emitter sampling), "meter"
              (``irradiancemeter``: diffuse T only), or "both" (adds ``T_diffuse`` from the meter).
    forward_peak_deg : delta-M of the phase table's forward peak within this cone (``forward_peak``).
    Returns dict(R, R_stderr, T, T_stderr[, T_diffuse, T_diffuse_stderr], T_direct_exact).
    """
    from ..kernel.variant import ensure_registered, set_variant
    if variant is not None:
        set_variant(variant)
    ensure_registered()
    if transmittance_method not in ("patch", "meter", "both"):
        raise ValueError(f"transmittance_method must be 'patch', 'meter' or 'both', got {transmittance_method!r}")
    if spp < passes or passes < 2:
        raise ValueError(f"need passes >= 2 and spp >= passes, got spp={spp}, passes={passes}")
    from ..optics.forward_peak import delta_scaled
    vol = delta_scaled(slab_volume(tau, albedo, phase_table, thickness, aspect), forward_peak_deg)
    sun = sun_for(mu0)
    h = thickness
    norm = 1.0 / (mu0 * float(np.mean(sun.irradiance)))
    args = (vol, sun, integrator, max_depth, rr_depth, spp, passes)
    r, r_se = _measure({"meter": _meter_shape((1.0 + GAP) * h, METER_HALF * h, facing_up=False)}, *args, seed)
    out = {"R": r * norm, "R_stderr": r_se * norm, "T_direct_exact": math.exp(-tau / mu0)}
    if transmittance_method in ("meter", "both"):
        t, t_se = _measure({"meter": _meter_shape(-GAP * h, METER_HALF * h, facing_up=True)}, *args, seed + 1)
        out["T_diffuse"], out["T_diffuse_stderr"] = t * norm, t_se * norm
        if transmittance_method == "meter":
            out["T"], out["T_stderr"] = out["T_diffuse"], out["T_diffuse_stderr"]
    if transmittance_method in ("patch", "both"):
        lum, lum_se = _measure(_patch_scene_parts(h), *args, seed + 2)
        out["T"], out["T_stderr"] = math.pi * lum * norm, math.pi * lum_se * norm  # E = pi L (albedo 1)
    return out


def slab_radiance(tau: float, albedo: float, phase_table, mu0: float, spp: int = 256, *, view: str = "nadir",
                  pixels: int = 16, passes: int = 16, seed: int = 0, integrator: str = "volpath",
                  max_depth: int = -1, rr_depth: int | None = None, thickness: float = 1.0,
                  aspect: float = 1000.0, variant: str | None = None,
                  forward_peak_deg: float | None = None) -> tuple[float, float]:
    """Normalised radiance pi L / (mu0 E) of the slab's centre seen by ``render_reference``:
    ``view="nadir"``: reflected, camera above looking straight down; ``"zenith"``: diffuse
    transmitted, camera below looking straight up. ``pixels`` x ``pixels`` image over 1% of H, ``spp``
    per pixel. Returns (mean over the pixels, its standard error).

    ``rr_depth``, ``forward_peak_deg``: as ``render_reference`` takes them."""
    from ..reference.render import render_reference
    from ..scene.spec import Camera, SceneSpec
    if view not in ("nadir", "zenith"):
        raise ValueError(f"view must be 'nadir' or 'zenith', got {view!r}")
    vol = slab_volume(tau, albedo, phase_table, thickness, aspect)
    h = thickness
    if view == "nadir":
        cam = Camera.orthographic(center=(0.0, 0.0, (1.0 + 10 * GAP) * h), direction=(0.0, 0.0, -1.0),
                                  width=0.01 * h, height=0.01 * h)
    else:
        cam = Camera.orthographic(center=(0.0, 0.0, -10 * GAP * h), direction=(0.0, 0.0, 1.0),
                                  width=0.01 * h, height=0.01 * h)
    spec = SceneSpec(camera=cam, sun=sun_for(mu0), sky=None, ground=None, width=pixels, height=pixels, seed=seed)
    img = render_reference(spec, vol, spp=spp, max_depth=max_depth, integrator=integrator, passes=passes,
                           normalize="reflectance", progress=False, variant=variant, rr_depth=rr_depth,
                           forward_peak_deg=forward_peak_deg)
    rad = img.radiance.astype(np.float64).mean(axis=2)
    se = img.stderr.astype(np.float64).mean(axis=2)  # channels are identical for a grey medium
    return float(rad.mean()), float(np.sqrt(np.sum(se ** 2)) / rad.size)


# ---------------------------------------------------------------- DISORT

def disort_slab(tau: float, albedo: float, g, mu0: float, n_streams: int = 64,
                n_moments: int = 512) -> dict:
    """DISORT (``disortpp``) solution for one homogeneous HG layer over a black surface, sun flux
    F0 = 1 at zenith cosine mu0, no diffuse illumination (``weather_mi.optics.disort.solve``: delta-M, the
    Nakajima-Tanaka intensity correction from ``n_moments`` HG moments g^l). ``g`` may instead be a PhaseTable: its own Legendre moments (green
    channel). Then the fluxes are exact to the solver's accuracy, but the corrected intensities only
    where the moments converge (a cloud droplet table at 2048: yes; ice or snow: no, they come out
    negative).

    Returns R, T (direct beam included), T_diffuse, T_direct, and the normalised radiances
    pi I / (mu0 F0): ``L_nadir`` (upward, umu = +1, at the top) and ``L_zenith`` (diffuse
    downward, umu = -1, at the bottom)."""
    from ..optics.disort import solve
    table = hasattr(g, "legendre")
    res = solve([tau], [albedo], mu0, [-1.0, 1.0], [0.0, float(tau)], [0.0], n_streams=n_streams,
                moments=np.asarray(g.legendre(int(n_moments)))[:, 1][None] if table else None,
                hg_g=None if table else float(g), n_moments=n_moments)
    f_in = mu0 * 1.0
    up, down, direct = list(res.flux_up), list(res.flux_down), list(res.flux_direct_beam)
    return {"R": up[0] / f_in, "T": (down[-1] + direct[-1]) / f_in, "T_diffuse": down[-1] / f_in,
            "T_direct": direct[-1] / f_in,
            "L_nadir": math.pi * res.intensities(1, 0, 0) / f_in,
            "L_zenith": math.pi * res.intensities(0, 1, 0) / f_in}


def agrees(mc: float, se: float, ref: float, abs_tol: float = 0.01, n_sigma: float = 3.0) -> bool:
    """The validation criterion: |mc - ref| within n_sigma standard errors AND within abs_tol."""
    d = abs(mc - ref)
    return bool(d <= n_sigma * se and d <= abs_tol)
