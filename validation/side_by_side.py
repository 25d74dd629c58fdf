"""The demo supercell from both renderers at the same view: path-traced reference | half-angle slicer.

    .venv/bin/python validation/side_by_side.py [-o out/side_by_side] [--size 320x240] [--spp 64]
                                               [--slices 128] [--lighting front|side|back]

Writes ``supercell_<lighting>_side_by_side.png`` (reference left, slicer right, one exposure for
both), both EXRs, the error map, and prints the metrics of ``wm.metrics.compare`` over cloud pixels
with the reference's own noise floor beside them.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import weather_mi as wm  # noqa: E402
from weather_mi import metrics, study  # noqa: E402
from weather_mi.imageio import auto_exposure  # noqa: E402
from weather_mi.slicing import TABLE_IV, SliceRenderer  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--output", default="out/side_by_side")
    ap.add_argument("--size", default="320x240")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--slices", type=int, default=128)
    ap.add_argument("--lighting", choices=("front", "side", "back"), default="front")
    ap.add_argument("--mode", choices=tuple(TABLE_IV), default="per-species/translucent")
    args = ap.parse_args(argv)
    width, height = (int(v) for v in args.size.lower().split("x"))
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)

    cfg = study.StudyConfig(width=width, height=height, spp=args.spp, slices=args.slices)
    vol, desc = study.load_scene("demo-supercell", cfg)
    spec = study.view(vol, args.lighting, cfg)
    ckpt = out / "reference.ckpt.npz"  # an interrupted run resumes; removed once the render is complete
    ref = wm.render_reference(spec, vol, spp=args.spp, checkpoint=ckpt, resume=True)
    ckpt.unlink(missing_ok=True)
    renderer = SliceRenderer(vol, TABLE_IV[args.mode], slices=args.slices, light_res=cfg.light_res)
    renderer.frame(spec)  # warm-up: the first frame compiles
    approx = renderer.frame(spec)
    trans = study.eye_transmittance(vol, spec, args.slices)
    mask = metrics.cloud_mask(trans)
    exposure = auto_exposure(ref.radiance)
    stem = f"supercell_{args.lighting}"
    ref.save(out / f"{stem}_reference.exr")
    approx.save(out / f"{stem}_slicer.exr")
    png = study.side_by_side(out / f"{stem}_side_by_side.png", ref, approx, exposure)
    m = metrics.compare(ref, approx, exposure=exposure, mask=mask, error_map=out / f"{stem}_error.png")
    print(f"{desc}; {args.lighting}-lit; {width} x {height}; mode {args.mode}")
    print(f"reference: {args.spp} spp, {ref.metadata['seconds']:.1f} s; slicer: {args.slices} slices, "
          f"{approx.metadata['seconds'] * 1e3:.0f} ms per frame")
    print(f"reference noise floor (RMS standard error over cloud pixels): {metrics.noise_floor(ref, mask=mask):.4g}")
    for k in ("rmse", "rel_mse", "ssim", "ciede2000", "flip", "n_pixels"):
        print(f"  {k:10s} {m[k]:.4g}")
    print(f"wrote {png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
