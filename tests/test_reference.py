"""``render_reference`` (the path-traced ground truth in passes) and the ``weather-mi render`` command:
image layout and standard errors, determinism, checkpoint and resume, EXR/PNG output, metadata,
input checks before any rendering, reflectance normalisation.

Every render is tiny (16 x 12 pixels, a few dozen samples per pixel, 8^3 voxels) and seeded.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

import mitsuba as mi

import weather_mi as wm
from weather_mi.cli import commands as cli

W, H = 16, 12
BBOX = ((0.0, 0.0, 1000.0), (1000.0, 1000.0, 2000.0))


def cloud_volume(g=0.85, seed=0, n=8, upper_half_only=False) -> wm.OpticalVolume:
    """A 1 km cube of cloud 1 km above the ground, extinction 3e-3 .. 1.3e-2 1/m in every voxel
    (optical depth ~8 across); ``upper_half_only`` empties its lower half."""
    rng = np.random.default_rng(seed)
    beta = (0.01 * (0.3 + rng.random((n, n, n)))).astype(np.float32)
    if upper_half_only:
        beta[: n // 2] = 0.0
    return wm.OpticalVolume.from_arrays(beta_ext=beta, albedo=0.99, phase=wm.phase.henyey_greenstein(g), bbox=BBOX)


# looking north from the south at the middle of the cube: the film (800 m x 600 m) lies inside the
# cube's face, so every pixel's primary ray crosses the cloud
SIDE_VIEW = wm.Camera.orthographic(center=(500.0, -1000.0, 1500.0), direction=(0.0, 1.0, 0.0), width=800, height=600)


def spec(seed=1, camera=SIDE_VIEW, sun=None, **kw) -> wm.SceneSpec:
    kw.setdefault("sky", wm.Sky("constant"))
    # a point sun: the pipeline is tested with both integrators (volpath has no sun disk)
    return wm.SceneSpec(camera=camera, sun=sun or wm.Sun(200.0, 40.0, angular_diameter_deg=0.0), width=W, height=H,
                        seed=seed, **kw)


def render(sp, vol, spp=16, passes=4, **kw) -> wm.Image:
    return wm.render_reference(sp, vol, spp=spp, passes=passes, progress=False, **kw)


@pytest.fixture(scope="module")
def vol():
    return cloud_volume()


@pytest.fixture
def no_rendering(monkeypatch):
    """Fail the test if a pass is rendered (every pass goes through ``passes.render_pass`` or
    ``passes.render_passes``)."""
    def forbidden(*args, **kwargs):
        pytest.fail("a pass was rendered although the input is invalid")
    monkeypatch.setattr(wm.reference.passes, "render_pass", forbidden)
    monkeypatch.setattr(wm.reference.passes, "render_passes", forbidden)
    monkeypatch.setattr(mi, "render", forbidden)


def one_pass_per_launch(monkeypatch):
    """Local passes one at a time, each through ``passes.render_pass`` (which tests intercept)."""
    monkeypatch.setattr(wm.reference.passes, "BATCH_SAMPLES", 0)


# ---------------------------------------------------------------- passes and standard error

def test_image_layout_and_standard_error_predicts_the_spread_between_seeds(vol):
    a = render(spec(seed=1), vol, spp=32, passes=16)
    b = render(spec(seed=2), vol, spp=32, passes=16)
    for img in (a, b):
        assert img.radiance.shape == (H, W, 3) and img.stderr.shape == (H, W, 3)
        assert img.radiance.dtype == np.float32 and img.stderr.dtype == np.float32
        assert np.all(np.isfinite(img.radiance)) and np.all(img.radiance >= 0)
        assert np.all(img.stderr > 0), "every pixel sees the cloud: its estimate must have a positive error"
        assert img.metadata["passes"] == 16 and img.metadata["spp"] == 32
    # independent check of the noise estimate: the difference of two independent renders has the
    # standard deviation sqrt(se_a^2 + se_b^2), so |z| <= 3 nearly always, and |z| is not much
    # smaller than 1 either (an overestimated error would pass the first check)
    z = np.abs(a.radiance.astype(np.float64) - b.radiance) / np.hypot(a.stderr, b.stderr)
    assert np.mean(z <= 3) > 0.95, f"only {np.mean(z <= 3):.3f} of pixel channels within 3 standard errors"
    assert 0.4 < np.median(z) < 1.3, f"median |a - b| / se = {np.median(z):.2f} (0.67 for exact errors)"
    # the error estimate is the one of the mean of the passes: about sqrt(2) larger with half the passes
    c = render(spec(seed=1), vol, spp=16, passes=8)
    ratio = float(np.median(c.stderr / a.stderr))
    assert 1.15 < ratio < 1.75, f"stderr(8 passes) / stderr(16 passes) = {ratio:.2f}, expected ~1.41"


def test_estimate_is_the_mean_of_the_passes_with_their_standard_error(vol, monkeypatch):
    """Record what every pass returns: the image is their mean, the error their sample standard
    deviation over sqrt(passes), the passes use distinct seeds and ``spp`` is split over them."""
    one_pass_per_launch(monkeypatch)
    real = wm.reference.passes.render_pass
    passes = []

    def recording(scene, spp, seed, **kwargs):
        out = real(scene, spp, seed, **kwargs)
        passes.append((seed, spp, np.array(out, np.float64)[..., :3]))
        return out
    monkeypatch.setattr(wm.reference.passes, "render_pass", recording)
    img = render(spec(seed=11), vol, spp=22, passes=5)
    seeds, spps, imgs = zip(*passes)
    assert len(set(seeds)) == 5 and sorted(spps, reverse=True) == [5, 5, 4, 4, 4]
    imgs = np.stack(imgs)
    np.testing.assert_allclose(img.radiance, imgs.mean(axis=0), rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(img.stderr, imgs.std(axis=0, ddof=1) / np.sqrt(5), rtol=1e-4, atol=1e-12)


def test_row_zero_is_the_top_of_the_picture():
    """Only the upper half of the cube holds cloud; no sky, no ground: the lower rows are black."""
    img = render(spec(sky=None, ground=None), cloud_volume(upper_half_only=True), spp=4, passes=2)
    lum = img.radiance.mean(axis=2)
    assert lum[: H // 2 - 2].min() > 0
    assert lum[H // 2 + 2:].max() == 0.0
    assert np.all(img.stderr[H // 2 + 2:] == 0)  # nothing random below the cloud


def test_single_pass_has_no_error_estimate(vol):
    img = render(spec(), vol, spp=4, passes=1)
    assert img.metadata["passes"] == 1
    assert np.all(np.isnan(img.stderr)) and np.all(np.isfinite(img.radiance))


# ---------------------------------------------------------------- determinism

@pytest.mark.parametrize("integrator", ["majorant", "volpath"])
def test_same_seed_bit_identical_different_seed_differs(vol, integrator):
    a = render(spec(seed=3), vol, integrator=integrator)
    b = render(spec(seed=3), vol, integrator=integrator)
    c = render(spec(seed=4), vol, integrator=integrator)
    assert np.array_equal(a.radiance, b.radiance) and np.array_equal(a.stderr, b.stderr)
    assert not np.array_equal(a.radiance, c.radiance)
    assert np.mean(a.radiance != c.radiance) > 0.9


# ---------------------------------------------------------------- checkpoint and resume

class Interrupted(Exception):
    pass


def _interrupt_after(monkeypatch, k):
    """Make the (k+1)-th pass raise, as if the process were killed during pass k+1."""
    one_pass_per_launch(monkeypatch)
    real = wm.reference.passes.render_pass
    calls = []

    def render_k(scene, spp, seed, **kwargs):
        if len(calls) == k:
            raise Interrupted
        calls.append(seed)
        return real(scene, spp, seed, **kwargs)
    monkeypatch.setattr(wm.reference.passes, "render_pass", render_k)
    return real


def _count_renders(monkeypatch, real):
    calls = []

    def counting(scene, spp, seed, **kwargs):
        calls.append(seed)
        return real(scene, spp, seed, **kwargs)
    monkeypatch.setattr(wm.reference.passes, "render_pass", counting)
    return calls


def test_interrupted_render_resumes_bit_for_bit(vol, tmp_path, monkeypatch):
    sp = spec(seed=5)
    full = render(sp, vol, spp=24, passes=6)
    ckpt = tmp_path / "sub" / "run.ckpt.npz"
    real = _interrupt_after(monkeypatch, 3)
    with pytest.raises(Interrupted):
        render(sp, vol, spp=24, passes=6, checkpoint=ckpt)
    state = np.load(ckpt)
    assert int(state["done"]) == 3 and state["mean"].shape == (H, W, 3)
    assert not list(ckpt.parent.glob("*.tmp*")), "temporary checkpoint files left behind"
    calls = _count_renders(monkeypatch, real)
    resumed = render(sp, vol, spp=24, passes=6, checkpoint=ckpt, resume=True)
    assert len(calls) == 3, f"the resumed render ran {len(calls)} passes instead of the 3 missing ones"
    assert np.array_equal(resumed.radiance, full.radiance)
    assert np.array_equal(resumed.stderr, full.stderr)
    assert resumed.metadata["passes"] == 6 and resumed.metadata["spp"] == 24
    assert int(np.load(ckpt)["done"]) == 6
    # resuming a finished checkpoint renders nothing and gives the same image
    calls.clear()
    again = render(sp, vol, spp=24, passes=6, resume=ckpt)
    assert calls == [] and np.array_equal(again.radiance, full.radiance)


# wider than the cube: its middle columns and rows see the cloud, the rest the sky beside and above it
WIDE_VIEW = wm.Camera.orthographic(center=(500.0, -1000.0, 1500.0), direction=(0.0, 1.0, 0.0), width=2000, height=1500)


def _recording(monkeypatch):
    """Record (scene, pixels asked for, image) of every pass."""
    one_pass_per_launch(monkeypatch)
    real = wm.reference.passes.render_pass
    passes = []

    def recording(scene, spp, seed, **kwargs):
        out = real(scene, spp, seed, **kwargs)
        passes.append((scene, kwargs.get("pixels"), np.array(out, np.float64)[..., :3]))
        return out
    monkeypatch.setattr(wm.reference.passes, "render_pass", recording)
    return real, passes


def test_render_to_a_target_adds_passes_over_the_cloud_pixels_only(vol, monkeypatch):
    """Past the planned passes a render to a target renders its cloud pixels only: there the estimate
    is the mean over every pass, elsewhere over the planned ones, each with its own standard error;
    a pass over some pixels gives them the values of the pass over all."""
    sp = spec(seed=2, camera=WIDE_VIEW)
    cloud = wm.reference.estimates.cloud_mask(sp, vol)
    assert 0.2 < cloud.mean() < 0.8
    monkeypatch.setattr(wm.reference.render, "MAX_TARGET_PASSES", 7)  # an unreachable target: 4 planned + 3 more
    real, passes = _recording(monkeypatch)
    img = render(sp, vol, spp=8, passes=4, target_rse=1e-6)
    scenes, pixels, imgs = zip(*passes)
    assert len(passes) == 7 and pixels[:4] == (None,) * 4
    for p in pixels[4:]:
        assert np.array_equal(p, np.flatnonzero(cloud.ravel()))
    imgs = np.stack(imgs)
    assert np.all(imgs[4:][:, ~cloud] == 0.0)  # the other pixels were not rendered
    np.testing.assert_allclose(img.radiance[cloud], imgs[:, cloud].mean(axis=0), rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(img.stderr[cloud], imgs[:, cloud].std(axis=0, ddof=1) / np.sqrt(7), rtol=1e-4, atol=1e-12)
    np.testing.assert_allclose(img.radiance[~cloud], imgs[:4, ~cloud].mean(axis=0), rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(img.stderr[~cloud], imgs[:4, ~cloud].std(axis=0, ddof=1) / 2, rtol=1e-4, atol=1e-12)
    m = img.metadata
    assert (m["passes"], m["spp"], m["spp_background"]) == (7, 14, 8)
    # the cloud pixels of a pass over them = those of the pass over every pixel (same seed)
    some = np.flatnonzero(cloud.ravel())[::3]
    whole = real(scenes[0], 2, 1234)
    part = real(scenes[0], 2, 1234, pixels=some)
    assert np.array_equal(part.reshape(-1, part.shape[-1])[some], whole.reshape(-1, whole.shape[-1])[some])
    assert np.all(np.delete(part.reshape(-1, part.shape[-1]), some, axis=0) == 0.0)
    with pytest.raises(ValueError, match="pixels"):
        real(scenes[0], 2, 1234, pixels=[W * H])


def test_render_to_a_target_over_every_pixel_averages_every_pass_everywhere(vol, monkeypatch):
    """``target_pixels="all"`` (the viewer's reference, issue 38: the sky seen through the air converges with the
    cloud): the passes past the planned ones render every pixel, so every pixel's estimate is the mean of all the
    passes and its standard error their spread; the stopping test still counts the cloud pixels only."""
    sp = spec(seed=2, camera=WIDE_VIEW)
    cloud = wm.reference.estimates.cloud_mask(sp, vol)
    monkeypatch.setattr(wm.reference.render, "MAX_TARGET_PASSES", 7)
    _, passes = _recording(monkeypatch)
    img = render(sp, vol, spp=8, passes=4, target_rse=1e-6, target_pixels="all")
    _, pixels, imgs = zip(*passes)
    assert len(passes) == 7 and pixels == (None,) * 7
    imgs = np.stack(imgs)
    assert np.all(imgs[4:][:, ~cloud].max(axis=0) > 0.0)  # the sky pixels were rendered in the added passes too
    np.testing.assert_allclose(img.radiance, imgs.mean(axis=0), rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(img.stderr, imgs.std(axis=0, ddof=1) / np.sqrt(7), rtol=1e-4, atol=1e-12)
    m = img.metadata
    assert (m["passes"], m["spp"], m["spp_background"], m["target_pixels"]) == (7, 14, 14, "all")
    st = wm.reference.estimates.noise_stats(img.radiance, img.stderr, cloud)
    assert m["noise"]["rse_mean"] == pytest.approx(st["rse_mean"])  # over the cloud pixels, as before
    with pytest.raises(ValueError, match="target_pixels must be one of"):
        render(sp, vol, spp=8, passes=4, target_rse=0.1, target_pixels="sky")


def test_render_to_a_target_resumes_bit_for_bit(vol, tmp_path, monkeypatch):
    """Interrupted among the passes over the cloud pixels, a render to a target resumes to the same image."""
    sp = spec(seed=8, camera=WIDE_VIEW)
    monkeypatch.setattr(wm.reference.render, "MAX_TARGET_PASSES", 6)
    full = render(sp, vol, spp=8, passes=4, target_rse=1e-6)
    ckpt = tmp_path / "t.npz"
    real = _interrupt_after(monkeypatch, 5)
    with pytest.raises(Interrupted):
        render(sp, vol, spp=8, passes=4, target_rse=1e-6, checkpoint=ckpt)
    calls = _count_renders(monkeypatch, real)
    resumed = render(sp, vol, spp=8, passes=4, target_rse=1e-6, checkpoint=ckpt, resume=True)
    assert len(calls) == 1
    assert np.array_equal(resumed.radiance, full.radiance) and np.array_equal(resumed.stderr, full.stderr, equal_nan=True)
    assert resumed.metadata["spp_background"] == 8 and resumed.metadata["spp"] == 12


def test_passes_rendered_together_equal_passes_rendered_one_by_one(vol, monkeypatch):
    """Local passes are rendered in shared launches (``render_passes``): the image is bit-identical to
    the one rendered a pass per launch, for planned passes and a render to a target alike."""
    sp = spec(seed=4, camera=WIDE_VIEW)
    monkeypatch.setattr(wm.reference.render, "MAX_TARGET_PASSES", 9)
    real, launches = wm.reference.passes.render_passes, []

    def counting(scene, passes, **kwargs):
        launches.append(len(passes))
        return real(scene, passes, **kwargs)
    monkeypatch.setattr(wm.reference.passes, "render_passes", counting)
    together = [render(sp, vol, spp=24, passes=6), render(sp, vol, spp=8, passes=4, target_rse=1e-6)]
    assert launches == [6, 4, 5]  # the planned passes in one launch, then the passes over the cloud pixels
    monkeypatch.setattr(wm.reference.passes, "BATCH_SAMPLES", 0)
    launches.clear()
    alone = [render(sp, vol, spp=24, passes=6), render(sp, vol, spp=8, passes=4, target_rse=1e-6)]
    assert launches == [1] * 15
    for a, b in zip(together, alone):
        assert np.array_equal(a.radiance, b.radiance) and np.array_equal(a.stderr, b.stderr)


def test_passes_run_at_the_path_tracing_simd_width_and_the_width_is_put_back(vol, monkeypatch):
    """Passes are rendered with packets of PATH_TRACING_VECTOR_WIDTH lanes (the scene built there too:
    Embree's packets follow the width) and the CPU's width is back afterwards; an image at the CPU's
    width estimates the same radiance."""
    from weather_mi.kernel import variant
    if not mi.variant().startswith("llvm") or variant.llvm_vector_width() is None:
        pytest.skip("an LLVM variant with Dr.Jit's target setters")
    before = variant.llvm_vector_width()
    one_pass_per_launch(monkeypatch)
    real, widths = wm.reference.passes.render_pass, []

    def spying(scene, spp, seed, **kwargs):
        widths.append(variant.llvm_vector_width())
        return real(scene, spp, seed, **kwargs)
    monkeypatch.setattr(wm.reference.passes, "render_pass", spying)
    narrow = render(spec(seed=12), vol, spp=256, passes=8)
    assert set(widths) == {variant.PATH_TRACING_VECTOR_WIDTH} and variant.llvm_vector_width() == before
    widths.clear()
    monkeypatch.setattr(variant, "PATH_TRACING_VECTOR_WIDTH", before)
    wide = render(spec(seed=12), vol, spp=256, passes=8)
    assert set(widths) == {before}
    diff = float(narrow.radiance.mean() - wide.radiance.mean())
    se = float(np.sqrt((narrow.stderr ** 2 + wide.stderr ** 2).sum()) / narrow.stderr.size)
    assert abs(diff) < 4 * se, f"{diff} vs se {se}"


def test_checkpoint_of_another_scene_is_refused(vol, tmp_path, monkeypatch):
    ckpt = tmp_path / "a.npz"
    render(spec(seed=6), vol, spp=8, passes=2, checkpoint=ckpt)
    before = ckpt.read_bytes()
    denser = wm.OpticalVolume.from_arrays(beta_ext=vol.beta_total * 1.01, albedo=0.99,
                                          phase=wm.phase.henyey_greenstein(0.85), bbox=BBOX)
    for name in ("render_pass", "render_passes"):
        monkeypatch.setattr(wm.reference.passes, name, lambda *a, **k: pytest.fail("rendered despite a foreign checkpoint"))
    others = [
        (spec(seed=6), denser, {}),                                  # another volume
        (spec(seed=6), cloud_volume(g=0.5), {}),                     # another phase function
        (spec(seed=7), vol, {}),                                     # another seed
        (spec(seed=6, sun=wm.Sun(100.0, 40.0)), vol, {}),            # another sun
        (spec(seed=6), vol, {"spp": 12, "passes": 3}),               # another sample plan
        (spec(seed=6), vol, {"integrator": "volpath"}),              # another integrator
        (spec(seed=6), vol, {"rr_depth": 100}),                      # another roulette
    ]
    for sp, v, kw in others:
        kw = {"spp": 8, "passes": 2, **kw}
        with pytest.raises(ValueError, match="different scene"):
            wm.render_reference(sp, v, checkpoint=ckpt, resume=True, progress=False, **kw)
    assert ckpt.read_bytes() == before


def test_transmittance_of_a_uniform_slab_is_beer_lambert():
    """render_transmittance through a uniform layer seen straight down: exp(-beta H) (closed form)."""
    beta, depth = 1.2e-3, 1000.0
    slab = wm.OpticalVolume.from_arrays(np.full((4, 4, 4), beta, np.float32), 0.9, wm.phase.henyey_greenstein(0.85),
                                        ((-5e4, -5e4, 0.0), (5e4, 5e4, depth)))
    cam = wm.Camera.orthographic(center=(0.0, 0.0, 3000.0), direction=(0, 0, -1), width=2000.0, height=2000.0)
    sp = wm.SceneSpec(camera=cam, sun=wm.Sun(0.0, 40.0), sky=wm.Sky("sunsky"), ground=wm.Ground(0.3, height=-10.0),
                      width=16, height=16)
    t = wm.render_transmittance(sp, slab, spp=64)
    expected = np.exp(-beta * depth)
    se = np.sqrt(expected * (1 - expected) / (64 * t.size))  # binary delta-tracking estimates
    assert abs(t.mean() - expected) < 4 * se


# ---------------------------------------------------------------- files

def test_exr_channels_values_and_metadata_round_trip(vol, tmp_path):
    import OpenEXR
    sp = spec(seed=8)
    img = render(sp, vol, spp=8, passes=4)
    path = img.save(tmp_path / "x.exr")
    assert path == tmp_path / "x.exr" and path.is_file()
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = f.channels()
        header = dict(f.header())  # a copy: OpenEXR.File empties its header dict when closed
        assert {"R", "G", "B", "stderr.R", "stderr.G", "stderr.B", "transmittance.Y"} <= set(ch)
        np.testing.assert_array_equal(np.asarray(ch["transmittance.Y"].pixels), img.transmittance)
        for i, c in enumerate("RGB"):
            px = np.asarray(ch[c].pixels)
            assert px.shape == (H, W) and px.dtype == np.float32
            np.testing.assert_array_equal(px, img.radiance[..., i])
            np.testing.assert_array_equal(np.asarray(ch[f"stderr.{c}"].pixels), img.stderr[..., i])
    meta = json.loads(header["weather_mi"])
    assert meta["spp"] == 8 and meta["passes"] == 4
    assert meta["scene"] == json.loads(json.dumps(sp.to_dict()))
    assert wm.SceneSpec.from_dict(meta["scene"]) == sp
    back = wm.Image.load(path)
    np.testing.assert_array_equal(back.radiance, img.radiance)
    np.testing.assert_array_equal(back.stderr, img.stderr)
    np.testing.assert_array_equal(back.transmittance, img.transmittance)
    assert back.metadata["seconds"] == img.metadata["seconds"]


def test_png_is_8_bit_rgb_of_the_image_size(vol, tmp_path):
    from PIL import Image as PILImage
    img = render(spec(seed=9), vol, spp=4, passes=2)
    path = img.save_png(tmp_path / "x.png")
    with PILImage.open(path) as p:
        assert p.format == "PNG" and p.mode == "RGB" and p.size == (W, H)
        a = np.asarray(p)
    assert a.dtype == np.uint8 and a.shape == (H, W, 3)
    assert a.max() > 128 and a.std() > 0  # auto exposure: a visible, non-uniform picture


def test_metadata_describes_the_render():
    q = np.zeros((6, 6, 6), np.float32)
    q[2:5, 1:5, 1:5] = 1e-3
    hyd = wm.from_arrays({"cloud": q}, rho_air=1.0, spacing=(200.0, 200.0, 200.0), origin=(1100.0, 100.0, 100.0),
                         source="test arrays")
    vol = wm.optical_volume(hyd, species="physical")
    sp = wm.SceneSpec(camera=wm.Camera.orbit(vol), sun=wm.Sun(angular_diameter_deg=0.0), sky=wm.Sky("constant"),
                      width=W, height=H, seed=2)
    img = render(sp, vol, spp=6, passes=3, integrator="volpath", max_depth=16)
    m = img.metadata
    assert m["spp"] == 6 and m["passes"] == 3 and m["max_depth"] == 16
    assert isinstance(m["seconds"], float) and m["seconds"] > 0
    assert m["scene"] == sp.to_dict()
    assert m["species_preset"] == "physical"
    assert m["source"] == "test arrays"
    assert m["integrator"] == "volpath" and m["variant"] == mi.variant() and m["renderer"] == "reference"
    assert m["normalize"] is None and m["sun"] == "scene emitter"
    assert img.radiance.max() > 0
    noise = m["noise"]  # the noise figures over cloud pixels, recomputed here from the image
    cloud = wm.reference.estimates.cloud_mask(sp, vol)
    lum, se = img.radiance.mean(axis=2), img.stderr.mean(axis=2)
    ok = cloud & (lum > 0)
    assert noise["cloud_pixels"] == ok.sum() > 0
    assert noise["rse_mean"] == pytest.approx(img.relative_stderr(mask=cloud), rel=1e-5)
    assert noise["worst_se_over_mean"] == pytest.approx(se[ok].max() / lum[ok].mean(), rel=1e-5)


# ---------------------------------------------------------------- bad input, before any rendering

def test_bad_scene_descriptions_are_refused():
    with pytest.raises(ValueError, match="inside the ground"):
        wm.SceneSpec(camera=wm.Camera(origin=(0.0, -5000.0, -10.0), target=(0.0, 0.0, 1000.0)))
    with pytest.raises(ValueError, match="inside the ground"):
        wm.SceneSpec(camera=wm.Camera(origin=(0.0, -5000.0, 100.0), target=(0.0, 0.0, 1000.0)),
                     ground=wm.Ground(height=200.0))
    for elevation in (0.0, -5.0):
        with pytest.raises(ValueError, match="above the horizon"):
            wm.Sun(180.0, elevation)
    with pytest.raises(wm.WeatherDataError, match="finite"):
        wm.OpticalVolume.from_arrays(np.full((4, 4, 4), np.nan, np.float32), 1.0, wm.phase.henyey_greenstein(0.85), BBOX)
    q = np.full((4, 4, 4), 1e-4, np.float32)
    q[1, 2, 3] = np.nan
    with pytest.raises(wm.WeatherDataError):
        wm.optical_volume(wm.from_arrays({"cloud": q}, rho_air=1.0, spacing=(100.0, 100.0, 100.0)))


@pytest.mark.parametrize("case", ["variant", "spp0", "spp_negative", "spp_float", "integrator", "normalize",
                                  "nan_extinction", "nan_albedo", "inf_weights", "negative_extinction"])
def test_bad_render_arguments_raise_before_rendering(vol, case, no_rendering, tmp_path):
    import dataclasses
    kw = {"spp": 4, "progress": False}
    v = vol
    expected = ValueError
    if case == "variant":
        kw["variant"] = "no_such_variant_rgb"
    elif case == "spp0":
        kw["spp"] = 0
    elif case == "spp_negative":
        kw["spp"] = -3
    elif case == "spp_float":
        kw["spp"] = 2.5
    elif case == "integrator":
        kw["integrator"] = "path"
    elif case == "normalize":
        kw["normalize"] = "albedo"
    else:
        expected = wm.WeatherDataError
        name, value = {"nan_extinction": ("beta_total", np.nan), "nan_albedo": ("albedo", np.nan),
                       "inf_weights": ("weights", np.inf), "negative_extinction": ("beta_total", -1e-3)}[case]
        a = getattr(vol, name).copy()
        a.flat[7] = value  # OpticalVolume.from_arrays refuses such data: corrupt a valid volume afterwards
        v = dataclasses.replace(vol, **{name: a})
    ckpt = tmp_path / "c.npz"
    with pytest.raises(expected):
        wm.render_reference(spec(), v, checkpoint=ckpt, **kw)
    assert not ckpt.exists()


# ---------------------------------------------------------------- reflectance

def test_reflectance_is_pi_radiance_over_mu0_irradiance(vol):
    sun = wm.Sun(210.0, 30.0, irradiance=(2.0, 1.0, 0.5))
    sp = spec(seed=10, sun=sun)
    rad = render(sp, vol, spp=8, passes=4)
    refl = render(sp, vol, spp=8, passes=4, normalize="reflectance")
    factor = np.pi / (0.5 * np.array([2.0, 1.0, 0.5]))  # mu0 = sin(30 deg)
    np.testing.assert_allclose(refl.radiance, rad.radiance * factor, rtol=2e-6, atol=1e-12)
    np.testing.assert_allclose(refl.stderr, rad.stderr * factor, rtol=2e-5, atol=1e-12)
    assert refl.metadata["normalize"] == "reflectance" and rad.metadata["normalize"] is None
    assert 0.05 < float(np.median(refl.radiance)) < 1.5  # a bright cloud reads as a reflectance of order 1


# ---------------------------------------------------------------- command line

def test_cli_render_demo_writes_exr_and_png(tmp_path, capsys):
    from PIL import Image as PILImage
    out = tmp_path / "c.exr"
    rc = cli.main(["render", "--demo", "supercell", "--size", f"{W}x{H}", "--spp", "4", "--seed", "3", "-o", str(out)])
    assert rc == 0
    assert out.is_file() and (tmp_path / "c.png").is_file()
    assert not (tmp_path / "c.exr.ckpt.npz").exists(), "the checkpoint of a finished render is removed"
    img = wm.Image.load(out)
    assert img.radiance.shape == (H, W, 3) and img.radiance.max() > 0
    assert np.all(np.isfinite(img.stderr))
    m = img.metadata
    assert m["spp"] == 4 and m["species_preset"] == "physical" and m["scene"]["seed"] == 3
    assert (m["scene"]["width"], m["scene"]["height"]) == (W, H)
    with PILImage.open(tmp_path / "c.png") as p:
        assert p.size == (W, H) and p.mode == "RGB"
    assert str(out) in capsys.readouterr().out


@pytest.mark.parametrize("name", ["missing_wrfout.nc", "missing_les.txt"])
def test_cli_missing_input_is_a_clean_error(tmp_path, capsys, name, no_rendering):
    missing = tmp_path / name
    out = tmp_path / "x.exr"
    try:
        rc = cli.main(["render", str(missing), "--size", "8x8", "--spp", "1", "-o", str(out)])
    except SystemExit as exc:
        rc = exc.code
    assert rc not in (0, None)
    err = capsys.readouterr().err
    assert str(missing) in err
    assert "Traceback" not in err
    assert not out.exists()


def test_reference_renders_in_another_variant_of_the_same_process():
    """The plugins are made per variant: majorant_volpath on llvm, then stock volpath with the
    mixture phase on scalar_rgb, then majorant_volpath on llvm again, in one process (a subprocess:
    the variant is global); the two llvm images of one seed are identical, and the scalar image
    agrees with them within noise. majorant_volpath itself refuses scalar variants."""
    import subprocess
    import sys
    script = """
import numpy as np, weather_mi as wm
beta = np.full((4, 4, 4), 0.01, np.float32)
vol = wm.OpticalVolume.from_arrays(beta_ext=beta, albedo=0.99, phase=wm.phase.henyey_greenstein(0.85),
                                   bbox=((0.0, 0.0, 1000.0), (1000.0, 1000.0, 2000.0)))
cam = wm.Camera.orthographic(center=(500.0, -1000.0, 1500.0), direction=(0.0, 1.0, 0.0), width=800, height=600)
spec = wm.SceneSpec(camera=cam, sun=wm.Sun(200.0, 40.0, angular_diameter_deg=0.0), sky=wm.Sky("constant"), width=4,
                    height=3, seed=1)
for variant, integrator in (("llvm_ad_rgb", "majorant"), ("scalar_rgb", "volpath"), ("llvm_ad_rgb", "majorant")):
    img = wm.render_reference(spec, vol, spp=64, passes=4, max_depth=4, progress=False, variant=variant,
                              integrator=integrator, rr_depth=100)
    print(variant, float(np.mean(img.radiance)), float(np.sum(img.radiance)),
          float(np.sqrt(np.sum(img.stderr ** 2)) / img.stderr.size))
"""
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-3000:]
    rows = [line.split() for line in out.stdout.strip().splitlines()]
    assert [r[0] for r in rows] == ["llvm_ad_rgb", "scalar_rgb", "llvm_ad_rgb"]
    means = [float(r[1]) for r in rows]
    se = [float(r[3]) for r in rows]
    assert all(m > 0 for m in means)
    assert rows[0][2] == rows[2][2]
    assert abs(means[1] - means[0]) < 4 * np.hypot(se[0], se[1]), (means, se)
    with pytest.raises(ValueError, match="JIT variants"):
        wm.render_reference(spec(), cloud_volume(), spp=1, variant="scalar_rgb", integrator="majorant")


def test_a_volume_without_its_species_extinction_renders_the_same_image():
    """The command line's ``optical_volume(keep=("weights",))``: the per-species extinction released after the
    optics (the path tracer reads beta_total, the albedo and the Eq. 8 weights only, the forward peak's delta
    scaling included) renders the same image, bit for bit, as the whole volume; reading it raises, naming it."""
    hyd = wm.synthetic.cumulus()
    whole = wm.optical_volume(hyd, phase_quality="test")
    lean = wm.optical_volume(hyd, phase_quality="test", keep=("weights",))
    assert lean.beta_ext.shape == whole.beta_ext.shape
    with pytest.raises(wm.WeatherDataError, match="beta_ext"):
        np.asarray(lean.beta_ext)
    with pytest.raises(wm.WeatherDataError, match="beta_ext"):
        lean.beta_ext.sum()
    import pickle  # to Dask workers and back: still released, its shape kept
    assert pickle.loads(pickle.dumps(lean)).beta_ext.shape == whole.beta_ext.shape
    (x0, y0, _), (x1, y1, z1) = whole.bbox
    cam = wm.Camera.orthographic(center=((x0 + x1) / 2, (y0 + y1) / 2, z1 + 1000.0), direction=(0.0, 0.0, -1.0),
                                 width=x1 - x0, height=y1 - y0)
    sp = spec(camera=cam, sun=wm.Sun(200.0, 40.0))
    a, b = render(sp, whole, spp=4, passes=2), render(sp, lean, spp=4, passes=2)
    assert np.array_equal(a.radiance, b.radiance) and np.array_equal(a.stderr, b.stderr)
    assert a.radiance.max() > 0
