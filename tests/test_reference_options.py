"""The reference renderer's estimator options declared once (``weather_mi.reference.options``): every field
enters the checkpoint fingerprint or says why not, ``render_reference``'s keywords and the flags of
``weather-mi render``, ``satellite`` and ``animate`` are today's (written out here, not derived from the
declarations), and what is derived from them (the resolved defaults, the metadata, the kernel's keywords)
follows the declarations.

The fingerprint test perturbs each declared field in turn, whatever fields there are: a field added
later is covered without a change here."""
from __future__ import annotations

import dataclasses
import inspect

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.cli import commands as cli
from weather_mi.reference import render as reference
from weather_mi.reference.passes import plan_passes
from weather_mi.reference.options import BASE_TYPES, DECLARED, VALUE, ReferenceOptions, flag_values

from test_reference import cloud_volume, spec

NOT_ESTIMATOR = {"spec", "vol", "options", "checkpoint", "resume", "progress", "variant", "client",
                 "worker_variant", "on_pass", "release_volume"}
# Written out, not derived from the declarations (a test comparing the declarations with what they generate
# cannot fail): a flag or keyword dropped, renamed or given another default is a change of the interface.
# The estimator's flags of `weather-mi render`: {flag: (dest, type, default, choices, metavar)}
RENDER_FLAGS = {"--spp": ("spp", int, 64, None, None),
                "--integrator": ("integrator", None, "majorant", ("majorant", "volpath"), None),
                "--target-rse": ("target_rse", float, None, None, None),
                "--max-seconds": ("max_seconds", float, None, None, None),
                "--target-pixels": ("target_pixels", None, "cloud", ("cloud", "all"), None),
                "--sun-guiding": ("sun_guiding", float, None, None, None),
                "--forward-peak": ("forward_peak_deg", float, None, None, "DEG"),
                "--aureole-nee": ("aureole_nee", float, None, None, "P")}
# `weather-mi satellite` and `animate --renderer reference` (a frame of a loop: fewer samples)
SATELLITE_FLAGS = {"--spp": ("spp", int, 64), "--target-rse": ("target_rse", float, None),
                   "--max-seconds": ("max_seconds", float, None)}
ANIMATE_FLAGS = {**SATELLITE_FLAGS, "--spp": ("spp", int, 16)}
# render_reference's estimator parameters: {name: default}; spp and max_depth also by position
RENDER_REFERENCE_OPTIONS = {"spp": 256, "max_depth": -1, "integrator": "majorant", "legacy": False, "passes": None,
                            "normalize": None, "rr_depth": None, "cell": None, "target_rse": None,
                            "max_seconds": None, "target_pixels": "cloud", "sun_guiding": None, "forward_peak_deg": None,
                            "aureole_nee": None, "mvnee": None}


@pytest.fixture(scope="module")
def vol():
    return cloud_volume()


def key(sp, vol, o: ReferenceOptions) -> str:
    """The checkpoint fingerprint of a render of ``sp``, ``vol`` with the (unresolved) options ``o``."""
    r = o.resolved(sp)
    return reference._render_key(sp, vol, plan_passes(sp, r.spp, r.passes), r, None)


def candidates(f: dataclasses.Field, d) -> list:
    """Values to perturb a field with: its choices, the other bool, a few numbers of its type."""
    if d.choices is not None:
        return list(d.choices)
    base = BASE_TYPES[f.name]
    if base is bool:
        return [True, False]
    if base is int:
        return [1, 2, 3, 7, 100, -1]
    if base is float:
        return [0.25, 0.5, 0.1, 1.0, 2.0, 10.0]
    return ["other"]


# ---------------------------------------------------------------- the checkpoint fingerprint

def test_each_field_changes_the_fingerprint_or_is_declared_out_of_it_with_a_reason(vol):
    """Perturb every declared field in turn (to each of a few valid values): the fingerprint changes, unless
    the field declares why its value stays out of it (then it must not change)."""
    sp = spec(seed=3)  # a point sun: every integrator and ``legacy`` render it
    base = ReferenceOptions(spp=8)
    base_key, base_resolved = key(sp, vol, base), base.resolved(sp)
    for f, d in DECLARED:
        changes = []  # for each valid value other than the default: whether the fingerprint changed
        for value in candidates(f, d):
            o = dataclasses.replace(base, **{f.name: value})
            try:
                r = o.resolved(sp)
            except ValueError:  # not valid with the others at their defaults
                continue
            if r != base_resolved:
                changes.append(key(sp, vol, o) != base_key)
        assert changes, f"no valid value found to perturb {f.name} with: extend candidates()"
        if d.key is None:
            assert d.key_reason.strip(), f"{f.name} is out of the fingerprint without a reason"
            assert not any(changes), f"{f.name} is declared out of the fingerprint, yet changes it"
        elif d.key == VALUE:
            assert all(changes), f"a value of {f.name} renders another image but resumes this render's checkpoint"
        else:  # in part (a function of the value)
            assert d.key_reason.strip(), f"{f.name} enters the fingerprint only in part without a reason"
            assert any(changes), f"no value of {f.name} changes the fingerprint"


def test_a_checkpoint_resumes_with_the_same_resolved_options_and_refuses_others(vol, tmp_path, monkeypatch):
    sp, ckpt = spec(seed=4), tmp_path / "a.npz"
    wm.render_reference(sp, vol, spp=2, passes=2, progress=False, checkpoint=ckpt)
    for name in ("render_pass", "render_passes"):  # resuming a finished render renders nothing
        monkeypatch.setattr(wm.reference.passes, name, lambda *a, **k: pytest.fail("rendered a pass of a finished render"))
    same = ReferenceOptions(spp=2, passes=2, sun_guiding=0.0, forward_peak_deg=3.0, mvnee=0.0)  # the defaults
    img = wm.render_reference(sp, vol, options=same, progress=False, checkpoint=ckpt, resume=True)
    assert img.metadata["passes"] == 2
    for other in ({"aureole_nee": 0.3}, {"mvnee": 0.3}, {"forward_peak_deg": 1.0}, {"max_depth": 4},
                  {"normalize": "reflectance"}, {"target_rse": 0.5}, {"legacy": True}):
        with pytest.raises(ValueError, match="different scene"):
            wm.render_reference(sp, vol, spp=2, passes=2, progress=False, checkpoint=ckpt, resume=True, **other)


# ---------------------------------------------------------------- render_reference's keywords

def test_render_reference_takes_todays_options():
    params = inspect.signature(wm.render_reference).parameters
    estimator = {n: p for n, p in params.items() if n not in NOT_ESTIMATOR}
    assert {n: p.default for n, p in estimator.items()} == RENDER_REFERENCE_OPTIONS
    assert [n for n, p in params.items() if p.kind == p.POSITIONAL_OR_KEYWORD] == ["spec", "vol", "spp", "max_depth"]
    assert all(p.kind == p.KEYWORD_ONLY for n, p in estimator.items() if n not in ("spp", "max_depth"))
    doc = wm.render_reference.__doc__
    assert all(f"    {name} : " in doc for name in RENDER_REFERENCE_OPTIONS) and "<ReferenceOptions" not in doc


def test_render_reference_refuses_another_keyword_before_rendering(no_rendering_anywhere):
    sp, v = spec(), cloud_volume()
    with pytest.raises(TypeError, match="unexpected keyword argument 'spectral_samples'"):
        wm.render_reference(sp, v, spp=2, spectral_samples=4)
    with pytest.raises(TypeError, match="multiple values for argument 'spp'"):
        wm.render_reference(sp, v, 2, spp=2)
    with pytest.raises(TypeError, match="positional"):
        wm.render_reference(sp, v, 2, -1, "volpath")
    with pytest.raises(TypeError, match="ReferenceOptions"):
        wm.render_reference(sp, v, options={"spp": 2})


@pytest.fixture
def no_rendering_anywhere(monkeypatch):
    for name in ("render_pass", "render_passes"):
        monkeypatch.setattr(wm.reference.passes, name, lambda *a, **k: pytest.fail("a pass was rendered"))


def test_options_keywords_and_positions_give_the_same_render(vol):
    """``options=ReferenceOptions(...)``, keywords and positions are one call; keywords replace fields of
    ``options``; the metadata records every field."""
    sp = spec(seed=5)
    by_keyword = wm.render_reference(sp, vol, spp=4, max_depth=3, passes=2, progress=False)
    by_position = wm.render_reference(sp, vol, 4, 3, passes=2, progress=False)
    by_options = wm.render_reference(sp, vol, options=ReferenceOptions(spp=4, max_depth=3, passes=2), progress=False)
    replaced = wm.render_reference(sp, vol, options=ReferenceOptions(spp=64, max_depth=3, passes=2), spp=4,
                                   progress=False)
    for img in (by_position, by_options, replaced):
        assert np.array_equal(img.radiance, by_keyword.radiance) and np.array_equal(img.stderr, by_keyword.stderr)
    meta = by_options.metadata
    assert set(RENDER_REFERENCE_OPTIONS) <= set(meta)
    assert meta["max_depth"] == 3 and meta["passes"] == 2 and meta["spp"] == 4 and meta["forward_peak_deg"] == 3.0


# ---------------------------------------------------------------- what is derived

def test_resolved_defaults_follow_the_other_options():
    point = spec()
    plain = ReferenceOptions(spp=8).resolved(point)
    assert (plain.sun_guiding, plain.aureole_nee, plain.mvnee, plain.forward_peak_deg) == (0.0, 0.0, 0.0, 3.0)
    assert plain.passes == 8 and plain.own_sun
    legacy = ReferenceOptions(legacy=True).resolved(point)
    assert legacy.forward_peak_deg == 0.0 and not legacy.own_sun
    assert legacy.metadata()["sun_guiding"] is None and legacy.metadata()["legacy"] is True
    assert ReferenceOptions(integrator="volpath").resolved(point).metadata()["cell"] is None
    disk = spec(sun=wm.Sun(200.0, 40.0))
    for bad, message in (({"integrator": "volpath"}, "renders the sun as a point"),
                         ({"legacy": True}, "renders the sun as a point"), ({"spp": 2.5}, "spp must be"),
                         ({"sun_guiding": 0.2, "mvnee": 0.1}, "mvnee needs"), ({"target_rse": 0.0}, "target_rse"),
                         ({"forward_peak_deg": -1.0}, "forward_peak_deg")):
        with pytest.raises(ValueError, match=message):
            ReferenceOptions(**bad).resolved(disk)


def test_kernel_options_are_integrator_dict_keywords():
    from weather_mi.kernel.scene_dict import integrator_dict
    kernel = ReferenceOptions().resolved(spec()).kernel_options()
    assert kernel and set(kernel) <= set(inspect.signature(integrator_dict).parameters)


# ---------------------------------------------------------------- the command line

def _subparser(command: str):
    return cli.build_parser().commands[command]


def _estimator_actions(command: str) -> dict:
    """{flag: argparse action} of the options of ``command`` whose destination is an estimator option."""
    return {a.option_strings[0]: a for a in _subparser(command)._actions
            if a.option_strings and a.dest in RENDER_REFERENCE_OPTIONS}


def test_render_flags_are_todays():
    actions = _estimator_actions("render")
    assert {flag: (a.dest, a.type, a.default, None if a.choices is None else tuple(a.choices), a.metavar)
            for flag, a in actions.items()} == RENDER_FLAGS
    args = _subparser("render").parse_args(
        ["--demo", "cumulus", "--spp", "3", "--forward-peak", "1.5", "--aureole-nee", "0.2", "--integrator", "volpath",
         "--target-rse", "0.1", "--max-seconds", "9", "--sun-guiding", "0.05"])
    assert ReferenceOptions(**flag_values(args)) == ReferenceOptions(
        spp=3, forward_peak_deg=1.5, aureole_nee=0.2, integrator="volpath", target_rse=0.1, max_seconds=9.0,
        sun_guiding=0.05)


def test_satellite_and_animate_flags_are_todays():
    for command, expected in (("satellite", SATELLITE_FLAGS), ("animate", ANIMATE_FLAGS)):
        actions = _estimator_actions(command)
        assert {flag: (a.dest, a.type, a.default) for flag, a in actions.items()} == expected, command
    args = _subparser("animate").parse_args(["a.nc", "--renderer", "reference", "--spp", "4", "--target-rse", "0.2"])
    assert flag_values(args, cli.ANIMATE_ESTIMATOR) == {"spp": 4, "target_rse": 0.2, "max_seconds": None}


def test_render_passes_the_flags_to_render_reference(tmp_path, monkeypatch, capsys):
    """``weather-mi render`` hands render_reference the options of its flags."""
    from weather_mi.io.image import Image
    seen = {}

    def render(spec, vol, **kw):
        seen.update(kw)
        rad = np.full((spec.height, spec.width, 3), 0.5, np.float32)
        return Image(rad, np.full_like(rad, 0.01), {"spp": 1, "seconds": 0.0, "noise": None})
    monkeypatch.setattr(reference, "render_reference", render)
    rc = cli.main(["render", "--demo", "cumulus", "--size", "8x6", "--spp", "3", "--forward-peak", "1",
                   "--no-denoise", "-o", str(tmp_path / "a.exr")])
    assert rc == 0, capsys.readouterr().err
    assert seen["options"] == ReferenceOptions(spp=3, forward_peak_deg=1.0)
