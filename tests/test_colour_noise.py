"""The colour-noise figures of ``reference.colour_noise`` (issue 38: the spectral mode's chroma noise and
fireflies) against numbers computed here independently: the spread of replicate renders, colour-science's
(u', v'), planted fireflies."""
from __future__ import annotations

import numpy as np
import pytest

from weather_mi.reference import colour_noise as cn


def _running_means(passes):
    return [passes[: i + 1].mean(axis=0) for i in range(len(passes))]


def test_pass_images_recovers_the_passes_from_running_means():
    rng = np.random.default_rng(0)
    passes = rng.random((6, 4, 5, 3))
    assert np.allclose(cn.pass_images(_running_means(passes)), passes, atol=1e-12)


def test_channel_rse_is_each_channels_standard_error_over_its_mean():
    rng = np.random.default_rng(1)
    mean, sd, n = np.array([2.0, 1.0, 0.5]), np.array([0.2, 0.05, 0.04]), 8
    passes = mean + sd * rng.standard_normal((n, 64, 64, 3))
    cloud = np.ones((64, 64), bool)
    got = cn.channel_rse(passes, cloud)
    # E[sample sd] = c4 sd; c4(8) = 0.9650 (the unbiasing constant of the normal sample sd)
    want = 0.9650 * sd / np.sqrt(n) / mean
    assert got == pytest.approx(want, rel=0.03)
    cloud[:32] = False  # only the cloud pixels count
    passes[:, :32] *= 10.0
    assert cn.channel_rse(passes, cloud) == pytest.approx(want, rel=0.05)


def test_chroma_se_is_the_spread_of_replicate_renders_chromaticity():
    """The delta-method se of (u', v') of an 8-pass mean against the standard deviation, over 4000 replicate
    renders, of colour-science's (u', v') of their means."""
    import colour
    rng = np.random.default_rng(2)
    n, reps = 8, 4000
    xyz0 = np.array([0.30, 0.32, 0.35])
    noise = np.array([0.05, 0.03, 0.12])  # X, Y, Z sd of a pass (correlated through a common factor, too)
    common = rng.standard_normal((reps, n, 1, 1)) * 0.04
    xyz = xyz0 + noise * rng.standard_normal((reps, n, 1, 1, 3)) + common[..., None] * xyz0
    rgb = np.asarray(colour.XYZ_to_RGB(
        xyz, "sRGB", illuminant=None, chromatic_adaptation_transform=None, apply_cctf_encoding=False))
    uv = np.asarray(colour.models.Luv_to_uv(colour.XYZ_to_Luv(xyz.mean(axis=1))))[:, 0, 0]  # (reps, 2)
    want = float(np.sqrt(uv[:, 0].var() + uv[:, 1].var()))
    got = np.mean([cn.chroma_se(rgb[r], np.ones((1, 1), bool)) for r in range(reps)])
    assert got == pytest.approx(want, rel=0.05)
    # grey noise (X, Y, Z scaled together) has no chroma noise
    grey = xyz0 * (1.0 + 0.3 * rng.standard_normal((n, 2, 2, 1)))
    rgb_grey = np.asarray(colour.XYZ_to_RGB(grey, "sRGB", illuminant=None, chromatic_adaptation_transform=None,
                                            apply_cctf_encoding=False))
    assert cn.chroma_se(rgb_grey, np.ones((2, 2), bool)) < 1e-12


def test_firefly_count_finds_the_planted_ones_only():
    rng = np.random.default_rng(3)
    passes = 1.0 + 0.3 * rng.standard_normal((8, 20, 30, 3))  # no pass above 3.4: none
    cloud = np.ones((20, 30), bool)
    assert cn.firefly_count(passes, cloud) == 0
    passes[3, 5, 7, 0] = 50.0   # red in one pass
    passes[6, 11, 2, 2] = 15.0  # blue, another pixel
    passes[0, 11, 2, 1] = 12.0  # the same pixel again: one pixel
    passes[2, 0, 0, 1] = 40.0   # not a cloud pixel
    cloud[0, 0] = False
    assert cn.firefly_count(passes, cloud) == 2
    assert cn.firefly_count(passes, cloud, k=20.0) == 1
    figures = cn.colour_noise(_running_means(passes), cloud)
    assert figures["fireflies"] == 2 and figures["rse_rgb"].shape == (3,) and figures["chroma_se"] > 0


def test_bad_shapes_are_refused():
    with pytest.raises(ValueError, match="passes shaped"):
        cn.channel_rse(np.zeros((1, 2, 2, 3)), np.ones((2, 2), bool))
    with pytest.raises(ValueError, match="cloud mask"):
        cn.chroma_se(np.ones((3, 2, 2, 3)), np.ones((3, 2), bool))
