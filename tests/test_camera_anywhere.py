"""A camera anywhere (issue 10): outside the volume's box, inside it in clear air, inside cloud. Each
is checked against the same scene seen from outside or against Beer-Lambert's law.

An orthographic camera moved along its own axis through clear air sees exactly the same rays beyond
it, so its images must agree within noise; a camera inside a uniform slab sees the transmittance
exp(-beta d) of the distance d left to the slab's far side.
"""
from __future__ import annotations

import numpy as np

import weather_mi as wm

BBOX = ((0.0, 0.0, 0.0), (2000.0, 2000.0, 1000.0))


def block_volume():
    """Clear air in the south half of the box, cloud (optical depth 2 across 1 km) in the north half."""
    beta = np.zeros((8, 16, 16), np.float32)
    beta[:, 8:, :] = 0.002
    return wm.OpticalVolume.from_arrays(beta_ext=beta, albedo=0.9, phase=wm.phase.henyey_greenstein(0.7),
                                        bbox=BBOX)


def north_camera(y):
    return wm.Camera.orthographic(center=(1000.0, y, 500.0), direction=(0.0, 1.0, 0.0), width=800, height=400)


def spec(camera, **kw):
    return wm.SceneSpec(camera=camera, sun=wm.Sun(250.0, 40.0), sky=wm.Sky("constant"), ground=None,
                        width=8, height=4, **kw)


def test_transmittance_from_clear_air_inside_the_box_equals_the_view_from_outside():
    vol = block_volume()
    outside = wm.render_transmittance(spec(north_camera(-500.0)), vol, spp=64)
    inside = wm.render_transmittance(spec(north_camera(300.0)), vol, spp=64)   # in the box, clear air
    expect = np.exp(-0.002 * 1000.0)
    assert abs(outside.mean() - expect) < 0.02 and abs(inside.mean() - expect) < 0.02, (outside.mean(), inside.mean())


def test_transmittance_from_inside_the_cloud_is_beer_lambert():
    vol = block_volume()
    inside = wm.render_transmittance(spec(north_camera(1600.0)), vol, spp=64)  # 400 m of cloud left
    assert abs(inside.mean() - np.exp(-0.002 * 400.0)) < 0.02, inside.mean()


def test_radiance_of_a_camera_moved_along_its_axis_through_clear_air_is_unchanged():
    vol = block_volume()
    a = wm.render_reference(spec(north_camera(-500.0), seed=1), vol, spp=64, progress=False)
    b = wm.render_reference(spec(north_camera(300.0), seed=2), vol, spp=64, progress=False)
    ma, mb = a.radiance.mean(), b.radiance.mean()
    se = np.hypot(np.sqrt((a.stderr ** 2).sum()) / a.stderr.size, np.sqrt((b.stderr ** 2).sum()) / b.stderr.size)
    assert ma > 0.05
    assert abs(ma - mb) < 4 * se + 1e-3 * ma, (ma, mb, se)


def test_ground_view_frames_the_storm_from_near_the_ground():
    vol = wm.optical_volume(wm.synthetic.supercell())
    cam = wm.Camera.ground_view(vol, distance_km=40, height_m=1500, azimuth=200, fov=70)
    assert abs(cam.origin[2] - 1500.0) < 1e-6
    (x0, y0, _), (x1, y1, z1) = vol.occupied_bbox()
    fwd = cam.forward
    assert fwd[2] > 0  # looking a little up: horizon low in the frame
    # the cloud top above the core is inside the vertical field of view of a 4:3 image
    half_v = np.degrees(np.arctan(np.tan(np.radians(cam.fov) / 2) * 3 / 4))
    pitch = np.degrees(np.arcsin(fwd[2]))
    top = np.degrees(np.arctan2(z1 - 1500.0, 40000.0))
    assert pitch + half_v > top and pitch - half_v < 0.0
