"""The spectral mode's cost per sample (issue 38 part 2): its packed lookups (the sun after the air,
``kernel.plugins.spectral_sun``; the mixture's pdf, ``spectral_phase.pack_pdf``; the albedo by wavelength,
``spectral_albedo``) against interpolation done here with scipy and numpy on the tables they were given, and
the luminance RSE the cost is measured with (``reference.estimates.luminance_rse``)."""
from __future__ import annotations

import numpy as np
import pytest

SPECTRAL = "llvm_ad_spectral"


@pytest.fixture
def spectral(variant_restored):
    import weather_mi as wm
    wm.set_variant(SPECTRAL)
    import mitsuba as mi
    return mi


def _lanes(mi, wl):
    return mi.Spectrum(*[mi.Float(np.asarray(w, np.float32)) for w in wl])


def test_sun_table_is_trilinear_and_clamped_as_scipy(spectral):
    """T(mu, h, lambda) at random points inside and beyond the grids' ends (held there): scipy's
    RegularGridInterpolator on the clamped coordinates, to float32 rounding."""
    from scipy.interpolate import RegularGridInterpolator
    from weather_mi.kernel.plugins.spectral_sun import SpectrumTable
    mi = spectral
    rng = np.random.default_rng(3)
    t = rng.random((6, 9, 95)).astype(np.float32)
    nm, h, mu = (360.0, 830.0), (0.0, 14000.0), (0.05, 0.45)
    table = SpectrumTable(t, nm, h, mu)
    n = 2000
    hs, mus = rng.uniform(-2000, 16000, n), rng.uniform(0.0, 0.5, n)
    wl = rng.uniform(350.0, 840.0, (4, n))
    got = np.array(table.eval(mi.Float(hs.astype(np.float32)), mi.Float(mus.astype(np.float32)), _lanes(mi, wl)))
    f = RegularGridInterpolator((np.linspace(*mu, 6), np.linspace(*h, 9), np.linspace(*nm, 95)), t.astype(np.float64))
    want = np.stack([f(np.stack([np.clip(mus, *mu), np.clip(hs, *h), np.clip(w, *nm)], axis=-1)) for w in wl])
    assert np.abs(got - want).max() < 2e-5
    # the top-of-atmosphere spectrum alone (one height, one mu): linear in wavelength, as np.interp
    toa = SpectrumTable(t[:1, :1], nm)
    got = np.array(toa.eval(mi.Float(0.0), mi.Float(0.0), _lanes(mi, wl)))
    assert np.abs(got - np.stack([np.interp(w, np.linspace(*nm, 95), t[0, 0]) for w in wl])).max() < 2e-5


def test_mixture_pdf_table_is_the_weighted_linear_density(spectral):
    """``spectral_pdf`` on ``pack_pdf``: sum_s w_s pbar_s(v) with pbar_s linear between the nodes, for 5 and 3
    species (the packets' padding), against numpy."""
    import drjit as dr
    from weather_mi.kernel.plugins.hydrometeor_mixture import _gather4, _storage
    from weather_mi.kernel.plugins.spectral_phase import pack_pdf, spectral_pdf
    mi = spectral
    rng = np.random.default_rng(4)
    for n_s in (5, 3):
        pbar = rng.random((n_s, 40)).astype(np.float32)
        n = 500
        idx, t = rng.integers(0, 39, n), rng.random(n).astype(np.float32)
        w = rng.random((n_s, n)).astype(np.float32)
        got = spectral_pdf(_storage(pack_pdf(pbar)), n_s, [mi.Float(x) for x in w], mi.UInt32(idx.astype(np.uint32)),
                           mi.Float(t), _gather4)
        dr.eval(got)
        want = sum(w[s] * ((1 - t) * pbar[s, idx] + t * pbar[s, idx + 1]) for s in range(n_s))
        assert np.allclose(np.array(got), want, rtol=1e-5, atol=1e-6)


def test_albedo_records_mix_five_species_coalbedo_spectra(spectral):
    """``spectral_albedo.albedo_at`` on ``pack_coalbedo`` for 5 species (4 packets a record, padded):
    1 - (1 - omega_ref) sum_s w_s c_s(lambda) / sum_s w_s c_s(ref), c_s linear on its grid and held beyond,
    against numpy at wavelengths inside and beyond the grid."""
    import drjit as dr
    from weather_mi.kernel.plugins.hydrometeor_mixture import _gather4, _storage
    from weather_mi.kernel.plugins.spectral_albedo import albedo_at, pack_coalbedo
    mi = spectral
    rng = np.random.default_rng(5)
    grid = np.arange(350.0, 851.0, 50.0)
    co = (rng.random((5, grid.size + 1)) * 1e-3).astype(np.float32)  # the last column: at the reference
    n = 300
    w = rng.random((5, n)).astype(np.float32)
    wl = rng.uniform(330.0, 870.0, (4, n))
    omega_ref = rng.uniform(0.99, 1.0, n).astype(np.float32)
    got = albedo_at(_storage(pack_coalbedo(co)), (grid[0], 1.0 / 50.0, grid.size), 5, [mi.Float(x) for x in w],
                    _lanes(mi, wl), mi.Float(omega_ref), _gather4)
    dr.eval(got)
    c = np.stack([np.stack([np.interp(lam, grid, co[s, :-1]) for s in range(5)]) for lam in wl])  # (4, 5, n)
    want = 1 - (1 - omega_ref) * np.einsum("sn,lsn->ln", w, c) / (w.T @ co[:, -1])
    assert np.abs(np.array(got) - want).max() < 1e-6
    assert np.ptp(want) > 1e-4  # the check can fail: the spectra differ by wavelength


def test_luminance_rse_is_the_spread_of_the_passes_luminance_only():
    """From the running means of 5 passes: se(Y) / Y summed here from the passes themselves; passes that differ
    only in chromaticity (equal Y) have no luminance noise, though every channel is noisy."""
    from weather_mi.reference.estimates import luminance_rse
    rng = np.random.default_rng(6)
    passes = rng.uniform(0.5, 1.5, (5, 4, 3, 3))
    means = [passes[:i + 1].mean(axis=0) for i in range(5)]
    cloud = np.ones((4, 3), bool)
    cloud[0, 0] = False
    y = passes @ np.array([0.2126729, 0.7151522, 0.0721750])  # IEC 61966-2-1's Y row
    want = np.mean((y.std(axis=0, ddof=1) / np.sqrt(5) / y.mean(axis=0))[cloud])
    assert luminance_rse(means, cloud) == pytest.approx(want, rel=1e-10)
    # chroma noise only: R and B traded against each other at constant Y
    d = rng.normal(0, 0.2, (5, 4, 3))
    chroma = np.full((5, 4, 3, 3), 1.0)
    chroma[..., 0] += d / 0.2126729
    chroma[..., 2] -= d / 0.0721750
    assert luminance_rse([chroma[:i + 1].mean(axis=0) for i in range(5)], cloud) < 1e-12
    assert chroma[..., 0].std(axis=0).mean() > 0.5  # the channels themselves are noisy
    with pytest.raises(ValueError, match="at least 2 passes"):
        luminance_rse(means[:1], cloud)
