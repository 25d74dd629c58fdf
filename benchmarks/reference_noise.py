"""Noise of the path-traced reference: the estimator before issue 10 ("old": point sun as a scene
emitter chosen per vertex, Russian roulette as Mitsuba's volpath, phase sampling by channel mean)
against the current one ("new": the sun as the integrator's own disk of 0.53 deg with MIS, roulette
that never inflates weights, long walks cut from depth 1024, history-aware channel sampling, forward
peaks within 3 deg as unscattered light, free flights over texel cells, exact shadow-ray
transmittance, persistent lanes, passes rendered together), "prev" (new without the texel grid, the
exact transmittance and persistent lanes) and "last" (new with one pass per launch, as at the stop
before ``render_passes``), in the same process, on the same scenes.

    .venv/bin/python benchmarks/reference_noise.py [--views] [--time-to 0.01] [--bias] [--profile] [--quick]
        [--mvnee [--mvnee-configs 0.3:2 0.5:4] [--mvnee-size 64 48] [--mvnee-spp 64]]

Scenes: the demo supercell (``wm.synthetic.supercell()``), camera ``Camera.orbit(vol, azimuth=200,
elevation=8, fov=45)``, sunsky + ground; sun at azimuth/elevation 200/35 (front), 290/35 (side),
20/20 (back); presets "paper" and "physical". Cloud pixels: eye-ray optical depth > ln 2
(``estimates.eye_optical_depth``, deterministic). Measures (``estimates.noise_stats``, channel means):

    rms se/mean    RMS standard error over cloud pixels / mean cloud radiance
    worst se/mean  largest standard error of a cloud pixel / mean cloud radiance
    mean RSE       mean over cloud pixels of se / radiance

Sections (all by default):
--views     the six views at 160 x 120, 64 spp in 16 passes: every estimator, seconds per spp.
--time-to   time to a mean RSE over cloud pixels, supercell side-lit, 256 x 256: each estimator
            renders --budget seconds of passes; t = T (RSE(T) / target)^2. Then the new estimator as a
            render to the target runs (16 planned passes over every pixel, then passes over the cloud
            pixels only): t = T0 + (passes needed - 16) x the time of such a pass.
--bias      point sun, small images, many spp: the mean cloud radiance of the old estimator, of the
            new one with the full phase tables (forward_peak_deg=0: the same transfer problem), of
            the new one as it renders (delta-M, 3 deg) and of prev (the same problem as new: a check
            of the texel grid, exact transmittance and persistent lanes), with the differences in
            combined standard errors (the heavy-tailed estimators' standard errors are themselves unreliable, and with
            the full tables both read low: validation/forward_peak_slabs.py).
--mvnee     multiple-vertex NEE (weather_mi/kernel/plugins/mvnee.py, render_reference(mvnee=...)) against today's estimator
            on the six views (--mvnee-size, --mvnee-spp, 16 passes). Configurations: EPS:K (chains of
            K vertices launched with probability EPS), aureole:EPS (the aureole estimator), today
            (today's estimator again, another seed: the spread of these figures). Seconds, RMS
            se/mean, efficiency 1 / (RMS^2 x time) over today's (eff; eff RSE: with the mean RSE; time:
            this process's CPU seconds, as the machine is shared),
            and the z-test of unbiasedness: per cloud pixel z = (on - off) / sqrt(se_on^2 + se_off^2)
            (channel means): mean z, fraction |z| > 3, and the cloud-mean difference in combined
            standard errors.
--profile   where the time of the new estimator goes, by ablation on the side view: each row changes
            one thing and gives its seconds per spp against the full estimator in the same run.
"""
from __future__ import annotations

import argparse
import contextlib
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import mitsuba as mi  # noqa: E402
import weather_mi as wm  # noqa: E402

wm.set_variant()  # selects the default variant (registers the plugins with it)
CPU_WIDTH = wm.kernel.variant.llvm_vector_width() or wm.kernel.variant.PATH_TRACING_VECTOR_WIDTH  # Dr.Jit's default: the CPU's

VIEWS = {"front": (200.0, 35.0), "side": (290.0, 35.0), "back": (20.0, 20.0)}


def spec_for(vol, view, width, height, diameter, seed=0):
    az, el = VIEWS[view]
    return wm.SceneSpec(camera=wm.Camera.orbit(vol, azimuth=200, elevation=8, fov=45),
                        sun=wm.Sun(az, el, angular_diameter_deg=diameter), width=width, height=height, seed=seed)


# the estimator of issue 10 before its sixth session (commit 9cc7700): free flights over the coarse majorant
# grid, shadow rays by ratio tracking, passes by mi.render
PREVIOUS = {"DEFAULT_TRACKING_GRID": "coarse", "DEFAULT_TRANSMITTANCE": "ratio", "DEFAULT_PERSISTENT_LANES": False}


@contextlib.contextmanager
def plugin_defaults(values, module=None):
    """Module constants (of ``majorant_volpath`` unless ``module`` is given) set to ``values`` for a while."""
    if module is None:
        from weather_mi.kernel.plugins import majorant_volpath as module
    saved = {k: getattr(module, k) for k in values}
    for k, v in values.items():
        setattr(module, k, v)
    try:
        yield
    finally:
        for k, v in saved.items():
            setattr(module, k, v)


def render(spec, vol, spp, which, passes=None, **kw):
    """``which``: "old", the estimator before issue 10 as it ran then, at Dr.Jit's default LLVM block size
    (weather-mi now sets ``variant.LLVM_BLOCK_SIZE``, which also speeds the old estimator up by 6-8%);
    "prev", the issue-10 estimator before the texel grid, exact transmittance and persistent lanes
    (``PREVIOUS``); "last", the new estimator as the last stop rendered (one pass per launch, before
    ``render_passes``: ``passes.BATCH_SAMPLES`` = 0); "new". All but "new" at the CPU's SIMD width
    (before ``variant.PATH_TRACING_VECTOR_WIDTH``)."""
    from weather_mi.kernel.variant import DRJIT_DEFAULT_BLOCK_SIZE, LLVM_BLOCK_SIZE, tune_llvm
    wm.set_variant()  # selects the variant (and our block size) before the old one is put back
    old = which == "old"
    if old:
        spec = replace(spec, sun=replace(spec.sun, angular_diameter_deg=0.0))
        tune_llvm(DRJIT_DEFAULT_BLOCK_SIZE)
    try:
        with plugin_defaults(PREVIOUS if which == "prev" else {}), \
                plugin_defaults({"BATCH_SAMPLES": 0} if which == "last" else {}, module=wm.reference.passes), \
                plugin_defaults({"PATH_TRACING_VECTOR_WIDTH": CPU_WIDTH} if which != "new" else {}, module=wm.kernel.variant):
            return wm.render_reference(spec, vol, spp=spp, passes=passes, progress=False, legacy=old, **kw)
    finally:
        tune_llvm(LLVM_BLOCK_SIZE)


def row(label, img):
    n = img.metadata["noise"]
    s = img.metadata["seconds"]
    return (f"{label:28s} {s:8.1f} {s / img.metadata['spp']:8.3f} {n['rms_se_over_mean']:12.3f} "
            f"{n['worst_se_over_mean']:13.2f} {n['rse_mean']:9.3f}")


HEADER = f"{'view / estimator':28s} {'seconds':>8s} {'s/spp':>8s} {'rms se/mean':>12s} {'worst se/mean':>13s} {'mean RSE':>9s}"


def views(vols, args):
    print(f"\n## six views, {args.width} x {args.height}, {args.spp} spp (16 passes)")
    print(HEADER)
    ratios, prev_ratios, last_ratios, same = [], [], [], []
    for preset, vol in vols.items():
        for view in VIEWS:
            spec = spec_for(vol, view, args.width, args.height, 0.53)
            imgs = {}
            for which in ("old", "prev", "last", "new"):
                render(replace(spec, width=8, height=8), vol, 1, which, passes=1)  # kernels compiled outside
                imgs[which] = render(spec, vol, args.spp, which)
                print(row(f"{preset} {view} {which}", imgs[which]), flush=True)
            s = {k: v.metadata["seconds"] for k, v in imgs.items()}
            ratios.append(s["new"] / s["old"])
            prev_ratios.append(s["new"] / s["prev"])
            last_ratios.append(s["new"] / s["last"])
            same.append(np.array_equal(imgs["new"].radiance, imgs["last"].radiance))
    print(f"time per spp new / old: median {np.median(ratios):.2f}x, range {min(ratios):.2f}-{max(ratios):.2f}x; "
          f"new / prev: median {np.median(prev_ratios):.2f}x, range {min(prev_ratios):.2f}-{max(prev_ratios):.2f}x; "
          f"new / last: median {np.median(last_ratios):.2f}x, range {min(last_ratios):.2f}-{max(last_ratios):.2f}x "
          f"(images bit-identical to last's: {sum(same)} of {len(same)})")


def time_to(vol, args):
    size = args.size
    print(f"\n## time to {100 * args.target:g}% mean RSE over cloud pixels, side-lit with sky, {size} x {size}, "
          f"{args.budget:.0f} s of passes each")
    spec = spec_for(vol, "side", size, size, 0.53)
    out, t1_of = {}, {}
    for which in ("old", "prev", "last", "new"):
        render(spec, vol, 1, which, passes=1)  # compile outside the timing (at this image size: a new size
        # may compile anew); seconds per spp from 4-spp passes: a 1-spp pass took 0.35 or 2.7 s, as a walk of
        # ~1e6 events (the long-walk roulette's tail) started early in it or late
        t1 = t1_of[which] = min(render(spec, vol, 4, which, passes=1).metadata["seconds"] for _ in range(2)) / 4
        per = max(1, int(args.budget / 16 / max(t1, 1e-3)))
        passes = max(4, int(args.budget / max(per * t1, 1e-3)))
        img = render(spec, vol, per * passes, which, passes=passes)
        n, s = img.metadata["noise"], img.metadata["seconds"]
        t = s * (n["rse_mean"] / args.target) ** 2
        out[which] = t
        print(f"{which}: {passes} passes x {per} spp in {s:.0f} s, mean RSE {n['rse_mean']:.4f}, "
              f"rms se/mean {n['rms_se_over_mean']:.3f}, worst {n['worst_se_over_mean']:.2f} -> t({args.target:g}) "
              f"= {t / 60:.1f} min", flush=True)
    print(f"speed-up to {args.target:g}: old / new {out['old'] / out['new']:.2f}x, prev / new "
          f"{out['prev'] / out['new']:.2f}x, last / new {out['last'] / out['new']:.2f}x")
    # the new estimator as a render to the target runs (render_reference(target_rse=...)): 16 planned passes
    # over every pixel, then passes over the cloud pixels only. Time to the target: the planned passes'
    # time T0 plus the further passes needed at their own cost (the variance per pass is that of a planned one)
    render(spec, vol, 1, "new", passes=1, target_rse=0.5)  # compiles the kernel of passes over some pixels
    per = max(1, int(args.budget / 64 / max(t1_of["new"], 1e-3)))  # planned passes: a quarter of the budget
    marks = []
    img = render(spec, vol, 16 * per, "new", passes=16, target_rse=args.target, max_seconds=args.budget,
                 on_pass=lambda im: marks.append(im.metadata["seconds"]))
    n_done, s = img.metadata["passes"], img.metadata["seconds"]
    t0, nz = marks[15], img.metadata["noise"]
    tau = (s - t0) / max(n_done - 16, 1)
    n_need = n_done * (nz["rse_mean"] / args.target) ** 2
    t = t0 + max(n_need - 16, 0.0) * tau
    out["new, cloud passes"] = t
    print(f"new, cloud passes: 16 passes x {per} spp over every pixel in {t0:.0f} s, then {n_done - 16} over the "
          f"cloud pixels ({tau:.2f} s each, {tau / (t0 / 16):.2f}x a planned one); mean RSE "
          f"{nz['rse_mean']:.4f} -> t({args.target:g}) = {t / 60:.1f} min; old / new, cloud passes "
          f"{out['old'] / t:.2f}x, prev / it {out['prev'] / t:.2f}x, last / it "
          f"{out['last'] / t:.2f}x, new / it {out['new'] / t:.2f}x", flush=True)


def bias(vols, args):
    print(f"\n## unbiased: point sun, 48 x 36, {args.bias_spp} spp, mean cloud radiance +- se")
    for preset, vol in vols.items():
        for view in VIEWS:
            spec = spec_for(vol, view, 48, 36, 0.0, seed=7)
            cloud = wm.reference.estimates.cloud_mask(spec, vol)
            means = []
            for which, kw in (("old", {}), ("new", {"forward_peak_deg": 0.0}), ("new", {}), ("prev", {})):
                img = render(spec, vol, args.bias_spp, which, **kw)
                lum, se = img.radiance.mean(axis=2), img.stderr.mean(axis=2)
                means.append((float(lum[cloud].mean()), float(np.sqrt((se[cloud] ** 2).sum()) / cloud.sum())))
            (mo, so), (mf, sf), (mn, sn), (mp, sp) = means
            print(f"{preset:8s} {view:5s} old {mo:.5f} +- {so:.5f}  new, full tables {mf:.5f} +- {sf:.5f} "
                  f"({(mf - mo) / math.hypot(so, sf):+.2f} se)  new {mn:.5f} +- {sn:.5f} "
                  f"({(mn - mo) / math.hypot(so, sn):+.2f} se, {100 * (mn / mo - 1):+.1f}%)  prev {mp:.5f} +- {sp:.5f} "
                  f"(new - prev {(mn - mp) / math.hypot(sp, sn):+.2f} se)", flush=True)


def zstats(a, b, cloud):
    """(mean z, fraction |z| > 3, relative cloud-mean difference, its z) of image ``a`` against ``b``."""
    la, lb = a.radiance.mean(axis=2)[cloud], b.radiance.mean(axis=2)[cloud]
    sa, sb = a.stderr.mean(axis=2)[cloud], b.stderr.mean(axis=2)[cloud]
    z = (la - lb) / np.sqrt(sa ** 2 + sb ** 2)
    z = z[np.isfinite(z)]
    se_m = math.sqrt((sa ** 2).sum() + (sb ** 2).sum()) / cloud.sum()
    return float(z.mean()), float((np.abs(z) > 3).mean()), float(la.mean() / lb.mean() - 1), \
        float((la.mean() - lb.mean()) / se_m)


def mvnee_render(spec, vol, args, config, mvnee):
    """``config``: "EPS:K" (multiple-vertex NEE), "aureole:EPS" (the aureole estimator) or "today" (today's
    estimator again, another seed: the spread of these figures); kernels compiled outside the timing."""
    kind, _, value = config.partition(":")
    kw = {} if kind == "today" else {"aureole_nee": float(value)} if kind == "aureole" else {"mvnee": float(kind)}
    with plugin_defaults({"DEFAULT_LENGTH": int(value)} if "mvnee" in kw else {}, module=mvnee):
        render(replace(spec, width=8, height=8, seed=4), vol, 1, "new", passes=1, **kw)
        return cpu_timed(lambda: render(replace(spec, seed=4), vol, args.mvnee_spp, "new", **kw))


def cpu_timed(fn):
    """``fn()``'s image with metadata["cpu_seconds"]: the CPU time of this process (all its threads) it took,
    less sensitive than the wall time to other processes on a shared machine."""
    t0 = time.process_time()
    img = fn()
    img.metadata["cpu_seconds"] = time.process_time() - t0
    return img


def mvnee_rows(vols, args):
    from weather_mi.kernel.plugins import mvnee
    w, h = args.mvnee_size
    print(f"\n## multiple-vertex NEE against today's estimator, six views, {w} x {h}, {args.mvnee_spp} spp "
          "(16 passes); cpu x: CPU seconds over today's; eff = (rms^2 t_cpu)_today / (rms^2 t_cpu), eff RSE the same "
          "with the mean RSE")
    print(HEADER + f" {'cpu x':>6s} {'eff':>6s} {'eff RSE':>7s} {'mean z':>7s} {'|z|>3':>6s} {'mean diff':>10s}")
    effs = {c: [] for c in args.mvnee_configs}
    for preset, vol in vols.items():
        for view in VIEWS:
            spec = spec_for(vol, view, w, h, 0.53, seed=3)
            cloud = wm.reference.estimates.cloud_mask(spec, vol)
            render(replace(spec, width=8, height=8), vol, 1, "new", passes=1)
            base = cpu_timed(lambda: render(spec, vol, args.mvnee_spp, "new"))
            nb, tb = base.metadata["noise"], base.metadata["cpu_seconds"]
            print(row(f"{preset} {view} today", base), flush=True)
            for c in args.mvnee_configs:
                img = mvnee_render(spec, vol, args, c, mvnee)
                n = img.metadata["noise"]
                tc = img.metadata["cpu_seconds"]
                eff = (nb["rms_se_over_mean"] ** 2 * tb) / (n["rms_se_over_mean"] ** 2 * tc)
                eff_rse = (nb["rse_mean"] ** 2 * tb) / (n["rse_mean"] ** 2 * tc)
                effs[c].append((eff, eff_rse))
                mz, f3, rel, zm = zstats(img, base, cloud)
                print(row(f"{preset} {view} {c}", img) + f" {tc / tb:6.2f} {eff:6.2f} {eff_rse:7.2f} "
                      f"{mz:+7.2f} {f3:6.3f} "
                      f"{100 * rel:+6.1f}% ({zm:+.1f} se)", flush=True)
    for c, pairs in effs.items():
        for i, label in enumerate(("rms", "mean RSE")):
            e = [p[i] for p in pairs]
            print(f"{c}: efficiency ({label}) over today's, median {np.median(e):.2f}x, range {min(e):.2f}-"
                  f"{max(e):.2f}x, wins on {sum(x > 1 for x in e)} of {len(e)} views")


def toggled(spec, vol, args, module=None, **defaults):
    """The new estimator with plugin (or ``module``) defaults changed (``plugin_defaults``), kernels compiled
    outside."""
    with plugin_defaults(defaults, module=module):
        render(replace(spec, width=8, height=8), vol, 1, "new", passes=1)
        return render(spec, vol, args.profile_spp, "new")


def profile(vol, args):
    print(f"\n## profile of the new estimator, side view, {args.width} x {args.height}, {args.profile_spp} spp")
    spec = spec_for(vol, "side", args.width, args.height, 0.53)
    t0 = time.perf_counter()
    first = render(replace(spec, width=8, height=8, seed=99), vol, 1, "new", passes=1)
    print(f"first render of a process (scene build + kernel compile or disk cache + 8x8 pixels): "
          f"{time.perf_counter() - t0:.1f} s ({first.metadata['seconds']:.1f} s of it in mi.render)")
    render(replace(spec, width=8, height=8), vol, 1, "new", passes=1)
    base = render(spec, vol, args.profile_spp, "new")
    b = base.metadata["seconds"]
    hg = wm.optical_volume(wm.synthetic.supercell(), species=args.presets[0],
                           phase_tables=[wm.phase.henyey_greenstein(0.85)] * 5)
    def warm(spec, vol, **kw):  # each case compiles its kernel before its timed render
        render(replace(spec, width=8, height=8), vol, 1, "new", passes=1, **kw)
        return render(spec, vol, args.profile_spp, "new", **kw)

    cases = [
        ("full estimator", base),
        ("max_depth 32 (long walks cut)", warm(spec, vol, max_depth=32)),
        ("max_depth 8", warm(spec, vol, max_depth=8)),
        ("no sky, no ground (sun only)", warm(replace(spec, sky=None, ground=None), vol)),
        ("HG phase instead of tables", warm(spec, hg)),
        ("free flights over the coarse grid (cell 2)", toggled(spec, vol, args, DEFAULT_TRACKING_GRID="coarse")),
        ("shadow rays by ratio tracking", toggled(spec, vol, args, DEFAULT_TRANSMITTANCE="ratio")),
        ("passes by mi.render (no persistent lanes)", toggled(spec, vol, args, DEFAULT_PERSISTENT_LANES=False)),
        ("one pass per launch", toggled(spec, vol, args, module=wm.reference.passes, BATCH_SAMPLES=0)),
        (f"SIMD width {CPU_WIDTH} (the CPU's) instead of {wm.kernel.variant.PATH_TRACING_VECTOR_WIDTH}",
         toggled(spec, vol, args, module=wm.kernel.variant, PATH_TRACING_VECTOR_WIDTH=CPU_WIDTH)),
        ("eye rays only (max_depth 1)", warm(spec, vol, max_depth=1)),
    ]
    print(f"{'case':40s} {'seconds':>8s} {'vs full':>8s}")
    for label, img in cases:
        s = img.metadata["seconds"]
        print(f"{label:40s} {s:8.1f} {s / b:8.2f}", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--views", action="store_true")
    ap.add_argument("--time-to", dest="time_to", action="store_true")
    ap.add_argument("--bias", action="store_true")
    ap.add_argument("--profile", action="store_true")
    ap.add_argument("--quick", action="store_true", help="smaller images and budgets")
    ap.add_argument("--mvnee", action="store_true")
    ap.add_argument("--mvnee-configs", dest="mvnee_configs", nargs="+", default=["0.3:2"], metavar="EPS:K")
    ap.add_argument("--mvnee-size", dest="mvnee_size", nargs=2, type=int, default=[64, 48])
    ap.add_argument("--mvnee-spp", dest="mvnee_spp", type=int, default=64)
    ap.add_argument("--target", type=float, default=0.01)
    ap.add_argument("--budget", type=float, default=120.0)
    ap.add_argument("--presets", nargs="+", default=["paper", "physical"])
    args = ap.parse_args(argv)
    if not (args.views or args.time_to or args.bias or args.profile or args.mvnee):
        args.views = args.time_to = args.bias = args.profile = True
    args.width, args.height, args.spp, args.size = (160, 120, 64, 256) if not args.quick else (80, 60, 32, 128)
    args.bias_spp = 1024 if not args.quick else 256
    args.profile_spp = 32 if not args.quick else 16
    if args.quick:
        args.budget = min(args.budget, 40.0)
    t0 = time.perf_counter()
    vols = {p: wm.optical_volume(wm.synthetic.supercell(), species=p) for p in args.presets}
    for v in vols.values():
        v.phase_tables  # noqa: B018  (tables built outside the timings)
    print(f"demo supercell, presets {', '.join(args.presets)}; {mi.variant()}")
    first = next(iter(vols.values()))
    if args.views:
        views(vols, args)
    if args.time_to:
        time_to(first, args)
    if args.bias:
        bias(vols, args)
    if args.profile:
        profile(first, args)
    if args.mvnee:
        mvnee_rows(vols, args)
    print(f"\ntotal {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
