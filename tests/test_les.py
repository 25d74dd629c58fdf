"""LES (SHDOM/pyshdom LWC text) reader: real BOMEX and RICO files, air density, orientation, synthetic
variants (every voxel listed, combined/split headers, non-uniform levels) and every bad-input case.

Expected numbers come from the files themselves (read here with plain Python string splitting) and from
the documented facts in ../shared/data/README.md, never from the reader under test.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from weather_mi.io.standard_atmosphere import standard_density
from weather_mi.errors import WeatherDataError
from weather_mi.io.hydrometeors import SPECIES_NAMES
from weather_mi.io.les import open_les

SHARED_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


def les_file(name: str) -> Path:
    """../shared/data/les/<name> (relative to the repository root), or skip with the reason."""
    path = SHARED_DATA / "les" / name
    if not path.is_file():
        pytest.skip(f"shared data file {path} is absent (tests use ../shared/data relative to the repository)")
    return path


def plain_read(path: Path):
    """An independent, plain-Python reading: (level altitudes in km, voxel rows [(i, j, k, lwc, reff, ...)])."""
    nz, levels, rows = None, None, []
    for line in path.read_text().splitlines():
        toks = line.split("#", 1)[0].replace(",", " ").split()
        if not toks:
            continue
        if nz is None:                      # nx ny nz
            nz = int(toks[2])
        elif levels is None:                # the level line: its last nz values (after dx dy for BOMEX)
            if len(toks) >= nz:
                levels = [float(t) for t in toks[-nz:]]
        elif toks[0].isdigit():             # a voxel line (skips the column-name line)
            rows.append((int(toks[0]), int(toks[1]), int(toks[2]), *(float(t) for t in toks[3:])))
    return levels, rows


# (file, (nz, ny, nx), dx = dy (m), dz (m), documented max LWC (g/m^3, 2 decimals), has v_eff)
REAL = [("bomex_50m.txt", (52, 146, 115), 50.0, 40.0, 1.69, True),
        ("rico_20m.txt", (39, 106, 122), 20.0, 40.0, 1.38, False)]


@pytest.mark.parametrize("name,shape,dxy,dz,max_lwc,has_veff", REAL)
def test_real_files_grid_counts_and_max(name, shape, dxy, dz, max_lwc, has_veff):
    path = les_file(name)
    levels, rows = plain_read(path)
    ds = open_les(path)  # its speed (3 s a file) is benchmarks/les_read.py's goal
    assert tuple(ds.sizes[d] for d in ("z", "y", "x")) == shape
    assert len(levels) == shape[0]
    for d, step in (("x", dxy), ("y", dxy), ("z", dz)):
        np.testing.assert_allclose(np.diff(ds[d].values), step, rtol=1e-6)
    assert float(ds.x[0]) == 0.0 and float(ds.y[0]) == 0.0
    np.testing.assert_allclose(ds.z.values, np.asarray(levels) * 1000.0, atol=1e-6)
    # counts: every data line, and those with LWC > 0 (the real files list cloudy voxels only)
    assert ds.attrs["n_voxels_listed"] == len(rows)
    assert ds.attrs["n_cloudy_voxels"] == sum(1 for r in rows if r[3] > 0)
    assert int((ds.q_cloud > 0).sum()) == sum(1 for r in rows if r[3] > 0)
    # maximum LWC: documented value, and the file's own maximum, recovered from q * rho * 1e3
    lwc = ds.q_cloud.values.astype(np.float64) * ds.rho_air.values * 1e3
    file_max = max(r[3] for r in rows)
    assert round(file_max, 2) == max_lwc
    assert lwc.max() == pytest.approx(file_max, rel=1e-5)
    # total liquid is conserved (uniform levels: no regridding)
    assert lwc.sum() == pytest.approx(sum(r[3] for r in rows), rel=1e-5)
    # effective radius in metres: file microns * 1e-6, zero where clear
    reff = ds.r_eff_cloud.values
    assert reff.max() == pytest.approx(max(r[4] for r in rows) * 1e-6, rel=1e-5)
    assert 1e-6 < reff.max() < 1e-4
    assert np.all(reff[ds.q_cloud.values == 0] == 0)
    assert ("v_eff_cloud" in ds) == has_veff
    if has_veff:
        assert float(ds.v_eff_cloud.max()) == pytest.approx(max(r[5] for r in rows), rel=1e-5)
    for s in SPECIES_NAMES:
        if s != "cloud":
            assert float(ds[f"q_{s}"].max()) == 0.0
    assert ds.attrs["source"] == str(path) and ds.attrs["model"] == "LES"
    assert ds.attrs["comment"] == path.read_text().splitlines()[0].lstrip("#").strip()


@pytest.mark.parametrize("name", ["bomex_50m.txt", "rico_20m.txt"])
def test_lwc_to_mixing_ratio_and_orientation(name):
    path = les_file(name)
    levels, rows = plain_read(path)
    ds = open_les(path)
    dxy = float(ds.x[1] - ds.x[0])
    q, rho = ds.q_cloud.values, ds.rho_air.values
    best = max(rows, key=lambda r: r[3])
    picks = [rows[0], rows[len(rows) // 3], rows[-1], best]
    picks += [r for r in rows if r[0] != r[1]][:3]  # asymmetric i != j: a transposition would show
    for i, j, k, lwc, reff, *_ in picks:
        z = levels[k] * 1000.0
        # air density: the 1976 standard atmosphere at the level height
        assert rho[k, j, i] == pytest.approx(float(standard_density(z)), rel=1e-6)
        # q = LWC * 1e-3 / rho_air, so q * rho * 1e3 gives back the file's LWC
        assert q[k, j, i] * rho[k, j, i] * 1e3 == pytest.approx(lwc, rel=1e-5)
        assert float(ds.r_eff_cloud[k, j, i]) == pytest.approx(reff * 1e-6, rel=1e-5)
        # coordinates of that voxel: x = i dx, y = j dy, z = level altitude
        assert float(ds.x[i]) == pytest.approx(i * dxy)
        assert float(ds.y[j]) == pytest.approx(j * dxy)
        assert float(ds.z[k]) == pytest.approx(z)
        # and the selection by coordinates finds the same value
        assert float(ds.q_cloud.sel(x=i * dxy, y=j * dxy, z=z, method="nearest")) == q[k, j, i]
    listed = {(r[0], r[1], r[2]) for r in rows}
    nz, ny, nx = q.shape
    clear = next((i, j, k) for k in range(nz) for j in range(ny) for i in range(nx) if (i, j, k) not in listed)
    assert q[clear[2], clear[1], clear[0]] == 0.0


def test_rho_air_number_profile_callable():
    path = les_file("rico_20m.txt")
    levels, rows = plain_read(path)
    i, j, k, lwc, *_ = max(rows, key=lambda r: r[3])
    z_m = np.asarray(levels) * 1000.0

    ds = open_les(path, rho_air=1.1)
    np.testing.assert_allclose(ds.rho_air.values, 1.1, rtol=1e-6)
    assert float(ds.q_cloud[k, j, i]) == pytest.approx(lwc * 1e-3 / 1.1, rel=1e-6)

    profile = np.linspace(1.15, 1.02, len(levels))
    ds = open_les(path, rho_air=profile)
    np.testing.assert_allclose(ds.rho_air.values[:, 3, 5], profile, rtol=1e-6)
    assert float(ds.q_cloud[k, j, i]) == pytest.approx(lwc * 1e-3 / profile[k], rel=1e-6)

    ds = open_les(path, rho_air=lambda z: 1.2 * np.exp(-z / 8000.0))
    np.testing.assert_allclose(ds.rho_air.values[:, 0, 0], 1.2 * np.exp(-z_m / 8000.0), rtol=1e-6)
    assert float(ds.q_cloud[k, j, i]) == pytest.approx(lwc * 1e-3 / (1.2 * math.exp(-z_m[k] / 8000.0)), rel=1e-6)

    ds = open_les(path, rho_air=lambda z: 1.2 * math.exp(-z / 8000.0))  # scalar-only callable
    np.testing.assert_allclose(ds.rho_air.values[:, 0, 0], 1.2 * np.exp(-z_m / 8000.0), rtol=1e-6)


def write_les(path: Path, text: str) -> Path:
    path.write_text(text.lstrip("\n"))
    return path


SMALL = """# tiny test cloud
3 2 4
0.1 0.2 1.0 1.1 1.2 1.3
0 0 0 0.5 10.0 0.1
2 1 3 1.5 12.0 0.2
"""


def test_species_rain_and_bad_species(tmp_path):
    path = write_les(tmp_path / "small.txt", SMALL)
    ds = open_les(path, species="rain", rho_air=1.0)
    assert float(ds.q_rain[3, 1, 2]) == pytest.approx(1.5e-3)
    assert float(ds.q_cloud.max()) == 0.0
    assert float(ds.r_eff_rain[3, 1, 2]) == pytest.approx(12e-6)
    assert float(ds.v_eff_rain[3, 1, 2]) == pytest.approx(0.2)
    with pytest.raises(WeatherDataError, match="species"):
        open_les(path, species="ice")


def test_small_file_orientation_and_units(tmp_path):
    path = write_les(tmp_path / "small.txt", SMALL)
    ds = open_les(path, rho_air=1.25)
    assert dict(ds.sizes) == {"z": 4, "y": 2, "x": 3}
    np.testing.assert_allclose(ds.x.values, [0, 100, 200])
    np.testing.assert_allclose(ds.y.values, [0, 200])
    np.testing.assert_allclose(ds.z.values, [1000, 1100, 1200, 1300])
    q = ds.q_cloud.values
    assert q[3, 1, 2] == pytest.approx(1.5e-3 / 1.25) and q[0, 0, 0] == pytest.approx(0.5e-3 / 1.25)
    assert np.count_nonzero(q) == 2
    assert float(ds.r_eff_cloud[0, 0, 0]) == pytest.approx(10e-6)
    assert ds.attrs["n_voxels_listed"] == 2 and ds.attrs["n_cloudy_voxels"] == 2
    assert ds.attrs["comment"] == "tiny test cloud"


def test_every_voxel_listed_with_zeros(tmp_path):
    nx, ny, nz = 3, 2, 2
    lines = ["# every voxel, zeros included", f"{nx},{ny},{nz}   # nx,ny,nz", "0.05,0.05   # dx,dy [km]",
             "0.5,0.55    # levels [km]", "i,j,k,lwc,reff"]
    expected = np.zeros((nz, ny, nx))
    for i in range(nx):
        for j in range(ny):
            for k in range(nz):
                lwc = 0.1 * (i + 2 * j + 3 * k) if (i + j + k) % 2 else 0.0
                expected[k, j, i] = lwc
                lines.append(f"{i},{j},{k},{lwc:.5f},{8.0 if lwc else 0.0:.3f}")
    path = write_les(tmp_path / "every.csv", "\n".join(lines) + "\n")
    ds = open_les(path, rho_air=1.0)
    assert ds.attrs["n_voxels_listed"] == nx * ny * nz
    assert ds.attrs["n_cloudy_voxels"] == int(np.count_nonzero(expected))
    np.testing.assert_allclose(ds.q_cloud.values * 1e3, expected, rtol=1e-6)
    assert np.all(ds.r_eff_cloud.values[expected == 0] == 0)
    np.testing.assert_allclose(ds.r_eff_cloud.values[expected > 0], 8e-6, rtol=1e-6)
    assert "v_eff_cloud" not in ds
    np.testing.assert_allclose(ds.z.values, [500, 550])


def test_header_split_or_combined_and_named_columns(tmp_path):
    # all header numbers on one line; levels continued on the next; a blank and a comment line in the data
    combined = write_les(tmp_path / "combined.txt",
                         "# combined\n2 2 3 0.1 0.1 0.2 0.3\n0.4\n0 1 2 0.7 9.0\n\n# a note\n"
                         "1 0 0 0.2 7.0  # trailing\n")
    ds = open_les(combined, rho_air=1.0)
    np.testing.assert_allclose(ds.z.values, [200, 300, 400])
    assert float(ds.q_cloud[2, 1, 0]) == pytest.approx(0.7e-3)
    assert float(ds.q_cloud[0, 0, 1]) == pytest.approx(0.2e-3)
    # named columns in another order
    named = write_les(tmp_path / "named.txt", "# named\n2 2 2\n0.1 0.1\n0.2 0.3\nlwc reff k j i\n0.9 11.0 1 0 1\n")
    ds = open_les(named, rho_air=1.0)
    assert float(ds.q_cloud[1, 0, 1]) == pytest.approx(0.9e-3)
    assert float(ds.r_eff_cloud[1, 0, 1]) == pytest.approx(11e-6)
    # a free-text title without '#', LWC-only voxel lines (no r_eff then), and a file with no voxel at all
    lwc_only = write_les(tmp_path / "lwc_only.txt", "LWC only\n2 2 2\n0.1 0.1\n0.2 0.3\n1 1 1 0.3\n")
    ds = open_les(lwc_only, rho_air=1.0)
    assert ds.attrs["comment"] == "LWC only" and "r_eff_cloud" not in ds
    assert float(ds.q_cloud[1, 1, 1]) == pytest.approx(0.3e-3)
    clear = write_les(tmp_path / "clear.csv", "# clear sky\n2,2,2\n0.1,0.1\n0.2,0.3\ni,j,k,lwc,reff\n")
    ds = open_les(clear)
    assert ds.attrs["n_voxels_listed"] == 0 and float(ds.q_cloud.max()) == 0.0


def test_non_uniform_levels_interpolated(tmp_path):
    # levels 0, 100, 300, 400 m (spacings 100, 200, 100): a uniform 100 m grid 0..400 m
    path = write_les(tmp_path / "stretched.txt",
                     "# stretched\n1 1 4\n0.1 0.1\n0.0 0.1 0.3 0.4\n"
                     "0 0 0 0.2 10.0\n0 0 1 0.4 10.0\n0 0 2 0.8 16.0\n0 0 3 0.6 12.0\n")
    ds = open_les(path, rho_air=[1.2, 1.1, 0.9, 0.8])
    np.testing.assert_allclose(ds.z.values, [0, 100, 200, 300, 400])
    lwc = ds.q_cloud.values[:, 0, 0] * ds.rho_air.values[:, 0, 0] * 1e3
    np.testing.assert_allclose(lwc, [0.2, 0.4, 0.6, 0.8, 0.6], rtol=1e-5)       # 0.6 = (0.4 + 0.8) / 2
    np.testing.assert_allclose(ds.rho_air.values[:, 0, 0], [1.2, 1.1, 1.0, 0.9, 0.8], rtol=1e-6)
    # r_eff at 200 m: LWC-weighted (0.4 * 10 + 0.8 * 16) / 1.2 = 14 um
    np.testing.assert_allclose(ds.r_eff_cloud.values[:, 0, 0] * 1e6, [10, 10, 14, 16, 12], rtol=1e-5)
    assert "interpolated linearly" in ds.attrs["vertical_regrid"]
    assert ds.attrs["n_levels_native"] == 4

    # spacings 30 and 70 m: the span 100 m split into the fewest steps no larger than 30 m (25 m)
    odd = write_les(tmp_path / "odd.txt", "# odd\n1 1 3\n0.1 0.1\n1.0 1.03 1.1\n0 0 1 1.0 10.0\n")
    ds = open_les(odd)
    np.testing.assert_allclose(ds.z.values, [1000, 1025, 1050, 1075, 1100])
    lwc = ds.q_cloud.values[:, 0, 0] * ds.rho_air.values[:, 0, 0] * 1e3
    np.testing.assert_allclose(lwc, [0, 25 / 30, 1 - 20 / 70, 1 - 45 / 70, 0], rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(ds.rho_air.values[:, 0, 0], standard_density(ds.z.values), rtol=1e-6)


# 16 levels 25 m apart from 437.5 m, printed in km to 3 decimals: 24-26 m apart as printed (a held-out file)
ROUNDED_LEVELS = ("0.438 0.463 0.487 0.512 0.537 0.562 0.588 0.613 0.637 0.662 0.688 0.713 0.738 0.762 "
                  "0.788 0.812")


def _column_file(tmp_path, name, levels):
    """A 1 x 1 column with the given level line and LWC 0.1 (k + 1) g/m^3 in every level."""
    n = len(levels.split())
    text = f"# {name}\n1 1 {n}\n0.025 0.025\n{levels}\n" + "".join(
        f"0 0 {k} {0.1 * (k + 1):.3f} 10.0\n" for k in range(n))
    return write_les(tmp_path / f"{name}.txt", text)


def test_levels_uniform_to_their_printed_precision_are_kept(tmp_path):
    """Every level within half a unit of the last printed digit (0.5 m) of a straight line: uniform, kept
    (the spacings differ from their mean by up to 1.07 m, more than a whole printed unit)."""
    steps = np.diff([float(t) for t in ROUNDED_LEVELS.split()])
    assert round(steps.min(), 3) == 0.024 and round(steps.max(), 3) == 0.026
    for name, levels in (("rounded", ROUNDED_LEVELS),
                         ("rounded_exponent", " ".join(f"{float(t):.2e}" for t in ROUNDED_LEVELS.split()))):
        ds = open_les(_column_file(tmp_path, name, levels), rho_air=1.0)
        assert "vertical_regrid" not in ds.attrs, name
        assert ds.sizes["z"] == 16
        # kept at the mean spacing from the first to the last level: within a printed unit of each level
        np.testing.assert_allclose(ds.z.values, [float(t) * 1000.0 for t in ROUNDED_LEVELS.split()], atol=1.0)
        np.testing.assert_allclose(np.diff(ds.z.values), 374.0 / 15, rtol=1e-9)
        lwc = ds.q_cloud.values[:, 0, 0] * 1e3
        np.testing.assert_allclose(lwc, 0.1 * np.arange(1, 17), rtol=1e-6)   # the peak LWC unchanged
        assert "within" in ds.attrs["vertical_grid"] and "straight line" in ds.attrs["vertical_grid"]


def test_levels_beyond_their_printed_precision_are_regridded(tmp_path):
    """Non-uniform levels printed to 3 decimals are still regridded: a stretched grid (25 m growing by 1 m
    a level), one level 2 m off an otherwise uniform 25 m grid, and the rounded levels above printed with a
    4th decimal (0.4380: precise to 0.05 m, so 0.52 m off any straight line)."""
    stretched = " ".join(f"{0.4 + (25 * k + k * (k - 1) / 2) / 1000:.3f}" for k in range(16))
    bumped = " ".join(f"{0.4 + 0.025 * k + (0.002 if k == 7 else 0.0):.3f}" for k in range(16))
    four = " ".join(f"{t}0" for t in ROUNDED_LEVELS.split())
    for name, levels in (("stretched", stretched), ("bumped", bumped), ("four_decimals", four)):
        ds = open_les(_column_file(tmp_path, name, levels), rho_air=1.0)
        assert "vertical_regrid" in ds.attrs, name
        assert ds.attrs["n_levels_native"] == 16
        assert ds.sizes["z"] > 16


GOOD_HEAD = "# bad-input case\n3 2 4\n0.1 0.1\n1.0 1.1 1.2 1.3\n"
BAD = [
    ("header_text", "# x\n3 two 4\n0.1 0.1\n1.0 1.1 1.2 1.3\n", ["header line 2", "nx ny nz"]),
    ("header_float_size", "# x\n3 2.5 4\n0.1 0.1\n1.0 1.1 1.2 1.3\n", ["header line 2", "nx ny nz"]),
    ("header_dx", "# x\n3 2 4\n0.1 abc\n1.0 1.1 1.2 1.3\n", ["header line 3", "dx dy"]),
    ("header_dx_negative", "# x\n3 2 4\n0.1 -0.1\n1.0 1.1 1.2 1.3\n", ["header line 3", "dx dy"]),
    ("header_truncated", "# x\n3 2\n", ["nx ny nz", "end of the file"]),
    ("too_few_levels", "# x\n3 2 4\n0.1 0.1\n1.0 1.1 1.2\n0 0 0 0.5 10\n", ["levels", "nz = 4", "3 on line 4"]),
    ("too_many_levels", "# x\n3 2 4\n0.1 0.1\n1.0 1.1 1.2 1.3 1.4\n0 0 0 0.5 10\n",
     ["levels", "nz = 4", "5 on line 4"]),
    ("no_levels", "# x\n3 2 4\n0.1 0.1\n0 0 0 0.5 10\n", ["levels", "nz = 4", "none before line 4"]),
    ("levels_not_increasing", "# x\n3 2 4\n0.1 0.1\n1.0 1.2 1.1 1.3\n", ["levels", "strictly increasing"]),
    ("i_out_of_range", GOOD_HEAD + "0 0 0 0.5 10\n3 1 0 0.5 10\n", ["'i'", "nx = 3", "i = 3 on line 6"]),
    ("j_out_of_range", GOOD_HEAD + "0 2 0 0.5 10\n", ["'j'", "ny = 2", "line 5"]),
    ("k_negative", GOOD_HEAD + "0 0 -1 0.5 10\n", ["'k'", "nz = 4", "line 5"]),
    ("negative_lwc", GOOD_HEAD + "0 0 0 0.5 10\n1 1 1 -0.2 10\n", ["'lwc'", "LWC >= 0", "line 6"]),
    ("nan_lwc", GOOD_HEAD + "0 0 0 nan 10\n", ["'lwc'", "finite", "line 5"]),
    ("nan_reff", GOOD_HEAD + "0 0 0 0.3 nan\n", ["'reff'", "finite", "line 5"]),
    ("duplicate", GOOD_HEAD + "0 0 0 0.5 10\n1 1 1 0.5 10\n0 0 0 0.7 11\n",
     ["each voxel", "(0, 0, 0)", "lines 5 and 7"]),
    ("ragged", GOOD_HEAD + "0 0 0 0.5 10\n1 1 1 0.5\n", ["data line 6", "5 columns"]),
    ("text_in_data", GOOD_HEAD + "0 0 0 0.5 10\n1 1 1 0.5 ten\n", ["data line 6", "numbers"]),
    ("fractional_index", GOOD_HEAD + "0.5 0 0 0.5 10\n", ["'i'", "integer"]),
    ("empty", "\n\n", ["empty file"]),
]


@pytest.mark.parametrize("case,text,phrases", BAD, ids=[b[0] for b in BAD])
def test_bad_input_names_file_and_problem(tmp_path, case, text, phrases):
    path = tmp_path / f"{case}.txt"
    path.write_text(text)
    with pytest.raises(WeatherDataError) as err:
        open_les(path, rho_air=1.0)
    msg = str(err.value)
    assert str(path) in msg
    for phrase in phrases:
        assert phrase in msg, f"{phrase!r} not in {msg!r}"


def test_missing_file_and_bad_rho(tmp_path):
    missing = tmp_path / "nowhere.txt"
    with pytest.raises(WeatherDataError, match="no such file") as err:
        open_les(missing)
    assert str(missing) in str(err.value)
    path = write_les(tmp_path / "small.txt", SMALL)
    for bad, phrase in (([1.0, 1.1], "length 2"), (-1.0, "positive"), (lambda z: 0 * z, "positive"),
                        ("dense", "rho_air"), (np.ones((2, 2)), "shape")):
        with pytest.raises(WeatherDataError, match="rho_air") as err:
            open_les(path, rho_air=bad)
        assert str(path) in str(err.value) and phrase in str(err.value)
