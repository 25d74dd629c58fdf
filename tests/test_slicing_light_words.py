"""Translucent light stored as one 64-bit word a texel-plane (``slicing/light_slabs.py``): the same floats as the
two-float store, bit for bit."""
from __future__ import annotations

import numpy as np

import weather_mi as wm


def test_a_pair_of_floats_comes_back_bit_for_bit_from_its_word():
    """``pair_word`` / ``word_pair`` against numpy's own bits: the light's logarithms (0, the floor, -0.0,
    denormals, the extremes) in either half, and the halves not swapped."""
    from weather_mi.kernel.variant import ensure_registered
    ensure_registered()
    import drjit as dr
    import mitsuba as mi
    from weather_mi.slicing.light_slabs import LOG_FLOOR, pair_word, word_pair
    special = np.array([0.0, -0.0, LOG_FLOOR, -1e-45, 1e-45, -3.4e38, 3.4e38, -1.5, 2.0 ** -126], np.float32)
    rng = np.random.default_rng(38)
    a = np.concatenate([special, rng.uniform(-70.0, 0.0, 500).astype(np.float32), special[::-1]])
    b = np.concatenate([special[::-1], rng.uniform(-70.0, 0.0, 500).astype(np.float32), special])
    words = pair_word(mi, dr, mi.Float(a), mi.Float(b))
    expect = a.view(np.uint32).astype(np.uint64) | (b.view(np.uint32).astype(np.uint64) << np.uint64(32))
    np.testing.assert_array_equal(np.asarray(words), expect)
    back = word_pair(mi, dr, words)
    np.testing.assert_array_equal(np.asarray(back[0]).view(np.uint32), a.view(np.uint32))
    np.testing.assert_array_equal(np.asarray(back[1]).view(np.uint32), b.view(np.uint32))


def test_translucent_frames_are_the_same_with_the_light_in_words():
    """A drag of the demo supercell in a translucent mode (the eye pass's light and the air's shadow read from
    the light volume), with and without the clear atmosphere: the frames of a renderer whose light volumes store
    2 floats a texel-plane and of one that stores words are identical."""
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
    import slicing as drag
    from weather_mi.optics.air import Atmosphere
    from weather_mi.slicing import MODES, SliceRenderer
    from weather_mi.slicing import light as light_module
    storm = wm.synthetic.supercell(shape=(20, 48, 48), spacing_m=(1000.0, 2000.0, 2000.0))
    vol = wm.optical_volume(storm, species="physical")
    init = light_module.LightVolume.__init__
    frames = {}
    try:
        for words in (False, True):
            def made(self, *a, _words=words, **k):
                init(self, *a, **k)
                self.words = self.words and _words
            light_module.LightVolume.__init__ = made
            r = SliceRenderer(vol, MODES["uniform/translucent"], slices=32, light_res=32)
            assert r.light.words is words
            out = []
            for i, atm in enumerate((None, Atmosphere(), Atmosphere())):
                drag.ATMOSPHERE = atm
                spec, params = drag.moving_view(vol, 112, 96, "drag", i)
                rad, tr = r.frame(spec, params, return_arrays=True)
                out.append(np.concatenate([np.asarray(rad).ravel(), np.asarray(tr).ravel()]))
            frames[words] = out
    finally:
        light_module.LightVolume.__init__ = init
        drag.ATMOSPHERE = None
    for a, b in zip(frames[False], frames[True]):
        assert np.any(a != 0)
        np.testing.assert_array_equal(a, b)
