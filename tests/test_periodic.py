"""Periodic horizontal boundaries (issue 39 part 4): the path tracer and the slicer against a render of 3 x 3
copies of the field tiled with numpy (periodic off), and checks that fail if the boundaries were ignored."""
from __future__ import annotations

import dataclasses
import types

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.display.metrics import agreement_in_noise
from weather_mi.errors import WeatherDataError
from weather_mi.kernel.plugins.majorants import empty_space_radius, texel_majorant_grid
from weather_mi.optics.periodic import check_periodic, pad_levels, padded_bbox

L, H = 1000.0, 600.0  # the tile's width and depth, its height (m)


def _field():
    """(z, y, x) extinction (1/m): a dense cloud against the east wall, a thin one across the north-east
    corner (both continue across the walls in the tiling)."""
    beta = np.zeros((6, 8, 8), np.float32)
    beta[1:4, 2:6, 6:8] = 0.02
    beta[2:5, 6:8, 7:8] = 0.01
    beta[2:5, 0:1, 0:2] = 0.01
    return beta


def _volumes(periodic=True):
    beta, ph = _field(), wm.phase.henyey_greenstein(0.7)
    vol = wm.OpticalVolume.from_arrays(beta, 0.95, ph, ((0, 0, 0), (L, L, H)))
    tiled = wm.OpticalVolume.from_arrays(np.tile(beta, (1, 3, 3)), 0.95, ph, ((-L, -L, 0), (2 * L, 2 * L, H)))
    return vol, dataclasses.replace(vol, periodic=periodic), tiled


def _spec(seed=0, width=L, pixels=16, elevation=40.0, ground=0.3):
    """Looking straight down at the tile (or a wider square about its centre); the sun low in the west: the
    shadow of the cloud at the east wall falls across the wall onto the west part of the tile."""
    cam = wm.Camera.orthographic(center=(L / 2, L / 2, 3000.0), direction=(0, 0, -1), width=width, height=width)
    return wm.SceneSpec(camera=cam, sun=wm.Sun(azimuth=270.0, elevation=elevation), sky=None,
                        ground=wm.Ground(albedo=ground), width=pixels, height=pixels, seed=seed)


def _block_chi2(a, b, region=np.s_[:, :]):
    return agreement_in_noise(a, b, region)["block_chi2"]


def _tile_mean_z(a, b):
    return agreement_in_noise(a, b)["mean_z"]


@pytest.fixture(scope="module")
def renders():
    vol, per, tiled = _volumes()
    opts = dict(spp=64, passes=4, progress=False)
    return {"plain": wm.render_reference(_spec(1), vol, **opts),
            "periodic": wm.render_reference(_spec(1), per, **opts),
            "tiled": wm.render_reference(_spec(2), tiled, **opts)}


def test_path_tracer_periodic_equals_tiled_centre(renders):
    """The periodic render of the tile agrees with the centre tile of the 3 x 3 tiling within noise
    (independent seeds): the mean within 3 combined standard errors, the pixels chi-square like."""
    chi2 = _block_chi2(renders["periodic"], renders["tiled"])
    assert chi2 < 2.0, chi2
    assert abs(_tile_mean_z(renders["periodic"], renders["tiled"])) < 3.0


def test_path_tracer_ignoring_periodic_fails(renders):
    """Without periodic boundaries the west of the tile is sunlit; the tiling (and the periodic render)
    put the east cloud's shadow there: the check above would fail for a render that ignored them."""
    west = np.s_[:, :5]  # image columns 0-4: the west ~300 m of the tile, under clear sky
    shade = renders["periodic"].radiance[west].mean() / renders["plain"].radiance[west].mean()
    tiled = renders["tiled"].radiance[west].mean() / renders["plain"].radiance[west].mean()
    assert shade < 0.8 and tiled < 0.8, (shade, tiled)
    chi2 = _block_chi2(renders["plain"], renders["tiled"])
    assert chi2 > 10.0, chi2


def test_path_tracer_view_and_transport_beyond_the_tile():
    """Looking at 3 x 3 tiles: periodic=True sees the copies (the tiled render's centre and its
    neighbours, where light from beyond the 3 x 3 matters little), "transport" sees the centre tile
    alone (clouds outside it are not seen, their shadows are) and the same centre tile."""
    vol, per, tiled = _volumes()
    opts = dict(spp=32, passes=4, progress=False)
    spec = _spec(3, width=3 * L, pixels=24, ground=0.05)  # a dark ground: the clouds stand out
    view = wm.render_reference(spec, per, **opts)
    ref = wm.render_reference(dataclasses.replace(spec, seed=4), tiled, **opts)
    transport = wm.render_reference(dataclasses.replace(spec, seed=5), dataclasses.replace(vol, periodic="transport"),
                                    **opts)
    centre = np.s_[8:16, 8:16]
    # the centre and part of each neighbour; not the west neighbour's west half, which the 3 x 3 tiling leaves
    # sunlit (its shade falls from a fourth tile, which the periodic view has)
    inner = np.s_[4:20, 6:20]
    chi2 = _block_chi2(view, ref, inner)
    assert chi2 < 2.0, chi2
    chi2 = _block_chi2(transport, view, centre)
    assert chi2 < 2.0, chi2
    # the east cloud seen from above: its west copy as bright as the centre's in view; in transport only the
    # ground there (dark, under the copy's shadow)
    def copy_over_centre(img):
        r = img.radiance[10:14].mean(axis=2)
        return r[:, 6:8].mean() / r[:, 14:16].mean()

    assert 0.6 < copy_over_centre(view) < 1.6, copy_over_centre(view)
    assert copy_over_centre(transport) < 0.5, copy_over_centre(transport)


def test_texel_majorants_periodic_brute_force():
    """Each periodic texel cell's majorant is the maximum of its 8 texels with x and y indices modulo the
    grid (z clamped), computed here one cell at a time."""
    rng = np.random.default_rng(0)
    a = rng.random((3, 4, 5)).astype(np.float32) * (rng.random((3, 4, 5)) > 0.5)
    m = texel_majorant_grid(a, safety=1.0, periodic=True)
    nz, ny, nx = a.shape
    assert m.shape == (nz + 1, ny, nx)
    for k in range(-1, nz):
        for j in range(ny):
            for i in range(nx):
                ks = [min(max(k, 0), nz - 1), min(max(k + 1, 0), nz - 1)]
                want = max(a[kk, jj % ny, ii % nx] for kk in ks for jj in (j, j + 1) for ii in (i, i + 1))
                assert m[k + 1, j, i] == want


def test_empty_space_radius_periodic_brute_force():
    """A radius never reaches an occupied cell across the wrap: the cube of side 2k + 1 about each cell
    (x and y modulo the grid, z beyond the grid empty) holds no occupied cell."""
    occ = np.zeros((5, 12, 12), np.float32)
    occ[2, 1, 11] = 1.0
    r = empty_space_radius(occ, periodic=True)
    plain = empty_space_radius(occ)
    for (k, j, i), rad in np.ndenumerate(r):
        for kk in range(max(k - rad, 0), min(k + rad, 4) + 1):
            for jj in range(j - rad, j + rad + 1):
                for ii in range(i - rad, i + rad + 1):
                    assert occ[kk, jj % 12, ii % 12] == 0.0 or rad == 0
    assert r[2, 1, 0] == 0 and plain[2, 1, 0] == 10   # next to the occupied cell across the wrap; far without it
    assert r.max() > 0


def test_padding_and_options():
    a = np.arange(24, dtype=np.float32).reshape(2, 3, 4)
    p = pad_levels(a)
    assert p.shape == (4, 3, 4) and np.array_equal(p[0], a[0]) and np.array_equal(p[-1], a[-1])
    assert padded_bbox(((0, 0, 100), (1, 1, 300)), 2) == ((0.0, 0.0, 0.0), (1.0, 1.0, 400.0))
    assert check_periodic(None) is False and check_periodic("view") is True
    with pytest.raises(WeatherDataError, match="periodic"):
        check_periodic("xy-ish")
    vol, per, _ = _volumes()
    with pytest.raises(WeatherDataError, match="periodic"):
        dataclasses.replace(vol, periodic="sideways")
    from weather_mi.io.terrain import Terrain
    from weather_mi.kernel.scene_dict import scene_dict
    from weather_mi.slicing import SliceRenderer
    flat = np.zeros((4, 4))
    hilly = dataclasses.replace(per, terrain=Terrain(np.linspace(0, L, 4), np.linspace(0, L, 4), flat, flat + 1,
                                                     flat + 0.2, "test"))
    for render in (lambda: scene_dict(_spec(), hilly, {"type": "majorant_volpath"}), lambda: SliceRenderer(hilly)):
        with pytest.raises(WeatherDataError, match="terrain"):  # a terrain is not periodic
            render()
    from weather_mi.kernel.scene_dict import integrator_dict
    for kind, legacy in (("volpath", False), ("majorant", True)):  # stock volpath cannot wrap; legacy tracks coarse
        with pytest.raises(ValueError, match="periodic"):
            integrator_dict(per, kind, -1, legacy=legacy)


def test_les_inputs_are_periodic_by_default(tmp_path):
    """The LES reader marks its domains doubly periodic; ``optical_volume`` follows ("transport": periodic
    light, the domain's own tile seen) unless told otherwise; other inputs stay isolated boxes."""
    from weather_mi.io.les import open_les
    path = tmp_path / "tiny.txt"
    path.write_text("# tiny\n3 2 4\n0.1 0.2 1.0 1.1 1.2 1.3\n0 0 0 0.5 10.0\n2 1 3 1.5 12.0\n")
    hyd = open_les(path)
    assert wm.optical_volume(hyd, phase_quality="test").periodic == "transport"
    assert wm.optical_volume(hyd, phase_quality="test", periodic=True).periodic is True
    assert wm.optical_volume(hyd, phase_quality="test", periodic=False).periodic is False
    assert wm.optical_volume(hyd, phase_quality="test", periodic="transport").periodic == "transport"
    assert wm.optical_volume(wm.synthetic.cumulus(), phase_quality="test").periodic is False


# ---------------------------------------------------------------- the slicer

def _slicer_frames(specs_and_volumes):
    from weather_mi.slicing import SliceRenderer
    return [SliceRenderer(v, slices=96).frame(spec).radiance for spec, v in specs_and_volumes]


def test_slicer_periodic_equals_tiled_centre():
    """The slicer's periodic frame of the tile is its frame of the 3 x 3 tiling's centre (the same slices:
    to float rounding); ignoring the boundaries leaves the west of the tile sunlit."""
    vol, per, tiled = _volumes()
    spec = _spec(pixels=24)
    plain, periodic, ref = _slicer_frames([(spec, vol), (spec, per), (spec, tiled)])
    assert np.abs(periodic - ref).mean() < 1e-2 * ref.mean()
    assert np.abs(plain - ref).mean() > 0.3 * ref.mean()
    west = np.s_[:, :7]
    assert periodic[west].mean() < 0.8 * plain[west].mean()


def test_slicer_view_and_transport():
    """Over 3 x 3 tiles the view sees the copies as the tiled frame does (but for the west neighbour's west
    half, shaded from a fourth tile); "transport" sees the centre tile as the view does and no copies."""
    vol, per, tiled = _volumes()
    spec = _spec(width=3 * L, pixels=24, ground=0.05)
    view, transport, ref = _slicer_frames([(spec, per), (spec, dataclasses.replace(vol, periodic="transport")),
                                           (spec, tiled)])
    inner = np.s_[:, 6:]
    assert np.abs(view[inner] - ref[inner]).mean() < 1e-2 * ref[inner].mean()
    centre = np.s_[8:16, 8:16]
    assert np.abs(transport[centre] - view[centre]).max() < 1e-5 * view.max()
    west_copy = np.s_[10:14, 7]  # the west neighbour's east cloud from above: its shaded ground in transport
    assert view[west_copy].mean() > 2.0 * transport[west_copy].mean()


def test_agreement_in_noise_on_known_noise():
    """Two images of one radiance with independent Gaussian noise of known standard error: |mean z| within 3 and
    the block chi-square ~1; a shift of 5 standard errors of the mean is caught."""
    rng = np.random.default_rng(7)
    se = np.full((32, 32, 3), 0.01)

    def img(shift=0.0):
        r = 0.5 + shift + se[..., :1] * rng.standard_normal((32, 32, 1))
        return types.SimpleNamespace(radiance=np.repeat(r, 3, axis=2), stderr=se)

    a = agreement_in_noise(img(), img())
    assert abs(a["mean_z"]) < 3 and 0.6 < a["block_chi2"] < 1.5, a
    shift = 5 * np.sqrt(2) * 0.01 / 32  # 5 standard errors of the difference of the means
    assert agreement_in_noise(img(shift), img())["mean_z"] > 3


def test_command_line_periodic_flags():
    from weather_mi.cli.commands import build_parser
    from weather_mi.cli.periodic_option import periodic_value
    parser = build_parser()
    expect = {(): None, ("--periodic",): True, ("--periodic", "view"): True, ("--periodic", "transport"): "transport",
              ("--no-periodic",): False}
    for command in ("render", "view", "satellite"):
        for flags, value in expect.items():
            output = ["-o", "x.nc"] if command == "satellite" else []
            args = parser.parse_args([command, "--demo", "cumulus", *flags, *output])
            got = periodic_value(args)
            assert got == value and type(got) is type(value), (command, flags, got)


def test_checkpoint_key_includes_periodic():
    """A checkpoint of an isolated render is not resumed as a periodic one (and the isolated key is the old one)."""
    from weather_mi.reference.checkpoints import fingerprint
    vol, per, _ = _volumes()
    keys = {fingerprint(_spec(), v, [1]) for v in (vol, per, dataclasses.replace(vol, periodic="transport"))}
    assert len(keys) == 3



def test_mixture_weights_wrap_like_the_tiling():
    """The Eq. 8 phase plugin of a periodic medium (two species, weights varying across the walls) gives at
    any point, in the domain or periods away, the value the clamped plugin of the 3 x 3 numpy tiling gives at
    the same point of its centre tile."""
    import drjit as dr
    import mitsuba as mi
    from weather_mi.kernel.plugins import hydrometeor_mixture as hm
    from weather_mi.kernel.variant import ensure_registered
    ensure_registered()
    rng = np.random.default_rng(2)
    weights = rng.random((3, 4, 5, 2)).astype(np.float32)
    nodes, values = hm.prepare_tables([wm.phase.isotropic(), wm.phase.henyey_greenstein(0.8)])

    def plugin(w, bbox, periodic):
        d = {"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]), "values": mi.TensorXf(values),
             "weights": mi.TensorXf(w), "to_world": hm.bbox_transform(bbox)}
        return mi.load_dict({**d, "periodic": True} if periodic else d)

    box = ((0.0, 0.0, 0.0), (5.0, 4.0, 3.0))
    per = plugin(weights, box, True)
    tiled = plugin(np.tile(weights, (1, 3, 3, 1)), ((-5.0, -4.0, 0.0), (10.0, 8.0, 3.0)), False)
    n = 4096
    p = rng.random((3, n)) * np.array([[5.0], [4.0], [3.0]])
    p[:2, : n // 2] = rng.random((2, n // 2)) * np.array([[0.4], [0.4]])  # half of them within 0.4 of a wall
    p[:2, : n // 4] = np.array([[5.0], [4.0]]) - p[:2, : n // 4]
    shift = rng.integers(-3, 4, (2, n)) * np.array([[5.0], [4.0]])

    def value(phase, pts):
        mei = dr.zeros(mi.MediumInteraction3f, n)
        mei.p = mi.Point3f(*(pts.astype(np.float32)))
        mei.wi = mi.Vector3f(0, 0, 1)
        mei.sh_frame = mi.Frame3f(mei.wi)
        ct = np.full(n, 0.9, np.float32)  # 26 deg from forward: the two species' values differ 1:6
        wo = mi.Vector3f(np.sqrt(1 - ct ** 2), np.zeros_like(ct), -ct)
        return np.array(phase.eval_pdf(mi.PhaseFunctionContext(None), mei, wo)[0])

    want = value(tiled, p)
    got = value(per, p + np.r_[shift, np.zeros((1, n))])
    np.testing.assert_allclose(got, want, rtol=2e-4)
    clamped = value(plugin(weights, box, False), p)
    assert np.abs(clamped - want).max() > 0.05 * np.abs(want).max()  # the walls matter: wrapping is tested
