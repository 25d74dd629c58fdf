"""``kernel/plugins/spectral_air_weights.by_lane``: the mixture's Eq. 8 weights with the box's air by wavelength,
against the formula of its module docstring evaluated here in float64 with numpy (the air's coefficients linear in
wavelength between nodes and in height between levels, times the weights' 1 / raw sum; each lane's weights the
hydrometeors' and the air's over their sum)."""
from __future__ import annotations

import numpy as np

LO_NM, STEP_NM = 400.0, 50.0


def _expected(table, hydro, z0, z1, fz, inv_total, wavelengths):
    """(lanes, S + A, points) float64: the weights by lane (the module docstring's p(lambda)'s beta_s / sum)."""
    k = table.shape[1]
    out = []
    for wl in wavelengths:
        u = np.clip((wl - LO_NM) / STEP_NM, 0.0, k - 1.0001)
        j = u.astype(int)
        t = u - j
        at = [table[z, j] * (1 - t[:, None]) + table[z, j + 1] * t[:, None] for z in (z0, z1)]  # (points, A)
        air = (at[0] * (1 - fz[:, None]) + at[1] * fz[:, None]) * inv_total[:, None]
        w = np.concatenate([hydro.T, air], axis=1)
        out.append((w / w.sum(axis=1, keepdims=True)).T)
    return np.array(out)


def test_by_lane_is_the_docstrings_mixture(variant_restored):
    import drjit as dr
    import mitsuba as mi
    import weather_mi
    from weather_mi.kernel.plugins import spectral_air_weights as saw
    weather_mi.set_variant("llvm_ad_rgb")
    rng = np.random.default_rng(7)
    n_levels, n_nm, n_a, n_s, n = 3, 4, 2, 3, 6
    table = rng.uniform(1e-6, 1e-4, (n_levels, n_nm, n_a))
    hydro = rng.uniform(0.0, 1.0, (n_s, n))
    hydro[:, 0] = 0.0  # the air alone there
    z0 = rng.integers(0, n_levels - 1, n)
    z1, fz = z0 + 1, rng.uniform(0.0, 1.0, n)
    inv_total = rng.uniform(1e3, 1e5, n)
    wavelengths = [rng.uniform(380.0, 570.0, n) for _ in range(4)]  # below and above the nodes too
    flat = mi.Float(np.ascontiguousarray(saw.pack(table)).ravel())
    spectral = (flat, (LO_NM, 1.0 / STEP_NM, n_nm), n_a)
    w = saw.Weights([mi.Float(h) for h in hydro] + [mi.Float(np.zeros(n)) for _ in range(n_a)],
                    (mi.UInt32(z0), mi.UInt32(z1), mi.Float(fz), mi.Float(inv_total), mi.Bool(np.ones(n, bool))))
    lanes = saw.by_lane(spectral, w, [mi.Float(wl) for wl in wavelengths], lambda src, i: dr.gather(mi.Vector4f, src, i))
    got = np.array([[np.asarray(v) for v in lane] for lane in lanes])
    expected = _expected(table, hydro, z0, z1, fz, inv_total, wavelengths)
    assert got.shape == expected.shape == (4, n_s + n_a, n)
    np.testing.assert_allclose(got, expected, rtol=2e-6, atol=1e-7)
    np.testing.assert_allclose(got.sum(axis=1), 1.0, rtol=2e-6)
    assert np.all(got[:, :n_s, 0] == 0) and np.all(got[:, n_s:, 0] > 0)
