"""Optics of a satellite band (weather_mi/satellite/bands.py, phase/mie.py at one wavelength) and of the molecular
atmosphere (weather_mi/optics/rayleigh.py), against closed forms and published values."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.optics import rayleigh
from weather_mi.io.standard_atmosphere import standard_density
from weather_mi.satellite.bands import band, band_volume
from weather_mi.optics.phase.mie import mie_cloud, water_index


@pytest.mark.parametrize("wavelength_nm", [450.0, 550.0, 640.0, 865.0])
def test_bodhaine_fit_matches_the_cross_section_from_its_definition(wavelength_nm):
    """Bodhaine et al. (1999) Eq. 29 against Eq. 2 with Peck & Reeder's refractive index and Bates' King
    factor: they quote the fit within 0.01% over 0.25-1 um."""
    lam = wavelength_nm * 1e-9
    assert rayleigh.cross_section_m2(lam) == pytest.approx(rayleigh.cross_section_physical_m2(lam), rel=2e-4)


@pytest.mark.parametrize("wavelength_um", [0.45, 0.55, 0.64, 0.865])
def test_rayleigh_optical_depth_of_the_standard_atmosphere(wavelength_um):
    """The column of the 1976 standard atmosphere (0-84 km, numerically) against the hydrostatic closed form
    tau = sigma P0 N_A / (M_air g0) (Bodhaine Eq. 4; g falls with height, +0.3% of column mass per g0), and
    that against Hansen & Travis (1974, Eq. 2.29) for sea-level pressure,
    tau = 0.008569 lambda^-4 (1 + 0.0113 lambda^-2 + 0.00013 lambda^-4) (lambda in um; 0.0973 at 0.55 um;
    their older refractive index and depolarisation put it 0.2-0.5% above Bodhaine's)."""
    lam = wavelength_um * 1e-6
    z = np.linspace(0.0, 84000.0, 84001)
    beta = rayleigh.beta_per_m(lam, standard_density(z))
    tau = float(np.sum((beta[1:] + beta[:-1]) / 2 * np.diff(z)))
    closed = float(rayleigh.cross_section_m2(lam)) * 101325.0 * rayleigh.AVOGADRO / (rayleigh.M_AIR_KG_MOL * 9.80665)
    assert tau == pytest.approx(closed, rel=5e-3)
    l = wavelength_um
    hansen_travis = 0.008569 * l ** -4 * (1 + 0.0113 * l ** -2 + 0.00013 * l ** -4)
    assert closed == pytest.approx(hansen_travis, rel=6e-3)


def test_rayleigh_phase_function_is_normalised_with_its_depolarisation():
    mu = np.linspace(-1.0, 1.0, 20001)
    p = rayleigh.phase_value(mu)
    assert 2 * np.pi * float(np.sum((p[1:] + p[:-1]) / 2 * np.diff(mu))) == pytest.approx(1.0, rel=1e-8)
    gamma = 0.0279 / (2 - 0.0279)  # Chandrasekhar: p(90) / p(0) = (1 + 3 gamma) / (2 + 2 gamma)
    assert rayleigh.phase_value(0.0) / rayleigh.phase_value(1.0) == pytest.approx((1 + 3 * gamma) / (2 + 2 * gamma))
    t = rayleigh.phase_table()
    assert float(t.g[1]) == pytest.approx(0.0, abs=1e-6)


def test_with_rayleigh_adds_a_conservative_species():
    beta = np.zeros((4, 3, 3), np.float32)
    beta[1:3, 1, 1] = 0.01
    vol = wm.OpticalVolume.from_arrays(beta, 0.9, wm.phase.henyey_greenstein(0.8), ((0, 0, 0), (3000, 3000, 4000)))
    rho = np.full(beta.shape, 1.0, np.float32)
    air = rayleigh.with_rayleigh(vol, 640e-9, rho)
    b_r = rayleigh.beta_per_m(640e-9, 1.0)
    assert air.species[-1] == "rayleigh" and len(air.phase_tables) == len(air.species)
    np.testing.assert_allclose(air.beta_total, beta + b_r, rtol=1e-6)
    np.testing.assert_allclose(air.weights.sum(axis=0), 1.0, rtol=1e-6)
    assert np.all(air.albedo[0] == 1.0)  # clear air scatters conservatively
    w = air.albedo[1, 1, 1, 0]  # (0.9 beta + b_r) / (beta + b_r)
    assert w == pytest.approx((0.9 * 0.01 + b_r) / (0.01 + b_r), rel=1e-6)
    assert air.weights[-1, 1, 1, 1] == pytest.approx(b_r / (0.9 * 0.01 + b_r), rel=1e-5)


def test_water_index_is_hale_and_querry():
    m = water_index(650e-9)
    assert (m.real, -m.imag) == pytest.approx((1.331, 1.64e-8), rel=1e-9)
    assert water_index(640e-9).real == pytest.approx(1.3314, abs=1e-4)
    with pytest.raises(ValueError, match="350-900 nm"):
        water_index(1.6e-6)


def test_band_tables_are_mie_at_the_band_wavelength():
    """One band's cloud table: Mie theory at 640 nm in all three channels; it is not the 650 nm channel
    (size parameter 1.6% larger: the glory and the forward peak move) but close to it."""
    rgb = mie_cloud(quality="test")
    b = mie_cloud(quality="test", wavelength_m=640e-9)
    assert b.wavelengths_m == (640e-9,) * 3
    np.testing.assert_array_equal(b.values[:, 0], b.values[:, 2])
    assert float(b.g[0]) == pytest.approx(float(rgb.g[0]), abs=0.01)
    assert not np.allclose(b.values[:, 0], rgb.values[:, 0], rtol=1e-3)


def test_band_volume_is_grey():
    hyd = wm.synthetic.cumulus()
    vol = wm.optical_volume(hyd, species="physical", phase_quality="test")
    bv = band_volume(vol, band("0.64um"))
    assert bv.attrs["band"] == "0.64"
    np.testing.assert_array_equal(bv.albedo[..., 0], bv.albedo[..., 2])
    np.testing.assert_array_equal(bv.albedo[..., 0], vol.albedo[..., 0])  # the nearest channel, 650 nm
    for t in bv.phase_tables:
        np.testing.assert_array_equal(t.values[:, 0], t.values[:, 1])
    with pytest.raises(ValueError, match="0.47, 0.51, 0.64, 0.86"):
        band("1.6")
