"""The sea surface's BRDF (``kernel.sea_surface``: Mitsuba's ``roughplastic``, Beckmann) against the Cox-Munk
(1954) glint written out here: f = F(omega) p(z_x, z_y) / (4 mu_i mu_o cos^4 beta), with
p = exp(-tan^2 beta / sigma^2) / (pi sigma^2), sigma^2 = 0.003 + 0.00512 W and unpolarised Fresnel of n = 1.34."""
import numpy as np
import pytest

import weather_mi as wm


def direction(theta_deg, phi_deg):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])


def cox_munk_brdf(wi, wo, wind_m_s, n=1.34):
    """Cox & Munk's glint BRDF (1/sr) for unit vectors towards the sun (wi) and the viewer (wo), z up."""
    sigma2 = 0.003 + 0.00512 * wind_m_s                  # Cox-Munk 1954, clean surface, isotropic
    h = (wi + wo) / np.linalg.norm(wi + wo)              # the facet normal that mirrors wi into wo
    cos_beta = h[2]
    tan2 = (1 - cos_beta ** 2) / cos_beta ** 2
    p = np.exp(-tan2 / sigma2) / (np.pi * sigma2)        # slope density
    ci = wi @ h                                          # incidence on the facet
    ct = np.sqrt(1 - (1 - ci ** 2) / n ** 2)
    rs, rp = (ci - n * ct) / (ci + n * ct), (n * ci - ct) / (n * ci + ct)
    return (rs ** 2 + rp ** 2) / 2 * p / (4 * wi[2] * wo[2] * cos_beta ** 4)


def mitsuba_brdf(bsdf, wi, wo):
    import drjit as dr
    import mitsuba as mi
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(*map(float, wi))
    si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
    value = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*map(float, wo)))  # f cos(theta_o)
    return float(np.array(value).ravel()[0]) / wo[2]


GEOMETRIES = [(30, 0, 30, 180), (40, 0, 20, 180), (50, 0, 45, 170), (10, 0, 5, 180), (60, 0, 55, 185),
              (30, 0, 10, 200), (20, 0, 35, 150)]


@pytest.mark.parametrize("wind", [0.0, 5.0, 12.0])
def test_sea_surface_brdf_is_cox_munk(wind):
    import mitsuba as mi
    from weather_mi.kernel.sea_surface import sea_bsdf_dict
    wm.set_variant("llvm_ad_rgb")
    bsdf = mi.load_dict(sea_bsdf_dict(wind, (0.0, 0.0, 0.0)))  # the glint alone
    for ti, pi_, to, po in GEOMETRIES:
        wi, wo = direction(ti, pi_), direction(to, po)
        want = cox_munk_brdf(wi, wo, wind)
        assert want > 1e-6
        assert mitsuba_brdf(bsdf, wi, wo) == pytest.approx(want, rel=1e-4), (wind, ti, to, po)


def test_sea_surface_water_body_adds_a_dim_lambertian_part():
    """The water body's albedo adds a nearly constant diffuse term (its albedo pi f: 0.02 within a factor 2,
    through the interface), far below the glint at its centre."""
    import mitsuba as mi
    from weather_mi.kernel.sea_surface import sea_bsdf_dict
    wm.set_variant("llvm_ad_rgb")
    glint = mi.load_dict(sea_bsdf_dict(5.0, 0.0))
    both = mi.load_dict(sea_bsdf_dict(5.0, 0.02))
    wi = direction(40, 0)
    far = [both_minus for both_minus in (mitsuba_brdf(both, wi, direction(t, 90)) - mitsuba_brdf(glint, wi, direction(t, 90))
                                         for t in (5, 20, 40))]
    assert np.ptp(far) < 0.2 * np.mean(far) and 0.01 < np.mean(far) * np.pi < 0.04
    assert mitsuba_brdf(both, wi, direction(40, 180)) > 10 * np.mean(far)


def test_wind_is_checked():
    from weather_mi.kernel.sea_surface import mean_square_slope
    assert mean_square_slope(0.0) == pytest.approx(0.003) and mean_square_slope(10.0) == pytest.approx(0.0542)
    with pytest.raises(ValueError, match="--wind"):
        mean_square_slope(-1.0)
