"""The clear 1-D atmosphere around and above a satellite view's model box (``satellite --atmosphere clear``).

Inside the box the air is part of the path tracer's medium at the band's wavelength (or the three bands of a
true-colour render, one per channel: ``optics.air.inside``, ``BoxAir.band_nm``), and the sun reaches every
vertex through the spherical shell (the direct beam's transmittance in each band, ``sunlight.channel_values``).
Outside the box each pixel's line of sight (its centre, ``rays.box_segment``) is completed here:

* through the box: the air A between the top of the atmosphere and the box entry (above the model top; below
  it where the line enters through a side) and B from a side wall's exit down to the ground (its single
  scattering times the clear column's ratio of all orders to the first), single scattering
  (``eye_path.segment_air``; heights above a spherical Earth whose centre is under the box's centre), and the coupling C of the air above the top with
  what lies below it, as the clear plane-parallel column has it (``above_box_coupling``: its diffuse light onto
  the box and back, 2-3 % of a clear sea's reflectance at 0.47 um under a 20 km top):
      R = pi S_A / mu0 + T_A R_render + C                              (S_A per unit irradiance of the sun)
* past the box: the plane-parallel 1-D atmosphere over a Lambertian surface, all orders of scattering
  (DISORT, ``air_layers``):
      R = R_0(mu, phi) + a K(mu, phi) / (1 - a s)                      (Chandrasekhar 1960, ch. 4; K = t(mu0) t(mu))
  with a = R_render / T_0 the surface's albedo as the render shows it lit by the direct sun (T_0 the direct
  beam's transmittance to the ground), R_0 the path reflectance over a black surface, K the product of the
  total (direct + diffuse) transmittances and s the spherical albedo, both from DISORT at two more albedos.

R is the reflectance factor pi L / (E0 mu0) of ``render_satellite``, mu0 the rendered sun's. Not included:
a cloud's own coupling with the air above the top (C is the clear column's), light that leaves the box through
its sides into the outside air and back (a periodic box has its copies instead), the outside air's shadow of
the clouds. The standard error is scaled by T_A (the added terms are exact).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..optics.air import layers as _layers
from ..optics.air.layers import N_STREAMS

LAYER_M = 2000.0  # the satellite's DISORT layers up to 30 km (1 km: R_0 within 8e-4 at 0.47 um, the image within 3e-4,
#                   each solve twice the time)
ALBEDOS = (0.0, 0.1, 0.5)         # the surface albedos of the three DISORT solves (R_0, then K and s)


def plane_parallel_terms(atm, wavelength_nm: float, mu0: float, mu_nodes, phi_nodes, ground_m: float = 0.0,
                         albedos=ALBEDOS, split_m: float | None = None):
    """(R_0, K, s) of the module docstring on the grid ``mu_nodes`` (ascending cos of the view zenith) x
    ``phi_nodes`` (deg, 0 forward scattering): three DISORT solves (``ALBEDOS``; ``albedos`` (0,): R_0 alone,
    K and s None); ``split_m``: ``air_layers``' layers split there."""
    layers = air_layers(atm, wavelength_nm, ground_m, split_m)
    refl = [reflectance(layers, mu0, mu_nodes, phi_nodes, a) for a in albedos]
    if len(refl) == 1:
        return refl[0], None, None
    r0, (a1, a2) = refl[0], albedos[1:]
    y1, y2 = (refl[1] - r0) / a1, (refl[2] - r0) / a2     # y_i = K / (1 - a_i s)
    s = (y1 - y2) / (a1 * y1 - a2 * y2)
    return r0, y1 * (1.0 - a1 * s), s


def above_box_coupling(atm, wavelength_nm: float, mu0: float, mu_nodes, phi_nodes, ground_m: float, top_m: float,
                       albedo: float, full=None) -> np.ndarray:
    """What the air above the box's top adds to a clear column beyond its single scattering along the line of
    sight and its direct transmittances (mu_nodes x phi_nodes): R_full - T(mu0) T(mu) R_below - R_above (DISORT,
    the surface of ``albedo``; T the direct transmittances of the air above ``top_m``, R_above its reflectance
    alone over a black surface): its diffuse light onto the box and the box's diffuse light scattered back into
    the line of sight. Added to every line of sight through the box (a cloud's own coupling taken as the clear
    column's). ``full``: R_full on the grid where known (``ColumnTerms.full``: no solve of the whole column)."""
    mu_nodes = np.asarray(mu_nodes, np.float64)
    layers = air_layers(atm, wavelength_nm, ground_m, split_m=top_m)
    n_above = _layers_above(ground_m, top_m)

    def refl(sl, a):
        return reflectance(tuple(v[sl] for v in layers), mu0, mu_nodes, phi_nodes, a)
    tau_above = float(layers[0][:n_above].sum())
    full = refl(slice(None), albedo) if full is None else full
    below, above = refl(slice(n_above, None), albedo), refl(slice(0, n_above), 0.0)
    t_dir = np.exp(-tau_above / mu0) * np.exp(-tau_above / mu_nodes)[:, None]
    return full - t_dir * below - above


def reflectance(layers, mu0: float, mu_nodes, phi_nodes, albedo: float) -> np.ndarray:
    """The reflectance factor pi I / mu0 (mu_nodes x phi_nodes) at the top of ``layers`` ((optical depth, albedo,
    moments) of ``air_layers``, top first) over a Lambertian surface of ``albedo``: one DISORT solve."""
    from ..optics.disort import solve
    tau, ssa, moments = layers
    mu_nodes, phi_nodes = np.asarray(mu_nodes, np.float64), np.asarray(phi_nodes, np.float64)
    res = solve(tau, ssa, mu0, mu_nodes, [0.0], phi_nodes, moments=moments, surface_albedo=albedo, n_streams=N_STREAMS)
    return np.array([[np.pi * res.intensities(m, 0, p) / mu0 for p in range(phi_nodes.size)]
                     for m in range(mu_nodes.size)])


def air_layers(atm, wavelength_nm: float, ground_m: float = 0.0, split_m=None):
    """``optics.air.layers.air_layers`` with the satellite's ``LAYER_M``."""
    return _layers.air_layers(atm, wavelength_nm, ground_m, split_m, layer_m=LAYER_M)


def _layer_edges(ground_m: float, split_m=None) -> np.ndarray:
    """``optics.air.layers.layer_edges`` with the satellite's ``LAYER_M``."""
    return _layers.layer_edges(ground_m, split_m, layer_m=LAYER_M)


def _layers_above(ground_m: float, top_m: float) -> int:
    """How many of ``air_layers``' layers (split at ``top_m``) lie above ``top_m``."""
    return int(np.sum(_layer_edges(ground_m, top_m) > top_m))


def pixel_angles(scene):
    """Per pixel centre (H, W): (origins (H, W, 3) in the frame with the box's centre at x = y = 0, directions
    (H, W, 3), mu = cos of the view zenith, phi = relative azimuth in deg (0: forward scattering), entry and
    exit distances t0, t1 along the line (t0 > t1: it misses the box)), for the rendered sun."""
    from .rays import box_segment
    vol = scene.vol
    t0, t1, o, d = box_segment(scene.view.rays, vol.bbox)
    (x0, y0, _), (x1, y1, _) = vol.bbox
    o = o - np.array([(x0 + x1) / 2, (y0 + y1) / 2, 0.0])
    sun = np.asarray(scene.spec.sun.to_sun, np.float64)
    dh, sh = d[..., :2], sun[:2]
    cos_phi = np.sum(dh * sh, axis=-1) / np.maximum(np.linalg.norm(dh, axis=-1) * np.linalg.norm(sh), 1e-12)
    return o, d, -d[..., 2], np.degrees(np.arccos(np.clip(cos_phi, -1.0, 1.0))), t0, t1


def with_air_outside(scene, img):
    """``img`` (a reflectance render of ``scene``, ``render_satellite``) with the air outside the box (module
    docstring), per channel at ``scene.vol.air.band_nm``; ``img`` itself without ``scene.spec.atmosphere``."""
    atm = scene.spec.atmosphere
    if atm is None:
        return img
    band_nm = scene.vol.air.band_nm
    o, d, mu, phi, t0, t1 = pixel_angles(scene)
    hit = t0 <= t1
    if scene.vol.periodic and scene.vol.periodic != "transport":  # the copies seen: A ends at the model top
        t0, hit = np.where(hit, t0, 0.0), np.ones_like(hit)
    mu0 = float(scene.spec.sun.mu0)
    rad = np.asarray(img.radiance, np.float64).copy()
    se = None if img.stderr is None else np.asarray(img.stderr, np.float64).copy()
    t_box = None if img.transmittance is None else np.asarray(img.transmittance, np.float64)[hit]
    col = ColumnTerms(atm, scene, mu, phi, mu0)
    t_a, r_a = _through_box(scene, col, t_box, o[hit], d[hit], mu[hit], phi[hit], t0[hit], t1[hit], band_nm)
    rad[hit] = r_a + t_a * rad[hit] + _coupling(col, mu[hit], phi[hit], band_nm, scene)
    if se is not None:
        se[hit] = t_a * se[hit]
    if (~hit).any():
        rad[~hit], surface = _past_box(col, mu[~hit], phi[~hit], rad[~hit], band_nm)
        if se is not None:
            se[~hit] = se[~hit] * surface
    meta = {**img.metadata, "air_outside": {"above_box_px": int(hit.sum()), "past_box_px": int((~hit).sum())}}
    return replace(img, radiance=rad.astype(np.float32), stderr=None if se is None else se.astype(np.float32),
                   metadata=meta)


def _sun_table(atm, start, band_nm, mu0):
    """The direct sun per channel over the heights and the band of mu that the lines of sight from ``start``
    (their points at the top of the air, (n, 3)) and the box see (``eye_path.wide_sun_table``)."""
    from ..optics.air.eye_path import wide_sun_table
    reach = float(np.max(np.linalg.norm(start[:, :2], axis=-1), initial=0.0)) + 50e3
    return wide_sun_table(atm, mu0, reach_m=reach, n_mu=17, n_h=61, band_nm=band_nm)


class ColumnTerms:
    """The clear plane-parallel column's DISORT terms (R_0, K, s of ``plane_parallel_terms``, its layers split at
    the box's top) per wavelength, each solved once, on one (mu, phi) grid spanning every line of sight of a view:
    shared by the lines that miss the box (``_past_box``), the side walls' ratio (``_path_reflectance``) and the
    coupling above the box, whose whole column over a surface of albedo a is R_0 + a K / (1 - a s) (``full``)."""

    def __init__(self, atm, scene, mu, phi, mu0: float):
        self.atm, self.mu0 = atm, float(mu0)
        self.ground, self.top = ground_height_m(scene), float(scene.vol.bbox[1][2])
        self.mu_nodes, self.phi_nodes = _grid(np.ravel(mu), np.ravel(phi))
        self._terms = {}

    def terms(self, wl: float):
        """(R_0, K, s) on the grid at ``wl`` (nm)."""
        if wl not in self._terms:
            self._terms[wl] = plane_parallel_terms(self.atm, wl, self.mu0, self.mu_nodes, self.phi_nodes, self.ground,
                                                   split_m=self.top)
        return self._terms[wl]

    def full(self, wl: float, albedo: float):
        """The whole column's reflectance over a Lambertian surface of ``albedo`` on the grid (Chandrasekhar)."""
        r0, k, s = self.terms(wl)
        return r0 + albedo * k / (1.0 - albedo * s)

    def at(self, values, mu, phi):
        """``values`` on the grid interpolated at (mu, phi) (n,)."""
        from scipy.interpolate import RegularGridInterpolator
        return RegularGridInterpolator((self.mu_nodes, self.phi_nodes), values)(np.stack([mu, phi], axis=-1))


def _through_box(scene, col, t_box, o, d, mu, phi, t0, t1, band_nm):
    """(T_A (n, 3), the air's reflectance added (n, 3)) of lines of sight through the box: A from the top of the
    air to the box entry ``t0`` (single scattering), and B from a side wall's exit ``t1`` down to the ground
    (single scattering times the column's ratio of all orders to the first, R_0 / (pi S_column / mu0),
    seen through A and the box: ``t_box`` (n,), the render's eye-ray transmittance, or None); the air and mu0
    are ``col``'s. Each segment's air is ``eye_path.segment_air`` (one compiled march)."""
    from ..optics.air.eye_path import segment_air, top_distance
    back = top_distance(o, -d)                      # from the start back up to the top of the air
    start = o - back[:, None] * d
    mu0 = col.mu0
    table = _sun_table(col.atm, start, band_nm, mu0)

    def segments(k, s0, s1):  # (T, S) (n, 3) over [s0, s1] along the lines k from ``start``
        return segment_air(col.atm, scene.spec.sun.to_sun, start[k], d[k], s0, s1, table, wavelengths_nm=band_nm)
    t_a, s_a = segments(slice(None), np.zeros(back.shape), back + np.maximum(t0, 0.0))
    floor = 0.0 if scene.spec.ground is None else float(scene.spec.ground.height)
    t_ground = (floor - o[:, 2]) / np.minimum(d[:, 2], -1e-9)
    side = (t1 < t_ground - 1.0) & ~(scene.vol.periodic and scene.vol.periodic != "transport")
    added = np.pi * s_a / mu0
    if side.any():
        k = np.flatnonzero(side)
        _, s_b = segments(k, back[k] + t1[k], back[k] + t_ground[k])
        _, s_col = segments(k, np.zeros(k.size), back[k] + t_ground[k])
        ratio = _path_reflectance(col, mu[k], phi[k], band_nm) / np.maximum(np.pi * s_col / mu0, 1e-12)
        seen = 1.0 if t_box is None else t_box[k, None]
        added[k] += t_a[k] * seen * ratio * np.pi * s_b / mu0
    return t_a, added


def _path_reflectance(col, mu, phi, band_nm):
    """R_0 (n, 3): the clear column's reflectance over a black surface (DISORT) at the lines' angles."""
    return np.stack([col.at(col.terms(wl)[0], mu, phi) for wl in band_nm], axis=-1)


def _grid(mu, phi):
    """(mu nodes, phi nodes) spanning the lines of sight's angles, for interpolating DISORT's terms."""
    mu_nodes = np.linspace(mu.min(), max(mu.max(), mu.min() + 1e-4), 5)
    phi_nodes = np.linspace(phi.min(), max(phi.max(), phi.min() + 1e-3), 7)
    return mu_nodes, phi_nodes


def _coupling(col, mu, phi, band_nm, scene):
    """``above_box_coupling`` (n, 3) at the lines of sight's angles, per channel (the ground's albedo there)."""
    albedo = (0.0,) * 3 if scene.spec.ground is None else scene.spec.ground.albedo
    out, done = np.zeros((mu.size, 3)), {}
    for c, (wl, a) in enumerate(zip(band_nm, albedo)):
        if (wl, a) not in done:
            table = above_box_coupling(col.atm, wl, col.mu0, col.mu_nodes, col.phi_nodes, col.ground, col.top, a,
                                       full=col.full(wl, a))
            done[(wl, a)] = col.at(table, mu, phi)
        out[:, c] = done[(wl, a)]
    return out


def _past_box(col, mu, phi, rendered, band_nm):
    """(reflectance (n, 3), the factor on the rendered surface term (n, 3)) of the lines of sight that miss the
    box (module docstring), the plane-parallel terms interpolated in (mu, phi) per distinct wavelength."""
    from ..optics.air.sunlight import transmittance
    out, factor = np.empty_like(rendered), np.empty_like(rendered)
    for wl in sorted(set(band_nm)):
        r0, k, s = (col.at(v, mu, phi) for v in col.terms(wl))
        t_dir = float(transmittance(col.atm, [wl], col.ground, col.mu0)[0])
        for c in (c for c, w in enumerate(band_nm) if w == wl):
            a = np.clip(rendered[:, c] / t_dir, 0.0, 1.0)
            factor[:, c] = k / (t_dir * (1.0 - a * s))
            out[:, c] = r0 + rendered[:, c] * factor[:, c]
    return out, factor


def ground_height_m(scene) -> float:
    """The scene's flat ground (m above sea level, >= 0; sea level without one): where the 1-D air starts."""
    return 0.0 if scene.spec.ground is None else max(float(scene.spec.ground.height), 0.0)


def column_rayleigh_optical_depth(atm, wavelength_nm: float, ground_m: float = 0.0) -> float:
    """The molecules' vertical optical depth of ``atm`` from ``ground_m`` to its top at ``wavelength_nm``: what
    the true-colour recipe's Rayleigh correction subtracts over (``truecolor``)."""
    from ..optics.rayleigh import cross_section_m2
    from ..optics.air.atmosphere import TOP_M
    z = np.linspace(ground_m, TOP_M, 8001)
    return float(np.trapezoid(atm.air_number_density_m3(z), z) * cross_section_m2(wavelength_nm * 1e-9))


__all__ = ["air_layers", "above_box_coupling", "plane_parallel_terms", "pixel_angles", "with_air_outside",
           "column_rayleigh_optical_depth", "ground_height_m"]
