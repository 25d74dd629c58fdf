"""The independent-pixel approximation (IPA): every column of a volume as a plane-parallel stack of layers
with the same optics, solved by DISORT (``disortpp``), the 1-D counterpart of a satellite image.

What a 1-D operator (RTTOV/MFASIS, CRTM) does: each pixel's reflectance is that of the model column at the
pixel's ground point, an infinite horizontally uniform slab under that pixel's sun and view angles: no
shadows cast by neighbours, no lit or shaded cloud sides, no light leaking sideways, no parallax (the
column is the one below the ground point, not the one the slanted line of sight crosses at cloud top).

DISORT: ``n_streams`` streams with delta-M and the Nakajima-Tanaka intensity correction from
``n_moments`` Legendre moments of each layer's Eq. 8 mixture (moments mix linearly with the scattering
weights). Azimuth: DISORT's relative azimuth phi - phi0 = 0 is forward scattering (the scattering angle
cos Theta = -mu0 mu + sin theta0 sin theta cos(phi - phi0)); ``scattering_geometry`` finds it from the sun's
and the sensor's directions.
"""
from __future__ import annotations

import numpy as np

from ..optics.volume import OpticalVolume


def disort_reflectance(tau, ssa, moments, mu0: float, mu: float, phi_rel_deg: float, surface_albedo: float = 0.0,
                       n_streams: int = 32) -> float:
    """Reflectance factor pi I / (mu0 F0) leaving the top of a stack of layers (top first) upwards at cosine
    ``mu``, relative azimuth ``phi_rel_deg`` (DISORT's phi - phi0), for a sun of flux F0 = 1 at cosine mu0
    over a Lambertian surface.

    Parameters
    ----------
    tau, ssa : sequence of float
        Optical depth and single-scattering albedo of each layer, top first.
    moments : array_like, (layers, n_moments + 1)
        Legendre moments of each layer's phase function (moment 0 = 1).
    """
    from ..optics.disort import solve
    res = solve(tau, ssa, mu0, [mu], [0.0], [phi_rel_deg], moments=moments, surface_albedo=surface_albedo,
                n_streams=n_streams)
    return float(np.pi * res.intensities(0, 0, 0) / mu0)


def layer_moments(vol: OpticalVolume, n_moments: int, channel: int = 0) -> list[np.ndarray]:
    """Legendre moments (n_moments + 1,) of every species' table (one channel; a band's channels agree)."""
    return [np.asarray(t.legendre(int(n_moments)), np.float64)[:, channel] for t in vol.require_phase_tables()]


def column_optics(vol: OpticalVolume, j: int, i: int, species_moments: list[np.ndarray], channel: int = 0):
    """(tau, ssa, moments) of column (j, i) of ``vol``, top layer first: tau = beta dz, the mixture albedo,
    and the moments of the Eq. 8 mixture (scattering-weighted; isotropic where nothing scatters)."""
    dz = (vol.bbox[1][2] - vol.bbox[0][2]) / vol.shape[0]
    beta = np.asarray(vol.beta_total[:, j, i], np.float64)
    ssa = np.asarray(vol.albedo[:, j, i, channel], np.float64)
    w = np.asarray(vol.weights[:, :, j, i], np.float64)  # (S, z)
    m = np.einsum("sz,sl->zl", w, np.asarray(species_moments))
    empty = w.sum(axis=0) <= 0
    m[empty] = 0.0
    m[empty, 0] = 1.0
    return (beta * dz)[::-1], ssa[::-1], m[::-1]


def merged_layers(tau, ssa, moments, min_tau: float = 1e-6):
    """The stack without its (nearly) empty layers, those of optical depth below ``min_tau`` (a vacuum does
    nothing in a plane-parallel stack; empty layers are most of a column, and each costs a solve of the
    streams' eigenproblem). A column with nothing left is one empty layer."""
    keep = np.asarray(tau) >= min_tau
    if not np.any(keep):
        return np.array([min_tau]), np.array([0.0]), np.eye(1, np.asarray(moments).shape[1])
    return np.asarray(tau)[keep], np.asarray(ssa)[keep], np.asarray(moments)[keep]


def pixel_directions(scene):
    """Unit vectors (H, W, 3) towards the satellite at the pixel centres in the domain's frame (the mean of
    the corner rays, reversed)."""
    from .rays import pixel_rays
    return -pixel_rays(scene.view.rays)[1]


def scattering_geometry(to_sun, to_sensor):
    """(mu0, mu, DISORT phi - phi0 in degrees) of a sun and a sensor given as unit vectors (z up)."""
    mu0, mu = float(to_sun[2]), float(to_sensor[2])
    cos_scat = -float(np.dot(to_sun, to_sensor))  # light travels along -to_sun, leaves along to_sensor
    sin_sin = np.sqrt(max(1.0 - mu0 * mu0, 0.0) * max(1.0 - mu * mu, 0.0))
    cphi = float(np.clip((cos_scat + mu0 * mu) / sin_sin, -1.0, 1.0)) if sin_sin > 1e-9 else 1.0
    return mu0, mu, float(np.degrees(np.arccos(cphi)))


def surface_points(vol: OpticalVolume, x_m, y_m, to_sensor, iterations: int = 4):
    """(x, y) where each pixel's line of sight meets the surface: from its ground point at sea level
    (x_m, y_m) up the line (``to_sensor``) to the terrain's height there (``Terrain.height_at``, level
    past the grid's edge as the reference's apron), a few fixed-point steps (the terrain's own parallax,
    h tan(VZA): 10 km for the plateau's 4.5 km at 67 deg)."""
    x, y = np.asarray(x_m, float), np.asarray(y_m, float)
    if vol.terrain is None:
        return x, y
    z = np.zeros(x.shape)
    for _ in range(iterations):
        px = x + to_sensor[..., 0] * z / to_sensor[..., 2]
        py = y + to_sensor[..., 1] * z / to_sensor[..., 2]
        z = vol.terrain.height_at(px, py)
    return px, py


def columns_of(vol: OpticalVolume, x_m, y_m):
    """(j, i, inside) of the grid column holding each point (m)."""
    nz, ny, nx = vol.shape
    (x0, y0, _), (x1, y1, _) = vol.bbox
    i = np.floor((np.asarray(x_m) - x0) / (x1 - x0) * nx).astype(int)
    j = np.floor((np.asarray(y_m) - y0) / (y1 - y0) * ny).astype(int)
    return j, i, (i >= 0) & (i < nx) & (j >= 0) & (j < ny)


def bare_surface(vol: OpticalVolume, spec, x_m, y_m) -> np.ndarray:
    """Reflectance of the bare Lambertian surface at points outside the grid: its albedo (the ground's, or
    the terrain's apron within ``terrain.TERRAIN_APRON_M`` of the grid, the surround beyond it)."""
    if vol.terrain is None:
        return np.full(np.shape(x_m), float(np.mean(spec.ground.albedo)))
    from ..io.terrain import TERRAIN_APRON_M
    t = vol.terrain
    x, y = np.asarray(x_m), np.asarray(y_m)
    near = ((x > t.x[0] - TERRAIN_APRON_M) & (x < t.x[-1] + TERRAIN_APRON_M)
            & (y > t.y[0] - TERRAIN_APRON_M) & (y < t.y[-1] + TERRAIN_APRON_M))
    return np.where(near, t.surface_at(x, y)[1], t.edge_albedo())


def ipa_reflectance(scene, n_streams: int = 16, n_moments: int = 256, progress: bool = True) -> np.ndarray:
    """The 1-D counterpart (H, W) of a ``satellite.imagery.SatelliteScene``: at each pixel, DISORT's reflectance
    of the column where the pixel's line of sight meets the surface (``surface_points``: the terrain's
    parallax kept, the clouds' not), under the rendered sun and the pixel's view direction, over that
    column's surface albedo (the terrain's, else the ground's); pixels whose line of sight meets the
    surface outside the domain see the bare surface (``bare_surface``). The optics are the path
    tracer's: the forward peaks within ``forward_peak.DEFAULT_CONE_DEG`` counted as unscattered (delta-M,
    ``forward_peak.delta_scaled``), which also makes the ice and snow tables' Legendre series converge
    (their raw peaks need thousands of moments, and truncated series give negative corrected radiances)."""
    from tqdm.auto import tqdm
    from ..optics.forward_peak import DEFAULT_CONE_DEG, delta_scaled
    vol, spec, view = delta_scaled(scene.vol, DEFAULT_CONE_DEG), scene.spec, scene.view
    nz, ny, nx = vol.shape
    to_sensor = pixel_directions(scene)
    sx, sy = surface_points(vol, view.x_m, view.y_m, to_sensor)
    j, i, inside = columns_of(vol, sx, sy)
    terrain = vol.terrain
    surface = np.full((ny, nx), float(np.mean(spec.ground.albedo))) if terrain is None else np.asarray(terrain.albedo)
    out = np.where(inside, np.nan, bare_surface(vol, spec, sx, sy))
    species_moments = layer_moments(vol, n_moments)
    columns, to_sun = {}, spec.sun.to_sun  # a column's layers serve every pixel that sees it
    for (r, c) in tqdm(list(zip(*np.nonzero(inside))), desc="IPA (DISORT)", unit="px", disable=not progress):
        jj, ii = int(j[r, c]), int(i[r, c])
        if (jj, ii) not in columns:
            columns[jj, ii] = merged_layers(*column_optics(vol, jj, ii, species_moments))
        tau, ssa, mom = columns[jj, ii]
        mu0, mu, phi = scattering_geometry(to_sun, to_sensor[r, c])
        out[r, c] = disort_reflectance(tau, ssa, mom, mu0, mu, phi, float(surface[jj, ii]), n_streams)
    return out


__all__ = ["disort_reflectance", "layer_moments", "column_optics", "merged_layers",
           "pixel_directions", "scattering_geometry", "surface_points", "columns_of", "bare_surface",
           "ipa_reflectance"]
