"""The spectral mode's tables kept across renders (issue 38, spectralcost38b): ``kernel.medium.
spectral_phase_values`` (the species' tables by wavelength, delta-M truncated and on the mixture's nodes) and
``lane_directions._host_tables`` (the lanes' alias tables) are built once per distinct input and found again by
the digest of what they are computed from. Checked: a repeat returns the same numbers as a fresh build (caches
cleared), as a copy the caller may change; inputs that differ only in the truncation, or in one table value, get
their own (different) tables, so a key that left them out fails."""
from __future__ import annotations

import numpy as np

import weather_mi as wm


def _cumulus():
    from weather_mi.optics.forward_peak import delta_scaled
    vol = wm.optical_volume(wm.synthetic.cumulus(shape=(12, 10, 10), spacing_m=(200.0, 200.0, 200.0)),
                            species="physical", phase_quality="test")
    return vol, delta_scaled(vol, 3.0, species_extinction=False)


def test_phase_values_kept_equal_a_fresh_build(variant_restored):
    from weather_mi.kernel import medium
    from weather_mi.kernel.plugins.hydrometeor_mixture import prepare_tables
    vol, scaled = _cumulus()
    nodes, _ = prepare_tables(scaled.require_phase_tables())
    species = [scaled.species_set[n] for n in scaled.species]
    medium._SPECTRAL_VALUES.clear()
    first = medium.spectral_phase_values(scaled, nodes, species)
    plain = medium.spectral_phase_values(vol, nodes, species)  # no truncation: its own tables
    assert len(medium._SPECTRAL_VALUES) == 2
    assert np.abs(plain[:, 0] - first[:, 0]).max() > 1.0  # the forward peak kept / taken out
    first[:] = -1.0  # the caller's copy
    again = medium.spectral_phase_values(scaled, nodes, species)
    assert len(medium._SPECTRAL_VALUES) == 2
    medium._SPECTRAL_VALUES.clear()
    fresh = medium.spectral_phase_values(scaled, nodes, species)
    np.testing.assert_array_equal(again, fresh)
    np.testing.assert_array_equal(medium.spectral_phase_values(vol, nodes, species), plain)


def test_alias_tables_kept_per_input(variant_restored):
    from weather_mi.kernel.plugins import lane_directions as ld
    rng = np.random.default_rng(3)
    nodes = np.linspace(0.0, 2.0, 65)
    values = rng.random((3, nodes.size, 5)).astype(np.float32) + 0.1
    ld._HOST.clear()
    exact, alias = ld._host_tables(values, (2,), nodes)
    exact2, alias2 = ld._host_tables(values.copy(), (2,), nodes.copy())
    assert len(ld._HOST) == 1 and exact2 is exact and alias2 is alias
    ld._HOST.clear()
    fresh = ld._host_tables(values, (2,), nodes)
    np.testing.assert_array_equal(fresh[0], exact)
    np.testing.assert_array_equal(fresh[1], alias)
    changed = values.copy()
    changed[0, 10, 1] *= 3.0
    other = ld._host_tables(changed, (2,), nodes)
    assert len(ld._HOST) == 2 and not np.array_equal(other[1], alias)
    assert ld._host_tables(values, (), nodes)[0] is not exact  # the flat species are part of the key
