"""The atmosphere on by default in ``render`` (issue 38): ``--atmosphere clear`` and with it ``--sky air`` unless
given; ``none`` and the sky model where the integrator's own sun is absent (``--integrator volpath``), and in
the other commands. The library's ``SceneSpec`` keeps ``atmosphere=None``."""
from __future__ import annotations

import pytest

from weather_mi.cli import air_option
from weather_mi.cli.commands import build_parser


def _resolved(argv):
    args = build_parser().parse_args(argv)
    air_option.resolve(args)
    return args.atmosphere, args.sky


@pytest.mark.parametrize("argv, expect", [
    (["render", "--demo", "cumulus"], ("clear", "air")),
    (["render", "--demo", "cumulus", "--atmosphere", "none"], ("none", "sunsky")),
    (["render", "--demo", "cumulus", "--sky", "sunsky"], ("clear", "sunsky")),
    (["render", "--demo", "cumulus", "--integrator", "volpath"], ("none", "sunsky")),
    (["animate", "wrfout.nc"], ("none", "sunsky")),
])
def test_render_has_the_atmosphere_on_by_default(argv, expect):
    assert _resolved(argv) == expect


def test_the_library_default_stays_without_air():
    import weather_mi as wm
    assert wm.SceneSpec.__dataclass_fields__["atmosphere"].default is None


def test_the_default_render_puts_the_air_on_its_eye_rays_after_releasing_the_volume(tmp_path):
    """``render``'s defaults end to end: the volume's grids are released as the kernel's are built
    (``release_volume=True``), yet the eye rays' air, whose storm shadow reads the extinction, is on the image
    (computed before the render): the metadata counts the pixels it changed."""
    from weather_mi.cli.commands import main
    from weather_mi.io.image import Image
    common = ["render", "--demo", "cumulus", "--size", "24x16", "--spp", "2", "--no-denoise"]
    assert main([*common, "-o", str(tmp_path / "air.exr")]) == 0
    assert main([*common, "--atmosphere", "none", "--sky", "sunsky", "-o", str(tmp_path / "none.exr")]) == 0
    air, none = Image.load(tmp_path / "air.exr"), Image.load(tmp_path / "none.exr")
    assert air.metadata["eye_air"]["pixels_changed"] > 0
    assert air.radiance.mean() != none.radiance.mean()
    assert (air.radiance > 0).all()
