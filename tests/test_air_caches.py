"""The per-atmosphere caches of a new sun's work (issue 38 part 3, benchmarks/README.md "fourth pass"): the same
floats as the uncached path, and a new atmosphere not served another's values."""
import numpy as np

from weather_mi.optics.air import Atmosphere
from weather_mi.optics.air.atmosphere import TOP_M
from weather_mi.optics.air.shell import _profile_table, slant_columns
from weather_mi.optics.air.sunlight import sun_rgb


def test_kept_profiles_give_the_same_columns_as_a_fresh_table():
    atm = Atmosphere()
    h, mu = np.linspace(0.0, 20e3, 7), np.linspace(-0.05, 1.0, 7)
    kept, blocked = slant_columns(atm.profiles, h, mu, TOP_M, samples=64)   # a bound method: the kept table
    fresh, blocked_f = slant_columns(lambda z: atm.profiles(z), h, mu, TOP_M, samples=64)  # a lambda: tabulated anew
    assert _profile_table.cache_info().currsize >= 1
    assert np.array_equal(blocked, blocked_f)
    for k in fresh:
        assert np.array_equal(kept[k], fresh[k]), k


def test_a_second_atmosphere_gets_its_own_values():
    h, mu = np.array([0.0, 3e3]), np.array([0.1, 0.1])
    clear, hazy = Atmosphere(), Atmosphere(aod_550=1.0, ozone_atm_cm=0.5, water_vapour_cm=4.0)
    a = sun_rgb(clear, h, mu, samples=64)
    b = sun_rgb(hazy, h, mu, samples=64)
    assert np.array_equal(sun_rgb(clear, h, mu, samples=64), a)
    # Beer-Lambert on the direct beam: ten times the aerosol dims and reddens the low sun (blue over red falls)
    assert np.all(b.sum(axis=-1) < a.sum(axis=-1))
    assert np.all(b[:, 2] / b[:, 0] < a[:, 2] / a[:, 0])
