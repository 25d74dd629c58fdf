"""The kernel's time with the box's air added per level (``majorant_volpath``: ``air_extinction``, ``air_albedo``,
``hydrometeor_mixture``'s ``air_weights``; render's default) against the air in 3-channel grids (the path before,
``kernel.medium.medium_dict(air_in_grid=True)``), the same scene in one process, kernels compiled first, in paired
rounds (the order alternates; each round its own seed).

    nice -n 5 .venv/bin/python benchmarks/air_per_level.py [--rounds 4] [--spp 128]
"""
from __future__ import annotations

import argparse
import time

import numpy as np


def main(argv=None):
    import mitsuba as mi

    from weather_mi.io import synthetic
    from weather_mi.kernel import scene_dict as sd
    from weather_mi.kernel.medium import medium_dict
    from weather_mi.optics.air import Atmosphere
    from weather_mi.optics.air.inside import with_box_air
    from weather_mi.optics.volume import optical_volume
    from weather_mi.reference.passes import pass_seed, render_pass
    from weather_mi.scene.framing import scene_spec
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=4)
    ap.add_argument("--spp", type=int, default=128)
    a = ap.parse_args(argv)
    mi.set_variant("llvm_ad_rgb")
    hyd = synthetic.supercell(shape=(30, 64, 64), spacing_m=(500.0, 1000.0, 1000.0))
    atm = Atmosphere()
    vol = with_box_air(optical_volume(hyd, "paper"), hyd, atm)
    spec, vol, _ = sd.recentred(scene_spec(vol, (80, 60), camera="orbit"), vol)
    integ = sd.integrator_dict(vol, "majorant", 256, sun=spec.sun, atmosphere=atm)

    def scene(in_grid):
        d = sd.scene_dict(spec, vol, integ)
        if in_grid:
            key = "weather_medium" if "weather_medium" in d else None
            if key:
                d[key] = medium_dict(vol, air_in_grid=True)
            else:
                d["medium_box"]["interior"] = medium_dict(vol, air_in_grid=True)
        return mi.load_dict(d)

    scenes = {"in grids": scene(True), "per level": scene(False)}
    for sc in scenes.values():
        render_pass(sc, 4, 0)  # compiled
    times = {k: [] for k in scenes}
    for r in range(a.rounds):
        for k in (list(scenes) if r % 2 == 0 else list(scenes)[::-1]):
            t0 = time.perf_counter()
            render_pass(scenes[k], a.spp, pass_seed(2, r))
            times[k].append(time.perf_counter() - t0)
    for k, t in times.items():
        print(f"air {k:10s}", " ".join(f"{x:6.2f}" for x in t), "s")
    ratio = [b / c for b, c in zip(times["per level"], times["in grids"])]
    print("per level / in grids, per round:", " ".join(f"{x:.2f}" for x in ratio), f"median {np.median(ratio):.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
