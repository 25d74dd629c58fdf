"""Issue 38's reference for a distant lit cloud: sun and sky seen through the same air (midday38).

What a white, diffusely reflecting cloud lit by SPCTRL2's sun and sky at the lit cloud's height looks like from
the camera, per lit pixel i (its eye ray from the camera to where it reaches optical depth 1 in the cloud):

    L_ref(lambda) = T_i(lambda) k E(lambda) / pi + L_path,i(lambda)                                   (1)

averaged over the lit pixels. E: SPCTRL2's irradiance at the cloud's height (``sun_colour.spectrl2_at_height``:
global horizontal, sun and sky; or direct normal). k: one number, fixed by equal luminance (Y of L_ref = Y of
the rendered lit cloud: the comparison is of chromaticity at equal lightness, as the headline's).

T_i: the eye path's transmittance, Beer-Lambert through an atmosphere written out here and not taken from
``optics.air``: molecules (Bodhaine et al. 1999 Eq. 29 cross section, the U.S. Standard Atmosphere 1976's
number density by its layer formulas), ozone (a Gaussian layer of 0.3 atm-cm at 22 km, sigma 7 km: the profile
our ``Atmosphere`` documents, absorbing with SPCTRL2's Chappuis table ``optics.air.ozone``, a published table),
aerosol (AOD 0.1 at 550 nm, exp(-z / 1.2 km), Angstrom 1.14, albedo 0.945, Henyey-Greenstein g 0.65: SPCTRL2's
rural aerosol as our ``Atmosphere()``'s defaults hold it). Water vapour is left out (its bands, 593 and 690-740 nm,
move a path's chromaticity by < 0.002).

L_path,i: the light the air itself sends along that path (in-scattered sun and sky, all orders), from DISORT on
the same atmosphere's layers (plane-parallel, the sun at the cosine whose air mass is Kasten & Young's: DisORT++'s
pseudo-spherical beam gave diffuse radiances 4x the plane-parallel ones at a 30 deg sun, unusable), not from our
renderer: in a horizontally homogeneous clear atmosphere the radiance along a straight ray obeys
I(camera) = L_path + T I(end), so

    L_path,i(lambda) = I(z_cam, mu_i, phi_i) - T_i(lambda) I(z_end,i, mu_i, phi_i)                      (2)

with I DISORT's radiance travelling towards the camera (mu_i = -d_z of the view direction, phi_i its azimuth
from the sun beam's) at the camera's and at the tau = 1 point's heights; per unit solar irradiance at the top,
times ASTM G173's extraterrestrial spectrum over its luminance (the render's unit: the sun above the air has
luminance 1). What (2) leaves out, as the renders have it: the storm's shadow on the air in front of it and the
sky the storm hides from that air, the storm's own light scattered into the path, a flat Earth for the eye path
(40 km: the Earth's curvature lowers the far end by 0.13 km), the diffuse light's plane-parallel geometry.
"""
from __future__ import annotations

import numpy as np

AOD_550, AEROSOL_SCALE_M, ANGSTROM, AEROSOL_SSA, AEROSOL_G = 0.1, 1200.0, 1.14, 0.945, 0.65
OZONE_ATM_CM, OZONE_PEAK_M, OZONE_SIGMA_M = 0.3, 22e3, 7e3
LOSCHMIDT_M3 = 2.6867811e25            # molecules per m^3 at 0 degC and 1 atm (CODATA 2018): 1 atm-cm per m^2
DEPOLARISATION = 0.0279                # Young (1980)'s depolarisation factor of air (Rayleigh's phase function)
TOP_M = 80e3
DISORT_NM = np.arange(380.0, 780.0 + 0.1, 25.0)   # 17 solves, the path's light log-linear between them
STREAMS = 16

# U.S. Standard Atmosphere 1976 to 84.852 km: base height (m), base temperature (K), lapse rate (K/m), base pressure
# (Pa); geometric heights used as geopotential (0.3 % at 20 km)
_US76 = ((0.0, 288.15, -0.0065, 101325.0), (11000.0, 216.65, 0.0, 22632.06), (20000.0, 216.65, 0.001, 5474.889),
         (32000.0, 228.65, 0.0028, 868.0187), (47000.0, 270.65, 0.0, 110.9063), (51000.0, 270.65, -0.0028, 66.93887),
         (71000.0, 214.65, -0.002, 3.956420))
_G0_M_OVER_R = 0.0341632               # g0 M / R* (K/m), the 1976 standard's


def us_standard_number_density_m3(z_m) -> np.ndarray:
    """Air molecules per m^3 of the U.S. Standard Atmosphere 1976 (its layer formulas, written out): in a layer of
    lapse L from (z_b, T_b, p_b), T = T_b + L (z - z_b), p = p_b (T_b / T)^(g0 M / (R* L)), or p_b exp(-g0 M
    (z - z_b) / (R* T_b)) where L = 0; n = p / (k T)."""
    z = np.clip(np.asarray(z_m, np.float64), 0.0, 84852.0)
    t, p = np.empty_like(z), np.empty_like(z)
    for zb, tb, lapse, pb in _US76:
        at = z >= zb
        tt = tb + lapse * (z - zb)
        with np.errstate(divide="ignore", invalid="ignore"):
            pp = (pb * (tb / tt) ** (_G0_M_OVER_R / lapse) if lapse else pb * np.exp(-_G0_M_OVER_R * (z - zb) / tb))
        t, p = np.where(at, tt, t), np.where(at, pp, p)
    return p / (1.380649e-23 * t)


def rayleigh_cross_section_cm2(wavelength_nm) -> np.ndarray:
    """Bodhaine et al. (1999) Eq. 29: the Rayleigh cross section of dry air (360 ppm CO2), cm^2 per molecule,
    their fit to their Eqs. 1-18 (lambda in um), written out here, not ``optics.air.rayleigh``'s."""
    lam2 = (np.asarray(wavelength_nm, np.float64) / 1000.0) ** 2
    return 1e-28 * (1.0455996 - 341.29061 / lam2 - 0.90230850 * lam2) / (1.0 + 0.0027059889 / lam2 - 85.968563 * lam2)


def ozone_number_density_m3(z_m) -> np.ndarray:
    """Ozone molecules per m^3: a Gaussian layer (OZONE_PEAK_M, OZONE_SIGMA_M) holding OZONE_ATM_CM from 0 to
    TOP_M."""
    from scipy.special import erf
    s = OZONE_SIGMA_M * np.sqrt(2.0)
    held = 0.5 * OZONE_SIGMA_M * np.sqrt(2 * np.pi) * (erf((TOP_M - OZONE_PEAK_M) / s) + erf(OZONE_PEAK_M / s))
    z = np.asarray(z_m, np.float64)
    return OZONE_ATM_CM * LOSCHMIDT_M3 * 0.01 / held * np.exp(-0.5 * ((z - OZONE_PEAK_M) / OZONE_SIGMA_M) ** 2)


def extinction_parts_per_m(wavelength_nm, z_m) -> dict:
    """Extinction (1/m) of molecules, ozone and aerosol at heights (...) and wavelengths (n,): (..., n) each."""
    from weather_mi.optics.air.ozone import cross_section_m2 as ozone_sigma  # SPCTRL2's published table
    wl = np.asarray(wavelength_nm, np.float64)
    z = np.clip(np.asarray(z_m, np.float64), 0.0, None)[..., None]
    return {"air": us_standard_number_density_m3(z) * rayleigh_cross_section_cm2(wl) * 1e-4,
            "ozone": ozone_number_density_m3(z) * ozone_sigma(wl),
            "aerosol": AOD_550 / AEROSOL_SCALE_M * np.exp(-z / AEROSOL_SCALE_M) * (wl / 550.0) ** -ANGSTROM}


def extinction_per_m(wavelength_nm, z_m) -> np.ndarray:
    """The clear air's extinction (1/m), (..., n): the sum of :func:`extinction_parts_per_m`."""
    return sum(extinction_parts_per_m(wavelength_nm, z_m).values())


def path_transmittance(origins, ends, wavelength_nm, points: int = 401, molecules_only: bool = False) -> np.ndarray:
    """Beer-Lambert transmittance (N, n) of straight paths from ``origins`` to ``ends`` (N, 3), m, z the height
    above a flat sea-level ground: exp(-int beta ds), trapezoid over ``points`` points; ``molecules_only``: Rayleigh
    alone."""
    o, e = np.asarray(origins, np.float64), np.asarray(ends, np.float64)
    s = np.linspace(0.0, 1.0, points)
    out = []
    for k in range(0, max(len(o), 1), 16):  # 16 paths at a time: (16, points, n) per part, not (N, points, n)
        ok, ek = o[k:k + 16], e[k:k + 16]
        z = ok[:, None, 2] + s[None, :] * (ek[:, 2] - ok[:, 2])[:, None]
        beta = (extinction_parts_per_m(wavelength_nm, z)["air"] if molecules_only
                else extinction_per_m(wavelength_nm, z))
        out.append(np.exp(-np.trapezoid(beta, s, axis=1) * np.linalg.norm(ek - ok, axis=1)[:, None]))
    return np.concatenate(out)


def layer_edges_m() -> np.ndarray:
    """DISORT's layer edges (m, ascending): 100 m to 16 km (the eye paths), 1 km to 50 km, 5 km to the top."""
    return np.r_[np.arange(0.0, 16e3, 100.0), np.arange(16e3, 50e3, 1000.0), np.arange(50e3, TOP_M + 1.0, 5000.0)]


def layers(wavelength_nm: float, edges_m) -> tuple:
    """(optical depth, single-scattering albedo, Legendre moments (layers, STREAMS + 1)) of the layers between
    ``edges_m`` (ascending), top first: Rayleigh (moments 1, 0, (1 - gamma) / (10 (1 + 2 gamma)), gamma =
    rho / (2 - rho)), ozone absorbing, aerosol Henyey-Greenstein (moments g^l) of albedo AEROSOL_SSA."""
    e = np.asarray(edges_m, np.float64)
    z = np.linspace(e[:-1], e[1:], 17, axis=-1)
    parts = extinction_parts_per_m(np.array([float(wavelength_nm)]), z)
    t_r, t_o, t_a = (np.trapezoid(parts[k][..., 0], z, axis=-1)[::-1] for k in ("air", "ozone", "aerosol"))
    gamma = DEPOLARISATION / (2.0 - DEPOLARISATION)
    chi_r = np.zeros(STREAMS + 1)
    chi_r[0], chi_r[2] = 1.0, (1.0 - gamma) / (10.0 * (1.0 + 2.0 * gamma))
    sca_a = AEROSOL_SSA * t_a
    sca, tau = t_r + sca_a, t_r + t_o + t_a
    moments = (t_r[:, None] * chi_r + sca_a[:, None] * AEROSOL_G ** np.arange(STREAMS + 1)) / sca[:, None]
    return tau, sca / tau, moments


def view_geometry(origins, ends, to_sun) -> tuple:
    """(mu, phi (deg)) of the light travelling from ``ends`` to ``origins`` (N, 3) in DISORT's convention:
    mu = cos of its direction from the zenith (negative: downward), phi its azimuth from the sun beam's (0:
    the light goes the way the sunlight goes)."""
    d = np.asarray(origins, np.float64) - np.asarray(ends, np.float64)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    beam = -np.asarray(to_sun, np.float64)
    a = np.degrees(np.arctan2(d[:, 1], d[:, 0]) - np.arctan2(beam[1], beam[0]))
    return d[:, 2], np.abs((a + 180.0) % 360.0 - 180.0)


def disort_radiance(mu0: float, heights_m, mu, phi, albedo: float = 0.15, wavelengths_nm=DISORT_NM) -> np.ndarray:
    """DISORT's radiance (n_wl, N) per unit irradiance of the sun above the air at heights ``heights_m`` (N,)
    travelling in directions (mu, phi) (N,) (:func:`view_geometry`), the sun at cos(zenith) ``mu0``, a Lambertian
    ground of ``albedo``: a grid of 12 mu (geometric in |mu|: near-level rays) x 7 phi x the layer edges,
    interpolated (linear in each)."""
    mu, phi, heights = (np.asarray(v, np.float64) for v in (mu, phi, heights_m))
    if np.min(np.abs(mu)) < 1e-5:
        raise ValueError(f"a path is level (plane-parallel: mu != 0), got |mu| {np.min(np.abs(mu)):.3g}")
    out = np.empty((len(wavelengths_nm), mu.size))
    for group in (mu < 0.0, mu > 0.0):  # light going down (rays looking up) and up: one DISORT grid each
        if group.any():
            out[:, group] = _radiance_one_way(mu0, heights[group], mu[group], phi[group], albedo, wavelengths_nm)
    return out


def _radiance_one_way(mu0: float, heights_m, mu, phi, albedo: float, wavelengths_nm) -> np.ndarray:
    """:func:`disort_radiance` for directions all downward or all upward."""
    from scipy.interpolate import RegularGridInterpolator
    from weather_mi.optics.disort import solve
    edges = layer_edges_m()
    a = np.abs(mu)  # near-level rays: a grid geometric in |mu|, ascending in mu as DISORT wants it
    mu_grid = np.sign(mu[0]) * np.geomspace(a.min(), a.max(), 12) if np.ptp(a) > 1e-6 else mu[:1]
    mu_grid = np.sort(mu_grid)
    phi_grid = np.linspace(np.min(phi), np.max(phi), 7) if np.ptp(phi) > 1e-3 else np.array([np.min(phi)])
    out = []
    for wl in np.asarray(wavelengths_nm, np.float64):
        tau, ssa, moments = layers(wl, edges)
        tau_user = np.r_[0.0, np.cumsum(tau)]  # at top_down
        res = solve(tau, ssa, mu0, mu_grid, tau_user, phi_grid, moments=moments, surface_albedo=albedo,
                    n_streams=STREAMS)
        i = np.asarray(res.intensity, np.float64)[::-1]  # (heights ascending, mu, phi)
        grids, vals, pts = [edges], i, [np.asarray(heights_m, np.float64)]
        for g, v in ((mu_grid, mu), (phi_grid, phi)):
            if g.size > 1:
                grids.append(g)
                pts.append(np.clip(v, g[0], g[-1]))
            else:
                vals = vals.take(0, axis=len(grids))
        out.append(RegularGridInterpolator(grids, vals)(np.stack(pts, axis=-1)))
    return np.asarray(out)


def effective_mu0(mu0: float) -> float:
    """The plane-parallel sun's cosine whose slant column at the ground is the spherical air's: 1 / m, m Kasten
    & Young (1989)'s relative air mass, 1 / (mu0 + 0.50572 (96.07995 - theta)^-1.6364), theta the zenith angle in
    degrees (Eq. 3; 12.4 at a 4 deg sun against 1 / mu0 = 14.3)."""
    theta = np.degrees(np.arccos(mu0))
    return float(mu0 + 0.50572 * (96.07995 - theta) ** -1.6364)


def path_radiance(origins, ends, to_sun, wavelength_nm, albedo: float = 0.15, disort_nm=DISORT_NM) -> tuple:
    """Eq. 2 per path: (L_path (N, n) per unit irradiance of the sun above the air, T (N, n)) on ``wavelength_nm``
    (the DISORT radiances at ``disort_nm``, log-linear between them, constant beyond)."""
    o, e = np.asarray(origins, np.float64), np.asarray(ends, np.float64)
    mu, phi = view_geometry(o, e, to_sun)
    mu0 = effective_mu0(float(np.asarray(to_sun, np.float64)[2] / np.linalg.norm(to_sun)))
    i = disort_radiance(mu0, np.r_[o[:, 2], e[:, 2]], np.r_[mu, mu], np.r_[phi, phi], albedo, disort_nm)
    wl = np.asarray(wavelength_nm, np.float64)
    fine = np.exp(np.stack([np.interp(wl, disort_nm, np.log(np.maximum(v, 1e-30))) for v in i.T]))  # (2N, n)
    t = path_transmittance(o, e, wl)
    n = o.shape[0]
    return fine[:n] - t * fine[n:], t


def reference_xyz(y_render: float, illuminant, transmittance, l_path, wavelength_nm) -> dict:
    """Eq. 1 (pixel means) as CIE XYZ in the render's unit: ``illuminant`` E (n,) in any unit (k fixes its
    level), ``transmittance`` and ``l_path`` (n,) (path radiance per unit irradiance of the sun above the air); k
    such that Y = ``y_render``. Returns {"xyz", "path_xyz" (L_path's share), "k"}. A ValueError if the air's own
    light is brighter than the rendered cloud (no k >= 0)."""
    from weather_mi.optics import spectrum
    from weather_mi.optics.air.sunlight import toa_luminance
    wl = np.asarray(wavelength_nm, np.float64)
    path = spectrum.xyz(spectrum.solar_toa_w_m2_nm(wl) * l_path, wl) / toa_luminance(spectrum.WAVELENGTHS_NM)
    lit = spectrum.xyz(np.asarray(transmittance) * np.asarray(illuminant) / np.pi, wl)
    k = (float(y_render) - path[1]) / lit[1]
    if k < 0.0:
        raise ValueError(f"the air's own light (Y {path[1]:.4g}) is brighter than the rendered cloud ({y_render:.4g})")
    return {"xyz": k * lit + path, "path_xyz": path, "k": k}


__all__ = ["us_standard_number_density_m3", "rayleigh_cross_section_cm2", "ozone_number_density_m3",
           "extinction_parts_per_m", "extinction_per_m", "path_transmittance", "layers", "view_geometry",
           "disort_radiance", "effective_mu0", "path_radiance", "reference_xyz"]
