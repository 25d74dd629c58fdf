"""The slicer's skipped work changes no float: the light pass reads the medium only in the slabs of each
light ray's occupied span (``light._slab_range``) and the eye pass skips the light model and the eye's texture
in packets of samples that scatter nothing; both give the same store and image as the passes that visit all."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.slicing import SliceMode, SliceParams, SliceRenderer
from weather_mi.slicing import light as light_module


@pytest.fixture(scope="module")
def storm():
    wm.set_variant(None)
    vol = wm.optical_volume(wm.synthetic.supercell(shape=(20, 40, 40), spacing_m=(1000.0, 2000.0, 2000.0)),
                            species="physical")
    return vol, wm.scene.spec.default_spec(vol, 40, 30)


def _captured_plan(monkeypatch, r, spec, params):
    """The sun's SweepPlan and light source of a frame of ``r``."""
    seen = []
    run = light_module.LightVolume.run

    def spy(self, plan, source):
        if self is r.light:
            seen.append((plan, source))
        return run(self, plan, source)

    monkeypatch.setattr(light_module.LightVolume, "run", spy)
    r.frozen = False
    r.frame(spec, params)
    monkeypatch.setattr(light_module.LightVolume, "run", run)
    return seen[-1]


@pytest.mark.parametrize("light,jitter", [("low_albedo", 0.0), ("translucent", 0.0), ("translucent", 1.0),
                                          ("multiple", 1.0)])
def test_light_pass_in_occupied_slabs_alone_stores_the_same_light(monkeypatch, storm, light, jitter):
    vol, spec = storm
    r = SliceRenderer(vol, SliceMode("per_species", light), slices=48, light_res=48)
    plan, source = _captured_plan(monkeypatch, r, spec, SliceParams(slab_jitter=jitter))
    import drjit as dr
    first, end = (np.asarray(v) for v in light_module._slab_range(r.mi, dr, plan.ka, plan.kb, plan.n_slices))
    assert np.mean(end - first) < 0.5 * plan.n_slices  # most slabs of most light rays are skipped
    assert np.any(end > first)
    skipped = np.asarray(r.light.run(plan, source))
    every = np.asarray(r.light.run(dataclasses.replace(plan, ka=None, kb=None), source))
    np.testing.assert_array_equal(skipped, every)


def test_slab_range_covers_every_slab_that_reads_the_medium():
    """A slab reads the medium where one of its halves (half a slab each side of k, plus a plane offset of
    up to half a slab) overlaps the span: those k are within the range, empty spans give none."""
    wm.set_variant(None)
    import drjit as dr
    import mitsuba as mi
    N = 16
    ka = np.array([0.0, 0.3, 5.2, 7.9, 15.6, 3.0, np.inf], dtype=np.float32)
    kb = np.array([0.2, 4.0, 5.2, 12.1, 15.9, 2.0, -np.inf], dtype=np.float32)
    first, end = (np.asarray(v) for v in light_module._slab_range(mi, dr, mi.Float(ka), mi.Float(kb), N))
    for a, b, f, e in zip(ka, kb, first, end):
        if a > b:
            assert e == f
            continue
        for k in range(N):
            reaches = (k + 1.0 >= a) and (k - 1.0 <= b)  # halves and offsets: within one slice unit of k
            if reaches:
                assert f <= k < e, (a, b, k, f, e)


def test_eye_pass_skipping_clear_air_gives_the_same_image(storm):
    """The "multiple" model's light pass is not differentiated, so a differentiable renderer's frame differs
    only by its eye pass, which visits every sample with the light model and the eye's texture."""
    vol, spec = storm
    mode = SliceMode("per_species", "multiple")
    images = [SliceRenderer(vol, mode, slices=32, light_res=32, differentiable=d).frame(spec).radiance
              for d in (False, True)]
    assert np.isfinite(images[0]).all() and images[0].max() > 0
    np.testing.assert_array_equal(images[0], images[1])
