"""A storm from both renderers at the same view: path-traced reference | slicer modes.

    .venv/bin/python validation/side_by_side.py [-o out/side_by_side] [--scene demo-supercell]
        [--data ../shared/data] [--size 320x240] [--spp 64] [--slices 128] [--lighting front|side|back]
        [--modes per-species/translucent,per-species/multiple]

Writes ``<scene>_<lighting>_side_by_side.png`` (reference left, then each slicer mode, one exposure for
all), the EXRs, an error map per mode, and prints the metrics of ``wm.metrics.compare`` over cloud
pixels with the reference's own noise floor beside them. Scenes: the study's (``weather_mi.study``):
demo-supercell, demo-cumulus, and from --data wrf-supercell, wrf-plateau, bomex, rico.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import weather_mi as wm  # noqa: E402
from weather_mi.display import metrics
from weather_mi import study  # noqa: E402
from weather_mi.io.image import Image, auto_exposure  # noqa: E402
from weather_mi.slicing import MODES, SliceRenderer  # noqa: E402


def cached_reference(path: Path, spec, spp: int):
    """The reference saved at ``path`` by an earlier run, if it was rendered for this scene with ``spp``
    samples (metadata compared), else None: a rerun for other slicer modes does not path-trace again."""
    if not path.is_file():
        return None
    ref = Image.load(path)
    same = lambda a, b: json.dumps(a, sort_keys=True, default=str) == json.dumps(b, sort_keys=True, default=str)  # noqa: E731
    if ref.metadata.get("spp") != spp or not same(json.loads(json.dumps(spec.to_dict(), default=str)),
                                                  ref.metadata.get("scene")):
        return None
    print(f"reusing {path} ({spp} spp)")
    return ref


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--output", default="out/side_by_side")
    ap.add_argument("--scene", default="demo-supercell")
    ap.add_argument("--data", default=str(Path(__file__).resolve().parents[2] / "shared" / "data"))
    ap.add_argument("--size", default="320x240")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--slices", type=int, default=128)
    ap.add_argument("--lighting", choices=("front", "side", "back"), default="front")
    ap.add_argument("--modes", default="per-species/translucent,per-species/multiple",
                    help="comma-separated, from: " + ", ".join(MODES))
    args = ap.parse_args(argv)
    width, height = (int(v) for v in args.size.lower().split("x"))
    modes = args.modes.split(",")
    for m in modes:
        if m not in MODES:
            ap.error(f"unknown mode {m!r}; choose from {', '.join(MODES)}")
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)

    cfg = study.StudyConfig(width=width, height=height, spp=args.spp, slices=args.slices)
    loaded = study.load_scene(args.scene, cfg, data_dir=args.data)
    if loaded is None:
        ap.error(f"scene {args.scene!r} needs its data file under --data {args.data}")
    vol, desc = loaded
    spec = study.view(vol, args.lighting, cfg)
    stem = f"{args.scene}_{args.lighting}"
    ref = cached_reference(out / f"{stem}_reference.exr", spec, args.spp)
    if ref is None:
        ckpt = out / f"{stem}_reference.ckpt.npz"  # an interrupted run resumes; removed once the render is complete
        ref = wm.render_reference(spec, vol, spp=args.spp, checkpoint=ckpt, resume=True)
        ckpt.unlink(missing_ok=True)
        ref.save(out / f"{stem}_reference.exr")
    mask = metrics.cloud_mask(study.eye_transmittance(vol, spec, args.slices))
    exposure = auto_exposure(ref.radiance)
    print(f"{desc}; {args.lighting}-lit; {width} x {height}; reference {args.spp} spp, "
          f"{ref.metadata['seconds']:.1f} s; noise floor (RMS standard error over cloud pixels) "
          f"{metrics.noise_floor(ref, mask=mask):.4g}")
    images = []
    for name in modes:
        renderer = SliceRenderer(vol, MODES[name], slices=args.slices, light_res=cfg.light_res)
        renderer.frame(spec)  # warm-up: the first frame compiles
        approx = renderer.frame(spec)
        images.append(approx)
        tag = name.replace("/", "-")
        approx.save(out / f"{stem}_{tag}.exr")
        m = metrics.compare(ref, approx, exposure=exposure, mask=mask, error_map=out / f"{stem}_{tag}_error.png")
        print(f"{name}: {args.slices} slices, {approx.metadata['seconds'] * 1e3:.0f} ms per frame; "
              + ", ".join(f"{k} {m[k]:.4g}" for k in ("rmse", "rel_mse", "ssim", "ciede2000", "flip", "n_pixels")))
    png = study.side_by_side(out / f"{stem}_side_by_side.png", ref, images, exposure)
    print(f"wrote {png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
