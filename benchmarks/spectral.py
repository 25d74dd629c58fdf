"""The spectral ground truth's cost (issue 38 part 2): the reference renderer in ``llvm_ad_spectral`` (4
wavelengths a path, the phase tables every 25 nm) against ``llvm_ad_rgb`` on the demo supercell (the study's
front view, ``study.runs.view``), paired: the two modes alternate in one process, kernels compiled first, and
each round's ratio is taken between renders run next to each other.

    .venv/bin/python benchmarks/spectral.py [--size 64x48] [--spp 64] [--passes 8] [--rounds 3] [--elevation 20]
                                            [--atmosphere clear|none] [--before-chroma] [--firefly-k 10]
    .venv/bin/python benchmarks/spectral.py --phase [--lanes 1048576] [--rounds 5]

Per round: each mode's seconds (wall, and the process's CPU seconds over all threads: on a loaded machine
the wall time measures the other processes too) and its luminance RSE over the cloud pixels
(``estimates.cloud_mask``): the standard error of Y over the passes over Y, averaged over the cloud pixels
(``estimates.luminance_rse``). The spectral mode's
time to the same RSE over the RGB mode's is (t RSE^2)_spectral / (t RSE^2)_RGB (RSE falls as
1 / sqrt(samples)); target: at most 1.5. Medians over rounds are printed last. The colour noise
(``reference.colour_noise``, what the luminance RSE does not count): the RSE of each linear sRGB channel, the
chroma se (the standard error of each cloud pixel's CIE 1976 (u', v'), mean over the cloud pixels), and the
fireflies (cloud pixels in which one pass of one channel exceeds ``--firefly-k`` x the median of the pixel's
passes); the time to the same chroma se and to the same R, G, B RSE, as above. ``--before-chroma`` adds the spectral
mode as before chroma38: directions from the phase's channel-mean density ("mean density"), Mitsuba's wavelengths
("mitsuba wavelengths"), both ("before chroma38"). Each mode's patches are applied by one context manager
(``patched``) and undone after its render; each render's arrays and Dr.Jit's cached memory are released after it. ``--channel-rse`` also prints
the figure with ``Image.metadata["noise"]["rse_mean"]`` (the R, G, B channels' mean se over their mean: the
spectral mode's R, G, B come from X, Y, Z through sRGB's matrix, whose chroma noise it counts).

``--atmosphere clear`` (default, as ``render`` runs): both modes have the air inside the box as well as on the
sun's path (the spectral mode over wavelength: ``kernel/spectral_air.py``); ``none``: no air. ``--phase-twice`` adds
the spectral mode with every phase value evaluated twice (the tables' reads' share of the render time, the paths
unchanged); ``--linear`` adds the spectral mode with the phase tables bilinear in wavelength (4 corners a lane)
instead of one wavelength node a lane (what renders read); ``--three-nodes`` adds the spectral mode as it was before
the tables every 25 nm (with ``--atmosphere none`` only: the box's air by wavelength needs the tables); ``--without-box-air`` both modes without the box's air (the air on the sun's path only:
``kernel.medium.air_in_medium`` None, a different scene; the spectral mode as it was before its box air was wired);
``--medium-lookups`` adds both modes with the trackers' medium lookups per step (as between c0780af and
spectralair38c: no texel interpolant, no split RGB flights, the box's air's optical depth per empty cube).

``--lane-directions`` adds the spectral mode with directions from the R, G, B tables ("lane channels", as chroma38),
with the lane that lends its table picked uniformly ("uniform lanes") and with each lane's table bilinear ("bilinear
lanes") instead of the renders' draw (``kernel/plugins/lane_directions.py``: one lane's own table, picked by
throughput); ``--uniform-lanes`` the second alone; ``--independent-wavelengths`` the spectral mode without the
stratified wavelengths; ``--as-main`` both undone (main 7ce4129's spectral mode); ``--mix a,b,c,d`` (repeatable) the
wavelengths drawn from that mixture of Mitsuba's density, xbar, ybar and zbar.

``--phase``: the mixture plugin alone in ``llvm_ad_spectral``, ``eval_pdf`` and ``sample`` on the demo
supercell's five species (their tables at "test" quality, a random 16^3 weight grid) at random directions and
wavelengths: ns per lane with the tables every 25 nm (``spectral_values``) against the R, G, B tables
interpolated (without them, as before), alternating, in one process.
"""
from __future__ import annotations

import argparse
import contextlib
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

MODES = {"rgb": "llvm_ad_rgb", "spectral": "llvm_ad_spectral"}


def phase_cost(lanes: int, rounds: int) -> None:
    """The plugin's ns per lane with and without the tables by wavelength (module docstring)."""
    import drjit as dr
    import mitsuba as mi

    import weather_mi as wm
    from weather_mi.kernel.plugins.hydrometeor_mixture import prepare_tables
    from weather_mi.kernel.plugins.spectral_phase import prepare_spectral
    from weather_mi.optics.phase import for_species
    from weather_mi.optics.phase.spectral_tables import SPECTRAL_NM, stacks_for
    wm.set_variant("llvm_ad_spectral")
    species = [wm.species.preset("physical")[n] for n in ("cloud", "rain", "ice", "snow", "graupel")]
    tables = for_species(species, quality="test")
    nodes, values = prepare_tables(tables)
    sv = prepare_spectral(nodes, stacks_for(species, tables, quality="test"))
    weights = np.random.default_rng(0).random((16, 16, 16, 5)).astype(np.float32)
    base = {"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]), "values": mi.TensorXf(values),
            "weights": mi.TensorXf(weights)}
    tables = {"spectral_values": mi.TensorXf(sv), "spectral_nm": mi.TensorXf(SPECTRAL_NM.astype(np.float32))}
    plugins = {"R, G, B interpolated": mi.load_dict(base),
               "every 25 nm, bilinear": mi.load_dict({**base, **tables}),
               "every 25 nm, one node a lane": mi.load_dict({**base, **tables, "spectral_interpolation": "stochastic"})}
    rng = np.random.default_rng(1)
    u = rng.random((8, lanes))
    mei = dr.zeros(mi.MediumInteraction3f, lanes)
    mei.p = mi.Point3f(u[0], u[1], u[2])
    mei.wi = dr.normalize(mi.Vector3f(u[3] - 0.5, u[4] - 0.5, u[5] - 0.5))
    mei.sh_frame = mi.Frame3f(mei.wi)
    mei.wavelengths = mi.Spectrum(*(mi.Float(360 + 470 * rng.random(lanes)) for _ in range(4)))
    wo = dr.normalize(mi.Vector3f(u[6] - 0.5, u[7] - 0.5, u[5] - 0.4))
    ctx = mi.PhaseFunctionContext(None)
    dr.eval(mei, wo)
    s1, s2 = mi.Float(u[0]), mi.Point2f(u[1], u[2])
    times = {k: [] for k in plugins}
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    for r in range(rounds + 1):
        for name, ph in plugins.items():
            dr.kernel_history()  # clear
            value, pdf = ph.eval_pdf(ctx, mei, wo)
            wo2, weight, pdf2 = ph.sample(ctx, mei, s1, s2)
            dr.eval(value, pdf, wo2, weight, pdf2)
            dr.sync_thread()
            ms = sum(k.get("execution_time", 0.0) for k in dr.kernel_history())  # the kernels' own time (ms)
            if r:  # round 0 compiles
                times[name].append(ms * 1e6 / lanes)
    for name, ts in times.items():
        print(f"{name}: eval_pdf + sample {np.median(ts):.0f} ns per lane (rounds: {', '.join(f'{t:.0f}' for t in ts)})")


def timed_render(spec, vol, spp: int, passes: int, variant: str, cloud, firefly_k: float) -> dict:
    """One render: wall and CPU seconds, the luminance RSE, the channel-mean RSE and the colour noise
    (``reference.colour_noise``: per-channel RSE, chroma se, fireflies); the render's arrays freed after."""
    from weather_mi.reference.colour_noise import colour_noise
    from weather_mi.reference.estimates import luminance_rse
    from weather_mi.reference.render import render_reference
    means = []
    wall, cpu = time.perf_counter(), time.process_time()
    img = render_reference(spec, vol, spp=spp, passes=passes, progress=False, variant=variant,
                           on_pass=lambda im: means.append(np.asarray(im.radiance, np.float64).copy()))
    out = {"wall": time.perf_counter() - wall, "cpu": time.process_time() - cpu, "rse": luminance_rse(means, cloud),
           "rse_ch": float(img.metadata["noise"]["rse_mean"]), **colour_noise(means, cloud, firefly_k)}
    del img, means
    release_kernel_memory()
    return out


def release_kernel_memory() -> None:
    """Frees what a render left behind: Python's garbage (the scene, its grids) and Dr.Jit's cached allocations,
    so that the next mode's render starts from the same memory."""
    import gc

    import drjit as dr
    gc.collect()
    dr.sync_thread()
    dr.flush_malloc_cache()


def main(argv=None):
    from weather_mi.optics.air import Atmosphere
    from weather_mi.reference.estimates import cloud_mask
    from weather_mi.reference.render import render_reference
    from weather_mi.study.runs import CONFIGS, load_scene, view
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="64x48")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--passes", type=int, default=8)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--elevation", type=float, default=20.0)
    ap.add_argument("--lighting", default="front")
    ap.add_argument("--atmosphere", choices=("clear", "none"), default="clear")
    ap.add_argument("--channel-rse", action="store_true", help="also the ratio with the channel-mean RSE")
    ap.add_argument("--phase", action="store_true", help="the phase plugin alone (module docstring)")
    ap.add_argument("--three-nodes", action="store_true",
                    help="also the spectral mode with the R, G, B tables interpolated (as before the 25 nm tables)")
    ap.add_argument("--linear", action="store_true",
                    help="also the spectral mode with the phase tables bilinear in wavelength (as before the one-node "
                         "stochastic reads, ``spectral_interpolation`` 'linear')")
    ap.add_argument("--phase-twice", action="store_true",
                    help="also the spectral mode with every phase value evaluated twice (the second kept alive, "
                         "unused): the cost of the tables' reads in the render, with the paths unchanged")
    ap.add_argument("--without-box-air", action="store_true",
                    help="also both modes without the box's air (the spectral one as before it was wired)")
    ap.add_argument("--medium-lookups", action="store_true",
                    help="also both modes with the trackers' medium lookups per step (no texel interpolant, no split "
                         "RGB flights, the box's air's optical depth per empty cube)")
    ap.add_argument("--before-chroma", action="store_true",
                    help="also the spectral mode with directions from the phase's channel-mean density ('mean density'), "
                         "with Mitsuba's wavelengths ('mitsuba wavelengths') and with both ('before chroma38')")
    ap.add_argument("--lane-directions", action="store_true",
                    help="also the spectral mode with directions from the R, G, B tables in the throughput's shares "
                         "('lane channels', as chroma38), from one lane's table picked uniformly ('uniform lanes') and "
                         "from the lanes' tables bilinear in wavelength ('bilinear lanes')")
    ap.add_argument("--independent-wavelengths", action="store_true",
                    help="also the spectral mode with each sample's wavelengths independent of the pixel's others "
                         "('independent wavelengths'; ``lanes.STRATIFIED_WAVELENGTHS`` False)")
    ap.add_argument("--as-main", action="store_true",
                    help="also the spectral mode as before spectralmis38: directions from the R, G, B tables "
                         "('lane channels') and each sample's wavelengths its own ('independent wavelengths')")
    ap.add_argument("--uniform-lanes", action="store_true",
                    help="also the spectral mode with the lane that draws a direction picked uniformly")
    ap.add_argument("--mix", action="append", default=[],
                    help="also the spectral mode with the wavelengths drawn from this mixture of Mitsuba's density, "
                         "xbar, ybar, zbar (4 weights, e.g. 0.8,0.1,0.05,0.05; repeatable; ``wavelengths.MIX``)")
    ap.add_argument("--rebuilt-tables", action="store_true",
                    help="also the spectral mode with its phase tables by wavelength and their alias tables built "
                         "anew for each render (as before spectralcost38b: not kept across renders)")
    ap.add_argument("--lanes", type=int, default=1 << 20)
    ap.add_argument("--firefly-k", type=float, default=10.0,
                    help="a firefly: a cloud pixel with one pass > k x the median of its passes in a channel")
    args = ap.parse_args(argv)
    if args.phase:
        return phase_cost(args.lanes, args.rounds)
    if args.passes < 2:
        ap.error("--passes must be >= 2 (the RSE is the spread over passes)")
    w, h = (int(v) for v in args.size.split("x"))
    cfg = replace(CONFIGS["quick"], width=w, height=h)
    vol, _ = load_scene("demo-supercell", cfg)
    spec = view(vol, args.lighting, cfg)
    spec = replace(spec, sun=replace(spec.sun, elevation=args.elevation),
                   atmosphere=Atmosphere() if args.atmosphere == "clear" else None)
    cloud = cloud_mask(spec, vol)
    modes = dict(MODES)
    if args.three_nodes:
        modes["spectral, 3 nodes"] = "llvm_ad_spectral"
    if args.linear:
        modes["spectral, linear"] = "llvm_ad_spectral"
    if args.phase_twice:
        modes["spectral, phase twice"] = "llvm_ad_spectral"
    if args.medium_lookups:
        modes["rgb, medium lookups"] = "llvm_ad_rgb"
        modes["spectral, medium lookups"] = "llvm_ad_spectral"
    if args.before_chroma:
        for name in ("mean density", "mitsuba wavelengths", "before chroma38"):
            modes[f"spectral, {name}"] = "llvm_ad_spectral"
    if args.lane_directions:
        for name in ("lane channels", "uniform lanes", "bilinear lanes"):
            modes[f"spectral, {name}"] = "llvm_ad_spectral"
    if args.independent_wavelengths:
        modes["spectral, independent wavelengths"] = "llvm_ad_spectral"
    if args.as_main:
        modes["spectral, as main"] = "llvm_ad_spectral"
    if args.uniform_lanes and not args.lane_directions:
        modes["spectral, uniform lanes"] = "llvm_ad_spectral"
    if args.rebuilt_tables:
        modes["spectral, tables rebuilt"] = "llvm_ad_spectral"
    for m in args.mix:
        modes[f"spectral, mix {m}"] = "llvm_ad_spectral"
    if args.without_box_air:
        modes["rgb, no box air"] = "llvm_ad_rgb"
        modes["spectral, no box air"] = "llvm_ad_spectral"
    for mode, variant in modes.items():  # compile (and build the spectral tables) first, as measured: the kernels
        with patched(mode):                # of 1 spp differ
            render_reference(replace(spec, seed=99), vol, spp=args.spp, passes=args.passes, progress=False,
                             variant=variant)
        release_kernel_memory()
    print(f"demo supercell, {args.lighting} view, sun {args.elevation:g} deg, {w}x{h}, {args.spp} spp in "
          f"{args.passes} passes, --atmosphere {args.atmosphere}, {int(cloud.sum())} cloud pixels; fireflies: cloud "
          f"pixels with one pass > {args.firefly_k:g} x the median of its passes in a channel")
    print("| round | mode | wall s | CPU s | luminance RSE | RSE R / G / B | chroma se (u'v') | fireflies | CPU time ratio "
          "to RGB | time to the same luminance RSE over RGB's (wall, CPU) | to the same chroma se (CPU) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    keys = ("wall", "cpu", "chroma", "R", "G", "B") + (("ch",) if args.channel_rse else ())
    ratios = {m: {k: [] for k in keys} for m in modes if m != "rgb"}
    fireflies = {m: [] for m in modes}
    for r in range(args.rounds):
        got = {}
        for mode, variant in (list(modes.items()) if r % 2 == 0 else list(modes.items())[::-1]):  # alternate
            with patched(mode):
                got[mode] = timed_render(replace(spec, seed=r), vol, args.spp, args.passes, variant, cloud,
                                         args.firefly_k)
        b = got["rgb"]
        for mode, g in got.items():
            fireflies[mode].append(g["fireflies"])
            if mode != "rgb":
                for k in ("wall", "cpu"):
                    ratios[mode][k].append(g[k] * g["rse"] ** 2 / (b[k] * b["rse"] ** 2))
                ratios[mode]["chroma"].append(g["cpu"] * g["chroma_se"] ** 2 / (b["cpu"] * b["chroma_se"] ** 2))
                for c, name in enumerate("RGB"):
                    ratios[mode][name].append(g["cpu"] * g["rse_rgb"][c] ** 2 / (b["cpu"] * b["rse_rgb"][c] ** 2))
                if args.channel_rse:
                    ratios[mode]["ch"].append(g["cpu"] * g["rse_ch"] ** 2 / (b["cpu"] * b["rse_ch"] ** 2))
            eff = "1, 1 | 1" if mode == "rgb" else (f"{ratios[mode]['wall'][-1]:.2f}, {ratios[mode]['cpu'][-1]:.2f} | "
                                                   f"{ratios[mode]['chroma'][-1]:.2f}")
            rgb_rse = " / ".join(f"{v:.4f}" for v in g["rse_rgb"])
            print(f"| {r} | {mode} | {g['wall']:.1f} | {g['cpu']:.1f} | {g['rse']:.4f} | {rgb_rse} | {g['chroma_se']:.5f} "
                  f"| {g['fireflies']} | {g['cpu'] / b['cpu']:.2f} | {eff} |", flush=True)
    for mode, rs in ratios.items():
        print(f"median time to the same luminance RSE, {mode} / RGB: wall {np.median(rs['wall']):.2f}, "
              f"CPU {np.median(rs['cpu']):.2f} (target <= 1.5); to the same chroma se (CPU) "
              f"{np.median(rs['chroma']):.2f}; to the same R / G / B RSE (CPU) "
              f"{' / '.join(f'{np.median(rs[c]):.2f}' for c in 'RGB')}")
        if args.channel_rse:
            print(f"  with the channel-mean RSE (CPU): {np.median(rs['ch']):.2f}")
    print("fireflies per render: " + "; ".join(f"{m} {', '.join(str(n) for n in f)}" for m, f in fireflies.items()))


@contextlib.contextmanager
def patched(mode: str):
    """The patches of ``mode`` (its name's ending: :func:`three_nodes`, :func:`no_box_air`, :func:`linear`,
    :func:`phase_twice`, :func:`medium_lookups`) for the duration of the block, undone after it."""
    with contextlib.ExitStack() as stack:
        for suffixes, patch in ((("3 nodes",), three_nodes), (("no box air",), no_box_air), (("linear",), linear),
                                (("twice",), phase_twice), (("lookups",), medium_lookups),
                                (("mean density", "before chroma38"), mean_density),
                                (("mitsuba wavelengths", "before chroma38"), mitsuba_wavelengths),
                                (("lane channels", "as main"), lane_channels), (("uniform lanes",), uniform_lanes),
                                (("bilinear lanes",), bilinear_lanes), (("tables rebuilt",), tables_rebuilt),
                                (("independent wavelengths", "as main"), independent_wavelengths)):
            stack.enter_context(patch(mode.endswith(suffixes)))
        if " mix " in mode:
            stack.enter_context(wavelength_mix(tuple(float(x) for x in mode.split(" mix ")[1].split(","))))
        yield


@contextlib.contextmanager
def tables_rebuilt(on: bool):
    """With ``on``: the spectral phase tables (``kernel.medium.spectral_phase_values``) and the lanes' alias tables
    (``lane_directions._host_tables``) not found among those kept from earlier renders: built anew for this render,
    as every render did before spectralcost38b (the renders after it find them again)."""
    if on:
        from weather_mi.kernel import medium
        from weather_mi.kernel.plugins import lane_directions
        medium._SPECTRAL_VALUES.clear()
        lane_directions._HOST.clear()
    yield


@contextlib.contextmanager
def independent_wavelengths(on: bool):
    """With ``on``: each sample's wavelength uniform its own (as before spectralmis38), not stratified over the
    pixel's samples in the pass (``wavelengths.stratified``)."""
    if not on:
        yield
        return
    from weather_mi.kernel.plugins import lanes
    lanes.STRATIFIED_WAVELENGTHS = False
    try:
        yield
    finally:
        lanes.STRATIFIED_WAVELENGTHS = True


@contextlib.contextmanager
def wavelength_mix(mix):
    """The spectral paths' wavelengths drawn from the mixture ``mix`` (``wavelengths.MIX``) for the block."""
    from weather_mi.kernel.plugins import wavelengths
    own = wavelengths.MIX
    wavelengths.MIX = mix
    wavelengths._CACHE.clear()
    try:
        yield
    finally:
        wavelengths.MIX = own
        wavelengths._CACHE.clear()


@contextlib.contextmanager
def mean_density(on: bool):
    """With ``on``: the spectral mode's directions drawn from the phase function's channel-mean density (as before
    chroma38), not from its R, G, B densities in the throughput's shares (``lane_channels``)."""
    with _path_loop_set(on, by_lane=False, own_lanes=False):
        yield


@contextlib.contextmanager
def lane_channels(on: bool):
    """With ``on``: the spectral mode's directions drawn from the phase's R, G, B densities in the throughput's
    shares by wavelength (``lane_channels``, chroma38), not from one lane's own table (``lane_directions``)."""
    with _path_loop_set(on, own_lanes=False):
        yield


@contextlib.contextmanager
def uniform_lanes(on: bool):
    """With ``on``: the lane whose table draws the direction picked with probability 1/4 each (hero wavelength
    sampling's uniform choice), not in proportion to its throughput (``lane_directions.shares``)."""
    with _path_loop_set(on, lane_shares="uniform"):
        yield


@contextlib.contextmanager
def bilinear_lanes(on: bool):
    """With ``on``: each lane's table bilinear in wavelength (its two nodes; 4 packet loads a lane) instead of one
    node a lane picked at each vertex (``lane_directions.pick_nodes``)."""
    with _path_loop_set(on, lane_nodes="bilinear"):
        yield


@contextlib.contextmanager
def _path_loop_set(on: bool, **attributes):
    """With ``on``: ``attributes`` set on every ``PathLoop`` after its own set-up."""
    if not on:
        yield
        return
    from weather_mi.kernel.plugins import path_loop
    own = path_loop.PathLoop.__init__

    def init(self, *args):
        own(self, *args)
        for k, v in attributes.items():
            setattr(self, k, v)
    path_loop.PathLoop.__init__ = init
    try:
        yield
    finally:
        path_loop.PathLoop.__init__ = own


@contextlib.contextmanager
def mitsuba_wavelengths(on: bool):
    """With ``on``: the spectral paths' wavelengths as Mitsuba's sensor draws them (``sample_rgb_spectrum``), not
    redrawn for colour (``kernel.plugins.wavelengths``)."""
    if not on:
        yield
        return
    from weather_mi.kernel.plugins import wavelengths
    own = wavelengths.redrawn
    wavelengths.redrawn = lambda ray, weight, sample, active: (ray, weight)
    try:
        yield
    finally:
        wavelengths.redrawn = own


@contextlib.contextmanager
def three_nodes(on: bool):
    """With ``on``: the spectral mode as before the tables every 25 nm (R, G, B tables interpolated), by
    leaving out the mixture's ``spectral_values``."""
    if not on:
        yield
        return
    from weather_mi.kernel import medium
    own = medium.spectral_phase_properties
    medium.spectral_phase_properties = lambda vol, nodes=None: own(vol)
    try:
        yield
    finally:
        medium.spectral_phase_properties = own


@contextlib.contextmanager
def linear(on: bool):
    """With ``on``: the spectral mode's phase tables read bilinearly in wavelength (4 corners a lane,
    ``spectral_interpolation`` "linear") instead of one wavelength node a lane at random ("stochastic")."""
    if not on:
        yield
        return
    from weather_mi.kernel import medium
    own = medium.spectral_phase_properties

    def bilinear(vol, nodes=None):
        d = own(vol, nodes)
        return {**d, "spectral_interpolation": "linear"} if "spectral_values" in d else d
    medium.spectral_phase_properties = bilinear
    try:
        yield
    finally:
        medium.spectral_phase_properties = own


@contextlib.contextmanager
def phase_twice(on: bool):
    """With ``on``: every phase value by wavelength (``spectral_value``, ``picked_value``) evaluated a second time
    half the table away (node segment idx +- half of them) with the lanes' wavelengths rotated, kept alive by a
    select that never fires: the extra time is one evaluation's (reads from lines the first did not load), and
    the paths (directions, weights, lengths) are those of the mode without it."""
    if not on:
        yield
        return
    import drjit as dr
    import mitsuba as mi
    from weather_mi.kernel.plugins import hydrometeor_mixture as hm
    own = hm.spectral_value, hm.picked_value

    def twice(f, picked):
        def evaluate(table, grid, n, w, idx, t, wl, *rest):
            flat = rest[3 if picked else 2] if len(rest) > (3 if picked else 2) else ()
            k = grid[2]  # node segments: the codes' (picked) or the corner table's width over a segment's record
            segments = dr.width(table) // (4 * k) - 1 if picked else dr.width(table) // (4 * (k - 1) * (n - len(flat)))
            half = segments // 2
            far = dr.select(idx >= half, idx - half, idx + half)  # half the table away: lines the first did not touch
            x = f(table, grid, n, w, far, t, mi.Spectrum(wl[1], wl[2], wl[3], wl[0]), *rest)
            return mi.Spectrum(f(table, grid, n, w, idx, t, wl, *rest) + dr.select(x < -1.0, 1.0, 0.0))
        return evaluate
    hm.spectral_value, hm.picked_value = twice(own[0], False), twice(own[1], True)
    try:
        yield
    finally:
        hm.spectral_value, hm.picked_value = own


@contextlib.contextmanager
def no_box_air(on: bool):
    """With ``on``: the box's air left out of the medium (``air_in_medium`` None, as the spectral mode was before
    its air was wired; the air on the sun's path stays)."""
    if not on:
        yield
        return
    from weather_mi.kernel import medium, scene_dict
    own = medium.air_in_medium
    medium.air_in_medium = scene_dict.air_in_medium = lambda vol: None
    try:
        yield
    finally:
        medium.air_in_medium = scene_dict.air_in_medium = own


@contextlib.contextmanager
def medium_lookups(on: bool):
    """With ``on``: the walks over a grey grid with the box's air take the medium's lookups per step
    (``trackers._air_on_grey_grid`` False)."""
    if not on:
        yield
        return
    from weather_mi.kernel.plugins import trackers
    own = trackers._air_on_grey_grid
    trackers._air_on_grey_grid = lambda tk, grid: False
    try:
        yield
    finally:
        trackers._air_on_grey_grid = own


if __name__ == "__main__":
    main()
