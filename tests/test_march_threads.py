"""The compiled slant columns on the calling thread for small work (``optics.air.march_kernels.threads_for``: the
slicer's per-frame sun column woke numba's OpenMP pool, 40 ms a call on a loaded machine): the same numbers as on
the pool, and the pool's thread count restored."""
from __future__ import annotations

import numba
import numpy as np

from weather_mi.optics.air import Atmosphere
from weather_mi.optics.air import march_kernels
from weather_mi.optics.air.shell import slant_columns


def test_small_marches_run_on_one_thread_and_give_the_pools_columns(monkeypatch):
    """129 heights at two suns (one below the horizon: both segments summed) on one thread against the same on
    the pool: identical columns (each point is summed alone); inside ``threads_for`` one thread, after it the
    pool's count again, and large work keeps the pool."""
    atm = Atmosphere()
    h = np.linspace(0.0, 22e3, 129)
    mu = np.concatenate([np.full(65, 0.3), np.full(64, -0.05)])
    threads = numba.get_num_threads()
    with march_kernels.threads_for(h.size * 128):
        assert numba.get_num_threads() == 1
    with march_kernels.threads_for(march_kernels.SERIAL_WORK):
        assert numba.get_num_threads() == threads
    assert numba.get_num_threads() == threads
    serial, blocked = slant_columns(atm.profiles, h, mu, 100e3, samples=128)
    monkeypatch.setattr(march_kernels, "SERIAL_WORK", 0)  # the pool for any work
    pooled, blocked_pool = slant_columns(atm.profiles, h, mu, 100e3, samples=128)
    assert np.array_equal(blocked, blocked_pool) and not blocked[:65].any()
    for name in serial:
        assert np.array_equal(serial[name], pooled[name]), name
        assert np.all(serial[name][~blocked] > 0)
