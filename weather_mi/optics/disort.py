"""DISORT (``disortpp``) as weather-mi sets it up: one function that builds the configuration (Lambertian
surface, user polar angles, optical depths and azimuths, sun flux F0 = 1, delta-M, the Nakajima-Tanaka
intensity correction) and solves it: for the clear air's skylight (``optics.air.skylight``), the satellite's
air outside its box (``satellite.air``), the plane-parallel validation (``plane_parallel.slab.disort_slab``) and
the independent-pixel approximation (``satellite.ipa.disort_reflectance``).

The Nakajima-Tanaka (TMS/IMS) correction is only active in DisORT++ when BOTH ``intensity_corr_buras`` (the
C code's ``corint``) and ``intensity_corr_nakajima`` are set (with only the latter nothing happens); it
uses all ``n_moments`` moments of the phase function.
"""
from __future__ import annotations

import numpy as np


def solve(tau, ssa, mu0: float, mu_user, tau_user, phi_user, *, moments=None, hg_g: float | None = None,
          n_moments: int | None = None, surface_albedo: float = 0.0, n_streams: int = 64):
    """The DisORT++ solution of a stack of layers (top first).

    Parameters
    ----------
    tau, ssa : sequence of float
        Optical depth and single-scattering albedo of each layer.
    mu0 : float
        Cosine of the solar zenith angle (beam flux 1, azimuth 0).
    mu_user, tau_user, phi_user : sequence of float
        Output polar cosines (negative: downward), optical depths and azimuths (degrees; phi - phi0 = 0 is
        forward scattering).
    moments : array_like, (layers, n_moments + 1), optional
        Legendre moments of each layer's phase function; or ``hg_g`` with ``n_moments``: Henyey-Greenstein.
    surface_albedo : float
        Lambertian albedo of the surface.

    Returns
    -------
    disortpp result (``flux_up``, ``flux_down``, ``flux_direct_beam``, ``intensities(mu, tau, phi)``).
    """
    import disortpp
    if moments is not None:
        moments = np.atleast_2d(np.asarray(moments, np.float64))
        n_moments = moments.shape[1] - 1
    cfg = disortpp.DisortConfig(len(tau), int(n_streams), int(n_moments))
    flags = cfg.flags  # a copy: modify and assign back
    flags.comp_only_fluxes = False
    flags.use_lambertian_surface = True
    flags.use_user_mu = True
    flags.use_user_tau = True
    flags.intensity_corr_buras = True
    flags.intensity_corr_nakajima = True
    cfg.flags = flags
    cfg.num_user_mu, cfg.num_user_tau, cfg.num_phi = len(mu_user), len(tau_user), len(phi_user)
    cfg.allocate()
    cfg.delta_tau = [max(float(t), 1e-12) for t in tau]
    cfg.single_scat_albedo = [float(min(max(w, 0.0), 1.0)) for w in ssa]
    if moments is not None:
        cfg.phase_function_moments = [[float(x) for x in m] for m in moments]
    else:
        cfg.set_henyey_greenstein(float(hg_g))
    cfg.mu_user = [float(m) for m in mu_user]
    cfg.tau_user = [float(t) for t in tau_user]
    cfg.phi_user = [float(p) for p in phi_user]
    bc = cfg.bc
    bc.direct_beam_flux, bc.direct_beam_mu, bc.direct_beam_phi = 1.0, float(mu0), 0.0
    bc.surface_albedo, bc.isotropic_flux_top = float(surface_albedo), 0.0
    cfg.bc = bc
    return disortpp.DisortSolver().solve(cfg)


__all__ = ["solve"]
