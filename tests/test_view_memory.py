"""What ``weather-mi view`` no longer holds or copies (issue 39: bytes per grid cell): the optics without their
Eq. 8 weights grid, the viewer's Hydrometeors without their effective radii, the slicer's grids the volume's own
memory, and the eye's texture unpadded (power-of-two channel textures, the same trilinear values)."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.slicing import MODES, SliceRenderer
from weather_mi.slicing.texture_storage import ChannelTextures, power_of_two_parts, replace_storage


def cumulus_with_radii(seed=1):
    hyd = wm.synthetic.cumulus()
    rng = np.random.default_rng(seed)
    for s in wm.SPECIES_NAMES:  # per-voxel radii, as a scheme's (10-500 um)
        hyd[f"r_eff_{s}"] = hyd[f"q_{s}"].copy(data=rng.uniform(1e-5, 5e-4, hyd[f"q_{s}"].shape).astype(np.float32))
    return hyd


def test_power_of_two_parts():
    assert [power_of_two_parts(c) for c in range(1, 8)] == [[1], [2], [2, 1], [4], [4, 1], [4, 2], [4, 2, 1]]


def test_volume_without_weights_and_radii_released():
    """``keep=("beta_ext",)`` never builds the weights grid (``mixture_kernels.voxel_optics``): the other grids are those of a volume that keeps them, bit for bit; ``release=("r_eff",)`` drops the
    radii from the dataset and keeps the mixing ratios (the viewer's read-out needs them)."""
    import weather_mi.optics.volume as volume
    hyd = cumulus_with_radii()
    whole = wm.optical_volume(hyd.copy(), "physical", sizes="scheme", phase_quality="test")
    vol = wm.optical_volume(hyd, "physical", sizes="scheme", phase_quality="test", keep=("beta_ext",),
                            release=("r_eff",))
    for name in ("beta_ext", "beta_total", "albedo"):
        np.testing.assert_array_equal(getattr(vol, name), getattr(whole, name))
    assert isinstance(vol.weights, volume.ReleasedGrid) and vol.weights.shape == whole.weights.shape
    assert not [v for v in hyd.data_vars if v.startswith("r_eff_")]
    assert all(f"q_{s}" in hyd for s in wm.SPECIES_NAMES)


def test_channel_textures_read_as_one_padded_texture():
    """6 channels as textures of 4 and 2 give the trilinear values of one 6-channel texture (Dr.Jit's, padded to
    8), bit for bit, at points inside and outside the grid; each part stores its channels unpadded."""
    import mitsuba as mi
    from weather_mi.kernel.variant import ensure_registered
    ensure_registered()
    rng = np.random.default_rng(3)
    shape, C = (5, 6, 7), 6
    data = rng.random(shape + (C,), dtype=np.float32)
    one = mi.Texture3f(mi.TensorXf(data), use_accel=False)
    split = ChannelTextures.zeros(lambda t: mi.Texture3f(t, use_accel=False), mi, C)
    replace_storage(mi, [(split, [mi.Float(np.ascontiguousarray(data[..., c]).ravel()) for c in range(C)])], shape)
    assert [int(t.shape[-1]) for t in split.parts] == [4, 2] and split.channels == C
    assert [int(np.asarray(t.value()).size) for t in split.parts] == [4 * data[..., 0].size, 2 * data[..., 0].size]
    p = rng.uniform(-0.2, 1.2, (3, 500)).astype(np.float32)
    tc = mi.Point3f(*(mi.Float(v) for v in p))
    a, b = one.eval(tc), split.eval(tc)
    assert len(b) == C
    for c in range(C):
        np.testing.assert_array_equal(np.asarray(b[c]), np.asarray(a[c]))


@pytest.mark.parametrize("mode", ["per-species/multiple", "per-species/translucent"])
def test_slicer_reads_the_volumes_grids_without_copies(mode):
    """The slicer's per-species grids are the volume's own float32 memory (no (z, y, x, S) copy), and after a frame
    its eye texture is power-of-two parts holding the groups' beta_sca alone."""
    vol = wm.optical_volume(wm.synthetic.cumulus(), phase_quality="test")
    r = SliceRenderer(vol, MODES[mode], slices=16, light_res=16)
    for s in range(len(vol.species)):
        assert np.shares_memory(r.beta_s[s].numpy(), vol.beta_ext[s])
    r.frame(wm.scene.spec.default_spec(vol, 24, 18))
    channels = [int(t.shape[-1]) for t in r.tex_eye.parts]
    assert sum(channels) == len(r.groups)  # beta_sca per group; beta is the light source's first channel
    assert all(c & (c - 1) == 0 for c in channels)
    assert tuple(r.tex_eye.parts[0].shape[:3]) == r.shape
