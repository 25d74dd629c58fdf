"""The slicer's per-view kernels (weather_mi/slicing/rays.py) against the numpy code they replace
(geometry.camera_rays and ray_box, scene.spec.ground_hits, np.interp of a phase table): the same float64
values, which the images' bit-identity across the move relies on."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.scene.spec import ground_hits
from weather_mi.slicing import geometry, rays


@pytest.fixture(scope="module")
def mi():
    wm.set_variant(None)
    import mitsuba
    return mitsuba


def host(v):
    return np.stack([np.asarray(c, np.float64) for c in v], axis=-1)


@pytest.mark.parametrize("kind", ["perspective", "orthographic"])
def test_camera_rays_box_and_ground_hits_are_numpys(mi, kind):
    box = (np.array([-3e3, -2e3, 500.0]), np.array([4e3, 2.5e3, 9e3]))
    cam = wm.Camera.orbit(box, azimuth=200.0, elevation=8.0)
    if kind == "orthographic":
        cam = wm.Camera(origin=cam.origin, target=cam.target, up=cam.up, kind="orthographic",
                        ortho_width=9e3, ortho_height=7e3)
    spec = wm.SceneSpec(camera=cam, sun=wm.Sun(240, 35), ground=wm.Ground(height=700.0), width=13, height=9)
    o, d = rays.camera_rays(mi, spec)
    o_np, d_np = (a.reshape(-1, 3) for a in geometry.camera_rays(spec))
    np.testing.assert_allclose(host(o), o_np, rtol=1e-15, atol=0)
    np.testing.assert_allclose(host(d), d_np, rtol=1e-15, atol=1e-16)
    t0, t1 = rays.ray_box(mi, o, d, box)
    e0, e1 = geometry.ray_box(o_np, d_np, box)
    np.testing.assert_allclose(np.asarray(t0), e0, rtol=1e-14)
    np.testing.assert_allclose(np.asarray(t1), e1, rtol=1e-14)
    assert np.any(e0 > e1) and np.any(e0 < e1)  # rays that miss the box and rays that cross it
    tg = np.asarray(rays.ground_hits(mi, spec, o, d))
    expected = ground_hits(spec, o_np, d_np)
    assert np.array_equal(np.isfinite(tg), np.isfinite(expected)) and np.isfinite(expected).any()
    np.testing.assert_allclose(tg[np.isfinite(tg)], expected[np.isfinite(expected)], rtol=1e-14)


def test_axis_aligned_rays_meet_the_box_as_numpys(mi):
    box = (np.array([-1.0, -1.0, -1.0]), np.array([1.0, 1.0, 1.0]))
    o_np = np.array([[0.0, 0.0, -5.0], [2.0, 0.0, -5.0], [1.0, 0.0, -5.0], [0.0, 0.0, 0.0]])
    d_np = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    o, d = ([mi.Float64(a[:, c].copy()) for c in range(3)] for a in (o_np, d_np))
    for clamp in (True, False):
        t0, t1 = rays.ray_box(mi, o, d, box, clamp_start=clamp)
        e0, e1 = geometry.ray_box(o_np, d_np, box, clamp_start=clamp)
        np.testing.assert_array_equal(np.asarray(t0), e0)
        np.testing.assert_array_equal(np.asarray(t1), e1)


def test_phase_values_interpolate_the_table_as_np_interp(mi):
    theta = np.array([0.0, 0.01, 0.2, 1.0, 2.5, np.pi])
    values = np.array([[50.0, 40.0, 30.0], [20.0, 20.0, 10.0], [1.0, 1.5, 2.0], [0.1, 0.1, 0.1],
                       [0.05, 0.2, 0.3], [0.5, 0.4, 0.3]])
    table = type("Table", (), {"theta": theta, "values": values})()
    at = np.r_[theta, np.linspace(-0.1, 3.3, 101), 0.005, 1.75]
    got = rays.phase_values(mi, rays.phase_table(mi, table), mi.Float64(at))
    for c in range(3):
        np.testing.assert_allclose(np.asarray(got[c]), np.interp(at, theta, values[:, c]), rtol=1e-15, atol=0)
