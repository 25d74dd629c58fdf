"""Where the time of ``satellite --atmosphere clear`` goes (issue 38): the benchmark's scenes
(``satellite_atmosphere.py``: the demo supercell, GOES-East, one band 0.64 um and true colour ``--rgb``), each
rendered with ``none`` and ``clear`` in one process, kernels compiled first.

    .venv/bin/python benchmarks/satellite_air_profile.py [--resolution 2] [--spp 64] [--repeats 2] [--count]

Per case: the whole call's seconds, the kernel's (Dr.Jit's kernel history: the launches' execution time), the
integrator's per-render set-up (``majorant_volpath._setup``: the trackers' grids), the scene's build
(``render_reference`` less the passes) and the air outside the box (``satellite.air.with_air_outside``), medians
over ``--repeats`` runs. ``--count`` (one more run each, the kernel slower by its atomics): what the kernel did
per sample, counted by lanes: path events (scatterings in the air alone, in cloud, surfaces), delta-tracking
steps (in the air's empty cells and in cloud cells, real collisions) and exact-transmittance steps (air cubes
and cloud cells).
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
import warnings
from contextlib import contextmanager
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

COUNTERS = ("events", "scatter", "scatter_air", "surface", "dt_steps", "dt_air_steps", "dt_collide", "dt_real",
            "tr_steps", "tr_air_steps", "shadow_rays")


class Timers:
    """Seconds spent in wrapped functions (outermost calls only)."""

    def __init__(self):
        self.t = {}
        self.depth = {}

    def wrap(self, owner, name, key):
        f = getattr(owner, name)

        def wrapped(*a, **k):
            if self.depth.get(key, 0):
                return f(*a, **k)
            self.depth[key] = 1
            t0 = time.perf_counter()
            try:
                return f(*a, **k)
            finally:
                self.t[key] = self.t.get(key, 0.0) + time.perf_counter() - t0
                self.depth[key] = 0
        setattr(owner, name, wrapped)


def install_timers(timers):
    from weather_mi.kernel.plugins import majorant_volpath as mv
    from weather_mi.satellite import air
    from weather_mi.reference import render as rr
    timers.wrap(mv.MajorantVolpath, "_setup", "setup")
    timers.wrap(air, "with_air_outside", "air_outside")
    timers.wrap(rr, "render_reference", "render_reference")


def install_counters():
    """Counters scattered from the traced code (monkeypatched: the kernel records them)."""
    import drjit as dr
    import mitsuba as mi
    from weather_mi.kernel.plugins import path_loop, trackers
    counts = dr.zeros(mi.UInt32, len(COUNTERS))
    box = {"c": counts}

    def inc(name, active):
        dr.scatter_reduce(dr.ReduceOp.Add, box["c"], mi.UInt32(1), mi.UInt32(COUNTERS.index(name)), active)

    tentative = trackers._Walk.tentative
    cell_of = trackers.cell_of

    def counted_tentative(self, sampler, active, t, cells, nexts):
        maj, k, seg_end, tc, collide, s_t = tentative(self, sampler, active, t, cells, nexts)
        inc("dt_steps", active)
        m, _ = cell_of(self.grid, cells, active)
        inc("dt_air_steps", active & (m <= 0.0))
        inc("dt_collide", collide)
        return maj, k, seg_end, tc, collide, s_t
    trackers._Walk.tentative = counted_tentative

    # exact transmittance's steps: its loop body calls cell_of once per step (the walk's tentative too: subtract)

    def counted_cell_of(grid, cells, active):
        maj, idx = cell_of(grid, cells, active)
        inc("tr_steps", active)
        inc("tr_air_steps", active & (maj <= 0.0))
        return maj, idx
    trackers.cell_of = counted_cell_of

    delta = path_loop.delta_tracking

    def counted_delta(tk, ray, t_end, sampler, active, weight, tile_only=None):
        found, t, w = delta(tk, ray, t_end, sampler, active, weight, tile_only)
        inc("dt_real", active & found)
        return found, t, w
    path_loop.delta_tracking = counted_delta

    free_flight = path_loop.PathLoop.free_flight

    def counted_free_flight(self, sampler, p):
        inc("events", p.active)
        v = free_flight(self, sampler, p)
        inc("scatter", v.act_scatter)
        inc("surface", v.active_surface)
        if self.ms.air is not None or getattr(self.tk.track, "air", None) is not None:
            m, _ = cell_of(self.tk.track, list(_cell_at(self.tk, v.mei.p)), v.act_scatter)
            inc("scatter_air", v.act_scatter & (m <= 0.0))
        return v
    path_loop.PathLoop.free_flight = counted_free_flight

    nee = path_loop.PathLoop.nee

    def counted_nee(self, sampler, p, v):
        inc("shadow_rays", v.act_e)
        return nee(self, sampler, p, v)
    path_loop.PathLoop.nee = counted_nee
    return box


def _cell_at(tk, p):
    """The texel cell (x, y, z) of the tracking grid at world point p."""
    import drjit as dr
    import mitsuba as mi
    grid = tk.track
    local = tk.to_local @ p
    for k in range(3):
        q = local[k] * grid.scale[k] + grid.shift
        yield dr.clip(mi.Int32(dr.floor(q)), *grid.span(k))


def kernel_seconds(hist) -> float:
    return sum(float(h.get("execution_time", 0.0)) for h in hist) / 1e3


@contextmanager
def kernel_history():
    import drjit as dr
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history()  # clear
    out = []
    try:
        yield out
    finally:
        out.extend(dr.kernel_history())
        dr.set_flag(dr.JitFlag.KernelHistory, False)


def main(argv=None):
    from weather_mi.optics.air import Atmosphere
    from satellite_atmosphere import run, scenes
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--resolution", type=float, default=2.0)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--count", action="store_true")
    ap.add_argument("--cases", default="0.64,rgb")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore", UserWarning)
    cases = args.cases.split(",")
    built = {a: scenes(args.resolution, None if a == "none" else Atmosphere()) for a in ("none", "clear")}
    timers = Timers()
    install_timers(timers)
    for a in built:
        for case in cases:
            run(case, built[a][case], 4)
    rows = {}
    for r in range(args.repeats):
        for case in cases:
            for a in (("none", "clear") if r % 2 == 0 else ("clear", "none")):
                timers.t.clear()
                with kernel_history() as hist:
                    total, _ = run(case, built[a][case], args.spp)
                k = kernel_seconds(hist)
                rr = timers.t.get("render_reference", 0.0)
                rows.setdefault((case, a), []).append({
                    "total": total, "kernel": k, "setup": timers.t.get("setup", 0.0),
                    "build": rr - k - timers.t.get("setup", 0.0), "air_outside": timers.t.get("air_outside", 0.0),
                    "rest": total - rr - timers.t.get("air_outside", 0.0)})
    print(f"seconds, median of {args.repeats} (spp {args.spp}, resolution {args.resolution} km)")
    print(f"{'case':5s} {'air':5s} " + " ".join(f"{c:>11s}" for c in ("total", "kernel", "setup", "build",
                                                                       "air_outside", "rest")))
    for (case, a), rs in rows.items():
        print(f"{case:5s} {a:5s} " + " ".join(f"{statistics.median(r[c] for r in rs):11.2f}"
                                              for c in ("total", "kernel", "setup", "build", "air_outside", "rest")))
    for case in cases:
        n, c = rows[(case, "none")], rows[(case, "clear")]
        kr = sorted(x["kernel"] / y["kernel"] for x, y in zip(c, n))
        print(f"{case}: kernel clear / none per round {', '.join(f'{x:.2f}' for x in kr)}")
    if args.count:
        import drjit as dr
        box = install_counters()
        for case in cases:
            for a in ("none", "clear"):
                box["c"] = dr.zeros(type(box["c"]), len(COUNTERS))
                dr.eval(box["c"])
                scene = built[a][case]
                run(case, scene, args.spp)
                c = box["c"].numpy().astype(float)
                w, h = scene[0].spec.width if case == "rgb" else scene.spec.width, \
                    scene[0].spec.height if case == "rgb" else scene.spec.height
                samples = w * h * args.spp
                tr_steps = c[COUNTERS.index("tr_steps")] - c[COUNTERS.index("dt_steps")]
                tr_air = c[COUNTERS.index("tr_air_steps")] - c[COUNTERS.index("dt_air_steps")]
                per = {name: c[i] / samples for i, name in enumerate(COUNTERS)}
                per["tr_steps"], per["tr_air_steps"] = tr_steps / samples, tr_air / samples
                print(f"{case:5s} {a:5s} per sample: " + ", ".join(f"{k} {v:.2f}" for k, v in per.items()))


if __name__ == "__main__":
    main()
