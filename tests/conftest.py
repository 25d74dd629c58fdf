"""Shared test helpers: the location of ../shared/data and a factory for small synthetic wrfout files."""
from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

import weather_mi

# tests call Mitsuba directly; importing weather_mi selects no variant. LLVM wherever it runs, also on a GPU
# machine: the bit-for-bit tests assume it (CUDA's film adds samples with atomics); tests/test_gpu.py selects
# cuda_ad_rgb itself
weather_mi.set_variant("llvm_ad_rgb" if weather_mi.kernel.variant.llvm_usable() else None)

SUITE_WORKERS = 2  # worker processes for the whole suite: CI's 2 cores (one process kept them ~55% busy)


def pytest_xdist_auto_num_workers(config):
    """``-n auto`` (pyproject's addopts): the whole suite (``pytest -q``, the tests from ``testpaths``) runs in
    SUITE_WORKERS processes (pytest-xdist, whole files to a worker: ``--dist loadfile``), at most one per core;
    tests or files named on the command line run in this process as before (no workers to start).
    ``PYTEST_XDIST_AUTO_NUM_WORKERS`` or an explicit ``-n N`` overrides."""
    import os
    if os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS"):
        return None  # pytest-xdist's own hook reads it
    if config.args_source != pytest.Config.ArgsSource.TESTPATHS:
        return 0
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return min(SUITE_WORKERS, cores) if cores > 1 else 0


SHARED_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
WRF_SUPERCELL = SHARED_DATA / "wrf" / "wrfout_quarter_ss_0130.nc"
WRF_THOMPSON = SHARED_DATA / "wrf" / "wrf_d01_allvars_cropped.nc"


def shared_file(path: Path) -> Path:
    """The path, or skip the test with a reason when ../shared/data is absent."""
    if not path.is_file():
        pytest.skip(f"shared data file {path} is absent (tests use ../shared/data relative to the repository)")
    return path


def write_wrfout(path: Path, *, nz=6, ny=4, nx=5, times=("2020-01-01_00:00:00",), drop=(), override=None,
                 mp_physics=6, dx=1000.0, species=("QCLOUD", "QRAIN", "QICE", "QSNOW", "QGRAUP"),
                 dz_w=500.0, terrain=None):
    """A small, self-consistent wrfout-like NetCDF file (hydrostatic-ish base state, flat terrain)."""
    import xarray as xr
    nt = len(times)
    zw = np.arange(nz + 1, dtype=np.float64) * dz_w
    zw = np.broadcast_to(zw[:, None, None], (nz + 1, ny, nx)).copy()
    if terrain is not None:
        zw = zw * (1 - terrain[None] / zw[-1:]) + terrain[None]
    zm = 0.5 * (zw[1:] + zw[:-1])
    pb = 1e5 * np.exp(-zm / 8000.0)
    data = {
        "P": np.zeros((nt, nz, ny, nx)), "PB": np.broadcast_to(pb, (nt, nz, ny, nx)).copy(),
        "T": np.full((nt, nz, ny, nx), 5.0), "QVAPOR": np.full((nt, nz, ny, nx), 0.005),
        "PH": np.zeros((nt, nz + 1, ny, nx)), "PHB": np.broadcast_to(zw * 9.81, (nt, nz + 1, ny, nx)).copy(),
    }
    for s in species:
        data[s] = np.zeros((nt, nz, ny, nx))
    data.update(override or {})
    dims_m = ("Time", "bottom_top", "south_north", "west_east")
    dims_w = ("Time", "bottom_top_stag", "south_north", "west_east")
    dims_2d = ("Time", "south_north", "west_east")  # MAPFAC_M, HGT, ...
    ds = xr.Dataset({k: ((dims_w if k in ("PH", "PHB") and np.shape(v)[1] == nz + 1 else dims_m)
                         if np.ndim(v) == 4 else dims_2d if np.ndim(v) == 3 and np.shape(v)[1:] == (ny, nx)
                         else tuple(f"d{i}_{k}" for i in range(np.ndim(v))), np.asarray(v, np.float32))
                     for k, v in data.items() if k not in drop})
    ds["Times"] = (("Time",), np.array([t.encode() for t in times], dtype="S19"))
    ds.attrs.update({"MP_PHYSICS": np.int32(mp_physics), "DX": np.float32(dx), "DY": np.float32(dx),
                     "TITLE": "OUTPUT FROM A TEST FACTORY", "MAP_PROJ": np.int32(0)})
    ds.to_netcdf(path)
    return path


@pytest.fixture
def variant_restored():
    """The Mitsuba variant as it was before the test (one that selects a spectral variant, say)."""
    import mitsuba as mi
    before = mi.variant()
    yield
    if before:
        weather_mi.set_variant(before)


@contextmanager
def storm_shadows_reused():
    """Within the block, ``optics.air.storm_shadow.storm_shadow`` (a pure function of the extinction grid, the box,
    the sun and the spacing) computes each distinct input once and hands the same result back for a repeat: a
    test module that renders the same demo cloud under the same sun many times through the CLI (whose eye rays'
    air computes the storm's shadow anew each time, most of a tiny render's time) pays for it once. The key is
    the grid's bytes, so a changed grid, box or sun is computed anew."""
    import hashlib

    from weather_mi.optics.air import storm_shadow as module
    real, done = module.storm_shadow, {}

    def reused(beta_total, bbox, to_sun, spacing_m=None):
        beta = np.ascontiguousarray(beta_total, np.float32)
        key = (hashlib.sha256(beta.tobytes()).hexdigest(), beta.shape, np.asarray(bbox, np.float64).tobytes(),
               np.asarray(to_sun, np.float64).tobytes(), spacing_m)
        if key not in done:
            done[key] = real(beta_total, bbox, to_sun, spacing_m)
        return done[key]
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(module, "storm_shadow", reused)
        yield done


@contextmanager
def kernels_compiled():
    """A list, filled when the block ends, of the Dr.Jit kernels the block did not find in memory: compiled, or
    loaded from Dr.Jit's disk cache (a kernel traced anew each frame, a value baked into it, is counted whether or
    not an earlier run left it on disk; only an in-memory hit, ``cache_hit`` without ``cache_disk``, is not)."""
    import drjit as dr
    found = []
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history()  # clear
    try:
        yield found
    finally:
        history = dr.kernel_history()
        dr.set_flag(dr.JitFlag.KernelHistory, False)
        found.extend(k for k in history if k.get("type") == dr.KernelType.JIT
                     and (k.get("cache_disk") or not k.get("cache_hit")))
