"""The path tracer against plane-parallel radiative transfer (DISORT via disortpp, van de Hulst's
published values), a white furnace, and the orientation of grids and images.

Criterion for slab quantities (R, T, radiances pi L / (mu0 E)): |MC - reference| <= 3 standard
errors AND <= 0.01. All renders use fixed seeds (deterministic). The full table (16 cases) is
validation/plane_parallel.py.
"""
import math

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.plane_parallel import slab

disortpp = pytest.importorskip("disortpp")

VDH = dict(tau=2.0, albedo=0.9, g=0.75, mu0=1.0)
VDH_R, VDH_T = 0.09739, 0.66096  # van de Hulst (1980), single HG layer, overhead sun, black surface
NO_RR = 1 << 30


def assert_agrees(name, mc, se, ref, abs_tol=0.01):
    assert np.isfinite(se) and se > 0, f"{name}: standard error {se}"
    assert slab.agrees(mc, se, ref, abs_tol=abs_tol), \
        f"{name}: MC {mc:.5f} +- {se:.5f} vs reference {ref:.5f} (diff {mc - ref:+.5f} = {(mc - ref) / se:+.1f} se)"


def test_disort_reproduces_van_de_hulst():
    d = slab.disort_slab(**VDH)
    assert d["R"] == pytest.approx(VDH_R, abs=1e-5)
    assert d["T"] == pytest.approx(VDH_T, abs=1e-5)
    assert d["T_direct"] == pytest.approx(math.exp(-2.0), rel=1e-9)


def test_disort_intensity_correction_is_active_and_converged():
    """The Nakajima-Tanaka correction needs both intensity flags in disortpp; with it, 64 streams are
    converged for the forward-peaked radiances the validation compares."""
    a = slab.disort_slab(1.0, 1.0, 0.85, 1.0, n_streams=64)
    b = slab.disort_slab(1.0, 1.0, 0.85, 1.0, n_streams=128)
    assert a["L_zenith"] == pytest.approx(b["L_zenith"], rel=1e-4)
    assert a["L_nadir"] == pytest.approx(b["L_nadir"], rel=1e-3)
    assert a["R"] + a["T"] == pytest.approx(1.0, abs=1e-6)  # conservative scattering


def plugin_asymmetry(table) -> float:
    """Mean cosine of a table as the ``hydrometeor_mixture`` plugin represents it: piecewise linear in
    the versine v = 1 - cos theta on its node set (so also linear in mu), exact integral of mu p."""
    from weather_mi.kernel.plugins.hydrometeor_mixture import prepare_tables
    nodes, values = prepare_tables([table])
    mu = (1.0 - nodes.astype(np.float64))[::-1]
    p = values[0].astype(np.float64).mean(axis=1)[::-1]
    a, b, pa, pb = mu[:-1], mu[1:], p[:-1], p[1:]
    return float(2 * np.pi * np.sum((b - a) * (pa * (2 * a + b) + pb * (a + 2 * b)) / 6.0))


def test_disort_takes_a_phase_tables_own_moments():
    """A tabulated HG phase function's Legendre moments (PhaseTable.legendre) give DISORT the same
    fluxes and corrected intensities as its own HG moments g^l."""
    own = slab.disort_slab(2.0, 0.99, 0.8, 0.5)
    tab = slab.disort_slab(2.0, 0.99, wm.phase.henyey_greenstein(0.8), 0.5)
    for key in ("R", "T", "L_nadir", "L_zenith"):
        assert tab[key] == pytest.approx(own[key], rel=1e-4), key


@pytest.mark.parametrize("g", [0.0, 0.75, 0.85])
def test_hg_table_as_the_plugin_sees_it(g):
    """The renderer's HG table keeps the closed-form mean cosine g (the DISORT runs use g itself)."""
    table = wm.phase.henyey_greenstein(g)
    assert plugin_asymmetry(table) == pytest.approx(g, abs=2e-4)
    mu = np.cos(table.theta)
    integral = -2 * np.pi * np.trapezoid(table.values[:, 0], mu)
    assert integral == pytest.approx(1.0, abs=1e-3)


def test_van_de_hulst_rendered_direct_beam_included():
    """R and T (direct beam included) against the published values. The irradiancemeter sees only the
    diffuse transmitted light (it never reaches the directional sun); the white-patch measurement
    adds the direct beam exp(-tau / mu0) by emitter sampling."""
    f = slab.slab_fluxes(VDH["tau"], VDH["albedo"], wm.phase.henyey_greenstein(VDH["g"]), VDH["mu0"], spp=1 << 19,
                           passes=16, seed=11, transmittance_method="both", rr_depth=NO_RR)
    d = slab.disort_slab(**VDH)
    assert_agrees("R", f["R"], f["R_stderr"], VDH_R)
    assert_agrees("T", f["T"], f["T_stderr"], VDH_T)
    assert_agrees("T_diffuse (irradiancemeter)", f["T_diffuse"], f["T_diffuse_stderr"], d["T_diffuse"])
    assert f["T"] - f["T_diffuse"] == pytest.approx(math.exp(-2.0), abs=4 * math.hypot(f["T_stderr"], f["T_diffuse_stderr"]))


@pytest.mark.parametrize("g, albedo, tau, mu0, paths, rr_depth", [
    (0.0, 1.0, 1.0, 0.5, 1 << 18, None),      # thin, oblique sun; radiance through render_reference as is
    (0.0, 0.99, 8.0, 1.0, 1 << 18, NO_RR),    # thick, isotropic
    (0.85, 0.99, 8.0, 1.0, 1 << 19, NO_RR),   # thick, forward-peaked (cloud-like)
])
def test_slab_against_disort(g, albedo, tau, mu0, paths, rr_depth):
    table = wm.phase.henyey_greenstein(g)
    d = slab.disort_slab(tau, albedo, g, mu0)
    f = slab.slab_fluxes(tau, albedo, table, mu0, spp=paths, passes=16, seed=21, rr_depth=rr_depth)
    assert_agrees("R", f["R"], f["R_stderr"], d["R"])
    assert_agrees("T", f["T"], f["T_stderr"], d["T"])
    rad, se = slab.slab_radiance(tau, albedo, table, mu0, spp=paths // 256, view="nadir", pixels=16, passes=16,
                                   seed=23, rr_depth=rr_depth)
    assert_agrees("nadir radiance", rad, se, d["L_nadir"])


def test_white_furnace():
    """A non-absorbing heterogeneous medium (forward-peaked phase) inside a uniform environment of
    radiance L, no sun: every pixel must show L (per channel) within noise."""
    rng = np.random.default_rng(3)
    n = 12
    z, y, x = np.meshgrid(*(np.linspace(-1, 1, n),) * 3, indexing="ij")
    beta = np.zeros((n, n, n))
    for _ in range(6):
        c = rng.uniform(-0.6, 0.6, 3)
        beta += np.exp(-((z - c[0]) ** 2 + (y - c[1]) ** 2 + (x - c[2]) ** 2) / 0.08)
    beta *= 0.02 / beta.max()  # up to 20 optical depths per km
    vol = wm.OpticalVolume.from_arrays(beta, 1.0, wm.phase.henyey_greenstein(0.85), ((0, 0, 0), (1000, 1000, 1000)))
    L = np.array([0.2, 0.5, 1.0])
    spec = wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=200.0, elevation=25.0),
                        sun=wm.Sun(240.0, 35.0, irradiance=0.0, angular_diameter_deg=0.0), sky=wm.Sky("constant", radiance=tuple(L)),
                        ground=None, width=24, height=24, seed=5)
    img = wm.render_reference(spec, vol, spp=128, integrator="volpath", passes=16, progress=False)
    rad, se = img.radiance.astype(np.float64), img.stderr.astype(np.float64)
    # the image mean per channel: L within 4 standard errors and 0.5%
    mean_se = np.sqrt((se ** 2).sum(axis=(0, 1))) / (24 * 24)
    np.testing.assert_array_less(np.abs(rad.mean(axis=(0, 1)) - L), 4 * mean_se + 1e-6)
    np.testing.assert_allclose(rad.mean(axis=(0, 1)), L, rtol=5e-3)
    # every pixel: beyond 3 standard errors (+ 1e-4 relative) only as often as chance allows. (A 1%
    # absorbing medium reads 0.28% low here, 5 se: the image mean catches it, single pixels do not.
    # Russian roulette makes single pixels heavy-tailed: no bound on the largest deviation.)
    z_score = np.abs(rad - L) / (se + 1e-4 * L)
    assert np.mean(z_score > 3) < 0.02, f"{np.mean(z_score > 3):.3f} of pixel channels beyond 3 se"
    # pixels whose rays miss the medium see the environment exactly
    clear = np.all(se == 0, axis=2)
    assert clear.any() and np.allclose(rad[clear], L, rtol=1e-6)


def _blob_volume(albedo_sw=None):
    """16 x 16 x 8 voxels of 100 m: a blob in the north-east corner (high y, high x) in the upper half;
    with ``albedo_sw`` also a blob of that albedo in the south-west corner (low y, low x)."""
    beta = np.zeros((8, 16, 16), np.float32)
    beta[4:8, 12:16, 12:16] = 0.02
    albedo = np.ones((8, 16, 16), np.float32)
    if albedo_sw is not None:
        beta[4:8, 0:4, 0:4] = 0.02
        albedo[:, 0:8, 0:8] = albedo_sw
    return wm.OpticalVolume.from_arrays(beta, albedo, wm.phase.henyey_greenstein(0.0), ((0, 0, 0), (1600, 1600, 800)))


def _render(vol, camera, width, height):
    spec = wm.SceneSpec(camera=camera, sun=wm.Sun(0.0, 90.0, 1.0, angular_diameter_deg=0.0), sky=None, ground=None,
                        width=width, height=height, seed=1)
    return wm.render_reference(spec, vol, spp=16, integrator="volpath", passes=4, progress=False)


def _quadrant_fractions(lum):
    h, w = lum.shape
    tot = lum.sum()
    return {"top_right": lum[: h // 2, w // 2:].sum() / tot, "top_left": lum[: h // 2, : w // 2].sum() / tot,
            "bottom_right": lum[h // 2:, w // 2:].sum() / tot, "bottom_left": lum[h // 2:, : w // 2].sum() / tot}


def test_orientation_top_view_north_up_east_right():
    """Looking straight down: north (+y) is the top of the image (row 0), east (+x) the right."""
    vol = _blob_volume()
    cam = wm.Camera.orthographic(center=(800.0, 800.0, 2000.0), direction=(0.0, 0.0, -1.0), width=1600, height=1600)
    lum = _render(vol, cam, 32, 32).radiance.mean(axis=2)
    q = _quadrant_fractions(lum)
    assert lum.sum() > 0
    assert q["top_right"] > 0.99, q
    # the blob's voxels cover x, y in [1200, 1600]: columns 24..31, rows 0..7; trilinear filtering
    # (texel centres at (i + 0.5) / N) ramps its edge over the neighbouring half voxel: column 23, row 8
    assert lum[:9, 23:].sum() / lum.sum() > 0.999
    assert lum[:8, 24:].sum() / lum.sum() > 0.8


def test_orientation_side_view_up_is_top():
    """Looking north from the south: up (+z) is the top of the image, east (+x) the right."""
    vol = _blob_volume()
    cam = wm.Camera.orthographic(center=(800.0, -2000.0, 400.0), direction=(0.0, 1.0, 0.0), width=1600, height=800)
    lum = _render(vol, cam, 32, 16).radiance.mean(axis=2)
    q = _quadrant_fractions(lum)
    assert lum.sum() > 0
    assert q["top_right"] > 0.99, q
    # z in [400, 800] (+ half a voxel of filtering) -> rows 0..8 of 16; x in [1150, 1600] -> columns 23..31
    assert lum[:9, 23:].sum() / lum.sum() > 0.999


def test_orientation_albedo_grid_follows_extinction_grid():
    """Two blobs, NE with albedo 1, SW with albedo 0: only the NE one is bright."""
    vol = _blob_volume(albedo_sw=0.0)
    cam = wm.Camera.orthographic(center=(800.0, 800.0, 2000.0), direction=(0.0, 0.0, -1.0), width=1600, height=1600)
    lum = _render(vol, cam, 32, 32).radiance.mean(axis=2)
    q = _quadrant_fractions(lum)
    assert q["top_right"] > 0.99, q
    assert lum[24:, :8].max() == 0.0  # the black blob in the south-west scatters nothing
