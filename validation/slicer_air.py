"""The slicer's air against the path tracer's, both with ``--atmosphere clear`` at a 4 deg sun (issue 38 part 3):
a cloud ball (HG g = 0.85, tau ~ 180) in a 10 x 10 x 10 km box seen from 30 km.

* The path tracer: the air inside the box in its medium (``optics.air.inside``, molecules from the US 1976
  density on the box's levels, which is the slicer's 1-D atmosphere), the air outside along the eye rays
  (``display.aerial.with_eye_air``).
* The slicer: the sun's colour by height, the sky scaled, the eye rays' air inside the box and out
  (``slicing.eye_air``); and, to show what the test can tell, the slicer without the box's air (the eye-ray
  air outside only, as before) and with a white sun and sky.

Printed: the clear pixels that cross the box (cloud transmittance > 0.99): the path tracer's mean radiance
per channel and the slicer's ratio to it (with the box's air, and with the eye-ray air outside the box only);
the cloud pixels' mean colour at equal lightness (Y = 0.5), CIEDE2000 (D65) against the path tracer's; and the
same two renderers without any atmosphere (the slicer's own error on this view, which the air must not grow).
(``render_reference`` puts the atmosphere's air into the box itself now, ``optics.air.inside.scene_air``: a
path-traced render "without the box's air" under the same atmosphere no longer exists.)

    python validation/slicer_air.py [SIZE [SPP]]     (defaults 32 px, 32 spp; tests/test_slicing_air.py)
"""
from __future__ import annotations

import dataclasses
import sys
import time

import colour
import numpy as np

import weather_mi as wm
from weather_mi.display.aerial import with_eye_air
from weather_mi.reference.render import render_reference
from weather_mi.scene.framing import scene_spec
from weather_mi.slicing import MODES, SliceRenderer


def ball():
    z, y, x = np.meshgrid(*(np.linspace(-1, 1, 20),) * 3, indexing="ij")
    beta = np.where(x ** 2 + y ** 2 + z ** 2 < 0.8, 0.02, 0.0).astype(np.float32)
    return wm.OpticalVolume.from_arrays(beta, 1.0, wm.phase.henyey_greenstein(0.85), ((-5e3, -5e3, 1e3), (5e3, 5e3, 11e3)))


def view(vol, size: int, elevation: float = 4.0, sun_azimuth: float = 0.0):
    return scene_spec(vol, (size, size), camera="ground", camera_distance_km=30.0, camera_height=2000.0, fov=40.0,
                      sun_elevation=elevation, sun_azimuth=sun_azimuth, camera_azimuth=180.0, sky="sunsky",
                      atmosphere="clear")


def lab(rgb):
    """CIELAB (D65) of linear sRGB ``rgb`` at equal lightness (Y = 0.5)."""
    xyz = colour.RGB_to_XYZ(rgb, colour.RGB_COLOURSPACES["sRGB"], apply_cctf_decoding=False)
    return colour.XYZ_to_Lab(xyz / xyz[1] * 0.5, np.array([0.3127, 0.3290]))


def measure(size: int = 32, spp: int = 32, elevation: float = 4.0, sun_azimuth: float = 0.0) -> dict:
    """The comparisons of the module docstring, as a dict (``tests/test_slicing_air.py`` reads it)."""
    vol = ball()
    spec = view(vol, size, elevation, sun_azimuth)
    t = time.time()  # render_reference puts the box's air into its medium (scene_air: the US 1976 density)
    ref = with_eye_air(render_reference(spec, vol, spp=spp, progress=False), spec, vol)
    t_ref = time.time() - t
    r = SliceRenderer(vol, MODES["per-species/multiple"], 128)
    t = time.time()
    sliced = r.frame(spec)
    t_slicer = time.time() - t
    before = SliceRenderer(vol, MODES["per-species/multiple"], 128, eye_air=False)  # the sun's colour by height
    outside = with_eye_air(dataclasses.replace(before.frame(spec), transmittance=before.transmittance), spec, vol)
    no_air = dataclasses.replace(spec, atmosphere=None)
    white = r.frame(no_air)
    ref_no_air = render_reference(no_air, vol, spp=spp, progress=False)
    clear = (ref.transmittance > 0.99) & (ref.radiance.sum(axis=-1) > 0)
    hit = _crosses_box(spec, vol)
    clear &= hit
    mask = ref.transmittance < 0.05
    out = {"cloud_pixels": int(mask.sum()), "clear_box_pixels": int(clear.sum()), "t_ref_s": t_ref,
           "t_slicer_s": t_slicer}
    mean = lambda img, m: img.radiance.reshape(-1, 3)[m.ravel()].mean(axis=0).astype(np.float64)  # noqa: E731
    out["clear_ref"] = mean(ref, clear)
    out["clear_slicer"], out["clear_outside_only"] = mean(sliced, clear), mean(outside, clear)
    truth = lab(mean(ref, mask))
    for name, img in (("slicer", sliced), ("outside_only", outside), ("white", white)):
        out[f"de_{name}"] = float(colour.delta_E(lab(mean(img, mask)), truth, method="CIE 2000"))
    # the same two renderers without any atmosphere: the slicer's own error on this view, which the air must not grow
    out["de_slicer_no_air"] = float(colour.delta_E(lab(mean(white, mask)), lab(mean(ref_no_air, mask)),
                                                   method="CIE 2000"))
    return out


def _crosses_box(spec, vol):
    from weather_mi.slicing.geometry import camera_rays, ray_box
    o, d = (a.reshape(-1, 3).astype(np.float64) for a in camera_rays(spec))
    t_in, t_out = ray_box(o, d, vol.bbox)
    return (t_out - t_in > 2000.0).reshape(spec.height, spec.width)


def main(size: int = 32, spp: int = 32) -> None:
    m = measure(size, spp)
    print(f"cloud pixels {m['cloud_pixels']}, clear pixels across the box {m['clear_box_pixels']}, "
          f"path tracer {m['t_ref_s']:.1f} s, slicer {m['t_slicer_s']:.2f} s")
    print(f"clear pixels, path tracer (R, G, B): {np.round(m['clear_ref'], 5)}")
    for name in ("slicer", "outside_only"):
        print(f"  {name:13s} / path tracer: {np.round(m[f'clear_{name}'] / m['clear_ref'], 3)}")
    for name in ("slicer", "outside_only", "white"):
        print(f"cloud colour, {name}: CIEDE2000 {m['de_' + name]:.2f} from the path tracer")
    print(f"without any atmosphere in either: the slicer's cloud CIEDE2000 {m['de_slicer_no_air']:.2f} from the path tracer's")


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:3]))
