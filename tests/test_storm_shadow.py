"""The storm's shadow on the air outside its box (``optics.air.storm_shadow``, issue 38): the shadow map of a
uniform box against its chord length (the slab method written here), and the single scattering of an eye ray
through the shadow against the same segment with the exact chord's transmittance; the shadow darkens the
in-scatter of the air between the camera and a storm lit from behind."""
from __future__ import annotations

import numpy as np

from weather_mi.optics.air import Atmosphere
from weather_mi.optics.air.eye_path import segment_air, wide_sun_table
from weather_mi.optics.air.storm_shadow import storm_shadow

LO, HI = np.array([-5e3, -4e3, 1e3]), np.array([5e3, 4e3, 9e3])
BETA = 2e-4  # 1/m: tau 1.6 - 2 across the box


def chord_m(points, s):
    """Length of the box's chord ahead of each point along s (0 where none)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / np.where(np.abs(s) < 1e-12, 1e-12, s)
        t0, t1 = (LO - points) * inv, (HI - points) * inv
    t_in = np.maximum(np.max(np.minimum(t0, t1), axis=-1), 0.0)
    t_out = np.min(np.maximum(t0, t1), axis=-1)
    return np.maximum(t_out - t_in, 0.0)


def _uniform():
    return np.full((16, 16, 20), BETA, np.float32)


def test_shadow_map_of_a_uniform_box_is_its_chord():
    to_sun = np.array([0.6, -0.3, 0.25])
    sh = storm_shadow(_uniform(), (LO, HI), to_sun)
    s = to_sun / np.linalg.norm(to_sun)
    rng = np.random.default_rng(2)
    p = (LO + HI) / 2 - 40e3 * s + rng.normal(scale=2.5e3, size=(4000, 3))  # behind the box, seen from the sun
    length = chord_m(p, s)
    solid = length > 3e3  # lines well inside the box's projection
    assert solid.sum() > 500 and (length == 0).sum() > 50
    got = sh.transmittance(p)
    np.testing.assert_allclose(-np.log(got[solid]), BETA * length[solid], rtol=0.03, atol=BETA * 2 * sh.h)
    assert np.all(got[length == 0] == 1.0)
    front = (LO + HI) / 2 + 40e3 * s  # on the sun's side of the box: no shadow
    assert sh.transmittance(front[None])[0] == 1.0


def test_in_scatter_through_the_shadow_against_the_exact_chord():
    atm = Atmosphere()
    to_sun = np.array([0.0, 1.0, 0.12])  # a low sun behind the storm, seen from the camera at y = -60 km
    s = to_sun / np.linalg.norm(to_sun)
    sh = storm_shadow(_uniform(), (LO, HI), to_sun)
    table = wide_sun_table(atm, s[2])
    o = np.array([[0.0, -60e3, 1.5e3], [2e3, -60e3, 3e3], [30e3, -60e3, 3e3]])  # the last one beside the shadow
    d = np.array([[0.0, 1.0, 0.03], [0.0, 1.0, 0.05], [0.0, 1.0, 0.05]])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    t1 = np.full(3, 55e3)
    exact = lambda q: np.exp(-BETA * chord_m(q.reshape(-1, 3), s)).reshape(q.shape[:-1])  # noqa: E731
    _, s_map = segment_air(atm, to_sun, o, d, np.zeros(3), t1, table, shadow=sh.transmittance)
    _, s_exact = segment_air(atm, to_sun, o, d, np.zeros(3), t1, table, shadow=exact)
    _, s_none = segment_air(atm, to_sun, o, d, np.zeros(3), t1, table)
    np.testing.assert_allclose(s_map, s_exact, rtol=0.04)  # the map blurs the shadow's edge over one line spacing
    assert np.all(s_map[:2] < 0.95 * s_none[:2])  # the shadow matters on the rays through it
    np.testing.assert_allclose(s_map[2], s_none[2], rtol=1e-12)
