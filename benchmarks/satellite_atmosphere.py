"""The cost of ``satellite --atmosphere clear`` against ``none`` (issue 38 part 5): the demo supercell placed at
35.2 N 97.4 W on 2013-05-20 20:00 UTC, GOES-East, one band (0.64 um) and true colour (``--rgb``), in one
process, kernels compiled first (a small render of each).

    .venv/bin/python benchmarks/satellite_atmosphere.py [--resolution 2] [--spp 64] [--repeats 2]

Prints each case's seconds (render plus the air outside the box, ``satellite.air``) in paired rounds (none and
clear one after the other, the order alternating), the ratio per round and its median, and the cloud pixels' mean
relative standard error of each (so the ratio to the same noise is the time ratio times the RSE ratio squared).
"""
from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def scenes(resolution_km: float, atmosphere):
    import weather_mi as wm
    from weather_mi.satellite import imagery as si, truecolor as tc
    from weather_mi.scene.place import assume_place
    hyd = assume_place(wm.open_source(None, "supercell"), 35.2, -97.4, "2013-05-20T20:00")
    vol = wm.optical_volume(hyd, species="physical")
    band = si.satellite_scene(hyd, vol, "goes-east", "0.64", resolution_km, atmosphere=atmosphere)
    rgb = tc.true_color_scenes(hyd, vol, "goes-east", resolution_km, atmosphere=atmosphere)
    return {"0.64": band, "rgb": rgb}


def run(case, scene, spp):
    from weather_mi.satellite import imagery as si, truecolor as tc
    t0 = time.perf_counter()
    if case == "rgb":
        ds, img = tc.render_true_color(scene, spp=spp, progress=False)
    else:
        ds, img = si.render_satellite(scene, spp=spp, progress=False)
    return time.perf_counter() - t0, float((img.metadata.get("noise") or {}).get("rse_mean", float("nan")))


def main(argv=None):
    from weather_mi.optics.air import Atmosphere
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--resolution", type=float, default=2.0)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore", UserWarning)
    built = {a: scenes(args.resolution, None if a == "none" else Atmosphere()) for a in ("none", "clear")}
    for a in built:  # compile the kernels first
        for case, scene in built[a].items():
            run(case, scene, 4)
    rounds = {(case, a): [] for case in ("0.64", "rgb") for a in ("none", "clear")}
    for r in range(args.repeats):  # paired rounds, the order alternating
        for case in ("0.64", "rgb"):
            for a in (("none", "clear") if r % 2 == 0 else ("clear", "none")):
                rounds[(case, a)].append(run(case, built[a][case], args.spp))
    for case in ("0.64", "rgb"):
        for a in ("none", "clear"):
            times = ", ".join(f"{t:.2f} s" for t, _ in rounds[(case, a)])
            print(f"{case:5s} {a:5s}: {times} (cloud RSE {rounds[(case, a)][0][1]:.3f})")
        ratios = sorted(c[0] / n[0] for n, c in zip(rounds[(case, "none")], rounds[(case, "clear")]))
        rse = (rounds[(case, "clear")][0][1] / rounds[(case, "none")][0][1]) ** 2
        med = ratios[len(ratios) // 2] if len(ratios) % 2 else 0.5 * sum(ratios[len(ratios) // 2 - 1:][:2])
        print(f"{case}: clear / none per round {', '.join(f'{x:.2f}' for x in ratios)}; median {med:.2f}x the time; "
              f"to the same cloud RSE {med * rse:.2f}x")

if __name__ == "__main__":
    main()
