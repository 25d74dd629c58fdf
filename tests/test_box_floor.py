"""The medium's box down to the ground (``kernel.scene_dict.medium_box``): hydrometeors without air used to
lose the bottom 3 x RAY_EPSILON x (1 + max|coord|) of the box (the box started that far above the ground; in a
periodic box 50 km wide, reaching 550 km out, 147 m). Rain reaching the ground, seen from above against the
closed form of Beer-Lambert through the whole column."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.kernel.scene_dict import RAY_EPSILON, medium_box

W_M, H_M = 50e3, 1000.0     # a periodic tile 50 km wide, rain from the ground (0 m) to 1 km
BETA_PER_M = 5e-4           # the rain's extinction: optical depth 0.5 of the column
GROUND_ALBEDO, MU0 = 0.5, 0.5


def _rain(periodic=True):
    """A purely absorbing field of constant extinction on the tile (periodic: the box reaches PATH_TILES tiles
    out on each side)."""
    vol = wm.OpticalVolume.from_arrays(np.full((4, 4, 4), BETA_PER_M, np.float32), 0.0, wm.phase.isotropic(),
                                       ((0.0, 0.0, 0.0), (W_M, W_M, H_M)))
    return dataclasses.replace(vol, periodic=periodic)


def test_box_reaches_below_the_ground_without_air():
    """Flat ground at the volume's floor: the box starts below the ground (it holds the ground, as over a
    terrain and as with the air), by three ray offsets; without a ground the box is the bbox; a ground well
    below the volume leaves the volume's floor; a volume wholly under the ground raises."""
    vol = _rain(periodic=False)
    gap = 3 * RAY_EPSILON * (1 + W_M)
    lo, hi = medium_box(vol, 0.0)
    assert lo[2] == pytest.approx(-gap, rel=1e-9) and hi[2] == H_M
    assert medium_box(vol, None)[0][2] == 0.0
    assert medium_box(vol, -500.0)[0][2] == 0.0
    assert medium_box(vol, 200.0)[0][2] == 0.0  # the volume reaching under the ground: down to its own floor
    with pytest.raises(ValueError, match="below the ground"):
        medium_box(vol, H_M)


def test_rain_reaching_the_ground_in_a_periodic_box_is_beer_lambert():
    """Nadir reflectance pi L / (mu0 E) of a Lambertian ground under a purely absorbing rain layer (periodic,
    the sun at 30 deg elevation): A exp(-tau (1 + 1 / mu0)), tau = beta H the whole column's optical depth.
    Within 3 se and 3 %; a box starting 147 m above the ground gave 22 % more (0.137 against 0.112)."""
    cam = wm.Camera.orthographic(center=(W_M / 2, W_M / 2, 3000.0), direction=(0, 0, -1), width=100.0,
                                 height=100.0)
    spec = wm.SceneSpec(camera=cam, sun=wm.Sun(azimuth=270.0, elevation=math.degrees(math.asin(MU0)),
                                               angular_diameter_deg=0.0),
                        sky=None, ground=wm.Ground(albedo=GROUND_ALBEDO), width=4, height=4, seed=5)
    img = wm.render_reference(spec, _rain(), spp=256, passes=4, progress=False, normalize="reflectance")
    r = img.radiance.reshape(-1, 3).astype(np.float64).mean(axis=0)
    se = np.sqrt((img.stderr.reshape(-1, 3).astype(np.float64) ** 2).sum(axis=0)) / 16
    closed = GROUND_ALBEDO * math.exp(-BETA_PER_M * H_M * (1 + 1 / MU0))
    for c in range(3):
        assert abs(r[c] - closed) < 3 * se[c] and abs(r[c] - closed) < 0.03 * closed, (c, r[c], se[c], closed)
