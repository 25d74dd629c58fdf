"""The spectral paths' wavelengths drawn for colour (``kernel.plugins.wavelengths``, issue 38 chroma38): the
kernel's draws follow the density and their pdf is its value, Mitsuba's density is its part (written out against Mitsuba's ``pdf_rgb_spectrum``); a
sensor's rays redrawn from it estimate the CIE 1931 functions' integrals (colour-science, numpy here) without bias,
and with less spread in Z than Mitsuba's draw (the point of it)."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm

SPECTRAL = "llvm_ad_spectral"


def test_density_is_normalised_and_mitsubas_part_is_mitsubas(variant_restored):
    import mitsuba as mi
    from weather_mi.kernel.plugins import wavelengths as wl
    wm.set_variant(SPECTRAL)
    lam = np.linspace(360.0, 830.0, 4701)
    # the density the kernel draws from: a draw's pdf is the mean of colour_pdf over its 1 nm bin, and a
    # histogram of the draws follows it (the binning and the inversion both checked)
    u = np.random.default_rng(3).random(1 << 20)
    x, p = (np.array(a).ravel() for a in wl.sample_colour(mi.Float(u)))
    fine = np.linspace(360.0, 830.0, 470 * 64 + 1)
    bin_mean = np.trapezoid(wl.colour_pdf(fine).reshape(-1)[:-1].reshape(470, 64), dx=1 / 64, axis=1)
    bin_mean /= bin_mean.sum()
    inside = np.abs(x - np.round(x)) > 1e-3  # float32 wavelengths at a bin's edge may round into the next
    np.testing.assert_allclose(p[inside], bin_mean[np.minimum((x[inside] - 360.0).astype(int), 469)], rtol=2e-3)
    hist, edges = np.histogram(x, bins=47, range=(360.0, 830.0), density=True)
    mean_pdf = [np.trapezoid(wl.colour_pdf(np.linspace(a, b, 41)), np.linspace(a, b, 41)) / (b - a)
                for a, b in zip(edges[:-1], edges[1:])]
    se = np.sqrt(np.asarray(mean_pdf) / (x.size * (edges[1] - edges[0])))  # a bin's Poisson se (1/nm)
    assert np.all(np.abs(hist - mean_pdf) < 4 * se), np.max(np.abs(hist - mean_pdf) / se)
    assert np.trapezoid(wl.mitsuba_pdf(lam), lam) == pytest.approx(1.0, abs=1e-4)
    got = np.array(mi.pdf_rgb_spectrum(mi.Float(lam[::50]))).ravel()
    np.testing.assert_allclose(wl.mitsuba_pdf(lam[::50]), got, rtol=1e-5)


def _redrawn_xyz(n: int, redraw: bool, seed: int = 0):
    """(n, 3): X, Y, Z of a flat unit spectrum estimated by n rays of a perspective sensor, 4 lanes each."""
    import colour
    import mitsuba as mi
    from weather_mi.kernel.plugins import wavelengths as wl
    wm.set_variant(SPECTRAL)
    sensor = mi.load_dict({"type": "perspective", "film": {"type": "hdrfilm", "width": 4, "height": 4,
                                                           "pixel_format": "xyz"}})
    u = mi.Float(np.random.default_rng(seed).random(n))
    ray, weight = sensor.sample_ray(0.0, u, mi.Point2f(0.5, 0.5), mi.Point2f(0.5, 0.5))
    if redraw:
        ray, weight = wl.redrawn(ray, weight, u, mi.Bool(True))
    lam, w = np.array(ray.wavelengths).T, np.array(weight).T  # (n, 4)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    grid = np.arange(360.0, 831.0, 1.0)
    table = cmfs.copy().align(colour.SpectralShape(360, 830, 1)).values
    c = np.stack([np.interp(lam, grid, table[:, k]) for k in range(3)], -1)  # (n, 4, 3)
    return (w[..., None] * c).mean(axis=1) / np.trapezoid(table[:, 1], grid)


def test_redrawn_wavelengths_estimate_the_colour_matching_integrals(variant_restored):
    """A flat spectrum of 1: E[X, Y, Z] = int xbar, ybar, zbar / int ybar (1.000, 1.000, 1.000 to 0.3 %) within
    3 se; the per-ray spread of Z at most half Mitsuba's own draw's (which the check would fail)."""
    import colour
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    grid = np.arange(360.0, 831.0, 1.0)
    table = cmfs.copy().align(colour.SpectralShape(360, 830, 1)).values
    want = np.trapezoid(table, grid, axis=0) / np.trapezoid(table[:, 1], grid)
    n = 1 << 18
    new, old = _redrawn_xyz(n, True), _redrawn_xyz(n, False)
    for xyz in (new, old):
        se = xyz.std(axis=0) / np.sqrt(n)
        assert np.all(np.abs(xyz.mean(axis=0) - want) < 3 * se + 1e-4), (xyz.mean(axis=0), want, se)
    assert new.std(axis=0)[2] < 0.5 * old.std(axis=0)[2]


def test_mitsubas_weight_in_closed_form_is_the_samplers_own(variant_restored):
    """``mitsuba_weight`` (what ``redrawn`` divides by, from the sensor's wavelengths) equals the weight Mitsuba's
    ``sample_rgb_spectrum`` returns with them, bit for bit, and is 1 / the written-out density (``mitsuba_pdf``,
    1 / (0.0039398 / cosh^2)) to 1e-4; a wrong constant (the lane shifted by 1 nm) fails the first check."""
    import mitsuba as mi
    from weather_mi.kernel.plugins import wavelengths as wl
    wm.set_variant(SPECTRAL)
    u = mi.Float(np.random.default_rng(5).random(1 << 14))
    lam, w = mi.sample_rgb_spectrum(mi.Spectrum(u, 0.5 * u, 0.25 + 0.5 * u, 1.0 - u))
    got = np.array(wl.mitsuba_weight(lam))
    assert np.array_equal(got, np.array(w))
    np.testing.assert_allclose(got, 1.0 / wl.mitsuba_pdf(np.array(lam)), rtol=1e-4)
    assert not np.array_equal(np.array(wl.mitsuba_weight(lam + 1.0)), np.array(w))
