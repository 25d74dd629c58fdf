"""The diffuse sky of the clear 1-D atmosphere (all orders of scattering), as seen from a height inside it: the
light that the air around the model's box sends into the box (``kernel.air_sky``: the envmap of ``--sky air``).

DISORT (``optics.disort.solve``; the layers of ``air.layers``: molecules, ozone, aerosol of an
``Atmosphere``, a Lambertian ground of one albedo) at ``SKY_WAVELENGTHS_NM`` gives the downward radiance
I(lambda, h, theta, phi) per unit irradiance of the sun above the air (on a plane normal to it) at heights h, view
zenith angles theta < 90 deg (looking up) and azimuths phi relative to the sun's (0: towards it), and the diffuse
irradiance on a horizontal plane F(lambda, h). As ``sunlight.sun_rgb`` does for the direct sun, the spectra
E_toa(lambda) I(lambda) (``optics.spectrum``: ASTM G173's extraterrestrial sun; I linear in log between the
DISORT wavelengths, constant beyond them) are projected to CIE XYZ and linear sRGB and divided by the luminance of
the sun above the air: a radiance per unit (luminance) irradiance of the sun, times the scene's sun irradiance the
sky's radiance. The atmosphere is plane-parallel here (the horizon's radiance of a sphere is finite, this one's
the limit of an infinite path: the last rows near the horizon are brighter than a spherical atmosphere's).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .. import spectrum
from .atmosphere import Atmosphere
from .layers import N_STREAMS, air_layers
from .sunlight import toa_luminance

SKY_WAVELENGTHS_NM = np.arange(400.0, 700.0 + 0.1, 25.0)  # 13 DISORT solves (the sky's spectrum is smooth)
HORIZON_ELEVATION_DEG = 0.5  # a view at the horizon is asked at this elevation (plane-parallel: mu = 0 is singular)


@dataclass(frozen=True)
class SkyTable:
    """The sky's linear sRGB radiance per unit luminance irradiance of the sun above the air (1/sr) on a grid:
    ``heights_m`` (n_h,) ascending, ``zenith_deg`` (n_z,) of the view, ``phi_deg`` (n_phi,) ascending in
    [0, 180] (relative azimuth, 0 towards the sun): ``rgb`` (n_h, n_z, n_phi, 3); ``diffuse_rgb`` (n_h, 3) the
    diffuse irradiance on a horizontal plane there (same unit times sr), ``direct_rgb`` (n_h, 3) the direct
    sun's on it (mu0 times its transmittance), both from DISORT's fluxes."""

    heights_m: np.ndarray
    zenith_deg: np.ndarray
    phi_deg: np.ndarray
    rgb: np.ndarray
    diffuse_rgb: np.ndarray
    direct_rgb: np.ndarray

    def at(self, h_m, zenith_deg, phi_deg) -> np.ndarray:
        """Radiance (..., 3) at heights ``h_m``, view zenith angles and relative azimuths (deg) (...): linear in
        each, clamped to the table (phi folded into [0, 180])."""
        from scipy.interpolate import RegularGridInterpolator
        phi = np.abs((np.asarray(phi_deg, np.float64) + 180.0) % 360.0 - 180.0)
        grids = (self.heights_m, self.zenith_deg, self.phi_deg)
        pts = [np.clip(np.asarray(v, np.float64), g[0], g[-1]) for v, g in zip((h_m, zenith_deg, phi), grids)]
        pts = np.broadcast_arrays(*pts)
        if self.heights_m.size == 1:  # one level: the sky there at every height
            grids, pts, values = grids[1:], pts[1:], self.rgb[0]
        else:
            values = self.rgb
        return RegularGridInterpolator(grids, values)(np.stack(pts, axis=-1))


TABLE_ZENITH_DEG = np.r_[np.arange(0.0, 70.0, 5.0), np.linspace(70.0, 90.0, 12)]  # dense towards the horizon
TABLE_PHI_DEG = np.linspace(0.0, 180.0, 37)


def sky_table(atm: Atmosphere, mu0: float, heights_m, zenith_deg=TABLE_ZENITH_DEG, phi_deg=TABLE_PHI_DEG,
              ground_m: float = 0.0, albedo: float = 0.15) -> SkyTable:
    """The :class:`SkyTable` of ``atm`` with the sun at cos(zenith) ``mu0`` over a ground at ``ground_m`` (m above
    sea level) of Lambertian ``albedo``, at ``heights_m`` (>= ground_m), view zenith angles ``zenith_deg`` (< 90;
    90 is asked at ``HORIZON_ELEVATION_DEG``) and relative azimuths ``phi_deg`` (kept: the same call costs
    nothing the second time)."""
    if not 0.0 < mu0 <= 1.0:
        raise ValueError(f"the sky of the air needs the sun above the horizon (cos(zenith) in (0, 1]), got {mu0}")
    if not 0.0 <= albedo <= 1.0:
        raise ValueError(f"the ground's albedo must be in [0, 1], got {albedo}")
    key = tuple(tuple(np.round(np.asarray(v, np.float64), 6).tolist()) for v in (heights_m, zenith_deg, phi_deg))
    return _sky_table(atm, round(float(mu0), 9), *key, round(float(ground_m), 3), round(float(albedo), 6))


@functools.lru_cache(maxsize=8)
def _sky_table(atm, mu0, heights, zenith, phi, ground_m, albedo) -> SkyTable:
    heights = np.maximum(np.asarray(heights, np.float64), ground_m)
    order = np.argsort(heights)
    heights = heights[order]
    zen = np.minimum(np.asarray(zenith, np.float64), 90.0 - HORIZON_ELEVATION_DEG)
    phi = np.asarray(phi, np.float64)
    radiance, diffuse, direct = spectral_sky(atm, mu0, heights, zen, phi, ground_m, albedo)
    return SkyTable(heights_m=heights, zenith_deg=np.asarray(zenith, np.float64), phi_deg=phi,
                    rgb=rgb(radiance), diffuse_rgb=rgb(diffuse), direct_rgb=rgb(direct))


def rgb(values) -> np.ndarray:
    """Linear sRGB (..., 3) per unit luminance of the sun above the air of quantities (n_wl, ...) per unit
    irradiance of the sun at ``SKY_WAVELENGTHS_NM`` (module docstring: linear in log between them, times the
    top-of-atmosphere sun's spectrum, projected)."""
    wl = spectrum.WAVELENGTHS_NM
    toa = spectrum.solar_toa_w_m2_nm(wl)
    v = np.moveaxis(np.log(np.maximum(np.asarray(values, np.float64), 1e-30)), 0, -1)
    lo = np.clip(np.searchsorted(SKY_WAVELENGTHS_NM, wl, side="right") - 1, 0, SKY_WAVELENGTHS_NM.size - 2)
    f = np.clip((wl - SKY_WAVELENGTHS_NM[lo]) / np.diff(SKY_WAVELENGTHS_NM)[lo], 0.0, 1.0)
    fine = np.exp(v[..., lo] * (1.0 - f) + v[..., lo + 1] * f)
    return spectrum.linear_srgb(spectrum.xyz(fine * toa, wl) / toa_luminance(wl))


def transmittance_rgb(values) -> np.ndarray:
    """The factor per linear sRGB channel (..., 3) that transmittances T (n_wl, ...) at ``SKY_WAVELENGTHS_NM`` put
    on the light of the top-of-atmosphere sun: rgb(T) / rgb(1) (:func:`rgb`), exact for light of that spectrum
    (a cloud lit by the sun, the daylight-white sky), a von Kries-like diagonal for other light (``docs/spectral.md``
    measures the difference)."""
    return rgb(values) / rgb(np.ones(SKY_WAVELENGTHS_NM.size))


DIFFUSE_TOP_M, DIFFUSE_STEP_M = 30e3, 500.0  # the diffuse light's table (above 30 km the air scatters < 1 %)


def diffuse_source_table(atm: Atmosphere, mu0: float, ground_m: float = 0.0, albedo: float = 0.15, band_nm=None):
    """The mean intensity J(h) = (1/4 pi) int L_diffuse dOmega of the diffuse light (down and up, all orders;
    DISORT) per unit irradiance of the sun above the air, on heights ``ground_m`` .. ``DIFFUSE_TOP_M`` every
    ``DIFFUSE_STEP_M``: a ``SunAirTable`` independent of mu (two identical rows), the source of the air's multiple
    scattering along an eye ray, beta_s J (an isotropic phase function: ``eye_path.segment_air(isotropic=True)``).
    Per channel: linear sRGB (``rgb``), or at the wavelengths ``band_nm`` (3,)."""
    from .sunlight import SunAirTable
    if not 0.0 < mu0 <= 1.0:
        raise ValueError(f"the sky of the air needs the sun above the horizon (cos(zenith) in (0, 1]), got {mu0}")
    key = None if band_nm is None else tuple(float(w) for w in band_nm)
    return _diffuse_table(atm, round(float(mu0), 9), round(float(ground_m), 3), round(float(albedo), 6), key,
                          SunAirTable)


@functools.lru_cache(maxsize=8)
def _diffuse_table(atm, mu0, ground_m, albedo, band_nm, table_class):
    from ..disort import solve
    heights = np.arange(ground_m, DIFFUSE_TOP_M + 1.0, DIFFUSE_STEP_M)
    wls = SKY_WAVELENGTHS_NM if band_nm is None else np.asarray(band_nm, np.float64)
    j = []
    for wl in wls:
        tau, ssa, moments = air_layers(atm, float(wl), ground_m, split_m=heights)
        res = solve(tau, ssa, mu0, [-1.0], _tau_at(tau, ground_m, heights), [0.0], moments=moments,
                    surface_albedo=albedo, n_streams=N_STREAMS)
        j.append((np.asarray(res.mean_intensity_down) + np.asarray(res.mean_intensity_up))[::-1])
    values = rgb(np.asarray(j)) if band_nm is None else np.asarray(j).T
    return table_class(heights_m=heights, mu=np.array([-1.0, 1.0]),
                       rgb=np.stack([values, values]).astype(np.float32))


def spectral_sky(atm: Atmosphere, mu0: float, heights_m, zenith_deg, phi_deg, ground_m: float = 0.0,
                 albedo: float = 0.15, wavelengths_nm=SKY_WAVELENGTHS_NM):
    """DISORT's (radiance (n_wl, n_h, n_z, n_phi), diffuse irradiance on a horizontal plane (n_wl, n_h), direct
    (n_wl, n_h)) per unit irradiance of the sun above the air, at ``heights_m`` (ascending, m above sea level),
    view zenith angles ``zenith_deg`` (< 90: looking up) and azimuths ``phi_deg`` (0: towards the sun)."""
    from ..disort import solve  # DISORT's one set-up (a leaf module over disortpp)
    heights = np.asarray(heights_m, np.float64)
    mu_user = -np.cos(np.radians(np.asarray(zenith_deg, np.float64)))  # downward-travelling light: looking up
    m_order = np.argsort(mu_user)                                       # DISORT wants them ascending
    out_i, out_dn, out_dir = [], [], []
    for wl in np.asarray(wavelengths_nm, np.float64):
        tau, ssa, moments = air_layers(atm, float(wl), ground_m, split_m=heights)
        tau_user = _tau_at(tau, ground_m, heights)
        res = solve(tau, ssa, mu0, mu_user[m_order], tau_user, phi_deg, moments=moments, surface_albedo=albedo,
                    n_streams=N_STREAMS)
        i = np.empty((heights.size, mu_user.size, len(phi_deg)))
        i[:, m_order] = np.asarray(res.intensity, np.float64)[::-1]  # (tau top first, mu, phi) -> heights ascending
        out_i.append(i)
        out_dn.append(np.asarray(res.flux_down, np.float64)[::-1])
        out_dir.append(np.asarray(res.flux_direct_beam, np.float64)[::-1])
    return np.asarray(out_i), np.asarray(out_dn), np.asarray(out_dir)


def _tau_at(tau, ground_m: float, heights) -> list:
    """DISORT's user optical depths (from the top, ascending) of ``heights`` (ascending), which are edges of
    ``air_layers(..., split_m=heights)``."""
    from .layers import layer_edges
    edges = layer_edges(ground_m, heights)              # ascending, len(tau) + 1
    cum_from_top = np.r_[0.0, np.cumsum(tau)]           # at edges[::-1]
    top_down = edges[::-1]
    return [float(cum_from_top[int(np.argmin(np.abs(top_down - h)))]) for h in heights[::-1]]


__all__ = ["SkyTable", "sky_table", "spectral_sky", "diffuse_source_table", "rgb", "transmittance_rgb",
           "SKY_WAVELENGTHS_NM"]
