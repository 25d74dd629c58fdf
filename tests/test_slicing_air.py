"""The slicer with a clear atmosphere (issue 38 part 3): the sun that reaches a point is the direct sun
after the air above it, C(h, mu0) of ``optics.air.sunlight.sun_rgb`` (evaluated here from the spectrum,
not through the slicer's table), on the lit ground and on a thin cloud layer; without the atmosphere the
frame is as before."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.optics.air import Atmosphere
from weather_mi.optics.air.sunlight import sun_rgb
from weather_mi.slicing import MODES, SliceRenderer

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
    r = SliceRenderer(vol, MODES["per-species/multiple"], slices=64)
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
    r = SliceRenderer(vol, MODES["per-species/multiple"], slices=64)
    atm = Atmosphere()
    plain = r.frame(_spec(None, None)).radiance.reshape(-1, 3).mean(axis=0)
    aired = r.frame(_spec(None, atm)).radiance.reshape(-1, 3).mean(axis=0)
    assert np.all(plain > 0)
    c = sun_rgb(atm, z + 125.0, np.sin(np.radians(ELEV)))
    np.testing.assert_allclose(aired / plain, c, rtol=1e-2)

