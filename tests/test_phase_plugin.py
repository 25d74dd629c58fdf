"""The ``hydrometeor_mixture`` Mitsuba phase function (Eq. 8): values against closed forms, sampling
against its own pdf with Mitsuba's chi-square test, and rendering against Mitsuba's built-in ``hg``."""
import types

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import weather_mi as wm
from weather_mi.kernel.plugins import hydrometeor_mixture as hm


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


def physical_tables():
    """The per-species tables of the "physical" preset: forward peaks 0.02 deg wide (rain), halos."""
    return wm.phase.for_species(list(wm.species.preset("physical")), mode="per_species")


@pytest.mark.parametrize("weights", [(0.2, 0.2, 0.2, 0.2, 0.2), (0.05, 0.1, 0.7, 0.05, 0.1)])
def test_sampling_of_peaked_tables_matches_pdf(weights):
    """Mitsuba's chi-square test cannot integrate the physical tables' forward peaks on its grid (its
    pdf sum exceeds 1 already for the sampler of the previous release), so this one works in the
    scattering angle alone: 2M samples binned in log(Theta) from 1e-5 rad to pi (pooled to >= 20
    expected counts), against 2 pi * integral of eval_pdf over v = 1 - cos, which is exact on the
    union of the node set and the bin edges (the pdf is piecewise linear in v). Also: the pdf that
    ``sample`` returns is eval_pdf's at the drawn direction, and the azimuth is uniform."""
    from scipy import stats
    nodes, values = hm.prepare_tables(physical_tables())
    phase = mi.load_dict({"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]),
                          "values": mi.TensorXf(values), "weights": mi.TensorXf(constant_weights(weights)),
                          "to_world": hm.bbox_transform(((0, 0, 0), (1, 1, 1)))})
    n = 1 << 21
    rng = np.random.default_rng(5)
    ctx = mi.PhaseFunctionContext(None)
    wo, weight, pdf = phase.sample(ctx, make_mei(n), mi.Float(rng.random(n, np.float32)),
                                   mi.Point2f(*rng.random((2, n), np.float32)))
    wo = np.array(wo, np.float64)
    v = 0.5 * ((wo[0] ** 2 + wo[1] ** 2) + (wo[2] + 1.0) ** 2)  # |wo + wi|^2 / 2, wi = +z
    theta = 2 * np.arcsin(np.sqrt(np.clip(v / 2, 0, 1)))

    edges = np.r_[0.0, np.geomspace(1e-5, np.pi, 121)]
    edges_v = 1 - np.cos(edges)
    grid = np.unique(np.r_[nodes.astype(np.float64), edges_v])
    th = 2 * np.arcsin(np.sqrt(grid / 2))  # wo from the angle: 1 - v would round to 1 in float32
    wo_grid = mi.Vector3f(np.sin(th).astype(np.float32), np.zeros(th.size, np.float32), -np.cos(th).astype(np.float32))
    p_grid = np.array(phase.eval_pdf(mi.PhaseFunctionContext(None), make_mei(th.size), wo_grid)[1], np.float64)
    cum = np.r_[0.0, np.cumsum(2 * np.pi * 0.5 * (p_grid[1:] + p_grid[:-1]) * np.diff(grid))]
    expected = np.diff(np.interp(edges_v, grid, cum)) * n
    observed = np.histogram(theta, edges)[0].astype(float)
    assert abs(cum[-1] - 1) < 2e-3
    # pool neighbouring bins until each expects >= 20 samples
    obs_p, exp_p, o, e = [], [], 0.0, 0.0
    for ob, ex in zip(observed, expected):
        o, e = o + ob, e + ex
        if e >= 20:
            obs_p.append(o), exp_p.append(e)
            o, e = 0.0, 0.0
    obs_p[-1] += o
    exp_p[-1] += e
    exp_p = np.array(exp_p) * (np.sum(obs_p) / np.sum(exp_p))
    assert len(obs_p) > 60
    assert stats.chisquare(obs_p, exp_p).pvalue > 1e-3

    # the returned pdf is eval_pdf at the drawn direction (pdf and weight = value / pdf)
    pick = rng.choice(n, 2000, replace=False)
    wo_pick = mi.Vector3f(*wo[:, pick].astype(np.float32))
    value_e, pdf_e = phase.eval_pdf(ctx, make_mei(pick.size), wo_pick)
    np.testing.assert_allclose(np.array(pdf)[pick], np.array(pdf_e), rtol=2e-3)
    np.testing.assert_allclose(np.array(weight)[:, pick] * np.array(pdf)[pick], np.array(value_e), rtol=2e-3)
    phi = np.arctan2(wo[1], wo[0])[theta > 1e-3]
    assert stats.kstest(phi, stats.uniform(-np.pi, 2 * np.pi).cdf).pvalue > 1e-3


def test_sampling_within_a_segment_follows_the_linear_density():
    """Three nodes (v = 0, 1, 2) and a density rising steeply within each segment: the drawn v
    follow the exact piecewise-linear density in 40 bins (catches a sampler that places v uniformly
    inside its segment, which the fine-grid tests cannot see)."""
    from scipy import stats
    theta = np.array([0.0, np.pi / 2, np.pi])
    p = np.array([0.02, 1.0, 0.1])  # in v: rises 50x over [0, 1], falls 10x over [1, 2]
    table = types.SimpleNamespace(theta=theta, values=np.stack([p] * 3, axis=1))
    nodes, values = hm.prepare_tables([table])
    assert nodes.size == 3
    phase = mi.load_dict({"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]),
                          "values": mi.TensorXf(values), "weights": mi.TensorXf(constant_weights((1.0,))),
                          "to_world": hm.bbox_transform(((0, 0, 0), (1, 1, 1)))})
    n = 1 << 20
    rng = np.random.default_rng(9)
    wo = np.array(phase.sample(mi.PhaseFunctionContext(None), make_mei(n), mi.Float(rng.random(n, np.float32)),
                               mi.Point2f(*rng.random((2, n), np.float32)))[0], np.float64)
    v = 1.0 + wo[2]  # 1 - cos(Theta), wi = +z, forward is -z
    edges = np.linspace(0, 2, 41)
    dens = np.interp(edges, [0, 1, 2], p)  # exact: linear in v within each segment
    cum = np.r_[0.0, np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.diff(edges))]
    expected = np.diff(cum) / cum[-1] * n
    assert stats.chisquare(np.histogram(v, edges)[0], expected).pvalue > 1e-3


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


def test_the_mixture_weighs_the_interpolated_scattering_coefficients(tmp_path):
    """Eq. 8 of a medium whose species' coefficients are trilinear: species 0 (HG 0.85) scattering 3 /km in
    the west cell, species 1 (isotropic) 1 /km in the east cell; a quarter of the way from the west
    centre the coefficients are 2.25 and 0.25 /km, the weights 0.9 and 0.1 (normalised weights
    interpolated instead: 0.75 and 0.25); at the midpoint 0.75 and 0.25 (they: 0.5 and 0.5). A cell
    where nothing scatters adds nothing."""
    weights = np.zeros((1, 1, 3, 2), np.float32)
    weights[0, 0, 0] = (3e-3, 0.0)
    weights[0, 0, 1] = (0.0, 1e-3)
    nodes, values = hm.prepare_tables([hg_table(0.85), hg_table(0.0)])
    phase = mi.load_dict({"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]),
                          "values": mi.TensorXf(values), "weights": mi.TensorXf(weights),
                          "to_world": hm.bbox_transform(((0, 0, 0), (3000, 10, 10)))})
    a, b = hg(0.85, np.arccos(0.3)), 1 / (4 * np.pi)
    quarter = eval_at(phase, [0.3], p=(750.0, 5.0, 5.0))[1][0]
    mid = eval_at(phase, [0.3], p=(1000.0, 5.0, 5.0))[1][0]
    east = eval_at(phase, [0.3], p=(2000.0, 5.0, 5.0))[1][0]  # halfway to the empty cell: still species 1
    assert quarter == pytest.approx(0.9 * a + 0.1 * b, rel=2e-3)
    assert mid == pytest.approx(0.75 * a + 0.25 * b, rel=2e-3)
    assert east == pytest.approx(b, rel=2e-3)


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
    vol = wm.optical_volume(wm.from_arrays({"cloud": a, "ice": a}, 1.0, (100, 100, 100)),
                            phase_tables=[hg_table(g) for g in (0.85, 0.8, 0.86, 0.75, 0.9)])
    medium = mi.load_dict(wm.medium_dict(vol))
    assert "HydrometeorMixture" in str(medium.phase_function())


def test_bad_shapes_rejected():
    nodes, values = hm.prepare_tables([hg_table(0.85)])
    with pytest.raises(Exception, match="weights"):
        mi.load_dict({"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]),
                      "values": mi.TensorXf(values), "weights": mi.TensorXf(np.ones((2, 2, 2, 3), np.float32))})


def test_same_draws_in_scalar_and_llvm_variants_of_one_process(tmp_path):
    """The plugin class is made per variant: switching llvm -> scalar -> llvm in one process works, and
    all three give the same sampled direction, weight and pdf (in a subprocess: the variant is global)."""
    import subprocess
    import sys
    nodes, values = hm.prepare_tables(physical_tables())
    weights = np.random.default_rng(0).random((3, 4, 5, 5)).astype(np.float32)
    path = tmp_path / "mix.npz"
    hm.save_npz(path, nodes, values, weights, ((0, 0, 0), (1, 1, 1)))
    script = f"""
import numpy as np, drjit as dr, mitsuba as mi, weather_mi as wm
for variant in ("llvm_ad_rgb", "scalar_rgb", "llvm_ad_rgb"):
    wm.set_variant(variant)
    ph = mi.load_dict({{"type": "hydrometeor_mixture", "filename": {str(path)!r}}})
    mei = dr.zeros(mi.MediumInteraction3f)
    mei.p, mei.wi = mi.Point3f(0.3, 0.4, 0.5), mi.Vector3f(0, 0, 1)
    mei.sh_frame = mi.Frame3f(mei.wi)
    wo, weight, pdf = ph.sample(mi.PhaseFunctionContext(None), mei, 0.7, mi.Point2f(0.3, 0.6))
    value, pdf_e = ph.eval_pdf(mi.PhaseFunctionContext(None), mei, wo)
    print(*np.ravel(np.array(wo)), *np.ravel(np.array(weight)), *np.ravel(np.array(pdf)), *np.ravel(np.array(pdf_e)))
"""
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-3000:]
    rows = np.array([[float(x) for x in line.split()] for line in out.stdout.strip().splitlines()])
    assert rows.shape == (3, 8)
    np.testing.assert_allclose(rows[1], rows[0], rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(rows[2], rows[0], rtol=0, atol=0)
    assert rows[0, 6] == pytest.approx(rows[0, 7], rel=1e-5)  # sample's pdf is eval_pdf's


def test_packed_weights_hold_the_coefficients_in_packets_of_four():
    w = np.zeros((1, 1, 3, 3), np.float32)
    w[0, 0, 0] = (2.0, 1.0, 1.0)
    w[0, 0, 2] = (0.0, -1.0, 5.0)   # negative as 0
    packed = hm.pack_weights(w)
    assert packed.shape == (1, 1, 3, 1, 4)
    np.testing.assert_array_equal(packed[0, 0, :, 0], [[2, 1, 1, 0], [0, 0, 0, 0], [0, 0, 5, 0]])
    assert hm.pack_weights(np.ones((1, 1, 1, 5))).shape == (1, 1, 1, 2, 4)  # 5 coefficients: 2 packets


def test_guide_table_bounds_every_node_segment():
    """For versines all over [0, 2] (nodes, midpoints, bucket edges), the guide bucket's range holds
    the node segment that numpy's searchsorted finds, within guide_steps bisection steps."""
    nodes, _ = hm.prepare_tables(physical_tables())
    v = nodes.astype(np.float64)
    guide, steps = hm.guide_table(v)
    assert steps <= 3
    m = guide.shape[0]
    probe = np.unique(np.r_[v, 0.5 * (v[1:] + v[:-1]), np.nextafter(v[1:], 0)])
    seg = np.clip(np.searchsorted(v, probe, side="right") - 1, 0, v.size - 2)
    j = np.clip((hm.angle_warp(probe) * m).astype(int), 0, m - 1)
    assert np.all((guide[j, 0] <= seg) & (seg <= guide[j, 1]))
    assert np.max(guide[:, 1] - guide[:, 0]) + 1 <= 2 ** steps


def test_weights_update_through_traverse():
    """New weights through ``mi.traverse`` + ``update()`` are repacked: species 0 (HG 0.85) everywhere,
    then species 1 (isotropic) everywhere."""
    nodes, values = hm.prepare_tables([hg_table(0.85), hg_table(0.0)])
    phase = mi.load_dict({"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]),
                          "values": mi.TensorXf(values), "weights": mi.TensorXf(constant_weights((1.0, 0.0))),
                          "to_world": hm.bbox_transform(((0, 0, 0), (1, 1, 1)))})
    ct = [0.3]
    assert eval_at(phase, ct)[1][0] == pytest.approx(hg(0.85, np.arccos(0.3)), rel=2e-3)
    params = mi.traverse(phase)
    params["weights"] = mi.TensorXf(constant_weights((0.0, 1.0)))
    params.update()
    assert eval_at(phase, ct)[1][0] == pytest.approx(1 / (4 * np.pi), rel=2e-3)


def test_eval_matches_the_prepared_tables_everywhere():
    """eval_pdf (float32 guide-table lookup, bisection, interpolation) equals numpy's interpolation of
    the prepared tables at 20000 angles from 1e-6 rad to pi, at the nodes and between them."""
    nodes, values = hm.prepare_tables(physical_tables())
    s = 2  # rain: the narrowest forward peak
    phase = mi.load_dict({"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]),
                          "values": mi.TensorXf(values[s:s + 1]), "weights": mi.TensorXf(constant_weights((1.0,))),
                          "to_world": hm.bbox_transform(((0, 0, 0), (1, 1, 1)))})
    rng = np.random.default_rng(3)
    v_nodes = nodes.astype(np.float64)
    theta = np.sort(np.r_[np.geomspace(1e-6, np.pi, 10000), 2 * np.arcsin(np.sqrt(v_nodes[1:-1] / 2)),
                          rng.uniform(0, np.pi, 10000 - v_nodes.size + 2)])
    wo = np.stack([np.sin(theta), np.zeros_like(theta), -np.cos(theta)]).astype(np.float32)
    value = np.array(phase.eval_pdf(mi.PhaseFunctionContext(None), make_mei(theta.size), mi.Vector3f(*wo))[0])
    w = wo.astype(np.float64)
    v = 0.5 * (w[0] ** 2 + (w[2] + 1.0) ** 2)  # the versine of the float32 direction
    expected = np.interp(v, v_nodes, values[s, :, 1].astype(np.float64))
    np.testing.assert_allclose(value[1], expected, rtol=1e-4, atol=1e-7 * expected.max())


def test_packed_weights_are_held_in_place_and_traverse_unpacks_them():
    """Weights given packed (z x y x x x P x 4, ``medium.phase_arrays(packed=True)``) are the plugin's one copy,
    used in place (the same Dr.Jit array, no second host copy), and evaluate as the same coefficients given
    unpacked (species 0 HG 0.85 in the west cell, species 1 isotropic in the east: closed forms at the texel
    centres, their mean at the midpoint); ``mi.traverse`` gives them back unpacked, exactly."""
    weights = np.zeros((1, 1, 2, 2), np.float32)
    weights[0, 0, 0] = (1, 0)
    weights[0, 0, 1] = (0, 1)
    nodes, values = hm.prepare_tables([hg_table(0.85), hg_table(0.0)])
    packed = mi.TensorXf(hm.pack_weights(weights))
    assert tuple(packed.shape) == (1, 1, 2, 1, 4)
    a, b = hg(0.85, np.arccos(0.3)), 1 / (4 * np.pi)
    for given in (packed, mi.TensorXf(weights)):
        phase = mi.load_dict({"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]),
                              "values": mi.TensorXf(values), "weights": given,
                              "to_world": hm.bbox_transform(((0, 0, 0), (2000, 10, 10)))})
        west, east, mid = (eval_at(phase, [0.3], p=(x, 5.0, 5.0))[1][0] for x in (500.0, 1500.0, 1000.0))
        assert west == pytest.approx(a, rel=2e-3) and east == pytest.approx(b, rel=2e-3)
        assert mid == pytest.approx(0.5 * (a + b), rel=2e-3)
        np.testing.assert_array_equal(np.array(mi.traverse(phase)["weights"]).reshape(weights.shape), weights)
    with pytest.raises(RuntimeError, match="packed"):
        mi.load_dict({"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]), "values": mi.TensorXf(values),
                      "weights": mi.TensorXf(np.zeros((1, 1, 2, 2, 4), np.float32))})


def test_phase_arrays_pack_the_scattering_coefficients_in_aligned_memory():
    """``phase_arrays(packed=True)``: beta_sca,s = w_s beta mean(omega) (1/m, computed here from the volume)
    per species in packets of 4, zero-padded, in 64-byte aligned memory; the unpacked ones equal."""
    import weather_mi as wm
    from weather_mi.kernel.medium import phase_arrays
    vol = wm.optical_volume(wm.synthetic.cumulus(), phase_quality="test")
    _, _, plain = phase_arrays(vol)
    _, _, packed = phase_arrays(vol, packed=True)
    assert packed.shape == vol.shape + (2, 4) and packed.ctypes.data % 64 == 0
    expect = np.moveaxis(vol.weights, 0, -1) * (vol.albedo.mean(axis=-1) * vol.beta_total)[..., None]
    np.testing.assert_allclose(plain, expect, rtol=1e-6, atol=0)
    flat = packed.reshape(vol.shape + (8,))
    np.testing.assert_array_equal(flat[..., :5], plain)
    assert not flat[..., 5:].any() and (flat[..., :5] > 0).any()


def test_a_grey_albedo_grid_is_handed_as_one_channel_and_renders_the_same():
    """``medium.grey_or_rgb``: a band's albedo (three equal channels) becomes one (z, y, x, 1) channel, which the
    gridvolume holds as given; an albedo whose channels differ anywhere stays RGB. The medium's albedo
    evaluated at points inside the grid is the same either way (trilinear, per channel)."""
    from weather_mi.kernel.medium import grey_or_rgb
    rng = np.random.default_rng(3)
    grey = np.repeat(rng.uniform(0.5, 1.0, (3, 4, 5, 1)).astype(np.float32), 3, axis=-1)
    one = grey_or_rgb(grey)
    assert one.shape == (3, 4, 5, 1) and one.flags.c_contiguous
    np.testing.assert_array_equal(one[..., 0], grey[..., 0])
    rgb = grey.copy()
    rgb[2, 3, 4, 2] += 1e-3  # one channel of one voxel differs: RGB kept
    assert grey_or_rgb(rgb).shape == (3, 4, 5, 3)
    p = mi.Point3f(*[mi.Float(rng.uniform(0.05, 0.95, 64).astype(np.float32)) for _ in range(3)])
    it = dr.zeros(mi.Interaction3f)
    it.p = p
    vals = [np.array(mi.load_dict({"type": "gridvolume", "data": mi.TensorXf(a), "filter_type": "trilinear",
                                   "accel": False}).eval(it)) for a in (grey, one)]
    np.testing.assert_array_equal(vals[0], vals[1])
    assert vals[0].min() >= 0.5
