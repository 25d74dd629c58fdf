"""The slicer's lit-cloud colour against the path tracer's, both with ``--atmosphere clear`` at a 4 deg sun
(issue 38 part 3): a cloud ball (HG g = 0.85, tau ~ 180) seen from 30 km, the cloud pixels' mean linear sRGB
at equal lightness (Y = 0.5), CIEDE2000 (D65) of the slicer with the atmosphere and of the slicer without it
(white sun and sky) against the path tracer (the air along the eye rays on both, ``display.aerial``).

    python validation/slicer_air.py [SIZE [SPP]]     (defaults 32 px, 32 spp; tests/test_slicing_air.py)
"""
from __future__ import annotations

import dataclasses
import sys
import time

import colour
import numpy as np

import weather_mi as wm
from weather_mi.display.aerial import slicer_frame_with_eye_air, with_eye_air
from weather_mi.reference.render import render_reference
from weather_mi.scene.framing import scene_spec
from weather_mi.slicing import MODES, SliceRenderer


def ball():
    z, y, x = np.meshgrid(*(np.linspace(-1, 1, 20),) * 3, indexing="ij")
    beta = np.where(x ** 2 + y ** 2 + z ** 2 < 0.8, 0.02, 0.0).astype(np.float32)
    return wm.OpticalVolume.from_arrays(beta, 1.0, wm.phase.henyey_greenstein(0.85), ((-5e3, -5e3, 1e3), (5e3, 5e3, 11e3)))


def cloud_colour(img, mask):
    """(mean linear sRGB, xy, CIELAB at Y = 0.5) over ``mask``'s pixels."""
    rgb = img.radiance.reshape(-1, 3)[mask.ravel()].mean(axis=0)
    xyz = colour.RGB_to_XYZ(rgb, colour.RGB_COLOURSPACES["sRGB"], apply_cctf_decoding=False)
    xyz = xyz / xyz[1] * 0.5
    return rgb, colour.XYZ_to_xy(xyz), colour.XYZ_to_Lab(xyz, np.array([0.3127, 0.3290]))


def main(size: int = 32, spp: int = 32) -> None:
    vol = ball()
    spec = scene_spec(vol, (size, size), camera="ground", camera_distance_km=30.0, camera_height=2000.0, fov=40.0,
                      sun_elevation=4.0, sun_azimuth=0.0, camera_azimuth=180.0, sky="sunsky", atmosphere="clear")
    t = time.time()
    ref = with_eye_air(render_reference(spec, vol, spp=spp, progress=False), spec, vol)
    t_ref = time.time() - t
    r = SliceRenderer(vol, MODES["per-species/multiple"], 128)
    t = time.time()
    sliced = slicer_frame_with_eye_air(r, r.frame(spec), spec)
    t_slicer = time.time() - t
    white = r.frame(dataclasses.replace(spec, atmosphere=None))
    mask = ref.transmittance < 0.05
    print(f"cloud pixels {int(mask.sum())}, path tracer {t_ref:.1f} s, slicer {t_slicer:.2f} s")
    labs = {}
    for name, img in (("path tracer", ref), ("slicer", sliced), ("slicer, no air", white)):
        rgb, xy, labs[name] = cloud_colour(img, mask)
        print(f"{name:15s} rgb {np.round(rgb, 4)} xy {np.round(xy, 4)} Lab {np.round(labs[name], 2)}")
    for name in ("slicer", "slicer, no air"):
        de = float(colour.delta_E(labs[name], labs["path tracer"], method="CIE 2000"))
        print(f"{name}: CIEDE2000 {de:.2f} from the path tracer")


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:3]))
