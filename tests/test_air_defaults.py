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
