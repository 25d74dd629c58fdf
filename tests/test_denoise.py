"""The denoised display layer (issue 24): an extra EXR layer and the PNG, never the data; the CLI writes it
and says so; OIDN brings a flat noisy field closer to its truth than the raw one (closed form); the
noise-free auxiliary features against closed forms on homogeneous and linear media."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.cli import commands as cli
from weather_mi.display import metrics
from weather_mi.reference import render as reference_module
from weather_mi.display.denoise import AUX, denoise_image, denoise_radiance, display_label
from weather_mi.io.image import Image, auto_exposure, to_srgb8

pytest.importorskip("pyoidn")


def noisy_flat(shape=(48, 64), mean=1.0, sigma=0.2, seed=0):
    rng = np.random.default_rng(seed)
    return (mean + sigma * rng.standard_normal(shape + (3,))).astype(np.float32)


def test_the_layer_round_trips_and_the_png_shows_it(tmp_path):
    rad = noisy_flat((6, 8))
    den = np.full_like(rad, 0.75)
    img = Image(rad, np.full_like(rad, 0.1), {"display": display_label("none")}, np.full((6, 8), 0.3, np.float32),
                denoised=den)
    img.save(tmp_path / "a.exr")
    back = Image.load(tmp_path / "a.exr")
    assert np.array_equal(back.radiance, rad) and np.array_equal(back.denoised, den)
    assert back.metadata["display"].startswith("denoised (OIDN 2.5")
    assert Image.load(_saved_without_layer(tmp_path, rad)).denoised is None
    img.save_png(tmp_path / "a.png")
    from PIL import Image as PILImage
    png = np.asarray(PILImage.open(tmp_path / "a.png"))
    assert np.array_equal(png, to_srgb8(den, auto_exposure(rad)))   # the denoised layer, the radiance's exposure
    with pytest.raises(ValueError, match="denoised"):
        Image(rad, denoised=den[:3])


def _saved_without_layer(tmp_path, rad):
    return Image(rad).save(tmp_path / "plain.exr")


def test_compare_never_uses_the_denoised_layer_unless_asked_by_name():
    truth = np.full((12, 16, 3), 0.5, np.float32)
    rad = noisy_flat((12, 16), 0.5, 0.1)
    img = Image(rad, denoised=truth.copy())
    ref = Image(truth, np.zeros_like(truth))
    by_default = metrics.compare(ref, img)
    assert by_default == metrics.compare(ref, rad)        # the unbiased radiance
    assert by_default["rmse"] == pytest.approx(float(np.sqrt(np.mean((rad - truth) ** 2.0))), rel=1e-6)
    assert metrics.compare(ref, img, layer="denoised")["rmse"] == 0.0
    with pytest.raises(ValueError, match="denoised layer"):
        metrics.compare(ref, Image(rad), layer="denoised")
    with pytest.raises(ValueError, match="layer"):
        metrics.compare(ref, img, layer="display")


def test_a_denoised_flat_noisy_field_is_closer_to_the_truth_than_the_raw_one():
    """A constant field plus i.i.d. Gaussian noise: the raw image's MSE is sigma^2 (closed form); the
    denoised one keeps the mean (bias < 1%) and is at least 5x closer in RMS."""
    mean, sigma = 1.0, 0.2
    rad = noisy_flat((96, 128), mean, sigma, seed=3)
    den = denoise_radiance(rad)
    raw_rms = float(np.sqrt(np.mean((rad - mean) ** 2)))
    assert raw_rms == pytest.approx(sigma, rel=0.02)
    assert float(np.sqrt(np.mean((den - mean) ** 2))) < raw_rms / 5
    assert abs(float(den.mean()) - mean) < 0.01 * mean
    with pytest.raises(ValueError, match="NaN"):
        denoise_radiance(np.where(rad > 1.5, np.nan, rad))


def _box_view(beta, albedo=0.8, width=24, height=18):
    vol = wm.OpticalVolume.from_arrays(beta, albedo=albedo, bbox=((0, 0, 0), (1000, 1000, 1000)))
    cam = wm.Camera.orbit(vol, azimuth=200, elevation=10, fov=40)
    return vol, wm.SceneSpec(camera=cam, sky=None, ground=None, width=width, height=height)


def test_the_albedo_feature_is_the_single_scattering_fraction_of_a_homogeneous_box():
    """Homogeneous box, no sky, no ground: the eye-ray first-scattering albedo is omega (1 - e^-tau)
    with tau the eye-ray optical depth (a sum that telescopes: exact for any step)."""
    from weather_mi.display.denoise_features import view_features
    from weather_mi.reference.estimates import view_optical_depth
    vol, spec = _box_view(np.full((8, 8, 8), 2e-3, np.float32), albedo=0.8)
    f = view_features(spec, vol, exposure=1.0)
    tau = view_optical_depth(spec, vol)
    assert (tau > 0.5).sum() > 50 and (tau == 0).sum() > 10
    assert np.allclose(f.transmittance, np.exp(-tau), atol=0.01)
    assert np.allclose(f.albedo, 0.8 * (1 - np.exp(-tau))[..., None], atol=0.01)


def test_the_normal_feature_faces_down_the_extinction_gradient():
    """Extinction rising along +x: the normal-like feature is -x (world) in camera coordinates."""
    from weather_mi.display.denoise_features import camera_frame, view_features
    x = np.linspace(0.5, 4.0, 16, dtype=np.float32) * 1e-3
    vol, spec = _box_view(np.broadcast_to(x, (16, 16, 16)).copy())
    f = view_features(spec, vol, exposure=1.0)
    from weather_mi.kernel.scene_dict import recentred
    want = camera_frame(recentred(spec, vol)[0]) @ np.array([-1.0, 0.0, 0.0])
    hit = f.transmittance < np.exp(-1.5)
    assert hit.sum() > 30
    assert np.allclose(f.normal[hit], want, atol=1e-3)
    assert np.allclose(np.linalg.norm(f.normal, axis=2), 1.0, atol=1e-5)


@pytest.mark.parametrize("aux", AUX)
def test_every_auxiliary_choice_denoises_a_view(aux):
    vol, spec = _box_view(np.full((8, 8, 8), 2e-3, np.float32))
    img = Image(noisy_flat((18, 24), 1.0, 0.3))
    frame = np.full((18, 24, 3), 0.8, np.float32) if aux == "slicer" else None
    denoise_image(img, spec, vol, aux=aux, slicer_frame=frame)
    assert img.denoised.shape == (18, 24, 3) and np.all(np.isfinite(img.denoised))
    assert f"auxiliaries: {aux}" in img.metadata["display"]
    with pytest.raises(ValueError, match="expected one of"):
        denoise_image(img, spec, vol, aux="depth")


def _render(tmp_path, capsys, *extra):
    rc = cli.main(["render", "--demo", "cumulus", "--size", "24x18", "--spp", "4", "-o", str(tmp_path / "a.exr"),
                   *extra])
    out, err = capsys.readouterr()
    assert rc == 0, err
    from PIL import Image as PILImage
    return Image.load(tmp_path / "a.exr"), np.asarray(PILImage.open(tmp_path / "a.png")), out


def test_the_cli_writes_the_denoised_layer_and_says_so(tmp_path, capsys):
    img, png, out = _render(tmp_path, capsys)
    assert img.denoised is not None and img.metadata["display"].startswith("denoised (OIDN")
    assert "the PNG shows the denoised (OIDN" in out
    assert np.array_equal(png, to_srgb8(img.denoised, auto_exposure(img.radiance)))
    assert not np.array_equal(img.denoised, img.radiance)
    assert img.metadata["noise"]["rse_mean"] > 0        # the noise figures: the unbiased radiance's


def test_no_denoise_writes_the_raw_png(tmp_path, capsys, monkeypatch):
    img, png, out = _render(tmp_path, capsys, "--no-denoise")
    assert img.denoised is None and "display" not in img.metadata
    assert "the PNG shows the raw (unbiased) radiance" in out
    assert np.array_equal(png, to_srgb8(img.radiance))


def test_a_missing_denoiser_is_said_before_rendering(tmp_path, capsys, monkeypatch):
    import sys
    monkeypatch.setitem(sys.modules, "pyoidn", None)
    monkeypatch.setattr(reference_module, "render_reference", lambda *a, **k: pytest.fail("rendering started"))
    with pytest.raises(ImportError, match="--no-denoise"):
        cli.main(["render", "--demo", "cumulus", "--size", "8x6", "-o", str(tmp_path / "a.exr")])
