"""``weather-mi satellite --time ...`` over several times (weather_mi/display/satellite_loop.py,
weather_mi/cli/satellite_loop.py): the bundled 4-time supercell series as a loop (one NetCDF with a CF time
coordinate, a PNG per time, an MP4), interrupted during its third time and resumed (the finished times read
back, the unfinished one from its checkpoint) to the same reflectance as an uninterrupted loop; a time
selection outside the file refused before rendering. Tiny: 10 km pixels (about 13 x 11), 4 spp."""
from __future__ import annotations

import warnings

import numpy as np
import pytest
import xarray as xr

from weather_mi.cli import commands as cli
from weather_mi.satellite import imagery

from conftest import SHARED_DATA, shared_file

SERIES = SHARED_DATA / "wrf" / "wrfout_quarter_ss_series.nc"
TAGS = ["20240520T210000Z", "20240520T213000Z", "20240520T220000Z", "20240520T223000Z"]


def _loop_args(out, *more, time="all"):
    return ["satellite", str(shared_file(SERIES)), "--time", time, "--lat", "35", "--lon", "-97",
            "--date", "2024-05-20T21:00", "--resolution", "10km", "--spp", "4", "-o", str(out), *more]


def _main(argv) -> int:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return cli.main(argv)


def test_a_loop_is_interrupted_and_resumed_to_the_uninterrupted_result(tmp_path, monkeypatch, capsys):
    real = imagery.render_satellite
    calls = []

    def cut_during_the_third_time(scene, **kw):
        calls.append(kw.get("resume"))
        if len(calls) == 3:  # a power cut after the first pass of the third time (its checkpoint written)
            def stop(_img):
                raise RuntimeError("power cut")
            return real(scene, **kw, on_pass=stop)
        return real(scene, **kw)

    out = tmp_path / "cut" / "sat.nc"
    out.parent.mkdir()
    monkeypatch.setattr(imagery, "render_satellite", cut_during_the_third_time)
    assert _main(_loop_args(out)) == 2
    assert "power cut" in capsys.readouterr().err
    parts = out.with_name("sat.nc.parts")
    assert sorted(p.name for p in parts.iterdir()) == sorted([f"{TAGS[0]}.nc", f"{TAGS[1]}.nc",
                                                              f"{TAGS[2]}.exr.ckpt.npz", "options.json"])
    assert not out.exists()
    assert _main(_loop_args(out)) == 2  # without --resume: refused, the finished times kept
    assert "--resume" in capsys.readouterr().err and len(list(parts.iterdir())) == 4

    calls.clear()
    monkeypatch.setattr(imagery, "render_satellite", lambda scene, **kw: calls.append(kw.get("resume")) or
                        real(scene, **kw))
    assert _main(_loop_args(out, "--resume")) == 0
    text = capsys.readouterr().out
    assert text.count("finished before") == 2 and "2 rendered now" in text
    assert len(calls) == 2 and calls[0] is not None and calls[1] is None  # the third time from its checkpoint
    assert not parts.exists()

    whole = tmp_path / "whole" / "sat.nc"
    whole.parent.mkdir()
    monkeypatch.setattr(imagery, "render_satellite", real)
    assert _main(_loop_args(whole)) == 0
    ds, ref = xr.open_dataset(out), xr.open_dataset(whole)
    assert ds.reflectance.dims == ("time", "y", "x") and ds.sizes["time"] == 4
    np.testing.assert_array_equal(ds.reflectance.values, ref.reflectance.values)
    assert list(ds.spp.values) == [4] * 4
    assert [str(t)[:16] for t in ds.time.values] == ["2024-05-20T21:00", "2024-05-20T21:30", "2024-05-20T22:00",
                                                     "2024-05-20T22:30"]
    raw = xr.open_dataset(out, decode_times=False)
    assert " since " in raw.time.attrs["units"] and raw.time.attrs["standard_name"] == "time"
    assert ds.sensor_zenith_angle.dims == ("y", "x") and ds.solar_zenith_angle.dims == ("time", "y", "x")
    sza = ds.rendered_solar_zenith_angle.values
    assert np.all(np.diff(sza) > 0)  # late afternoon in Oklahoma: the sun sinks through the loop
    for tag in TAGS:
        assert out.with_name(f"sat_{tag}.png").is_file() and out.with_name(f"sat_{tag}.exr").is_file()
    import imageio_ffmpeg
    frames, _ = imageio_ffmpeg.count_frames_and_secs(str(out.with_suffix(".mp4")))
    assert frames == 4


@pytest.mark.parametrize("time, message", [("5,6", r"time indices in \[-4, 3\]"),
                                           ("7:9", "at least one of the 4 times"),
                                           ("0,2030-01-01_00:00:00", "one of the times")])
def test_a_selection_outside_the_file_is_refused_before_rendering(tmp_path, capsys, monkeypatch, time, message):
    monkeypatch.setattr(imagery, "render_satellite", lambda *a, **k: pytest.fail("rendered"))
    assert _main(_loop_args(tmp_path / "sat.nc", time=time)) == 2
    err = capsys.readouterr().err
    assert len(__import__("re").findall(message, err)) == 1, err
    assert not list(tmp_path.iterdir())


def test_a_true_colour_loop_has_time_and_band(tmp_path):
    out = tmp_path / "rgb.nc"
    assert _main(_loop_args(out, "--rgb", time="2:4")) == 0
    ds = xr.open_dataset(out)
    assert ds.reflectance.dims == ("time", "band", "y", "x") and ds.sizes["time"] == 2
    assert len(list(tmp_path.glob("rgb_2*.png"))) == 2 and out.with_suffix(".mp4").is_file()
    assert (tmp_path / "rgb_contact_sheet.png").is_file()


def test_a_loop_over_several_files_takes_their_times_in_order(tmp_path):
    """The series then the one-time file (01:30 again): times 0 and 4 of the five, 00:30 and 01:30."""
    out = tmp_path / "two.nc"
    argv = _loop_args(out, time="0,4")
    argv.insert(2, str(shared_file(SHARED_DATA / "wrf" / "wrfout_quarter_ss_0130.nc")))
    assert _main(argv) == 0
    ds = xr.open_dataset(out)
    assert [str(t)[:16] for t in ds.time.values] == ["2024-05-20T21:00", "2024-05-20T22:00"]


def test_a_true_colour_rayleigh_loop_resumes_band_by_band(tmp_path, monkeypatch):
    """--rgb --rayleigh (a render per band, a checkpoint each): cut in the second time's second band, resumed;
    the first time read back, the second's first band from its finished checkpoint, its second band resumed,
    its third rendered."""
    from weather_mi.reference import render as ref_render
    real = ref_render.render_reference
    calls = []

    def cut(spec, vol, **kw):
        calls.append(kw.get("resume"))
        if len(calls) == 5 and "cut" not in calls:
            calls.append("cut")

            def stop(_img):
                raise RuntimeError("power cut")
            return real(spec, vol, **kw, on_pass=stop)
        return real(spec, vol, **kw)

    monkeypatch.setattr(ref_render, "render_reference", cut)
    out = tmp_path / "rgb.nc"
    argv = _loop_args(out, "--rgb", "--rayleigh", time="0:2")
    assert _main(argv) == 2
    parts = out.with_name("rgb.nc.parts")
    assert sorted(p.name for p in parts.glob("*.ckpt.npz")) == [f"{TAGS[1]}.exr.0.64.ckpt.npz",
                                                              f"{TAGS[1]}.exr.0.86.ckpt.npz"]
    calls[:] = ["cut"]
    assert _main(argv + ["--resume"]) == 0
    assert [c is not None for c in calls[1:]] == [True, True, False]
    ds = xr.open_dataset(out)
    assert ds.reflectance.dims == ("time", "band", "y", "x") and ds.sizes["time"] == 2 and not parts.exists()


@pytest.mark.parametrize("changed", [["--surface", "flat"], ["--wind", "12"], ["--sizes", "paper"], ["--size-classes", "3"],
                                     ["--no-periodic"], ["--periodic", "view"], ["--atmosphere", "none"],
                                     ["--atmosphere", "clear", "--aod", "0.3"]])
def test_loop_options_record_every_option_the_times_depend_on(changed):
    """A resume with another surface, wind, particle sizes or periodic setting is refused, not mixed into the loop:
    each changes what ``loop_options`` records."""
    from weather_mi.cli.commands import build_parser
    from weather_mi.cli.satellite_loop import loop_options
    base = ["satellite", "--demo", "supercell", "--time", "all"]
    a, b = (build_parser().parse_args(base + extra) for extra in ([] if changed[-1] != "0.3" else ["--atmosphere", "clear"], changed))
    assert loop_options(a, 2.0, {}) != loop_options(b, 2.0, {})
