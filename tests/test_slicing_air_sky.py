"""The slicer under the air's own sky (``Sky("air")``, issue 38 part 3): its cloud's and ground's skylight is the
1-D atmosphere's diffuse flux at the envmap's reference point (``kernel.air_sky.sky_irradiance``), checked against
DISORT solving ``validation/seen_through_air.py``'s own atmosphere (written out from the published formulas), not
against our renderer; and the frames use it."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.optics.air import Atmosphere


def _spec(elevation: float, volume=None, ground_m: float = 0.0, sky: str = "air", **kw):
    cam = wm.Camera(origin=(0.0, -200e3, 5e3), target=(0.0, 0.0, 5e3), fov=10.0) if volume is None else \
        wm.Camera.orbit(volume, azimuth=180, elevation=10, fov=40)
    return wm.SceneSpec(camera=cam, sun=wm.Sun(azimuth=90.0, elevation=elevation), sky=wm.Sky(sky),
                        ground=wm.Ground(0.15, height=ground_m), width=kw.get("width", 4), height=kw.get("height", 4),
                        atmosphere=Atmosphere())


def _disort_flux_down(mu0: float, wavelengths_nm) -> np.ndarray:
    """The independent atmosphere's diffuse downward flux at sea level per unit irradiance of the sun above the
    air (normal to it), a Lambertian ground of albedo 0.15."""
    from validation.seen_through_air import STREAMS, layer_edges_m, layers
    from weather_mi.optics.disort import solve
    out = []
    for wl in wavelengths_nm:
        tau, ssa, moments = layers(float(wl), layer_edges_m())
        res = solve(tau, ssa, mu0, [-1.0], [float(np.sum(tau))], [0.0], moments=moments, surface_albedo=0.15,
                    n_streams=STREAMS)
        out.append(float(np.asarray(res.flux_down).ravel()[-1]))
    return np.asarray(out)


@pytest.mark.parametrize("elevation", [35.0, 60.0, 90.0])
def test_the_air_skys_irradiance_is_disorts_diffuse_flux(elevation):
    """``sky_irradiance_horizontal`` of ``Sky("air")`` per unit of the sun's colour above the air (the white sun's
    projection, ``skylight.rgb`` of 1) against the independent atmosphere's DISORT diffuse flux at the channels'
    wavelengths (650, 550, 450 nm), a mean over each channel against one wavelength: within 6% (measured 1-4%);
    the value was 0 before (no skylight on the slicer's cloud and ground under the air's sky). Between the
    nodes over the sun's cosine (33 deg: between two) within 1% of the exact table's."""
    from weather_mi.kernel.sky import sky_irradiance_horizontal
    from weather_mi.optics.air.inside import CHANNEL_NM
    from weather_mi.optics.air.skylight import SKY_WAVELENGTHS_NM, rgb, sky_table
    spec = _spec(elevation)
    white = rgb(np.ones(SKY_WAVELENGTHS_NM.size))
    e = sky_irradiance_horizontal(spec) / (np.asarray(spec.sun.irradiance) * white)
    ref = _disort_flux_down(float(spec.sun.mu0), CHANNEL_NM)
    assert np.all(np.abs(e / ref - 1.0) < 0.06), (e, ref, e / ref)
    off = _spec(33.0)
    exact = sky_table(off.atmosphere, float(off.sun.mu0), [0.0], ground_m=0.0, albedo=0.15).diffuse_rgb[0]
    np.testing.assert_allclose(sky_irradiance_horizontal(off), exact * np.asarray(off.sun.irradiance), rtol=0.01)


def test_the_air_skys_irradiance_follows_the_ground_and_the_sun():
    """Over a ground at 1.5 km less sky than at sea level (less air above it: DISORT's flux there, measured
    0.5-0.7x); an error without an atmosphere (the air's sky needs it)."""
    from dataclasses import replace
    from weather_mi.kernel.air_sky import sky_irradiance
    low, high = sky_irradiance(_spec(35.0)), sky_irradiance(_spec(35.0, ground_m=1500.0))
    assert np.all(high < 0.8 * low) and np.all(high > 0.3 * low), (low, high)
    with pytest.raises(ValueError, match="atmosphere"):
        sky_irradiance(replace(_spec(35.0), atmosphere=None))


def test_the_slicers_cloud_takes_the_air_skys_light():
    """A slab of cloud under the air's sky: its pixels are brighter with the sky's gain than without it (sky_gain
    0), by the sky's term alone: before, the air's sky lit nothing (its irradiance was 0 here)."""
    from weather_mi.slicing import SliceMode, SliceParams, SliceRenderer
    from test_slicing import slab
    vol = slab(beta=5e-3, size=(16, 8, 8))
    spec = _spec(35.0, vol, width=16, height=12)
    r = SliceRenderer(vol, SliceMode("per_species", "multiple"), slices=32, light_res=16)
    lit = r.frame(spec, SliceParams()).radiance
    cloud = r.transmittance < 0.5
    dark = r.frame(spec, SliceParams(sky_gain=0.0)).radiance
    assert cloud.sum() > 10 and np.all(lit[cloud] > dark[cloud] * 1.01)


@pytest.mark.parametrize("width", [48, 128])  # every pixel's own air, and the coarse grid's (eye_air_coarse)
def test_the_slicers_sky_under_the_air_is_the_references(width):
    """``Sky("air")`` has no sky model: the slicer's sky is the air along the eye ray to the top (with its
    multiple scattering), as the reference's (``display.aerial.with_eye_air(sky_air=True)``, integrated on its own
    points in numpy): the sky's pixels within 3% of its E S_A per channel (measured 0.3-3%). Through a cloud-free
    box the sky goes on behind it (the air from the box's exit to the top, B): the pixels just inside the box's top
    edge within 10% of those just above it (measured 1-7%; without B they were the box's air alone, ~half)."""
    from weather_mi.display.aerial import eye_air
    from weather_mi.slicing import SliceMode, SliceParams, SliceRenderer
    from test_slicing import slab
    vol = slab(beta=1e-9, size=(16, 8, 8))  # ((-20, -20, 1), (20, 20, 2)) km: clear
    cam = wm.Camera(origin=(0.0, -60e3, 1500.0), target=(0.0, 0.0, 1500.0), fov=40.0)
    spec = wm.SceneSpec(camera=cam, sun=wm.Sun(120, 35), sky=wm.Sky("air"), ground=wm.Ground(0.15, height=0.0),
                        width=width, height=width * 3 // 4, atmosphere=Atmosphere())
    r = SliceRenderer(vol, SliceMode("per_species", "multiple"), slices=32, light_res=16)
    img = r.frame(spec, SliceParams()).radiance
    _, s_a, _, _, hit, _, _ = eye_air(spec, vol, True)
    sky = ~hit[:3]  # the top rows: the sky above the box
    assert sky.all()
    ratio = img[:3][sky].mean(axis=0) / s_a[:3][sky].mean(axis=0)
    assert np.all(np.abs(ratio - 1.0) < 0.03), ratio
    col = width // 2
    top = int(np.flatnonzero(hit[:, col]).min())
    edge = img[top, col] / img[top - 1, col]
    assert np.all(np.abs(edge - 1.0) < 0.10), edge
