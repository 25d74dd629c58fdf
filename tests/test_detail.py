"""Simulated turbulent detail (weather_mi.optics.detail): tileable fractal noise and its use on Hydrometeors."""
from __future__ import annotations

import json

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.optics import detail
from weather_mi.io.hydrometeors import SPECIES_NAMES, spacing_of, validate


def _seam_ratio(n: np.ndarray, axis: int) -> float:
    """Mean squared jump across the wrap-around seam (last -> first slice) over the mean squared jump
    between neighbouring interior slices: about 1 for a tileable field, about 2 / (2 (1 - rho_1)) >> 1
    for a smooth field that does not wrap."""
    inner = np.mean(np.diff(n, axis=axis).astype(np.float64) ** 2)
    seam = np.mean((np.take(n, 0, axis=axis).astype(np.float64) - np.take(n, -1, axis=axis)) ** 2)
    return float(seam / inner)


def _hyd(shape=(48, 48, 48), spacing=(500.0, 500.0, 500.0), rho=1.0, value=1e-3, species=SPECIES_NAMES):
    q = np.full(shape, value, np.float32)
    return wm.from_arrays({s: q for s in species}, rho_air=rho, spacing=spacing)


def _mass(hyd, name):
    """Independent total water (kg): sum over the grid of rho_air q dV, in float64."""
    dz, dy, dx = spacing_of(hyd)
    return float((hyd["rho_air"].values.astype(np.float64) * hyd[f"q_{name}"].values.astype(np.float64)).sum()
                 * dz * dy * dx)


def test_noise_is_zero_mean_unit_variance_float32():
    n = detail.noise((40, 48, 56), spacing_m=(250.0, 500.0, 500.0), seed=3)
    assert n.dtype == np.float32 and n.shape == (40, 48, 56)
    assert abs(n.mean(dtype=np.float64)) < 1e-5
    assert n.std(dtype=np.float64) == pytest.approx(1.0, abs=1e-5)
    assert np.all(np.isfinite(n))


def test_noise_is_tileable_along_every_axis():
    n = detail.noise((48, 48, 48), seed=1)
    for axis in range(3):
        assert 0.6 < _seam_ratio(n, axis) < 1.6, axis
        # a 2 x 2 x 2 tiling shows no seam either: jumps across the copies' joins match the interior
        tiled = np.concatenate([n, n], axis=axis)
        joint = np.take(tiled, n.shape[axis], axis=axis) - np.take(tiled, n.shape[axis] - 1, axis=axis)
        assert np.mean(joint.astype(np.float64) ** 2) == pytest.approx(
            np.mean(np.diff(n, axis=axis).astype(np.float64) ** 2), rel=0.6)
    # control: the same kind of field, cropped out of a bigger grid, does NOT wrap (the test has power)
    crop = detail.noise((96, 96, 96), seed=1, base_wavelength_m=16.0)[:48, :48, :48]
    assert min(_seam_ratio(crop, axis) for axis in range(3)) > 3.0


def test_noise_is_translation_invariant_on_the_torus():
    """Rolling the field is another sample of the same periodic field: statistics of the rolled field's
    seam are those of the interior (the seam moved to where the field is continuous)."""
    n = detail.noise((32, 40, 48), seed=7)
    rolled = np.roll(n, (11, 17, 23), axis=(0, 1, 2))
    for axis in range(3):
        assert 0.5 < _seam_ratio(rolled, axis) < 2.0


def test_noise_deterministic_per_seed():
    a = detail.noise((32, 32, 32), seed=5)
    b = detail.noise((32, 32, 32), seed=5)
    c = detail.noise((32, 32, 32), seed=6)
    assert np.array_equal(a, b)
    assert not np.allclose(a, c)
    assert abs(np.corrcoef(a.ravel(), c.ravel())[0, 1]) < 0.2


def test_noise_scales_follow_base_wavelength_and_spacing():
    """Longer wavelength -> smoother field (smaller neighbour jumps); the same physical wavelength on a
    finer grid spans more cells."""
    fine = detail.noise((32, 32, 32), base_wavelength_m=8.0, octaves=1, seed=2)
    coarse = detail.noise((32, 32, 32), base_wavelength_m=24.0, octaves=1, seed=2)
    jump = lambda n: np.mean(np.diff(n, axis=2) ** 2)  # noqa: E731
    assert jump(coarse) < 0.5 * jump(fine)
    # anisotropic spacing: isotropic in metres, so smoother along the finely spaced z axis
    n = detail.noise((64, 32, 32), spacing_m=(250.0, 1000.0, 1000.0), base_wavelength_m=16000.0, seed=2)
    assert np.mean(np.diff(n, axis=0) ** 2) < 0.5 * np.mean(np.diff(n, axis=2) ** 2)


def test_noise_rejects_unrepresentable_scales():
    with pytest.raises(ValueError, match="Nyquist"):
        detail.noise((16, 16, 16), base_wavelength_m=1.0)
    with pytest.raises(ValueError, match="spacing"):
        detail.noise((16, 16, 16), spacing_m=(1.0, -1.0, 1.0))


def test_noise_on_128_cubed_builds_its_filter_once():
    """A re-seeded noise on the same grid reuses the cached spectral filter (its speed, 1 s at 128^3, is a goal of
    benchmarks/detail.py, not a timed test) and is another zero-mean, unit-variance float32 field."""
    detail._spectral_filter.cache_clear()
    first = detail.noise((128, 128, 128), seed=0)  # builds and caches the spectral filter
    second = detail.noise((128, 128, 128), seed=1)
    info = detail._spectral_filter.cache_info()
    assert (info.misses, info.hits) == (1, 1)
    for n in (first, second):
        assert n.dtype == np.float32 and n.shape == (128, 128, 128)
        assert abs(n.mean(dtype=np.float64)) < 1e-5 and n.std(dtype=np.float64) == pytest.approx(1.0, abs=1e-5)
    assert abs(np.corrcoef(first.ravel(), second.ravel())[0, 1]) < 0.05  # another draw, not the same field


def test_field_is_a_mean_one_float32_multiplier():
    f = detail.field((24, 32, 40), seed=0, amplitude=0.5)
    assert f.dtype == np.float32 and f.shape == (24, 32, 40)
    assert np.all(f > 0)
    assert f.mean(dtype=np.float64) == pytest.approx(1.0, abs=1e-6)
    assert f.std() > 0.2
    assert np.array_equal(f, detail.field((24, 32, 40), seed=0, amplitude=0.5))
    assert np.array_equal(detail.field((8, 8, 8), amplitude=0.0), np.ones((8, 8, 8), np.float32))
    lin = detail.field((24, 32, 40), seed=0, amplitude=1.5, mean_preserving=False)
    assert np.all(lin >= 0) and np.any(lin == 0)
    assert lin.mean(dtype=np.float64) == pytest.approx(1.0, abs=1e-6)


def test_mean_preserving_form_keeps_total_water_within_one_percent():
    hyd = _hyd(shape=(64, 64, 64))
    for seed in range(4):
        _, report = detail.add_detail(hyd, amplitude=0.8, seed=seed)
        for key, change in report.items():
            assert abs(change) < 0.01, (seed, key, change)


def test_add_detail_valid_nonnegative_and_report_matches():
    rng = np.random.default_rng(0)
    shape = (24, 32, 40)
    q = {"cloud": rng.random(shape) * 1e-3, "ice": rng.random(shape) * 2e-4, "snow": np.zeros(shape),
         "rain": rng.random(shape) * 5e-4}
    hyd = wm.from_arrays(q, rho_air=np.linspace(1.2, 0.4, shape[0]), spacing=(250.0, 500.0, 500.0))
    before = {name: _mass(hyd, name) for name in SPECIES_NAMES}
    for mean_preserving in (True, False):
        out, report = detail.add_detail(hyd, amplitude={"cloud": 0.8, "ice": 1.5, "rain": 0.3},
                                        mean_preserving=mean_preserving, seed=4)
        validate(out)
        for name in SPECIES_NAMES:
            v = out[f"q_{name}"].values
            assert v.dtype == np.float32 and v.shape == shape and np.all(v >= 0)
            expected = (_mass(out, name) - before[name]) / before[name] if before[name] > 0 else 0.0
            assert report[name] == pytest.approx(expected, rel=1e-4, abs=1e-7)
        total = (sum(_mass(out, n) for n in SPECIES_NAMES) - sum(before.values())) / sum(before.values())
        assert report["total"] == pytest.approx(total, rel=1e-4, abs=1e-7)
        assert not np.array_equal(out["q_cloud"].values, hyd["q_cloud"].values)
        assert np.array_equal(out["q_graupel"].values, hyd["q_graupel"].values)  # amplitude 0 (not named)
        assert np.array_equal(out["rho_air"].values, hyd["rho_air"].values)
        settings = json.loads(out.attrs["detail"])
        assert settings["mean_preserving"] is mean_preserving and settings["amplitude"]["ice"] == 1.5
        assert out.attrs["source"] == hyd.attrs["source"]
    assert "detail" not in hyd.attrs  # the input is untouched
    assert np.array_equal(hyd["q_cloud"].values, q["cloud"].astype(np.float32))


def test_linear_form_clips_at_zero():
    hyd = _hyd(shape=(32, 32, 32), species=("cloud",))
    out, report = detail.add_detail(hyd, amplitude=2.0, mean_preserving=False)
    v = out["q_cloud"].values
    assert np.all(v >= 0) and np.any(v == 0)
    assert report["cloud"] > 0.05  # clipping the negative side raises the mean


def test_amplitude_zero_is_identity():
    rng = np.random.default_rng(1)
    hyd = wm.from_arrays({"cloud": rng.random((16, 16, 16)) * 1e-3, "graupel": rng.random((16, 16, 16)) * 1e-4},
                         rho_air=1.0, spacing=(100.0, 100.0, 100.0))
    for form in (True, False):
        out, report = detail.add_detail(hyd, amplitude=0.0, mean_preserving=form)
        for name in SPECIES_NAMES:
            assert np.array_equal(out[f"q_{name}"].values, hyd[f"q_{name}"].values)
        assert all(v == 0.0 for v in report.values())


def test_add_detail_deterministic_correlated_and_exact_total():
    hyd = _hyd(shape=(32, 32, 32))
    a, _ = detail.add_detail(hyd, seed=3)
    b, _ = detail.add_detail(hyd, seed=3)
    c, _ = detail.add_detail(hyd, seed=4)
    assert np.array_equal(a["q_cloud"].values, b["q_cloud"].values)
    assert not np.allclose(a["q_cloud"].values, c["q_cloud"].values)
    # correlated (default): the same eddies in every species; independent: uncorrelated species
    lc, li = np.log(a["q_cloud"].values).ravel(), np.log(a["q_ice"].values).ravel()
    assert np.corrcoef(lc, li)[0, 1] > 0.99
    d, _ = detail.add_detail(hyd, seed=3, correlated=False)
    assert abs(np.corrcoef(np.log(d["q_cloud"].values).ravel(), np.log(d["q_ice"].values).ravel())[0, 1]) < 0.2
    e, report = detail.add_detail(hyd, seed=3, amplitude=1.2, exact_total=True)
    assert all(abs(v) < 1e-5 for v in report.values())


def test_add_detail_rejects_bad_arguments():
    hyd = _hyd(shape=(8, 8, 8))
    with pytest.raises(ValueError, match="species"):
        detail.add_detail(hyd, amplitude={"hail": 0.5})
    with pytest.raises(ValueError, match="amplitude"):
        detail.add_detail(hyd, amplitude=-1.0)
