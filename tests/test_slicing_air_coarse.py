"""The slicer's eye-ray air on a coarse grid of rays (``slicing.eye_air_coarse``, issue 38 part 3) against every
pixel's own integration (``slicing.eye_air.seen_through_air``, itself checked against numpy's segments and the
path tracer in tests/test_slicing_air.py), and frames that compile nothing new as the camera and the sun move."""
from __future__ import annotations

import numpy as np
import pytest

import weather_mi as wm
from weather_mi.optics.air import Atmosphere
from weather_mi.slicing import MODES, SliceRenderer
from conftest import kernels_compiled


@pytest.fixture(scope="module")
def supercell():
    return wm.optical_volume(wm.synthetic.supercell(), species="physical")


def _spec(vol, i, size=160, atmosphere=None):
    """Frame i of a drag (benchmarks/slicing.py's): the camera and the sun swing a few degrees a frame."""
    import math
    base = wm.scene.spec.default_spec(vol, size, size, camera_azimuth=200.0 + 8.0 * math.sin(0.31 * i),
                                      camera_elevation=8.0 + 3.0 * math.sin(0.23 * i + 1.0))
    return wm.SceneSpec(camera=base.camera, sun=wm.Sun(240.0 + 8.0 * math.sin(0.27 * i + 2.0), 35.0),
                        sky=base.sky, ground=base.ground, width=size, height=size, atmosphere=atmosphere)


def test_the_coarse_air_is_every_pixels_own(supercell, monkeypatch):
    """The demo supercell at 160 x 160 with the clear atmosphere: the frame with the air read from every 4th
    pixel's ray against the frame with every pixel's own air. The mean per channel within 0.1% (measured
    0.07% with the air's multiple scattering, ``air_multiple``; 0.02% before), 99% of pixels within 6% (measured
    4.8% here; 4.5% before), the worst within 12% (10.4%, the rows below the horizon; 21% at the box's side walls
    with the brighter box air until the whole box's air was scaled to each pixel's own chord, ``own_chord``). Without the air the frame differs from it by far more (the test can tell)."""
    import weather_mi.slicing.eye_air_coarse as coarse
    spec = _spec(supercell, 3, atmosphere=Atmosphere())
    assert coarse.applies(type("A", (), {"width": spec.width, "height": spec.height})(), spec.width * spec.height)
    grid = SliceRenderer(supercell, MODES["per-species/multiple"], slices=64).frame(spec).radiance
    monkeypatch.setattr(coarse, "MIN_PIXELS", 10 ** 6)  # every pixel's own air
    own = SliceRenderer(supercell, MODES["per-species/multiple"], slices=64).frame(spec).radiance
    grid, own = (a.reshape(-1, 3).astype(np.float64) for a in (grid, own))
    np.testing.assert_allclose(grid.mean(axis=0), own.mean(axis=0), rtol=1e-3)
    rel = np.abs(grid - own).sum(axis=1) / np.maximum(own.sum(axis=1), 1e-12)
    assert np.percentile(rel, 99) < 0.06 and rel.max() < 0.12, (np.percentile(rel, 99), rel.max())
    bare = SliceRenderer(supercell, MODES["per-species/multiple"], slices=64).frame(
        _spec(supercell, 3)).radiance.reshape(-1, 3).astype(np.float64)
    assert np.percentile(np.abs(bare - own).sum(axis=1) / own.sum(axis=1), 99) > 0.1


def test_the_coarse_air_recompiles_nothing_when_the_sun_and_camera_move(supercell):
    """At the grid's size too, frames of a drag (the camera and the sun moving) after the first compile no kernel."""
    r = SliceRenderer(supercell, MODES["uniform/translucent"], slices=32, light_res=32)
    for i in range(2):
        r.frame(_spec(supercell, i, 128, Atmosphere()))
    with kernels_compiled() as compiled:
        for i in range(2, 5):
            r.frame(_spec(supercell, i, 128, Atmosphere()))
    assert compiled == [], f"{len(compiled)} kernels compiled after the first frames"
