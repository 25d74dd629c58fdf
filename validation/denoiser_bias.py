"""The denoised display layer's bias (issue 24, items 1-2): on views of the validation study's storms,
raw and OIDN-denoised path-traced images at 64/128/256 spp against a long reference of the same view
(rendered to a target cloud RSE), for every auxiliary choice (``weather_mi.display.denoise.AUX``); where the
denoiser fails (thin edges, the darkest and brightest cloud pixels) with crops in out/denoiser_bias/.

    .venv/bin/python validation/denoiser_bias.py [--size 64x48] [--target-rse 0.025] [--views ...]

Prints a markdown table and writes out/denoiser_bias/{table.md, rows.json, *_crops.png} and the references
(*_reference.exr, reused by a later run of the same size: delete them to render afresh).
``--demo-reference-spp N``: the README demo (320 x 240 at its default spp) raw and denoised against an
N-spp reference of the same view instead (out/denoiser_bias/demo.md, demo_crops.png).
"""
from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

import weather_mi as wm
from weather_mi.display.denoise import AUX
from weather_mi.reference.estimates import view_optical_depth
from weather_mi.io.image import auto_exposure, to_srgb8
from weather_mi.study.denoiser import KEYS, bias_rows, error_figures
from weather_mi.study.report import _table
from weather_mi.study.runs import CONFIGS, load_scene, view

ROOT = Path(__file__).resolve().parents[1]


def regions(spec, vol, ref) -> dict:
    """Cloud-pixel classes where a denoiser fails: thin edges (eye-ray optical depth ln 2 .. 2), dense
    (> 2), the darkest 10% of cloud pixels (shadows) and the brightest 5% (sun glints, silver linings)."""
    tau = view_optical_depth(spec, vol)
    cloud = np.asarray(ref.transmittance) < 0.5
    lum = ref.radiance.mean(axis=2)
    lo, hi = np.percentile(lum[cloud], [10, 95])
    return {"thin edges": cloud & (tau < 2.0), "dense": cloud & (tau >= 2.0),
            "darkest 10%": cloud & (lum <= lo), "brightest 5%": cloud & (lum >= hi)}


def crops(path: Path, ref, raw, den: dict, scale: int = 8, margin: int = 3) -> None:
    """reference | raw | denoised (each aux) | |denoised(none) - ref| x 4, cropped to the cloud pixels' box
    (plus ``margin``), one exposure (the reference's), nearest-neighbour x ``scale``."""
    from PIL import Image as PILImage
    e = auto_exposure(ref.radiance)
    cloud = np.asarray(ref.transmittance) < 0.5
    ys, xs = np.nonzero(cloud) if cloud.any() else (np.array([0, ref.shape[0] - 1]), np.array([0, ref.shape[1] - 1]))
    box = (slice(max(ys.min() - margin, 0), ys.max() + margin + 1), slice(max(xs.min() - margin, 0), xs.max() + margin + 1))
    first = den.get("none", den[next(iter(den))])
    panels = [ref.radiance, raw.radiance] + list(den.values()) + [np.abs(first - ref.radiance) * 4]
    row = np.concatenate([to_srgb8(p[box], e) for p in panels], axis=1)
    PILImage.fromarray(row).resize((row.shape[1] * scale, row.shape[0] * scale), PILImage.NEAREST).save(path)


def noise_ciede(ref, mask: np.ndarray, seed: int = 0) -> float:
    """The CIEDE2000 over ``mask`` that the reference's own noise alone gives: the reference against
    itself plus Gaussian noise of its per-pixel standard error (an estimate, for reading the others)."""
    rng = np.random.default_rng(seed)
    noisy = ref.radiance + np.nan_to_num(ref.stderr) * rng.standard_normal(ref.radiance.shape)
    return wm.metrics.compare(ref, np.maximum(noisy, 0.0), mask=mask)["ciede2000"]


def demo(ref_spp: int, out: Path) -> None:
    """The README demo (``weather-mi render --demo supercell``: 320 x 240, its default spp) raw and denoised
    against a longer reference of the same view (seed 7), over cloud pixels; crops of both PNGs."""
    from weather_mi.cli.commands import build_parser, scene_spec
    from weather_mi.display.denoise import auxiliaries, denoise_radiance
    args = build_parser().parse_args(["render", "--demo", "supercell"])
    vol = wm.optical_volume(wm.open_source(None, "supercell"), species=args.preset, phase=args.phase)
    spec = scene_spec(args, vol)
    t0 = time.perf_counter()
    img = wm.render_reference(spec, vol, spp=args.spp, progress=False)
    t_raw = time.perf_counter() - t0
    img.save(out / "demo_raw.exr")
    cached = out / f"demo_reference_{ref_spp}spp.exr"
    if cached.is_file():
        ref = wm.Image.load(cached)
    else:
        ref = wm.render_reference(replace(spec, seed=7), vol, spp=ref_spp, progress=False)
        ref.save(cached)
    mask = np.asarray(ref.transmittance) < 0.5
    rows = [{"image": f"raw {args.spp} spp", "seconds": t_raw, **error_figures(ref, img.radiance, mask)}]
    den = {}
    for aux in AUX:
        t0 = time.perf_counter()
        alb, nrm = auxiliaries(aux, spec, vol, img.radiance)
        den[aux] = denoise_radiance(img.radiance, alb, nrm)
        rows.append({"image": f"denoised ({aux})", "seconds": time.perf_counter() - t0,
                     **error_figures(ref, den[aux], mask)})
    rows.append({"image": "reference + its own noise (estimate)", "seconds": float("nan"),
                 "ciede2000": noise_ciede(ref, mask), "rel_bias": 0.0,
                 "rel_rms": float(np.sqrt(np.mean(np.nan_to_num(ref.stderr[mask]) ** 2)) / ref.radiance[mask].mean())})
    crops(out / "demo_crops.png", ref, img, den, scale=2)
    n = ref.metadata["noise"]
    text = [f"README demo, 320 x 240, {args.spp} spp (the demo's budget), against a {ref_spp}-spp reference "
            f"(seed 7; cloud RSE {n['rse_mean']:.3f}, RMS se/mean {n['rms_se_over_mean']:.3f}), "
            f"{int(mask.sum())} cloud pixels; rel_rms with the reference's noise removed; seconds: the raw "
            "render's (wall, on the shared machine), the denoiser's own (features + OIDN):", "",
            _table(rows, ["image", "seconds", "ciede2000", "rel_bias", "rel_rms"])]
    (out / "demo.md").write_text("\n".join(text))
    (out / "demo.json").write_text(json.dumps(rows, indent=1))
    print("\n".join(text))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", default="64x48")
    ap.add_argument("--target-rse", type=float, default=0.025)
    ap.add_argument("--max-seconds", type=float, default=300.0)
    ap.add_argument("--spp", default="64,128,256")
    ap.add_argument("--raw-spp", default="16,32,64,128,256")
    ap.add_argument("--views", default="demo-supercell:side,demo-supercell:back,wrf-supercell:side,bomex:side")
    ap.add_argument("--data", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("-o", "--out", default=str(ROOT / "out" / "denoiser_bias"))
    ap.add_argument("--demo-reference-spp", type=int, default=None,
                    help="instead: the README demo against a reference of this spp")
    a = ap.parse_args()
    w, h = (int(v) for v in a.size.split("x"))
    cfg = replace(CONFIGS["full"], width=w, height=h)
    spp = [int(s) for s in a.spp.split(",")]
    raw_spp = [int(s) for s in a.raw_spp.split(",")]
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    if a.demo_reference_spp:
        return demo(a.demo_reference_spp, out)
    rows, region_rows, refs = [], [], []
    for item in a.views.split(","):
        scene, lighting = item.split(":")
        vol, _ = load_scene(scene, cfg, data_dir=a.data)
        spec = view(vol, lighting, cfg)
        t0 = time.perf_counter()
        cached = out / f"{scene}_{lighting}_{w}x{h}_reference.exr"
        if cached.is_file():  # a reference of an earlier run (delete it to render afresh)
            ref = wm.Image.load(cached)
        else:
            ref = wm.render_reference(replace(spec, seed=7), vol, spp=256, target_rse=a.target_rse,
                                      max_seconds=a.max_seconds, progress=False)
            ref.save(cached)
        noise = ref.metadata["noise"]
        refs.append({"scene": scene, "lighting": lighting, "spp": ref.metadata["spp"], "seconds": time.perf_counter() - t0,
                     "rse_mean": noise["rse_mean"], "rms_se_over_mean": noise["rms_se_over_mean"]})
        print(refs[-1], flush=True)
        slicer = wm.render_slices(spec, vol, wm.slicing.MODES["per-species/multiple"], slices=128).radiance
        r, images = bias_rows(scene, lighting, spec, vol, ref, spp, aux=AUX, raw_spp=raw_spp, slicer_frame=slicer)
        rows += r
        mine = [x for x in r if x["image"] != "raw"]
        best = min(AUX, key=lambda k: np.mean([x["rel_rms"] for x in mine if x["image"] == f"denoised ({k})"]))
        for s, (raw, den) in images.items():
            for name, m in regions(spec, vol, ref).items():
                if m.sum() < 5:
                    continue
                region_rows.append({"scene": scene, "lighting": lighting, "spp": s, "region": name,
                                    "pixels": int(m.sum()), "aux": best,
                                    **{f"raw {k}": v for k, v in error_figures(ref, raw.radiance, m).items()
                                       if k != "ciede2000"},
                                    **{f"denoised {k}": v for k, v in
                                       error_figures(ref, den[best], m).items() if k != "ciede2000"}})
            if s == spp[0]:
                crops(out / f"{scene}_{lighting}_{s}spp_crops.png", ref, raw, den)
        (out / "rows.json").write_text(json.dumps({"refs": refs, "rows": rows, "regions": region_rows}, indent=1))
    text = ["References (render to a target cloud RSE, seed independent of the test images):", "",
            _table(refs, ["scene", "lighting", "spp", "seconds", "rse_mean", "rms_se_over_mean"]), "",
            _table(rows, KEYS), "", "Where it fails (per view, the auxiliaries of lowest rel_rms):", "",
            _table(region_rows, list(region_rows[0]) if region_rows else [])]
    (out / "table.md").write_text("\n".join(text))
    print("\n".join(text))


if __name__ == "__main__":
    main()
