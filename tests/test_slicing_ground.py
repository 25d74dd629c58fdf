"""The ground under a cloud in the slicer's "multiple" light model: the column's total transmission
(delta-Eddington), checked against DISORT, and the shadow it leaves in an image."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.plane_parallel.slab import disort_slab
from weather_mi.slicing import MODES, SliceRenderer
from weather_mi.slicing.eye import ground_transmission


@pytest.mark.parametrize("mu0", [0.3, 0.5, 0.866])
@pytest.mark.parametrize("tau", [0.5, 2.0, 5.0, 20.0, 60.0])
def test_the_layer_transmission_matches_disort(tau, mu0):
    """Conservative Henyey-Greenstein layer (g = 0.85), black surface: delta-Eddington total transmission
    within 10% of DISORT's (32 streams), within 5% for a sun above 30 degrees."""
    ref = disort_slab(tau, 1.0, 0.85, mu0, n_streams=32, n_moments=256)["T"]
    t = float(ground_transmission(np, tau, mu0, 0.85))
    assert t == pytest.approx(ref, rel=0.10 if mu0 < 0.4 else 0.05)


@pytest.mark.parametrize("tau", [0.5, 5.0, 20.0, 60.0])
def test_skylight_through_the_layer_matches_disort(tau):
    """The ground's skylight under a cloud column ("multiple" model): the delta-Eddington transmission at
    the diffusivity cosine 1/1.66 against the exact transmission of isotropic incident light, 2 int T(mu)
    mu dmu over DISORT's beam transmissions (8-point Gauss-Legendre in mu), within 6%."""
    from weather_mi.slicing.eye import DIFFUSE_MU
    x, w = np.polynomial.legendre.leggauss(8)
    mu, w = 0.5 * (x + 1.0), 0.5 * w
    exact = 2.0 * sum(wi * m * disort_slab(tau, 1.0, 0.85, m, n_streams=32, n_moments=256)["T"] for m, wi in zip(mu, w))
    assert float(ground_transmission(np, tau, DIFFUSE_MU, 0.85)) == pytest.approx(exact, rel=0.06)


def test_a_cloud_layer_shades_the_ground_as_disort_says():
    """A uniform layer (vertical optical depth 20, HG g = 0.85, no absorption) over half a 40 km domain,
    the sun 60 degrees high, no sky: the ground under the layer's middle, seen from below the layer,
    against the sunlit ground far from it, is DISORT's total transmission (within 10%); the
    multiple-scattering octaves alone left it at 0.80 of the sunlit ground against 0.35."""
    nz, ny, nx = 10, 8, 40
    beta = np.zeros((nz, ny, nx), np.float32)
    beta[4:6, :, :20] = 20.0 / 1000.0            # 2 cells of 500 m: tau = 20 in the layer's columns
    bbox = ((0.0, 0.0, 0.0), (40000.0, 8000.0, 5000.0))
    vol = wm.OpticalVolume.from_arrays(beta, 1.0, wm.phase.henyey_greenstein(0.85), bbox)
    sun = wm.Sun(azimuth=0.0, elevation=60.0)    # from the north: the shadow falls due south, along y
    r = SliceRenderer(vol, MODES["per-species/multiple"], slices=128)

    def ground_mean(x):
        cam = wm.Camera.orthographic(center=(x, 4000.0, 500.0), direction=(0.0, 0.0, -1.0), width=1500, height=1500)
        spec = wm.SceneSpec(camera=cam, sun=sun, sky=None, ground=wm.Ground(albedo=0.3), width=16, height=16)
        return r.frame(spec).radiance.mean()
    shadow, sunlit = ground_mean(10000.0), ground_mean(32000.0)
    mu0 = np.sin(np.radians(60.0))
    expected = disort_slab(20.0, 1.0, 0.85, mu0, n_streams=32, n_moments=256)["T"]
    assert shadow / sunlit == pytest.approx(expected, rel=0.10), (shadow / sunlit, expected)
    assert sunlit == pytest.approx(0.3 / np.pi * np.mean(sun.irradiance) * mu0, rel=1e-3)
