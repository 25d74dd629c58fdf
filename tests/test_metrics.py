"""Image metrics (weather_mi.display.metrics) on pairs with known answers."""
from __future__ import annotations

import numpy as np
import pytest

from weather_mi.display import metrics
from weather_mi.io.image import Image, auto_exposure

KEYS = ("rmse", "rel_mse", "ssim", "ciede2000", "flip", "noise_floor", "exposure", "n_pixels")


def _smooth_image(h=64, w=96, seed=0):
    """A smooth, coloured radiance image (W/m^2/sr-like values around 0.1 - 0.6)."""
    from scipy.ndimage import gaussian_filter
    rng = np.random.default_rng(seed)
    img = gaussian_filter(rng.random((h, w, 3)), sigma=(4, 4, 0)) * 0.8 + 0.05
    yy, xx = np.mgrid[0:h, 0:w]
    img += 0.2 * np.stack([xx / w, yy / h, 1 - xx / w], axis=-1)
    return img.astype(np.float32)


def test_identical_images_are_perfect():
    ref = _smooth_image()
    m = metrics.compare(ref, ref.copy())
    assert set(KEYS) <= set(m)
    assert m["rmse"] == 0.0 and m["rel_mse"] == 0.0
    assert m["ssim"] == pytest.approx(1.0, abs=1e-12)
    assert m["ciede2000"] == pytest.approx(0.0, abs=1e-9)
    assert m["flip"] == 0.0
    assert m["n_pixels"] == ref.shape[0] * ref.shape[1] and isinstance(m["n_pixels"], int)
    assert all(isinstance(m[k], float) for k in KEYS if k != "n_pixels")
    assert m["exposure"] == pytest.approx(auto_exposure(ref))


def test_constant_offset_gives_closed_form_rmse_and_rel_mse():
    ref = _smooth_image()
    c = 0.03
    m = metrics.compare(ref, ref + np.float32(c))
    r = ref.astype(np.float64)
    a = (ref + np.float32(c)).astype(np.float64)
    assert m["rmse"] == pytest.approx(c, rel=1e-5)
    eps = 1e-2 * r.mean() ** 2
    assert m["rel_mse"] == pytest.approx(np.mean((a - r) ** 2 / (r ** 2 + eps)), rel=1e-9)
    assert m["ciede2000"] > 0.5 and m["flip"] > 0 and m["ssim"] < 1.0


def test_equal_luminance_hue_swap_has_nonzero_ciede2000():
    ref = np.zeros((32, 32, 3), np.float32)
    ref[...] = (0.6, 0.3, 0.1)
    swapped = ref[..., ::-1].copy()  # R <-> B: the channel mean (the project's luminance) is unchanged
    assert auto_exposure(ref) == pytest.approx(auto_exposure(swapped))
    m = metrics.compare(ref, swapped)
    assert m["ciede2000"] > 20.0
    assert m["flip"] > 0.1


def test_cloud_mask_selects_pixels_below_threshold():
    ref = _smooth_image(64, 128)
    transmittance = np.ones((64, 128))
    transmittance[:, :40] = 0.3            # cloud on the left
    approx = ref.copy()
    approx[:, 96:] *= 1.5                   # a difference far outside the cloud
    img = Image(ref, metadata={"transmittance": transmittance.tolist()})
    m = metrics.compare(img, approx, mask="cloud")  # transmittance from the reference's metadata
    assert m["n_pixels"] == 64 * 40
    assert m["rmse"] == 0.0 and m["rel_mse"] == 0.0 and m["ciede2000"] == pytest.approx(0.0, abs=1e-9)
    assert m["ssim"] == pytest.approx(1.0, abs=1e-12) and m["flip"] == pytest.approx(0.0, abs=1e-7)
    everywhere = metrics.compare(ref, approx)
    assert everywhere["rmse"] > 0 and everywhere["ciede2000"] > 0 and everywhere["flip"] > 0
    # the explicit transmittance argument and a boolean mask agree with the metadata
    m2 = metrics.compare(ref, approx, mask="cloud", transmittance=transmittance, threshold=0.5)
    assert m2["n_pixels"] == 64 * 40
    inside = np.zeros((64, 128), bool)
    inside[:, 100:] = True
    m3 = metrics.compare(ref, approx, mask=inside)
    expected = np.sqrt(np.mean((approx[inside].astype(np.float64) - ref[inside]) ** 2))
    assert m3["n_pixels"] == 64 * 28 and m3["rmse"] == pytest.approx(expected, rel=1e-6)
    # the exposure comes from the whole reference, not the masked part
    assert m3["exposure"] == m["exposure"] == everywhere["exposure"]


def test_cloud_mask_without_transmittance_raises():
    ref = _smooth_image(16, 16)
    with pytest.raises(ValueError, match="transmittance"):
        metrics.compare(ref, ref, mask="cloud")
    with pytest.raises(ValueError, match="no pixels"):
        metrics.compare(ref, ref, mask="cloud", transmittance=np.ones((16, 16)))
    with pytest.raises(ValueError, match="shape"):
        metrics.compare(ref, ref[:8])


def test_cloud_mask_of_a_reference_comes_with_it_also_through_its_exr(tmp_path):
    """``render_reference`` keeps its eye-ray transmittance with the image (``Image.transmittance``, an EXR
    layer): ``compare(ref, img, mask="cloud")`` needs no transmittance argument, before and after an EXR
    round trip, and at threshold 1/2 it measures the cloud pixels of the reference's noise figures."""
    import weather_mi as wm
    from test_reference import WIDE_VIEW, cloud_volume, spec
    vol, sp = cloud_volume(), spec(seed=3, camera=WIDE_VIEW)
    ref = wm.render_reference(sp, vol, spp=4, passes=2, progress=False)
    t = ref.transmittance
    assert t.shape == ref.shape and t.dtype == np.float32 and np.all((t > 0) & (t <= 1))
    cloud = wm.reference.estimates.cloud_mask(sp, vol)
    assert np.array_equal(t < 0.5, cloud) and 0.2 < cloud.mean() < 0.8
    assert ref.metadata["noise"]["cloud_pixels"] == int(np.count_nonzero(cloud & (ref.radiance.mean(axis=2) > 0)))
    approx = ref.radiance * np.float32(1.1)
    m = metrics.compare(ref, approx, mask="cloud")
    assert m["n_pixels"] == int(np.count_nonzero(t < 0.99)) < t.size
    assert metrics.compare(ref, approx, mask="cloud", threshold=0.5)["n_pixels"] == int(cloud.sum())
    assert m == metrics.compare(ref, approx, mask="cloud", transmittance=t)
    back = Image.load(ref.save(tmp_path / "ref.exr"))
    np.testing.assert_array_equal(back.transmittance, t)
    assert metrics.compare(back, approx, mask="cloud") == m
    assert metrics.noise_floor(back, mask="cloud") == metrics.noise_floor(ref, mask="cloud")
    # a transmittance put in the metadata (the study's, the slicer's) still comes first
    other = np.ones(ref.shape)
    other[:, :3] = 0.0
    back.metadata["transmittance"] = other.tolist()
    assert metrics.compare(back, approx, mask="cloud")["n_pixels"] == 3 * ref.shape[0]
    # an image without one (the slicer's, an older EXR) still needs the argument
    with pytest.raises(ValueError, match="transmittance"):
        metrics.compare(Image(ref.radiance, ref.stderr, {}), approx, mask="cloud")
    with pytest.raises(ValueError, match=r"transmittance must be \(H, W\)"):
        Image(ref.radiance, transmittance=np.ones(3))


def test_ssim_decreases_with_added_noise():
    ref = _smooth_image()
    rng = np.random.default_rng(1)
    values = []
    for sigma in (0.0, 0.01, 0.05, 0.2):
        noisy = np.clip(ref + rng.normal(0, sigma, ref.shape), 0, None).astype(np.float32)
        values.append(metrics.compare(ref, noisy)["ssim"])
    assert values[0] == pytest.approx(1.0)
    assert values[0] > values[1] > values[2] > values[3]
    assert values[3] < 0.8


def test_ssim_matches_a_direct_wang_formula_on_constant_images():
    """Two constant images: SSIM = (2 mu_x mu_y + C1) / (mu_x^2 + mu_y^2 + C1) (variances vanish)."""
    x = np.full((20, 20), 0.4)
    y = np.full((20, 20), 0.6)
    c1 = (0.01 * 1.0) ** 2
    expected = (2 * 0.4 * 0.6 + c1) / (0.4 ** 2 + 0.6 ** 2 + c1)
    assert np.allclose(metrics.ssim_map(x, y), expected, atol=1e-10)


def test_noise_floor_of_constant_stderr():
    ref = _smooth_image(32, 32)
    s = 0.0123
    img = Image(ref, np.full_like(ref, s))
    assert metrics.noise_floor(img) == pytest.approx(s, rel=1e-6)
    stderr = np.full_like(ref, s)
    stderr[:, 16:] = 3 * s
    t = np.ones((32, 32))
    t[:, :16] = 0.2
    img2 = Image(ref, stderr, {"transmittance": t})
    assert metrics.noise_floor(img2, mask="cloud") == pytest.approx(s, rel=1e-6)
    assert metrics.noise_floor(img2) == pytest.approx(np.sqrt((s ** 2 + 9 * s ** 2) / 2), rel=1e-6)
    assert metrics.compare(img, ref)["noise_floor"] == pytest.approx(s, rel=1e-6)
    assert np.isnan(metrics.noise_floor(Image(ref)))  # no stderr


def test_error_map_png_is_written(tmp_path):
    ref = _smooth_image(48, 64)
    approx = ref * np.float32(1.1)
    t = np.ones((48, 64))
    t[10:30, 10:40] = 0.5
    path = tmp_path / "err" / "map.png"
    m = metrics.compare(Image(ref), approx, mask="cloud", transmittance=t, error_map=path)
    assert path.is_file() and path.stat().st_size > 1000
    from PIL import Image as PILImage
    with PILImage.open(path) as im:
        assert im.size[0] > im.size[1]
    assert m["n_pixels"] == 20 * 30


def test_display_conversion_matches_project_png():
    """The metrics' display colour is imageio.to_srgb8 without the 8-bit rounding."""
    from weather_mi.io.image import to_srgb8
    ref = _smooth_image(16, 16) * 3
    e = auto_exposure(ref)
    srgb = metrics.display_srgb(ref, e)
    assert np.max(np.abs(np.round(srgb * 255) - to_srgb8(ref, e))) <= 1
    lab = metrics.display_lab(np.ones((1, 1, 3)))
    assert lab[0, 0] == pytest.approx([100.0, 0.0, 0.0], abs=0.02)  # display white ~ the D65 white


def test_non_finite_radiance_is_rejected():
    ref = _smooth_image(8, 8)
    bad = ref.copy()
    bad[0, 0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        metrics.compare(ref, bad)
