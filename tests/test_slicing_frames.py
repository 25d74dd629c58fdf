"""Recorded frames (dr.freeze) and per-pixel slab offsets of the half-angle slicer: a frozen frame is
the traced one bit for bit when parameters, sun and camera change, is recorded again when the
structure changes (image size, slice count), compiles nothing between frames, and the slab offsets
are stable between frames, off by default and remove the slab terraces' coherence."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.slicing import MODES, SliceParams, SliceRenderer
from weather_mi.slicing.jitter import offset_pattern
from conftest import kernels_compiled


@pytest.fixture(scope="module")
def vol():
    wm.set_variant(None)
    return wm.optical_volume(wm.synthetic.supercell(), species="physical")


def spec_at(vol, i, w=40, h=30):
    spec = wm.scene.spec.default_spec(vol, w, h, camera_azimuth=200.0 + 9.0 * i)
    return wm.SceneSpec(camera=spec.camera, sun=wm.Sun(200.0 + 10.0 * i, 30.0 + 4.0 * i), sky=spec.sky,
                        ground=spec.ground, width=w, height=h)


@pytest.mark.parametrize("name", ["per-species/multiple", "per-species/translucent", "uniform/low-albedo"])
def test_frozen_frames_equal_traced_frames_as_everything_changes(vol, name):
    frozen = SliceRenderer(vol, MODES[name], slices=24, light_res=16)
    traced = SliceRenderer(vol, MODES[name], slices=24, light_res=16)
    traced.frozen = False
    changes = [SliceParams(), SliceParams(scale={"ice": 1.7}), SliceParams(scale={"ice": 1.7}, albedo=0.9),
               SliceParams(cone_angle_deg=5.0, slab_jitter=1.0), SliceParams(ms_extinction=0.3, sky_gain=1.5,
                                                                            jitter_frame=3, slab_jitter=0.5)]
    for i, params in enumerate(changes):
        spec = spec_at(vol, i)  # camera and sun move every frame
        a, b = frozen.frame(spec, params), traced.frame(spec, params)
        np.testing.assert_array_equal(a.radiance, b.radiance)
        np.testing.assert_array_equal(frozen.transmittance, traced.transmittance)
    # the light volume that light_at reads is the last frame's
    pts = np.array([[0.0, 0.0, 3000.0], [2000.0, -1000.0, 6000.0]])
    np.testing.assert_array_equal(np.concatenate(frozen.light_at(pts)), np.concatenate(traced.light_at(pts)))
    if name == "per-species/multiple":  # (translucent: a moving sun or camera changes the blur's chunks)
        assert frozen._frozen_kernels.n_recordings <= 4  # (textures rebuilt or not) x (first literal values)


@pytest.mark.parametrize("name", ["per-species/translucent", "uniform/translucent"])
def test_a_frame_depends_on_its_inputs_alone(vol, name):
    """What a renderer keeps from its last frame (geometry, cone fractions, the scene's description)
    never leaks into the next: every frame of a sequence that changes the cone angle, the sun and the
    camera, and returns, equals the frame of a new renderer, image and metadata."""
    r = SliceRenderer(vol, MODES[name], slices=16, light_res=16)
    sequence = [(0, 10.0), (0, 25.0), (1, 25.0), (1, 10.0), (0, 10.0)]
    images = set()
    for i, cone in sequence:
        spec, params = spec_at(vol, i), SliceParams(cone_angle_deg=cone)
        a, b = r.frame(spec, params), SliceRenderer(vol, MODES[name], slices=16, light_res=16).frame(spec, params)
        np.testing.assert_array_equal(a.radiance, b.radiance)
        for key in ("scene", "forward_fraction_per_species", "back_to_front"):
            assert a.metadata[key] == b.metadata[key]
        assert a.metadata["scene"] == spec.to_dict()
        images.add(a.radiance.tobytes())
    assert len(images) == 4  # the four distinct inputs give four images


def test_a_new_structure_is_recorded_again(vol):
    frozen = SliceRenderer(vol, MODES["per-species/multiple"], slices=24, light_res=16)
    traced = SliceRenderer(vol, MODES["per-species/multiple"], slices=24, light_res=16)
    traced.frozen = False
    for w, h, slices in [(40, 30, 24), (40, 30, 24), (24, 16, 24), (40, 30, 12), (40, 30, 24)]:
        frozen.slices = traced.slices = slices  # as the viewer's drafts do
        spec = spec_at(vol, 1, w, h)
        p = SliceParams(scale={"ice": 1.0 + 0.1 * w + slices})
        np.testing.assert_array_equal(frozen.frame(spec, p).radiance, traced.frame(spec, p).radiance)


def test_frozen_frames_compile_nothing(vol):
    r = SliceRenderer(vol, MODES["per-species/multiple"], slices=24, light_res=16)
    for i in range(3):  # warm-up: records (textures rebuilt, literal values made opaque), then a first move
        r.frame(spec_at(vol, 0), SliceParams(scale={"ice": 1.0 + 0.1 * i}))
    r.frame(spec_at(vol, 1), SliceParams(scale={"ice": 1.5}, ms_contribution=0.05, slab_jitter=0.1))
    with kernels_compiled() as compiled:
        for i in range(2, 5):
            r.frame(spec_at(vol, i), SliceParams(scale={"ice": 2.0 + i}, ms_contribution=0.1 * i, slab_jitter=0.2 * i))
    assert compiled == [], f"{len(compiled)} kernels compiled after the first frames"


def test_slab_offsets_are_stable_off_by_default_and_rotate_with_the_frame_index(vol):
    r = SliceRenderer(vol, MODES["per-species/multiple"], slices=24, light_res=16)
    spec = spec_at(vol, 0)
    aligned = r.frame(spec).radiance
    np.testing.assert_array_equal(aligned, r.frame(spec, SliceParams(slab_jitter=0.0)).radiance)
    a = r.frame(spec, SliceParams(slab_jitter=1.0)).radiance
    np.testing.assert_array_equal(a, r.frame(spec, SliceParams(slab_jitter=1.0)).radiance)  # no crawl
    b = r.frame(spec, SliceParams(slab_jitter=1.0, jitter_frame=1)).radiance
    assert np.abs(a - aligned).max() > 0 and np.abs(b - a).max() > 0
    # offsets move slabs, they do not add or remove light: the means stay close
    assert abs(a.mean() / aligned.mean() - 1.0) < 0.05
    p = offset_pattern(64, 48)
    assert p.min() >= 0.0 and p.max() < 1.0 and abs(p.mean() - 0.5) < 0.02
    with pytest.raises(ValueError):
        SliceParams(slab_jitter=1.5)


def test_offsets_reduce_the_banding_metric_on_the_tower(vol):
    import importlib.util
    from pathlib import Path
    spec_file = Path(__file__).resolve().parents[1] / "benchmarks" / "banding.py"
    spec_mod = importlib.util.spec_from_file_location("banding", spec_file)
    banding = importlib.util.module_from_spec(spec_mod)
    spec_mod.loader.exec_module(banding)
    spec = wm.scene.spec.default_spec(vol, 160, 120)
    mode = MODES["per-species/translucent"]  # ("multiple" carries its light: little banding to remove)
    ref_r = SliceRenderer(vol, mode, slices=256)
    ref = ref_r.frame(spec).radiance
    k, tau = banding.surface_slice_index(ref_r, spec, 32)
    mask = tau > 2.0
    r = SliceRenderer(vol, mode, slices=32)
    e_aligned = banding.banding(r.frame(spec).radiance, ref, k, mask)[0]
    e_offsets = banding.banding(r.frame(spec, SliceParams(slab_jitter=1.0)).radiance, ref, k, mask)[0]
    assert e_offsets < 0.5 * e_aligned
