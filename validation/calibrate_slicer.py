"""Calibrate the slicer's "multiple" light model on training storms and judge it on held-out storms,
beside the paper's Table IV modes.

    .venv/bin/python validation/calibrate_slicer.py [-o out/slicer_calibration] [--data ../shared/data]
        [--size 64x48] [--spp 128] [--train-target-rse R] [--target-rse 0.02] [--max-seconds 600] [--iterations 50]
        [--learning-rate 0.15] [--slices 128] [--supersample 2] [--slab-jitter 1]
        [--no-fit] [--noise-floor] [--start defaults|fit-start|fitted.json] [--fit-slices N] [--fit-supersample N]
        [--fit-only] [--fitted fitted.json] [--held-out-only] [--air-target-rse R [--air-max-seconds S]]

1. References (path tracer) for every view, cached as EXR in the output folder (a rerun reuses them);
   training views at --spp, or to --train-target-rse (the loss clips display colours at 1, so that noisy
   references pull the brightest faces down; measured: it did not help the held-out views, and the shipped
   defaults were fitted to --spp 128), the training views with the air (LOW_SUN and TODAY_AIR; the air: 5-10x
   slower to the same noise, cloud RSE 0.13-0.17 at 128 spp) to --air-target-rse (alias --low-sun-target-rse)
   if given, held-out views to --target-rse; a
   reference with the air carries AIR_REFERENCES in its name (one of an older path tracer's air is not read):
   training: the demo supercell, the demo cumulus and the thin demo cumulus (wm.synthetic; the cumulus with
   its condensate x 0.15), the real WRF supercell at 01:00 and 02:00 (wrf/wrfout_quarter_ss_series.nc,
   the held-out one's run at other times) and the WRF plateau at 00:00 (held out: its last time, 09:00,
   with a fifth of the cloud cover), front-, side- and back-lit, and seven views with the sun at 6 deg and the
   clear atmosphere (LOW_SUN: the demo supercell and the WRF supercell at 01:00 and the plateau at 00:00 front-
   and side-lit, the demo cumulus front-lit; issue 38), and every training storm front-, side- and back-lit at
   its own sun with the clear atmosphere (TODAY_AIR, as `view` shows it by default); a training field that is a held-out
   one (the same file and time, or the same mixing ratios in another file) is refused (check_held_out);
   held-out: the real WRF supercell, the WRF Tibetan Plateau file, BOMEX and RICO (from --data),
   front-, side- and back-lit (the sun behind the storm: silver linings, dark cores).
2. Fit the model's parameters with Dr.Jit reverse-mode AD on the training views
   (weather_mi.slicing.calibrate), starting near single scattering (--start fit-start: calibrate.FIT_START)
   or from the shipped defaults (--start defaults: a refit after a change of the model, the new parameters
   at FIT_START's values), or from an earlier fit (--start fitted.json: continue it), in the frames it judges (--slices, the automatic light buffer; 810 s on 2 idle
   cores at the defaults; --fit-slices / --fit-supersample: the fit's frames coarser than the judged ones,
   for a busy machine). Each iteration's loss and the parameters it was measured at are appended to
   fit_steps.jsonl in the output folder (a fit stopped early keeps its iterates; Adam's last step may overshoot
   the best one).
   The slicer's frames, in the fit and the evaluation, average each pixel over --supersample^2 points
   (SliceRenderer.frame(supersample=)) with slab offsets --slab-jitter: the references' pixels are
   box-filtered footprint averages, and a pixel-centre sample differs from them at every edge (held-out
   median CIEDE2000 4.03 centre-sampled, 3.71 with 2 x 2 points, the same model and references).
3. Print, per view, CIEDE2000 and FLIP over cloud pixels for the Table IV modes, the new model with its
   shipped defaults and with the parameters fitted here; write calibration.md and a side-by-side PNG
   (reference | per-species/translucent | new model) of each held-out view, at least 320 px wide.
   --no-fit evaluates the shipped defaults only; --fit-only stops after the fit (fitted.json in the output
   folder: the fit can run beside the held-out references' rendering); --fitted JSON evaluates the
   parameters of an earlier fit's fitted.json (the column named after the file) without fitting;
   --held-out-only leaves the training views out of the tables; --noise-floor adds, per held-out view, the error of a
   second, independent reference (seed 1) against the first: the part of every error that is the
   reference's own Monte Carlo noise.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

import weather_mi as wm  # noqa: E402
from weather_mi.display import metrics  # noqa: E402
from weather_mi.io.image import Image, auto_exposure  # noqa: E402
from weather_mi.slicing import MODES, SliceParams, SliceRenderer  # noqa: E402
from weather_mi.slicing.calibrate import FIT_START, MULTIPLE_PARAMS, TrainingView, calibrate  # noqa: E402
from weather_mi.study.report import side_by_side  # noqa: E402
from weather_mi.display.aerial import with_eye_air  # noqa: E402
from weather_mi.optics.air import Atmosphere  # noqa: E402
from weather_mi.optics.air.inside import with_box_air  # noqa: E402
from weather_mi.io.times import select_times, time_strings  # noqa: E402
from weather_mi.study.runs import (DATA_SCENES, DATA_TIMES, StudyConfig, eye_transmittance, load_scene,  # noqa: E402
                                   low_sun_view, view)

TRAIN_SCENES = ("demo-supercell", "demo-cumulus", "demo-cumulus-thin", "wrf-supercell-0100", "wrf-supercell-0200",
                "wrf-plateau-0000")
# the sun low (LOW_SUN_DEG) with the clear atmosphere (issue 38): the slicer's sun coloured by height, its sky
# scaled and its eye rays' air, against the path tracer with the air in its box and along its eye rays
LOW_SUN_DEG = 6.0
LOW_SUN = f"-{LOW_SUN_DEG:g}deg-clear"
# today's sun (study.runs.view: front/side 35 deg, back 20 deg) with the clear atmosphere, as `view` shows it by
# default (issue 38 part 3, refit38); a lighting ending in LOW_SUN also ends in TODAY_AIR: test LOW_SUN first
TODAY_AIR = "-clear"
TRAIN = [(s, l) for s in TRAIN_SCENES for l in ("front", "side", "back")] + \
    [(s, l + LOW_SUN) for s, l in (("demo-supercell", "front"), ("demo-supercell", "side"), ("demo-cumulus", "front"),
                                   ("wrf-supercell-0100", "front"), ("wrf-supercell-0100", "side"),
                                   ("wrf-plateau-0000", "front"), ("wrf-plateau-0000", "side"))] + \
    [(s, l + TODAY_AIR) for s in TRAIN_SCENES for l in ("front", "side", "back")]
HELD_OUT = [(s, l) for s in ("wrf-supercell", "wrf-plateau", "bomex", "rico") for l in ("front", "side", "back")]
DEFAULT_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
# in the cache name of every reference rendered with the air (here and validation/slicer_low_sun.py): bumped when
# the path tracer's air changes, so that a cached reference of an older air is never read (air2: Eq. 8's weights
# per level and channel, kernel.medium.air_weights; air3: the air's albedo point-wise, kernel/plugins/air_albedo.py;
# air4: ozone's band average in the RGB channels, optics/air/ozone.channel_cross_section_m2; air5: the views with the
# air lit by the air's own sky, Sky("air"), as render's default with the air, not Hosek-Wilkie's sea-level sky, which
# already holds the whole column's scattering and with the box's air counted it twice: study.runs.low_sun_view)
AIR_REFERENCES = "air5"


def cache_name(tag: str, spec, plan: str) -> str:
    """The EXR name of a cached reference: ``tag``, the size, the sampling plan, the seed (if not 0) and, for a
    view with the air, AIR_REFERENCES."""
    seed = "" if spec.seed == 0 else f"_seed{spec.seed}"
    air = "" if spec.atmosphere is None else f"_{AIR_REFERENCES}"
    return f"{tag}_{spec.width}x{spec.height}_{plan}{seed}{air}_reference.exr"


def field_of(scene: str, data) -> tuple | None:
    """(file, timestamp, digest of its mixing ratios at that time) of a data scene; None for a demo storm or
    a file absent from ``data``. The digest names the field whatever file holds it (the held-out 01:30
    supercell is also the series file's third time)."""
    if scene not in DATA_SCENES or not (Path(data) / DATA_SCENES[scene][0]).is_file():
        return None
    path = Path(data) / DATA_SCENES[scene][0]
    if path.suffix != ".nc":  # an LES text file: one field
        return path.resolve(), None, hashlib.sha256(path.read_bytes()).hexdigest()
    import xarray as xr
    with xr.open_dataset(path) as ds:
        labels = time_strings(ds)
        i = select_times(labels, DATA_TIMES.get(scene, -1), str(path))[0]
        digest = hashlib.sha256()
        for name in sorted(v for v in ds.data_vars if v.startswith("Q") and "Time" in ds[v].dims):
            digest.update(np.ascontiguousarray(ds[name].isel(Time=i).values).tobytes())
    return path.resolve(), labels[i], digest.hexdigest()


def check_held_out(train, held_out, data) -> None:
    """SystemExit naming the scenes where a training view's field (the same file and time, or the same
    mixing ratios in another file) is a held-out one."""
    held = {s: field_of(s, data) for s in {s for s, _ in held_out}}
    for scene in sorted({s for s, _ in train}):
        mine = field_of(scene, data)
        for other, theirs in held.items():
            if mine and theirs and (mine[:2] == theirs[:2] or mine[2] == theirs[2]):
                raise SystemExit(f"calibrate_slicer: training scene {scene} ({mine[0]}, time {mine[1]}) is the "
                                 f"held-out field of {other} ({theirs[0]}, time {theirs[1]}): train on other times")


def view_of(vol, lighting: str, cfg):
    """``study.runs.view``'s view of a lighting; for a lighting ending in LOW_SUN, that lighting's with the sun at
    LOW_SUN_DEG and the clear atmosphere (``study.runs.low_sun_view``); ending in TODAY_AIR, with the clear
    atmosphere at the view's own sun."""
    if lighting.endswith(LOW_SUN):
        return low_sun_view(vol, lighting[: -len(LOW_SUN)], cfg, LOW_SUN_DEG, Atmosphere())
    if lighting.endswith(TODAY_AIR):
        base = lighting[: -len(TODAY_AIR)]
        return low_sun_view(vol, base, cfg, view(vol, base, cfg).sun.elevation, Atmosphere())
    return view(vol, lighting, cfg)


def reference(out: Path, scene: str, lighting: str, vol, spec, spp: int, target_rse=None,
              max_seconds=None) -> Image:
    """The path-traced reference of a view: ``spp`` samples, or with ``target_rse`` passes added until the
    mean relative standard error over cloud pixels reaches it (or ``max_seconds``); cached as EXR."""
    plan = f"{spp}spp" if target_rse is None else f"rse{target_rse:g}"
    path = out / cache_name(f"{scene}_{lighting}", spec, plan)
    if path.is_file():
        return Image.load(path)
    t = time.perf_counter()
    medium = vol if spec.atmosphere is None else with_box_air(vol, None, spec.atmosphere)
    ref = wm.render_reference(spec, medium, spp=spp, progress=False, target_rse=target_rse, max_seconds=max_seconds)
    if spec.atmosphere is not None:  # the air along the eye rays outside the box (as slicer_low_sun.py)
        ref = with_eye_air(ref, spec, vol, sky_air=spec.sky is not None and spec.sky.kind == "air")
    ref.save(path)
    noise = ref.metadata.get("noise") or {}
    print(f"  reference {scene} {lighting}: {time.perf_counter() - t:.0f} s, {ref.metadata['spp']} spp, "
          f"cloud RSE {noise.get('rse_mean', float('nan')):.3f}", flush=True)
    return ref


def load_views(names, out, cfg, data, spp, second_seed=False, target_rse=None, max_seconds=None, noise=None,
               low_sun=None):
    """{(scene, lighting): TrainingView}; with ``second_seed`` also {(scene, lighting): a second,
    independent reference (seed 1)} for the reference's own noise. ``target_rse``/``max_seconds``: see
    ``reference``; ``low_sun``: (target_rse, max_seconds) of the views with the air (LOW_SUN, TODAY_AIR) instead; ``noise`` (a dict)
    receives each reference's (spp, mean relative standard error over cloud pixels)."""
    views, vols, seconds = {}, {}, {}
    for scene, lighting in names:
        if scene not in vols:
            vols[scene] = load_scene(scene, cfg, data_dir=data)
        if vols[scene] is None:
            continue
        vol = vols[scene][0]
        spec = view_of(vol, lighting, cfg)
        plan = low_sun if low_sun is not None and spec.atmosphere is not None else (target_rse, max_seconds)
        ref = reference(out, scene, lighting, vol, spec, spp, *plan)
        if noise is not None:
            noise[(scene, lighting)] = (ref.metadata["spp"], (ref.metadata.get("noise") or {}).get("rse_mean"))
        mask = metrics.cloud_mask(eye_transmittance(vol, spec, 128))
        views[(scene, lighting)] = TrainingView(vol, spec, ref.radiance, mask)
        if second_seed:
            seconds[(scene, lighting)] = reference(out, scene, lighting, vol, replace(spec, seed=1), spp,
                                                   *plan).radiance
    return (views, seconds) if second_seed else views


def read_fitted(path: Path) -> dict:
    """The parameters of a fitted.json (``calibrate.MULTIPLE_PARAMS`` names -> numbers); SystemExit naming
    the file and what is wrong for anything else."""
    try:
        fit = json.loads(path.read_text())
    except (OSError, ValueError) as e:
        raise SystemExit(f"--fitted {path}: not a readable JSON file ({e})") from None
    bad = sorted(set(fit) - set(MULTIPLE_PARAMS)) if isinstance(fit, dict) else None
    if bad is None or bad or not all(isinstance(v, (int, float)) for v in fit.values()):
        raise SystemExit(f"--fitted {path}: expected an object of numbers named from {sorted(MULTIPLE_PARAMS)}"
                         + (f"; unknown: {bad}" if bad else ""))
    return fit


def evaluate(views, fitted, slices, out=None, second=None, supersample=1, slab_jitter=0.0,
             fitted_label="multiple (fitted here)"):
    """Rows of CIEDE2000 / FLIP per view and mode (and of a second reference: the noise floor), the frames
    with ``supersample`` x ``supersample`` points per pixel and slab offsets ``slab_jitter``; ``fitted``
    (SliceParams or None) is the column ``fitted_label``."""
    rows, renderers = [], {}
    base = SliceParams(slab_jitter=slab_jitter)
    candidates = [(name, mode, base) for name, mode in MODES.items() if mode.light != "multiple"]
    candidates += [("multiple (defaults)", MODES["per-species/multiple"], base)]
    if fitted is not None:
        candidates += [(fitted_label, MODES["per-species/multiple"], fitted.updated(slab_jitter=slab_jitter))]
    names = [c[0] for c in candidates] + (["reference, seed 1"] if second else [])
    for (scene, lighting), v in views.items():
        row = {"scene": scene, "lighting": lighting}
        if second:
            m = metrics.compare(v.reference, second[(scene, lighting)], mask=v.mask if v.mask.any() else "all")
            row["reference, seed 1"] = (m["ciede2000"], m["flip"])
        imgs = {}
        for name, mode, params in candidates:
            key = (id(v.vol), mode)  # one renderer per volume and mode: the lightings reuse its kernels
            if key not in renderers:
                detail = None
                if mode.detail:
                    from weather_mi.optics.detail import field
                    detail = field(v.vol.shape, seed=0, amplitude=0.5, spacing_m=v.vol.spacing)
                renderers[key] = SliceRenderer(v.vol, mode, slices=slices, detail_field=detail)
            img = renderers[key].frame(v.spec, params, supersample=supersample)
            m = metrics.compare(v.reference, img, mask=v.mask if v.mask.any() else "all")
            row[name] = (m["ciede2000"], m["flip"])
            imgs[name] = img
        rows.append(row)
        if out is not None:
            ref = Image(v.reference.astype(np.float32), np.zeros_like(v.reference, dtype=np.float32), {})
            e = auto_exposure(v.reference)
            side_by_side(out / f"{scene}_{lighting}_side_by_side.png", ref,
                         [imgs["per-species/translucent"], imgs["multiple (defaults)"]], e)
    return rows, names


def table(rows, names, title, noise):
    head = "| view | reference spp, cloud RSE | " + " | ".join(names) + " |"
    lines = [f"### {title} (CIEDE2000 / FLIP over cloud pixels)", "", head, "|---|---|" + "---|" * len(names)]
    for r in rows:
        spp, rse = noise[(r["scene"], r["lighting"])]
        lines.append(f"| {r['scene']} {r['lighting']} | {spp}, {rse:.3f} | "
                     + " | ".join(f"{r[n][0]:.2f} / {r[n][1]:.3f}" for n in names) + " |")
    if rows:
        med = [np.median([r[n][k] for r in rows]) for n in names for k in (0, 1)]
        lines.append("| median | | " + " | ".join(f"{med[2 * i]:.2f} / {med[2 * i + 1]:.3f}" for i in range(len(names))) + " |")
        worst = [max(r[n][0] for r in rows) for n in names]
        lines.append("| worst CIEDE2000 | | " + " | ".join(f"{w:.2f}" for w in worst) + " |")
    return "\n".join(lines)


def log_step(path: Path, iteration: int, loss: float, params: dict) -> None:
    """Append one fit iteration (its loss and the parameters it was measured at) to a JSON-lines file: a fit
    stopped early keeps its iterates (``--start``/``--fitted`` read a line's "params" saved as a fitted.json)."""
    with open(path, "a") as f:
        f.write(json.dumps({"iteration": iteration, "loss": loss,
                            "params": {n: round(v, 4) for n, v in params.items()}}) + "\n")


def fit_start(start: str) -> SliceParams:
    """--start's parameters: "fit-start", "defaults" (the shipped ones, those they leave at 0 at FIT_START's
    values) or the path of an earlier fit's fitted.json (read_fitted); SystemExit for anything else."""
    if start == "fit-start":
        return FIT_START
    if start == "defaults":
        return SliceParams().updated(**{n: getattr(FIT_START, n) for n in MULTIPLE_PARAMS
                                        if getattr(SliceParams(), n) == 0})
    if not Path(start).is_file():
        raise SystemExit(f"--start {start}: expected fit-start, defaults or an existing fitted.json")
    return SliceParams().updated(**read_fitted(Path(start)))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--output", default="out/slicer_calibration")
    ap.add_argument("--data", default=str(DEFAULT_DATA))
    ap.add_argument("--size", default="64x48")
    ap.add_argument("--spp", type=int, default=128,
                    help="samples per pixel of the training references (noise there is unbiased for the fit), "
                         "and of the first estimate of the held-out ones")
    ap.add_argument("--train-target-rse", type=float, default=None,
                    help="training references: render to this mean cloud RSE instead of --spp (the fit's loss "
                         "clips display colours at 1, so noise there darkens bright faces)")
    ap.add_argument("--target-rse", type=float, default=0.02,
                    help="held-out references: mean relative standard error over cloud pixels to reach")
    ap.add_argument("--max-seconds", type=float, default=600.0, help="held-out references: time limit each")
    ap.add_argument("--air-target-rse", "--low-sun-target-rse", dest="low_sun_target_rse", type=float,
                    default=None,
                    help="the training references with the air (LOW_SUN, TODAY_AIR: slower, noisier at --spp) to "
                         "this mean cloud RSE, at most --air-max-seconds each; the other training views as before")
    ap.add_argument("--air-max-seconds", "--low-sun-max-seconds", dest="low_sun_max_seconds", type=float,
                    default=180.0, help="with --air-target-rse: time limit of each training reference with the air")
    ap.add_argument("--iterations", type=int, default=50)
    ap.add_argument("--learning-rate", type=float, default=0.15)
    ap.add_argument("--slices", type=int, default=128)
    ap.add_argument("--references-only", action="store_true")
    ap.add_argument("--supersample", type=int, default=2,
                    help="the slicer's frames (fit and evaluation) with n x n points per pixel, as the references' "
                         "box-filtered pixels; 1: pixel centres")
    ap.add_argument("--slab-jitter", type=float, default=1.0,
                    help="SliceParams.slab_jitter of the frames (fit and evaluation): with --supersample, each "
                         "pixel's points see the slab planes at different depths, which the average smooths")
    ap.add_argument("--fit-slices", type=int, default=None, help="the fit's slice count (default --slices)")
    ap.add_argument("--fit-supersample", type=int, default=None,
                    help="the fit's points per pixel per side (default --supersample)")
    ap.add_argument("--no-fit", action="store_true", help="evaluate the shipped defaults only")
    ap.add_argument("--start", default="fit-start",
                    help="where the fit starts: fit-start (calibrate.FIT_START, near single scattering), defaults "
                         "(the shipped defaults with the parameters they leave at 0, terms that are off, at "
                         "FIT_START's values), or a fitted.json of an earlier fit (continue it)")
    ap.add_argument("--fit-only", action="store_true", help="stop after the fit (writes fitted.json)")
    ap.add_argument("--fitted", default=None,
                    help="a fitted.json of an earlier fit: evaluate its parameters as \"fitted here\", no fit")
    ap.add_argument("--held-out-only", action="store_true",
                    help="evaluate the held-out views only (no training table)")
    ap.add_argument("--noise-floor", action="store_true",
                    help="also render a second reference (seed 1) of each held-out view and report its error")
    args = ap.parse_args(argv)
    width, height = (int(v) for v in args.size.lower().split("x"))
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    cfg = StudyConfig(width=width, height=height, phase_quality="test")
    noise = {}
    check_held_out(TRAIN, HELD_OUT, args.data)
    start = fit_start(args.start)
    low_sun = None if args.low_sun_target_rse is None else (args.low_sun_target_rse, args.low_sun_max_seconds)
    fits = args.fitted is None and not args.no_fit
    # the training views: to fit, for their table, or to render; --held-out-only of an earlier fit needs none
    train = load_views(TRAIN, out, cfg, args.data, args.spp, noise=noise, target_rse=args.train_target_rse,
                       max_seconds=args.max_seconds if args.train_target_rse else None, low_sun=low_sun) \
        if args.references_only or fits or not args.held_out_only else {}
    if args.references_only:
        load_views(HELD_OUT, out, cfg, args.data, args.spp, target_rse=args.target_rse,
                   max_seconds=args.max_seconds)
        return 0
    fitted, history, head = None, [], "Shipped defaults only (no fit)."
    if args.fitted is not None:
        fit = read_fitted(Path(args.fitted))
        fitted = SliceParams().updated(**fit)
        head = f"Parameters of an earlier fit ({args.fitted}): `{json.dumps(fit)}`."
    elif not args.no_fit:
        t = time.perf_counter()
        fitted, history = calibrate(list(train.values()), start=start.updated(slab_jitter=args.slab_jitter),
                                    iterations=args.iterations, slices=args.fit_slices or args.slices,
                                    light_res=None, learning_rate=args.learning_rate, progress=True,
                                    supersample=args.fit_supersample or args.supersample,
                                    on_step=lambda i, loss, p: log_step(out / "fit_steps.jsonl", i, loss, p))
        fit = {n: round(float(getattr(fitted, n)), 4) for n in MULTIPLE_PARAMS}
        head = (f"Fitted on {len(train)} training views in {time.perf_counter() - t:.0f} s: `{json.dumps(fit)}`; "
                f"loss {history[0]:.4g} -> {history[-1]:.4g} in {len(history)} iterations.")
        (out / "fitted.json").write_text(json.dumps(fit, indent=1))
        print(head, flush=True)
        if args.fit_only:
            return 0
    held = load_views(HELD_OUT, out, cfg, args.data, args.spp, second_seed=args.noise_floor,
                      target_rse=args.target_rse, max_seconds=args.max_seconds, noise=noise)
    held, second = held if args.noise_floor else (held, None)
    label = "multiple (fitted here)" if args.fitted is None else f"multiple ({Path(args.fitted).stem})"
    kw = dict(supersample=args.supersample, slab_jitter=args.slab_jitter, fitted_label=label)
    rows_t, names_t = ([], []) if args.held_out_only else evaluate(train, fitted, args.slices, **kw)
    rows_h, names_h = evaluate(held, fitted, args.slices, out, second, **kw)
    text = "\n\n".join([f"# Slicer calibration ({width} x {height}; references: training {args.spp} spp, held-out to a "
                         f"cloud RSE of {args.target_rse:g} or {args.max_seconds:g} s; slicer frames with "
                         f"{args.supersample} x {args.supersample} points per pixel, slab jitter {args.slab_jitter:g})", head,
                         table(rows_t, names_t, "Training views", noise),
                         table(rows_h, names_h, "Held-out views", noise)])
    (out / "calibration.md").write_text(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
