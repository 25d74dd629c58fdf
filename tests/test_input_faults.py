"""Faults in input data found by probing the readers (issue 14): each one either an error that names the
file, the variable and the expectation, or a warning that says how much was changed."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import weather_mi as wm

from conftest import write_wrfout


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
