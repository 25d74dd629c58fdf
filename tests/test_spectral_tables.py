"""The spectral mode's phase tables by wavelength (issue 38 part 2): ``optics.phase.spectral_tables`` and the
mixture plugin's lookups of them (``kernel.plugins.spectral_phase``), checked against numbers computed here:
Hale & Querry's water index, a cloud's phase function summed from miepython at a wavelength between two nodes,
and the plugin's values at the lanes' wavelengths against numpy's interpolation of its inputs."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.optics.phase import PhaseTable

SPECTRAL = "llvm_ad_spectral"


def _hg(g, mu):
    return (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * mu) ** 1.5)


def test_water_index_below_450nm_is_hale_and_querry():
    """The rows added for the spectral mode, as Hale & Querry (1973) Table 1 prints them (25 C)."""
    from weather_mi.optics.phase.mie import water_index
    for nm, n, k in ((350, 1.343, 6.50e-9), (400, 1.339, 1.86e-9), (425, 1.338, 1.30e-9), (450, 1.337, 1.02e-9)):
        m = water_index(nm * 1e-9)
        assert m.real == pytest.approx(n, abs=1e-12) and -m.imag == pytest.approx(k, rel=1e-9)
    assert water_index(362.5e-9).real == pytest.approx(1.342, abs=1e-9)  # linear between the rows
    with pytest.raises(ValueError, match="350-900 nm"):
        water_index(340e-9)


def test_grid_covers_the_cie_range_with_the_rgb_wavelengths():
    from weather_mi.optics.phase.spectral_tables import SPECTRAL_NM, check_grid
    check_grid(SPECTRAL_NM)
    assert SPECTRAL_NM[0] <= 360 and SPECTRAL_NM[-1] >= 830
    assert {450.0, 550.0, 650.0} <= set(SPECTRAL_NM.tolist())
    with pytest.raises(ValueError, match="cover 360-830"):
        check_grid(np.arange(400.0, 801.0, 25.0))
    with pytest.raises(ValueError, match="uniform"):
        check_grid([350.0, 400.0, 500.0, 850.0])


def _miepython_cloud(theta, wavelength_nm, r_eff=10e-6, v_eff=0.1, n=200):
    """The cloud droplets' phase function summed here: miepython's |S1|^2 + |S2|^2 over n radii at the
    quantiles of the area-weighted gamma distribution (each weighted 1 / r^2, as for n(r) dr), normalised."""
    import miepython
    from scipy.stats import gamma
    radii = gamma.ppf((np.arange(n) + 0.5) / n, (1 - 2 * v_eff) / v_eff + 2, scale=r_eff * v_eff)
    from weather_mi.optics.phase.mie import water_index
    m = water_index(wavelength_nm * 1e-9)
    k = 2 * np.pi / (wavelength_nm * 1e-9)
    p = np.zeros_like(theta)
    for r in radii:
        s1, s2 = miepython.S1_S2(m, k * r, np.cos(theta), norm="wiscombe")
        p += (np.abs(s1) ** 2 + np.abs(s2) ** 2) / r ** 2
    return p / np.trapezoid(2 * np.pi * p * np.sin(theta), theta)


def _tv_outside(p, q, theta, cone_deg=3.0):
    keep = theta >= np.radians(cone_deg)
    return 0.5 * np.trapezoid(2 * np.pi * np.abs(p - q)[keep] * np.sin(theta[keep]), theta[keep])


def test_cloud_tables_between_nodes_against_miepython():
    """At 537.5 nm, halfway between the 525 and 550 nm nodes, the interpolated cloud table sends less than
    0.5% of the scattered light (outside the 3 deg cone delta-M takes) in another direction than Mie theory
    summed here (the rest is the size sum's resonance ripple, which no wavelength grid interpolates); the
    450 nm table there (a 90 nm error of wavelength) is more than 3 times as far, so the check can fail."""
    from weather_mi.optics.phase import mie
    from weather_mi.optics.phase.spectral_tables import STEP_NM, interpolated, species_stack
    assert STEP_NM == 25.0
    cloud = wm.species.preset("physical")["cloud"]
    nodes = [525.0, 550.0]
    stack = [mie.mie_cloud(quality="test", wavelength_m=nm * 1e-9) for nm in nodes]
    assert stack[0] is species_stack(cloud, quality="test")[7]  # the spectral mode's own 525 nm table
    theta = np.radians(np.unique(np.r_[np.arange(2.0, 180.0, 0.25), 180.0]))
    truth = _miepython_cloud(theta, 537.5)

    def normalised(p):
        return p / np.trapezoid(2 * np.pi * p * np.sin(theta), theta)

    tv = _tv_outside(normalised(interpolated(stack, nodes, 537.5, theta)), truth, theta)
    assert tv < 0.005
    blue = normalised(mie.mie_cloud(quality="test", wavelength_m=450e-9).eval(theta)[:, 0])
    assert _tv_outside(blue, truth, theta) > 3 * tv


def test_tables_without_a_spectral_form_are_their_channels_by_wavelength():
    """A given R, G, B table (no species): linear between 450, 550 and 650 nm, held beyond (as before)."""
    from weather_mi.optics.phase.spectral_tables import lerp_stack, stacks_for
    theta = np.linspace(0, np.pi, 721)
    table = PhaseTable.from_values(theta, np.stack([_hg(g, np.cos(theta)) for g in (0.3, 0.6, 0.85)], -1))
    stack = lerp_stack(table, [400.0, 500.0, 650.0, 800.0])
    np.testing.assert_allclose(stack[0].values[:, 0], table.values[:, 2], rtol=1e-9)
    np.testing.assert_allclose(stack[1].values[:, 0], 0.5 * (table.values[:, 1] + table.values[:, 2]), rtol=1e-9)
    np.testing.assert_allclose(stack[3].values[:, 0], table.values[:, 0], rtol=1e-9)
    assert stacks_for([None], [table], wavelengths_nm=np.arange(350.0, 851.0, 25.0))[0][0].values.shape == (721, 3)


def test_plugin_reads_the_tables_at_the_lanes_wavelengths(variant_restored):
    """``hydrometeor_mixture`` with ``spectral_values``: eval_pdf per lane is sum_s w_s p_s(v, lambda), linear
    in wavelength between the grid's tables and in v between nodes (numpy here, from the plugin's own
    inputs; and the HG functions at the nodes); directions drawn from the wavelengths' mean density carry
    weights value / pdf whose mean is 1 at every wavelength (the mixture is normalised at each)."""
    import drjit as dr
    import mitsuba as mi
    from weather_mi.kernel.plugins.hydrometeor_mixture import prepare_tables
    from weather_mi.kernel.plugins.spectral_phase import prepare_spectral
    wm.set_variant(SPECTRAL)
    theta = np.unique(np.concatenate([np.linspace(0, np.pi, 2001), np.geomspace(1e-4, 0.2, 400)]))
    grid = np.arange(350.0, 851.0, 25.0)
    gs = 0.2 + 0.7 * (grid - 350) / 500  # g rising with wavelength
    stacks = [[PhaseTable.from_values(theta, _hg(sign * g, np.cos(theta))) for g in gs] for sign in (1.0, -0.5)]
    rgb = [PhaseTable.from_values(theta, np.stack([_hg(sign * g, np.cos(theta)) for g in (0.8, 0.6, 0.4)], -1))
           for sign in (1.0, -0.5)]
    nodes, values = prepare_tables(rgb)
    sv = prepare_spectral(nodes, stacks)
    w = np.array([3.0, 1.0], np.float32)
    phase = mi.load_dict({"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]),
                          "values": mi.TensorXf(values), "weights": mi.TensorXf(np.broadcast_to(w, (1, 1, 1, 2)).copy()),
                          "spectral_values": mi.TensorXf(sv), "spectral_nm": mi.TensorXf(grid.astype(np.float32))})
    lanes = np.array([[360.0, 412.5, 500.0, 550.0], [600.0, 660.0, 700.0, 829.0]])
    cos = np.array([0.9, -0.5])
    mei = dr.zeros(mi.MediumInteraction3f, 2)
    mei.wi = mi.Vector3f(0, 0, -1)
    mei.sh_frame = mi.Frame3f(mei.wi)
    mei.wavelengths = mi.Spectrum(*(mi.Float(lanes[:, i]) for i in range(4)))
    value, _ = phase.eval_pdf(mi.PhaseFunctionContext(None), mei, mi.Vector3f(np.sqrt(1 - cos ** 2), 0 * cos, cos))
    value = np.array(value).T
    wn = w / w.sum()
    for j in range(2):
        at_nodes = [np.interp(1 - cos[j], nodes, sv[s, :, :].T[k]) for s in range(2) for k in range(grid.size)]
        per_s = np.reshape(at_nodes, (2, grid.size))
        expect = wn @ np.array([np.interp(lanes[j], grid, per_s[s]) for s in range(2)])
        np.testing.assert_allclose(value[j], expect, rtol=1e-4)
        hg = wn[0] * _hg(np.interp(lanes[j], grid, gs), cos[j]) + wn[1] * _hg(-0.5 * np.interp(lanes[j], grid, gs), cos[j])
        np.testing.assert_allclose(value[j], hg, rtol=3e-3)
    n = 200_000
    mei = dr.zeros(mi.MediumInteraction3f, n)
    mei.wi = mi.Vector3f(0, 0, -1)
    mei.sh_frame = mi.Frame3f(mei.wi)
    mei.wavelengths = mi.Spectrum(*(mi.Float(np.full(n, v)) for v in (380.0, 480.0, 580.0, 780.0)))
    u = np.random.default_rng(1).random((3, n))
    _, weight, _ = phase.sample(mi.PhaseFunctionContext(None), mei, mi.Float(u[0]), mi.Point2f(u[1], u[2]))
    mean = np.array(weight).mean(axis=1)
    np.testing.assert_allclose(mean, 1.0, atol=0.01)


def test_delta_scaled_volume_truncates_every_wavelength(variant_restored):
    """The medium's tables by wavelength (``kernel.medium.spectral_phase_values``) of a delta-M scaled demo
    cumulus: at 550 nm each species' table is the truncated R, G, B table's green channel (Mie at the same
    wavelength, the same forward fraction taken out; within 0.5%), every wavelength normalised; without the
    truncation the forward value would be 60 to a million times larger, so the check can fail."""
    from weather_mi.kernel.medium import spectral_phase_values
    from weather_mi.kernel.plugins.hydrometeor_mixture import prepare_tables
    from weather_mi.optics.forward_peak import delta_scaled
    from weather_mi.optics.phase.spectral_tables import SPECTRAL_NM
    vol = wm.optical_volume(wm.synthetic.cumulus(shape=(20, 16, 16), spacing_m=(200.0, 200.0, 200.0)),
                            species="physical", phase_quality="test")
    scaled = delta_scaled(vol, 3.0, species_extinction=False)
    assert scaled.attrs["forward_peak_deg"] == 3.0
    nodes, values = prepare_tables(scaled.require_phase_tables())
    species = [scaled.species_set[n] for n in scaled.species]
    sv = spectral_phase_values(scaled, nodes, species)
    assert sv.shape == (len(species), nodes.size, SPECTRAL_NM.size)
    integral = 2 * np.pi * np.sum(0.5 * (sv[:, 1:] + sv[:, :-1]) * np.diff(nodes.astype(np.float64))[None, :, None], axis=1)
    np.testing.assert_allclose(integral, 1.0, rtol=1e-4)
    g550 = int(np.flatnonzero(SPECTRAL_NM == 550.0)[0])
    np.testing.assert_allclose(sv[:, :, g550], values[:, :, 1], rtol=5e-3, atol=1e-6)
    unscaled = prepare_tables(vol.require_phase_tables())[1]
    assert np.all(unscaled[:, 0, 1] > 30 * sv[:, 0, g550])
