"""The box's air added per level by the kernel (issue 39, render's memory): with ``majorant_volpath`` the medium's
sigma_t grid stays the hydrometeors' grey one and the Eq. 8 coefficients their own grid, the air's extinction and
coefficients one value per level that the integrator (``air_extinction``) and the phase (``air_weights``) add;
stock ``volpath`` keeps the air in 3-channel grids (``kernel.medium.medium_dict(air_in_grid=True)``, the path
before). sigma_t is the same in both to float rounding. The albedo is the point-wise mixture in the integrator
(checked at random points against its closed form) and the texels' mixtures blended in the grids (stock volpath's
only way), which differ at the cloud's edges where the air absorbs; in air that does not absorb the renders of
one scene with the same seeds agree within their noise, while the same scene without its air does not. The phase
takes the air per level and colour channel in both (Eq. 8 per wavelength: checked here against its closed form on a
uniform cloud, and against DISORT in ``tests/test_clear_sky_disort.py``)."""
from __future__ import annotations

import numpy as np
import pytest

import drjit as dr
import mitsuba as mi

import weather_mi  # noqa: F401  (variant + plugins)
from weather_mi.io import synthetic
from weather_mi.kernel import scene_dict as sd
from weather_mi.kernel.medium import medium_dict, phase_dict
from weather_mi.optics.air import Atmosphere
from weather_mi.optics.air.inside import with_box_air
from weather_mi.optics.volume import optical_volume
from weather_mi.scene.framing import scene_spec

ATM = Atmosphere(aod_550=0.3)  # aerosol absorbs (ssa < 1) and scatters forward: the air's albedo is not 1
CONSERVATIVE = Atmosphere(aod_550=0.0, ozone_atm_cm=0.0)


def _storm(atm):
    """(spec, volume in kernel coordinates, integrator dict): a small synthetic supercell (five species, the paper's
    optics) with the box's air of ``atm``."""
    mi.set_variant("llvm_ad_rgb")
    hyd = synthetic.supercell(shape=(20, 32, 32), spacing_m=(800.0, 2000.0, 2000.0))
    vol = with_box_air(optical_volume(hyd, "paper"), hyd, atm)
    spec, vol_k, _ = sd.recentred(scene_spec(vol, (24, 16), camera="orbit"), vol)
    integ = sd.integrator_dict(vol_k, "majorant", 64, sun=spec.sun, atmosphere=atm)
    return spec, vol_k, integ


@pytest.fixture(scope="module")
def storm():
    return _storm(ATM)


@pytest.fixture(scope="module")
def conservative_storm():
    """The storm in air that does not absorb (no aerosol, no ozone): the air's albedo 1 everywhere."""
    return _storm(CONSERVATIVE)


def _scene(spec, vol, integ, air_in_grid: bool):
    d = sd.scene_dict(spec, vol, integ)
    if air_in_grid:  # the path before: the air in the medium's grids
        m = medium_dict(vol, air_in_grid=True)
        if "weather_medium" in d:
            d["weather_medium"] = m
        else:
            d["medium_box"]["interior"] = m
    return d


def _medium(d):
    return d["weather_medium"] if "weather_medium" in d else d["medium_box"]["interior"]


def test_the_kernel_grids_leave_the_air_out(storm):
    """The default (majorant_volpath) medium: a grey sigma_t grid, five species' coefficients (packets and tail),
    the air's two components per level, no albedo grid (the integrator reads the volume's in place); with the air in
    the grids: RGB sigma_t, the mixture's albedo grid and two packets of coefficients."""
    spec, vol, integ = storm
    new, old = _medium(_scene(spec, vol, integ, False)), _medium(_scene(spec, vol, integ, True))
    nz = vol.shape[0]
    assert tuple(new["sigma_t"]["data"].shape) == tuple(vol.shape) + (1,) and not new["has_spectral_extinction"]
    assert tuple(old["sigma_t"]["data"].shape) == tuple(vol.shape) + (3,) and old["has_spectral_extinction"]
    assert tuple(new["phase"]["weights"].shape) == tuple(vol.shape) + (1, 4) and "weights_tail" in new["phase"]
    for m in (new, old):  # the air's two components per level and channel (R, G, B), whichever integrator
        assert tuple(m["phase"]["weights"].shape) == tuple(vol.shape) + (1, 4) and "weights_tail" in m["phase"]
        assert tuple(m["phase"]["air_weights"].shape) == (nz, 2, 3)
    assert new["albedo"] == 1.0 and tuple(old["albedo"]["data"].shape) == tuple(vol.shape) + (3,)  # albedo: the kernel's


def _points(vol, n, seed=3):
    rng = np.random.default_rng(seed)
    lo, hi = (np.asarray(p, np.float64) for p in vol.bbox)
    p = lo + rng.random((n, 3)) * (hi - lo)
    p[: n // 4, 2] = lo[2] + (rng.integers(0, vol.shape[0], n // 4) + 0.5) / vol.shape[0] * (hi[2] - lo[2])  # centres
    return mi.Point3f(*(p[:, k].astype(np.float32) for k in range(3)))


def test_the_phase_weights_are_each_channels_shares_of_its_scattering():
    """Eq. 8 per colour channel on a uniform cloud (one species, albedo 1, beta 2e-4 /m) in a box of air whose
    density changes by level: at random points each channel's weights are beta / (beta + air_R,c + air_A,c) and
    air_k,c / (...), with the air's scattering per channel linear between level centres (computed here from the
    box's per-level table), within float32 rounding; the channels differ (molecules scatter ~3.6x more at 450
    than at 650 nm) and sum to 1. A single band (equal channels) keeps one weight for all three."""
    from dataclasses import replace
    from weather_mi.optics.air.inside import box_air
    from weather_mi.optics.phase.analytic import henyey_greenstein
    from weather_mi.optics.volume import OpticalVolume
    mi.set_variant("llvm_ad_rgb")
    nz, beta = 6, 2e-4
    bbox = ((-5e3, -5e3, 0.0), (5e3, 5e3, 12e3))
    vol = OpticalVolume.from_arrays(np.full((nz, 4, 4), beta, np.float32), 1.0, henyey_greenstein(0.85), bbox)
    z = (np.arange(nz) + 0.5) * 2e3
    vol = replace(vol, air=box_air(Atmosphere(aod_550=0.3), 1.2 * np.exp(-z / 8e3), z, shape=(nz, 4, 4)))
    phase = mi.load_dict(phase_dict(vol))
    mei = dr.zeros(mi.MediumInteraction3f, 500)
    rng = np.random.default_rng(5)
    p = rng.uniform([-5e3, -5e3, 0.0], [5e3, 5e3, 12e3], (500, 3)).astype(np.float32)
    mei.p = mi.Point3f(*(p[:, k] for k in range(3)))
    w = phase._weights_at(mei)
    sca = np.asarray(vol.air.scattering_levels, np.float64)  # (2, levels, R G B)
    fz = np.clip(p[:, 2] / 2e3 - 0.5, 0.0, nz - 1.0)
    i0 = np.minimum(np.floor(fz).astype(int), nz - 2)
    air = sca[:, i0] + (sca[:, i0 + 1] - sca[:, i0]) * (fz - i0)[None, :, None]  # (2, points, 3)
    total = beta + air.sum(axis=0)
    got = np.array([[np.array(w.channels[c][s]) for c in range(3)] for s in range(3)])  # (species, channel, points)
    np.testing.assert_allclose(got[0], (beta / total).T, rtol=2e-6)
    np.testing.assert_allclose(got[1:], np.transpose(air / total, (0, 2, 1)), rtol=2e-5, atol=1e-9)
    np.testing.assert_allclose(got.sum(axis=0), 1.0, rtol=1e-6)
    assert np.all(got[1, 2] > 3.0 * got[1, 0])  # the molecules' share in blue against red
    grey = replace(vol, air=replace(vol.air, scattering_levels=np.repeat(vol.air.scattering_levels[..., 1:2], 3, -1),
                                    extinction_levels=np.repeat(vol.air.extinction_levels[..., 1:2], 3, -1)))
    assert tuple(phase_dict(grey)["air_weights"].shape) == (nz, 2)


def _trilinear(grid, p_unit):
    """numpy: ``grid`` (z, y, x, ...) at unit-cube points (n, 3 as x, y, z), texel centres at (i + 0.5) / n,
    clamped at the edges (Mitsuba's grid volumes)."""
    idx, frac = [], []
    for axis, n in enumerate(grid.shape[:3]):
        u = p_unit[:, 2 - axis] * n - 0.5
        i0 = np.floor(u)
        idx.append((np.clip(i0, 0, n - 1).astype(int), np.clip(i0 + 1, 0, n - 1).astype(int)))
        frac.append(u - i0)
    out = 0.0
    for k in range(8):
        bits = [(k >> 2) & 1, (k >> 1) & 1, k & 1]
        w = np.prod([f if b else 1.0 - f for f, b in zip(frac, bits)], axis=0)
        z, y, x = (idx[a][b] for a, b in zip(range(3), bits))
        out = out + (w[:, None] if grid.ndim == 4 else w) * grid[z, y, x]
    return out


def test_sigma_t_is_the_grids_and_the_albedo_the_point_wise_mixture(storm):
    """At random points: sigma_t (per channel), the grey grid plus the air per level, equals the RGB grid that holds
    their sum (the medium's own lookups) to float32 rounding; the single-scattering albedo is the point-wise
    mixture (omega_h beta + s) / (beta + e), each term interpolated as the medium interpolates it (computed here
    in numpy from the volume's arrays). The RGB grid's albedo, its texels' mixtures blended (stock volpath's only
    way), differs from it at the cloud's edges, where the air's albedo is not 1 (aerosol absorbs)."""
    from weather_mi.kernel.plugins.medium_setup import scattering_event, sigma_t_at
    spec, vol, integ = storm
    got = []
    p = _points(vol, 4000)
    for in_grid in (True, False):
        scene = mi.load_dict(_scene(spec, vol, integ, in_grid))
        it = scene.integrator()
        it._setup(scene, None)
        assert (it._ms.air is None) == in_grid and it._ms.spectral
        ray = mi.Ray3f(p, mi.Vector3f(0, 0, 1))
        s_t = np.array(sigma_t_at(it._ms, p, ray, mi.Bool(True)))
        _, albedo = scattering_event(it._ms, ray, mi.Float(0.0), mi.Bool(True))
        got.append((s_t, np.array(albedo)))
    (s0, a0), (s1, a1) = got
    np.testing.assert_allclose(s1, s0, rtol=3e-6, atol=1e-12)
    lo, hi = (np.asarray(q, np.float64) for q in vol.bbox)
    unit = (np.stack([np.array(c, np.float64) for c in (p.x, p.y, p.z)], 1) - lo) / (hi - lo)
    beta = _trilinear(np.asarray(vol.beta_total, np.float64), unit)
    omega_h = _trilinear(np.broadcast_to(np.asarray(vol.albedo, np.float64)[..., None] if np.ndim(vol.albedo) == 3
                                         else np.asarray(vol.albedo, np.float64), vol.shape[:3] + (3,)), unit)
    air = vol.air
    ext = _trilinear(np.broadcast_to(air.extinction_levels[:, None, None, :], vol.shape[:3] + (3,)), unit)
    sca = _trilinear(np.broadcast_to(air.scattering_levels.sum(0)[:, None, None, :], vol.shape[:3] + (3,)), unit)
    want = np.clip((omega_h * beta[:, None] + sca) / (beta[:, None] + ext), 0.0, 1.0)
    np.testing.assert_allclose(a1.T if a1.shape[0] == 3 else a1, want, rtol=1e-4, atol=1e-6)
    a0 = a0.T if a0.shape[0] == 3 else a0
    assert s0.min() > 0 and want.min() < 0.99  # the air's extinction everywhere, its absorption somewhere
    assert np.abs(a0 - want).max() > 0.01  # the blended texel mixtures differ at the edges


def _passes(d, n, spp=32):
    from weather_mi.reference.passes import pass_seed
    scene = mi.load_dict(d)
    return np.stack([np.array(mi.render(scene, spp=spp, seed=pass_seed(1, i)), np.float64)[..., :3] for i in range(n)])


def test_renders_agree_with_the_air_in_the_grids(conservative_storm):
    """The default air render (the air per level) and the render with the air in the grids, same scene and seeds,
    in air that does not absorb (with absorbing air the two are different media at the cloud's edges by
    definition: the grids blend their texels' mixture albedos, the integrator mixes point-wise; that one is checked
    against DISORT with an absorbing cloud in ``tests/test_clear_sky_disort.py``; with ATM's aerosol the grid render
    was 2-9 % darker):
    the per-channel mean within 0.3 % and the pixels' differences within their noise (RMS of the differences over
    their combined standard errors below 1: the two follow nearly the same paths), the image means within 4
    standard errors of their paired differences; the scene without its air more than 6 away in blue (-8.8 measured; the check can
    fail)."""
    from dataclasses import replace
    spec, vol, integ = conservative_storm
    n = 8
    old, new = _passes(_scene(spec, vol, integ, True), n), _passes(_scene(spec, vol, integ, False), n)
    m0, m1 = old.mean(0), new.mean(0)
    se = np.sqrt(old.var(0, ddof=1) / n + new.var(0, ddof=1) / n) + 1e-30
    z = (m1 - m0) / se
    np.testing.assert_allclose(m1.mean(axis=(0, 1)), m0.mean(axis=(0, 1)), rtol=3e-3)
    assert np.sqrt(np.mean(z ** 2)) < 1.0 and np.abs(z).max() < 5.0
    bare = replace(vol, air=None)
    none = _passes(_scene(spec, bare, sd.integrator_dict(bare, "majorant", 64, sun=spec.sun, atmosphere=CONSERVATIVE),
                          False), n)
    z_new, z_none = _paired_z(new, old), _paired_z(none, old)
    assert np.abs(z_new).max() < 4.0 and np.abs(z_none).max() > 6.0, (z_new, z_none)


def _paired_z(a, b):
    """Per channel: the image means' difference (a - b) over its standard error from the passes' paired differences."""
    d = a.mean(axis=(1, 2)) - b.mean(axis=(1, 2))   # (passes, 3)
    return d.mean(0) / (d.std(0, ddof=1) / np.sqrt(d.shape[0]) + 1e-30)
