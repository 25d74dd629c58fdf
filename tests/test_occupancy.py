"""The eye pass visits only each ray's occupied span (weather_mi/slicing/occupancy.py): the span holds
every point where the interpolated extinction is positive, and frames are bit-identical to visiting
every slab of the box."""
import numpy as np

import weather_mi as wm
from weather_mi.slicing import MODES, SliceRenderer
from weather_mi.slicing.occupancy import occupied_blocks


def sparse_volume(seed=0):
    rng = np.random.default_rng(seed)
    beta = np.zeros((20, 24, 28), np.float32)
    for _ in range(6):  # a few small blobs, one touching the grid's edge
        z, y, x = rng.integers(0, 20), rng.integers(0, 24), rng.integers(0, 28)
        beta[max(z - 1, 0):z + 2, max(y - 1, 0):y + 2, max(x - 1, 0):x + 2] = rng.uniform(1e-3, 5e-3)
    beta[0, 0, 0] = 2e-3
    return wm.OpticalVolume.from_arrays(beta, 0.9, wm.phase.henyey_greenstein(0.8),
                                        ((0.0, 0.0, 0.0), (2800.0, 2400.0, 2000.0)))


def test_blocks_cover_the_interpolation_reach():
    a = np.zeros((9, 9, 9))
    a[4, 4, 4] = 1.0
    assert occupied_blocks(a, 3).all()                 # the voxel's block and every neighbour block
    a = np.zeros((12, 12, 12))
    a[0, 0, 0] = 1.0
    b = occupied_blocks(a, 4)
    assert b[:2, :2, :2].all() and b.sum() == 8        # no wrap-around to the far faces


def test_spans_hold_every_lit_point_and_frames_are_unchanged():
    vol = sparse_volume()
    spec = wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=35.0, elevation=25.0), sun=wm.Sun(120.0, 40.0),
                        sky=wm.Sky("sunsky"), ground=wm.Ground(0.2), width=48, height=36)
    r = SliceRenderer(vol, MODES["per-species/multiple"], slices=64, light_res=32)
    with_spans = r.frame(spec).radiance
    mi = r.mi
    import drjit as dr
    rays = r.views.get(mi, spec)
    ta, tb = (np.asarray(v, dtype=np.float64) for v in (rays.span_a, rays.span_b))
    o, d = np.asarray(rays.origin, dtype=np.float64).T, np.asarray(rays.direction, dtype=np.float64).T
    t0, t1 = np.asarray(rays.t0, dtype=np.float64), np.asarray(rays.t1, dtype=np.float64)
    lo, hi = (np.asarray(p, dtype=np.float64) for p in r.grid_box)
    ts = t0[:, None] + (t1 - t0)[:, None] * np.linspace(0.0, 1.0, 400)[None]  # a fine march of every ray
    p = o[:, None] + ts[..., None] * d[:, None]
    q = (p - lo) / (hi - lo)
    ext = np.asarray(r.tex_light_src.eval(mi.Point3f(*(mi.Float(q[..., i].ravel()) for i in range(3))))[0]).reshape(ts.shape)
    lit = (ext > 0) & (t1 > t0)[:, None]
    assert lit.any()
    assert np.all(ts[lit] >= np.broadcast_to(ta[:, None], ts.shape)[lit] - 1e-3)
    assert np.all(ts[lit] <= np.broadcast_to(tb[:, None], ts.shape)[lit] + 1e-3)
    assert np.mean(np.where(tb > ta, tb - ta, 0.0)) < 0.8 * np.mean(np.maximum(t1 - t0, 0.0))  # it skips something
    # every slab of the box: the spans widened to the rays' whole box
    rays.span_a, rays.span_b = mi.Float(t0), mi.Float(t1)
    r.frozen = False
    np.testing.assert_array_equal(with_spans, r.frame(spec).radiance)
    dr.eval()
