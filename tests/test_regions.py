"""Pixels sorted into regions by what they show (weather_mi/study/regions.py), on a homogeneous slab whose
optical depths are closed forms."""
import math

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.slicing import SliceMode, SliceRenderer
from weather_mi.study.regions import eye_surface, pixel_regions, region_residuals

TOP_M = 2000.0


def slab(beta):
    arr = np.full((8, 8, 8), beta, np.float32)
    table = wm.phase.PhaseTable.from_values(np.linspace(0.0, np.pi, 200), np.full(200, 1.0 / (4.0 * np.pi)))
    return wm.OpticalVolume.from_arrays(arr, 1.0, table, ((-20e3, -20e3, 1000.0), (20e3, 20e3, TOP_M)))


def seen_from_above(vol, sun_elevation_deg, from_below=False):
    z, direction = (500.0, (0, 0, 1)) if from_below else (5000.0, (0, 0, -1))
    camera = wm.Camera.orthographic(center=(0.0, 0.0, z), direction=direction, width=4000.0, height=3000.0)
    spec = wm.SceneSpec(camera=camera, sun=wm.Sun(30.0, sun_elevation_deg), width=8, height=6)
    r = SliceRenderer(vol, SliceMode("uniform", "low_albedo"), slices=128, light_res=128)
    r.frame(spec)
    return r, spec


def test_the_surface_lies_one_optical_depth_inside():
    beta = 4e-3
    r, spec = seen_from_above(slab(beta), 60.0)
    p1, tau = eye_surface(r, spec)
    np.testing.assert_allclose(p1[..., 2], TOP_M - 1.0 / beta, atol=1.0)   # z = top - 1 / beta
    np.testing.assert_allclose(tau, beta * 1000.0, rtol=1e-3)              # the whole slab, 1 km


@pytest.mark.parametrize("beta, elevation, region, from_below", [
    (4e-3, 80.0, "sunlit face", False),    # sunlight at p1: exp(-1 / sin 80) = 0.36 >= 0.3
    (4e-3, 30.0, "shaded face", False),    # exp(-1 / sin 30) = 0.14, and more cloud below p1 than above: no base
    (1.5e-3, 60.0, "thin edge", False),    # tau = 1.5
    # looking up through the slab towards a sun 60 deg high (scattering angle 30 deg): back-lit
    (1.5e-3, 60.0, "back-lit rim", True),  # tau = 1.5
    (4e-3, 60.0, "back-lit core", True),   # p1 250 m above the base: exp(-4e-3 x 750 / sin 60) = 0.03 < 0.3
    (4e-3, 20.0, "shaded face", True),     # scattering angle 70 deg: not back-lit; the same p1, D ~ 0
])
def test_regions_of_a_slab(beta, elevation, region, from_below):
    r, spec = seen_from_above(slab(beta), elevation, from_below)
    masks = pixel_regions(r, spec)
    assert masks[region].all(), {k: int(v.sum()) for k, v in masks.items()}
    assert sum(int(m.sum()) for m in masks.values()) == spec.width * spec.height  # no pixel in two regions
    if region == "sunlit face":  # the light volume's sunlight there against the closed form
        p1, _ = eye_surface(r, spec)
        d = r.light_at(p1.reshape(-1, 3))[0]
        np.testing.assert_allclose(d, math.exp(-1.0 / math.sin(math.radians(elevation))), rtol=0.05)


def test_residuals_by_region_report_a_uniform_bias():
    rng = np.random.default_rng(0)
    ref = rng.uniform(0.1, 1.0, (6, 8, 3))
    masks = {"a": np.zeros((6, 8), bool), "b": np.zeros((6, 8), bool)}
    masks["a"][:3], masks["b"][3:] = True, True
    rows = region_residuals(ref, 1.1 * ref, masks)
    for row in rows:
        assert row["pixels"] == 24
        assert row["bias"] == pytest.approx(0.1, rel=1e-9)
        assert row["rel_rms"] >= row["bias"] and row["ciede2000"] > 0
