"""A slicer frame reads its declared inputs alone (weather_mi/slicing/frame_inputs.py): kernels that read a
per-frame value of the renderer fail, recorded or traced; so does a per-frame value declared a constant;
and the premise: without the guard, a recorded frame replays such a value stale, without an error."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.slicing import MODES, SliceParams, SliceRenderer
from weather_mi.slicing import frame_inputs
from weather_mi.slicing.frame_inputs import KERNEL_CONSTANTS, FrameInputError

from test_slicing_frames import spec_at, vol  # noqa: F401  (the module's storm and views)

MODE = MODES["per-species/multiple"]


EYE_PASS = SliceRenderer._eye_pass


def eye_pass_reads(monkeypatch, name):
    """Make the eye pass scale its radiance by renderer.<name>, as a kernel that took a per-frame value
    (a new slider's, say) from the renderer instead of from its inputs would."""
    eye_pass = EYE_PASS

    def leaky(self, inputs):
        out, transmittance = eye_pass(self, inputs)
        return out * getattr(self, name), transmittance
    monkeypatch.setattr(SliceRenderer, "_eye_pass", leaky)


class Unguarded:
    """The renderer itself as its kernels' view: no guard (as before FrameInputs)."""

    def __init__(self, renderer):
        self._r = renderer

    def check(self, owner):
        pass

    def __getattr__(self, name):
        return getattr(self._r, name)


@pytest.mark.parametrize("way", ["recorded", "traced", "arrays"])
@pytest.mark.parametrize("name", ["gain", "_texture_key", "views"])
def test_a_frame_that_reads_a_value_not_among_its_inputs_fails(vol, monkeypatch, way, name):
    eye_pass_reads(monkeypatch, name)
    r = SliceRenderer(vol, MODE, slices=24, light_res=16)
    r.frozen = way == "recorded"
    r.gain = 2.0  # a per-frame value kept on the renderer
    spec = spec_at(vol, 0)
    with pytest.raises(FrameInputError, match=rf"renderer\.{name}\b"):
        r.frame(spec, return_arrays=way == "arrays")
    # (a recording that raised is dropped: the renderer renders on once the kernels are fixed)
    monkeypatch.setattr(SliceRenderer, "_eye_pass", EYE_PASS)
    np.testing.assert_array_equal(r.frame(spec).radiance,
                                  SliceRenderer(vol, MODE, slices=24, light_res=16).frame(spec).radiance)


def test_a_frame_that_failed_while_recorded_leaves_no_cycle(vol, monkeypatch):
    """The renderer of a frame whose recording raised is freed by reference counting, not left in cyclic
    garbage: a garbage collection that frees recordings inside another recording aborts the process."""
    import gc
    import weakref
    eye_pass_reads(monkeypatch, "gain")
    r = SliceRenderer(vol, MODE, slices=24, light_res=16)
    r.gain = 2.0
    gc.collect()
    gc.disable()
    try:
        with pytest.raises(FrameInputError) as info:
            r.frame(spec_at(vol, 0))
        alive = weakref.ref(r)
        del r, info
        assert alive() is None, "the renderer of a failed recording is kept alive by a reference cycle"
    finally:
        gc.enable()


def test_without_the_guard_a_recorded_frame_replays_a_per_frame_value_stale(vol, monkeypatch):
    """The premise of the guard (Dr.Jit 1.5's dr.freeze): should this fail, Dr.Jit catches such reads."""
    eye_pass_reads(monkeypatch, "gain")
    recorded, traced = (SliceRenderer(vol, MODE, slices=24, light_res=16) for _ in range(2))
    traced.frozen = False
    for r in (recorded, traced):
        monkeypatch.setattr(r, "_constants", Unguarded(r))
        r.gain = 1.0
    spec = spec_at(vol, 0)
    for i in range(3):  # recorded (textures rebuilt every frame: one structure)
        recorded.frame(spec, SliceParams(scale={"ice": 1.0 + 0.1 * i}))
    n = recorded._frozen_kernels.n_recordings
    recorded.gain = traced.gain = 2.0
    p = SliceParams(scale={"ice": 1.5})
    a, b = recorded.frame(spec, p).radiance, traced.frame(spec, p).radiance
    assert recorded._frozen_kernels.n_recordings == n  # replayed, not traced
    assert b.max() > 0
    np.testing.assert_allclose(2.0 * a, b, rtol=1e-6)  # the replay kept gain = 1


def test_the_kernels_see_the_declared_constants_alone(vol):
    r = SliceRenderer(vol, MODE, slices=24, light_res=16)
    r.frame(spec_at(vol, 0))
    view = r._constants
    for name in vars(r):
        if name in KERNEL_CONSTANTS:
            assert getattr(view, name) is getattr(r, name)
        else:
            with pytest.raises(FrameInputError):
                getattr(view, name)
    assert view._eye_pass.__self__ is view  # methods read the renderer through the view too
    with pytest.raises(FrameInputError):
        view.slices = 12


@pytest.mark.parametrize("name", ["_texture_key", "_last", "timing"])
def test_a_per_frame_value_declared_a_constant_fails(vol, monkeypatch, name):
    """Reassigned (_texture_key, timing) or changed in place (_last, a cache): caught at the frame."""
    monkeypatch.setattr(frame_inputs, "KERNEL_CONSTANTS", KERNEL_CONSTANTS + (name,))
    r = SliceRenderer(vol, MODE, slices=24, light_res=16)
    with pytest.raises(FrameInputError, match=rf"renderer\.{name} changed"):
        for i in range(2):
            r.frame(spec_at(vol, i), SliceParams(scale={"ice": 1.0 + i}))
