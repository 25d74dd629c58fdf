"""Eq. 1-6 and 8 against hand-computed numbers; species presets; orientation through optics."""
import numpy as np
import pytest

import weather_mi as wm
from weather_mi.optics.species import preset


def hyd_one_point(name, q=1e-3, rho=1.0):
    a = np.zeros((3, 4, 5))
    a[1, 2, 3] = q
    return wm.from_arrays({name: a}, rho, (100.0, 100.0, 100.0))


@pytest.mark.parametrize("name,expected", [
    ("cloud", 0.15),                     # 3 * 1 * 1e-3 / (2 * 1000 * 1e-5)
    ("ice", 3e-3 / (2 * 917 * 1e-3)),    # 1.636e-3
    ("rain", 1.5e-3),                    # 3e-3 / (2 * 1000 * 1e-3)
    ("snow", 7.5e-3),                    # 3e-3 / (2 * 100 * 2e-3)
    ("graupel", 1.5e-3),                 # 3e-3 / (2 * 400 * 2.5e-3)
])
def test_eq4_paper_preset_by_hand(name, expected):
    vol = wm.optical_volume(hyd_one_point(name), species="paper")
    i = vol.species.index(name)
    assert vol.beta_ext[i, 1, 2, 3] == pytest.approx(expected, rel=1e-6)
    assert vol.beta_total[1, 2, 3] == pytest.approx(expected, rel=1e-6)
    assert vol.beta_ext.dtype == np.float32 and vol.beta_total.dtype == np.float32


def test_eq1_to_eq3_consistent_with_eq4():
    # Eq. 1-3 from first principles: sigma = 2 pi R^2, eta = rho q / (rho_p 4/3 pi R^3)
    r, rho_p, rho_air, q = 10e-6, 1000.0, 0.9, 2e-3
    beta_eq3 = 2 * np.pi * r ** 2 * rho_air * q / (rho_p * 4 / 3 * np.pi * r ** 3)
    vol = wm.optical_volume(hyd_one_point("cloud", q, rho_air), species="paper")
    assert vol.beta_total[1, 2, 3] == pytest.approx(beta_eq3, rel=1e-6)


@pytest.mark.parametrize("model_radii", [False, True])
def test_extinction_is_optical_volumes_eq4_and_eq6(model_radii):
    """``volume.extinction`` (the summary's) and ``optical_volume`` give Eq. 4 summed over the species (Eq. 6),
    written out here in float64: 3 scale rho_air q / (2 rho_p R), R the voxel's r_eff where > 0 (with the
    model's radii), else the species' radius; the largest extinction per species as well."""
    hyd = wm.synthetic.cumulus()
    rng = np.random.default_rng(4)
    for name in ("cloud", "rain"):
        r = rng.uniform(5e-6, 2e-3, hyd["rho_air"].shape)
        r[rng.random(r.shape) < 0.3] = 0.0  # no radius there: the species'
        hyd[f"r_eff_{name}"] = (("z", "y", "x"), r)
    sp = preset("physical", scale={"ice": 1.7})
    rho = hyd["rho_air"].values.astype(np.float64)
    expected, largest = 0.0, {}
    for s in sp:
        r = s.radius_m
        if model_radii and f"r_eff_{s.name}" in hyd:
            r = np.where(hyd[f"r_eff_{s.name}"].values > 0, hyd[f"r_eff_{s.name}"].values, s.radius_m)
        beta = 3.0 * s.scale * rho * hyd[f"q_{s.name}"].values / (2.0 * s.density_kg_m3 * r)
        expected, largest[s.name] = expected + beta, beta.max()
    assert expected.max() > 1e-3  # a storm, not zeros
    total, by_species = wm.optics.volume.extinction(hyd, sp, model_radii=model_radii)
    vol = wm.optical_volume(hyd, sp, model_radii=model_radii)
    np.testing.assert_allclose(total, expected, rtol=2e-6, atol=1e-12)
    np.testing.assert_allclose(vol.beta_total, expected, rtol=2e-6, atol=1e-12)
    for i, s in enumerate(sp):
        assert by_species[s.name] == pytest.approx(largest[s.name], rel=2e-6)
        assert float(vol.beta_ext[i].max()) == pytest.approx(largest[s.name], rel=2e-6)


def test_eq6_sum_and_eq8_weights_mixture():
    a = np.zeros((2, 2, 2))
    a[0, 0, 0] = 1e-3
    hyd = wm.from_arrays({"cloud": a, "snow": 2 * a}, 1.0, (1.0, 1.0, 1.0))
    vol = wm.optical_volume(hyd, species="paper")
    b_cloud, b_snow = 0.15, 3 * 2e-3 / (2 * 100 * 2e-3)  # 0.15, 0.015
    assert vol.beta_total[0, 0, 0] == pytest.approx(b_cloud + b_snow, rel=1e-6)
    sp = preset("paper")
    w_c = np.mean(sp["cloud"].albedo_rgb) * b_cloud
    w_s = np.mean(sp["snow"].albedo_rgb) * b_snow
    assert vol.weights[0, 0, 0, 0] == pytest.approx(w_c / (w_c + w_s), rel=1e-5)
    assert vol.weights[3, 0, 0, 0] == pytest.approx(w_s / (w_c + w_s), rel=1e-5)
    assert np.all(vol.weights[:, 1, 1, 1] == 0)  # nothing scatters there
    np.testing.assert_allclose(vol.weights.sum(axis=0)[0, 0, 0], 1.0, rtol=1e-6)
    expected_alb = (np.array(sp["cloud"].albedo_rgb) * b_cloud + np.array(sp["snow"].albedo_rgb) * b_snow) / (b_cloud + b_snow)
    np.testing.assert_allclose(vol.albedo[0, 0, 0], expected_alb, rtol=1e-6)


def test_scale_multiplies_one_species_only():
    a = np.full((2, 2, 2), 1e-3)
    hyd = wm.from_arrays({"cloud": a, "ice": a}, 1.0, (1.0, 1.0, 1.0))
    base = wm.optical_volume(hyd)
    scaled = wm.optical_volume(hyd, scale={"ice": 2.0})
    np.testing.assert_allclose(scaled.beta_ext[1], 2 * base.beta_ext[1], rtol=1e-6)
    np.testing.assert_array_equal(scaled.beta_ext[0], base.beta_ext[0])
    with pytest.raises(wm.WeatherDataError, match="hail"):
        wm.optical_volume(hyd, scale={"hail": 2.0})


def test_albedo_physics_close_to_unity():
    # optics-notes: co-albedo 1e-7..1e-6 for 10 um droplets at 550 nm, ~3e-4 in the red for 1 mm rain
    sp = preset("paper")
    assert 1e-7 <= 1 - sp["cloud"].albedo_rgb[1] <= 1e-6
    assert 1e-4 <= 1 - sp["rain"].albedo_rgb[0] <= 6e-4
    assert all(a > 0.999 for s in sp for a in s.albedo_rgb)


def test_paper_preset_table_ii_and_iii():
    sp = preset("paper")
    assert [s.radius_m for s in sp] == pytest.approx([1e-5, 1e-3, 1e-3, 2e-3, 2.5e-3])
    assert [s.phase_class for s in sp] == ["water", "ice", "water", "ice", "ice"]
    assert sp["cloud"].color_rgb == (1, 0, 0) and sp["ice"].color_rgb == (1, 0, 1)
    assert sp["rain"].color_rgb == (0, 0, 1) and sp["snow"].color_rgb == (1, 1, 0)
    assert sp["graupel"].color_rgb == (0, 1, 0)
    phys = preset("physical")
    assert 10e-6 <= phys["ice"].radius_m <= 125e-6  # WRF effective radii (optics-notes)


def test_overrides_and_bad_species():
    sp = preset("paper", {"ice": {"radius_m": 30e-6}}, scale={"snow": 0.5}, albedo=0.9)
    assert sp["ice"].radius_m == 30e-6 and sp["snow"].scale == 0.5
    assert sp["cloud"].albedo_rgb == (0.9, 0.9, 0.9)
    with pytest.raises(wm.WeatherDataError, match="hail"):
        preset("paper", {"hail": {"radius_m": 1e-3}})
    with pytest.raises(wm.WeatherDataError, match="radius_m"):
        preset("paper", {"ice": {"radius_m": -1.0}})
    with pytest.raises(wm.WeatherDataError, match="physical"):
        preset("nonsense")


def test_model_effective_radius_used_by_physical_preset():
    a = np.zeros((1, 1, 2))
    a[0, 0, :] = 1e-3
    r = np.array([[[20e-6, 0.0]]])
    hyd = wm.from_arrays({"cloud": a}, 1.0, (1.0, 1.0, 1.0), r_eff={"cloud": r})
    vol = wm.optical_volume(hyd, species="physical")
    assert vol.beta_total[0, 0, 0] == pytest.approx(3e-3 / (2 * 1000 * 20e-6), rel=1e-6)
    assert vol.beta_total[0, 0, 1] == pytest.approx(3e-3 / (2 * 1000 * 10e-6), rel=1e-6)  # fallback
    paper = wm.optical_volume(hyd, species="paper")
    assert paper.beta_total[0, 0, 0] == pytest.approx(0.15, rel=1e-6)


def test_orientation_and_bbox_from_arrays():
    a = np.zeros((3, 4, 5))
    a[2, 1, 4] = 1e-3  # top, second row north, easternmost column
    hyd = wm.from_arrays({"rain": a}, 1.0, (10.0, 20.0, 30.0), origin=(5.0, 10.0, 15.0))
    vol = wm.optical_volume(hyd)
    k, j, i = np.unravel_index(np.argmax(vol.beta_total), vol.shape)
    assert (k, j, i) == (2, 1, 4)
    assert float(hyd.x[i]) == 15.0 + 4 * 30 and float(hyd.y[j]) == 10.0 + 20 and float(hyd.z[k]) == 25.0
    assert vol.bbox == ((0.0, 0.0, 0.0), (150.0, 80.0, 30.0))
    assert vol.spacing == (10.0, 20.0, 30.0)


def test_from_arrays_bad_input():
    a = np.zeros((2, 3, 4))
    with pytest.raises(wm.WeatherDataError, match="shape"):
        wm.from_arrays({"cloud": a, "ice": np.zeros((2, 3, 5))}, 1.0, (1, 1, 1))
    with pytest.raises(wm.WeatherDataError, match="NaN"):
        wm.from_arrays({"cloud": np.full((2, 3, 4), np.nan)}, 1.0, (1, 1, 1))
    with pytest.raises(wm.WeatherDataError, match="species name"):
        wm.from_arrays({"hail": a}, 1.0, (1, 1, 1))
    with pytest.raises(wm.WeatherDataError, match="rho_air"):
        wm.from_arrays({"cloud": a}, np.ones(3), (1, 1, 1))
    with pytest.raises(wm.WeatherDataError, match="spacing"):
        wm.from_arrays({"cloud": a}, 1.0, (1, 0, 1))
    neg = a.copy()
    neg[0, 0, 0] = -1e-9
    with pytest.warns(UserWarning, match="negative"):
        hyd = wm.from_arrays({"cloud": neg}, 1.0, (1, 1, 1))
    assert hyd.attrs["n_negative_clipped"] == 1 and float(hyd.q_cloud.min()) == 0.0


def test_raw_optics_from_arrays():
    beta = np.random.default_rng(0).random((3, 4, 5)).astype(np.float32)
    vol = wm.OpticalVolume.from_arrays(beta, albedo=0.9, bbox=((0, 0, 0), (5, 4, 3)))
    assert vol.albedo.shape == (3, 4, 5, 3) and np.all(vol.albedo == np.float32(0.9))
    with pytest.raises(wm.WeatherDataError, match="albedo"):
        wm.OpticalVolume.from_arrays(beta, albedo=np.ones((2, 2)))


def test_large_grid_memory_layout():
    # a small stand-in for the 500 x 500 x 100 case (benchmarks/load_optics.py measures the real one)
    shape = (10, 50, 50)
    q = np.random.default_rng(1).random(shape, dtype=np.float32) * 1e-3
    hyd = wm.from_arrays({s: q for s in wm.SPECIES_NAMES}, 1.0, (100, 1000, 1000))
    vol = wm.optical_volume(hyd)
    assert vol.beta_ext.shape == (5,) + shape and vol.weights.dtype == np.float32
    np.testing.assert_allclose(vol.weights.sum(axis=0), 1.0, rtol=1e-5)


@pytest.mark.parametrize("sizes,size_classes", [("scheme", None), ("scheme", 3), ("paper", None)])
def test_release_drops_the_fields_once_used_and_changes_no_grid(sizes, size_classes):
    """``optical_volume(release=True)`` (the command line's): the same grids, bit for bit, as without it; the
    mixing ratios and radii are gone from the dataset afterwards (their memory with them), rho_air stays."""
    hyd = wm.synthetic.cumulus()
    rng = np.random.default_rng(1)
    for s in wm.SPECIES_NAMES:  # per-voxel radii, as a scheme's (10-500 um)
        hyd[f"r_eff_{s}"] = hyd[f"q_{s}"].copy(data=rng.uniform(1e-5, 5e-4, hyd[f"q_{s}"].shape).astype(np.float32))
    kept = wm.optical_volume(hyd.copy(), sizes=sizes, size_classes=size_classes, phase_quality="test")
    vol = wm.optical_volume(hyd, sizes=sizes, size_classes=size_classes, phase_quality="test", release=True)
    for name in ("beta_ext", "beta_total", "albedo", "weights"):
        np.testing.assert_array_equal(getattr(vol, name), getattr(kept, name))
    assert vol.species == kept.species
    assert [v for v in hyd.data_vars if v.startswith(("q_", "r_eff_"))] == []
    assert "rho_air" in hyd


def numpy_voxel_albedo(hyd, sp, beta_ext, albedo_sum):
    """``optics.volume._voxel_albedo`` as numpy expressions (weather-mi before the compiled pass)."""
    from weather_mi.optics.species import physical_albedo
    for i, s in enumerate(sp):
        var = f"r_eff_{s.name}"
        physical = tuple(float(a) for a in physical_albedo(s.phase_class, np.float64(s.radius_m), s.density_kg_m3))
        if var not in hyd or tuple(s.albedo_rgb) != physical:
            continue
        r, beta = np.asarray(hyd[var].values).reshape(-1), beta_ext[i].reshape(-1)
        idx = np.flatnonzero((beta > 0) & (r > 0))
        omegas = physical_albedo(s.phase_class, r[idx].astype(np.float64), s.density_kg_m3)
        b = beta[idx].astype(np.float64)
        for c in range(3):
            albedo_sum[idx, c] += ((omegas[c] - s.albedo_rgb[c]) * b).astype(np.float32)


def numpy_optics(hyd, sp, use_model, voxel_albedo):
    """``optics.volume``'s four grids (beta_ext, beta_total, albedo, weights) as the numpy expressions of
    weather-mi before the compiled voxel pass: Eq. 4 as numpy's float32 operations in the expression's order (the
    radius grid's zeros the species' radius), Eq. 6, 5, 8 summed species after species in float32, each voxel's albedo from its radius
    (``numpy_voxel_albedo``), the clear voxels filled with the volume's mean albedo, clipped to [0, 1]."""
    rho = hyd["rho_air"].values.astype(np.float32)
    beta = np.empty((len(sp),) + rho.shape, np.float32)
    for i, s in enumerate(sp):
        r = s.radius_m
        if use_model and f"r_eff_{s.name}" in hyd:
            r = hyd[f"r_eff_{s.name}"].values.astype(np.float32)
            r = np.where(r > 0, r, np.float32(s.radius_m))
        q = hyd[f"q_{s.name}"].values.astype(np.float32)
        beta[i] = rho * np.float32(s.scale * 3.0) * q / (np.float32(2.0 * s.density_kg_m3 * r) if np.ndim(r) == 0
                                                         else r * np.float32(2.0 * s.density_kg_m3))
    rgb = np.asarray([s.albedo_rgb for s in sp], np.float32)
    mean_albedo = np.asarray([np.float32(np.mean(s.albedo_rgb)) for s in sp], np.float32)
    total, albedo_sum = beta[0].copy(), np.stack([beta[0] * rgb[0, c] for c in range(3)], axis=-1)
    w = beta * mean_albedo[:, None, None, None]
    sca = w[0].copy()
    for i in range(1, len(sp)):
        total = total + beta[i]
        albedo_sum = albedo_sum + np.stack([beta[i] * rgb[i, c] for c in range(3)], axis=-1)
        sca = sca + w[i]
    with np.errstate(divide="ignore", invalid="ignore"):
        weights = np.where(sca > 0, w / sca, np.float32(0.0))
    if voxel_albedo and use_model:
        numpy_voxel_albedo(hyd, sp, beta, albedo_sum.reshape(-1, 3))
    total_ext = float(total.sum(dtype=np.float64))
    fill = albedo_sum.reshape(-1, 3).sum(axis=0, dtype=np.float64) / total_ext
    with np.errstate(divide="ignore", invalid="ignore"):
        albedo = np.where(total[..., None] > 0, albedo_sum / total[..., None], fill.astype(np.float32))
    return beta, total, np.clip(albedo, 0, 1), weights


def bits(a):
    return np.asarray(a).view(np.uint32)


@pytest.mark.parametrize("species,sizes,scale", [
    ("paper", "scheme", None), ("physical", "scheme", {"ice": 2.0}), ("physical", None, None),
    ("paper", "paper", None), ("physical", "physical", None), (preset("physical", albedo=0.9), "scheme", None)])
@pytest.mark.parametrize("keep", [("beta_ext", "weights"), ("weights",), ("beta_ext",), ()])
def test_compiled_voxel_pass_equals_the_numpy_expressions(species, sizes, scale, keep):
    """The one compiled pass (``optics.mixture_kernels.voxel_optics``) gives the numpy expressions' grids
    (written out above) bit for bit, signed zeros included, for each species table, particle sizes, scaling and
    set of kept grids; a grid not kept is released (never built); the albedo of each voxel's radius differs from
    the species' fixed one."""
    hyd = wm.synthetic.cumulus()
    rng = np.random.default_rng(2)
    for s in wm.SPECIES_NAMES:
        r = rng.uniform(1e-5, 5e-4, hyd[f"q_{s}"].shape).astype(np.float32)
        r[rng.random(r.shape) < 0.2] = 0  # the species' radius there
        if s != "snow":  # a species without radii: the table's
            hyd[f"r_eff_{s}"] = hyd[f"q_{s}"].copy(data=r)
    q = hyd["q_rain"].values.copy()
    q[(q == 0) & (rng.random(q.shape) < 0.01)] = -0.0  # signed zeros pass validate and reach the grids
    hyd["q_rain"] = hyd["q_rain"].copy(data=q)
    vol = wm.optical_volume(hyd, species, scale=scale, sizes=sizes, phase_quality="test", keep=keep)
    sp, use_model = wm.optics.volume._species_setup(species, scale, None, sizes)
    expected = dict(zip(("beta_ext", "beta_total", "albedo", "weights"),
                        numpy_optics(hyd, sp, use_model, sizes == "scheme")))
    assert np.any(np.signbit(expected["beta_ext"]) & (expected["beta_ext"] == 0))
    for name, grid in expected.items():
        if name in ("beta_total", "albedo") or name in keep:
            np.testing.assert_array_equal(bits(getattr(vol, name)), bits(grid), err_msg=name)
        else:
            released = getattr(vol, name)
            assert isinstance(released, wm.optics.volume.ReleasedGrid) and released.shape == grid.shape
    if sizes == "scheme" and not isinstance(species, wm.species.SpeciesSet):
        fixed = wm.optical_volume(hyd, species, scale=scale, sizes="physical", phase_quality="test")
        assert not np.array_equal(fixed.albedo, vol.albedo)


def test_each_species_inputs_released_before_the_next_is_read(monkeypatch):
    """With ``release``, the optics drop each species' mixing ratio and radii from the dataset before the next
    species' pass reads its own (``mixture_kernels.species_pass``): the peak holds one species' inputs, not
    all five with the outputs."""
    from weather_mi.optics import mixture_kernels
    hyd = wm.synthetic.cumulus()
    for s in wm.SPECIES_NAMES:
        hyd[f"r_eff_{s}"] = hyd[f"q_{s}"].copy(data=np.full(hyd[f"q_{s}"].shape, 2e-5, np.float32))
    held, real = [], mixture_kernels.species_pass
    def spy(*a):
        held.append(sorted(n for n in hyd.data_vars if n[:2] in ("q_", "r_")))
        return real(*a)
    monkeypatch.setattr(mixture_kernels, "species_pass", spy)
    wm.optical_volume(hyd, "physical", sizes="scheme", phase_quality="test", release=True, keep=("weights",))
    assert held == [sorted(f"{k}_{s}" for s in wm.SPECIES_NAMES[i:] for k in ("q", "r_eff"))
                    for i in range(len(wm.SPECIES_NAMES))]
    assert not any(n[:2] in ("q_", "r_") for n in hyd.data_vars)


def test_albedo_sums_is_numpys_sum_over_voxels():
    """``mixture_kernels.albedo_sums`` (the voxels with extinction only) is numpy's float64 sum over axis 0,
    bit for bit, on sums of widely spread magnitudes (a different order of the additions would show)."""
    from weather_mi.optics.mixture_kernels import albedo_sums
    rng = np.random.default_rng(5)
    for n in (7, 8193, 300_001):
        a = (rng.standard_normal((n, 3)) * np.exp(5 * rng.standard_normal((n, 3)))).astype(np.float32)
        total = rng.random(n).astype(np.float32)
        total[rng.random(n) < 0.5] = 0
        a[total == 0] = 0
        np.testing.assert_array_equal(albedo_sums(a, total), a.sum(axis=0, dtype=np.float64))
