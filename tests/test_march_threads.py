"""The compiled slant columns on the calling thread for small work (``optics.air.march_kernels.SERIAL_WORK``: the
serial kernel below it; the slicer's per-frame sun column woke numba's OpenMP pool, 40 ms a call on a loaded
machine): the same numbers as the parallel kernel's."""
from __future__ import annotations

import numpy as np

from weather_mi.optics.air import Atmosphere
from weather_mi.optics.air import march_kernels
from weather_mi.optics.air.shell import slant_columns


def test_small_marches_run_serially_and_give_the_parallel_kernels_columns(monkeypatch):
    """129 heights at two suns (one below the horizon: both segments summed) through the serial kernel against
    the parallel one (forced with ``SERIAL_WORK`` 0): identical columns (each point is summed alone), and the
    choice is the one expected on each side (the kernels counted)."""
    atm = Atmosphere()
    h = np.linspace(0.0, 22e3, 129)
    mu = np.concatenate([np.full(65, 0.3), np.full(64, -0.05)])
    calls = []
    for name in ("_slant_columns_serial", "_slant_columns_parallel"):
        kernel = getattr(march_kernels, name)
        monkeypatch.setattr(march_kernels, name, lambda *a, _k=kernel, _n=name: calls.append(_n) or _k(*a))
    serial, blocked = slant_columns(atm.profiles, h, mu, 100e3, samples=128)
    monkeypatch.setattr(march_kernels, "SERIAL_WORK", 0)  # the parallel kernel for any work
    pooled, blocked_pool = slant_columns(atm.profiles, h, mu, 100e3, samples=128)
    assert calls == ["_slant_columns_serial", "_slant_columns_parallel"]
    assert np.array_equal(blocked, blocked_pool) and not blocked[:65].any()
    for name in serial:
        assert np.array_equal(serial[name], pooled[name]), name
        assert np.all(serial[name][~blocked] > 0)
