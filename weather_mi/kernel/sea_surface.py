"""The sea surface as Mitsuba sees it: a wind-roughened Fresnel interface (the sun glint) over a dim Lambertian
water body.

Cox & Munk (1954, J. Opt. Soc. Am. 44, 838; J. Mar. Res. 13, 198), clean surface, isotropic: the sea's facet
slopes (z_x, z_y) are Gaussian with total mean square slope

    sigma^2 = 0.003 + 0.00512 W                      (Cox-Munk Eq. 1; W: wind speed 10 m above the sea, m/s)

    p(z_x, z_y) = exp(-(z_x^2 + z_y^2) / sigma^2) / (pi sigma^2)

and the glint's BRDF is f = F(omega) p / (4 mu_i mu_o cos^4 beta) (beta the facet's tilt, omega the angle of
incidence on it, F unpolarised Fresnel reflectance of water, n = 1.34). That is the microfacet BRDF with a
Beckmann distribution D(m) = exp(-tan^2 beta / alpha^2) / (pi alpha^2 cos^4 beta) of alpha^2 = sigma^2 (its mean
square slope, Walter et al. 2007 Eq. 25), times the Smith shadowing G, which is exactly 1 in Mitsuba's Beckmann
unless a direction is within 1 / (1.6 alpha) of grazing (tan theta > 3.7 at 5 m/s). Mitsuba's ``roughplastic``
is that interface (``distribution = beckmann``, ``alpha``, ``int_ior``) over a Lambertian base
(``diffuse_reflectance``, seen through the interface's transmission and internal reflection): the water-leaving
light, small (``io.land_use.WATER_BODY_ALBEDO``). ``tests/test_sea_surface.py`` checks its BRDF against the
Cox-Munk closed form.
"""
from __future__ import annotations

import numpy as np

WATER_IOR = 1.34               # refractive index of sea water in the visible (Hale & Querry 1973: 1.331-1.337, + salt)
DEFAULT_WIND_M_S = 5.0         # the wind where the file has no U10/V10 (m/s)


def mean_square_slope(wind_m_s: float) -> float:
    """Cox-Munk's isotropic mean square slope sigma^2 = 0.003 + 0.00512 W of a clean sea at wind W (m/s)."""
    w = float(wind_m_s)
    if not (np.isfinite(w) and w >= 0.0):
        raise ValueError(f"--wind {wind_m_s}: expected a wind speed >= 0 m/s")
    return 0.003 + 0.00512 * w


def sea_bsdf_dict(wind_m_s: float, water_body_albedo=(0.02, 0.02, 0.02)) -> dict:
    """The sea surface (module docstring) as a Mitsuba ``roughplastic`` dict: Beckmann alpha = sqrt(sigma^2) of
    Cox-Munk at ``wind_m_s``, water's index, the water body's Lambertian albedo (RGB: one per channel)."""
    rgb = [float(v) for v in np.broadcast_to(np.asarray(water_body_albedo, float), (3,))]
    return {"type": "roughplastic", "distribution": "beckmann", "alpha": float(np.sqrt(mean_square_slope(wind_m_s))),
            "int_ior": WATER_IOR, "ext_ior": 1.0, "nonlinear": False,
            "diffuse_reflectance": {"type": "rgb", "value": rgb}}


__all__ = ["mean_square_slope", "sea_bsdf_dict", "WATER_IOR", "DEFAULT_WIND_M_S"]
