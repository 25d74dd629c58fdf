"""The ``hydrometeor_mixture`` Mitsuba phase function (Eq. 8): values against closed forms, sampling
against its own pdf with Mitsuba's chi-square test, and rendering against Mitsuba's built-in ``hg``."""
import types

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import weather_mi as wm
from weather_mi.plugins import hydrometeor_mixture as hm


def hg(g, theta):
    """Henyey-Greenstein phase function (1/sr), closed form."""
    mu = np.cos(theta)
    return (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * mu) ** 1.5)


THETA = np.unique(np.r_[0.0, np.geomspace(1e-4, 0.2, 300), np.linspace(0.2, np.pi, 1200)])
GS = (0.85, 0.0, -0.4, 0.6)


def hg_table(g, tint=(1.0, 1.0, 1.0)):
    return types.SimpleNamespace(theta=THETA, values=np.stack([hg(g, THETA) * 1.0] * 3, axis=1))


def plugin_npz(tmp_path, weights, tables=None):
    tables = tables or [hg_table(g) for g in GS[: weights.shape[-1]]]
    nodes, values = hm.prepare_tables(tables)
    path = tmp_path / "mix.npz"
    hm.save_npz(path, nodes, values, weights.astype(np.float32), ((0, 0, 0), (1, 1, 1)))
    return path


def constant_weights(w):
    return np.broadcast_to(np.asarray(w, np.float32), (2, 2, 2, len(w))).copy()


def test_prepared_tables_normalised_and_match_closed_form():
    v, values = hm.prepare_tables([hg_table(0.85)])
    integral = 2 * np.pi * np.sum(0.5 * (values[0, 1:, 1] + values[0, :-1, 1]) * np.diff(v))
    assert integral == pytest.approx(1.0, abs=1e-5)
    np.testing.assert_allclose(values[0, ::50, 0], hg(0.85, np.arccos(1 - v[::50].astype(float))), rtol=5e-3)


def test_narrow_forward_peak_keeps_its_mean_cosine():
    """A peak 0.02 deg wide (a raindrop's diffraction) survives the float32 node set: the mean
    cosine of the prepared table equals the closed-form HG value."""
    g = 0.99995  # HG with a forward lobe of ~0.01 deg
    theta = np.unique(np.r_[0.0, np.geomspace(1e-7, 1e-2, 400), np.linspace(1e-2, np.pi, 800)])
    table = types.SimpleNamespace(theta=theta, values=np.stack([hg(g, theta)] * 3, axis=1))
    v, values = hm.prepare_tables([table])
    v = v.astype(float)
    p = values[0, :, 1].astype(float)
    mean_cos = 2 * np.pi * np.sum(0.5 * ((1 - v[1:]) * p[1:] + (1 - v[:-1]) * p[:-1]) * np.diff(v))
    assert mean_cos == pytest.approx(g, abs=2e-4)


@pytest.mark.parametrize("weights", [(1.0,), (0.5, 0.3, 0.2), (0.1, 0.0, 0.0, 0.9), (0.25, 0.25, 0.25, 0.25)])
def test_chi2_sampling_matches_pdf(tmp_path, monkeypatch, weights):
    from mitsuba.chi2 import ChiSquareTest, PhaseFunctionAdapter, SphericalDomain
    monkeypatch.chdir(tmp_path)  # the test writes chi2_data.py on failure
    path = plugin_npz(tmp_path, constant_weights(weights))
    wi = np.array([0.2, 0.3, 0.9])
    wi = [float(v) for v in wi / np.linalg.norm(wi)]
    sample, pdf = PhaseFunctionAdapter(hm.PLUGIN_NAME, f'<string name="filename" value="{path}"/>', wi=wi)
    chi2 = ChiSquareTest(domain=SphericalDomain(), sample_func=sample, pdf_func=pdf, sample_dim=3,
                         res=201, ires=32, sample_count=2_000_000)
    assert chi2.run(), chi2.messages


def make_mei(n, p=(0.5, 0.5, 0.5)):
    mei = dr.zeros(mi.MediumInteraction3f, n)
    mei.p = mi.Point3f(*p)
    mei.wi = mi.Vector3f(0, 0, 1)
    mei.sh_frame = mi.Frame3f(mei.wi)
    return mei


def eval_at(phase, cos_theta, p=(0.5, 0.5, 0.5)):
    ct = np.asarray(cos_theta, np.float32)
    wo = mi.Vector3f(np.sqrt(1 - ct ** 2), np.zeros_like(ct), -ct)
    value, pdf = phase.eval_pdf(mi.PhaseFunctionContext(None), make_mei(ct.size, p), wo)
    return np.array(value), np.array(pdf)


def test_eq8_mixture_value_against_closed_form(tmp_path):
    w = (0.5, 0.3, 0.2)
    phase = mi.load_dict({"type": "hydrometeor_mixture", "filename": str(plugin_npz(tmp_path, constant_weights(w)))})
    ct = np.array([0.99, 0.5, 0.0, -0.7])
    value, pdf = eval_at(phase, ct)
    expected = sum(wi * hg(g, np.arccos(ct)) for wi, g in zip(w, GS))
    np.testing.assert_allclose(value[1], expected, rtol=2e-3)
    np.testing.assert_allclose(pdf, expected, rtol=2e-3)


def test_weights_vary_in_space_trilinearly(tmp_path):
    # species 0 (HG 0.85) in the west half, species 1 (isotropic) in the east half, on a 1 x 1 x 2 grid
    weights = np.zeros((1, 1, 2, 2), np.float32)
    weights[0, 0, 0] = (1, 0)
    weights[0, 0, 1] = (0, 1)
    nodes, values = hm.prepare_tables([hg_table(0.85), hg_table(0.0)])
    phase = mi.load_dict({"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]),
                          "values": mi.TensorXf(values), "weights": mi.TensorXf(weights),
                          "to_world": hm.bbox_transform(((0, 0, 0), (2000, 10, 10)))})
    ct = [0.3]
    west = eval_at(phase, ct, p=(500.0, 5.0, 5.0))[1]   # texel centre of the west cell
    east = eval_at(phase, ct, p=(1500.0, 5.0, 5.0))[1]
    mid = eval_at(phase, ct, p=(1000.0, 5.0, 5.0))[1]
    a, b = hg(0.85, np.arccos(0.3)), 1 / (4 * np.pi)
    assert west[0] == pytest.approx(a, rel=2e-3) and east[0] == pytest.approx(b, rel=2e-3)
    assert mid[0] == pytest.approx(0.5 * (a + b), rel=2e-3)


def slab_scene(phase):
    """A cube of medium lit from above, seen from the side: exercises multiple scattering."""
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": 64},
        "sensor": {"type": "perspective", "fov": 30, "film": {"type": "hdrfilm", "width": 16, "height": 16,
                                                               "rfilter": {"type": "box"}},
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, -6, 1], target=[0, 0, 0], up=[0, 0, 1])},
        "sun": {"type": "directional", "direction": [0.3, 0.2, -1.0], "irradiance": 1.0},
        "cube": {"type": "cube", "bsdf": {"type": "null"},
                 "interior": {"type": "homogeneous", "sigma_t": 2.0, "albedo": 0.95, "phase": phase}},
    })


def test_renders_like_builtin_hg_within_noise(tmp_path):
    path = plugin_npz(tmp_path, constant_weights((1.0,)), [hg_table(0.7)])
    ours = slab_scene({"type": "hydrometeor_mixture", "filename": str(path)})
    ref = slab_scene({"type": "hg", "g": 0.7})
    imgs = {}
    for name, scene in (("ours", ours), ("ref", ref)):
        passes = np.stack([np.array(mi.render(scene, spp=64, seed=s)) for s in range(8)])
        imgs[name] = (passes.mean(0), passes.std(0, ddof=1) / np.sqrt(len(passes)))
    diff = imgs["ours"][0] - imgs["ref"][0]
    sigma = np.sqrt(imgs["ours"][1] ** 2 + imgs["ref"][1] ** 2) + 1e-6
    assert np.mean(imgs["ref"][0]) > 0.01
    assert abs(diff.mean()) < 3 * np.sqrt((sigma ** 2).mean() / diff.size)
    assert np.mean(np.abs(diff / sigma) < 4) > 0.99


def test_two_species_render_like_their_mixture_table_within_noise(tmp_path):
    """Two co-located species with constant weights (w, 1 - w) render like one species whose table is
    the mixture w p1 + (1 - w) p2 (computed in numpy). p1 differs per channel (HG g = 0.85 / 0.6 / 0.3
    in R / G / B), p2 is back-scattering (HG g = -0.3). Sanity check: swapped weights differ clearly."""
    w = 0.7
    p1 = np.stack([hg(g, THETA) for g in (0.85, 0.6, 0.3)], axis=1)
    p2 = np.stack([hg(-0.3, THETA)] * 3, axis=1)
    tables = [types.SimpleNamespace(theta=THETA, values=p1), types.SimpleNamespace(theta=THETA, values=p2)]
    mix = [types.SimpleNamespace(theta=THETA, values=w * p1 + (1 - w) * p2)]

    def render(tables, weights, seed0):
        folder = tmp_path / f"s{seed0}"
        folder.mkdir()
        path = plugin_npz(folder, constant_weights(weights), tables)
        scene = slab_scene({"type": "hydrometeor_mixture", "filename": str(path)})
        passes = np.stack([np.array(mi.render(scene, spp=64, seed=seed0 + s)) for s in range(8)])
        return passes.mean(0), passes.std(0, ddof=1) / np.sqrt(len(passes))

    def z_scores(a, b):
        """(z of the image-mean difference, per-pixel z) between two independent renders."""
        diff = a[0] - b[0]
        sigma = np.sqrt(a[1] ** 2 + b[1] ** 2) + 1e-6
        return diff.mean() / np.sqrt((sigma ** 2).mean() / diff.size), diff / sigma

    # independent seeds per render, so the per-image standard errors describe the difference
    two = render(tables, (w, 1 - w), 0)
    one = render(mix, (1.0,), 100)
    swapped = render(tables, (1 - w, w), 200)
    assert np.mean(two[0]) > 0.01
    z_mean, z_pixel = z_scores(two, one)
    assert abs(z_mean) < 3, z_mean
    assert np.mean(np.abs(z_pixel) < 4) > 0.99
    z_swapped, _ = z_scores(two, swapped)
    assert abs(z_swapped) > 8, z_swapped  # the comparison has the power to see wrong weights


def test_medium_dict_from_optical_volume():
    a = np.zeros((3, 4, 5))
    a[1, 2, 3] = 1e-3
    vol = wm.optical_volume(wm.from_arrays({"cloud": a, "ice": a}, 1.0, (100, 100, 100)))
    vol.phase_tables = [hg_table(g) for g in (0.85, 0.8, 0.86, 0.75, 0.9)]
    medium = mi.load_dict(wm.medium_dict(vol))
    assert "HydrometeorMixture" in str(medium.phase_function())


def test_bad_shapes_rejected():
    nodes, values = hm.prepare_tables([hg_table(0.85)])
    with pytest.raises(Exception, match="weights"):
        mi.load_dict({"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]),
                      "values": mi.TensorXf(values), "weights": mi.TensorXf(np.ones((2, 2, 2, 3), np.float32))})
