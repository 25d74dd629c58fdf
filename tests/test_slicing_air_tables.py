"""The slicer's air read from cheaper tables (issue 38 part 3, the air's cost per drag frame): the sun's colour by
height of a new sun off a per-atmosphere table over sun elevations, the air's coefficients as its profiles times
cross sections, and the storm's shadow outside the slicing box from the light volume's last plane. Each against the
computation it replaces."""
from __future__ import annotations

import types

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.optics.air import Atmosphere
from weather_mi.optics.air.inside import CHANNEL_NM
from weather_mi.slicing import sun_air, sun_air_table
from weather_mi.optics.air.ozone import channel_cross_section_m2, cross_section_m2
from weather_mi.slicing.eye_air import HEIGHT_STEP_M, cross_sections, height_table


@pytest.mark.parametrize("elevation", [2.0, 2.3, 3.7, 4.0, 11.5, 35.0, 62.0, 89.9])
def test_a_new_suns_colour_by_height_off_the_elevation_table(elevation):
    """``sun_rows`` (cubic in sqrt(elevation) on the per-atmosphere table) against ``sun_by_height`` (the slant
    columns for that sun): within 1e-4 of each height's brightest channel (measured 4.6e-5 at worst, 2-90 deg),
    5e-4 in a hazier, drier atmosphere (1.8e-4: the dimmest heights of a low sun through AOD 0.4)."""
    for atm, bound in ((Atmosphere(), 1e-4), (Atmosphere(aod_550=0.4, water_vapour_cm=0.5), 5e-4)):
        spec = types.SimpleNamespace(atmosphere=atm, sun=wm.Sun(240.0, elevation))
        h, exact = sun_air.sun_by_height(spec, 18000.0)
        h2, table = sun_air_table.sun_rows(spec, 18000.0)
        np.testing.assert_array_equal(h, h2)
        assert np.max(np.abs(table - exact) / exact.max(axis=1, keepdims=True)) < bound


def test_a_sun_below_the_tables_lowest_elevation_is_computed_for_itself():
    """Below ``ELEVATION_MIN_DEG`` (the terminator's heights) the rows are the slant columns' own."""
    spec = types.SimpleNamespace(atmosphere=Atmosphere(), sun=wm.Sun(240.0, 0.5 * sun_air_table.ELEVATION_MIN_DEG))
    np.testing.assert_array_equal(sun_air_table.sun_rows(spec, 18000.0)[1], sun_air.sun_by_height(spec, 18000.0)[1])


@pytest.mark.parametrize("elevation", [2.1, 4.0, 35.0, 88.0])
def test_the_kernels_fine_rows_are_the_hosts(elevation):
    """``sun_air_table.as_sun_air`` of a ``sun_source`` (a kernel from the uploaded elevation table) against
    ``sun_rows`` interpolated on the same fine heights by ``np.interp`` on the host: within 2e-5 of each height's
    brightest channel (float32)."""
    from weather_mi.kernel.variant import ensure_registered
    ensure_registered()
    import mitsuba as mi
    kept = {}

    def reuse(name, key, make):
        return kept.setdefault((name, key), make())
    spec = types.SimpleNamespace(atmosphere=Atmosphere(), sun=wm.Sun(240.0, elevation))
    source = sun_air_table.sun_source(mi, spec, 18000.0, 4096, reuse)
    h0, h1 = float(source.h0[0]), float(source.h0[0]) + 4095 / float(source.inv_dh[0])
    rgb = np.asarray(sun_air_table.source_rows(mi, source)).T  # (rows, 3)
    heights, rows = sun_air_table.sun_rows(spec, 18000.0)
    fine = np.linspace(h0, h1, 4096)
    host = np.stack([np.interp(fine, heights, rows[:, c]) for c in range(3)], axis=1)
    dev = np.asarray(rgb).reshape(-1, 3)
    exact = sun_air.sun_by_height(spec, 18000.0)[0]  # the slant columns' own heights, not the table's
    np.testing.assert_allclose((h0, h1), (exact[0], exact[-1]), rtol=1e-6)  # the step: (rows - 1) / (h1 - h0)
    assert np.max(np.abs(dev[:, :3] - host) / np.abs(host).max(axis=1, keepdims=True)) < 2e-5


def test_the_air_profiles_times_cross_sections_are_its_coefficients():
    """``height_table``'s profiles times ``cross_sections`` give the atmosphere's extinction at R, G, B
    (``Atmosphere.extinction_per_m``), the molecules' scattering (their extinction: Rayleigh) and the aerosol's
    (extinction times its single-scattering albedo), at every height of the table."""
    atm = Atmosphere(aod_550=0.25, ozone_atm_cm=0.35)
    prof, cross = height_table(atm), cross_sections(atm)
    h = np.arange(prof.shape[0]) * HEIGHT_STEP_M
    ext = prof[:, 0:1] * cross[0] + prof[:, 1:2] * cross[1] + prof[:, 2:3] * cross[2]
    # the RGB channels' ozone is the band average (air.ozone), not the line's that extinction_per_m reads
    # (the band averages are pinned by test_air.py against colour-science's projection of sunlight)
    band_minus_line = channel_cross_section_m2(CHANNEL_NM) - cross_section_m2(np.asarray(CHANNEL_NM))
    expected = atm.extinction_per_m(CHANNEL_NM, h) + atm.ozone_number_density_m3(h)[:, None] * band_minus_line
    np.testing.assert_allclose(ext, expected, rtol=1e-9)
    aerosol = atm.aerosol_extinction_550_per_m(h)[:, None] * atm.aerosol_factor(np.asarray(CHANNEL_NM))
    np.testing.assert_allclose(prof[:, 2:3] * cross[3], aerosol * atm.aerosol_ssa, rtol=1e-12)
    assert np.all(cross[3] < cross[2]) and np.all(cross[1][:2] > 0)  # absorbing aerosol, ozone's Chappuis band


def test_the_shadow_outside_the_box_is_the_light_leaving_it():
    """``light_shadow``'s ``outside`` (the light volume's last plane at the point's light ray) against the
    general lookup (the light read where the point's sun ray enters the box) at points around the demo storm's
    slicing box, in its shadow and out of it: the same light (within 1e-5) at 99% of them (measured 1.8e-6);
    within 0.15 at the few (0.1%) whose sun ray leaves the box through the storm (the slicing box is the grid's
    where the storm reaches it), where the last plane holds the light after the whole chord and the general
    lookup interpolates between the two planes around the box's face."""
    from weather_mi.slicing import MODES, SliceRenderer
    from weather_mi.slicing.eye_air import light_shadow
    vol = wm.optical_volume(wm.synthetic.supercell(), species="physical")
    r = SliceRenderer(vol, MODES["uniform/translucent"], slices=64, light_res=64)
    sun = wm.Sun(240.0, 25.0)
    spec = wm.scene.spec.default_spec(vol, 48, 48)
    r.frame(wm.SceneSpec(camera=spec.camera, sun=sun, sky=spec.sky, ground=spec.ground, width=48, height=48,
                         atmosphere=Atmosphere()))
    mi = r.mi
    lo, hi = (np.asarray(c, np.float64) for c in (r.light.lo, r.light.hi))
    rng = np.random.default_rng(3)
    p = lo + (hi - lo) * rng.uniform(-0.8, 1.8, (4000, 3))
    p = p[np.any((p < lo) | (p > hi), axis=1)]  # outside the slicing box
    to_sun = np.asarray(sun.to_sun, np.float64)
    shadow = light_shadow(mi, r.light, mi.Vector3f(*to_sun.tolist()))
    q = mi.Point3f(*(mi.Float(p[:, i].astype(np.float32)) for i in range(3)))
    general, last_plane = np.asarray(shadow(q)), np.asarray(shadow.outside(q))
    assert np.mean(general < 0.5) > 0.02 and np.mean(general > 0.99) > 0.2  # points in the shadow and out of it
    diff = np.abs(last_plane - general)
    assert np.percentile(diff, 99) < 1e-5, np.percentile(diff, [50, 99, 100])
    assert diff.max() < 0.15  # (the few whose sun ray leaves the box through the storm: see the docstring)


def test_the_sun_colour_read_from_one_word_a_row_is_the_row_within_2_to_the_minus_14():
    """``sun_air.sun_colour_at`` reads each row as one 64-bit word (``packets.rgb_words``: per channel the float32
    rounded to 13 mantissa bits): against the rows themselves (numpy float32), every channel within 2^-14 of its
    own value (not of the brightest), zero stays zero, the channels in order, and the nearest row at each height."""
    from weather_mi.kernel.variant import ensure_registered
    ensure_registered()
    import drjit as dr
    import mitsuba as mi
    rng = np.random.default_rng(38)
    rows = np.exp(rng.uniform(-14.0, 1.0, (1000, 3))).astype(np.float32)  # sun colours of 1e-6 .. 2.7
    rows[:3] = [[0.0, 0.5, 1.0], [1.0, 0.0, 0.25], [np.float32(0.1), np.float32(0.2), 0.0]]
    sun = sun_air.sun_air_of_rows(mi, dr.opaque(mi.Float, 100.0), dr.opaque(mi.Float, 0.5),
                                  mi.Color3f(*(mi.Float(rows[:, c]) for c in range(3))))
    z = 100.0 + 2.0 * np.arange(1000) + rng.uniform(-0.9, 0.9, 1000)  # within the nearest row's half step
    got = np.asarray(sun_air.sun_colour_at(mi, sun, mi.Float(z.astype(np.float32)))).T
    assert np.all(got[rows == 0] == 0)
    rel = np.abs(got - rows)[rows > 0] / rows[rows > 0]
    assert rel.max() <= 2.0 ** -14 and np.median(rel) > 1e-6  # rounded (not the float32 itself)
