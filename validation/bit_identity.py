"""Bit-identity of the two renderers across a refactor: render a fixed set of reference passes and slicer
frames and a satellite view, save them (``--save DIR``) and compare a later checkout's images with them (``--check DIR``).

    .venv/bin/python validation/bit_identity.py --save /tmp/bits-before     # on the old commit
    .venv/bin/python validation/bit_identity.py --check /tmp/bits-before    # on the new one

Every case is rendered in this process from the built-in demo storms (the clear atmosphere in a reference, a slicer
frame and a satellite true-colour view); ``--check`` prints one row per
case (identical, or the largest absolute difference) and exits 1 when any image differs by a bit. This
is a regression check of code moves (the same estimator must give the same floats), not a validation.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

W, H = 48, 36


def _storms():
    import weather_mi as wm
    return {"supercell": wm.optical_volume(wm.synthetic.supercell()),
            "cumulus": wm.optical_volume(wm.synthetic.cumulus())}


def _views(wm, vol):
    sun = wm.Sun(azimuth=240, elevation=35)
    return {"orbit": wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=200, elevation=8, fov=45), sun=sun,
                                  width=W, height=H),
            "ground": wm.SceneSpec(camera=wm.Camera.ground_view(vol, azimuth=200), sun=sun, sky=wm.Sky("sunsky"),
                                   width=W, height=H)}


def reference_cases(wm, storms):
    """(name, thunk) of reference renders covering the estimator's options."""
    sc = storms["supercell"]
    views = _views(wm, sc)
    cu_view = _views(wm, storms["cumulus"])["orbit"]
    quiet = dict(progress=False)
    point = wm.SceneSpec(camera=views["orbit"].camera, sun=wm.Sun(azimuth=240, elevation=35, angular_diameter_deg=0.0),
                         width=W, height=H)
    return [
        ("ref/orbit/default", lambda: wm.render_reference(views["orbit"], sc, spp=8, **quiet)),
        ("ref/ground/default", lambda: wm.render_reference(views["ground"], sc, spp=8, **quiet)),
        ("ref/cumulus/default", lambda: wm.render_reference(cu_view, storms["cumulus"], spp=8, **quiet)),
        ("ref/orbit/aureole", lambda: wm.render_reference(views["orbit"], sc, spp=4, aureole_nee=0.3, **quiet)),
        ("ref/orbit/guiding", lambda: wm.render_reference(views["orbit"], sc, spp=4, sun_guiding=0.1, **quiet)),
        ("ref/orbit/legacy", lambda: wm.render_reference(point, sc, spp=4, legacy=True, **quiet)),
        ("ref/orbit/point-sun", lambda: wm.render_reference(point, sc, spp=4, **quiet)),
        ("ref/orbit/reflectance-depth3", lambda: wm.render_reference(views["orbit"], sc, spp=4, max_depth=3,
                                                                      normalize="reflectance", **quiet)),
        ("ref/orbit/target", lambda: wm.render_reference(views["orbit"], sc, spp=4, passes=2, target_rse=0.5,
                                                         max_seconds=60, **quiet)),
        ("ref/orbit/volpath", lambda: wm.render_reference(point, sc, spp=4, integrator="volpath", **quiet)),
        # the clear atmosphere (the box's air per level and channel, the sun's colour by height), a low sun
        ("ref/ground/air", lambda: wm.render_reference(_with_air(wm, views["ground"]), sc, spp=4, **quiet)),
    ]


def _with_air(wm, spec):
    """``spec`` with the default clear atmosphere, the sun at 6 deg, the air's own sky (no sky emitter)."""
    from dataclasses import replace
    return replace(spec, atmosphere=wm.Atmosphere(), sun=wm.Sun(azimuth=240, elevation=6), sky=None)


def slicer_cases(wm, storms):
    sc = storms["supercell"]
    views = _views(wm, sc)
    cases = []
    detail = wm.detail.field(sc.beta_total.shape, amplitude=0.5)
    for name, mode in wm.slicing.MODES.items():
        kw = {"detail_field": detail} if mode.detail else {}
        cases.append((f"slices/orbit/{name}",
                      lambda mode=mode, kw=kw: wm.render_slices(views["orbit"], sc, mode, slices=64, **kw)))
    cases.append(("slices/ground/per-species/multiple",
                  lambda: wm.render_slices(views["ground"], sc, wm.slicing.MODES["per-species/multiple"], slices=64)))
    cases.append(("slices/ground/per-species/multiple/air",
                  lambda: wm.render_slices(_with_air(wm, views["ground"]), sc, wm.slicing.MODES["per-species/multiple"],
                                           slices=64)))
    return cases


def satellite_cases(wm):
    """The satellite view (rays from a table, reflectance, Rayleigh) of the demo cumulus placed over the sea."""
    from weather_mi.scene.place import assume_place
    from weather_mi.satellite.imagery import render_satellite, satellite_scene
    hyd = assume_place(wm.synthetic.cumulus(), lat=20.0, lon=-60.0, date="2024-07-01T15:00:00Z")
    vol = wm.optical_volume(hyd)
    scene = satellite_scene(hyd, vol, "goes-east", "0.64", resolution_km=2.0, rayleigh=True)
    rgb = satellite_scene(hyd, wm.optical_volume(hyd), "goes-east", "0.64", resolution_km=2.0, rgb=True,
                          atmosphere=wm.Atmosphere())
    return [("satellite/goes-east/0.64", lambda: render_satellite(scene, spp=4, progress=False)[1]),
            ("satellite/goes-east/rgb-air", lambda: render_satellite(rgb, spp=4, progress=False)[1])]


def render_all() -> dict[str, np.ndarray]:
    import weather_mi as wm
    storms = _storms()
    out = {}
    for name, thunk in reference_cases(wm, storms) + slicer_cases(wm, storms) + satellite_cases(wm):
        t0 = time.perf_counter()
        img = thunk()
        out[name + "/radiance"] = np.asarray(img.radiance)
        if getattr(img, "stderr", None) is not None:
            out[name + "/stderr"] = np.asarray(img.stderr)
        print(f"  {name:45s} {time.perf_counter() - t0:6.1f} s", flush=True)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--save", type=Path, help="directory to write the images to")
    g.add_argument("--check", type=Path, help="directory of images saved by --save to compare with")
    a = ap.parse_args(argv)
    images = render_all()
    if a.save:
        a.save.mkdir(parents=True, exist_ok=True)
        np.savez(a.save / "images.npz", **images)
        print(f"saved {len(images)} arrays to {a.save / 'images.npz'}")
        return 0
    before = dict(np.load(a.check / "images.npz"))
    bad = 0
    print(f"{'case':55s} result")
    for name in sorted(set(before) | set(images)):
        if name not in images or name not in before:
            print(f"{name:55s} missing {'now' if name not in images else 'before'}")
            bad += 1
            continue
        x, y = before[name], images[name]
        same = x.shape == y.shape and np.array_equal(x.view(np.uint32), y.view(np.uint32))
        if not same:
            bad += 1
        diff = "" if same or x.shape != y.shape else f" max |diff| {np.nanmax(np.abs(x - y)):.3g}"
        print(f"{name:55s} {'bit-identical' if same else 'DIFFERS' + diff}")
    print(f"{len(images) - bad} of {len(set(before) | set(images))} arrays bit-identical")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
