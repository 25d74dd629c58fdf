"""The air in the box as ``majorant_volpath``'s trackers see it (``kernel/plugins/air_levels.py``, issue 38): a
cloud inside an RGB air that varies with height only. Cells that hold the air alone are crossed as empty space
with the air's own majorant, and their optical depth is taken in closed form. Checked against numbers that do
not come from that code: the optical depth of the trilinear interpolant by a fine midpoint rule in numpy, and
Mitsuba's stock ``volpath`` (delta tracking against one global majorant) on the same scene; and the library:
``render_reference`` with ``spec.atmosphere`` puts the same air into the box as ``with_box_air``."""
from __future__ import annotations

import numpy as np
import pytest

import mitsuba as mi

import weather_mi  # noqa: F401  (variant + plugins)
from weather_mi.kernel.plugins import majorant_volpath as mv
from weather_mi.kernel.plugins.trackers import exact_transmittance
from test_majorant_volpath import HI, LO, assert_agree, bbox_tf, blobs, optical_depth_numpy, passes, scene_dict

mv.register()

AIR_SCALE = np.array([0.08, 0.12, 0.2])  # 1/m at the bottom, R, G, B: tau ~ 0.3 - 0.8 across the 4 m box


def air_profile(nz: int) -> np.ndarray:
    """(nz, 3) extinction per level: decaying with height, with a bump near the top (an ozone-like layer)."""
    z = (np.arange(nz) + 0.5) / nz
    return (AIR_SCALE[None, :] * (np.exp(-3.0 * z) + 0.3 * np.exp(-((z - 0.8) / 0.1) ** 2))[:, None]).astype(np.float32)


def cloud_in_air(shape=(16, 32, 32)):
    """(sigma_t (z, y, x, 3), the cloud (z, y, x), the air (z, 3)): the medium's grid holds their sum."""
    cloud = blobs(shape)
    air = air_profile(shape[0])
    return (cloud[..., None] + air[:, None, None, :]).astype(np.float32), cloud, air


def air_scene(sigma_rgb, integrator, **kw):
    d = scene_dict(sigma_rgb[..., 0], integrator, **kw)
    d["cloud"]["sigma_t"]["data"] = mi.TensorXf(sigma_rgb)
    d["cloud"]["has_spectral_extinction"] = True
    return d


def ours_air(sigma_rgb, air, **kw):
    return {"type": "majorant_volpath", "majorant": mi.TensorXf(mv.majorant_grid(sigma_rgb, 4)), "cell": 4,
            "to_world": bbox_tf(), "air_extinction": mi.TensorXf(air), **kw}


def random_rays(seed: int, n: int):
    """``n`` rays from around the box (a fifth nearly horizontal) with lengths up to 16: numpy origins,
    directions and lengths, and the Mitsuba ray."""
    rng = np.random.default_rng(seed)
    o = LO - 2.0 + rng.random((n, 3)) * (HI - LO + 4.0)
    d = rng.normal(size=(n, 3))
    d[: n // 5, 2] *= 1e-3  # nearly horizontal
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    t_end = rng.random(n) * 16.0
    ray = mi.Ray3f(mi.Point3f(*(o[:, k].astype(np.float32) for k in range(3))),
                   mi.Vector3f(*(d[:, k].astype(np.float32) for k in range(3))))
    return o, d, t_end, ray


def test_air_cells_are_empty_space_and_their_optical_depth_is_the_interpolants():
    """Exact transmittance (sampler None: deterministic) per channel against the fine midpoint integral of the
    trilinear interpolant of each channel's grid, on rays inside and outside the box, nearly horizontal ones
    among them; and the DDA sees empty space (radii > 0) although no cell of the grid is 0."""
    sigma, cloud, air = cloud_in_air()
    scene = mi.load_dict(air_scene(sigma, ours_air(sigma, air)))
    integ = scene.integrator()
    integ._setup(scene, None)
    assert integ._tk.texel.air is not None and np.array(integ._tk.texel.empty).max() >= 2
    n = 1500
    o, d, t_end, ray = random_rays(5, n)
    got = np.array(exact_transmittance(integ._tk, ray, mi.Float(t_end.astype(np.float32)), mi.Bool(True)))
    grids = np.concatenate([sigma[..., :3], np.broadcast_to(air[:, None, None, 2], cloud.shape)[..., None]], -1)
    tau = optical_depth_numpy(grids, o, d, t_end)  # the three channels and the air's blue in one pass
    for c in range(3):
        np.testing.assert_allclose(got[c], np.exp(-tau[:, c]), rtol=2e-3, atol=1e-6)
    tau_air = tau[:, 3]
    assert (tau_air > 0.3).sum() > n // 10  # the air matters on many of these rays


def test_air_majorants_bound_every_cube():
    """``AirLevels``' cube majorant bounds the air's interpolant over every cube of texel cells (brute force)."""
    from weather_mi.kernel.plugins.air_levels import AirLevels
    air = air_profile(12)
    bound = np.array(AirLevels(air).bound)
    n = air.shape[0]
    for centre in range(-1, n):
        for k in range(0, 6):
            levels = np.clip(np.arange(centre - k, centre + k + 2), 0, n - 1)  # texel cells c - k .. c + k
            i = int(np.clip(centre - k + 1, 0, n))
            assert bound[i] >= air[levels].max() * (1 - 1e-7)


@pytest.mark.parametrize("transmittance", ["exact", "ratio"])
def test_a_cloud_in_the_air_agrees_with_volpath(transmittance):
    """Free flights (spectral tracking against the cloud's texel majorants and the air's cube majorants) and
    shadow rays (exact: Simpson + closed form; ratio tracking) against stock volpath, with a ground."""
    sigma, _, air = cloud_in_air()
    a = passes(mi.load_dict(air_scene(sigma, {"type": "volpath", "max_depth": 4}, ground=True)), 16, 16)
    b = passes(mi.load_dict(air_scene(sigma, ours_air(sigma, air, max_depth=4, transmittance=transmittance),
                                      ground=True)), 16, 16, seed0=1000)
    assert np.all(np.isfinite(b)) and b.min() >= 0
    assert_agree(a, b)


def test_air_levels_must_match_the_grid():
    sigma, _, air = cloud_in_air()
    scene = mi.load_dict(air_scene(sigma, ours_air(sigma, air[:-1])))
    with pytest.raises(RuntimeError, match="'air_extinction' has 15 levels, the sigma_t grid is"):
        scene.integrator()._setup(scene, None)
    with pytest.raises(Exception, match="air_extinction"):
        mi.load_dict(air_scene(sigma, ours_air(sigma, -air)))


def test_render_reference_puts_the_atmosphere_into_the_box():
    """A SceneSpec's ``atmosphere`` alone gives the image of a volume whose air was added by ``with_box_air``
    (the same seeds: identical), from the level densities ``optical_volume`` keeps of the model's ``rho_air``."""
    import weather_mi as wm
    from weather_mi.optics.air.inside import with_box_air
    hyd = wm.synthetic.cumulus()
    vol = wm.optical_volume(hyd)
    np.testing.assert_allclose(vol.air_density, hyd["rho_air"].mean(("y", "x")).values, rtol=1e-6)
    spec = wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=200, elevation=8, fov=45), width=16, height=12,
                        sun=wm.Sun(azimuth=240, elevation=10), atmosphere=wm.Atmosphere())
    alone = wm.render_reference(spec, vol, spp=2, progress=False)
    boxed = wm.render_reference(spec, with_box_air(vol, hyd, spec.atmosphere), spp=2, progress=False)
    assert np.array_equal(alone.radiance, boxed.radiance)



GREY_ALBEDO = np.array([0.95, 0.9, 0.8], np.float32)  # test_majorant_volpath.scene_dict's default


def grey_cloud_in_air(shape=(16, 32, 32)):
    """(The cloud (z, y, x), the air (z, 3) with its G channel in all three: a satellite's single band)."""
    return blobs(shape), np.repeat(air_profile(shape[0])[:, 1:2], 3, axis=1)


def ours_grey_air(cloud, air, **kw):
    """majorant_volpath with the air added per level to the cloud's grey grid (``air_albedo``: the cloud's albedo,
    ``air_scattering``: the air scattering with the same albedo, so the mixture's is the scene's constant)."""
    alb = np.broadcast_to(GREY_ALBEDO, cloud.shape + (3,)).copy()
    return {**ours_air(cloud, air, **kw), "air_albedo": mi.TensorXf(alb),
            "air_scattering": mi.TensorXf((air * GREY_ALBEDO[None, :]).astype(np.float32))}


def test_a_grey_air_is_tracked_grey_with_its_optical_depth_the_interpolants():
    """A grey air (three equal channels) added per level to a one-channel grid: the trackers stay grey (no
    spectral tracking), ``AirLevels`` holds one channel whose values are the three-channel one's to the bit, and
    the exact transmittance is the fine midpoint integral of the trilinear interpolant of cloud plus air (numpy)."""
    from weather_mi.kernel.plugins.air_levels import AirLevels
    cloud, air = grey_cloud_in_air()
    scene = mi.load_dict(scene_dict(cloud, ours_grey_air(cloud, air)))
    integ = scene.integrator()
    integ._setup(scene, None)
    tk = integ._tk
    # the grey grid's texels interpolated by the trackers, the air added to them per level
    assert not tk.ms.spectral and tk.ms.air.grey and tk.texel.air is tk.ms.air and tk.texel_data is not None
    n = 1200
    o, d, t_end, ray = random_rays(7, n)
    got = np.array(exact_transmittance(tk, ray, mi.Float(t_end.astype(np.float32)), mi.Bool(True)))
    tau = optical_depth_numpy(cloud + air[:, None, None, 0], o, d, t_end)
    assert (optical_depth_numpy(np.broadcast_to(air[:, None, None, 0], cloud.shape), o, d, t_end) > 0.1).sum() > n // 10
    for c in range(3):
        np.testing.assert_allclose(got[c], np.exp(-tau), rtol=2e-3, atol=1e-6)
    q = mi.Float(np.linspace(-2.0, 18.0, 301, dtype=np.float32))
    grey, rgb = AirLevels(air, grey=True), AirLevels(air)
    np.testing.assert_array_equal(np.array(grey.sigma_at(q, True)), np.array(rgb.sigma_at(q, True))[1])
    args = (mi.Float(0.3), mi.Float(0.7), mi.Float(0.0), mi.Float(np.linspace(0.0, 25.0, 301, dtype=np.float32)))
    np.testing.assert_array_equal(np.array(grey.tau(*args, True)), np.array(rgb.tau(*args, True))[1])
    with pytest.raises(RuntimeError, match="differs between channels"):
        AirLevels(air_profile(16), grey=True)


@pytest.mark.parametrize("transmittance", ["exact", "ratio"])
def test_a_cloud_in_a_grey_air_agrees_with_volpath(transmittance):
    """Free flights and shadow rays in a grey air added per level against stock volpath on the grid that holds
    cloud plus air (one channel), with a ground."""
    cloud, air = grey_cloud_in_air()
    total = (cloud + air[:, None, None, 0]).astype(np.float32)
    a = passes(mi.load_dict(scene_dict(total, {"type": "volpath", "max_depth": 4}, ground=True)), 16, 16)
    b = passes(mi.load_dict(scene_dict(cloud, ours_grey_air(cloud, air, max_depth=4, transmittance=transmittance),
                                       ground=True)), 16, 16, seed0=1000)
    assert np.all(np.isfinite(b)) and b.min() >= 0
    assert_agree(a, b)


@pytest.mark.parametrize("transmittance", ["exact", "ratio"])
def test_a_cloud_in_a_chromatic_air_per_level_agrees_with_volpath(transmittance):
    """A chromatic air added per level to the cloud's grey grid (render's and ``satellite --rgb``'s default kernel):
    free flights and ratio tracking follow the air's largest channel, grey, the channels weighted by the excess in
    closed form; exact transmittance takes the air's optical depth of a segment in closed form. Against stock volpath
    on the grid that holds cloud plus air (three channels, spectral extinction), with a ground. (The walk's own
    texels decide it: from c0780af to spectralair38c this test asserted the predicate on the tracker's texels
    while the walks, gated on grey media, did not take the split path.)"""
    from weather_mi.kernel.plugins import trackers
    sigma, cloud, air = cloud_in_air()
    a = passes(mi.load_dict(air_scene(sigma, {"type": "volpath", "max_depth": 4}, ground=True)), 16, 16)
    scene = mi.load_dict(scene_dict(cloud, ours_grey_air(cloud, air, max_depth=4, transmittance=transmittance),
                                    ground=True))
    integ = scene.integrator()
    integ._setup(scene, None)
    tk = integ._tk
    walk = trackers._tracking_walk(tk, mi.Ray3f(mi.Point3f(0.0, 0.0, 0.5), mi.Vector3f(0.0, 0.0, -1.0)), mi.Float(1.0),
                                   mi.Bool(True))
    assert tk.ms.spectral and walk.texels is not None and walk.excess is not None  # the split walk is taken
    b = passes(scene, 16, 16, seed0=1000)
    assert np.all(np.isfinite(b)) and b.min() >= 0
    assert_agree(a, b)
