"""The slicer with a clear atmosphere (issue 38 part 3): the sun that reaches a point is the direct sun
after the air above it, C(h, mu0) of ``optics.air.sunlight.sun_rgb`` (evaluated here from the spectrum,
not through the slicer's table), on the lit ground and on a thin cloud layer; and the lit cloud's colour
against the path tracer's at a low sun."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.optics.air import Atmosphere
from weather_mi.optics.air.sunlight import sun_rgb
from weather_mi.slicing import MODES, SliceRenderer
from conftest import kernels_compiled

from validation.slicer_air import ball

ELEV = 4.0


def _layer_volume(z0_m: float, z1_m: float):
    nz, ny, nx = 40, 8, 8
    beta = np.zeros((nz, ny, nx), np.float32)
    dz = 10000.0 / nz
    beta[int(z0_m / dz):int(z1_m / dz)] = 1e-4   # optically thin (tau << 1 along any ray here)
    bbox = ((0.0, 0.0, 0.0), (8000.0, 8000.0, 10000.0))
    return wm.OpticalVolume.from_arrays(beta, 1.0, wm.phase.henyey_greenstein(0.85), bbox)


def _spec(ground, atmosphere, z_cam=9000.0):
    cam = wm.Camera.orthographic(center=(4000.0, 4000.0, z_cam), direction=(0.0, 0.0, -1.0), width=2000, height=2000)
    return wm.SceneSpec(camera=cam, sun=wm.Sun(azimuth=0.0, elevation=ELEV), sky=None, ground=ground,
                        width=8, height=8, atmosphere=atmosphere)


def test_the_sunlit_ground_gets_the_sun_after_the_air():
    """Clear ground (albedo 0.3) at sea level, no sky, sun 4 deg high: rho / pi E mu0 C(0, mu0) per
    channel, C from the spectrum (within 0.5%: the slicer's table is linear over 129 heights); without the
    atmosphere rho / pi E mu0 as before."""
    vol = _layer_volume(0.0, 0.0)
    r = SliceRenderer(vol, MODES["per-species/multiple"], slices=64, eye_air=False)  # the sun's path's air alone
    atm = Atmosphere()
    mu0 = np.sin(np.radians(ELEV))
    plain = r.frame(_spec(wm.Ground(albedo=0.3), None)).radiance.reshape(-1, 3).mean(axis=0)
    aired = r.frame(_spec(wm.Ground(albedo=0.3), atm)).radiance.reshape(-1, 3).mean(axis=0)
    e = np.asarray(wm.Sun(azimuth=0.0, elevation=ELEV).irradiance)
    np.testing.assert_allclose(plain, 0.3 / np.pi * e * mu0, rtol=1e-3)
    c = sun_rgb(atm, 0.0, mu0)
    np.testing.assert_allclose(aired, 0.3 / np.pi * e * mu0 * c, rtol=5e-3)
    assert c[0] > 2 * c[2]  # a red sun at 4 deg: the test can tell


@pytest.mark.parametrize("z", [1000.0, 6000.0])
def test_a_thin_layer_is_lit_by_the_sun_at_its_height(z):
    """A thin layer (250 m, tau ~ 0.03) at height z, no ground, no sky: all its light is the sun's, so the
    frame with the atmosphere over the one without is C(z, mu0) per channel (within 1%: the layer's
    250 m of height)."""
    vol = _layer_volume(z, z + 250.0)
    r = SliceRenderer(vol, MODES["per-species/multiple"], slices=64, eye_air=False)  # the sun's path's air alone
    atm = Atmosphere()
    plain = r.frame(_spec(None, None)).radiance.reshape(-1, 3).mean(axis=0)
    aired = r.frame(_spec(None, atm)).radiance.reshape(-1, 3).mean(axis=0)
    assert np.all(plain > 0)
    c = sun_rgb(atm, z + 125.0, np.sin(np.radians(ELEV)))
    np.testing.assert_allclose(aired / plain, c, rtol=1e-2)


def test_the_air_adds_no_error_to_the_slicers_cloud_and_the_box_air_is_there_at_a_low_sun():
    """A cloud ball seen from 30 km, sun 4 deg high behind it, --atmosphere clear in both
    (``validation/slicer_air.py``): the path tracer with the air inside its box (US 1976 molecules on the box's
    levels, ozone, aerosol) and along the eye rays outside it with the storm's shadow (``display.aerial``); the
    slicer with the sun coloured at each point's height, the sky scaled, and the eye rays' air inside the box and
    out with the storm's shadow from its light volume (``slicing.eye_air``).
    The cloud's colour at equal lightness: the slicer's error with the air is its error on the same view without
    any atmosphere in either renderer (the "multiple" model lets the low sun through the back-lit tau ~ 180 ball),
    or less: with the defaults refitted with the lit face's incidence and low-sun training views with the air
    (issue 38) the air adds none here: 3.47 with it against 6.72 without at 32 spp. With issue 41's defaults
    (trained without air, at high suns, before the path tracer's air fixes) it added 1.0-1.2 (with air /
    without: 7.31 / 6.28 at 32 spp, 7.75 / 6.60 at 256 spp), and the bound was 1.5; with the ones before
    them it added none at this size (6.53 / 7.20 at 256 spp). At 48 px both add more (10.4 / 5.3 and
    9.2 / 5.6): the slicer's low-sun light with the air needs its own calibration (issue 38). A white sun and sky
    (the slicer before the atmosphere) measured 14.9-15.6 from the truth: the test can tell.
    The clear pixels that cross the box, in the ball's shadow (sky behind: its air's light and the sky dimmed):
    the slicer over the path tracer (0.946, 0.934, 0.855) at 32 spp, within 8% in R and G and 16% in B (the
    slicer's air scatters the sun and sky once; the path tracer's also scatters its own light, which in the shadow
    is most of what the blue holds; (0.98, 0.95, 0.84) before the path tracer's Eq. 8 took the air's share per
    channel, which moved its red and green here by 2-4%); without the box's air (0.82, 0.81, 0.73): the box's air
    adds over 5%."""
    from validation.slicer_air import measure
    m = measure(32, 32)
    assert m["cloud_pixels"] > 50 and m["clear_box_pixels"] > 30
    assert m["de_slicer"] < m["de_slicer_no_air"], m
    assert m["de_white"] > m["de_slicer"] + 6.0, m
    ratio = m["clear_slicer"] / m["clear_ref"]
    assert np.all(np.abs(ratio - [1.0, 1.0, 0.95]) < [0.08, 0.08, 0.16]), ratio
    without = m["clear_outside_only"] / m["clear_ref"]
    assert np.all(ratio - without > 0.05), (ratio, without)  # the box's air is there (and the test can tell)


def _clear_box():
    beta = np.zeros((20, 20, 20), np.float32)  # no cloud: the box holds air alone
    return wm.OpticalVolume.from_arrays(beta, 1.0, wm.phase.henyey_greenstein(0.85), ((-5e3, -5e3, 1e3), (5e3, 5e3, 11e3)))


@pytest.mark.parametrize("elevation", [20.0, 4.0])
def test_a_clear_box_shows_its_air(elevation):
    """A cloud-free 10 km box seen from 30 km through its middle (6 km up), no sky, no ground: every pixel is
    the light the box's air scatters once towards the eye. The slicer (``slicing.eye_air``, Dr.Jit) against
    ``optics.air.eye_path.segment_air`` (numpy, 257 points, checked against scipy's Runge-Kutta in
    tests/test_eye_air.py) on the same segments, within 1% per channel (measured 0.1%); against the path
    tracer with the box's air in its medium (molecules from the US 1976 density on the box's levels, multiple
    scattering included: 5-9% above single scattering at 20 and 4 deg, 2-3% standard error at 64 spp), within
    12% and 3 standard errors."""
    from weather_mi.optics.air.eye_path import segment_air, wide_sun_table
    from weather_mi.reference.render import render_reference
    from weather_mi.slicing.geometry import camera_rays, ray_box
    vol, atm = _clear_box(), Atmosphere()
    spec = wm.SceneSpec(camera=wm.Camera(origin=(0.0, -30e3, 6e3), target=(0.0, 0.0, 6e3), fov=12.0),
                        sun=wm.Sun(azimuth=60.0, elevation=elevation), sky=None, ground=None, width=12, height=12,
                        atmosphere=atm)
    sliced = SliceRenderer(vol, MODES["per-species/multiple"], slices=32).frame(spec).radiance.reshape(-1, 3)
    o, d = (a.reshape(-1, 3).astype(np.float64) for a in camera_rays(spec))
    t_in, t_out = ray_box(o, d, vol.bbox)
    assert np.all(t_out > t_in)
    _, s = segment_air(atm, spec.sun.to_sun, o, d, t_in, t_out, wide_sun_table(atm, spec.sun.mu0))
    np.testing.assert_allclose(sliced.mean(axis=0), (s * np.asarray(spec.sun.irradiance)).mean(axis=0), rtol=0.01)
    ref = render_reference(spec, vol, spp=64, progress=False)  # the box's air from the US 1976 density (scene_air)
    mean = ref.radiance.reshape(-1, 3).mean(axis=0)
    se = np.sqrt((ref.stderr.reshape(-1, 3) ** 2).sum(axis=0)) / (spec.width * spec.height)
    assert np.all(np.abs(sliced.mean(axis=0) - mean) < 0.12 * mean + 3 * se), (sliced.mean(axis=0), mean, se)
    assert np.all(sliced.mean(axis=0) > 0.5 * mean)


def test_the_air_recompiles_nothing_when_the_sun_and_camera_move():
    """With an atmosphere, frames after the first compile no kernel: the sun (azimuth and elevation), the
    camera and the aerosol are inputs of the frame."""
    vol = ball()
    r = SliceRenderer(vol, MODES["per-species/multiple"], slices=24, light_res=16)

    def spec(i):
        return wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=180 + 7 * i, elevation=10), sun=wm.Sun(200 + 10 * i, 5 + 2 * i),
                            sky=wm.Sky("sunsky"), ground=wm.Ground(0.2), width=24, height=16,
                            atmosphere=Atmosphere(aod_550=0.1 + 0.05 * i))
    for i in range(4):  # warm-up, moves included
        r.frame(spec(i))
    with kernels_compiled() as compiled:
        for i in range(4, 10):
            r.frame(spec(i))
    # the sun's and the air's tables are new numpy data every frame: held in 64-byte aligned memory
    # (``jitarrays.aligned_float``), or a kernel's IR records the alignment malloc happened to give (CI compiled
    # 2 kernels here when the tests before it had left the heap differently)
    assert compiled == [], f"{len(compiled)} kernels compiled in 6 frames after the first"


@pytest.mark.parametrize("mode", ["per-species/multiple", "per-species/translucent"])
def test_the_storms_shadow_darkens_the_slicers_air_as_the_numpy_segments(mode, monkeypatch):
    """The view of ``validation/slicer_air.py`` (the cloud ball, the sun 4 deg up at azimuth 0, the camera 30 km
    south of it, 2 km up): its eye rays lie in the ball's long shadow. A black ground, no sky model: the pixels
    whose rays miss the box and end on the ground show the air's single scattering E S_A alone. The slicer's
    (``slicing.eye_air``, its shadow the sun's light volume) against ``optics.air.eye_path.segment_air``
    (numpy, 257 points) with the shadow map of the hydrometeors' chords (``optics.air.storm_shadow``) on the
    same segments: within 6% per channel (measured 0.5-2.8%, the slicer darker, with the outside segment on 12
    Gauss-Legendre nodes; 2.4-4.4% lighter on 33 trapezoids: the light volume's penumbra at the ball's rim). Without the shadow the air is 1.5-2.3x brighter here, and so is the slicer's with
    its shadow switched off (the test can tell)."""
    import dataclasses

    import weather_mi.slicing.renderer as renderer_module
    from validation.slicer_air import view
    from weather_mi.display.aerial import eye_air
    vol = ball()
    spec = dataclasses.replace(view(vol, 32), sky=None, ground=wm.Ground(0.0))
    sliced = SliceRenderer(vol, MODES[mode], slices=128).frame(spec).radiance.reshape(-1, 3).astype(np.float64)
    _, s_a, _, sky_end, hit, *_ = eye_air(spec, vol, False)
    ground = (~hit & ~sky_end).ravel()
    assert ground.sum() > 40
    numpy_air = s_a.reshape(-1, 3)[ground].mean(axis=0)
    print(mode, "slicer / numpy:", sliced[ground].mean(axis=0) / numpy_air)
    np.testing.assert_allclose(sliced[ground].mean(axis=0), numpy_air, rtol=0.06)
    shadowed = renderer_module.eye_air_input

    def unshadowed(*args, **kwargs):  # the same frame without the storm's shadow on the air
        return shadowed(*args[:4], shadow=False)
    monkeypatch.setattr(renderer_module, "eye_air_input", unshadowed)
    bright = SliceRenderer(vol, MODES[mode], slices=128).frame(spec).radiance.reshape(-1, 3)[ground].mean(axis=0)
    print(mode, "unshadowed slicer / numpy:", bright / numpy_air)
    assert np.all(bright > 1.5 * numpy_air), (bright, numpy_air)
