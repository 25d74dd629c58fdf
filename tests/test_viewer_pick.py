"""``weather_mi.viewer.pick.first_dense_voxel`` (the viewer's hover read-out): a synthetic grid with one
dense block at a known place, cameras looking at it along the axes; expected cells, points and
distances worked out by hand from the grid's geometry, the camera rays checked against Mitsuba's own
sensors."""
from __future__ import annotations

import numpy as np
import pytest

import mitsuba as mi

import weather_mi as wm
from weather_mi.viewer.pick import DenseMixingRatios, default_threshold_per_m, first_dense_voxel, pixel_ray

# cells of (dz, dy, dx) = (100, 200, 250) m, the box from (0, 0, 0) to (3500, 2400, 1000) m (x, y, z)
NZ, NY, NX = 10, 12, 14
DZ, DY, DX = 100.0, 200.0, 250.0
# the dense block: k 3..5 (z 300..600 m), j 4..7 (y 800..1600 m), i 6..9 (x 1500..2500 m)
BLOCK = (slice(3, 6), slice(4, 8), slice(6, 10))
W, H = 32, 24


@pytest.fixture(scope="module")
def storm():
    rng = np.random.default_rng(7)
    q_cloud = np.full((NZ, NY, NX), 1e-9)                # faint everywhere: below the default threshold
    q_cloud[BLOCK] = rng.uniform(5e-4, 1.5e-3, q_cloud[BLOCK].shape)
    q_ice = np.zeros((NZ, NY, NX))
    q_ice[BLOCK] = rng.uniform(1e-4, 3e-4, q_ice[BLOCK].shape)
    hyd = wm.from_arrays({"cloud": q_cloud, "ice": q_ice}, rho_air=1.0, spacing=(DZ, DY, DX),
                         origin=(DZ / 2, DY / 2, DX / 2))
    vol = wm.optical_volume(hyd, species="physical", phase_quality="test")
    assert vol.bbox == ((0.0, 0.0, 0.0), (NX * DX, NY * DY, NZ * DZ))
    return hyd, vol


def spec_of(camera, ground=None) -> wm.SceneSpec:
    return wm.SceneSpec(camera=camera, sky=wm.Sky("constant"), ground=ground, width=W, height=H)


def looking_east(x0=-5000.0, y=1100.0, z=450.0, fov=30.0) -> wm.Camera:
    return wm.Camera(origin=(x0, y, z), target=(x0 + 1000.0, y, z), fov=fov)


def expected_read_out(hyd, vol, k, j, i):
    q = {s: float(hyd[f"q_{s}"].values[k, j, i]) for s in wm.hydrometeors.SPECIES_NAMES}
    ext = vol.beta_ext[:, k, j, i]
    return q, vol.species[int(np.argmax(ext))]


def test_centre_pixel_picks_the_near_face_of_the_block_with_its_mixing_ratios(storm):
    hyd, vol = storm
    hit = first_dense_voxel(hyd, vol, spec_of(looking_east()), W / 2, H / 2)
    # the central ray runs along +x at y = 1100 (cell j 5), z = 450 (cell k 4); the block starts at x 1500 (i 6)
    assert hit["index"] == (4, 5, 6)
    assert hit["position_m"] == pytest.approx((1500.0, 1100.0, 450.0), abs=1e-6)
    assert hit["distance_m"] == pytest.approx(6500.0, abs=1e-6)
    assert hit["centre_m"] == pytest.approx((1625.0, 1100.0, 450.0))
    q, dominant = expected_read_out(hyd, vol, 4, 5, 6)
    assert hit["mixing_ratio_kg_per_kg"] == q          # exactly the input's values (float32)
    assert q["cloud"] > 5e-4 and q["ice"] > 1e-4 and q["rain"] == 0.0
    assert hit["dominant"] == dominant == "cloud"
    assert hit["beta_ext_per_m"] == pytest.approx(float(vol.beta_total[4, 5, 6]))
    assert hit["beta_ext_per_m"] > default_threshold_per_m(vol)


def test_pixel_centres_and_rows_from_the_top(storm):
    hyd, vol = storm
    spec = spec_of(looking_east())
    # row 11 (its centre 0.5 px above the middle of 24 rows) looks up by tan(15 deg) 3/4 / 24 = 0.0084:
    # 54 m above the centre line at the block's face 6500 m away; column 14 (1.5 px left of the middle)
    # looks north (left, facing east) by tan(15 deg) 3 / 32: 163 m
    tan_x = np.tan(np.radians(15.0))
    up = first_dense_voxel(hyd, vol, spec, W / 2, 11.5)
    z = 450.0 + 6500.0 * tan_x * H / W * 1.0 / H
    assert up["position_m"] == pytest.approx((1500.0, 1100.0, z), abs=1e-6)
    assert up["index"] == (int(z // DZ), 5, 6) == (5, 5, 6)
    left = first_dense_voxel(hyd, vol, spec, 14.5, H / 2)
    y = 1100.0 + 6500.0 * tan_x * 3.0 / W
    assert left["position_m"] == pytest.approx((1500.0, y, 450.0), abs=1e-6)
    assert left["index"] == (4, int(y // DY), 6) == (4, 6, 6)
    assert left["mixing_ratio_kg_per_kg"] == expected_read_out(hyd, vol, 4, 6, 6)[0]
    # row 10 looks 163 m up: above the block's top (600 m) at its face, and rising: nothing
    assert first_dense_voxel(hyd, vol, spec, W / 2, 10.5) is None


def test_a_pixel_beside_the_block_sees_nothing(storm):
    hyd, vol = storm
    spec = spec_of(looking_east())
    # px 7: lateral slope (1 - 14/32) tan 15 deg = 0.151: y = 1853 m where it enters the box (x 0),
    # 2080 m at the block's near face: through clear cells of the box, north of the block (y < 1600)
    assert first_dense_voxel(hyd, vol, spec, 7.0, H / 2) is None
    # ... where the faint background counts (any extinction): the first cell of the box, at x = 0
    faint = first_dense_voxel(hyd, vol, spec, 7.0, H / 2, threshold_per_m=0.0)
    slope = (1 - 14 / 32) * np.tan(np.radians(15.0))
    assert faint["index"] == (4, int((1100 + 5000 * slope) // DY), 0)
    assert faint["distance_m"] == pytest.approx(5000.0 * np.sqrt(1 + slope ** 2), abs=1e-6)
    assert faint["dominant"] == "cloud" and faint["mixing_ratio_kg_per_kg"]["cloud"] == pytest.approx(1e-9)
    # outside the picture, or a camera looking away from the box
    assert first_dense_voxel(hyd, vol, spec, -1.0, H / 2) is None
    away = spec_of(wm.Camera(origin=(-5000.0, 1100.0, 450.0), target=(-6000.0, 1100.0, 450.0), fov=30.0))
    assert first_dense_voxel(hyd, vol, away, W / 2, H / 2) is None


def test_camera_inside_the_box(storm):
    hyd, vol = storm
    # in cell i 2 (x 700 m) looking east: the block's near face 800 m ahead
    hit = first_dense_voxel(hyd, vol, spec_of(looking_east(x0=700.0)), W / 2, H / 2)
    assert hit["index"] == (4, 5, 6) and hit["distance_m"] == pytest.approx(800.0, abs=1e-6)
    # beyond the block (x 3000 m, cell i 12) looking west: its far face (i 9, x 2500 m) 500 m ahead
    west = wm.Camera(origin=(3000.0, 1100.0, 450.0), target=(2000.0, 1100.0, 450.0), fov=30.0)
    hit = first_dense_voxel(hyd, vol, spec_of(west), W / 2, H / 2)
    assert hit["index"] == (4, 5, 9) and hit["distance_m"] == pytest.approx(500.0, abs=1e-6)
    assert hit["mixing_ratio_kg_per_kg"] == expected_read_out(hyd, vol, 4, 5, 9)[0]
    # inside the block itself: the cell the camera is in
    hit = first_dense_voxel(hyd, vol, spec_of(looking_east(x0=2100.0)), W / 2, H / 2)
    assert hit["index"] == (4, 5, 8) and hit["distance_m"] == pytest.approx(0.0, abs=1e-9)


def test_orthographic_camera_looking_down(storm):
    hyd, vol = storm
    # 3200 m x 2400 m film, 100 m per pixel, north at the top, centred on (1875, 1100) 2 km up
    cam = wm.Camera.orthographic(center=(1875.0, 1100.0, 2000.0), direction=(0.0, 0.0, -1.0), width=3200.0,
                                 height=2400.0)
    spec = spec_of(cam)
    hit = first_dense_voxel(hyd, vol, spec, W / 2, H / 2)
    assert hit["index"] == (5, 5, 7)                       # the block's top layer (z 500..600 m)
    assert hit["position_m"] == pytest.approx((1875.0, 1100.0, 600.0), abs=1e-6)
    assert hit["distance_m"] == pytest.approx(1400.0, abs=1e-6)
    # pixel column 19 (centre 19.5): 350 m east; row 5 (centre 5.5): 650 m north, y 1750 m: off the block
    east = first_dense_voxel(hyd, vol, spec, 19.5, H / 2)
    assert east["position_m"][:2] == pytest.approx((2225.0, 1100.0), abs=1e-6) and east["index"] == (5, 5, 8)
    assert first_dense_voxel(hyd, vol, spec, W / 2, 5.5) is None
    assert first_dense_voxel(hyd, vol, spec, W / 2, 9.5)["position_m"][1] == pytest.approx(1350.0, abs=1e-6)


def test_the_ground_hides_what_is_below_it(storm):
    hyd, vol = storm
    cam = wm.Camera.orthographic(center=(1875.0, 1100.0, 2000.0), direction=(0.0, 0.0, -1.0), width=3200.0,
                                 height=2400.0)
    assert first_dense_voxel(hyd, vol, spec_of(cam, ground=wm.Ground(height=700.0)), W / 2, H / 2) is None
    assert first_dense_voxel(hyd, vol, spec_of(cam, ground=wm.Ground(height=550.0)), W / 2, H / 2) is not None


@pytest.mark.parametrize("camera", [
    wm.Camera(origin=(-4000.0, 300.0, 1900.0), target=(1700.0, 1300.0, 400.0), fov=50.0),
    wm.Camera(origin=(900.0, 1700.0, 20.0), target=(1000.0, 1800.0, 900.0), fov=120.0),  # looking up, wide
    # near the origin: Camera.orthographic's target is 1 m ahead, which float32 resolves to 1e-4 at 3 km
    wm.Camera.orthographic(center=(18.0, -30.0, 7.0), direction=(0.2, 1.0, -0.1), width=900.0, height=500.0),
], ids=["perspective", "wide-up", "orthographic"])
def test_pixel_rays_are_mitsubas_sensor_rays(camera):
    from weather_mi.kernel.scene_dict import sensor_dict
    spec = wm.SceneSpec(camera=camera, width=40, height=30)
    sensor = mi.load_dict(sensor_dict(spec))
    for px, py in [(0.0, 0.0), (40.0, 30.0), (3.25, 27.5), (20.0, 15.0), (39.5, 0.5)]:
        ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(px / 40, py / 30), mi.Point2f(0.5, 0.5))
        o, d = pixel_ray(spec, px, py)
        mo, md = np.array(ray.o, np.float64).ravel(), np.array(ray.d, np.float64).ravel()
        np.testing.assert_allclose(d, md, atol=2e-6)
        # Mitsuba starts its rays at the near clip plane (perspective 1 m, orthographic 1 mm ahead): on ours
        along = float(np.dot(mo - o, d))
        assert 0.0 <= along < 3.0
        np.testing.assert_allclose(o + along * d, mo, atol=5e-3)


class _BigGrid:
    """What first_dense_voxel reads of an OpticalVolume, for a 300 x 300 x 128 grid without the albedo
    and phase weights (a 150 km x 150 km x 20 km storm box)."""
    species = ("cloud",)
    bbox = ((0.0, 0.0, 0.0), (150e3, 150e3, 20e3))

    def __init__(self):
        self.beta_total = np.zeros((128, 300, 300), np.float32)
        self.beta_total[60:, 200:, 250:] = 1e-2
        self.beta_ext = self.beta_total[None]

    @property
    def spacing(self):
        (x0, y0, z0), (x1, y1, z1) = self.bbox
        nz, ny, nx = self.beta_total.shape
        return ((z1 - z0) / nz, (y1 - y0) / ny, (x1 - x0) / nx)


def test_a_long_ray_through_a_big_grid_finds_the_blocks_face():
    """A diagonal through ~600 cells before the block (the pick's speed, 20 ms, is benchmarks/viewer_pick.py's
    goal, not a timed test)."""
    big = _BigGrid()
    spec = spec_of(wm.Camera(origin=(-1000.0, -3000.0, 500.0), target=(150e3, 150e3, 18e3), fov=40.0))
    hit = first_dense_voxel(None, big, spec, W / 2, H / 2)
    # it enters the block through its west face (x 125 km, i 250) at y 124.7 km, z 15 km
    assert hit is not None and hit["index"][2] == 250 and hit["index"][1] == 249 and hit["index"][0] >= 60


def test_the_dense_cells_mixing_ratios_read_out_as_the_dataset_and_hold_only_the_block(storm):
    """The viewer's read-out store (``DenseMixingRatios``): the block's 48 cells and nothing of the faint rest
    (the volume's optical depth 0.1 a cell is the line), their values exactly the Dataset's, the same hits."""
    hyd, vol = storm
    dense = DenseMixingRatios(hyd, vol)
    block_cells = 3 * 4 * 4
    assert dense.index.size == block_cells
    kk, jj, ii = np.unravel_index(dense.index, (NZ, NY, NX))
    assert (kk.min(), kk.max(), jj.min(), jj.max(), ii.min(), ii.max()) == (3, 5, 4, 7, 6, 9)
    assert np.array_equal(np.sort(dense.q["cloud"]), np.sort(hyd["q_cloud"].values[BLOCK].ravel()))
    assert dense.nbytes <= block_cells * (8 + 4 * len(dense.q))
    for k, j, i in [(3, 4, 6), (5, 7, 9), (4, 6, 8)]:
        assert dense.at(k, j, i) == {s: float(hyd[f"q_{s}"].values[k, j, i]) for s in dense.q}
    with pytest.raises(KeyError, match="not denser"):
        dense.at(0, 0, 0)
    spec = spec_of(looking_east())
    for px, py in [(W / 2, H / 2), (W / 2, 11.5), (14.5, H / 2), (17.5, 13.0)]:
        a, b = first_dense_voxel(hyd, vol, spec, px, py), first_dense_voxel(dense, vol, spec, px, py)
        assert a is not None and a == b
