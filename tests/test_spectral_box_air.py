"""The box's air in the spectral ground truth (issue 38 part 2): ``llvm_ad_spectral`` with the air per level over
wavelength (``kernel/spectral_air.py``, ``kernel/plugins/spectral_air.py``, ``spectral_air_albedo.py``,
``spectral_air_weights.py``). A cloud-free 10 km slab of air (``tests/test_box_air.py``'s) checked against numbers
that do not come from our code: the kernel's optical depth at fixed wavelengths against the RGB medium's per channel
and against Bodhaine et al. (1999)'s cross section (Eq. 2, written out in ``test_box_air``) x the number density;
the direct sun through the box (Beer-Lambert) at one wavelength; the nadir reflectance's CIE X, Y, Z against DISORT
solved every 5 nm and integrated over the ASTM G173 sun and the CIE 1931 functions here; a grey cloud layer inside the
slab (the trackers' texel path with the air at the ray's wavelengths) against the cloud's optical depth plus
Bodhaine's, per lane. Every test puts the variant back as it found it."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from test_box_air import AVOGADRO, DEPOL, H_M, M_AIR, MU0, RHO, WIDE_M, _clear_slab, _nadir_camera, _point_sun, \
    _sigma_physical_m2, _tau
from test_spectral import SPECTRAL, _astm_toa, _cmfs

RGB = "llvm_ad_rgb"


def _integrator(variant: str, slab=None):
    """The loaded ``majorant_volpath`` of a scene with the clear slab (after its per-render set-up) and the slab."""
    import mitsuba as mi
    from weather_mi.kernel.scene_dict import integrator_dict, scene_dict
    from weather_mi.kernel.variant import set_variant
    from weather_mi.scene.spec import SceneSpec
    set_variant(variant)
    slab = _clear_slab() if slab is None else slab
    spec = SceneSpec(camera=_nadir_camera(), sun=_point_sun(), sky=None, ground=None, width=4, height=4)
    scene = mi.load_dict(scene_dict(spec, slab, integrator_dict(slab, "majorant", -1, sun=spec.sun)))
    integ = scene.integrator()
    integ._setup(scene, None)
    return integ


def _vertical_rays(variant: str, wavelengths_nm, slant: float = 0.0):
    """Rays from 1 m below the slab's top straight down (tilted by ``slant`` in x per unit z), 4 lanes, the given
    wavelengths (spectral) in every lane; their length to 1 m above the bottom."""
    import mitsuba as mi
    d = np.array([slant, 0.0, -1.0]) / math.hypot(slant, 1.0)
    n = 4
    ray = mi.Ray3f(mi.Point3f(np.zeros(n), np.linspace(-50.0, 50.0, n), np.full(n, H_M - 1.0)),
                   mi.Vector3f(*(np.full(n, v) for v in d)))
    if variant == SPECTRAL:
        ray.wavelengths = mi.Spectrum(*(mi.Float(np.full(n, w, np.float32)) for w in wavelengths_nm))
    return ray, mi.Float(np.full(n, (H_M - 2.0) / -d[2], np.float32))


def _tau_kernel(variant: str, wavelengths_nm=None, slant: float = 0.0, tracker: str = "exact", slab=None):
    """-log T through the slab's air by the trackers (exact, or a ratio-tracking mean), (lanes or channels,)."""
    import mitsuba as mi
    from weather_mi.kernel.plugins.trackers import exact_transmittance, ratio_tracking
    integ = _integrator(variant, slab)
    ray, t_end = _vertical_rays(variant, wavelengths_nm, slant)
    if tracker == "exact":
        tr = np.array(exact_transmittance(integ._tk, ray, t_end, mi.Bool(True)))
    else:
        n = 1 << 14
        big, sampler = _repeated_rays(ray, wavelengths_nm, n, seed=7)
        tr = np.array(ratio_tracking(integ._tk, big, dr_repeat(t_end, n), sampler, mi.Bool(True)))
        return -np.log(tr.reshape(tr.shape[0], -1).mean(axis=1)), tr.reshape(tr.shape[0], -1).std(axis=1) / math.sqrt(4 * n)
    return -np.log(tr.reshape(tr.shape[0], -1).mean(axis=1))


def dr_repeat(a, n):
    import mitsuba as mi
    return mi.Float(np.tile(np.asarray(a, np.float32), n))


def _repeated_rays(ray, wavelengths_nm, n: int, seed: int):
    """(``ray``'s 4 lanes each repeated ``n`` times with ``wavelengths_nm``, an independent sampler for them)."""
    import mitsuba as mi
    big = mi.Ray3f(mi.Point3f(*(dr_repeat(c, n) for c in (ray.o.x, ray.o.y, ray.o.z))),
                   mi.Vector3f(*(dr_repeat(c, n) for c in (ray.d.x, ray.d.y, ray.d.z))))
    big.wavelengths = mi.Spectrum(*(mi.Float(np.full(4 * n, w, np.float32)) for w in wavelengths_nm))
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(seed, 4 * n)
    return big, sampler


def test_optical_depth_at_the_rgb_wavelengths_is_the_rgb_mediums(variant_restored):
    """A slanted ray through the slab: the spectral kernel's optical depth at 650 / 550 / 450 nm equals the RGB
    kernel's per channel to float rounding; at 500 nm it is Bodhaine's cross section x the number density x the
    path (the 5 nm grid read between nodes: within 0.1 %)."""
    slant = 0.7
    rgb = _tau_kernel(RGB, slant=slant)
    spec = _tau_kernel(SPECTRAL, (650.0, 550.0, 450.0, 500.0), slant=slant)
    np.testing.assert_allclose(spec[:3], rgb, rtol=2e-6)
    assert rgb[2] > 1.2 * rgb[1] > 1.2 * rgb[0]  # chromatic: the check can fail
    path = (H_M - 2.0) * math.hypot(slant, 1.0)
    n_air = RHO * AVOGADRO / M_AIR
    for lane, nm in enumerate((650.0, 550.0, 450.0, 500.0)):
        assert spec[lane] == pytest.approx(_sigma_physical_m2(nm) * n_air * path, rel=1e-3), nm


def test_ratio_tracking_at_one_wavelength_is_beer_lambert(variant_restored):
    """Ratio tracking (the trackers' spectral majorants: the air's largest over the 360-830 nm grid) through the
    slab at 420 nm in every lane: exp(-tau) within 3 standard errors and 0.3 %."""
    got, se = _tau_kernel(SPECTRAL, (420.0,) * 4, tracker="ratio")
    expect = _sigma_physical_m2(420.0) * RHO * AVOGADRO / M_AIR * (H_M - 2.0)
    t = math.exp(-expect)
    for lane in range(4):
        assert abs(math.exp(-got[lane]) - t) < max(3 * se[lane], 0.003 * t), (got[lane], expect, se[lane])


def _render(camera, sun, variant=SPECTRAL, **kw):
    from weather_mi.reference.render import render_reference
    from weather_mi.scene.spec import SceneSpec
    spec = SceneSpec(camera=camera, sun=sun, sky=None, ground=None, width=4, height=4, seed=5)
    return render_reference(spec, _clear_slab(), progress=False, variant=variant, **kw)


def test_sun_seen_through_the_box_is_beer_lambert_over_the_spectrum(variant_restored):
    """A camera under the slab looking into the sun's disk: its CIE X, Y, Z over the disk's above the air are the
    ASTM G173 sun x exp(-tau(lambda) / mu0) (tau from Bodhaine's Eq. 2) integrated with the CIE 1931 functions
    here, within 3 se and 1 %; the box's air is tracked (the sun's table is read where its ray leaves the box,
    above the slab's top: the air above the top counted once)."""
    from weather_mi.scene.spec import Camera, Sun
    sun = Sun(azimuth=0.0, elevation=math.degrees(math.asin(MU0)), irradiance=1.0, angular_diameter_deg=0.53)
    d = tuple(float(v) for v in sun.to_sun)
    cam = Camera(origin=(0.0, 0.0, -10.0), target=(d[0], d[1], -10.0 + d[2]), fov=0.05)
    img = _render(cam, sun, spp=1024, passes=4)
    wl = np.arange(360.0, 830.1, 5.0)
    s, cmf = _astm_toa(wl), _cmfs(wl)
    t = np.exp(-np.array([_tau(w) for w in wl]) / MU0)
    r_disk = 1.0 / (math.pi * math.sin(math.radians(0.265)) ** 2)
    expect = (s * t) @ cmf / (s @ cmf[:, 1])
    got = img.xyz.reshape(-1, 3).astype(np.float64).mean(axis=0) / r_disk
    from weather_mi.optics.spectrum import xyz_of_linear_srgb
    se = np.abs(xyz_of_linear_srgb(np.sqrt((img.stderr.reshape(-1, 3).astype(np.float64) ** 2).mean(axis=0)))) / 4 / r_disk
    assert np.all(np.abs(got - expect) < np.maximum(3 * se, 0.01 * expect)), (got, expect, se)
    white = (s @ cmf) / (s @ cmf[:, 1])
    assert expect[2] / white[2] < 0.8 * expect[0] / white[0]  # reddened by the air: the check can fail


def _disort_nadir(tau):
    """DISORT (disortpp): a conservative Rayleigh slab over a black surface, pi I / mu0 upward at nadir at the top
    (Legendre moments 1, 0, (1 - g) / (10 (1 + 2 g)), g = DEPOL / (2 - DEPOL))."""
    from weather_mi.optics.disort import solve
    g = DEPOL / (2 - DEPOL)
    moments = np.zeros(33)
    moments[0], moments[2] = 1.0, (1 - g) / (10 * (1 + 2 * g))
    res = solve([tau], [1.0], MU0, [1.0], [0.0], [0.0], moments=moments[None], n_streams=32)  # up (mu 1) at the top
    return math.pi * res.intensities(0, 0, 0) / MU0


def test_rayleigh_slab_xyz_against_disort(variant_restored):
    """All orders of scattering in the pure molecular slab: the nadir reflectance's CIE X, Y, Z from the spectral
    variant against DISORT (Rayleigh's Legendre moments) solved every 5 nm at Bodhaine's tau(lambda), integrated over
    the ASTM G173 sun and the CIE 1931 functions (luminance 1 for the sun): within 3 se and 2 %."""
    img = _render(_nadir_camera(), _point_sun(), spp=2048, passes=8, normalize="reflectance")
    wl = np.arange(360.0, 830.1, 5.0)
    refl = np.array([_disort_nadir(_tau(w)) for w in wl])
    s, cmf = _astm_toa(wl), _cmfs(wl)
    expect = (s * refl) @ cmf / (s @ cmf[:, 1])
    got = img.xyz.reshape(-1, 3).astype(np.float64).mean(axis=0)
    from weather_mi.optics.spectrum import xyz_of_linear_srgb
    se = np.abs(xyz_of_linear_srgb(np.sqrt((img.stderr.reshape(-1, 3).astype(np.float64) ** 2).mean(axis=0)))) / 4
    assert np.all(np.abs(got - expect) < np.maximum(3 * se, 0.02 * expect)), (got, expect, se)
    assert np.all(np.abs(got - expect) < 0.05 * expect)
    assert expect[2] > 1.5 * expect[1]  # blue: the check can fail


def test_air_in_the_grid_is_refused_in_a_spectral_variant(variant_restored):
    """Stock ``volpath`` would hold the air at 650 / 550 / 450 nm only: a clear error before rendering."""
    from weather_mi.kernel.medium import medium_dict
    from weather_mi.kernel.variant import set_variant
    set_variant(SPECTRAL)
    with pytest.raises(ValueError, match="majorant_volpath"):
        medium_dict(_clear_slab(), air_in_grid=True)


def test_a_flat_species_read_once_gives_the_same_values(variant_restored):
    """``spectral_phase.spectral_value`` reads a species whose tables are the same at every wavelength (the air's
    Rayleigh and Henyey-Greenstein) once for the 4 lanes, from the whole table or from one of its own
    (``mixture_tables``' split, as the plugin loads it): the same floats as reading it per lane."""
    from weather_mi.kernel.variant import set_variant
    set_variant(SPECTRAL)
    import drjit as dr
    import mitsuba as mi
    from weather_mi.kernel.plugins.spectral_phase import flat_species, mixture_tables, pack_spectral, spectral_value
    rng = np.random.default_rng(3)
    values = rng.random((3, 50, 21)).astype(np.float32)
    values[1] = values[1][:, :1]  # species 1 flat in wavelength
    assert flat_species(values) == (1,)
    table = mi.Float(pack_spectral(values).ravel())
    n = 256
    idx, t = mi.UInt32(rng.integers(0, 49, n).astype(np.uint32)), mi.Float(rng.random(n).astype(np.float32))
    wl = mi.Spectrum(*(mi.Float((340.0 + 520.0 * rng.random(n)).astype(np.float32)) for _ in range(4)))
    w = [mi.Float(rng.random(n).astype(np.float32)) for _ in range(3)]
    grid = (350.0, 1.0 / 25.0, 21)
    a = spectral_value(table, grid, 3, w, idx, t, wl, lambda src, i: dr.gather(mi.Vector4f, src, i))
    b = spectral_value(table, grid, 3, w, idx, t, wl, lambda src, i: dr.gather(mi.Vector4f, src, i), flat=(1,))
    np.testing.assert_array_equal(np.array(a), np.array(b))
    props = {"spectral_values": values, "spectral_nm": 350.0 + 25.0 * np.arange(21)}
    out = mixture_tables(props, 3, 50, "test", lambda x: mi.Float(np.asarray(x).ravel()))  # the flat one apart
    assert out["spectral_flat"] == (1,) and out["spectral_codes"] is None
    c = spectral_value(out["spectral_table"], grid, 3, w, idx, t, wl, lambda src, i: dr.gather(mi.Vector4f, src, i),
                       flat=out["spectral_flat"], flat_table=out["spectral_flat_table"])
    np.testing.assert_array_equal(np.array(a), np.array(c))


def test_albedo_with_the_air_at_voxel_centres(variant_restored):
    """A small supercell with the box's air (AOD 0.3), in the spectral variant: at voxel centres (in the cloud and
    in the air alone) the medium's sigma_t and albedo at 4 wavelengths equal, within 1e-4, what is computed here in
    numpy: sigma_t = beta + e(lambda), omega = (omega_h(lambda) beta + s(lambda)) / sigma_t, omega_h = 1 - (1 -
    omega_550) sum_s w_s c_s(lambda) / sum_s w_s c_s(550) from the species' co-albedo table, e and s the air's tables
    (``spectral_air_levels``) at the voxel's level."""
    import mitsuba as mi
    import weather_mi as wm
    from weather_mi.kernel.plugins.medium_setup import scattering_event
    from weather_mi.kernel.scene_dict import integrator_dict, scene_dict
    from weather_mi.kernel.variant import set_variant
    from weather_mi.optics.air import Atmosphere
    from weather_mi.optics.air.inside import scene_air
    from weather_mi.optics.air.spectral_levels import spectral_air_levels
    from weather_mi.optics.spectral import COALBEDO_NM, coalbedo_table
    vol = scene_air(wm.optical_volume(wm.synthetic.supercell(shape=(12, 16, 16)), phase_quality="test"),
                    Atmosphere(aod_550=0.3))
    set_variant(SPECTRAL)
    spec = wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=200, elevation=8, fov=45), sun=wm.Sun(240.0, 30.0),
                        width=4, height=4)
    scene = mi.load_dict(scene_dict(spec, vol, integrator_dict(vol, "majorant", -1, sun=spec.sun)))
    integ = scene.integrator()
    integ._setup(scene, None)
    beta = np.asarray(vol.beta_total, np.float64)
    cloud = np.argwhere(beta > 0.5 * beta.max())[:6]
    clear = np.argwhere(beta == 0.0)[:: max(1, int((beta == 0).sum()) // 6)][:6]
    vox = np.concatenate([cloud, clear])
    shape = np.array(beta.shape)
    (lo, hi) = (np.asarray(v, np.float64) for v in vol.bbox)
    p = lo + (vox[:, ::-1] + 0.5) / shape[::-1] * (hi - lo)                           # x, y, z of the centres
    lanes = (420.0, 505.0, 610.0, 700.0)
    n = len(vox)
    ray = mi.Ray3f(mi.Point3f(p[:, 0].astype(np.float32), p[:, 1].astype(np.float32), (p[:, 2] + 1.0).astype(np.float32)),
                   mi.Vector3f(0.0, 0.0, -1.0))
    ray.wavelengths = mi.Spectrum(*(mi.Float(np.full(n, w, np.float32)) for w in lanes))
    mei, albedo = scattering_event(integ._ms, ray, mi.Float(np.ones(n, np.float32)), mi.Bool(True))
    got_a, got_t = np.array(albedo), np.array(mei.sigma_t)
    species = [vol.species_set[s] for s in vol.species]
    c = coalbedo_table(species)
    c_l = np.stack([np.interp(lanes, COALBEDO_NM, c[s, :-1]) for s in range(len(species))])  # (S, 4)
    tables = spectral_air_levels(vol.air)
    ext, sca = tables.at(lanes)
    for i, (z, y, x) in enumerate(vox):
        w = np.array([np.asarray(vol.weights[s])[z, y, x] for s in range(len(species))], np.float64)
        ref = w @ c[:, -1]
        omega_h = 1 - (1 - float(vol.albedo[z, y, x, 1])) * (w @ c_l / ref if ref > 0 else 1.0)
        sigma_t = beta[z, y, x] + ext[z]
        expect = (omega_h * beta[z, y, x] + sca[:, z].sum(axis=0)) / sigma_t
        np.testing.assert_allclose(got_t[:, i], sigma_t, rtol=1e-5)
        np.testing.assert_allclose(got_a[:, i], expect, rtol=1e-4, atol=1e-7)
    assert np.ptp(got_a[:, len(cloud):], axis=0).max() > 0.01  # the air's albedo differs by wavelength (ozone)


def _cloud_in_air(beta_per_m: float):
    """The clear slab with a grey cloud layer: the (4, 4, 4) grid's level 1 (centre 3.75 km) at ``beta_per_m``, the
    others 0; its trilinear interpolant is a hat in z over 1.25-6.25 km, constant in x and y: a vertical ray through
    the slab crosses 2.5 km x beta of it."""
    from weather_mi.optics.phase.analytic import isotropic
    from weather_mi.optics.volume import OpticalVolume
    beta = np.zeros((4, 4, 4), np.float32)
    beta[1] = beta_per_m
    box = ((-WIDE_M / 2, -WIDE_M / 2, 0.0), (WIDE_M / 2, WIDE_M / 2, H_M))
    vol = OpticalVolume.from_arrays(beta, 1.0, isotropic(), box)
    return replace(vol, air=_clear_slab().air)


CLOUD_BETA = 2e-4  # 1/m: the layer's optical depth 0.5 on a vertical ray
LANES_NM = (420.0, 500.0, 610.0, 700.0)


def _air_and_cloud_tau(slant: float):
    """The expected optical depth per lane of :data:`LANES_NM` (Bodhaine x the number density x the path, plus the
    cloud layer's 2.5 km x beta x the path's secant), written out here."""
    sec = math.hypot(slant, 1.0)
    n_air = RHO * AVOGADRO / M_AIR
    return np.array([(_sigma_physical_m2(nm) * n_air * (H_M - 2.0) + 2500.0 * CLOUD_BETA) * sec for nm in LANES_NM])


def test_exact_transmittance_through_a_cloud_in_the_air_per_lane(variant_restored):
    """Exact transmittance in the spectral variant (the grey grid's texels interpolated, the air's optical depth in
    closed form per segment at the ray's wavelengths) through a grey cloud layer inside the slab's air, four
    different wavelengths in one ray's lanes: -log T = the cloud's 2.5 km x beta + Bodhaine's tau(lambda), per lane."""
    got = _tau_kernel(SPECTRAL, LANES_NM, slant=0.4, slab=_cloud_in_air(CLOUD_BETA))
    expect = _air_and_cloud_tau(0.4)
    np.testing.assert_allclose(got, expect, rtol=1e-3)
    assert expect[0] - expect[3] > 0.05  # the lanes differ: the check can tell them apart


def test_free_flights_through_a_cloud_in_the_air_escape_per_lane(variant_restored):
    """Delta tracking (spectral tracking over the 4 lanes, the grey grid's texels plus the air at the ray's
    wavelengths) through the cloud layer inside the slab's air: the weight of the flights that escape, averaged,
    is exp(-tau(lambda)) per lane (within 3 standard errors and 0.5 %)."""
    import mitsuba as mi
    from weather_mi.kernel.plugins.trackers import delta_tracking
    integ = _integrator(SPECTRAL, _cloud_in_air(CLOUD_BETA))
    ray, t_end = _vertical_rays(SPECTRAL, LANES_NM, 0.4)
    n = 1 << 14
    big, sampler = _repeated_rays(ray, LANES_NM, n, seed=11)
    found, _, w = delta_tracking(integ._tk, big, dr_repeat(t_end, n), sampler, mi.Bool(True), mi.Spectrum(1.0))
    escaped = np.array(w) * ~np.array(found, bool)[None, :]
    mean, se = escaped.mean(axis=1), escaped.std(axis=1) / math.sqrt(escaped.shape[1])
    t = np.exp(-_air_and_cloud_tau(0.4))
    for lane in range(4):
        assert abs(mean[lane] - t[lane]) < max(3 * se[lane], 0.005 * t[lane]), (lane, mean[lane], t[lane], se[lane])
    assert t[3] - t[0] > 10 * se.max()  # the lanes differ by more than the noise
