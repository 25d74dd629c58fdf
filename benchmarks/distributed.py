"""Cost of rendering the reference over Dask (``render_reference(..., client=...)``) against the same
render in this process, at equal spp, and a projection to a cluster.

    .venv/bin/python benchmarks/distributed.py [--seconds 30] [--size 160x120] [--passes 16]
                                               [--wrf ../shared/data/wrf/wrfout_quarter_ss_0130.nc]
                                               [--bandwidth-gbit 10]

Volume: the last time of ``--wrf`` (default the shared supercell when present, else the demo
supercell), physical species; scene ``weather_mi.scene.spec.default_spec``. The spp is chosen from a short
calibration render so that the in-process render lasts about ``--seconds``. Then, with the same seed
and spp: in process; LocalCluster(1 worker x 2 threads); LocalCluster(2 workers x 1 thread). Each
cluster first renders a 1-spp warm-up (worker start, imports, kernel compilation: a cost paid once per
worker, reported apart). Columns: wall seconds of the render, ratio to in-process, overhead, and
whether the image is bit-identical to the in-process one.

Projection (1024x768 at 1% mean RSE over cloud pixels, 1..512 workers), from measured numbers: the
samples per second of one worker (this machine's in-process render, scaled by pixel count), the spp
that 1% needs (RSE ~ 1/sqrt(spp), from the in-process render's own RSE), the client's cost per pass
(receiving a 1024x768x3 float32 image over ``--bandwidth-gbit`` + the Welford merge, measured here at
1024x768) and the scheduler's cost per task (measured: no-op tasks per second). Passes: 4 per worker,
at least 16. The client merges passes one after another, so the render cannot finish before
passes x client cost: that is the bottleneck once it exceeds the workers' compute time.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

# this file is named distributed.py: its folder must not shadow the dask.distributed package
_here = str(Path(__file__).resolve().parent)
sys.path[:] = [p for p in sys.path if os.path.abspath(p or ".") != _here]
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

DEFAULT_WRF = Path(__file__).resolve().parents[2] / "shared" / "data" / "wrf" / "wrfout_quarter_ss_0130.nc"


def _volume(wrf):
    import weather_mi as wm
    hyd = wm.open_wrf(wrf) if wrf and Path(wrf).is_file() else wm.synthetic.supercell()
    return wm.optical_volume(hyd, species="physical"), str(wrf if wrf and Path(wrf).is_file() else "demo supercell")


def _timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def scheduler_task_cost_s(client, n: int = 400) -> float:
    """Seconds of scheduler + client per task: n no-op tasks submitted and gathered."""
    _, dt = _timed(lambda: client.gather(client.map(lambda i: i, range(n), pure=False)))
    return dt / n


def merge_cost_s(width: int = 1024, height: int = 768, repeats: int = 5) -> float:
    """Seconds of the client's Welford update of one (H, W, 3) pass (render_reference's)."""
    from weather_mi.reference.estimates import welford_update
    rng = np.random.default_rng(0)
    mean, m2 = np.zeros((height, width, 3)), np.zeros((height, width, 3))
    raw = rng.random((height, width, 3), dtype=np.float32)
    t0 = time.perf_counter()
    for n in range(1, repeats + 1):
        welford_update(mean, m2, raw.astype(np.float64), n)
    return (time.perf_counter() - t0) / repeats


def projection(per_sample_s: float, rse_at: tuple[float, int], pass_cost_s: float, task_cost_s: float,
               workers=(1, 8, 64, 512), width=1024, height=768, target=0.01):
    """Rows of the projected table: (workers, passes, spp/pass, compute s, client s, wall s, efficiency)."""
    rse, spp = rse_at
    spp_needed = int(np.ceil(spp * (rse / target) ** 2))
    compute_1 = per_sample_s * spp_needed * width * height  # one worker, whole image
    rows = []
    for n in workers:
        passes = max(16, 4 * n)
        per = max(1, spp_needed // passes)
        compute = compute_1 / n
        client = passes * (pass_cost_s + task_cost_s)
        wall = max(compute, client) + pass_cost_s
        rows.append((n, passes, per, compute, client, wall, compute_1 / n / wall))
    knee = np.sqrt(compute_1 / (4 * (pass_cost_s + task_cost_s)))  # compute / n == 4 n x cost per pass
    return spp_needed, rows, float(knee)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=30.0, help="target length of the in-process render")
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--passes", type=int, default=16)
    ap.add_argument("--wrf", default=str(DEFAULT_WRF))
    ap.add_argument("--bandwidth-gbit", type=float, default=10.0, help="network into the client (projection)")
    args = ap.parse_args()
    from weather_mi.reference import cluster
    from weather_mi.reference.render import render_reference
    from weather_mi.scene.spec import default_spec
    w, h = (int(v) for v in args.size.split("x"))
    vol, source = _volume(args.wrf)
    spec = default_spec(vol, width=w, height=h)

    def render(spp, client=None):
        return render_reference(spec, vol, spp=spp, passes=min(args.passes, spp), progress=False, client=client)

    render(1)  # compilation
    _, t_cal = _timed(lambda: render(args.passes))
    spp = max(1, round(args.seconds / t_cal)) * args.passes  # a multiple of the passes
    print(f"volume: {source}, {vol.shape} voxels; image {w}x{h}; {spp} spp in {args.passes} passes "
          f"(calibration: {args.passes} spp in {t_cal:.1f} s)")
    local, t_local = _timed(lambda: render(spp))
    rows = [("in process", t_local, None, True)]
    for label, nw, nt in (("LocalCluster 1 worker x 2 threads", 1, 2), ("LocalCluster 2 workers x 1 thread", 2, 1)):
        client, t_start = _timed(lambda: cluster.local_cluster(nw, threads_per_worker=nt))
        try:
            _, t_warm = _timed(lambda: render(1, client))
            img, t = _timed(lambda: render(spp, client))
            rows.append((label, t, t_start + t_warm, np.array_equal(img.radiance, local.radiance)
                         and np.array_equal(img.stderr, local.stderr)))
            if nw == 2:
                task_cost = scheduler_task_cost_s(client)
                bytes_per_pass = img.metadata["dask"]["bytes_per_pass"]
        finally:
            cluster.close(client)
    print("\n| run | wall s | ratio | overhead | start + warm-up s (once) | bit-identical |\n|---|---|---|---|---|---|")
    for label, t, start, same in rows:
        print(f"| {label} | {t:.1f} | {t / t_local:.3f} | {100 * (t / t_local - 1):+.1f}% | "
              f"{'-' if start is None else f'{start:.1f}'} | {'yes' if same else 'NO'} |")

    merge = merge_cost_s()
    transfer = 1024 * 768 * 3 * 4 * 8 / (args.bandwidth_gbit * 1e9)
    per_sample = t_local / (spp * w * h)
    rse = local.metadata["noise"]["rse_mean"]
    spp_needed, proj, knee = projection(per_sample, (rse, spp), merge + transfer, task_cost)
    print(f"\nmeasured: {per_sample * 1e9:.1f} ns per sample per pixel (in process, 2 cores); cloud RSE {rse:.4f} at "
          f"{spp} spp; {bytes_per_pass} bytes per pass at {w}x{h} ({1024 * 768 * 3 * 4 / 1e6:.1f} MB at 1024x768); "
          f"merge {1e3 * merge:.1f} ms per 1024x768 pass; transfer {1e3 * transfer:.1f} ms per pass at "
          f"{args.bandwidth_gbit:g} Gbit/s; scheduler {1e3 * task_cost:.2f} ms per task")
    print(f"\nprojection: 1024x768 at 1% mean cloud RSE = {spp_needed} spp; a worker = this machine (2 cores)\n")
    print("| workers | passes | spp/pass | compute s | client s (receive + merge) | wall s | efficiency |\n"
          "|---|---|---|---|---|---|---|")
    for n, passes, per, compute, client_s, wall, eff in proj:
        print(f"| {n} | {passes} | {per} | {compute:.0f} | {client_s:.0f} | {wall:.0f} | {100 * eff:.0f}% |")
    print(f"\nthe client's ordered merge becomes the bottleneck near {knee:.0f} workers "
          f"(compute / workers = 4 passes per worker x client cost per pass)")


if __name__ == "__main__":
    main()
