"""The ``raytable`` sensor (weather_mi/kernel/plugins/raytable_sensor.py): each pixel's rays from a table of corner rays.

Checked against geometry by hand: rays tilted by theta from nadir, starting at height H, meet the ground
H tan(theta) further along, so a glowing half-plane x < 0 seen through them lights exactly the pixels
whose footprints (shifted by H tan(theta)) fall on it -- the parallax a geostationary imager sees.
"""
import numpy as np
import pytest

import weather_mi as wm


def _scene(origins, directions, width, height):
    import mitsuba as mi
    from weather_mi.kernel.plugins.raytable_sensor import sensor_dict
    film = {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"},
            "pixel_format": "rgb", "component_format": "float32"}
    glow = mi.ScalarTransform4f().translate([-5000.0, 0.0, 0.0]).scale([5000.0, 5000.0, 1.0])
    return mi.load_dict({"type": "scene", "integrator": {"type": "direct"},
                         "sensor": sensor_dict(origins, directions, film),
                         "glow": {"type": "rectangle", "to_world": glow,
                                  "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}}}})


def _corner_rays(width, height, pixel_m, height_m, theta_deg):
    """Corner rays over [-W/2, W/2] x [-H/2, H/2] pixels of pixel_m, from height_m, tilted towards +x."""
    xs = (np.arange(width + 1) - width / 2) * pixel_m
    ys = (height / 2 - np.arange(height + 1)) * pixel_m  # row 0 at the top (north)
    gx, gy = np.meshgrid(xs, ys)
    origins = np.stack([gx, gy, np.full_like(gx, height_m)], -1)
    t = np.radians(theta_deg)
    directions = np.broadcast_to(np.array([np.sin(t), 0.0, -np.cos(t)]), origins.shape).copy()
    return origins, directions, xs


@pytest.mark.parametrize("theta_deg", [0.0, 30.0, 55.0])
def test_tilted_rays_land_displaced_by_h_tan_theta(theta_deg):
    import mitsuba as mi
    wm.set_variant("llvm_ad_rgb")
    width, height, pixel_m, h = 16, 4, 1000.0, 5000.0
    origins, directions, xs = _corner_rays(width, height, pixel_m, h, theta_deg)
    img = np.array(mi.render(_scene(origins, directions, width, height), spp=256))[..., 0]
    shift = h * np.tan(np.radians(theta_deg))
    ground_left, ground_right = xs[:-1] + shift, xs[1:] + shift
    lit = np.clip((0.0 - ground_left) / (ground_right - ground_left), 0.0, 1.0)  # share of the footprint at x < 0
    np.testing.assert_allclose(img.mean(axis=0), lit, atol=0.08)
    assert np.all(img[:, lit == 1.0] == 1.0) and np.all(img[:, lit == 0.0] == 0.0)


def test_shape_of_the_table_is_checked():
    with pytest.raises(RuntimeError, match=r"\(H \+ 1, W \+ 1, 3\)"):  # Mitsuba wraps the plugin's ValueError
        o, d, _ = _corner_rays(8, 4, 1.0, 10.0, 0.0)
        _scene(o[:-1], d[:-1], 8, 4)


def test_majorant_volpath_through_the_table_matches_the_orthographic_camera():
    """The path tracer's persistent lanes take the table's rays: nadir rays over a uniform slab give the
    orthographic camera's radiance (the same sun, medium and seeds; within 4 combined standard errors)."""
    import mitsuba as mi
    from weather_mi.kernel.scene_dict import integrator_dict, recentred, scene_dict
    from weather_mi.reference.passes import render_pass
    from weather_mi.kernel.plugins.raytable_sensor import sensor_dict
    wm.set_variant("llvm_ad_rgb")
    beta = np.full((8, 16, 16), 0.004, np.float32)  # tau 3.2 over 800 m
    vol = wm.OpticalVolume.from_arrays(beta, np.ones_like(beta), wm.phase.henyey_greenstein(0.5),
                                       ((0, 0, 0), (1600, 1600, 800)))
    cam = wm.Camera.orthographic(center=(800.0, 800.0, 2000.0), direction=(0.0, 0.0, -1.0), width=400, height=400)
    spec = wm.SceneSpec(camera=cam, sun=wm.Sun(30.0, 60.0, 1.0, angular_diameter_deg=0.0), sky=None, ground=None,
                        width=8, height=8, seed=1)
    spec_k, vol_k, _ = recentred(spec, vol)
    d = scene_dict(spec_k, vol_k, integrator_dict(vol_k, "majorant", -1, sun=spec_k.sun))
    ortho = [render_pass(mi.load_dict(d), 64, s)[..., 0] for s in (1, 2)]
    xs = np.linspace(-200.0, 200.0, 9)
    gx, gy = np.meshgrid(xs, xs[::-1])
    origins = np.stack([gx, gy, np.full_like(gx, 1500.0)], -1)
    d["sensor"] = sensor_dict(origins, np.broadcast_to([0.0, 0.0, -1.0], origins.shape).copy(), d["sensor"]["film"])
    table = [render_pass(mi.load_dict(d), 64, s)[..., 0] for s in (3, 4)]
    a, b = np.concatenate(ortho).ravel(), np.concatenate(table).ravel()
    se = np.hypot(a.std() / np.sqrt(a.size), b.std() / np.sqrt(b.size))
    assert a.mean() > 0.05 and abs(a.mean() - b.mean()) < 4 * se, (a.mean(), b.mean(), se)
