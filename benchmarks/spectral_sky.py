"""The cost of the spectral mode's air outside the box (``render --spectral`` with ``--sky air``, issue 38): the
skylight envmap in the spectral render (``kernel.air_sky``) against the same render without it (``--sky none``:
the spectral ``--sky air`` render before), in one process, kernels compiled first, rounds in reversing order with
their own seeds; and the eye rays' air (``display.aerial.eye_air``) per wavelength (``spectral=True``, 13
wavelengths) against the RGB mode's three, its DISORT tables rebuilt each time, alternating.

    .venv/bin/python benchmarks/spectral_sky.py [--size 160x120] [--spp 16] [--rounds 3] [--elevation 4]
"""
from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def main(argv=None):
    from validation.sun_colour import demo_volume
    from weather_mi.display.aerial import eye_air
    from weather_mi.optics.air import skylight
    from weather_mi.optics.air.inside import scene_air
    from weather_mi.reference.render import render_reference
    from weather_mi.scene.framing import scene_spec
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--elevation", type=float, default=4.0)
    args = ap.parse_args(argv)
    size = tuple(int(v) for v in args.size.split("x"))
    vol = demo_volume()
    cases = {}
    for sky in ("none", "air"):
        spec = scene_spec(vol, size, sun_elevation=args.elevation, sun_azimuth=260.0, camera_azimuth=290.0,
                          atmosphere="clear", sky=sky)
        cases[sky] = (spec, scene_air(vol, spec.atmosphere))
    for spec, v in cases.values():  # compile the kernels first
        render_reference(spec, v, spp=2, progress=False, variant="llvm_ad_spectral")
    times, rse = {a: [] for a in cases}, {a: [] for a in cases}
    names = list(cases)
    for r in range(args.rounds):
        for a in (names if r % 2 == 0 else names[::-1]):
            spec, v = cases[a]
            img = render_reference(replace(spec, seed=spec.seed + r), v, spp=args.spp, progress=False,
                                   variant="llvm_ad_spectral")
            times[a].append(img.metadata["seconds"])
            rse[a].append(img.metadata["noise"]["rse_mean"])
        print(f"round {r + 1}: " + "; ".join(f"--sky {a} {times[a][-1]:.2f} s, RSE {rse[a][-1]:.4f}" for a in names),
              flush=True)
    cost = {a: sum(times[a]) * float(np.mean(np.square(rse[a]))) for a in cases}
    print(f"spectral render {args.size}, {args.spp} spp, {args.rounds} rounds, with the envmap / without: time ratio "
          f"(medians) {np.median(times['air']) / np.median(times['none']):.2f}, per round "
          + ", ".join(f"{x / y:.2f}" for x, y in zip(times["air"], times["none"]))
          + f"; time to the same luminance RSE {cost['air'] / cost['none']:.2f}")
    spec, v = cases["air"]
    eye = {False: [], True: []}
    for r in range(args.rounds):
        for spectral in ((False, True) if r % 2 == 0 else (True, False)):
            skylight._diffuse_table.cache_clear()
            skylight._sky_table.cache_clear()
            t0 = time.perf_counter()
            eye_air(spec, v, True, spectral=spectral)
            eye[spectral].append(time.perf_counter() - t0)
    print(f"eye rays' air {args.size}: RGB (3 wavelengths) " + ", ".join(f"{t:.1f}" for t in eye[False])
          + " s; spectral (13) " + ", ".join(f"{t:.1f}" for t in eye[True])
          + f" s; ratio (medians) {np.median(eye[True]) / np.median(eye[False]):.2f}")


if __name__ == "__main__":
    main()
