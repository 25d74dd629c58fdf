"""Cost of the ``hydrometeor_mixture`` phase function against Mitsuba's built-in ``hg`` and ``tabphase``.

    .venv/bin/python benchmarks/phase_plugin.py [--size 128] [--spp 16] [--rounds 3] [--renders 3]
                                                [--max-depth 64] [--tab-size 2048] [--variant llvm_ad_rgb]
                                                [--cases 0 1 2 3 4]

One scene, four phase functions (only the phase differs): a cube [-1, 1]^3 of ``heterogeneous``
medium (a 32^3 ``gridvolume`` sigma_t, a lumpy blob up to 20 per unit length: optical depth ~15-18
through the centre, albedo 0.98) lit by a directional sun, seen by a perspective camera, ``volpath``
with ``max_depth`` 64 (multiple scattering, next-event estimation: every scattering event costs one
phase ``sample`` and one ``eval_pdf``), box pixel filter, black background.

  (a) hg        built-in Henyey-Greenstein, g = 0.85
  (b) tabphase  built-in table of the same HG, ``--tab-size`` values uniform in cos(theta)
  (c) plugin-1  ``hydrometeor_mixture`` with one species: ``weather_mi.optics.phase.henyey_greenstein(0.85)``
                (the default angle grid), weights grid 16^3 x 1
  (d) plugin-5  five species, each holding that same HG 0.85 table, with spatially varying weights on
                a 16^3 x 5 grid, every weight >= ~1e-3 everywhere (the worst case: no species is
                ever absent). The plugin does all the work of five species (weights lookup, five
                tables mixed, a species drawn), but the light transport is that of (a)-(c), so
                the timing compares the phase functions and nothing else. This is the target row.
  (e) physical-5  the same weights with the "physical" preset's per-species tables (Mie cloud, ice
                columns, Mie rain 0.7 mm, snow, graupel): a realistic node set and memory footprint,
                but other light transport (other paths, other null-collision counts), so its cost
                is not the phase function's alone.

"events/path" is the mean number of phase-function samples (scattering events) per camera path,
counted in a separate untimed render by a subclass of the plugin with an atomic counter (so only
for the plugin cases; (a) and (b) have the transport of (c)). Russian roulette from depth 5 keeps
it near 1.2. For (e) the CPU time per scattering event relative to tabphase is printed as well.

Protocol. Every case runs in its own worker process (``--worker``), one scene per process: Mitsuba
dispatches phase-function calls over every live phase-function instance of the variant, so with
several scenes in one process the kernel holds several phase functions behind an indirect call
(measured: with all four scenes loaded every case ran the same 4638-operation kernel, which made
plugin-5 look like 1.1x tabphase instead of ~1.5x). A worker renders once to compile ("1st
render", compilation or Dr.Jit's disk cache included), then ``--renders`` timed renders with new
seeds; the cases run round-robin for ``--rounds`` rounds, so drift of a shared machine hits all
alike. The table gives medians over all timed renders of the wall time and of the CPU time of the
worker (all Dr.Jit threads), samples (camera paths) per CPU-second, the CPU-time ratios to hg and
to tabphase (> 1 is slower) and the wall-time ratio to tabphase. On a machine shared with other
jobs both follow their load: on the 2-core development VM the same code gave plugin-5 ratios from
1.09x to 1.37x in back-to-back runs while hg's CPU time itself moved from 1.7 s to 2.6 s. The
target line therefore also prints the ratio of each round (its two workers ran seconds apart at
most); use more ``--rounds`` and compare within one run. The operation count of each case's render kernel is printed
(it used to differ from run to run: numpy memory mapped by Dr.Jit is not always aligned to the
vector width, and then Dr.Jit splits packet loads; the plugin now copies its tables). The
image-mean radiance (mean +- standard error over the timed renders) is a sanity check: (a) to (d)
render the same phase function and must agree within noise; (e) has other phase functions.

Target (issue): plugin-5 costs at most 1.25x tabphase.

A second table (``--calls``, on by default) times the phase functions alone, outside any render:
one ``eval_pdf`` and one ``sample`` on 2^18 lanes of random positions in the box and random
directions (in aligned memory), on one Dr.Jit thread, in nanoseconds per lane (median of 15 after a warm-up), for
(b), (c), (d) and (e). A render dilutes these costs with ray tracing and null collisions.
"""
from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

import weather_mi as wm  # noqa: E402


def sigma_t_grid(n=32, peak=20.0, seed=3):
    """(n, n, n) extinction per unit length: a smooth blob with some lumpy structure, 0 at the edges."""
    rng = np.random.default_rng(seed)
    c = (np.arange(n) + 0.5) / n * 2 - 1
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    r2 = x ** 2 + y ** 2 + (1.3 * z) ** 2
    k2 = sum(np.meshgrid(np.fft.fftfreq(n) ** 2, np.fft.fftfreq(n) ** 2, np.fft.rfftfreq(n) ** 2, indexing="ij"))
    noise = np.fft.irfftn(np.fft.rfftn(rng.standard_normal((n, n, n))) * np.exp(-400 * k2), (n, n, n), axes=(0, 1, 2))
    noise /= noise.std()
    s = np.exp(-1.5 * r2) * np.exp(0.25 * noise) * (r2 < 1)
    return (peak * s / s.max()).astype(np.float32)


def weights_grid(n_species, n=16):
    """(n, n, n, S) mixture weights varying in space (rows sum to 1): for 5 species cloud in the
    middle, ice at the top, rain low and central, snow and graupel in the upper and lower halves."""
    c = (np.arange(n) + 0.5) / n
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    if n_species == 1:
        return np.ones((n, n, n, 1), np.float32)
    fields = [np.exp(-((z - 0.5) / 0.25) ** 2),                       # cloud
              np.clip(z - 0.4, 0, None) * 2,                           # ice
              np.clip(0.6 - z, 0, None) * np.exp(-((x - 0.5) ** 2 + (y - 0.5) ** 2) / 0.05),  # rain
              0.5 * z * (1 + x),                                       # snow
              0.3 * (1 - z) * (1 + y)]                                 # graupel
    w = np.stack(fields[:n_species], axis=-1) + 1e-3
    return (w / w.sum(axis=-1, keepdims=True)).astype(np.float32)


def hg_values(g, mu):
    return (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * mu) ** 1.5)


def plugin_phase(tables, weights):
    from weather_mi.kernel.plugins import hydrometeor_mixture as hm
    nodes, values = hm.prepare_tables(tables)
    return {"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]), "values": mi.TensorXf(values),
            "weights": mi.TensorXf(weights), "to_world": hm.bbox_transform(((-1, -1, -1), (1, 1, 1)))}, nodes.size


def scene(phase, sigma_t, size, max_depth):
    box = mi.ScalarTransform4f().translate([-1, -1, -1]).scale(2.0)
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": max_depth},
        "sensor": {"type": "perspective", "fov": 40,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0.8, -4.5, 1.2], target=[0, 0, 0], up=[0, 0, 1]),
                   "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"}}},
        "sun": {"type": "directional", "direction": [0.3, 0.6, -0.75], "irradiance": 1.0},
        "cube": {"type": "cube", "bsdf": {"type": "null"},
                 "interior": {"type": "heterogeneous", "scale": 1.0, "albedo": 0.98, "has_spectral_extinction": False,
                              "sigma_t": {"type": "gridvolume", "data": mi.TensorXf(sigma_t[..., None]),
                                          "to_world": box, "filter_type": "trilinear"},
                              "phase": phase}},
    })


def render_timed(sc, spp, seed):
    """(wall seconds, CPU seconds of this process (all threads), image)."""
    t0, c0 = time.perf_counter(), time.process_time()
    img = mi.render(sc, spp=spp, seed=seed)
    dr.eval(img)
    dr.sync_thread()
    return time.perf_counter() - t0, time.process_time() - c0, img


def events_str(events):
    return "-" if events is None else f"{events:.2f}"


def mean_se(x):
    """'mean +- standard error' of the per-render image means."""
    x = np.asarray(x)
    se = x.std(ddof=1) / np.sqrt(x.size) if x.size > 1 else float("nan")
    return f"{x.mean():.5f} +- {se:.5f}"


CASES = ("(a) hg", "(b) tabphase", "(c) plugin-1", "(d) plugin-5", "(e) physical-5")


def call_costs(phase, n=1 << 18, repeats=15):
    """Nanoseconds of CPU per lane for one eval_pdf, one sample and both, on one Dr.Jit thread: random
    positions in the box [-1, 1]^3 and random directions, median over ``repeats`` after a warm-up.
    The inputs sit in aligned memory (``aligned_float``), as unaligned ones slow the loads at random."""
    from weather_mi.kernel.jitarrays import aligned_float
    threads = dr.thread_count()
    dr.set_thread_count(1)
    ctx = mi.PhaseFunctionContext(None)

    def inputs(seed):
        rng = np.random.default_rng(seed)

        def f(*rows):
            return [aligned_float(mi, r) for r in rows]

        d = rng.normal(size=(2, 3, n))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        mei = dr.zeros(mi.MediumInteraction3f, n)
        mei.p = mi.Point3f(*f(*rng.uniform(-1, 1, (3, n))))
        mei.wi = mi.Vector3f(*f(*d[0]))
        mei.sh_frame = mi.Frame3f(mei.wi)
        wo = mi.Vector3f(*f(*d[1]))
        u1, u2 = f(rng.random(n))[0], mi.Point2f(*f(*rng.random((2, n))))
        dr.eval(mei, u1, u2, wo)
        return mei, wo, u1, u2

    def once(mode, seed):
        mei, wo, u1, u2 = inputs(seed)
        dr.sync_thread()
        c0 = time.process_time()
        out = []
        if mode != "sample":
            out += list(phase.eval_pdf(ctx, mei, wo))
        if mode != "eval":
            out += list(phase.sample(ctx, mei, u1, u2))
        dr.eval(*out)
        dr.sync_thread()
        return time.process_time() - c0

    res = {}
    try:
        for mode in ("eval", "sample", "both"):
            once(mode, 0)
            res[mode] = statistics.median(once(mode, 1 + r) for r in range(repeats)) * 1e9 / n
    finally:
        dr.set_thread_count(threads)
    return res


def events_per_path(phase_dict, sigma_t, size, max_depth, spp=4):
    """Mean number of phase-function samples (scattering events) per camera path, counted by a
    subclass of the plugin with an atomic counter (a separate, untimed render)."""
    from weather_mi.kernel.plugins.hydrometeor_mixture import mixture_class

    class Counting(mixture_class()):
        def __init__(self, props):
            super().__init__(props)
            self.count = dr.zeros(mi.UInt32, 1)

        def sample(self, ctx, mei, sample1, sample2, active=True):
            dr.scatter_reduce(dr.ReduceOp.Add, self.count, mi.UInt32(1), mi.UInt32(0), active)
            return super().sample(ctx, mei, sample1, sample2, active)

    made = []
    mi.register_phase("hydrometeor_mixture_counting", lambda props: made.append(Counting(props)) or made[-1])
    sc = scene(dict(phase_dict, type="hydrometeor_mixture_counting"), sigma_t, size, max_depth)
    dr.eval(mi.render(sc, spp=spp, seed=12345))
    return float(made[-1].count[0]) / (size * size * spp)


def worker(args) -> dict:
    """Render one case (warm-up + args.renders timed renders) in this process; a JSON-able dict."""
    variant = wm.set_variant(args.variant)
    from weather_mi.optics import phase
    name = CASES[args.worker]
    note = ""
    if name == "(a) hg":
        ph = {"type": "hg", "g": 0.85}
    elif name == "(b) tabphase":
        ph = {"type": "tabphase", "values": ", ".join(f"{v:.6g}" for v in hg_values(0.85, np.linspace(-1, 1, args.tab_size)))}
        note = f"{args.tab_size} values"
    elif name == "(c) plugin-1":
        ph, n = plugin_phase([phase.henyey_greenstein(0.85)], weights_grid(1))
        note = f"{n} nodes"
    elif name == "(d) plugin-5":
        ph, n = plugin_phase([phase.henyey_greenstein(0.85) for _ in range(5)], weights_grid(5))
        note = f"{n} nodes, 5 x HG 0.85"
    else:
        ph, n = plugin_phase(phase.for_species(list(wm.species.preset("physical")), mode="per_species"), weights_grid(5))
        note = f"{n} nodes, physical tables"
    sc = scene(ph, sigma_t_grid(), args.size, args.max_depth)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    first, _, img = render_timed(sc, args.spp, 0)
    out = {"variant": variant, "first": first, "wall": [], "cpu": [], "radiance": [], "ops": set(), "note": note}
    for r in range(args.renders):
        dr.kernel_history()  # clear
        dt, dc, img = render_timed(sc, args.spp, 1 + args.round * args.renders + r)
        out["ops"] |= {k.get("operation_count", 0) for k in dr.kernel_history() if k.get("type") == dr.KernelType.JIT}
        out["wall"].append(dt)
        out["cpu"].append(dc)
        out["radiance"].append(float(np.mean(np.array(img))))
    out["ops"] = max(out["ops"])
    if args.calls:
        medium = next(s.interior_medium() for s in sc.shapes() if s.interior_medium() is not None)
        out["calls"] = call_costs(medium.phase_function())
    out["events"] = events_per_path(ph, sigma_t_grid(), args.size, args.max_depth) if "plugin" in name or "physical" in name else None
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--rounds", type=int, default=3, help="worker processes per case (round-robin)")
    ap.add_argument("--renders", type=int, default=3, help="timed renders per worker")
    ap.add_argument("--max-depth", type=int, default=64)
    ap.add_argument("--tab-size", type=int, default=2048)
    ap.add_argument("--variant", default=None)
    ap.add_argument("--cases", type=int, nargs="+", default=list(range(len(CASES))),
                    help="which cases to run (0 hg, 1 tabphase, 2 plugin-1, 3 plugin-5); ratios to a case "
                         "not run print as nan")
    ap.add_argument("--calls", action=argparse.BooleanOptionalAction, default=True,
                    help="also time eval_pdf and sample outside a render (second table)")
    ap.add_argument("--worker", type=int, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--round", type=int, default=0, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker is not None:
        print("RESULT " + json.dumps(worker(args)), flush=True)
        return

    res = {name: {"first": [], "wall": [], "cpu": [], "radiance": [], "ops": set(), "note": "", "events": None,
                  "calls": []} for name in CASES}
    variant = None
    for r in range(args.rounds):
        for i, name in enumerate(CASES):
            if i not in args.cases:
                continue
            cmd = [sys.executable, __file__, "--worker", str(i), "--round", str(r), "--size", str(args.size),
                   "--spp", str(args.spp), "--renders", str(args.renders), "--max-depth", str(args.max_depth),
                   "--tab-size", str(args.tab_size), "--calls" if args.calls else "--no-calls"] + (
                       ["--variant", args.variant] if args.variant else [])
            proc = subprocess.run(cmd, capture_output=True, text=True)
            line = next((ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")), None)
            if proc.returncode != 0 or line is None:
                sys.exit(f"worker {name} failed (exit {proc.returncode}):\n{proc.stdout[-2000:]}\n{proc.stderr[-4000:]}")
            out = json.loads(line[len("RESULT "):])
            variant = out["variant"]
            rr = res[name]
            rr["first"].append(out["first"])
            rr.setdefault("round_cpu", []).append(statistics.median(out["cpu"]))
            for key in ("wall", "cpu", "radiance"):
                rr[key] += out[key]
            rr["ops"].add(out["ops"])
            rr["note"] = out["note"]
            rr["events"] = out["events"]
            if out.get("calls"):
                rr["calls"].append(out["calls"])

    n = args.rounds * args.renders
    print(f"variant {variant}; {args.size} x {args.size}, {args.spp} spp, max_depth {args.max_depth}; "
          f"{n} timed renders per case ({args.rounds} worker processes x {args.renders})")
    samples = args.size * args.size * args.spp
    run = [CASES[i] for i in sorted(set(args.cases))]
    nan = float("nan")
    med = {name: statistics.median(res[name]["wall"]) if name in run else nan for name in CASES}
    mcpu = {name: statistics.median(res[name]["cpu"]) if name in run else nan for name in CASES}
    header = (f"{'case':<14}{'1st render':>11}{'wall s':>8}{'CPU s':>7}{'Msamples/CPU-s':>16}"
              f"{'vs hg':>8}{'vs tabphase':>13}{'(wall)':>8}{'mean radiance':>22}{'kernel ops':>12}  notes")
    print(header)
    print("-" * len(header))
    for name in run:
        rr = res[name]
        ops = "/".join(str(o) for o in sorted(rr["ops"]))
        print(f"{name:<14}{statistics.median(rr['first']):>10.2f}s{med[name]:>8.3f}{mcpu[name]:>7.2f}"
              f"{samples / mcpu[name] / 1e6:>16.3f}{mcpu[name] / mcpu['(a) hg']:>7.2f}x"
              f"{mcpu[name] / mcpu['(b) tabphase']:>12.2f}x{med[name] / med['(b) tabphase']:>7.2f}x"
              f"{mean_se(rr['radiance']):>22}{ops:>12}{events_str(rr['events']):>13}  {rr['note']}")
    ratio = mcpu["(d) plugin-5"] / mcpu["(b) tabphase"]
    per_round = [d / b for d, b in zip(res["(d) plugin-5"].get("round_cpu", []), res["(b) tabphase"].get("round_cpu", []))]
    print(f"target: plugin-5 <= 1.25x tabphase (CPU time): {ratio:.2f}x -> {'met' if ratio <= 1.25 else 'MISSED'}"
          f" (wall time: {med['(d) plugin-5'] / med['(b) tabphase']:.2f}x; round by round: "
          + ", ".join(f"{x:.2f}" for x in per_round) + ")")
    ev_c, ev_e = res["(c) plugin-1"]["events"], res["(e) physical-5"]["events"]
    if ev_c and ev_e:
        per_event = (mcpu["(e) physical-5"] / ev_e) / (mcpu["(b) tabphase"] / ev_c)
        print(f"(e) has its own light transport ({ev_e:.2f} scattering events per path against {ev_c:.2f} for "
              f"HG 0.85): CPU per scattering event {per_event:.2f}x tabphase's")
    if args.calls:
        print()
        print("phase function alone, 2^18 lanes, one Dr.Jit thread: ns of CPU per lane (median over workers)")
        cost = {name: {m: statistics.median(c[m] for c in res[name]["calls"]) for m in ("eval", "sample", "both")}
                for name in run if res[name]["calls"]}
        base = cost.get("(b) tabphase", {}).get("both", nan)
        print(f"{'case':<16}{'eval_pdf':>10}{'sample':>10}{'both':>10}{'vs tabphase':>13}")
        for name, c in cost.items():
            print(f"{name:<16}{c['eval']:>10.1f}{c['sample']:>10.1f}{c['both']:>10.1f}{c['both'] / base:>12.2f}x")


if __name__ == "__main__":
    main()
