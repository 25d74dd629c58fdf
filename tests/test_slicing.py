"""Half-angle slicing against closed forms: background, Beer-Lambert light buffer, single scattering;
mode behaviour; no recompilation between frames."""
import math

import drjit as dr
import numpy as np
import pytest

import weather_mi as wm
from weather_mi.slicing import SliceMode, SliceParams, SliceRenderer, render_slices
from conftest import kernels_compiled


def hg_table(g):
    theta = np.unique(np.r_[np.geomspace(1e-4, 0.3, 300), np.linspace(0.0, np.pi, 1500)])
    mu = np.cos(theta)
    p = (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * mu) ** 1.5)
    return wm.phase.PhaseTable.from_values(theta, p)


def slab(beta=1e-3, albedo=1.0, g=0.0, size=(8, 8, 8), bbox=((-20e3, -20e3, 1000.0), (20e3, 20e3, 2000.0))):
    arr = np.full(size, beta, np.float32)
    return wm.OpticalVolume.from_arrays(arr, albedo, hg_table(g), bbox)


def down_camera(w=8, h=8, z=5000.0, half=2000.0):
    return wm.Camera.orthographic(center=(0.0, 0.0, z), direction=(0, 0, -1), width=2 * half, height=2 * half)


def test_empty_volume_returns_exactly_the_background():
    vol = slab(beta=0.0)
    for sky, ground in ((wm.Sky("constant", radiance=(0.1, 0.2, 0.3)), None),
                        (None, wm.Ground(albedo=0.5, height=0.0)),
                        (wm.Sky("constant", radiance=(0.1, 0.2, 0.3)), wm.Ground(albedo=(0.2, 0.4, 0.6), height=0.0))):
        spec = wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=30, elevation=20), sun=wm.Sun(120, 40, (1.0, 2.0, 3.0)),
                            sky=sky, ground=ground, width=24, height=16)
        img = render_slices(spec, vol, SliceMode("uniform", "translucent"), slices=16, light_res=16)
        from weather_mi.scene.spec import ground_hits
        from weather_mi.slicing.geometry import camera_rays
        o, d = camera_rays(spec)
        hit = np.isfinite(ground_hits(spec, o, d))
        sky_l = np.asarray(sky.radiance) if sky is not None else np.zeros(3)
        expected = np.broadcast_to(sky_l, img.radiance.shape).copy()
        if ground is not None:
            # Lambertian ground: rho / pi (E mu0 + pi L_sky), closed form for a constant sky
            e = np.asarray(spec.sun.irradiance) * math.sin(math.radians(40)) + np.pi * sky_l
            expected[hit] = np.asarray(ground.albedo) / np.pi * e
        np.testing.assert_allclose(img.radiance, expected, rtol=1e-5, atol=1e-7)


@pytest.mark.parametrize("camera_dir", [(0.0, 0.0, -1.0), (0.3, 0.2, 1.0)], ids=["front-lit", "back-lit"])
def test_light_buffer_beer_lambert(camera_dir):
    # a layer between 1000 and 2000 m (upper half of a 0-2000 m grid; trilinear interpolation makes a
    # ramp symmetric about 1000 m, so the vertical optical depth is exactly tau) and clear air below
    tau = 1.2
    beta = np.zeros((8, 8, 8), np.float32)
    beta[4:] = tau / 1000.0
    vol = wm.OpticalVolume.from_arrays(beta, 0.0, hg_table(0.0), ((-8e3, -8e3, 0.0), (8e3, 8e3, 2000.0)))
    sun = wm.Sun(azimuth=60, elevation=50)
    cam = wm.Camera.orthographic(center=(0, 0, 1000.0 - 4000 * camera_dir[2]), direction=camera_dir, width=4000,
                                 height=4000)
    spec = wm.SceneSpec(camera=cam, sun=sun, sky=None, ground=None, width=8, height=8)
    r = SliceRenderer(vol, SliceMode("uniform", "low_albedo"), slices=160, light_res=64)
    r.frame(spec)
    view_dot_light = float(np.dot(cam.forward, sun.to_sun))
    assert (view_dot_light > 0) == (camera_dir[2] > 0)  # both slicing orders are exercised
    below = np.array([[0.0, 0.0, 300.0], [500.0, -400.0, 600.0], [-900.0, 700.0, 100.0]])
    direct, indirect = r.light_at(below)
    np.testing.assert_allclose(direct, np.exp(-tau / sun.mu0), rtol=0.01)
    assert np.all(indirect == 0)
    above = np.array([[0.0, 0.0, 2500.0], [3000.0, 3000.0, 2600.0]])
    np.testing.assert_allclose(r.light_at(above)[0], 1.0, rtol=1e-3)


def test_thin_slab_single_scattering_closed_form():
    # L = omega P(Theta) E mu0 / (mu0 + mu) [1 - exp(-tau (1/mu0 + 1/mu))], nadir view (mu = 1)
    tau, g = 0.05, 0.5
    vol = slab(beta=tau / 1000.0, albedo=1.0, g=g)
    sun = wm.Sun(azimuth=0, elevation=40, irradiance=(2.0, 2.0, 2.0))
    spec = wm.SceneSpec(camera=down_camera(), sun=sun, sky=None, ground=None, width=8, height=8)
    img = render_slices(spec, vol, SliceMode("uniform", "low_albedo"), slices=128, light_res=32)
    mu0, mu = sun.mu0, 1.0
    cos_theta = -mu0  # light travels down, scattered up to the camera: l . d with d = (0, 0, -1)
    p = (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * cos_theta) ** 1.5)
    expected = 2.0 * p * mu0 / (mu0 + mu) * (1 - np.exp(-tau * (1 / mu0 + 1 / mu)))
    np.testing.assert_allclose(img.radiance, expected, rtol=0.02)


def species_volume(ice_only_east=True):
    """Cloud water in the west half, ice in the east half, a thick core."""
    q_cloud = np.zeros((8, 12, 16))
    q_ice = np.zeros((8, 12, 16))
    q_cloud[2:6, 3:9, 1:7] = 1e-3
    q_ice[2:6, 3:9, 9:15] = 1e-4
    hyd = wm.from_arrays({"cloud": q_cloud, "ice": q_ice}, 1.0, (500.0, 500.0, 500.0), origin=(250.0, 250.0, 250.0))
    return wm.optical_volume(hyd, species="physical", phase_tables=[hg_table(g) for g in (0.85, 0.3, 0.85, 0.75, 0.8)])


def test_translucent_brighter_than_low_albedo_and_species_phase_matters():
    vol = species_volume()
    spec = wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=180, elevation=15), sun=wm.Sun(200, 30),
                        sky=None, ground=None, width=48, height=32)
    low = render_slices(spec, vol, SliceMode("per_species", "low_albedo"), slices=64, light_res=48)
    tra = render_slices(spec, vol, SliceMode("per_species", "translucent"), slices=64, light_res=48)
    cloudy = low.radiance.mean(axis=2) > 0
    assert cloudy.sum() > 20
    assert tra.radiance[cloudy].mean() > 1.2 * low.radiance[cloudy].mean()
    uni = render_slices(spec, vol, SliceMode("uniform", "translucent"), slices=64, light_res=48)
    # columns on the ice side (east: right half of the picture seen from the south) differ,
    # columns on the cloud-water side (west) agree
    diff = np.abs(uni.radiance - tra.radiance).mean(axis=2)
    assert diff[:, 30:].max() > 10 * max(diff[:, :16].max(), 1e-12)


def test_species_colours_paint_by_species():
    vol = species_volume()
    spec = wm.SceneSpec(camera=down_camera(16, 16, z=9000.0, half=4000.0), sun=wm.Sun(200, 60), sky=None, ground=None,
                        width=16, height=16)
    spec = wm.SceneSpec(camera=wm.Camera.orthographic(center=(4000, 3000, 9000), width=8000, height=6000),
                        sun=wm.Sun(200, 60), sky=None, ground=None, width=32, height=24)
    img = render_slices(spec, vol, SliceMode("per_species", "translucent", species_colors=True), slices=32, light_res=32)
    west, east = img.radiance[:, :14].reshape(-1, 3), img.radiance[:, 18:].reshape(-1, 3)
    west, east = west[west.sum(1) > 0], east[east.sum(1) > 0]
    assert np.all(west[:, 1:] < 1e-6 * west[:, :1] + 1e-12)       # cloud water: red
    assert np.all(east[:, 1] < 1e-6 * east[:, 0] + 1e-12) and np.allclose(east[:, 0], east[:, 2])  # ice: magenta


@pytest.mark.parametrize("light", ["translucent", "multiple"])
def test_no_recompilation_when_sliders_move(light):
    vol = species_volume()
    spec = wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=180, elevation=15), sun=wm.Sun(200, 30),
                        sky=wm.Sky("sunsky"), ground=wm.Ground(0.2), width=32, height=24)
    r = SliceRenderer(vol, SliceMode("per_species", light), slices=32, light_res=32)
    r.frame(spec)
    r.frame(spec, SliceParams(scale={"ice": 1.5}))  # warm-up of every code path
    with kernels_compiled() as compiled:
        changes = [SliceParams(scale={"ice": 2.0, "cloud": 0.5}), SliceParams(albedo=0.9),
                   SliceParams(cone_angle_deg=5.0), SliceParams(forward_fraction=0.9), SliceParams(ambient=0.5),
                   SliceParams(ms_extinction=0.4, ms_contribution=0.3, ms_eccentricity=0.2, sky_gain=2.0, sky_extinction=0.1)]
        for i, params in enumerate(changes):
            camera = wm.Camera.orbit(vol, azimuth=180 + 7 * i, elevation=15)  # an orbiting camera
            moved = wm.SceneSpec(camera=camera, sun=wm.Sun(200 + 10 * i, 30 + 5 * i), sky=spec.sky,
                                 ground=spec.ground, width=32, height=24)
            r.frame(moved, params)
    assert compiled == [], f"{len(compiled)} kernels compiled after the first frame"


def test_frame_is_differentiable():
    """Reverse-mode gradient of the mean radiance w.r.t. the forward fraction and the cone angle
    through the whole frame (light and eye passes) against central finite differences."""
    import mitsuba as mi
    vol = species_volume()
    spec = wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=150, elevation=20), sun=wm.Sun(330, 25),
                        sky=None, ground=None, width=24, height=16)
    r = SliceRenderer(vol, SliceMode("per_species", "translucent"), slices=24, light_res=24, differentiable=True)

    def mean_radiance(ff, cone):
        out, _ = r.frame(spec, SliceParams(forward_fraction=ff, cone_angle_deg=cone), return_arrays=True)
        return dr.mean(out[0] + out[1] + out[2])

    for name, x0, other in (("forward_fraction", 0.5, 10.0), ("cone", 10.0, 0.5)):
        x = mi.Float(x0)
        dr.enable_grad(x)
        y = mean_radiance(x, other) if name == "forward_fraction" else mean_radiance(other, x)
        dr.backward(y)
        grad = float(dr.grad(x)[0])
        h = 0.02 if name == "forward_fraction" else 1.0
        f = (lambda v: float(mean_radiance(v, other)[0])) if name == "forward_fraction" else \
            (lambda v: float(mean_radiance(other, v)[0]))
        fd = (f(x0 + h) - f(x0 - h)) / (2 * h)
        assert abs(fd) > 0
        assert grad == pytest.approx(fd, rel=0.05), name


def blob_volume():
    """An asymmetric, optically thick blob (a tall lobe and a wide lobe) with sharp edges, 3 km across."""
    z, y, x = np.meshgrid(*(np.linspace(-1, 1, n) for n in (20, 24, 28)), indexing="ij")
    tall = ((x + 0.3) / 0.35) ** 2 + (y / 0.4) ** 2 + ((z - 0.1) / 0.8) ** 2
    wide = ((x - 0.35) / 0.45) ** 2 + ((y - 0.1) / 0.45) ** 2 + ((z + 0.35) / 0.3) ** 2
    beta = np.where(np.minimum(tall, wide) < 1.0, 0.05, 0.0).astype(np.float32)  # 1/m: tau ~ 50 across
    return wm.OpticalVolume.from_arrays(beta, 0.9, hg_table(0.85), ((-1500.0, -1500.0, 1000.0), (1500.0, 1500.0, 3000.0)))


@pytest.mark.parametrize("sun_azimuth", [180.0, 0.0], ids=["front-lit", "back-lit"])
def test_silhouette_matches_the_path_tracer(sun_azimuth):
    """Pixels where the reference's eye-ray transmittance is below 0.5 (``wm.render_transmittance``: the
    path tracer on the volume made purely absorbing, against a sky of radiance 1) overlap the slicer's
    with IoU >= 0.98, with the camera south of the cloud and the sun behind it (front-lit) or in
    front of it (back-lit, looking towards the sun). A one-pixel shift gives IoU 0.89."""
    vol = blob_volume()
    cam = wm.Camera.orbit(vol, azimuth=180, elevation=10, fov=40)
    spec = wm.SceneSpec(camera=cam, sun=wm.Sun(sun_azimuth, 25), sky=None, ground=None, width=48, height=36)
    r = SliceRenderer(vol, SliceMode("uniform", "translucent"), slices=96, light_res=48)
    r.frame(spec)
    assert (float(np.dot(cam.forward, spec.sun.to_sun)) > 0) == (sun_azimuth == 0.0)  # both slicing orders
    t_ref = wm.render_transmittance(spec, vol, spp=64, integrator="volpath")
    ref_cloud, approx_cloud = t_ref < 0.5, r.transmittance < 0.5
    assert 150 < ref_cloud.sum() < 0.8 * ref_cloud.size  # the blob fills part of the picture
    iou = (ref_cloud & approx_cloud).sum() / (ref_cloud | approx_cloud).sum()
    assert iou >= 0.98, f"silhouette IoU {iou:.3f}"


@pytest.mark.parametrize("slices", [24, 160])
def test_forward_light_through_a_thick_layer_is_exact_for_any_slice_count(slices):
    """Below a homogeneous layer of optical depth tau (vertical sun) the translucent light volume holds
    D = exp(-tau) and D + I = exp(-(1 - omega f) tau), whatever the slice count: the per-slab update
    is exact (a survival factor omega f per slice would compound with the number of slices)."""
    tau, f, omega = 6.0, 0.6, 1.0
    beta = np.zeros((8, 8, 8), np.float32)
    beta[4:] = tau / 1000.0
    vol = wm.OpticalVolume.from_arrays(beta, omega, hg_table(0.0), ((-8e3, -8e3, 0.0), (8e3, 8e3, 2000.0)))
    sun = wm.Sun(azimuth=0, elevation=90)
    cam = wm.Camera.orthographic(center=(0, 0, 5000.0), direction=(0.3, 0.0, -1.0), width=4000, height=4000)
    spec = wm.SceneSpec(camera=cam, sun=sun, sky=None, ground=None, width=8, height=8)
    r = SliceRenderer(vol, SliceMode("uniform", "translucent"), slices=slices, light_res=16)
    r.frame(spec, SliceParams(forward_fraction=f))
    direct, indirect = r.light_at(np.array([[0.0, 0.0, 300.0], [1000.0, -2000.0, 500.0]]))
    np.testing.assert_allclose(direct, np.exp(-tau), rtol=0.02)
    np.testing.assert_allclose(direct + indirect, np.exp(-(1 - omega * f) * tau), rtol=0.02)


def test_uniform_modes_read_extinction_alone_where_albedos_agree(monkeypatch):
    """One phase function and albedos within UNIFORM_ALBEDO_SPREAD (the five physical species at 550 nm
    agree within 1e-4): the light pass reads beta alone, with beta_f = f omega_bar beta, and the eye pass
    too, with beta_sca = omega_bar beta; light and image agree with the passes that read (beta, beta_f)
    and (beta, beta_sca) per voxel to the albedos' spread. A wider spread keeps the channels, and so do
    per-species phase functions."""
    from weather_mi.slicing import renderer as renderer_module
    vol = wm.optical_volume(wm.synthetic.supercell(shape=(20, 40, 40), spacing_m=(1000.0, 2000.0, 2000.0)),
                            species="physical")
    spec = wm.scene.spec.default_spec(vol, 16, 12)
    points = np.stack(np.meshgrid(np.linspace(-30e3, 30e3, 7), np.linspace(-30e3, 30e3, 7),
                                  np.linspace(1e3, 14e3, 6)), axis=-1).reshape(-1, 3)
    light, image = {}, {}
    for spread in (renderer_module.UNIFORM_ALBEDO_SPREAD, 1e-6):
        monkeypatch.setattr(renderer_module, "UNIFORM_ALBEDO_SPREAD", spread)
        r = SliceRenderer(vol, SliceMode("uniform", "translucent"), slices=32, light_res=32)
        channels = (r.light_channels, r.tex_eye.channels + 1)  # (the eye pass reads beta from the light's source)
        assert channels == ((1, 1) if spread > 1e-5 else (2, 2))
        image[channels] = r.frame(spec, SliceParams(forward_fraction=0.6)).radiance
        light[channels] = np.stack(r.light_at(points))
    one, two = light[(1, 1)], light[(2, 2)]
    assert (two[1] > 0.01).sum() >= 10 and (two[0] < 0.5).sum() >= 10  # points in and below the storm
    lit = two > 1e-3
    np.testing.assert_allclose(one[lit], two[lit], rtol=1e-3)
    cloud = r.transmittance < 0.9
    assert cloud.sum() >= 10
    np.testing.assert_allclose(image[(1, 1)][cloud], image[(2, 2)][cloud], rtol=1e-3)
    r = SliceRenderer(vol, SliceMode("per_species", "translucent"), slices=8, light_res=8)
    assert r.light_channels == 2 and r.tex_eye.channels > 1


def test_blur_weights_have_the_requested_variance():
    """The taps sum to 1, are >= 0, have the variance asked for and, above 1/3 texels^2 per fold, a
    Gaussian's fourth moment 3 var^2; beyond MAX_TEXEL_VARIANCE they clamp."""
    from weather_mi.slicing.blur import BLUR_FOLDS, MAX_TEXEL_VARIANCE, blur_weights
    for v in (0.0, 0.01, 0.2, 1 / 3, 0.7, 1.2, 2.0, MAX_TEXEL_VARIANCE, MAX_TEXEL_VARIANCE + 1.0):
        c = [float(x) for x in blur_weights(np, np.float64(v))]
        assert len(c) == 2 * BLUR_FOLDS + 1
        offsets = np.arange(1 - len(c), len(c))
        w = np.array([c[abs(o)] for o in offsets])
        assert w.min() >= 0 and w.sum() == pytest.approx(1.0)
        assert (w * offsets ** 2).sum() == pytest.approx(min(v, MAX_TEXEL_VARIANCE), abs=1e-12)
        if 1 / 3 <= v / BLUR_FOLDS and v <= MAX_TEXEL_VARIANCE:
            assert (w * offsets ** 4).sum() == pytest.approx(3 * v * v, rel=1e-12)


def test_translucent_image_converges_in_the_slice_count():
    """A thick, forward-scattering cloud in the paper's translucent mode: doubling the slices from 64
    to 128 changes the image by little (CIEDE2000 <= 1 over cloud pixels, mean radiance within 3%),
    which fails with a blur radius and a survival factor per slice (the image then darkens with every
    doubling)."""
    from weather_mi.display import metrics
    from weather_mi.io.image import auto_exposure
    vol = blob_volume()
    spec = wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=180, elevation=10, fov=40), sun=wm.Sun(150, 30),
                        sky=None, ground=None, width=40, height=30)
    imgs = {}
    for n in (64, 128):
        r = SliceRenderer(vol, SliceMode("uniform", "translucent"), slices=n, light_res=48)
        imgs[n] = r.frame(spec, SliceParams(forward_fraction=0.9)).radiance
    mask = metrics.cloud_mask(r.transmittance)
    assert mask.sum() > 100
    m = metrics.compare(imgs[128], imgs[64], exposure=auto_exposure(imgs[128]), mask=mask)
    assert m["ciede2000"] <= 1.0, m["ciede2000"]
    assert imgs[64][mask].mean() == pytest.approx(imgs[128][mask].mean(), rel=0.03)


def test_view_cache_is_bounded_for_an_orbiting_camera():
    vol = species_volume()
    r = SliceRenderer(vol, SliceMode("uniform", "low_albedo"), slices=8, light_res=8)
    for az in range(0, 360, 30):
        r.frame(wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=az, elevation=15), sun=wm.Sun(200, 30),
                             sky=wm.Sky("sunsky"), ground=wm.Ground(0.2), width=16, height=12))
    assert len(r.views.rays) <= r.views.rays.maxsize and len(r.views.backgrounds) <= r.views.backgrounds.maxsize
    assert len(r.views.sky) <= r.views.sky.maxsize


def test_multiple_light_model_reduces_to_single_scattering_and_adds_light():
    """With no octave beyond the first and no skylight the "multiple" model is the low-albedo image
    (single scattering of the direct beam; within 10% per pixel and 2% on average, the interpolation between
    slice planes differing); its octaves and skylight only add light. (No ground: under
    the "multiple" model it is lit by the column's diffuse transmission, tests/test_slicing_ground.py.)"""
    vol = blob_volume()
    spec = wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=180, elevation=10, fov=40), sun=wm.Sun(170, 30),
                        sky=wm.Sky("sunsky"), ground=None, width=32, height=24)
    low = render_slices(spec, vol, SliceMode("per_species", "low_albedo"), slices=48, light_res=32)
    single = render_slices(spec, vol, SliceMode("per_species", "multiple"), slices=48, light_res=32,
                           forward_peak_deg=0.0, ms_contribution=0.0, diffusion_gain=0.0, sky_gain=0.0)
    # the same up to how the light is interpolated between slice planes (the "multiple" model interpolates
    # optical depths, the paper's modes the light: test_optical_depth_is_interpolated_between_slice_planes)
    lit = low.radiance.mean(axis=2) > 0.05 * low.radiance.max()
    np.testing.assert_allclose(single.radiance[lit], low.radiance[lit], rtol=0.1)
    assert single.radiance[lit].mean() == pytest.approx(low.radiance[lit].mean(), rel=0.02)
    full = render_slices(spec, vol, SliceMode("per_species", "multiple"), slices=48, light_res=32)
    assert np.all(full.radiance >= single.radiance - 1e-7)
    cloud = low.radiance.mean(axis=2) > 0
    assert full.radiance[cloud].mean() > 1.5 * single.radiance[cloud].mean()


def test_light_outside_the_light_buffer_is_the_unattenuated_sun():
    """Points whose sun ray misses the volume's box (beside it, below it) get the full sun, not the
    light of the buffer's edge texels."""
    vol = blob_volume()
    spec = wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=180, elevation=10, fov=40), sun=wm.Sun(200, 30),
                        sky=None, ground=wm.Ground(0.2, height=0.0), width=16, height=12)
    r = SliceRenderer(vol, SliceMode("uniform", "translucent"), slices=32, light_res=16)
    r.frame(spec)
    far = np.array([[40e3, 0.0, 0.0], [-30e3, 25e3, 10.0], [0.0, -50e3, 500.0]])
    direct, indirect = r.light_at(far)
    np.testing.assert_array_equal(direct, 1.0)
    np.testing.assert_array_equal(indirect, 0.0)
    lobe = np.array([-450.0, 0.0, 2100.0])                       # centre of the blob's tall lobe
    shadow = (lobe - 2400.0 * np.asarray(spec.sun.to_sun))[None]  # below it, its sun ray through the lobe
    assert r.light_at(shadow)[0][0] < 0.1


def peaked_table(peak=0.4, width_deg=0.5):
    """A phase table that is a Gaussian lobe of ``width_deg`` holding ``peak`` of the scattered energy
    plus an isotropic rest: its forward peak within 3 degrees is ``peak`` by construction."""
    theta = np.unique(np.r_[np.linspace(0.0, np.radians(5.0), 400), np.linspace(0.0, np.pi, 1500)])
    lobe = np.exp(-0.5 * (theta / np.radians(width_deg)) ** 2)
    lobe /= np.trapezoid(lobe * 2 * np.pi * np.sin(theta), theta)
    return wm.phase.PhaseTable.from_values(theta, peak * lobe + (1 - peak) / (4 * np.pi))


def test_the_multiple_model_counts_forward_peaks_as_unscattered_light():
    """As the path-traced reference does (delta-M, weather_mi.optics.forward_peak): a conservative slab whose
    phase function puts 40% of its light in a 0.5 degree lobe is seen, and shades, with the optical depth
    (1 - 0.4) tau; the paper's modes keep the full tau; and a thin slab's single scattering outside the
    peak is unchanged (omega' p' tau' = omega p tau)."""
    tau = 1.5
    beta = np.zeros((8, 8, 8), np.float32)
    beta[4:] = tau / 1000.0                      # a layer of vertical optical depth tau (see the Beer-Lambert test)
    vol = wm.OpticalVolume.from_arrays(beta, 1.0, peaked_table(0.4), ((-8e3, -8e3, 0.0), (8e3, 8e3, 2000.0)))
    sun = wm.Sun(azimuth=60, elevation=50)
    spec = wm.SceneSpec(camera=down_camera(z=2500.0), sun=sun, sky=None, ground=None, width=8, height=8)
    multiple = SliceRenderer(vol, SliceMode("per_species", "multiple"), slices=160, light_res=64)
    multiple.frame(spec)
    paper = SliceRenderer(vol, SliceMode("per_species", "low_albedo"), slices=160, light_res=64)
    paper.frame(spec)
    below = np.array([[0.0, 0.0, 300.0], [500.0, -400.0, 600.0]])
    np.testing.assert_allclose(multiple.light_at(below)[0], np.exp(-0.6 * tau / sun.mu0), rtol=0.02)
    np.testing.assert_allclose(paper.light_at(below)[0], np.exp(-tau / sun.mu0), rtol=0.02)
    # the camera looks down through the whole layer (transmittance of the eye ray)
    np.testing.assert_allclose(multiple.transmittance, np.exp(-0.6 * tau), rtol=0.02)
    np.testing.assert_allclose(paper.transmittance, np.exp(-tau), rtol=0.02)
    thin = wm.OpticalVolume.from_arrays(beta * 0.01, 1.0, peaked_table(0.4), vol.bbox)
    single = dict(ms_contribution=0.0, diffusion_gain=0.0, sky_gain=0.0)
    with_peak = render_slices(spec, thin, SliceMode("per_species", "multiple"), slices=128, light_res=32, **single)
    without = render_slices(spec, thin, SliceMode("per_species", "multiple"), slices=128, light_res=32,
                            forward_peak_deg=0.0, **single)
    np.testing.assert_allclose(with_peak.radiance, without.radiance, rtol=0.02)
    assert with_peak.metadata["forward_peak_deg"] == 3.0 and without.metadata["forward_peak_deg"] == 0.0


def test_diffusion_profile_of_a_cloud_column():
    """eye.diffusion_profile against its closed form (z0 = 2/3 transport depths): 1 at the lit face of a
    semi-infinite cloud, (1 + z0) / z0 from one transport depth inwards, a straight line down to the
    shadowed face of a finite column, and vanishing like the transport thickness X for thin columns."""
    from weather_mi.slicing.eye import DIFFUSION_Z0 as z0, diffusion_profile
    J = lambda tau, tau_col, scale=0.5: float(diffusion_profile(np, np.float64(tau), np.float64(tau_col), scale))  # noqa: E731
    assert J(0.0, 1e9) == pytest.approx(1.0, rel=1e-6)
    assert J(2.0, 1e9) == pytest.approx((1 + z0) / z0, rel=1e-6)
    assert J(50.0, 1e9) == pytest.approx((1 + z0) / z0, rel=1e-6)
    X = 10.0                                       # tau_col = 20 at scale 0.5
    line = [J(t, 20.0) for t in (4.0, 10.0, 16.0)]  # x = 2, 5, 8: beyond x_s = 1, on the straight line
    assert line[1] - line[0] == pytest.approx(line[2] - line[1], rel=1e-9)
    assert J(20.0, 20.0) == pytest.approx((1 - np.exp(-X)) * (1 + z0) * z0 / ((X + 2 * z0) * z0), rel=1e-9)
    for X in (1e-2, 1e-3):
        assert J(0.0, 2 * X) / X == pytest.approx(1.0 * z0 * (X + z0 - X / 2) / ((X + 2 * z0) * z0), rel=0.02)


def test_diffused_light_leaves_a_cloud_with_eddingtons_limb_law():
    """The diffused light's flux term (eye.diffused_towards_eye): at the shadowed face of a thick column the
    diffusion radiance (phi + 3 F . w) / (4 pi) with the extrapolated boundary z0 = 2/3 is the Eddington
    approximation's emergent radiance I(mu) / I(0) = 1 + 3/2 mu (Chandrasekhar 1960, Radiative Transfer,
    section 2.8), brightest looking towards the sun (back-lit); at the sunlit face the same law for light
    leaving towards the sun. The flux itself is the profile's slope (a central difference); with no flux
    weight, or no direction, the isotropic terms are unchanged."""
    from types import SimpleNamespace
    from weather_mi.slicing.eye import diffused_towards_eye, diffusion_flux, diffusion_profile
    xp = SimpleNamespace(select=np.where, minimum=np.minimum, maximum=np.maximum, exp=np.exp)  # Dr.Jit's names
    scale, tau_col = 0.15, 400.0                    # X = 60 transport depths
    I = lambda tau, mu, flux=1.0: float(diffused_towards_eye(xp, np.float64(tau), np.float64(tau_col), scale, 1.0,  # noqa: E731
                                                             0.0, 1.0, flux, mu))
    for mu in (0.25, 0.5, 0.9):
        assert I(tau_col, mu) / I(tau_col, 0.0) == pytest.approx(1.0 + 1.5 * mu, rel=1e-9)   # shadowed face, mu > 0
        assert I(0.0, -mu) / I(0.0, 0.0) == pytest.approx(1.0 + 1.5 * mu, rel=1e-9)         # sunlit face, towards the sun
        assert I(tau_col, -mu) < I(tau_col, 0.0)
    J = lambda t: float(diffusion_profile(np, np.float64(t), np.float64(tau_col), scale))  # noqa: E731
    for t in (2.0, 100.0, 300.0):  # off the kink at x_s = 1 (tau = 6.7)
        slope = (J(t + 1e-3) - J(t - 1e-3)) / (2e-3 * scale)
        assert float(diffusion_flux(xp, np.float64(t), np.float64(tau_col), scale)) == pytest.approx(-slope, rel=1e-5)
    iso = float(diffused_towards_eye(xp, np.float64(50.0), np.float64(tau_col), scale, 1.1, 0.5, 0.7))
    assert iso == pytest.approx(1.1 * J(50.0) + 0.5 * float(np.exp(-0.7 * scale * 50.0) * (1 - np.exp(-scale * tau_col))))


def test_optical_depth_is_interpolated_between_slice_planes():
    """Inside a dense homogeneous layer the optical depth towards the sun grows linearly between two slice
    planes while the light falls exponentially: the "multiple" model's lookup (``log_direct``) interpolates
    the depth and is exact there (Beer-Lambert within 2%); a linear interpolation of the light itself is off
    by a factor of several in the middle of a slab (the terraces it drew on towers)."""
    import mitsuba as mi
    tau = 40.0
    beta = np.zeros((8, 8, 8), np.float32)
    beta[4:] = tau / 1000.0
    vol = wm.OpticalVolume.from_arrays(beta, 1.0, hg_table(0.0), ((-8e3, -8e3, 0.0), (8e3, 8e3, 2000.0)))
    sun = wm.Sun(azimuth=0.0, elevation=90.0)
    cam = wm.Camera.orthographic(center=(0, 0, 5000.0), direction=(0.3, 0.0, -1.0), width=4000, height=4000)
    spec = wm.SceneSpec(camera=cam, sun=sun, sky=None, ground=None, width=8, height=8)
    r = SliceRenderer(vol, SliceMode("uniform", "low_albedo"), slices=12, light_res=32)
    r.frame(spec)
    z = np.linspace(1300.0, 1800.0, 11)       # inside the layer's uniform part, away from its faces
    pts = mi.Point3f(mi.Float(np.zeros_like(z)), mi.Float(np.zeros_like(z)), mi.Float(z))
    # vertical optical depth from the top (2000 m): the trilinear ramp ends at 1000 m, uniform above 1125 m
    expected = np.exp(-(tau / 1000.0) * (2000.0 - z))
    logged = np.asarray(r.light.lookup(pts, log_direct=True)[0])
    linear = np.asarray(r.light.lookup(pts)[0])
    np.testing.assert_allclose(np.log(logged), np.log(expected), atol=0.15)   # depths of 8 to 28
    assert np.max(np.abs(np.log(linear) - np.log(expected))) > 1.0


def test_the_eye_weighted_mean_position_in_a_segment():
    """``SlabAverage.mean_offset`` against a numerical average of u with weights exp(-x (u + h))."""
    import mitsuba as mi
    from weather_mi.slicing.eye import SlabAverage
    for x, h in ((1e-5, 0.5), (0.3, 0.5), (4.0, 0.5), (40.0, 0.3), (2.0, 0.1)):
        u = np.linspace(-h, h, 200001)
        w = np.exp(-x * (u + h))
        expected = np.trapezoid(u * w, u) / np.trapezoid(w, u)
        got = float(SlabAverage(mi.Float(x), 1.0, mi.Float(h)).mean_offset()[0])
        assert got == pytest.approx(expected, abs=1e-4 * max(h, 1e-3)), (x, h)


def test_the_slab_average_of_exponentially_varying_light():
    """``SlabAverage.factor``: the in-scattering of light L_m exp(-sigma kappa u) over a segment [-h, h]
    seen through the transmittance exp(-x (u + h)), x int L T du, over the midpoint rule's
    (1 - exp(-2 x h)) L_m, by numerical quadrature; thin segments, kappa cancelling x (q h -> 0),
    light that grows or decays along the ray."""
    import mitsuba as mi
    from weather_mi.slicing.eye import SlabAverage
    cases = [(1e-5, 1.0, 3.0, 0.5), (0.3, 1.0, 0.0, 0.5), (0.3, -1.0, 0.3, 0.5), (2.0, -1.0, 2.00001, 0.5),
             (4.0, 1.0, 7.0, 0.5), (4.0, -1.0, 9.0, 0.5), (40.0, -1.0, 5.0, 0.3), (2.0, 1.0, 0.5, 0.125)]
    for x, sigma, kappa, h in cases:
        u = np.linspace(-h, h, 400001)
        exact = x * np.trapezoid(np.exp(-sigma * kappa * u - x * (u + h)), u)
        expected = 1.0 if x * h < 1e-4 else exact / (1.0 - np.exp(-2.0 * x * h))
        slab = SlabAverage(mi.Float(x), sigma, mi.Float(h))
        got = float(slab.factor(mi.Float(kappa))[0])
        assert got == pytest.approx(expected, rel=2e-4), (x, sigma, kappa, h)
        light = float(slab.mean_light(mi.Float(math.log(0.3)), mi.Float(kappa))[0])  # the same, times light 0.3
        assert light == pytest.approx(0.3 * expected, rel=2e-4), (x, sigma, kappa, h)


def test_the_sky_and_the_ground_light_a_layer_through_the_columns_above_and_below():
    """In a homogeneous layer (extinction beta between z0 and z1) the "multiple" model's skylight passes
    the optical depth above, beta (z1 - z), as diffuse light (``ground_transmission`` at the diffusivity
    cosine, tests/test_slicing_ground.py checks it against DISORT), and the light of the lit ground the
    optical depth below, beta (z - z0), both scaled by k (``sky_extinction``); the ground's light is its
    radiance rho / pi E_sun mu0 + rho / pi E_sky, and it brightens every cloud pixel over a black ground's."""
    import mitsuba as mi
    from weather_mi.slicing.eye import LightModel
    beta, z0, z1, k = 20e-3, 1000.0, 2000.0, 0.5
    vol = slab(beta=beta, size=(16, 8, 8))
    sky = wm.Sky("sunsky")
    spec = wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=180, elevation=10, fov=40), sun=wm.Sun(170, 30),
                        sky=sky, ground=wm.Ground(albedo=0.2), width=16, height=12)
    r = SliceRenderer(vol, SliceMode("per_species", "multiple"), slices=64, light_res=16)
    r.frame(spec, SliceParams(sky_extinction=k))
    z = np.linspace(z0 + 50.0, z1 - 50.0, 9)
    p = mi.Point3f(mi.Float(np.zeros(9)), mi.Float(np.zeros(9)), mi.Float(z))
    from weather_mi.slicing.eye import DIFFUSE_MU, ground_transmission
    model = LightModel(r.light, r.sky_light, 4, 0.1, 0.2, 0.5, mi.Float(k), below=True, g=0.85)
    _, _, occ, occ_below = model.terms(p)
    above, below = ground_transmission(np, k * beta * (z1 - z), DIFFUSE_MU, 0.85), \
        ground_transmission(np, k * beta * (z - z0), DIFFUSE_MU, 0.85)
    assert above[0] < 0.95 * above[-1] and below[-1] < 0.95 * below[0]  # the layer occludes, both ways
    np.testing.assert_allclose(np.asarray(occ), above, rtol=0.01)
    np.testing.assert_allclose(np.asarray(occ_below), below, rtol=0.01)
    from weather_mi.kernel.sky import sky_irradiance_horizontal
    from weather_mi.slicing.renderer import ground_radiance
    e_sky = sky_irradiance_horizontal(spec)
    from_sun, from_sky = ground_radiance(spec, e_sky)
    np.testing.assert_allclose(from_sun, 0.2 / math.pi * np.asarray(spec.sun.irradiance) * math.sin(math.radians(30.0)),
                               rtol=1e-12)
    np.testing.assert_allclose(from_sky, 0.2 / math.pi * np.asarray(e_sky), rtol=1e-12)
    np.testing.assert_allclose(ground_radiance(spec, e_sky, np.ones(3))[1], np.asarray(e_sky) / math.pi, rtol=1e-12)
    # the ground's light adds to the image
    gain = SliceParams(sky_extinction=k)
    lit = r.frame(spec, gain).radiance
    dark = r.frame(wm.SceneSpec(camera=spec.camera, sun=spec.sun, sky=sky, ground=wm.Ground(albedo=0.0),
                                width=16, height=12), gain).radiance
    cloud = r.transmittance < 0.5
    assert cloud.sum() > 10 and np.all(lit[cloud] > dark[cloud])


def test_supersampled_pixels_average_their_footprint():
    """A slab's edge (x = 20 km, tau = 1 through it) on the middle line of a pixel column: that pixel's
    footprint average, which the path tracer's box filter estimates, is (1 + exp(-1)) / 2; 2 x 2 and 4 x 4
    points per pixel give it exactly, every other pixel exp(-1) or 1, and the differentiable arrays agree."""
    vol = slab(beta=1e-3)
    cam = wm.Camera.orthographic(center=(19e3, 0.0, 5000.0), direction=(0, 0, -1), width=16e3, height=8e3)
    spec = wm.SceneSpec(camera=cam, sun=wm.Sun(180.0, 60.0), sky=None, ground=None, width=8, height=4)
    r = SliceRenderer(vol, SliceMode("uniform", "low_albedo"), slices=16, light_res=16)
    for n in (2, 4):
        img = r.frame(spec, supersample=n)
        t = r.transmittance
        assert img.radiance.shape == (4, 8, 3) and t.shape == (4, 8)
        edge = np.abs(t - (1 + math.exp(-1)) / 2) < 1e-4
        assert np.array_equal(edge.sum(axis=1), [1, 1, 1, 1]), t
        inside = t[~edge] < 0.7
        assert inside.any() and (~inside).any()
        np.testing.assert_allclose(t[~edge], np.where(inside, math.exp(-1), 1.0), atol=1e-4)
        out, t_arr = r.frame(spec, return_arrays=True, supersample=n)
        np.testing.assert_allclose(np.asarray(t_arr).reshape(4, 8), t, atol=1e-6)
        np.testing.assert_allclose(np.asarray(dr.ravel(out)).reshape(4, 8, 3), img.radiance, atol=1e-6)
    with pytest.raises(ValueError, match="supersample"):
        r.frame(spec, supersample=0)
