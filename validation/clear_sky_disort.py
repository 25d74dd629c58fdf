"""The path tracer's clear air against DISORT (issue 38's target: "Pure molecular plane-parallel atmosphere: sky
radiance at the ground (zenith and three view angles in the principal plane) and reflectance at the top,
450/550/650 nm, against DISORT (disortpp) on the same layers: within 1% or 3 combined se. A cloud layer inside the
molecular atmosphere: the same.").

The scene: a 10 km slab of air of constant density 1.2 kg/m^3, 400 km wide (the box's air, ``optics.air.inside``:
molecules only, Bodhaine et al.'s cross section at 650/550/450 nm), over a black surface, sun at 60 deg zenith
(azimuth 0), optionally a conservative Henyey-Greenstein cloud layer (g 0.85) between 4 and 6 km inside it. One
render with the ``raytable`` sensor: five rays, from 10 m below the slab looking up (the zenith, 30 deg towards
the sun's azimuth, 30 and 60 deg away from it; not into the sun itself, whose aureole within 3 deg the path
tracer's delta-M moves into the direct beam, ``reference.options.forward_peak_deg``) and from 10 m above looking down (nadir). pi I / mu0 in both.

DISORT gets the same layers (0-4 km air, 4-6 km air and cloud mixed by their scattering optical depths, 6-10 km
air; the cloud's 125 m voxel edges of the path tracer's grid are ramps whose optical depth is the layer's), its
Rayleigh cross section from Bodhaine's Eq. 2 written out here (not ours), Rayleigh's
Legendre moments 1, 0, (1 - gamma) / (10 (1 + 2 gamma)), Henyey-Greenstein's g^k.

    python validation/clear_sky_disort.py [--spp 16384] [--passes 8] [--cloud-tau 0 2]
"""
from __future__ import annotations

import argparse
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

H_M, WIDE_M, RHO = 10e3, 400e3, 1.2
AVOGADRO, M_AIR = 6.02214076e23, 28.9595e-3
DEPOL = 0.0279             # Young (1980)
CLOUD_M = (4e3, 6e3)
CLOUD_G = 0.85
MU0 = 0.5
NZ = 80                    # levels of 125 m: the cloud's edges are voxel centres apart
CHANNELS = ((0, 650.0), (1, 550.0), (2, 450.0))
# (name, view zenith deg, azimuth of the view relative to the sun's: 0 towards it, 180 away; looking up or down)
VIEWS = (("zenith sky", 0.0, 180.0, "up"), ("sky 30 deg towards the sun", 30.0, 0.0, "up"),
         ("sky 30 deg away from the sun", 30.0, 180.0, "up"), ("sky 60 deg away from the sun", 60.0, 180.0, "up"),
         ("nadir reflectance at the top", 0.0, 0.0, "down"))


def bodhaine_cross_section_m2(lam_nm):
    """Rayleigh cross section from its definition (Bodhaine et al. 1999, Eq. 2), written out here (not
    ``optics.rayleigh``'s): Peck & Reeder's index of standard air, N_s = 2.546899e19 /cm^3 and the King factor of
    Bates (1984) for 360 ppm."""
    lam = lam_nm * 1e-3
    inv2 = lam ** -2
    n = 1 + (1e-8 * (8060.51 + 2480990.0 / (132.274 - inv2) + 17455.7 / (39.32957 - inv2))) * (1 + 0.54 * (360e-6 - 3e-4))
    f_n2, f_o2 = 1.034 + 3.17e-4 * inv2, 1.096 + 1.385e-3 * inv2 + 1.448e-4 * inv2 ** 2
    c = 0.036
    king = (78.084 * f_n2 + 20.946 * f_o2 + 0.934 + c * 1.15) / (78.084 + 20.946 + 0.934 + c)
    lam_cm, ns = lam * 1e-4, 2.546899e19
    return 24 * math.pi ** 3 * (n * n - 1) ** 2 / (lam_cm ** 4 * ns ** 2 * (n * n + 2) ** 2) * king * 1e-4


def slab(cloud_tau: float, nz: int = NZ, cloud_albedo: float = 1.0):
    """The OpticalVolume: the air slab on ``nz`` levels with a cloud layer of optical depth ``cloud_tau`` (0: none)
    and single-scattering albedo ``cloud_albedo``."""
    from weather_mi.optics.air import Atmosphere
    from weather_mi.optics.air.inside import box_air
    from weather_mi.optics.phase.analytic import henyey_greenstein
    from weather_mi.optics.volume import OpticalVolume
    z = (np.arange(nz) + 0.5) * (H_M / nz)
    beta = np.zeros((nz, 4, 4), np.float32)
    beta[(z > CLOUD_M[0]) & (z < CLOUD_M[1])] = cloud_tau / (CLOUD_M[1] - CLOUD_M[0])
    vol = OpticalVolume.from_arrays(beta, cloud_albedo, henyey_greenstein(CLOUD_G),
                                    ((-WIDE_M / 2, -WIDE_M / 2, 0.0), (WIDE_M / 2, WIDE_M / 2, H_M)))
    return replace(vol, air=box_air(Atmosphere(aod_550=0.0, ozone_atm_cm=0.0), np.full(nz, RHO), z,
                                    shape=(nz, 4, 4)))


def view_rays():
    """The ``RayTable`` of ``VIEWS``: pixel 2j is view j (its two corner columns the same ray), odd pixels are
    the ramps between them."""
    from weather_mi.scene.spec import RayTable
    to_sun_h = np.array([0.0, 1.0, 0.0])  # the sun at azimuth 0 (north, +y)
    rays = []
    for _, zen, rel_az, way in VIEWS:
        s = math.sin(math.radians(zen))
        h = to_sun_h if rel_az == 0.0 else -to_sun_h
        if way == "up":
            rays.append(((0.0, 0.0, -10.0), (s * h[0], s * h[1], math.cos(math.radians(zen)))))
        else:
            rays.append(((0.0, 0.0, H_M + 10.0), (0.0, 0.0, -1.0)))
    o = np.array([r[0] for r in rays for _ in (0, 1)], np.float64)
    d = np.array([r[1] for r in rays for _ in (0, 1)], np.float64)
    return RayTable(np.stack([o, o]), np.stack([d, d]))


def path_tracer(cloud_tau: float, spp: int, passes: int, nz: int = NZ, cloud_albedo: float = 1.0, **render_kw):
    """(pi I / mu0, its standard error), each (views, 3 channels), from one render (``render_kw``: more options of
    ``render_reference``)."""
    from weather_mi.reference.render import render_reference
    from weather_mi.scene.spec import Camera, SceneSpec, Sun
    rays = view_rays()
    w, h = rays.film_size
    sun = Sun(azimuth=0.0, elevation=math.degrees(math.asin(MU0)), irradiance=1.0, angular_diameter_deg=0.0)
    spec = SceneSpec(camera=Camera(origin=(0.0, 0.0, -10.0), target=(0.0, 1.0, 0.0)), sun=sun, sky=None,
                     ground=None, width=w, height=h, seed=5, rays=rays)
    img = render_reference(spec, slab(cloud_tau, nz, cloud_albedo), spp=spp, passes=passes, progress=False,
                           variant="llvm_ad_rgb", normalize="reflectance", **render_kw)
    r = img.radiance.reshape(w, 3)[0::2].astype(np.float64)
    se = img.stderr.reshape(w, 3)[0::2].astype(np.float64)
    return r, se


def _tau_rayleigh(lam_nm: float) -> float:
    return bodhaine_cross_section_m2(lam_nm) * RHO * AVOGADRO / M_AIR * H_M


def cloud_layers(cloud_tau: float, nz: int = NZ, sub: int = 8):
    """(Layer edges, top first (m); the cloud's extinction in each layer (1/m)): the path tracer's cloud, linear
    between the grid's level centres (clamped beyond the first and last), each ramp cut into ``sub`` layers whose
    extinction is its mean (exact for a linear piece)."""
    zc = (np.arange(nz) + 0.5) * (H_M / nz)
    b = np.where((zc > CLOUD_M[0]) & (zc < CLOUD_M[1]), cloud_tau / (CLOUD_M[1] - CLOUD_M[0]), 0.0)
    knots, values = [0.0, *zc, H_M], [b[0], *b, b[-1]]
    edges, beta = [0.0], []
    for z0, z1, v0, v1 in zip(knots[:-1], knots[1:], values[:-1], values[1:]):
        m = sub if v0 != v1 else 1
        for k in range(m):
            edges.append(z0 + (z1 - z0) * (k + 1) / m)
            beta.append(v0 + (v1 - v0) * (k + 0.5) / m)
    return edges[::-1], beta[::-1]


def disort(cloud_tau: float, lam_nm: float, nz: int = NZ, cloud_albedo: float = 1.0) -> np.ndarray:
    """pi I / mu0 of ``VIEWS`` from DISORT on the same layers (the cloud's ramps resolved, :func:`cloud_layers`;
    each layer's single-scattering albedo and moments those of its molecules and cloud by their optical depths)."""
    from weather_mi.optics.disort import solve
    n = 64
    gamma = DEPOL / (2 - DEPOL)
    chi_r = np.zeros(n + 1)
    chi_r[0], chi_r[2] = 1.0, (1 - gamma) / (10 * (1 + 2 * gamma))
    chi_c = CLOUD_G ** np.arange(n + 1)
    per_m = _tau_rayleigh(lam_nm) / H_M
    edges, beta_c = cloud_layers(cloud_tau, nz)
    dz = -np.diff(edges)
    tau_r, tau_c = per_m * dz, np.asarray(beta_c) * dz
    tau_sca = tau_r + cloud_albedo * tau_c
    moments = (tau_r[:, None] * chi_r + cloud_albedo * tau_c[:, None] * chi_c) / tau_sca[:, None]
    tau = tau_r + tau_c
    mus = [(-math.cos(math.radians(z)) if way == "up" else math.cos(math.radians(z))) for _, z, _, way in VIEWS]
    mu_user = sorted(set(mus))
    phis = sorted({a for _, _, a, _ in VIEWS})
    res = solve(list(tau), list(tau_sca / tau), MU0, mu_user, [0.0, float(tau.sum())], phis, moments=moments,
                n_streams=n)
    out = []
    for (_, z, a, way), mu in zip(VIEWS, mus):
        it = 1 if way == "up" else 0  # the bottom for the sky, the top for the reflectance
        out.append(math.pi * res.intensities(mu_user.index(mu), it, phis.index(a)) / MU0)
    return np.array(out)


def compare(cloud_tau: float, spp: int, passes: int, nz: int = NZ, cloud_albedo: float = 1.0):
    """Rows (view, wavelength, ours, se, DISORT, relative difference, within: 1 % or 3 se)."""
    ours, se = path_tracer(cloud_tau, spp, passes, nz, cloud_albedo)
    rows = []
    for c, lam in CHANNELS:
        ref = disort(cloud_tau, lam, nz, cloud_albedo)
        for j, (name, *_rest) in enumerate(VIEWS):
            diff = ours[j, c] - ref[j]
            rows.append((name, lam, ours[j, c], se[j, c], ref[j], diff / ref[j],
                         abs(diff) <= max(0.01 * ref[j], 3 * se[j, c])))
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spp", type=int, default=16384)
    ap.add_argument("--passes", type=int, default=8)
    ap.add_argument("--cloud-tau", type=float, nargs="+", default=[0.0, 2.0])
    ap.add_argument("--levels", type=int, default=NZ, help="the grid's levels over the 10 km (80: 125 m)")
    ap.add_argument("--cloud-albedo", type=float, default=1.0)
    args = ap.parse_args(argv)
    for tau in args.cloud_tau:
        print(f"\n{'pure molecular' if tau == 0 else f'cloud layer tau {tau:g}, albedo {args.cloud_albedo:g} at 4-6 km'}"
              f" (10 km on {args.levels} levels, mu0 {MU0}), {args.spp} spp: pi I / mu0")
        print("| view | nm | path tracer | se | DISORT | difference | within 1% or 3 se |\n|---|---|---|---|---|---|---|")
        for name, lam, o, s, r, rel, ok in compare(tau, args.spp, args.passes, args.levels, args.cloud_albedo):
            print(f"| {name} | {lam:.0f} | {o:.5f} | {s:.5f} | {r:.5f} | {100 * rel:+.2f}% | {'yes' if ok else 'NO'} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
