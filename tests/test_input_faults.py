"""Faults in input data found by probing the readers (issue 14): each one either an error that names the
file, the variable and the expectation, or a warning that says how much was changed."""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import weather_mi as wm

from conftest import SHARED_DATA, shared_file, write_wrfout


# ---------------------------------------------------------------- WRF: the scheme's own species

def test_wsm6_file_without_qcloud_is_an_error(tmp_path):
    path = write_wrfout(tmp_path / "w.nc", mp_physics=6, species=("QRAIN", "QICE", "QSNOW", "QGRAUP"))
    with pytest.raises(wm.WeatherDataError, match=r"w\.nc.*'QCLOUD'.*WSM6.*writes"):
        wm.open_wrf(path)


def test_thompson_file_without_qsnow_is_an_error(tmp_path):
    path = write_wrfout(tmp_path / "w.nc", mp_physics=8, species=("QCLOUD", "QRAIN", "QICE", "QGRAUP"))
    with pytest.raises(wm.WeatherDataError, match=r"w\.nc.*'QSNOW'.*Thompson"):
        wm.open_wrf(path)


def test_kessler_file_without_ice_species_only_warns(tmp_path):
    path = write_wrfout(tmp_path / "w.nc", mp_physics=1, species=("QCLOUD", "QRAIN"))
    with pytest.warns(UserWarning, match="Kessler.*QICE"):
        hyd = wm.open_wrf(path)
    assert float(hyd.q_snow.max()) == 0.0


def test_unknown_scheme_without_a_species_only_warns(tmp_path):
    path = write_wrfout(tmp_path / "w.nc", mp_physics=99, species=("QRAIN",))
    with pytest.warns(UserWarning, match="QCLOUD"):
        wm.open_wrf(path)


# ---------------------------------------------------------------- negative mixing ratios

def test_wrf_negative_mixing_ratios_warn_with_count_and_minimum(tmp_path):
    q = np.zeros((1, 6, 4, 5))
    q[0, 1, 1, 1] = -1e-7
    q[0, 3, 2, 2] = -2e-8
    path = write_wrfout(tmp_path / "w.nc", override={"QCLOUD": q})
    with pytest.warns(UserWarning, match=r"w\.nc.*negative.*QCLOUD: 2 values.*minimum -1e-07"):
        hyd = wm.open_wrf(path)
    assert hyd.attrs["n_negative_clipped"] == 2


def test_from_arrays_negative_mixing_ratios_warn_with_count_and_minimum():
    q = np.zeros((2, 3, 4))
    q[0, 0, 0], q[1, 2, 3], q[1, 1, 1] = -3e-9, -1e-9, 1e-3
    with pytest.warns(UserWarning, match=r"arrays.*negative.*q_cloud: 2 values.*minimum -3e-09"):
        hyd = wm.from_arrays({"cloud": q}, 1.0, (1, 1, 1))
    assert hyd.attrs["n_negative_clipped"] == 2


def test_no_warning_without_negative_values(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        wm.from_arrays({"cloud": np.zeros((2, 3, 4))}, 1.0, (1, 1, 1))
        wm.open_wrf(write_wrfout(tmp_path / "w.nc"))


# ---------------------------------------------------------------- LES text files

LES_HEAD = "# a test cloud\n3 2 4\n0.100 0.100\n1.000 1.100 1.200 1.300\n"


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def test_les_file_cut_mid_line_names_the_line(tmp_path):
    """Cut inside the last number (17.261 -> 1): the same column count, so only the unfinished last line
    (no newline, fewer decimals than its column) tells."""
    path = _write(tmp_path / "cut.txt", LES_HEAD + "0 0 0 0.50000 12.125\n1 1 1 0.30000 1")
    with pytest.raises(wm.WeatherDataError, match=r"cut\.txt.*line 6.*cut"):
        wm.open_les(path)


def test_les_file_without_final_newline_but_complete_loads(tmp_path):
    path = _write(tmp_path / "whole.txt", LES_HEAD + "0 0 0 0.50000 12.125\n1 1 1 0.30000 17.261")
    assert float(wm.open_les(path, rho_air=1.0).q_cloud[1, 1, 1]) == pytest.approx(0.3e-3)


def test_les_file_listing_every_voxel_checked_against_the_header(tmp_path):
    """A file that lists clear voxels too (every voxel, in order) must list nx ny nz of them."""
    rows = [f"{i} {j} {k} {0.1 if (i + j + k) % 3 == 0 else 0.0:.5f} 10.000"
            for k in range(4) for j in range(2) for i in range(3)]
    full = _write(tmp_path / "full.txt", LES_HEAD + "\n".join(rows) + "\n")
    assert wm.open_les(full, rho_air=1.0).attrs["n_voxels_listed"] == 24
    cut = _write(tmp_path / "dense_cut.txt", LES_HEAD + "\n".join(rows[:13]) + "\n")
    with pytest.raises(wm.WeatherDataError, match=r"dense_cut\.txt.*24 voxel lines.*13.*line 17"):
        wm.open_les(cut)


def test_real_les_file_cut_mid_line_is_an_error(tmp_path):
    """RICO cut at 54% inside the last number of a line (r_eff 17.261 -> 1): an error naming that line."""
    rico = shared_file(SHARED_DATA / "les" / "rico_20m.txt")
    text = rico.read_text()
    head = text[:text.index("\n", int(0.54 * len(text))) + 1]
    line = text[len(head):text.index("\n", len(head))]
    cut = head + line[:line.rindex(",") + 2]
    path = _write(tmp_path / "rico_cut.txt", cut)
    with pytest.raises(wm.WeatherDataError, match=rf"rico_cut\.txt.*line {cut.count(chr(10)) + 1}\b"):
        wm.open_les(path)


def test_les_levels_uniform_within_their_printed_precision_are_kept(tmp_path):
    """25 m levels printed in km to 3 decimals read as 24-26 m apart: uniform, not regridded."""
    levels = " ".join(f"{0.5125 + 0.025 * k:.3f}" for k in range(8))
    assert len({round(float(b) - float(a), 3) for a, b in zip(levels.split(), levels.split()[1:])}) > 1
    text = f"# rounded levels\n2 1 8\n0.025 0.025\n{levels}\n" + "".join(
        f"0 0 {k} {0.1 * (k + 1):.3f} 10.0\n" for k in range(8))
    ds = wm.open_les(_write(tmp_path / "rounded.txt", text), rho_air=1.0)
    assert "vertical_regrid" not in ds.attrs
    assert ds.sizes["z"] == 8
    np.testing.assert_allclose(np.diff(ds.z.values), 25.0, atol=0.2)
    np.testing.assert_allclose(ds.q_cloud.values[:, 0, 0] * 1e3, 0.1 * np.arange(1, 9), rtol=1e-5)


# ---------------------------------------------------------------- WRF map factors

def test_wrf_map_factors_set_the_horizontal_spacing_and_the_rest_is_warned(tmp_path):
    """A Mercator grid (Katrina: map factors 1.08-1.12): the true distance between mass points is DX / m.
    The spacing is DX over the mean map factor; what a uniform grid cannot follow is warned with its size."""
    m = np.linspace(1.08, 1.12, 4)[None, :, None] * np.ones((1, 4, 5))
    path = write_wrfout(tmp_path / "w.nc", dx=3000.0, override={"MAPFAC_M": m})
    with pytest.warns(UserWarning, match=r"w\.nc.*MAPFAC_M.*1\.08.*1\.12.*1\.8%"):
        hyd = wm.open_wrf(path)
    dz, dy, dx = wm.hydrometeors.spacing_of(hyd)
    assert dx == pytest.approx(3000.0 / 1.1, rel=1e-4) and dy == pytest.approx(3000.0 / 1.1, rel=1e-4)
    assert hyd.attrs["map_factor_mean"] == pytest.approx(1.1, rel=1e-4)


def test_wrf_uniform_map_factor_scales_silently(tmp_path):
    path = write_wrfout(tmp_path / "w.nc", dx=3000.0, override={"MAPFAC_M": np.full((1, 4, 5), 1.25)})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        hyd = wm.open_wrf(path)
    assert wm.hydrometeors.spacing_of(hyd)[2] == pytest.approx(2400.0, rel=1e-4)


def test_wrf_bad_map_factors_are_an_error(tmp_path):
    path = write_wrfout(tmp_path / "w.nc", override={"MAPFAC_M": np.zeros((1, 4, 5))})
    with pytest.raises(wm.WeatherDataError, match=r"w\.nc.*MAPFAC_M.*positive"):
        wm.open_wrf(path)


def huge_wrfout(path: Path, nz: int, ny: int, nx: int) -> Path:
    """A wrfout whose fields are declared (nz, ny, nx) but never written: chunked NetCDF-4, a few KB on disk."""
    import netCDF4
    with netCDF4.Dataset(path, "w") as nc:
        for name, size in (("Time", None), ("DateStrLen", 19), ("bottom_top", nz), ("bottom_top_stag", nz + 1),
                           ("south_north", ny), ("west_east", nx)):
            nc.createDimension(name, size)
        nc.setncatts({"MP_PHYSICS": 6, "DX": 1000.0, "DY": 1000.0})
        for name in ("P", "PB", "T", "QVAPOR", "QCLOUD", "QRAIN", "QICE", "QSNOW", "QGRAUP", "PH", "PHB"):
            z = "bottom_top_stag" if name in ("PH", "PHB") else "bottom_top"
            nc.createVariable(name, "f4", ("Time", z, "south_north", "west_east"), chunksizes=(1, 1, 256, 256))
        t = nc.createVariable("Times", "S1", ("Time", "DateStrLen"))
        t[0] = netCDF4.stringtochar(np.array(["2024-05-20_21:00:00"], "S19"))
    return path


def test_a_domain_too_large_for_memory_fails_before_allocating(tmp_path, monkeypatch):
    """Refused from the file's dimensions, nothing of the grid read or allocated (its speed, 5 s, is
    benchmarks/domain_refusal.py's goal, not a timed test)."""
    monkeypatch.delenv("WEATHER_MI_MAX_MEMORY_GB", raising=False)  # the machine's own memory, not an override
    import tracemalloc
    path = huge_wrfout(tmp_path / "huge.nc", 100, 200_000, 200_000)  # 4e12 cells: 190 TB at 48 bytes per cell
    tracemalloc.start()
    with pytest.raises(wm.errors.DomainTooLargeError) as info:
        wm.open_wrf(path)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    msg = str(info.value)
    assert "100 x 200000 x 200000" in msg and " TB" not in msg and "GB more at peak" in msg
    assert "sub-box" in msg and "coarser levels" in msg and "tiles on a cluster" in msg
    assert info.value.needed > 1e14 and isinstance(info.value, MemoryError)
    assert peak < 50e6  # nothing of the grid was read or allocated


def test_optical_volume_checks_the_memory_before_allocating(monkeypatch):
    hyd = wm.synthetic.cumulus()
    monkeypatch.setenv("WEATHER_MI_MAX_MEMORY_GB", "0.001")
    with pytest.raises(wm.errors.DomainTooLargeError, match="needs about .* GB more at peak and 0.0 GB"):
        wm.optical_volume(hyd)
    monkeypatch.setenv("WEATHER_MI_MAX_MEMORY_GB", "100")
    assert wm.optical_volume(hyd, phase_quality="test").shape == tuple(hyd.rho_air.shape)


def _tree(root: Path, files: dict) -> Path:
    for rel, text in files.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)
    return root


@pytest.mark.parametrize("version", ["v1", "v2"])
def test_available_memory_is_the_tightest_of_meminfo_and_every_cgroup_limit(tmp_path, monkeypatch, version):
    from weather_mi.io.budget import available_bytes
    monkeypatch.delenv("WEATHER_MI_MAX_MEMORY_GB", raising=False)
    gb, unlimited = 1 << 30, "9223372036854771712" if version == "v1" else "max"
    limit, usage, base = (("memory.limit_in_bytes", "memory.usage_in_bytes", "memory/") if version == "v1"
                          else ("memory.max", "memory.current", ""))
    own = "4:memory:/jobs/run7\n" if version == "v1" else "0::/jobs/run7\n"
    proc = _tree(tmp_path / "proc", {"meminfo": "MemTotal: 67108864 kB\nMemAvailable: 33554432 kB\n",
                                     "self/cgroup": "1:cpu:/\n" + own})  # 32 GiB available
    cg = tmp_path / "cg"
    _tree(cg, {f"{base}{limit}": unlimited, f"{base}{usage}": str(50 * gb),
               f"{base}jobs/{limit}": str(12 * gb), f"{base}jobs/{usage}": str(4 * gb),          # 8 GiB left
               f"{base}jobs/run7/{limit}": str(10 * gb), f"{base}jobs/run7/{usage}": str(1 * gb)})  # 9 GiB
    assert available_bytes(str(proc), str(cg)) == 8 * gb  # the parent's room, under its child's and meminfo
    (cg / f"{base}jobs/{limit}").write_text(unlimited)
    assert available_bytes(str(proc), str(cg)) == 9 * gb
    (cg / f"{base}jobs/run7/{limit}").write_text(unlimited)
    assert available_bytes(str(proc), str(cg)) == 32 * gb  # no limit anywhere: MemAvailable
    assert available_bytes(str(tmp_path / "none"), str(tmp_path / "none")) == float("inf")
    monkeypatch.setenv("WEATHER_MI_MAX_MEMORY_GB", "2.5")
    assert available_bytes(str(proc), str(cg)) == 2.5e9
