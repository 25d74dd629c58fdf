"""validation/calibrate_slicer.py's evaluation of an earlier fit (--fitted) and its refusal of a bad file."""
import json

import numpy as np
import pytest

from conftest import SHARED_DATA
from validation import calibrate_slicer as cs


def test_fitted_file_is_checked(tmp_path):
    good = tmp_path / "good.json"
    good.write_text(json.dumps({"ms_extinction": 0.2, "diffusion_flux": 0.3}))
    assert cs.read_fitted(good) == {"ms_extinction": 0.2, "diffusion_flux": 0.3}
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"ms_extinction": 0.2, "no_such_parameter": 1.0}))
    with pytest.raises(SystemExit, match=r"bad\.json.*unknown: \['no_such_parameter'\]"):
        cs.read_fitted(bad)
    text = tmp_path / "text.json"
    text.write_text(json.dumps({"ms_extinction": "high"}))
    with pytest.raises(SystemExit, match=r"text\.json.*object of numbers"):
        cs.read_fitted(text)
    broken = tmp_path / "broken.json"
    broken.write_text("{")
    with pytest.raises(SystemExit, match=r"broken\.json: not a readable JSON"):
        cs.read_fitted(broken)


def test_fitted_column_is_named_after_its_file(tmp_path):
    """--fitted evaluates without fitting; its column carries the file's name (held-out storms absent here:
    the held-out table is its header)."""
    fit = tmp_path / "earlier_fit.json"
    fit.write_text(json.dumps({"ms_extinction": 0.2}))
    out = tmp_path / "out"
    assert cs.main(["-o", str(out), "--data", str(tmp_path / "no-data"), "--size", "8x6", "--spp", "2",
                    "--fitted", str(fit), "--held-out-only"]) == 0
    text = (out / "calibration.md").read_text()
    assert "| multiple (defaults) | multiple (earlier_fit) |" in text
    assert "Parameters of an earlier fit" in text and "Fitted on" not in text


DATA = SHARED_DATA
needs_data = pytest.mark.skipif(not (DATA / "wrf" / "wrfout_quarter_ss_series.nc").is_file(),
                                reason="needs ../shared/data (the WRF supercell series)")


def test_training_set_has_real_storms_at_other_times():
    """The real WRF supercell trains at 01:00 and 02:00 (its held-out view: the 01:30 file), the plateau at
    00:00 (held out: its last time, 09:00)."""
    from weather_mi.study.runs import DATA_SCENES, DATA_TIMES
    real = [s for s in cs.TRAIN_SCENES if s in DATA_SCENES]
    assert real == ["wrf-supercell-0100", "wrf-supercell-0200", "wrf-plateau-0000"]
    assert {DATA_TIMES[s] for s in real} == {"0001-01-01_01:00:00", "0001-01-01_02:00:00", "2005-09-21_00:00:00"}
    assert not {s for s, _ in cs.TRAIN} & {s for s, _ in cs.HELD_OUT}
    assert {l for s, l in cs.TRAIN if s in real} == {"front", "side", "back", "front" + cs.LOW_SUN, "side" + cs.LOW_SUN,
                                                     "front" + cs.TODAY_AIR, "side" + cs.TODAY_AIR, "back" + cs.TODAY_AIR}


def test_the_low_sun_training_views_have_the_air_and_a_low_sun():
    """Issue 38: training views with the sun at LOW_SUN_DEG and the clear atmosphere (the held-out low-sun
    table's conditions, on training storms only); the other lightings are study.runs.view's."""
    import weather_mi as wm
    from weather_mi.study.runs import StudyConfig, view
    vol = wm.OpticalVolume.from_arrays(np.full((4, 4, 4), 1e-3, np.float32), 1.0, wm.phase.henyey_greenstein(0.85),
                                       ((0.0, 0.0, 1000.0), (4e3, 4e3, 5e3)))
    cfg = StudyConfig(width=16, height=12)
    low = [(s, l) for s, l in cs.TRAIN if l.endswith(cs.LOW_SUN)]
    assert len(low) == 7 and not {s for s, _ in low} & {s for s, _ in cs.HELD_OUT}
    for lighting in ("front", "side"):
        spec = cs.view_of(vol, lighting + cs.LOW_SUN, cfg)
        assert spec.atmosphere is not None and spec.sun.elevation == pytest.approx(cs.LOW_SUN_DEG)
        assert spec.sky.kind == "air"  # the air's own sky (render's default with the air), not sunsky's
        plain = cs.view_of(vol, lighting, cfg)
        assert plain == view(vol, lighting, cfg) and plain.atmosphere is None
        assert spec.sun.azimuth == pytest.approx(plain.sun.azimuth)


def test_every_training_storm_is_also_seen_with_the_air_at_todays_sun():
    """refit38: each training storm front-, side- and back-lit at study.runs.view's own sun (35 deg, back 20 deg)
    with the clear atmosphere, as `view` shows it by default: the same view as without the air, the air added."""
    from dataclasses import replace

    import weather_mi as wm
    from weather_mi.study.runs import StudyConfig, view
    vol = wm.OpticalVolume.from_arrays(np.full((4, 4, 4), 1e-3, np.float32), 1.0, wm.phase.henyey_greenstein(0.85),
                                       ((0.0, 0.0, 1000.0), (4e3, 4e3, 5e3)))
    cfg = StudyConfig(width=16, height=12)
    today = [(s, l) for s, l in cs.TRAIN if l.endswith(cs.TODAY_AIR) and not l.endswith(cs.LOW_SUN)]
    assert sorted(today) == sorted((s, l + cs.TODAY_AIR) for s in cs.TRAIN_SCENES for l in ("front", "side", "back"))
    for lighting, elevation in (("front", 35.0), ("side", 35.0), ("back", 20.0)):
        spec = cs.view_of(vol, lighting + cs.TODAY_AIR, cfg)
        assert spec.atmosphere is not None and spec.sun.elevation == pytest.approx(elevation)
        plain = view(vol, lighting, cfg)
        assert spec.sky.kind == "air" and plain.sky.kind == "sunsky"  # the air's own sky: not counted twice
        assert replace(spec, atmosphere=None, sky=plain.sky) == plain


@needs_data
def test_no_held_out_field_is_trained_on(monkeypatch):
    """Every training field differs from every held-out one: by file and time, and by content (the held-out
    01:30 supercell is also the series file's third time). The check refuses a training scene that is the
    01:30 field read from the series file, and one that is a held-out scene itself."""
    train = {cs.field_of(s, DATA) for s, _ in cs.TRAIN} - {None}
    held = {cs.field_of(s, DATA) for s, _ in cs.HELD_OUT} - {None}
    assert len(train) == 3 and len(held) == 4
    assert not {f[:2] for f in train} & {f[:2] for f in held}
    assert not {f[2] for f in train} & {f[2] for f in held}
    cs.check_held_out(cs.TRAIN, cs.HELD_OUT, DATA)  # the shipped sets pass
    from weather_mi.study import runs
    monkeypatch.setitem(runs.DATA_SCENES, "wrf-supercell-0130", ("wrf/wrfout_quarter_ss_series.nc", "01:30"))
    monkeypatch.setitem(runs.DATA_TIMES, "wrf-supercell-0130", "0001-01-01_01:30:00")
    with pytest.raises(SystemExit, match=r"wrf-supercell-0130 .* held-out field of wrf-supercell"):
        cs.check_held_out(cs.TRAIN + [("wrf-supercell-0130", "front")], cs.HELD_OUT, DATA)
    with pytest.raises(SystemExit, match=r"training scene bomex .* held-out field of bomex"):
        cs.check_held_out(cs.TRAIN + [("bomex", "back")], cs.HELD_OUT, DATA)


def test_a_reference_with_the_air_is_named_after_the_air_it_was_rendered_with():
    """Cached references with the air carry AIR_REFERENCES in their name: one rendered before the path tracer's
    per-channel Eq. 8 (the name without it) is never read as a current one; those without the air keep their
    names (still valid: the air's change does not touch them)."""
    import weather_mi as wm
    from weather_mi.study.runs import StudyConfig
    vol = wm.OpticalVolume.from_arrays(np.full((4, 4, 4), 1e-3, np.float32), 1.0, wm.phase.henyey_greenstein(0.85),
                                       ((0.0, 0.0, 1000.0), (4e3, 4e3, 5e3)))
    cfg = StudyConfig(width=64, height=48)
    low = cs.view_of(vol, "front" + cs.LOW_SUN, cfg)
    plain = cs.view_of(vol, "front", cfg)
    assert cs.cache_name("s_front", plain, "128spp") == "s_front_64x48_128spp_reference.exr"
    assert cs.cache_name("s_front", low, "rse0.06") == f"s_front_64x48_rse0.06_{cs.AIR_REFERENCES}_reference.exr"
    assert cs.AIR_REFERENCES != "" and "s_front_64x48_rse0.06_reference.exr" != cs.cache_name("s_front", low, "rse0.06")
    from dataclasses import replace
    assert cs.cache_name("s_front", replace(low, seed=1), "128spp").endswith(f"_seed1_{cs.AIR_REFERENCES}_reference.exr")


def test_a_fit_starts_where_asked(tmp_path):
    """--start: FIT_START, the shipped defaults (their terms that are off at FIT_START's values), or an earlier
    fit's parameters (fitted.json, or a line's "params" of fit_steps.jsonl); anything else refused by name."""
    from weather_mi.slicing import SliceParams
    from weather_mi.slicing.calibrate import FIT_START, MULTIPLE_PARAMS
    assert cs.fit_start("fit-start") == FIT_START
    shipped = cs.fit_start("defaults")
    for n in MULTIPLE_PARAMS:
        assert getattr(shipped, n) == (getattr(SliceParams(), n) or getattr(FIT_START, n))
    steps = tmp_path / "fit_steps.jsonl"
    cs.log_step(steps, 0, 0.0125, {"ms_extinction": 0.25151, "diffusion_incidence": 0.7})
    cs.log_step(steps, 1, 0.0121, {"ms_extinction": 0.3, "diffusion_incidence": 0.65})
    lines = [json.loads(line) for line in steps.read_text().splitlines()]
    assert [line["iteration"] for line in lines] == [0, 1] and lines[1]["loss"] == 0.0121
    earlier = tmp_path / "earlier.json"
    earlier.write_text(json.dumps(lines[0]["params"]))
    start = cs.fit_start(str(earlier))
    assert start.ms_extinction == 0.2515 and start.diffusion_incidence == 0.7
    assert start.leak_gain == SliceParams().leak_gain  # the parameters it does not name: the shipped ones
    with pytest.raises(SystemExit, match=r"--start no-such\.json: expected fit-start, defaults or an existing"):
        cs.fit_start("no-such.json")
