"""Cost of the path-traced reference: stock ``volpath`` against the local-majorant tracker
(``majorant_volpath``, ``integrator="majorant"`` of ``render_reference``), time to a given error.

    .venv/bin/python benchmarks/reference.py [--size 256] [--budget 45] [--equal-time 60]
                                             [--wrf ../shared/data/wrf/wrfout_quarter_ss_0130.nc]
                                             [--preset paper|physical] [--max-depth -1] [--rr-depth 5]
                                             [--cells 8] [--integrators volpath majorant]

Volume: ``wm.optical_volume(wm.synthetic.supercell())`` (the demo supercell), or with ``--wrf PATH``
one time (``--time``, default the last) of a wrfout file through ``wm.open_wrf``. Scene:
``weather_mi.scene.spec.default_spec`` (orbit camera south-south-west, low; sun in the south-west; sunsky;
ground), rendered by ``render_reference`` itself (its passes, seeds and per-pixel standard errors),
square images of ``--size`` pixels. ``--cells 2 4 8 16`` measures the majorant tracker once per
coarse-cell size (fine voxels per majorant cell along each axis).

For each integrator: one 1-spp render at 1/8 of the size ("1st render": compilation + one run), one to
get the cost of a sample per pixel; the integrator is then measured at the largest of N, N/2, N/4,
N/8 (N = --size) where 4 passes of 1 spp fit the budget (stock volpath on a storm: N/8), with
passes of about budget/16 s and consecutive seeds for ``--budget`` seconds of wall time (at least 4
passes), and its times per spp are scaled to N x N by the pixel count. When volpath is measured on
a smaller image, the majorant tracker is measured on that image too (for a third of the budget): the
like-for-like comparison (tiny images use the CPU poorly: the majorant tracker runs ~3x fewer
paths/s at 32^2 than at 256^2, so scaled figures are pessimistic). From the passes: seconds per spp,
camera paths per second, the per-pixel variance of one sample (spread of the passes x spp) and so
the relative standard error after any time (RSE ~ 1/sqrt(time)). Errors are reported like
``Image.relative_stderr``: the mean over cloudy pixels of channel-mean standard error / channel-mean
radiance. Cloudy pixels: primary-ray transmittance < 0.9 (``wm.render_transmittance``, 32 spp).
Columns:

    RSE(run) mean RSE over cloudy pixels of this run's own passes (after its budget)
    RSE@Ts   mean RSE over cloudy pixels after T = --equal-time seconds of rendering
    t(1%)    extrapolated wall time to a mean RSE of 1% over cloudy pixels: T (RSE@T / 0.01)^2
    cloudy mean  mean radiance over the cloudy pixels +- its standard error (from the passes)

and the speed-up majorant/volpath at equal error, t(1%) of volpath / t(1%) of majorant.

Caveats. (1) Past ``rr_depth`` stock ``volpath`` plays
Russian roulette at every null collision, so its multiply scattered light in optically thick cores
survives with probability ~0.95^N after N null collisions: a rare-event estimator whose cloudy mean
reads low (about half of the majorant tracker's on the demo supercell) and whose sample variance (so
its RSE) is underestimated at practical sample counts. The table therefore also gives the difference
of the two cloudy means in standard errors. ``--rr-depth 100000 --max-depth 16`` compares both
without roulette (depth-limited light, so not the full image): there the cloudy means agree.
(2) volpath gets only a handful of passes: per-pixel standard deviations from few heavy-tailed
samples read low, which also favours volpath. Timings on a shared machine are noisy.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import mitsuba as mi  # noqa: E402
import weather_mi as wm  # noqa: E402
from weather_mi.kernel.plugins.majorant_volpath import DEFAULT_CELL  # noqa: E402
from weather_mi.scene.spec import default_spec  # noqa: E402

wm.set_variant()  # selects the default variant (registers the plugins with it)

DEFAULT_WRF = Path(__file__).resolve().parents[2] / "shared" / "data" / "wrf" / "wrfout_quarter_ss_0130.nc"
TARGET_RSE = 0.01


def load_volume(args):
    t0 = time.perf_counter()
    if args.wrf:
        hyd = wm.open_wrf(args.wrf, time=args.time)
        label = f"WRF {Path(args.wrf).name} (time {hyd.attrs.get('time', args.time)})"
    else:
        hyd = wm.synthetic.supercell()
        label = "demo supercell wm.synthetic.supercell()"
    vol = wm.optical_volume(hyd, species=args.preset)
    vol.phase_tables  # noqa: B018  (build the tables now, outside any timing)
    return vol, label, time.perf_counter() - t0


def cloudy_mask(spec, vol, spp=32):
    """Primary-ray transmittance < 0.9."""
    tr = wm.render_transmittance(spec, vol, spp=spp, passes=1)
    return tr < 0.9, tr


def render(spec, vol, integrator, args, spp, passes=1, cell=None):
    return wm.render_reference(spec, vol, spp=spp, passes=passes, integrator=integrator, max_depth=args.max_depth,
                               rr_depth=args.rr_depth, cell=cell or args.cells[0], progress=False)


def time_one(spec, vol, integrator, args, cell=None):
    """Seconds of one 1-spp render (``render_reference``'s own timing: rendering only)."""
    return render(spec, vol, integrator, args, 1, cell=cell).metadata["seconds"]


def measure(label, spec, vol, integrator, args, budget, cloudy, t_one, pixel_ratio=1.0, cell=None):
    """About ``budget`` seconds of passes (at least 4) of ``render_reference``; per-sample variances
    from its per-pixel standard errors. ``pixel_ratio``: (benchmark pixels) / (pixels of ``spec``),
    by which the times per spp are scaled."""
    spp = max(1, min(256, int(budget / 16 / max(t_one, 1e-3))))  # about 16 passes in the budget
    passes = max(4, min(256, int(budget / max(spp * t_one, 1e-3))))
    img = render(spec, vol, integrator, args, spp * passes, passes, cell)
    wall = img.metadata["seconds"]
    s_per_spp = wall / (passes * spp)
    h, w = img.radiance.shape[:2]
    se = img.stderr.astype(np.float64)
    lum = img.radiance.astype(np.float64).mean(axis=2)
    se_lum = se.mean(axis=2)  # an upper bound of the channel mean's standard error
    r = dict(label=label, size=w, spp=spp, passes=passes, wall=wall, s_per_spp=s_per_spp, paths=w * h / s_per_spp,
             var_spp=se ** 2 * passes * spp, mean=img.radiance.astype(np.float64), ok=cloudy & (lum > 0),
             cloudy_mean=float(lum[cloudy].mean()), cloudy_se=float(np.sqrt(np.sum(se_lum[cloudy] ** 2)) / cloudy.sum()))
    r["rse_now"] = rse_after(r, wall)  # measured: after this run's own passes, at its own size
    r["s_per_spp"] = s_per_spp * pixel_ratio  # time per spp of the benchmark image
    return r


def rse_after(r, seconds):
    """Mean over cloudy pixels of channel-mean standard error / channel-mean radiance after
    ``seconds`` of rendering (``Image.relative_stderr``)."""
    n_spp = seconds / r["s_per_spp"]
    se = np.sqrt(r["var_spp"] / n_spp).mean(axis=2)
    lum = r["mean"].mean(axis=2)
    ok = r["ok"]
    return float(np.mean(se[ok] / lum[ok]))


def fmt_time(s):
    if not math.isfinite(s):
        return "-"
    if s < 120:
        return f"{s:.0f} s"
    if s < 7200:
        return f"{s / 60:.1f} min"
    return f"{s / 3600:.1f} h"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", type=int, default=256, help="image width and height (pixels)")
    ap.add_argument("--budget", type=float, default=45.0, help="seconds of passes per integrator")
    ap.add_argument("--equal-time", type=float, default=60.0, help="time at which the RSEs are compared (s)")
    ap.add_argument("--wrf", nargs="?", const=str(DEFAULT_WRF), default=None, metavar="PATH",
                    help=f"a wrfout file instead of the demo supercell (default {DEFAULT_WRF})")
    ap.add_argument("--time", default=-1, type=lambda s: int(s) if s.lstrip("-").isdigit() else s,
                    help="time index or timestamp in the wrfout file")
    ap.add_argument("--preset", default="paper", choices=("paper", "physical"), help="species table")
    ap.add_argument("--max-depth", type=int, default=-1)
    ap.add_argument("--rr-depth", type=int, default=None, help="Russian roulette start (default: plugins' 5)")
    ap.add_argument("--integrators", nargs="+", default=["volpath", "majorant"], choices=["volpath", "majorant"])
    ap.add_argument("--cells", type=int, nargs="+", default=[DEFAULT_CELL],
                    help="majorant-grid cell sizes (fine voxels per coarse cell) to measure")
    args = ap.parse_args(argv)

    t_start = time.perf_counter()
    vol, label, t_load = load_volume(args)
    spec = default_spec(vol, width=args.size, height=args.size)
    nz, ny, nx = vol.shape
    bt = vol.beta_total
    print(f"volume: {label}, preset {args.preset}, grid {nz} x {ny} x {nx} (z, y, x), built in {t_load:.1f} s")
    print(f"beta_total max {1e3 * float(bt.max()):.3g} 1/km, {100 * float((bt > 0).mean()):.1f}% of voxels non-zero, "
          f"{100 * float((bt > 0.1 * bt.max()).mean()):.2f}% above 10% of the max; "
          f"max vertical optical depth {float(vol.optical_depth_z().max()):.0f}")
    rr = "default (5)" if args.rr_depth is None else str(args.rr_depth)
    print(f"{mi.variant()}, {args.size} x {args.size}, default_spec (sunsky, ground), max_depth {args.max_depth}, "
          f"rr_depth {rr}, budget {args.budget:.0f} s per integrator")
    masks = {}

    def mask(size):
        if size not in masks:
            t0 = time.perf_counter()
            masks[size] = cloudy_mask(default_spec(vol, width=size, height=size), vol)[0]
            print(f"cloudy pixels at {size} x {size} (primary transmittance < 0.9): {int(masks[size].sum())} of "
                  f"{masks[size].size} ({time.perf_counter() - t0:.1f} s)", flush=True)
            if not masks[size].any():
                raise SystemExit("no cloudy pixels in this view")
        return masks[size]

    def spec_at(size):
        return default_spec(vol, width=size, height=size)

    mask(args.size)
    N = args.size
    runs = [(name, None) for name in args.integrators if name == "volpath"]
    if "majorant" in args.integrators:
        runs += [("majorant", c) for c in args.cells]
    rows = []
    for name, cell in runs:
        label = name if cell is None or len(args.cells) == 1 else f"maj c={cell}"
        # the cost of one sample per pixel, probed at 1/8 of the size; measured at the largest of
        # N, N/2, N/4, N/8 where 4 passes of 1 spp fit the budget, times scaled to N x N
        p = max(8, N // 8)
        t_compile = time_one(spec_at(p), vol, name, args, cell)  # compile (or the kernel cache) and run
        cost_px = time_one(spec_at(p), vol, name, args, cell) / p ** 2
        size = next((s for s in (N, N // 2, N // 4) if s > p and 4 * cost_px * s * s <= args.budget), p)
        t_one = time_one(spec_at(size), vol, name, args, cell) if size != p else cost_px * p * p
        r = measure(label, spec_at(size), vol, name, args, args.budget, mask(size), t_one,
                    pixel_ratio=(N / size) ** 2, cell=cell)
        r["compile"] = t_compile
        rows.append(r)
        print(f"  {label}: 1st render {t_compile:.1f} s, measured at {size} x {size}: {r['passes']} x {r['spp']} spp "
              f"in {r['wall']:.1f} s", flush=True)
        if name == "volpath" and size < N and "majorant" in args.integrators:
            c = args.cells[0]  # the same reduced image with the majorant tracker
            t_m = time_one(spec_at(size), vol, "majorant", args, c)
            r = measure("majorant" if len(args.cells) == 1 else f"maj c={c}", spec_at(size), vol, "majorant", args,
                        args.budget / 3, mask(size), t_m, pixel_ratio=(N / size) ** 2, cell=c)
            r["compile"] = t_m
            rows.append(r)
            print(f"  majorant at the same size: {r['passes']} x {r['spp']} spp in {r['wall']:.1f} s", flush=True)

    T = args.equal_time
    print()
    print(f"times for {N} x {N} pixels (measured at the size given; per-spp times scaled by the pixel count)")
    print(f"{'integrator':10s} {'measured':>9s} {'1st render':>10s} {'passes x spp':>13s} {'s/spp':>8s} {'paths/s':>9s} "
          f"{'RSE(run)':>8s} {'RSE@' + f'{T:g}' + 's':>9s} {'t(1% RSE)':>10s} {'cloudy mean +- se':>22s}")
    for r in rows:
        r["rse_T"] = rse_after(r, T)
        r["t_target"] = T * (r["rse_T"] / TARGET_RSE) ** 2
        print(f"{r['label']:10s} {str(r['size']) + chr(178):>9s} {r['compile']:9.1f}s {r['passes']:>6d} x {r['spp']:<5d} "
              f"{r['s_per_spp']:8.3f} {r['paths']:9.3g} {r['rse_now']:8.4f} {r['rse_T']:9.4f} "
              f"{fmt_time(r['t_target']):>10s} {r['cloudy_mean']:11.5f} +- {r['cloudy_se']:.5f}")
    vol_rows = [r for r in rows if r["label"] == "volpath"]
    maj_rows = [r for r in rows if r["label"].startswith("maj")]
    if vol_rows and maj_rows:
        v = vol_rows[0]
        print()
        for m in maj_rows:
            speed = v["t_target"] / m["t_target"]
            per_sample = v["s_per_spp"] / m["s_per_spp"]
            print(f"speed-up majorant ({m['size']}{chr(178)}) / volpath ({v['size']}{chr(178)}) at equal error "
                  f"(t(1%) ratio): {speed:.3g}x = {per_sample:.3g}x samples per second x "
                  f"{speed / per_sample:.3g} (relative per-sample variance, volpath / majorant)")
        m = next(m for m in maj_rows if m["size"] == v["size"]) if any(m["size"] == v["size"] for m in maj_rows) else None
        if m is not None:
            z = (m["cloudy_mean"] - v["cloudy_mean"]) / math.hypot(m["cloudy_se"], v["cloudy_se"])
            print(f"cloudy means at {v['size']}{chr(178)}: majorant - volpath = {m['cloudy_mean'] - v['cloudy_mean']:+.5f} "
                  f"({100 * (m['cloudy_mean'] / v['cloudy_mean'] - 1):+.1f}% of volpath, {z:+.1f} se)")
        if args.rr_depth is None or args.rr_depth < 1000:
            print("(volpath plays Russian roulette at every null collision past rr_depth: where its mean reads low\n"
                  " and its per-sample variance looks small, its RSE and t(1%) are optimistic, and so is its\n"
                  " side of the speed-up; --rr-depth 100000 --max-depth N compares both without roulette)")
    print(f"\ntotal wall time {time.perf_counter() - t_start:.0f} s")


if __name__ == "__main__":
    main()
