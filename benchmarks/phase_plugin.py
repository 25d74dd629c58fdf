"""Cost of the ``hydrometeor_mixture`` phase function against Mitsuba's built-in ``hg`` and ``tabphase``.

    .venv/bin/python benchmarks/phase_plugin.py [--size 128] [--spp 16] [--rounds 3] [--renders 3]
                                                [--max-depth 64] [--tab-size 2048] [--variant llvm_ad_rgb]

One scene, four phase functions (only the phase differs): a cube [-1, 1]^3 of ``heterogeneous``
medium (a 32^3 ``gridvolume`` sigma_t, a lumpy blob up to 20 per unit length: optical depth ~15-18
through the centre, albedo 0.98) lit by a directional sun, seen by a perspective camera, ``volpath``
with ``max_depth`` 64 (multiple scattering, next-event estimation: every scattering event costs one
phase ``sample`` and one ``eval_pdf``), box pixel filter, black background.

  (a) hg        built-in Henyey-Greenstein, g = 0.85
  (b) tabphase  built-in table of the same HG, ``--tab-size`` values uniform in cos(theta)
  (c) plugin-1  ``hydrometeor_mixture`` with one species: ``weather_mi.phase.henyey_greenstein(0.85)``
                (the default angle grid), weights grid 16^3 x 1
  (d) plugin-5  five species, the "physical" preset's per-species tables (Mie cloud, ice columns,
                Mie rain 0.7 mm, snow, graupel), spatially varying weights on a 16^3 x 5 grid, every
                weight >= ~1e-3 everywhere (the worst case: no species is ever absent)

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
jobs both follow their load (ratios moved by ~0.1 between runs on the 2-core development machine):
compare within one run, and repeat. The operation count of each case's render kernel is printed
(Dr.Jit traced the plugin cases into one of two slightly different kernels from run to run). The
image-mean radiance (mean +- standard error over the timed renders) is a sanity check: (a), (b)
and (c) render the same phase function and must agree within noise; (d) has other phase functions.

Target (issue): plugin-5 costs at most 1.25x tabphase.
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
    from weather_mi.plugins import hydrometeor_mixture as hm
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


def mean_se(x):
    """'mean +- standard error' of the per-render image means."""
    x = np.asarray(x)
    se = x.std(ddof=1) / np.sqrt(x.size) if x.size > 1 else float("nan")
    return f"{x.mean():.5f} +- {se:.5f}"


CASES = ("(a) hg", "(b) tabphase", "(c) plugin-1", "(d) plugin-5")


def worker(args) -> dict:
    """Render one case (warm-up + args.renders timed renders) in this process; a JSON-able dict."""
    variant = wm.set_variant(args.variant)
    from weather_mi import phase
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
    else:
        ph, n = plugin_phase(phase.for_species(list(wm.species.preset("physical")), mode="per_species"), weights_grid(5))
        note = f"{n} nodes"
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
    ap.add_argument("--worker", type=int, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--round", type=int, default=0, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker is not None:
        print("RESULT " + json.dumps(worker(args)), flush=True)
        return

    res = {name: {"first": [], "wall": [], "cpu": [], "radiance": [], "ops": set(), "note": ""} for name in CASES}
    variant = None
    for r in range(args.rounds):
        for i, name in enumerate(CASES):
            cmd = [sys.executable, __file__, "--worker", str(i), "--round", str(r), "--size", str(args.size),
                   "--spp", str(args.spp), "--renders", str(args.renders), "--max-depth", str(args.max_depth),
                   "--tab-size", str(args.tab_size)] + (["--variant", args.variant] if args.variant else [])
            proc = subprocess.run(cmd, capture_output=True, text=True)
            line = next((ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")), None)
            if proc.returncode != 0 or line is None:
                sys.exit(f"worker {name} failed (exit {proc.returncode}):\n{proc.stdout[-2000:]}\n{proc.stderr[-4000:]}")
            out = json.loads(line[len("RESULT "):])
            variant = out["variant"]
            rr = res[name]
            rr["first"].append(out["first"])
            for key in ("wall", "cpu", "radiance"):
                rr[key] += out[key]
            rr["ops"].add(out["ops"])
            rr["note"] = out["note"]

    n = args.rounds * args.renders
    print(f"variant {variant}; {args.size} x {args.size}, {args.spp} spp, max_depth {args.max_depth}; "
          f"{n} timed renders per case ({args.rounds} worker processes x {args.renders})")
    samples = args.size * args.size * args.spp
    med = {name: statistics.median(res[name]["wall"]) for name in CASES}
    mcpu = {name: statistics.median(res[name]["cpu"]) for name in CASES}
    header = (f"{'case':<14}{'1st render':>11}{'wall s':>8}{'CPU s':>7}{'Msamples/CPU-s':>16}"
              f"{'vs hg':>8}{'vs tabphase':>13}{'(wall)':>8}{'mean radiance':>22}{'kernel ops':>12}  notes")
    print(header)
    print("-" * len(header))
    for name in CASES:
        rr = res[name]
        ops = "/".join(str(o) for o in sorted(rr["ops"]))
        print(f"{name:<14}{statistics.median(rr['first']):>10.2f}s{med[name]:>8.3f}{mcpu[name]:>7.2f}"
              f"{samples / mcpu[name] / 1e6:>16.3f}{mcpu[name] / mcpu['(a) hg']:>7.2f}x"
              f"{mcpu[name] / mcpu['(b) tabphase']:>12.2f}x{med[name] / med['(b) tabphase']:>7.2f}x"
              f"{mean_se(rr['radiance']):>22}{ops:>12}  {rr['note']}")
    ratio = mcpu["(d) plugin-5"] / mcpu["(b) tabphase"]
    print(f"target: plugin-5 <= 1.25x tabphase (CPU time): {ratio:.2f}x -> {'met' if ratio <= 1.25 else 'MISSED'}"
          f" (wall time: {med['(d) plugin-5'] / med['(b) tabphase']:.2f}x)")


if __name__ == "__main__":
    main()
