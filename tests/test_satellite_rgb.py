"""``weather-mi satellite --rgb`` (weather_mi/satellite/truecolor.py, bands.rgb_volume): the true-colour recipe
against the published coefficients and a pixel worked by hand, the Rayleigh reflectance against the
single-scattering closed form, the demo's picture (white clouds, a blue sea) and the refusals before rendering."""
from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
import xarray as xr

import weather_mi as wm
from weather_mi.cli import commands as cli
from weather_mi.satellite import truecolor as tc
from weather_mi.satellite.bands import band, band_volume, rgb_volume, true_color_bands
from weather_mi.satellite.geostationary import satellite

DEMO = ["satellite", "--demo", "supercell", "--lat", "35.2", "--lon", "-97.4", "--date", "2013-05-20T20:00"]


def _dataset(refl, sza, rendered_sza):
    """A one-pixel true-colour dataset: reflectance per band (0.47, 0.64, 0.86), the pixel's SZA."""
    return xr.Dataset({"reflectance": (("band", "y", "x"), np.asarray(refl, float).reshape(3, 1, 1)),
                       "solar_zenith_angle": (("y", "x"), [[sza]])},
                      coords={"band": ["0.47", "0.64", "0.86"]}, attrs={"rendered_solar_zenith_deg": rendered_sza})


def test_recipe_uses_the_published_coefficients():
    """CIMSS simulated green (Bah et al. 2018): 0.45, 0.45, 0.10; CIRA stretch (satpy): log10 reflectance from
    0.0223 (0) with denominator 0.75 (1 - log10 0.0223); satpy's SZA cap 88 deg, zero at 95 deg; pyspectral's
    relaxation 1 - (red% - 20) / 80."""
    assert tc.simulated_green(1.0, 0.0, 0.0) == 0.45 and tc.simulated_green(0.0, 1.0, 0.0) == 0.45
    assert tc.simulated_green(0.0, 0.0, 1.0) == pytest.approx(0.10)
    assert tc.cira_stretch(0.0223) == pytest.approx(0.0, abs=1e-12)
    assert tc.cira_stretch(1.0) == pytest.approx(1.6516951 / (0.75 * 2.6516951), rel=1e-6)  # 0.8305
    assert tc.cira_stretch(0.001) == 0.0 and tc.cira_stretch(5.0) == 1.0
    assert tc.sun_zenith_correction(0.5, 60.0) == pytest.approx(1.0)
    assert tc.sun_zenith_correction(1.0, 89.0) == pytest.approx((1 - np.log(1 + 1 / 7) / np.log(2)) / np.cos(np.radians(88)))
    assert tc.sun_zenith_correction(1.0, 96.0) == 0.0
    np.testing.assert_allclose(tc.relaxed_rayleigh([0.05, 0.05, 0.05], [0.10, 0.60, 1.20]), [0.05, 0.025, 0.0])


def test_a_pixel_worked_by_hand():
    """Rendered R = pi L / (E0 cos 30 deg) of 0.20, 0.15, 0.30 at 0.47, 0.64, 0.86 um; the pixel's own sun at
    40 deg: the imager's pi L / E0 is R cos 30, sun-corrected R cos 30 / cos 40 (0.226, 0.170, 0.339); green
    0.45 x 0.226 + 0.45 x 0.170 + 0.10 x 0.339 = 0.212; CIRA: (log10 R + 1.65170) / 1.98877 = 0.443,
    0.492, 0.506 (R, G, B)."""
    k = np.cos(np.radians(30)) / np.cos(np.radians(40))  # 1.13052
    b, r, n = 0.20 * k, 0.15 * k, 0.30 * k
    g = 0.45 * b + 0.45 * r + 0.10 * n
    stretch = [(np.log10(v) + 1.6516951) / 1.9887713 for v in (r, g, b)]  # (1 - log10 0.0223) x 0.75 = 1.98877
    rgb = tc.true_color(_dataset([0.20, 0.15, 0.30], 40.0, 30.0))[0, 0]
    np.testing.assert_allclose(rgb, stretch, rtol=1e-6)
    assert rgb == pytest.approx([0.4430, 0.4917, 0.5058], abs=1e-4)  # by hand (a calculator)


def test_rayleigh_reflectance_is_single_scattering_when_thin():
    """tau 1e-4 over a black surface: R = pi p(Theta) tau / (mu0 mu) (Chandrasekhar's p with depolarisation),
    with the view azimuth towards the satellite (the sun behind it: backscatter)."""
    from weather_mi.optics.rayleigh import phase_value
    sza, vza, saa, vaa, tau = 40.0, 30.0, 200.0, 20.0, 1e-4  # satellite towards the sun's opposite side
    r = tc.rayleigh_reflectance(tau, np.array([sza]), np.array([vza]), np.array([saa]), np.array([vaa]))[0]
    mu0, mu = np.cos(np.radians(sza)), np.cos(np.radians(vza))
    # sensor at azimuth 20, sun at 200: the light scattered from the sun's direction back toward 20 deg azimuth
    cos_t = -mu0 * mu + np.sqrt(1 - mu0 ** 2) * np.sqrt(1 - mu ** 2) * np.cos(np.radians(vaa - saa - 180.0))
    assert r == pytest.approx(np.pi * phase_value(cos_t) * tau / (mu0 * mu), rel=2e-3)


def test_rgb_volume_puts_each_band_in_its_channel():
    hyd = wm.synthetic.cumulus()
    vol = wm.optical_volume(hyd, species="physical", phase_quality="test")
    bands = true_color_bands(satellite("goes-east"))
    assert [b.name for b in bands] == ["0.64", "0.86", "0.47"]
    assert [b.name for b in true_color_bands(satellite("himawari"))] == ["0.64", "0.51", "0.47"]
    rv = rgb_volume(vol, bands)
    for c, b in enumerate(bands):
        bv = band_volume(vol, b)
        np.testing.assert_array_equal(rv.albedo[..., c], bv.albedo[..., 0])
        for t, tb in zip(rv.phase_tables, bv.phase_tables):
            np.testing.assert_allclose(t.eval(tb.theta)[:, c], tb.values[:, 0], rtol=1e-9, atol=1e-12)
            assert t.wavelengths_m[c] == b.wavelength_m


def test_rgb_of_the_demo_is_white_cloud_over_a_blue_sea(tmp_path, capsys):
    """One run, three bands: the NetCDF's band dimension; in the PNG the brightest tenth (cloud) grey within 0.12
    across channels on average, the clear sea bluer than red."""
    from PIL import Image
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        assert cli.main(DEMO + ["--rgb", "--resolution", "4km", "--spp", "64", "-o", str(tmp_path / "tc.nc")]) == 0
    assert "one render, one band per channel" in capsys.readouterr().out
    ds = xr.open_dataset(tmp_path / "tc.nc")
    assert ds.attrs["Conventions"] == "CF-1.8" and list(ds.band.values) == ["0.47", "0.64", "0.86"]
    assert ds.reflectance.dims == ("band", "y", "x")
    assert ds.reflectance.attrs["standard_name"] == "toa_bidirectional_reflectance"
    np.testing.assert_allclose(ds.reflectance.attrs["wavelength"], [0.47, 0.64, 0.865])
    np.testing.assert_allclose(ds.wavelength.values, [0.47, 0.64, 0.865])
    from weather_mi.display.satellite_picture import zoom_for
    a = np.asarray(Image.open(tmp_path / "tc.png"), float) / 255.0
    k = zoom_for(ds.sizes["x"])  # enlarged k times (nearest neighbour); an ideal case: no coastlines
    assert a.shape == (ds.sizes["y"] * k, ds.sizes["x"] * k, 3)
    a = a[k // 2::k, k // 2::k]
    lum = a.mean(axis=-1)
    top = lum >= np.quantile(lum, 0.9)
    assert float((a.max(axis=-1) - a.min(axis=-1))[top].mean()) <= 0.12
    clear = (ds.cloud.values == 0) & (ds.in_domain.values == 1)
    assert clear.sum() > 20 and a[..., 2][clear].mean() > a[..., 0][clear].mean() + 0.05


@pytest.mark.parametrize("more, message", [
    (["--rgb", "--band", "0.64"], r"--rgb renders the true-colour bands \(0\.64, 0\.86, 0\.47 um on goes-east\)"),
    (["--rgb", "--satellite", "meteosat"], r"--rgb: meteosat's imager \(MSG SEVIRI\) has no 0\.47 um \(blue\) band"),
    (["--band", "0.47", "--satellite", "meteosat"], r"--band 0\.47: meteosat's imager \(MSG SEVIRI\) has no 0\.47"),
    (["--band", "0.51"], r"--band 0\.51: goes-east's imager \(GOES-R ABI\) has no 0\.51 um band"),
])
def test_rgb_and_band_refusals_before_rendering(tmp_path, capsys, more, message):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        assert cli.main(DEMO + more + ["-o", str(tmp_path / "a.nc")]) == 2
    captured = capsys.readouterr()
    assert len(re.findall(message, captured.err)) == 1, captured.err
    assert "pixels of" not in captured.out  # refused before the scene was built
    assert not list(tmp_path.iterdir())


def test_band_names_the_new_green_band():
    assert band("0.51").channels == {"ahi": "B02"}
