"""Time series: ``open_wrf(path, time=slice | list | "all")`` and several files give one Dataset with a
``time`` dimension on one grid; ``weather-mi animate`` renders every time into EXR frames, an MP4 and
a contact sheet (slicer, spread over a 2-worker LocalCluster; the reference at a tiny size)."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.cli import commands as cli
from weather_mi.errors import WeatherDataError
from weather_mi.io.series import time_steps

from conftest import SHARED_DATA, shared_file, write_wrfout

SERIES = SHARED_DATA / "wrf" / "wrfout_quarter_ss_series.nc"
STAMPS = ["2020-01-01_00:00:00", "2020-01-01_00:10:00", "2020-01-01_00:20:00"]


def _growing(path, times=STAMPS, nz=6, ny=4, nx=5, lift_m=0.0):
    """A wrfout with cloud water growing with time (k + 1 g/kg at time k) and, with ``lift_m``, model
    levels that rise by that much per time (the grid must still be one for all times)."""
    nt = len(times)
    q = np.zeros((nt, nz, ny, nx))
    for k in range(nt):
        q[k, 2:4, 1:3, 1:4] = 1e-3 * (k + 1)
    zw = np.arange(nz + 1, dtype=np.float64) * 500.0
    ph = np.stack([np.broadcast_to((zw * (1 + k * lift_m / 3000.0) - zw)[:, None, None] * 9.81,
                                   (nz + 1, ny, nx)) for k in range(nt)])
    return write_wrfout(path, nz=nz, ny=ny, nx=nx, times=times, override={"QCLOUD": q, "PH": ph})


def test_all_times_of_a_file_on_one_grid(tmp_path):
    path = _growing(tmp_path / "wrfout.nc", lift_m=300.0)
    ds = wm.open_wrf(path, time="all")
    assert ds.sizes["time"] == 3 and list(ds["time"].values) == STAMPS
    assert ds["q_cloud"].dims == ("time", "z", "y", "x")
    steps = time_steps(ds)
    masses = [float((h.q_cloud * h.rho_air).sum()) for h in steps]
    assert masses[0] < masses[1] < masses[2]
    vols = [wm.optical_volume(h) for h in steps]
    assert len({v.shape for v in vols}) == 1 and len({v.bbox for v in vols}) == 1
    assert [h.attrs["time"] for h in steps] == STAMPS


def test_one_time_of_a_series_equals_the_single_time_reading(tmp_path):
    path = _growing(tmp_path / "wrfout.nc")  # same levels at every time: the same grid as one time alone
    one = wm.open_wrf(path, time=1)
    from_series = time_steps(wm.open_wrf(path, time=[1]))[0]
    for var in ("q_cloud", "rho_air"):
        assert np.array_equal(one[var].values, from_series[var].values)
    assert np.array_equal(one.z.values, from_series.z.values)


def test_slices_lists_timestamps_and_several_files(tmp_path):
    path = _growing(tmp_path / "a.nc")
    assert list(wm.open_wrf(path, time=slice(1, None))["time"].values) == STAMPS[1:]
    assert list(wm.open_wrf(path, time=[2, "2020-01-01T00:00:00"])["time"].values) == [STAMPS[2], STAMPS[0]]
    later = ["2020-01-01_00:30:00", "2020-01-01_00:40:00"]
    other = _growing(tmp_path / "b.nc", times=later)
    both = wm.open_wrf([path, other])
    assert list(both["time"].values) == STAMPS + later
    assert list(both["source"].values) == [str(path)] * 3 + [str(other)] * 2
    assert list(wm.open_wrf([path, other], time=slice(2, 4))["time"].values) == [STAMPS[2], later[0]]


@pytest.mark.parametrize("time, match", [([5], r"time indices in \[-3, 2\]"), (["2021-01-01_00:00:00"], "one of the times"),
                                         (slice(5, 9), "at least one of the 3 times")])
def test_bad_time_selection_is_refused(tmp_path, time, match):
    path = _growing(tmp_path / "wrfout.nc")
    with pytest.raises(WeatherDataError, match=match):
        wm.open_wrf(path, time=time)


def test_the_supercell_series_grows_on_a_fixed_domain():
    path = shared_file(SERIES)
    ds = wm.open_wrf(path, time="all", x=slice(35, 65), y=slice(35, 65))
    assert list(ds["time"].values) == ["0001-01-01_00:30:00", "0001-01-01_01:00:00", "0001-01-01_01:30:00",
                                       "0001-01-01_02:00:00"]
    condensate = [float(sum((h[f"q_{s}"] * h.rho_air).sum() for s in wm.SPECIES_NAMES)) for h in time_steps(ds)]
    assert condensate[0] < condensate[-1]


def test_animate_the_supercell_series_with_the_slicer_on_two_workers(tmp_path, capsys):
    path = shared_file(SERIES)
    out = tmp_path / "anim"
    assert cli.main(["animate", str(path), "--size", "32x24", "--slices", "16", "--orbit", "30",
                     "--workers", "2", "-o", str(out)]) == 0
    frames = sorted((out / "frames").glob("frame_*.exr"))
    assert len(frames) == 4
    imgs = [wm.Image.load(f) for f in frames]
    assert [im.metadata["label"] for im in imgs] == ["0001-01-01_00:30:00", "0001-01-01_01:00:00",
                                                     "0001-01-01_01:30:00", "0001-01-01_02:00:00"]
    assert [im.metadata["orbit_deg"] for im in imgs] == [0.0, 10.0, 20.0, 30.0]
    assert all(im.radiance.shape == (24, 32, 3) and np.all(np.isfinite(im.radiance)) for im in imgs)
    assert not np.array_equal(imgs[0].radiance, imgs[-1].radiance)
    assert all(im.metadata["mode"]["light"] == "multiple" for im in imgs)  # the mode closest to the truth
    _check_movie(out, n=4, w=32, h=24)
    assert "wrote 4 frames" in capsys.readouterr().out


def test_animate_refuses_an_unknown_slicer_mode(tmp_path):
    from weather_mi.display.animate import animate
    vol = wm.optical_volume(wm.synthetic.cumulus(shape=(8, 8, 8), spacing_m=(100.0, 100.0, 100.0)))
    spec = wm.SceneSpec(camera=wm.Camera.orbit(vol), sun=wm.Sun(290, 35), width=8, height=6)
    with pytest.raises(ValueError, match="slicer mode must be one of"):
        animate([vol], spec, tmp_path / "x", mode="per-species/fancy", progress=False)
    assert not (tmp_path / "x").exists()


def test_animate_with_the_reference_renderer(tmp_path):
    path = shared_file(SERIES)
    hyds = time_steps(wm.open_wrf(path, time=[0, -1], x=slice(40, 60), y=slice(40, 60)))
    vols = [wm.optical_volume(h, species="physical") for h in hyds]
    spec = wm.SceneSpec(camera=wm.Camera.orbit(vols[-1], azimuth=200, elevation=20), sun=wm.Sun(290, 35),
                        width=16, height=12, sky=wm.Sky("constant"))
    from weather_mi.display.animate import animate
    anim = animate(vols, spec, tmp_path / "ref", renderer="reference", labels=[h.attrs["time"] for h in hyds],
                   reference_kw={"spp": 4, "passes": 2}, progress=False)
    assert len(anim.frames) == 2 and all(im.metadata["renderer"] == "reference" for im in anim.images)
    assert all(im.metadata["spp"] == 4 for im in anim.images)
    assert not list((tmp_path / "ref" / "frames").glob("*.ckpt.npz")), "checkpoints of finished frames left behind"
    _check_movie(tmp_path / "ref", n=2, w=16, h=12)


def _check_movie(out, n, w, h):
    import imageio_ffmpeg
    from PIL import Image
    reader = imageio_ffmpeg.read_frames(str(out / "animation.mp4"))
    meta = next(reader)
    assert tuple(meta["size"]) == (w + (-w % 16), h + (-h % 16))
    assert sum(1 for _ in reader) == n
    sheet = Image.open(out / "contact_sheet.png")
    assert sheet.mode == "RGB" and sheet.width >= 2 * w and sheet.height >= h


def test_each_file_is_opened_once_for_all_its_times(tmp_path, monkeypatch):
    from weather_mi.io import wrfout
    a, b = _growing(tmp_path / "a.nc"), _growing(tmp_path / "b.nc", times=["2020-01-01_00:30:00"])
    opened = []
    real = wrfout.open_dataset
    monkeypatch.setattr(wrfout, "open_dataset", lambda p: opened.append(p) or real(p))
    assert wm.open_wrf([a, b]).sizes["time"] == 4
    assert sorted(opened) == sorted([str(a), str(b)])
