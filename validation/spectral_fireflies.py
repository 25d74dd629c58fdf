"""Issue 38 (chroma38): where the spectral mode's colour fireflies come from. Renders the study's front view of the
demo supercell in ``llvm_ad_spectral`` with persistent lanes, keeps every sample's CIE XYZ (each sample has its own
slot, ``kernel.plugins.lanes``), lists the brightest samples with their pixel, pass and number in the pass, and
(``--trace``) re-runs one sample alone with the loops evaluated step by step, printing its 4 lanes' throughput after
every stage of the path loop and, at the end, each stage's summed log change per lane: which weight blew up.

    .venv/bin/python validation/spectral_fireflies.py [--elevation 4] [--spp 1024] [--passes 8] [--seed 1]
        [--pixel ROW,COL] [--size 64x48] [--trace PIXEL,PASS,SAMPLE] [--before]

``--before``: the code as before chroma38 (directions from the phase's channel-mean density, Mitsuba's wavelengths;
``benchmarks/spectral.py``'s patches). A sample is the same path with and without ``--pixel`` (its random numbers
depend on its pass's seed and its number only). Tracing takes minutes (thousands of scatterings, each stage a
kernel launch). Findings: docs/spectral.md, "The colour fireflies".
"""
from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

STAGES = ("roulette", "free_flight", "emitters_hit", "vertex", "nee", "aureole_nee", "sample_phase", "sample_bsdf")


def scene(args):
    from weather_mi.optics.air import Atmosphere
    from weather_mi.study.runs import CONFIGS, load_scene, view
    w, h = (int(v) for v in args.size.split("x"))
    cfg = replace(CONFIGS["quick"], width=w, height=h)
    vol, _ = load_scene("demo-supercell", cfg)
    spec = view(vol, "front", cfg)
    return replace(spec, sun=replace(spec.sun, elevation=args.elevation), atmosphere=Atmosphere(), seed=args.seed), vol


def samples(args, spec, vol, pixels=None) -> np.ndarray:
    """(samples per pixel, pixels, 3) CIE XYZ of every sample, pass-major (``pixels``: flat indices or None)."""
    from weather_mi.kernel.plugins import lanes
    from weather_mi.reference import passes
    from weather_mi.reference.render import render_reference
    got, own_run, own_passes = [], lanes._Launch.run, passes.render_passes

    def run(self, *a):
        v = own_run(self, *a)
        got.append(v.copy())
        return v
    lanes._Launch.run = run
    passes.render_passes = lambda scene, p, persistent=None, pixels_=None, **k: own_passes(scene, p, persistent, pixels)
    try:
        render_reference(spec, vol, spp=args.spp, passes=args.passes, progress=False, variant="llvm_ad_spectral")
    finally:
        lanes._Launch.run, passes.render_passes = own_run, own_passes
    n_pix = spec.width * spec.height if pixels is None else len(pixels)
    return np.concatenate(got).reshape(-1, n_pix, 3)


class _Traced(Exception):
    """The traced sample is done: the render that ran it stops here."""


def trace(args, spec, vol, pixel: int, pass_i: int, sample: int) -> None:
    """Sample ``sample`` of pass ``pass_i`` in ``pixel`` alone, loops evaluated: its lanes after every stage."""
    import drjit as dr
    import mitsuba as mi
    from weather_mi.kernel.plugins import lanes, path_loop
    from weather_mi.reference import passes
    from weather_mi.reference.render import render_reference
    log = {s: np.zeros(4) for s in STAGES}

    def body(self, sampler, p):
        v = None
        for s in STAGES:
            before = np.array([float(p.throughput[i][0]) for i in range(4)])
            out = getattr(self, s)(*((sampler, p) if s in ("roulette", "free_flight") else
                                     (p, v) if s == "emitters_hit" else (sampler, p, v)))
            v = out if s == "free_flight" else v
            after = np.array([float(p.throughput[i][0]) for i in range(4)])
            if np.all(before > 0) and np.all(after > 0):
                log[s] += np.log(after / before)
            if s == "sample_bsdf" and int(p.depth[0]) % args.every == 0:
                wl = [round(float(p.ray.wavelengths[i][0]), 1) for i in range(4)]
                res = [float(p.result[i][0]) for i in range(4)]
                print(f"depth {int(p.depth[0])}: wavelengths {wl} throughput {np.array2string(after, precision=3)} "
                      f"radiance {np.array2string(np.array(res), precision=3)}")
        return sampler, p

    def one(scene, *a, **k):
        dr.set_flag(dr.JitFlag.SymbolicLoops, False)
        sensor = scene.sensors()[0]
        w, h = (int(v) for v in sensor.film().crop_size())
        medium = sensor.get_medium()
        launch = lanes._Launch(sensor, medium, scene.integrator()._path_loop(scene, medium), w, h, mi.UInt32([pixel]),
                               1, mi.UInt32([sample]),
                               mi.UInt64(np.array([lanes._splitmix64(passes.pass_seed(args.seed, pass_i))], np.uint64)),
                               mi.Float([1.0 / (args.spp // args.passes)]) if lanes.STRATIFIED_WAVELENGTHS else None)
        print("the sample's XYZ", launch.run(lanes.job_sampler_class(), 1, 1, 0)[0])
        raise _Traced  # (not StopIteration: raised inside the passes' generator it would become a RuntimeError)
    own_body, own_passes = path_loop.PathLoop.body, passes.render_passes
    path_loop.PathLoop.body, passes.render_passes = body, one
    try:
        render_reference(spec, vol, spp=args.spp, passes=args.passes, progress=False, variant="llvm_ad_spectral")
    except _Traced:
        pass
    finally:
        path_loop.PathLoop.body, passes.render_passes = own_body, own_passes
        dr.set_flag(dr.JitFlag.SymbolicLoops, True)
    print("summed log change of each lane's throughput, by stage:")
    for s, v in log.items():
        print(f"  {s}: {np.array2string(v, precision=2)}")


def main(argv=None):
    import colour
    from spectral import patched
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--elevation", type=float, default=4.0)
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--passes", type=int, default=8)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--size", default="64x48")
    ap.add_argument("--pixel", help="ROW,COL: that pixel's samples only")
    ap.add_argument("--trace", help="PIXEL,PASS,SAMPLE (flat pixel index): trace that sample")
    ap.add_argument("--every", type=int, default=250, help="with --trace: print every this many scatterings")
    ap.add_argument("--top", type=int, default=8)
    ap.add_argument("--before", action="store_true", help="the code as before chroma38")
    ap.add_argument("--mode", default="spectral",
                    help="a mode of benchmarks/spectral.py whose patches apply (e.g. 'spectral, linear')")
    args = ap.parse_args(argv)
    spec, vol = scene(args)
    with patched("spectral, before chroma38" if args.before else args.mode):
        if args.trace:
            return trace(args, spec, vol, *(int(v) for v in args.trace.split(",")))
        pixels = None
        if args.pixel:
            r, c = (int(v) for v in args.pixel.split(","))
            pixels = [r * spec.width + c]
        xyz = samples(args, spec, vol, pixels)
    rgb = np.asarray(colour.XYZ_to_RGB(xyz, "sRGB", illuminant=None, chromatic_adaptation_transform=None,
                                       apply_cctf_encoding=False))
    per = args.spp // args.passes
    size = np.abs(rgb).max(axis=-1)
    med = np.median(size)
    print(f"{xyz.shape[0] * xyz.shape[1]} samples; the median sample's largest |R|, |G|, |B|: {med:.4f}; samples above "
          + ", ".join(f"{k} x: {int(np.sum(size > k * med))}" for k in (100, 1000, 10000))
          + f"; the largest {size.max() / med:.0f} x; samples with a channel above "
          + ", ".join(f"{v:g}: {int(np.sum(size > v))}" for v in (10.0, 30.0, 100.0)))
    print("| pixel (row, col; flat) | pass | sample in the pass | XYZ | linear sRGB | x the median |")
    print("|---|---|---|---|---|---|")
    for i in np.argsort(-size.ravel())[: args.top]:
        layer, k = divmod(int(i), xyz.shape[1])
        pix = k if pixels is None else pixels[k]
        print(f"| ({pix // spec.width}, {pix % spec.width}; {pix}) | {layer // per} | {layer % per} | "
              f"{np.array2string(xyz[layer, k], precision=3)} | {np.array2string(rgb[layer, k], precision=3)} | "
              f"{size[layer, k] / np.median(size):.0f} |")


if __name__ == "__main__":
    main()
