"""The command line and the output files under faults (issue 14): bad options and outputs refused before
anything is rendered, with one line that says what is wrong; checkpoints never lost nor silently
discarded; two renders never mix their outputs; Ctrl-C and a full disk say how to resume."""
from __future__ import annotations

import errno
import os
import threading
from pathlib import Path

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.cli import commands as cli
from weather_mi.reference import render as reference_module
from weather_mi.io.image import Image, read_exr

from conftest import storm_shadows_reused


@pytest.fixture(scope="module", autouse=True)
def one_storm_shadow():
    """Every render here is the demo cumulus under the default sun, with the eye rays' air on (``render``'s
    default): its storm shadow, the same arrays each time, is computed once (``conftest.storm_shadows_reused``)."""
    with storm_shadows_reused() as done:
        yield done


@pytest.fixture
def no_render(monkeypatch):
    """Fail the test if a render starts."""
    monkeypatch.setattr(reference_module, "render_reference",
                        lambda *a, **k: pytest.fail("rendering started despite a bad argument or output"))


def fake_render(monkeypatch, value=0.5):
    """A render that returns a flat image at once (the CLI's own logic is under test, not the renderer)."""
    def render(spec, vol, **kw):
        rad = np.full((spec.height, spec.width, 3), value, np.float32)
        return Image(rad, np.full_like(rad, 0.01), {"spp": 1, "seconds": 0.0, "noise": None})
    monkeypatch.setattr(reference_module, "render_reference", render)


def run(args, capsys):
    rc = cli.main(["render", "--demo", "cumulus", "--size", "8x6", "--spp", "1", *args])
    out, err = capsys.readouterr()
    return rc, out, err


def one_line_error(err: str) -> str:
    lines = [line for line in err.strip().splitlines() if line.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


# ---------------------------------------------------------------- options

@pytest.mark.parametrize("fov", ["0", "-5", "180", "nan"])
@pytest.mark.parametrize("camera", ["orbit", "ground"])
def test_fov_outside_0_180_exits_2(tmp_path, capsys, no_render, fov, camera):
    rc, _, err = run(["--camera", camera, "--fov", fov, "-o", str(tmp_path / "a.exr")], capsys)
    assert rc == 2 and "fov" in one_line_error(err)


def test_unknown_option_is_named(tmp_path, capsys, no_render):
    with pytest.raises(SystemExit) as exc:
        cli.main(["render", "--demo", "cumulus", "--bogus", "1", "-o", str(tmp_path / "a.exr")])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "--bogus" in err and "not allowed with" not in err


def test_file_and_demo_together_or_neither_are_refused(tmp_path, capsys, no_render):
    for argv in (["render", "x.nc", "--demo", "cumulus"], ["render"], ["info"]):
        with pytest.raises(SystemExit) as exc:
            cli.main(argv)
        assert exc.value.code == 2
        assert "--demo" in capsys.readouterr().err


@pytest.fixture
def no_loading(monkeypatch):
    """Fail the test if the input is read (the scene options are checked first)."""
    import weather_mi.io
    import weather_mi.io.sources
    fail = lambda *a, **k: pytest.fail("the input was read despite a bad scene option")  # noqa: E731
    import weather_mi.cli.options
    monkeypatch.setattr(weather_mi.cli.options, "open_source", fail)
    monkeypatch.setattr(weather_mi.io.sources, "open_times", fail)
    monkeypatch.setattr(weather_mi.io, "open_wrf", fail)


@pytest.mark.parametrize("option", [["--size", "0x6"], ["--size", "8x-1"], ["--size", "8x6x2"], ["--size", "axb"],
                                    ["--fov", "0"], ["--fov", "180"]])
@pytest.mark.parametrize("command", ["render", "animate"])
def test_bad_size_or_fov_is_refused_before_the_input_is_read(tmp_path, capsys, no_render, no_loading, option, command):
    source = ["--demo", "cumulus"] if command == "render" else [str(tmp_path / "wrfout.nc")]
    out = tmp_path / ("a.exr" if command == "render" else "anim")
    rc = cli.main([command, *source, *option, "-o", str(out)])
    assert rc == 2 and option[0].lstrip("-") in one_line_error(capsys.readouterr().err)
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("command", ["render", "info"])
def test_time_with_a_demo_storm_is_refused(tmp_path, capsys, no_render, command):
    argv = [command, "--demo", "cumulus", "--time", "3"] + (["-o", str(tmp_path / "a.exr")] if command == "render" else [])
    rc = cli.main(argv)
    assert rc == 2 and "--time" in one_line_error(capsys.readouterr().err)


# ---------------------------------------------------------------- outputs

def test_output_with_an_unknown_extension_is_refused_before_rendering(tmp_path, capsys, no_render):
    rc, _, err = run(["-o", str(tmp_path / "c.txt")], capsys)
    assert rc == 2 and ".txt" in one_line_error(err) and ".exr" in err
    assert not list(tmp_path.iterdir())


def test_unwritable_output_directory_is_refused_before_rendering(tmp_path, capsys, no_render):
    blocker = tmp_path / "file"
    blocker.write_text("a file where the output folder should be")
    rc, _, err = run(["-o", str(blocker / "out" / "a.exr")], capsys)
    assert rc == 2 and str(blocker) in one_line_error(err)


def test_png_output_names_the_pair(tmp_path, capsys, monkeypatch):
    fake_render(monkeypatch)
    rc, out, err = run(["-o", str(tmp_path / "pic.png")], capsys)
    assert rc == 0, err
    assert (tmp_path / "pic.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    radiance, _, _ = read_exr(tmp_path / "pic.exr")
    assert radiance.shape == (6, 8, 3)


def test_image_save_takes_the_format_from_the_extension(tmp_path):
    img = Image(np.full((3, 4, 3), 0.25, np.float32))
    img.save(tmp_path / "x.png")
    assert (tmp_path / "x.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    img.save(tmp_path / "x.exr")
    assert np.allclose(Image.load(tmp_path / "x.exr").radiance, 0.25)
    for bad in ("x.txt", "x", "x.jpg"):
        with pytest.raises(ValueError, match=r"\.exr.*\.png"):
            img.save(tmp_path / bad)
    with pytest.raises(ValueError, match=r"\.png"):
        img.save_png(tmp_path / "y.exr")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.exr", "x.png"]


def test_concurrent_writes_of_one_path_leave_one_whole_file(tmp_path):
    """Unique temporary names: writers of the same path never trip over each other's temporary file."""
    errors = []

    def write(value):
        try:
            for _ in range(5):
                img = Image(np.full((16, 16, 3), value, np.float32))
                img.save(tmp_path / "same.exr")
                img.save(tmp_path / "same.png")
        except Exception as exc:  # noqa: BLE001 - any failure is the test's finding
            errors.append(exc)
    threads = [threading.Thread(target=write, args=(v,)) for v in (0.25, 0.75)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    assert sorted(p.name for p in tmp_path.iterdir()) == ["same.exr", "same.png"]
    assert float(Image.load(tmp_path / "same.exr").radiance.mean()) in (0.25, 0.75)


def test_second_render_to_the_same_output_refuses_while_the_first_holds_it(tmp_path, capsys, no_render):
    out = tmp_path / "a.exr"
    lock = tmp_path / "a.exr.lock"
    lock.write_text(str(os.getpid()))  # a live process holds it
    rc, _, err = run(["-o", str(out)], capsys)
    assert rc == 2 and "another render" in one_line_error(err) and str(os.getpid()) in err
    assert lock.exists()


def test_a_stale_lock_of_a_dead_process_is_taken_over(tmp_path, capsys, monkeypatch):
    fake_render(monkeypatch)
    lock = tmp_path / "a.exr.lock"
    lock.write_text("999999999")  # no such process
    rc, _, err = run(["-o", str(tmp_path / "a.exr")], capsys)
    assert rc == 0, err
    assert not lock.exists() and (tmp_path / "a.exr").exists() and (tmp_path / "a.png").exists()


# ---------------------------------------------------------------- checkpoints

def test_fresh_render_over_an_unfinished_checkpoint_is_refused(tmp_path, capsys, no_render):
    ckpt = tmp_path / "a.exr.ckpt.npz"
    np.savez(ckpt, done=3)
    rc, _, err = run(["-o", str(tmp_path / "a.exr")], capsys)
    line = one_line_error(err)
    assert rc == 2 and str(ckpt) in line and "--resume" in line
    assert ckpt.exists()


def test_corrupt_checkpoint_with_resume_is_a_clear_error(tmp_path, capsys):
    ckpt = tmp_path / "a.exr.ckpt.npz"
    ckpt.write_bytes(b"PK\x03\x04 not really a zip file")
    rc, _, err = run(["--resume", "-o", str(tmp_path / "a.exr")], capsys)
    line = one_line_error(err)
    assert rc == 2 and str(ckpt) in line and "afresh" in line


def test_api_keeps_an_existing_checkpoint_aside_and_says_so(tmp_path):
    beta = np.full((4, 4, 4), 1e-3, np.float32)
    vol = wm.OpticalVolume.from_arrays(beta, 0.9, wm.phase.henyey_greenstein(0.8), ((0, 0, 0), (1000, 1000, 1000)))
    spec = wm.SceneSpec(camera=wm.Camera.orbit(vol, elevation=10), sun=wm.Sun(200, 40, angular_diameter_deg=0),
                        sky=wm.Sky("constant"), ground=None, width=4, height=3)
    ckpt = tmp_path / "r.ckpt.npz"
    ckpt.write_bytes(b"an older render's checkpoint")
    with pytest.warns(UserWarning, match=r"r\.ckpt\.npz.*kept aside.*r\.ckpt\.previous\.npz"):
        wm.render_reference(spec, vol, spp=2, progress=False, checkpoint=ckpt)
    assert (tmp_path / "r.ckpt.previous.npz").read_bytes() == b"an older render's checkpoint"
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"garbage")
    with pytest.raises(ValueError, match=r"bad\.npz.*cannot be read"):
        wm.render_reference(spec, vol, spp=2, progress=False, checkpoint=bad, resume=True)


# ---------------------------------------------------------------- Ctrl-C

def test_ctrl_c_says_where_the_checkpoint_is_and_how_to_resume(tmp_path, capsys, monkeypatch):
    def interrupted(spec, vol, checkpoint=None, **kw):
        np.savez(checkpoint, done=2)  # two passes finished, then Ctrl-C
        raise KeyboardInterrupt
    monkeypatch.setattr(reference_module, "render_reference", interrupted)
    out = tmp_path / "a.exr"
    rc, _, err = run(["-o", str(out)], capsys)
    line = one_line_error(err)
    assert rc == 130
    assert "interrupted" in line and "a.exr.ckpt.npz" in line and "--resume" in line
    assert not (tmp_path / "a.exr.lock").exists()


# ---------------------------------------------------------------- a full disk

ENOSPC = os.strerror(errno.ENOSPC)  # "No space left on device"


def error_line(err: str) -> str:
    """The one error line of a real render's stderr (its progress bar is there too), no traceback."""
    lines = [line for line in err.replace("\r", "\n").splitlines() if line.startswith("weather-mi:")]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def disk_full_at_checkpoint(monkeypatch, k):
    """The disk fills up while the (k+1)-th checkpoint is written (``np.savez``, the checkpoint's write): a
    few bytes of it, then ENOSPC, as the system reports a full disk."""
    real, calls = np.savez, []

    def savez(file, *args, **kwds):
        if len(calls) == k:
            Path(file).write_bytes(b"PK\x03\x04 the first bytes of a checkpoint")
            raise OSError(errno.ENOSPC, ENOSPC)
        calls.append(file)
        return real(file, *args, **kwds)
    monkeypatch.setattr(np, "savez", savez)
    return real


def test_full_disk_mid_render_names_the_checkpoint_keeps_it_and_resumes_bit_for_bit(tmp_path, capsys, monkeypatch):
    """4 passes; the disk is full when the third checkpoint is written: exit 2 with one line naming the
    checkpoint and --resume, no traceback; the checkpoint of the first two passes is whole, no temporary
    file is left, and --resume finishes the render with the image of an uninterrupted one."""
    whole = tmp_path / "whole.exr"
    assert run(["--spp", "4", "-o", str(whole)], capsys)[0] == 0
    out, ckpt = tmp_path / "a.exr", tmp_path / "a.exr.ckpt.npz"
    real = disk_full_at_checkpoint(monkeypatch, 2)
    rc, _, err = run(["--spp", "4", "-o", str(out)], capsys)
    line = error_line(err)
    assert rc == 2 and f"could not write the checkpoint {ckpt}: {ENOSPC}" in line
    assert "the checkpoint keeps its first 2 passes, whole" in line and "--resume" in line
    assert int(np.load(ckpt)["done"]) == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.exr.ckpt.npz", "whole.exr", "whole.png"]
    monkeypatch.setattr(np, "savez", real)  # space freed
    rc, _, err = run(["--spp", "4", "--resume", "-o", str(out)], capsys)
    assert rc == 0, err
    a, b = Image.load(out), Image.load(whole)
    assert np.array_equal(a.radiance, b.radiance) and np.array_equal(a.stderr, b.stderr)
    assert a.metadata["passes"] == 4 and not ckpt.exists()


@pytest.mark.parametrize("which", ["EXR", "PNG"])
def test_full_disk_when_the_image_is_written_names_it_and_resumes_without_rendering(tmp_path, capsys, monkeypatch,
                                                                                      which):
    """The render is finished and the EXR (OpenEXR's RuntimeError) or the PNG (PIL's OSError) cannot be
    written: the message names that file (not its temporary name) and the checkpoint; --resume writes
    the images without rendering a pass."""
    import OpenEXR
    from PIL import Image as PILImage
    out, ckpt = tmp_path / "a.exr", tmp_path / "a.exr.ckpt.npz"
    target = out if which == "EXR" else tmp_path / "a.png"

    def exr_full(self, name):
        raise RuntimeError(f'Failed to write pixel data to image file "{name}". {ENOSPC}.')

    def png_full(self, fp, *args, **kwargs):
        raise OSError(errno.ENOSPC, ENOSPC)
    if which == "EXR":
        monkeypatch.setattr(OpenEXR.File, "write", exr_full)
    else:
        monkeypatch.setattr(PILImage.Image, "save", png_full)
    rc, _, err = run(["--spp", "4", "-o", str(out)], capsys)
    line = error_line(err)
    assert rc == 2 and f"could not write the {which} image {target}: {ENOSPC}" in line
    assert ".tmp" not in line and str(ckpt) in line and "--resume" in line
    assert int(np.load(ckpt)["done"]) == 4
    assert not [p for p in tmp_path.iterdir() if ".tmp" in p.name]
    monkeypatch.undo()
    for name in ("render_pass", "render_passes"):
        monkeypatch.setattr(wm.reference.passes, name, lambda *a, **k: pytest.fail("rendered although every pass is done"))
    rc, _, err = run(["--spp", "4", "--resume", "-o", str(out)], capsys)
    assert rc == 0, err
    assert out.exists() and (tmp_path / "a.png").exists() and not ckpt.exists()


def test_full_disk_api_raises_output_write_error_and_the_checkpoint_resumes(tmp_path, monkeypatch):
    """The library's error: an OSError (errno ENOSPC) naming the checkpoint; a first pass that cannot be
    saved leaves no checkpoint; a later one leaves the previous pass's, from which resume=True continues."""
    from weather_mi.errors import OutputWriteError
    beta = np.full((4, 4, 4), 1e-3, np.float32)
    vol = wm.OpticalVolume.from_arrays(beta, 0.9, wm.phase.henyey_greenstein(0.8), ((0, 0, 0), (1000, 1000, 1000)))
    spec = wm.SceneSpec(camera=wm.Camera.orbit(vol, elevation=10), sun=wm.Sun(200, 40, angular_diameter_deg=0),
                        sky=wm.Sky("constant"), ground=None, width=4, height=3)
    ckpt = tmp_path / "r.ckpt.npz"
    real = disk_full_at_checkpoint(monkeypatch, 0)
    with pytest.raises(OutputWriteError) as exc:
        wm.render_reference(spec, vol, spp=3, progress=False, checkpoint=ckpt)
    assert isinstance(exc.value, OSError) and exc.value.errno == errno.ENOSPC and exc.value.filename == str(ckpt)
    assert str(exc.value) == f"could not write the checkpoint {ckpt}: {ENOSPC}; the render stopped"
    assert not list(tmp_path.iterdir())
    monkeypatch.setattr(np, "savez", real)
    disk_full_at_checkpoint(monkeypatch, 1)
    with pytest.raises(OutputWriteError, match="the checkpoint keeps its first pass, whole, to resume from once there"):
        wm.render_reference(spec, vol, spp=3, progress=False, checkpoint=ckpt)
    assert int(np.load(ckpt)["done"]) == 1 and [p.name for p in tmp_path.iterdir()] == [ckpt.name]
    monkeypatch.setattr(np, "savez", real)
    resumed = wm.render_reference(spec, vol, spp=3, progress=False, checkpoint=ckpt, resume=True)
    whole = wm.render_reference(spec, vol, spp=3, progress=False)
    assert np.array_equal(resumed.radiance, whole.radiance) and np.array_equal(resumed.stderr, whole.stderr)
