"""Views the renderers must take whatever they see: the slicer under a Hosek-Wilkie sky when no pixel
sees the sky (camera looking down at the storm and the ground), at any camera elevation; and scene
arguments that are wrong (a fractional image size, a zero field of view) refused at construction."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.kernel.sky import sky_radiance


@pytest.fixture(scope="module")
def small_cumulus():
    hyd = wm.synthetic.cumulus(shape=(24, 24, 24), spacing_m=(200.0, 200.0, 200.0), rain=False)
    return wm.optical_volume(hyd, species="paper", phase_quality="test")


def test_sunsky_radiance_of_no_directions_is_empty():
    spec = wm.SceneSpec(camera=wm.Camera((0, -1000, 500), (0, 0, 500)), sky=wm.Sky("sunsky"), width=4, height=3)
    assert sky_radiance(spec, np.zeros((0, 3))).shape == (0, 3)


def test_slicer_renders_under_a_sunsky_at_every_camera_elevation(small_cumulus):
    """From 0 to 89.9 deg: at 20 deg and above no pixel of this framing sees the sky (the ground and the
    cloud fill the frame), which made Mitsuba's sky evaluation fail on an empty array."""
    renderer = wm.SliceRenderer(small_cumulus, wm.SliceMode(), slices=32, light_res=16)
    for elevation in (0.0, 20.0, 60.0, 89.9):
        spec = wm.SceneSpec(camera=wm.Camera.orbit(small_cumulus, azimuth=200, elevation=elevation, fov=30),
                            sun=wm.Sun(240, 35), sky=wm.Sky("sunsky"), ground=wm.Ground(0.15), width=12, height=9)
        img = renderer.frame(spec)
        assert np.all(np.isfinite(img.radiance)) and img.radiance.max() > 0, elevation


@pytest.mark.parametrize("width, height", [(64.7, 48), (64, 0.5), (True, 4), ("64", 48), (np.float64(3.5), 3)])
def test_scene_spec_refuses_a_size_that_is_not_a_positive_integer(width, height):
    cam = wm.Camera((0, -1000, 500), (0, 0, 500))
    with pytest.raises(ValueError, match="size"):
        wm.SceneSpec(camera=cam, width=width, height=height)


def test_scene_spec_takes_integral_sizes_of_any_integer_type():
    cam = wm.Camera((0, -1000, 500), (0, 0, 500))
    spec = wm.SceneSpec(camera=cam, width=np.int64(8), height=6.0)
    assert (spec.width, spec.height) == (8, 6) and type(spec.width) is int and type(spec.height) is int


@pytest.mark.parametrize("seed", [-1, 1.5, "0"])
def test_scene_spec_refuses_a_bad_seed(seed):
    with pytest.raises(ValueError, match="seed"):
        wm.SceneSpec(camera=wm.Camera((0, -1000, 500), (0, 0, 500)), seed=seed)


@pytest.mark.parametrize("fov", [0.0, -10.0, 180.0, float("nan"), float("inf")])
def test_orbit_refuses_a_field_of_view_outside_0_180(small_cumulus, fov):
    with pytest.raises(ValueError, match="fov"):
        wm.Camera.orbit(small_cumulus, fov=fov)
    with pytest.raises(ValueError, match="fov"):
        wm.Camera((0, -1000, 500), (0, 0, 500), fov=fov)


@pytest.mark.parametrize("kw", [{"elevation": float("nan")}, {"azimuth": float("inf")}, {"distance": 0.0},
                                {"distance": -5.0}])
def test_orbit_refuses_other_bad_arguments(small_cumulus, kw):
    with pytest.raises(ValueError):
        wm.Camera.orbit(small_cumulus, **kw)


def test_regional_domain_gets_an_aerial_view_by_default():
    """``render``'s default camera ("auto"): a storm-scale box keeps the ground camera; a domain wider than
    300 km (a regional wrfout) is seen from above at 50 degrees, the weather in the picture, not the sky."""
    import numpy as np
    import weather_mi as wm
    from weather_mi.scene.framing import scene_spec
    beta = np.full((4, 8, 8), 1e-3, np.float32)
    wide = wm.OpticalVolume.from_arrays(beta, 1.0, wm.phase.isotropic(), ((0, 0, 0), (480e3, 480e3, 16e3)))
    small = wm.OpticalVolume.from_arrays(beta, 1.0, wm.phase.isotropic(), ((0, 0, 0), (80e3, 80e3, 16e3)))
    spec = scene_spec(wide, camera="auto")
    elevation = np.degrees(np.arcsin(-spec.camera.forward[2]))
    assert 40.0 < elevation < 60.0 and spec.camera.origin[2] > 100e3
    assert scene_spec(small, camera="auto").camera == scene_spec(small, camera="ground").camera
