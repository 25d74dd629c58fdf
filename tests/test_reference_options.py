"""The reference renderer's estimator options declared once (``weather_mi.reference.options``): every field
enters the checkpoint fingerprint or says why not, ``render_reference``'s keywords and the flags of
``weather-mi render`` are the declared fields, and what is derived from them (the resolved defaults, the
metadata, the kernel's keywords) follows the declarations.

The fingerprint test perturbs each declared field in turn, whatever fields there are: a field added
later is covered without a change here."""
from __future__ import annotations

import dataclasses
import inspect
import typing
from dataclasses import dataclass

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.cli import commands as cli
from weather_mi.reference import render as reference
from weather_mi.reference.passes import plan_passes
from weather_mi.reference.options import (FIELD_DEFAULT, VALUE, ReferenceOptions, declared, flag_values, option,
    unexplained_keys)

from test_reference import cloud_volume, spec

NOT_ESTIMATOR = {"spec", "vol", "options", "checkpoint", "resume", "progress", "variant", "client",
                 "worker_variant", "on_pass"}
# the estimator's flags of `weather-mi render` before the options were declared once: kept as they were
# (a field declared later may add its own)
RENDER_FLAGS = {"--spp": "spp", "--integrator": "integrator", "--target-rse": "target_rse",
                "--max-seconds": "max_seconds", "--sun-guiding": "sun_guiding", "--forward-peak": "forward_peak_deg",
                "--aureole-nee": "aureole_nee"}


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
    hint = typing.get_type_hints(ReferenceOptions)[f.name]
    base = [t for t in (typing.get_args(hint) or (hint,)) if t is not type(None)][0]
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
    for f, d in declared():
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


def test_a_field_out_of_the_fingerprint_without_a_reason_is_caught():
    assert unexplained_keys() == []

    @dataclass(frozen=True)
    class Options:
        a: int = option(1, "enters the fingerprint")
        b: int = option(1, "out of it, no reason", key=None)
        c: int = option(1, "out of it", key=None, key_reason="speed only")
        d: int = option(1, "in part, no reason", key=lambda v: v > 0)
    assert unexplained_keys(Options) == ["b", "d"]


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

def test_render_reference_takes_exactly_the_declared_fields():
    params = inspect.signature(wm.render_reference).parameters
    estimator = {n: p for n, p in params.items() if n not in NOT_ESTIMATOR}
    fields = {f.name: (f, d) for f, d in declared()}
    assert list(estimator) == list(fields)
    for name, p in estimator.items():
        f, d = fields[name]
        assert p.default == f.default
        assert p.kind == (p.POSITIONAL_OR_KEYWORD if d.positional else p.KEYWORD_ONLY)
    assert [n for n, p in params.items() if p.kind == p.POSITIONAL_OR_KEYWORD] == ["spec", "vol", "spp", "max_depth"]
    doc = wm.render_reference.__doc__
    assert all(f"    {name} : " in doc for name in fields) and "<ReferenceOptions" not in doc


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
    assert {f.name for f, _ in declared()} <= set(meta)
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


def test_render_flags_are_the_declared_fields():
    parser = _subparser("render")
    fields = {f.name: (f, d) for f, d in declared()}
    flagged = {d.flag.name: f.name for f, d in declared() if d.flag is not None}
    assert RENDER_FLAGS.items() <= flagged.items()  # today's flags kept: names and destinations
    actions = {a.option_strings[0]: a for a in parser._actions if a.option_strings}
    estimator_actions = {flag: a for flag, a in actions.items() if a.dest in fields}
    assert {flag: a.dest for flag, a in estimator_actions.items()} == flagged
    for flag, a in estimator_actions.items():
        f, d = fields[a.dest]
        assert a.help == d.flag.help and a.metavar == d.flag.metavar
        assert a.default == (f.default if d.flag.default == FIELD_DEFAULT else d.flag.default)
        if d.choices is not None:
            assert tuple(a.choices) == tuple(c for c in d.choices if c is not None)
    assert actions["--spp"].type is int and actions["--spp"].default == 64
    assert actions["--forward-peak"].type is float and actions["--integrator"].choices == ("majorant", "volpath")
    args = parser.parse_args(["--demo", "cumulus", "--spp", "3", "--forward-peak", "1.5", "--aureole-nee", "0.2",
                              "--integrator", "volpath", "--target-rse", "0.1", "--max-seconds", "9",
                              "--sun-guiding", "0.05"])
    assert ReferenceOptions(**flag_values(args)) == ReferenceOptions(
        spp=3, forward_peak_deg=1.5, aureole_nee=0.2, integrator="volpath", target_rse=0.1, max_seconds=9.0,
        sun_guiding=0.05)


def test_satellite_flags_come_from_the_declarations():
    actions = {a.option_strings[0]: a for a in _subparser("satellite")._actions if a.option_strings}
    for flag, name in (("--spp", "spp"), ("--target-rse", "target_rse"), ("--max-seconds", "max_seconds")):
        assert actions[flag].dest == name
    assert actions["--spp"].default == 64 and actions["--spp"].type is int
    assert not {"--integrator", "--forward-peak", "--aureole-nee", "--sun-guiding"} & set(actions)


def test_animate_flags_come_from_the_declarations_with_its_own_spp():
    parser = _subparser("animate")
    actions = {a.option_strings[0]: a for a in parser._actions if a.option_strings}
    fields = dict(declared())
    for flag, name in (("--spp", "spp"), ("--target-rse", "target_rse"), ("--max-seconds", "max_seconds")):
        d = next(d for f, d in fields.items() if f.name == name)
        assert actions[flag].dest == name and actions[flag].help == d.flag.help
    assert actions["--spp"].default == 16 and actions["--spp"].type is int  # a frame of a loop: fewer samples
    args = parser.parse_args(["a.nc", "--renderer", "reference", "--spp", "4", "--target-rse", "0.2"])
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
