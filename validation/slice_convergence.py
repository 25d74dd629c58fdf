"""Slice-count convergence of the half-angle slicer: CIEDE2000 between renders with n and 2n slices,
per mode and study view (no reference needed: the limit must not depend on the sampling).

    .venv/bin/python validation/slice_convergence.py [--size 96x72] [--slices 64,128,256,512]
                                                     [--scenes demo-supercell,demo-cumulus]

Prints one row per (scene, lighting, mode): CIEDE2000 over cloud pixels (eye-ray transmittance < 0.99)
between consecutive slice counts, and the targets (256 vs 512 <= 1, 128 vs 256 <= 2).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from weather_mi.display import metrics  # noqa: E402
from weather_mi.io.image import auto_exposure  # noqa: E402
from weather_mi.slicing import MODES, SliceRenderer  # noqa: E402
from weather_mi.study.runs import StudyConfig, load_scene, view  # noqa: E402


def convergence(vol, spec, mode, slices, light_res, detail=None):
    """[(n, image)] and the cloud mask of the finest render."""
    imgs = []
    for n in slices:
        r = SliceRenderer(vol, mode, slices=n, light_res=light_res, detail_field=detail)
        imgs.append((n, r.frame(spec)))
        mask = metrics.cloud_mask(r.transmittance)
    return imgs, mask


def pairwise(imgs, mask):
    """CIEDE2000 between consecutive images, exposure of the finest."""
    exposure = auto_exposure(imgs[-1][1].radiance)
    out = []
    for (n0, a), (n1, b) in zip(imgs, imgs[1:]):
        m = metrics.compare(b, a, exposure=exposure, mask=mask if mask.any() else "all")
        out.append((n0, n1, m["ciede2000"]))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="96x72")
    ap.add_argument("--slices", default="64,128,256,512")
    ap.add_argument("--light-res", type=int, default=None, help="default: the slicer's automatic size")
    ap.add_argument("--scenes", default="demo-supercell,demo-cumulus")
    ap.add_argument("--lightings", default="front,side,back")
    ap.add_argument("--modes", default=",".join(MODES))
    ap.add_argument("--data", default=str(Path(__file__).resolve().parents[2] / "shared" / "data"))
    args = ap.parse_args(argv)
    width, height = (int(v) for v in args.size.lower().split("x"))
    slices = [int(s) for s in args.slices.split(",")]
    cfg = StudyConfig(width=width, height=height, phase_quality="test")
    head = " ".join(f"{a}-{b}".rjust(9) for a, b in zip(slices, slices[1:]))
    res = f"{args.light_res}^2" if args.light_res else "automatic"
    print(f"CIEDE2000 over cloud pixels between slice counts ({width} x {height}, light buffer {res})")
    print(f"{'scene':<20}{'light':<7}{'mode':<32}{head}")
    worst = {}
    for scene in args.scenes.split(","):
        loaded = load_scene(scene, cfg, data_dir=args.data)
        if loaded is None:
            print(f"{scene}: data absent, skipped")
            continue
        vol, _ = loaded
        for lighting in args.lightings.split(","):
            spec = view(vol, lighting, cfg)
            for name in args.modes.split(","):
                mode = MODES[name]
                detail = None
                if mode.detail:
                    from weather_mi.optics.detail import field
                    detail = field(vol.shape, seed=0, amplitude=0.5, spacing_m=vol.spacing)
                imgs, mask = convergence(vol, spec, mode, slices, args.light_res, detail)
                pw = pairwise(imgs, mask)
                for n0, n1, de in pw:
                    worst[(n0, n1)] = max(worst.get((n0, n1), 0.0), de)
                print(f"{scene:<20}{lighting:<7}{name:<32}" + " ".join(f"{de:9.3f}" for *_, de in pw), flush=True)
    print("worst: " + ", ".join(f"{a} vs {b}: {v:.3f}" for (a, b), v in worst.items()))
    ok = worst.get((256, 512), 0.0) <= 1.0 and worst.get((128, 256), 0.0) <= 2.0
    print("targets (256 vs 512 <= 1, 128 vs 256 <= 2):", "met" if ok else "NOT met")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
