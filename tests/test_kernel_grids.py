"""One copy of each grid the path tracer holds (issue 39, part 1): the delta-scaled weights packed as they are
computed, a grey band albedo held as one channel, the five species' coefficients as a packet and a tail, the
volume's grids released as the kernel's are built, the coarse majorants a slab at a time. Every change is a memory change only: the references here are the whole-grid
float32 expressions the code used before (written out in the test), compared bit for bit, and the rendered image
with and without the savings.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.optics import forward_peak
from weather_mi.optics.forward_peak import ScaledWeights, delta_scaled, grey_albedo, is_grey, peak_tables


def whole_grid_delta(vol, cone_deg=3.0):
    """(beta_ext', beta_total', albedo', weights') by the whole-grid expressions (forward_peak before the chunks)."""
    f, _ = peak_tables(vol.phase_tables, cone_deg)
    f32 = f.astype(np.float32)[:, None, None, None]
    w = np.asarray(vol.weights)
    F = np.tensordot(f.astype(np.float32), w, axes=1)
    omega_mean = np.asarray(vol.albedo).mean(axis=-1)
    scattering = omega_mean * vol.beta_total
    beta_ext = np.multiply(f32, w)
    np.multiply(beta_ext, scattering[None], out=beta_ext)
    np.maximum(np.subtract(vol.beta_ext, beta_ext, out=beta_ext), 0, out=beta_ext)
    beta_total = np.multiply(F, scattering)
    np.maximum(np.subtract(vol.beta_total, beta_total, out=beta_total), 0, out=beta_total)
    with np.errstate(invalid="ignore", divide="ignore"):
        albedo = np.asarray(vol.albedo) * ((1 - F) / (1 - omega_mean * F))[..., None]
        np.copyto(albedo, vol.albedo, where=~(vol.beta_total > 0)[..., None])
        np.clip(albedo, 0, 1, out=albedo)
        weights = np.multiply(w, 1 - f32)
        total = weights.sum(axis=0)
        np.divide(weights, total, out=weights)
        np.copyto(weights, np.float32(0), where=~(total > 0))
    return beta_ext, beta_total, albedo, weights


@pytest.fixture(scope="module")
def storm():
    return wm.optical_volume(wm.synthetic.cumulus(), "physical", phase_quality="test")


@pytest.fixture
def small_chunks(monkeypatch):
    monkeypatch.setattr(forward_peak, "CHUNK", 997)  # chunks that end mid-row, a short last one


def test_delta_scaling_by_chunks_equals_the_whole_grid_expressions(storm, small_chunks):
    be, bt, alb, w = whole_grid_delta(storm)
    assert np.any(bt != storm.beta_total) and np.any(w != storm.weights)  # the scaling changes each grid
    full = delta_scaled(storm, 3.0)
    for name, ref in (("beta_ext", be), ("beta_total", bt), ("albedo", alb), ("weights", w)):
        assert np.array_equal(np.asarray(getattr(full, name)), ref), name
    lean = delta_scaled(storm, 3.0, species_extinction=False, deferred_weights=True)
    assert isinstance(lean.weights, ScaledWeights) and lean.weights.shape == w.shape
    assert np.array_equal(np.asarray(lean.weights), w)
    assert np.array_equal(lean.weights[2], w[2])
    assert np.array_equal(lean.albedo, alb) and np.array_equal(lean.beta_total, bt)


def test_a_grey_albedo_stays_one_channel_with_the_values_of_three(storm, small_chunks):
    channel = np.ascontiguousarray(storm.albedo[..., 1])
    grey = wm.OpticalVolume(storm.species, storm.beta_ext, storm.beta_total, grey_albedo(channel), storm.weights,
                            storm.bbox, storm.species_set, phase_tables=storm.phase_tables)
    three = wm.OpticalVolume(storm.species, storm.beta_ext, storm.beta_total, np.repeat(channel[..., None], 3, -1),
                             storm.weights, storm.bbox, storm.species_set, phase_tables=storm.phase_tables)
    assert is_grey(grey.albedo) and not is_grey(three.albedo) and not is_grey(storm.albedo)
    assert grey.albedo.base is not None and np.shares_memory(grey.albedo, grey.albedo[..., 0])
    a, b = delta_scaled(grey, 3.0), delta_scaled(three, 3.0)
    assert is_grey(a.albedo)
    for name in ("beta_total", "albedo", "weights"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    from weather_mi.kernel.medium import grey_or_rgb
    one = grey_or_rgb(a.albedo)
    assert one.shape == a.albedo.shape[:3] + (1,) and np.shares_memory(one, a.albedo)
    assert np.array_equal(one, grey_or_rgb(b.albedo))


def test_packed_weights_from_the_deferred_weights_equal_the_whole_grid_ones(storm, small_chunks):
    from weather_mi.kernel.medium import phase_arrays
    from weather_mi.kernel.plugins.hydrometeor_mixture import pack_weights
    _, bt, alb, w = whole_grid_delta(storm)
    sca = alb.mean(axis=-1)
    sca *= bt
    expect = pack_weights(np.moveaxis(w * sca[None], 0, -1))
    lean = delta_scaled(storm, 3.0, species_extinction=False, deferred_weights=True)
    for vol in (lean, delta_scaled(storm, 3.0)):
        nodes, values, packed = phase_arrays(vol, packed=True)
        assert packed.shape == expect.shape and np.array_equal(packed, expect)
        assert packed.ctypes.data % 64 == 0


def test_release_frees_grids_and_reading_one_raises_naming_it(storm):
    vol = delta_scaled(storm, 3.0)
    vol.release("albedo", "weights")
    assert vol.albedo.shape == storm.albedo.shape and vol.beta_total.shape == storm.beta_total.shape
    with pytest.raises(wm.WeatherDataError, match="albedo"):
        np.asarray(vol.albedo)
    with pytest.raises(wm.WeatherDataError, match="weights"):
        vol.weights.sum()
    with pytest.raises(ValueError, match="bbox"):
        vol.release("bbox")
    np.asarray(storm.albedo)  # the volume it came from keeps its own


def test_a_render_that_releases_its_volume_renders_the_same_image(storm):
    """``render_reference(release_volume=True)`` (the command line's): the same image, bit for bit; the volume's
    grids are released after it (reading one raises), the rest (bbox, attrs) stays."""
    (x0, y0, _), (x1, y1, z1) = storm.bbox
    cam = wm.Camera.orthographic(center=((x0 + x1) / 2, (y0 + y1) / 2, z1 + 1000.0), direction=(0.0, 0.0, -1.0),
                                 width=x1 - x0, height=y1 - y0)
    sp = wm.SceneSpec(camera=cam, sun=wm.Sun(200.0, 40.0), width=24, height=18, seed=3)
    keep = wm.render_reference(sp, storm, spp=4, passes=2, progress=False)
    mine = wm.OpticalVolume(storm.species, storm.beta_ext, storm.beta_total, storm.albedo, storm.weights, storm.bbox,
                            storm.species_set, phase_tables=storm.phase_tables, attrs=storm.attrs)
    released = wm.render_reference(sp, mine, spp=4, passes=2, progress=False, release_volume=True)
    assert np.array_equal(keep.radiance, released.radiance) and np.array_equal(keep.stderr, released.stderr)
    assert keep.radiance.max() > 0
    for name in ("beta_total", "albedo", "weights"):
        with pytest.raises(wm.WeatherDataError, match=name):
            np.asarray(getattr(mine, name))
    assert mine.bbox == storm.bbox
    np.asarray(storm.weights)  # the other volume over the same arrays keeps them


@pytest.mark.parametrize("kind", ["rgb", "grey", "deferred"])
def test_the_species_coefficients_with_the_air_in_the_grid_are_the_kernels(storm, small_chunks, monkeypatch, kind):
    """Eq. 8's w_s beta omega (``optics.scattering_coefficients``) as ``medium_grids`` puts them before the box's
    air's (a slab of levels at a time, slabs ending mid-chunk) and as the kernel hands the hydrometeors' alone
    (``kernel.medium._hydrometeor_arrays``): both the whole-grid float32 expression w * (mean albedo * beta), bit
    for bit, for a three-channel albedo, a grey one (read as three) and deferred (delta-scaled) weights."""
    from weather_mi.kernel.medium import _hydrometeor_arrays
    from weather_mi.optics.air import Atmosphere
    from weather_mi.optics.air import inside
    vol = storm
    if kind == "grey":
        vol = replace(vol, albedo=grey_albedo(np.asarray(vol.albedo)[..., 1]))
    if kind == "deferred":
        vol = delta_scaled(vol, 3.0, species_extinction=False, deferred_weights=True)
    cells = vol.shape[1] * vol.shape[2]
    monkeypatch.setattr(inside, "SLAB_CELLS", 3 * cells)
    air = inside.scene_air(vol, Atmosphere()).air
    coeffs = inside.medium_grids(vol.beta_total, vol.albedo, vol.weights, air, want=("coeffs",))[2]
    sca = np.asarray(vol.albedo).mean(axis=-1) * vol.beta_total
    expected = np.moveaxis(np.asarray(vol.weights) * sca[None], 0, -1)
    n_s = len(vol.species)
    np.testing.assert_array_equal(coeffs[..., :n_s], expected)
    np.testing.assert_array_equal(_hydrometeor_arrays(vol, packed=False)[2], expected)
    assert expected.max() > 0 and np.all(coeffs[..., n_s:] > 0)  # and the air's after them


def test_five_species_hand_the_plugin_a_packet_and_a_tail_with_the_same_values(storm, small_chunks):
    """``kernel.medium.kernel_weights``: for 4 P + 1 species the last one's grid of its own (20 bytes per cell for
    five, not 32); its values are the padded packets' (``phase_arrays(packed=True)``), and the plugin's lookups
    (``weights_tail``) give the same phase function and sampling, bit for bit, as from the padded packets."""
    import drjit as dr
    import mitsuba as mi
    from weather_mi.kernel.medium import kernel_weights, phase_arrays
    from weather_mi.kernel.plugins.hydrometeor_mixture import bbox_transform
    wm.kernel.variant.set_variant("llvm_ad_rgb")
    w = np.random.default_rng(4).uniform(0, 1, storm.weights.shape).astype(np.float32)  # every species present
    w /= w.sum(axis=0)
    mixed = wm.OpticalVolume(storm.species, storm.beta_ext, storm.beta_total, storm.albedo, w, storm.bbox,
                             storm.species_set, phase_tables=storm.phase_tables)
    vol = delta_scaled(mixed, 3.0, species_extinction=False, deferred_weights=True)
    nodes, values, padded = phase_arrays(vol, packed=True)
    packets, tail = kernel_weights(vol)
    assert padded.shape[-2:] == (2, 4) and packets.shape[-2:] == (1, 4) and tail.shape == packets.shape[:3]
    assert np.array_equal(packets[..., 0, :], padded[..., 0, :]) and np.array_equal(tail, padded[..., 1, 0])
    assert not np.any(padded[..., 1, 1:]) and tail.max() > 0
    common = {"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]), "values": mi.TensorXf(values),
              "to_world": bbox_transform(vol.bbox)}
    a = mi.load_dict({**common, "weights": mi.TensorXf(padded)})
    b = mi.load_dict({**common, "weights": mi.TensorXf(packets), "weights_tail": mi.TensorXf(tail)})
    rng = np.random.default_rng(5)
    n = 4096
    (x0, y0, z0), (x1, y1, z1) = vol.bbox
    mei = dr.zeros(mi.MediumInteraction3f, n)
    mei.p = mi.Point3f(*(rng.uniform(lo, hi, n).astype(np.float32) for lo, hi in ((x0, x1), (y0, y1), (z0, z1))))
    d = rng.normal(size=(3, n)).astype(np.float32)
    mei.wi = dr.normalize(mi.Vector3f(*d))
    mei.sh_frame = mi.Frame3f(mei.wi)
    wo = dr.normalize(mi.Vector3f(*rng.normal(size=(3, n)).astype(np.float32)))
    ctx = mi.PhaseFunctionContext(None)
    s1, s2 = mi.Float(rng.uniform(size=n).astype(np.float32)), mi.Point2f(*rng.uniform(size=(2, n)).astype(np.float32))
    for out_a, out_b in ((a.eval_pdf(ctx, mei, wo), b.eval_pdf(ctx, mei, wo)),
                         (a.sample(ctx, mei, s1, s2), b.sample(ctx, mei, s1, s2))):
        for x, y in zip(out_a, out_b):
            assert np.array_equal(np.array(x), np.array(y))
    assert np.array_equal(np.array(mi.traverse(b)["weights"]), np.array(mi.traverse(a)["weights"]))


def whole_grid_majorants(a, cell, safety):
    """``majorants.majorant_grid`` as whole-grid dilations (weather-mi before the slabs)."""
    d = np.asarray(a, np.float32)
    d = d.max(axis=3) if d.ndim == 4 else d
    for axis in range(3):
        lo, hi = [slice(None)] * 3, [slice(None)] * 3
        lo[axis], hi[axis] = slice(0, -1), slice(1, None)
        e = d.copy()
        np.maximum(e[tuple(hi)], d[tuple(lo)], out=e[tuple(hi)])
        np.maximum(e[tuple(lo)], d[tuple(hi)], out=e[tuple(lo)])
        d = e
    for axis in range(3):
        d = np.maximum.reduceat(d, np.arange(0, d.shape[axis], cell), axis=axis)
    return (np.maximum(d, 0.0).astype(np.float64) * float(safety)).astype(np.float32)


@pytest.mark.parametrize("shape", [(7, 9, 10), (1, 5, 3), (6, 1, 1), (5, 4, 6, 3)])
@pytest.mark.parametrize("cell", [1, 2, 3, 4])
def test_coarse_majorants_by_slabs_equal_the_whole_grid_dilations(shape, cell):
    from weather_mi.kernel.plugins.majorants import SAFETY, majorant_grid
    a = np.random.default_rng(cell).normal(size=shape).astype(np.float32)  # negatives count as 0
    got = majorant_grid(a, cell)
    assert np.array_equal(got, whole_grid_majorants(a, cell, SAFETY))
    grey = a if a.ndim == 3 else a.max(axis=3)  # and a bound of every voxel of its dilated cell (the definition)
    for (k, j, i), m in np.ndenumerate(got):
        box = grey[max(k * cell - 1, 0):(k + 1) * cell + 1, max(j * cell - 1, 0):(j + 1) * cell + 1,
                   max(i * cell - 1, 0):(i + 1) * cell + 1]
        assert m == np.float32(max(float(box.max()), 0.0) * SAFETY)
