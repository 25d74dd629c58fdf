"""The slicer against the path tracer at a low sun, with the atmosphere and without it, on the held-out storms
(issue 38 part 3; no refit: the "multiple" model's shipped parameters, ``slicing/modes.py``).

Views: ``validation/calibrate_slicer.py``'s held-out storms (the real WRF supercell, the WRF Tibetan Plateau
file, BOMEX, RICO; from --data) front-, side- (and back-) lit at the calibration size (64 x 48), the sun moved
down to --elevations (default 4 and 8 deg; "today": each view's own sun, front/side 35, back 20). Each view twice:

* ``--atmosphere clear`` (RGB mode): the path tracer with the air inside the box in its medium (molecules from
  the storm's rho_air, ``optics.air.inside.with_box_air``) and along the eye rays outside it
  (``display.aerial.with_eye_air``), the sun coloured per vertex by height; the slicer with the sun's colour
  by height, the sky scaled and the eye rays' air inside the box and out (``slicing.eye_air``);
* no atmosphere: both as before issue 38;
* and, against the same references with the atmosphere, the slicer as it was before the box's air: the sun's
  colour by height and the air outside the box put on its frame afterwards (``SliceRenderer(eye_air=False)``,
  ``display.aerial.with_eye_air``).

The slicer's frames are the refined viewer frames the calibration judges (2 x 2 points per pixel, slab
jitter 1, 128 slices), with the shipped defaults or the parameters of --fitted. CIEDE2000 and FLIP over the
cloud pixels (``display.metrics.compare``), and the reference's own noise (its mean relative standard error over
them). References are cached as EXR in --out (--spp samples, or passes of --spp to --target-rse, at most
--max-seconds each; --references-only renders them alone; those with the air named with
``calibrate_slicer.AIR_REFERENCES``, so that one of an older path tracer's air is never read). The table of issue 38 part 3: --elevations 6
--lightings front,side,back --spp 64 --target-rse 0.03 --max-seconds 150 (validation/README.md).

``--spectral``: against the spectral ground truth instead. Each view with the atmosphere twice, the slicer
unchanged: the reference rendered in Mitsuba's spectral variant (``kernel.variant.spectral_variant``, as ``render
--spectral``: the film's CIE XYZ as linear sRGB, the eye rays' air outside the box per wavelength) and the RGB one
(with --rgb-target-rse's plan, default --target-rse: the RGB references already cached); the spectral ones cached
with "spectral" in their name, so neither is read for the other.

    python validation/slicer_low_sun.py [--data ../shared/data] [--size 64x48] [--spp 64] [--elevations 4,8]
        [--scenes wrf-supercell,wrf-plateau,bomex,rico] [--lightings front,side,back] [--out DIR]
        [--target-rse R --max-seconds S] [--references-only] [--fitted fitted.json]
        [--spectral [--rgb-target-rse R]] [--atmospheres clear,none (with --references-only)]
"""
from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

import weather_mi as wm  # noqa: E402
from weather_mi.display import metrics  # noqa: E402
from weather_mi.display.aerial import with_eye_air  # noqa: E402
from weather_mi.io import sources  # noqa: E402
from weather_mi.io.image import Image  # noqa: E402
from weather_mi.optics.air import Atmosphere  # noqa: E402
from weather_mi.optics.air.inside import with_box_air  # noqa: E402
from weather_mi.optics.volume import optical_volume  # noqa: E402
from weather_mi.slicing import MODES, SliceParams, SliceRenderer  # noqa: E402
from weather_mi.study.runs import DATA_SCENES, StudyConfig, eye_transmittance, low_sun_view, view  # noqa: E402
from validation.calibrate_slicer import cache_name, read_fitted  # noqa: E402

DEFAULT_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


def storm(name: str, data: Path, cfg: StudyConfig):
    """(Hydrometeors, OpticalVolume) of a held-out storm, as the calibration loads it (isolated box)."""
    hyd = sources.open_source(Path(data) / DATA_SCENES[name][0])
    return hyd, optical_volume(hyd, species=cfg.species, phase_quality=cfg.phase_quality, periodic=False)


def reference(out: Path, tag: str, spec, vol, hyd, spp: int, target_rse=None, max_seconds=None,
              spectral: bool = False) -> Image:
    """The path-traced reference (cached as EXR): with ``spec.atmosphere``, the box's air in the medium and
    the eye rays' air outside it, as ``weather-mi render --atmosphere clear``. ``spp`` samples, or with
    ``target_rse`` passes of ``spp`` added until the mean relative standard error over the cloud pixels
    reaches it (or ``max_seconds``). ``spectral``: in the spectral variant, as ``render --spectral`` (the eye
    rays' air per wavelength: ``with_eye_air`` on an image with X, Y, Z), "spectral" in the cached name."""
    from weather_mi.kernel.variant import default_variant, set_variant, spectral_variant
    plan = f"{spp}spp" if target_rse is None else f"rse{target_rse:g}"
    path = out / cache_name(f"{tag}_spectral" if spectral else tag, spec, plan)
    if path.is_file():
        return Image.load(path)
    t = time.perf_counter()
    medium = vol if spec.atmosphere is None else with_box_air(vol, hyd, spec.atmosphere)
    variant = spectral_variant() if spectral else default_variant()  # not the one a spectral render left
    img = wm.render_reference(spec, medium, spp=spp, progress=False, target_rse=target_rse, max_seconds=max_seconds,
                              variant=variant)
    set_variant(default_variant())  # the slicer's sky (kernel.sky) evaluates Mitsuba's emitter in RGB
    if spec.atmosphere is not None:  # with the air's own sky (study.runs.low_sun_view) its light along the eye rays
        img = with_eye_air(img, spec, vol, sky_air=spec.sky is not None and spec.sky.kind == "air")
    img.save(path)
    noise = img.metadata.get("noise") or {}
    print(f"  reference {tag}{' (spectral)' if spectral else ''}: {time.perf_counter() - t:.0f} s, {img.metadata.get('spp')} spp, "
          f"cloud RSE {noise.get('rse_mean', float('nan')):.3f}", flush=True)
    return img


def spectral_row(row: dict, out: Path, name: str, spec, vol, hyd, slicer, params, args) -> None:
    """``row["spectral"]`` and ``row["rgb"]``: (CIEDE2000, FLIP, reference RSE) of the slicer's frame against the
    spectral reference and against the RGB one of the same view with the atmosphere (--spectral);
    ``row["refs"]``: (CIEDE2000, FLIP) of the RGB reference against the spectral one (both noisy) and the ratio
    of their cloud pixels' mean linear R, G, B (spectral / RGB)."""
    tag = f"{name}_{row['lighting']}_{row['elevation']:g}deg_clear"
    rgb_rse = args.target_rse if args.rgb_target_rse is None else args.rgb_target_rse
    refs = {"spectral": reference(out, tag, spec, vol, hyd, args.spp, args.target_rse, args.max_seconds, True),
            "rgb": reference(out, tag, spec, vol, hyd, args.spp, rgb_rse, args.max_seconds)}
    if args.references_only:
        return
    mask = metrics.cloud_mask(eye_transmittance(vol, spec, 128))
    img = slicer.frame(spec, params, supersample=2)
    for label, ref in refs.items():
        m = metrics.compare(ref.radiance, img.radiance, mask=mask if mask.any() else "all")
        row[label] = (m["ciede2000"], m["flip"], (ref.metadata.get("noise") or {}).get("rse_mean", float("nan")))
    m = metrics.compare(refs["spectral"].radiance, refs["rgb"].radiance, mask=mask if mask.any() else "all")
    cloud = mask if mask.any() else np.ones(mask.shape, bool)
    spectral, rgb = (np.asarray(refs[k].radiance, np.float64)[cloud].mean(axis=0) for k in ("spectral", "rgb"))
    row["refs"] = (m["ciede2000"], m["flip"], spectral / rgb)


def print_spectral(rows: list, width: int, height: int, plan: str) -> None:
    """The --spectral table: per view the slicer against the spectral and the RGB reference with the air."""
    print(f"\n### The slicer against the spectral and the RGB path tracer at a low sun, with the atmosphere ({width} x "
          f"{height}, references {plan}; CIEDE2000 / FLIP over cloud pixels; reference noise: mean RSE)\n")
    print("| storm | lighting | sun elevation | against the spectral reference | against the RGB reference | "
          "RGB reference against the spectral | cloud's mean R, G, B: spectral / RGB reference | "
          "reference RSE (spectral / RGB) |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        (ds, fs, rs), (dr, fr, rr), (dd, fd, ratio) = r["spectral"], r["rgb"], r["refs"]
        print(f"| {r['scene']} | {r['lighting']} | {r['elevation']:g} | {ds:.2f} / {fs:.3f} | {dr:.2f} / {fr:.3f} | "
              f"{dd:.2f} / {fd:.3f} | {', '.join(f'{v:.3f}' for v in ratio)} | {rs:.3f} / {rr:.3f} |")
    texts = {"spectral": "the slicer against the spectral reference", "rgb": "the slicer against the RGB reference",
             "refs": "the RGB reference against the spectral"}
    for label, text in texts.items():
        if rows:
            de, flip = [r[label][0] for r in rows], [r[label][1] for r in rows]
            print(f"\n{text}: median CIEDE2000 {np.median(de):.2f}, mean {np.mean(de):.2f}, worst {max(de):.2f}, "
                  f"median FLIP {np.median(flip):.3f}, worst {max(flip):.3f}")


def elevations_of(text: str, vol, lighting: str, cfg: StudyConfig) -> list:
    """The sun elevations (deg) of --elevations: comma-separated numbers, "today" the view's own (``study.runs.view``:
    front and side 35, back 20) as ``slicer_air_tables.py``'s table "today, air"."""
    return [view(vol, lighting, cfg).sun.elevation if e == "today" else float(e) for e in text.split(",")]


def parse_args(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(DEFAULT_DATA))
    ap.add_argument("--size", default="64x48")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--elevations", default="4,8",
                    help="sun elevations (deg), comma-separated; \"today\": each view's own (front/side 35, back 20)")
    ap.add_argument("--scenes", default="wrf-supercell,wrf-plateau,bomex,rico")
    ap.add_argument("--lightings", default="front,side")
    ap.add_argument("--target-rse", type=float, default=None,
                    help="render each reference in passes of --spp until its mean RSE over cloud pixels reaches this")
    ap.add_argument("--max-seconds", type=float, default=None, help="with --target-rse: at most this long a view")
    ap.add_argument("--references-only", action="store_true",
                    help="render (and cache) the references, judge nothing (to run beside other work)")
    ap.add_argument("--fitted", default=None,
                    help="a fitted.json (validation/calibrate_slicer.py): the \"multiple\" model's parameters instead "
                         "of the shipped defaults")
    ap.add_argument("--spectral", action="store_true",
                    help="the slicer against the spectral references with the atmosphere and the RGB ones (docstring)")
    ap.add_argument("--rgb-target-rse", type=float, default=None,
                    help="with --spectral: the RGB references' --target-rse (default --target-rse), to read cached ones")
    ap.add_argument("--out", default="validation-low-sun")
    ap.add_argument("--atmospheres", default="clear,none",
                    help="with --references-only: render the references of these only (clear, none; the table "
                         "needs both)")
    return ap.parse_args(argv)


def main(argv=None) -> int:
    args = parse_args(argv)
    args.atmospheres = args.atmospheres.split(",")
    if not args.references_only and not args.spectral and set(args.atmospheres) != {"clear", "none"}:
        raise SystemExit("slicer_low_sun: --atmospheres other than clear,none needs --references-only (the table "
                         "compares both)")
    width, height = (int(v) for v in args.size.split("x"))
    cfg = replace(StudyConfig(), width=width, height=height)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    params = SliceParams(slab_jitter=1.0)
    if args.fitted is not None:
        params = params.updated(**read_fitted(Path(args.fitted)))
    rows = []
    for name in args.scenes.split(","):
        if not (Path(args.data) / DATA_SCENES[name][0]).is_file():
            print(f"skipped {name}: {Path(args.data) / DATA_SCENES[name][0]} absent")
            continue
        hyd, vol = storm(name, Path(args.data), cfg)
        slicer = SliceRenderer(vol, MODES["per-species/multiple"], slices=128)
        before = SliceRenderer(vol, MODES["per-species/multiple"], slices=128, eye_air=False)
        for lighting in args.lightings.split(","):
            for elevation in elevations_of(args.elevations, vol, lighting, cfg):
                row = {"scene": name, "lighting": lighting, "elevation": elevation}
                if args.spectral:
                    spec = low_sun_view(vol, lighting, cfg, elevation, Atmosphere())
                    spectral_row(row, out, name, spec, vol, hyd, slicer, params, args)
                atms = [(lb, a) for lb, a in (("clear", Atmosphere()), ("none", None)) if lb in args.atmospheres]
                for label, atm in () if args.spectral else atms:
                    spec = low_sun_view(vol, lighting, cfg, elevation, atm)
                    tag = f"{name}_{lighting}_{elevation:g}deg_{label}"
                    ref = reference(out, tag, spec, vol, hyd, args.spp, args.target_rse, args.max_seconds)
                    if args.references_only:
                        continue
                    mask = metrics.cloud_mask(eye_transmittance(vol, spec, 128))
                    img = slicer.frame(spec, params, supersample=2)
                    m = metrics.compare(ref.radiance, img.radiance, mask=mask if mask.any() else "all")
                    rse = (ref.metadata.get("noise") or {}).get("rse_mean", float("nan"))
                    row[label] = (m["ciede2000"], m["flip"], rse)
                    if atm is not None:  # the slicer before the box's air, against the same reference
                        old = before.frame(spec, params, supersample=2)
                        old = with_eye_air(replace(old, transmittance=before.transmittance), spec, vol,
                                           sky_air=spec.sky is not None and spec.sky.kind == "air")
                        m = metrics.compare(ref.radiance, old.radiance, mask=mask if mask.any() else "all")
                        row["before"] = (m["ciede2000"], m["flip"])
                if not args.references_only:
                    rows.append(row)
                    print(row, flush=True)
    plan = f"{args.spp} spp" if args.target_rse is None else \
        f"to a cloud RSE of {args.target_rse:g} (at most {args.max_seconds} s), passes of {args.spp} spp"
    if args.spectral:
        print_spectral(rows, width, height, plan if args.rgb_target_rse is None else
                       f"{plan} (RGB: to {args.rgb_target_rse:g})")
        return 0
    print(f"\n### The slicer against the path tracer at a low sun ({width} x {height}, references {plan}; "
          "CIEDE2000 / FLIP over cloud pixels; reference noise: mean RSE)\n")
    print("| storm | lighting | sun elevation | with the atmosphere | the same, slicer without the box's air | "
          "without the atmosphere | reference RSE (with / without) |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        (dc, fc, rc), (db, fb), (dn, fn, rn) = r["clear"], r["before"], r["none"]
        print(f"| {r['scene']} | {r['lighting']} | {r['elevation']:g} | {dc:.2f} / {fc:.3f} | {db:.2f} / {fb:.3f} | "
              f"{dn:.2f} / {fn:.3f} | {rc:.3f} / {rn:.3f} |")
    names = {"clear": "with the atmosphere", "before": "with it, the slicer without the box's air",
             "none": "without the atmosphere"}
    for label, text in names.items():
        de = [r[label][0] for r in rows]
        if de:
            print(f"\n{text}: median CIEDE2000 {np.median(de):.2f}, mean {np.mean(de):.2f}, "
                  f"median FLIP {np.median([r[label][1] for r in rows]):.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
