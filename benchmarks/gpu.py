"""The GPU path: both renderers under ``cuda_ad_rgb`` against ``llvm_ad_rgb`` in the same process.

    .venv/bin/python benchmarks/gpu.py [--quick] [--out table.md]
    .venv/bin/python benchmarks/gpu.py --dry-run     # the same code on the CPU: LLVM as both variants, tiny

Without a usable CUDA device (``weather_mi.variant.cuda_usable``: a test kernel must run) it prints one
line saying so and exits 0. With one, on the demo supercell (``species="physical"``):

1. **Reference** (``render_reference``, ``majorant_volpath``, ``default_spec``; 16 passes): first render
   (compilation + 1 pass of 1 spp at 1/4 of the size; both renders seed 1), then seconds per spp for each variant, and the
   speed-up CUDA / LLVM. Agreement: z = (cuda - llvm) / sqrt(se_cuda^2 + se_llvm^2) per channel over the
   cloud pixels (eye-ray transmittance < 1/2): mean, max |z|, fraction |z| > 3 (a Gaussian gives 0.27%;
   16 passes give se from 15 degrees of freedom: ~0.9% for a t15).
2. **Slicer** (``SliceRenderer``, each mode of ``weather_mi.slicing.MODES``) at 300 x 300 with 128 slices
   and 1024 x 768 with 256 slices: frames per second (median of timed frames after two warm-up frames
   that compile; each timed frame changes a scaling, as an interactive user would) per variant, CUDA / LLVM,
   and max |cuda - llvm| / max(llvm) of the last frame.
3. **Texture hardware interpolation** (CUDA only): the slicer's two ``Texture3f`` are built with
   ``use_accel=False`` (float32 weights, as on LLVM); with ``use_accel=True`` the texture units
   interpolate with 8-bit weights (fixed point). The row gives fps and the image difference of the
   "per-species/multiple" mode at 300 x 300 with accel on vs off. (The reference's gridvolumes are built
   with ``accel: False`` for the same reason: its trackers interpolate the texels in float32.)

``--quick`` (meant to fit 5 min on an H200 including kernel compilation, most of it LLVM's): the
reference at 160 x 120 with 256 spp, 1 timed slicer frame per mode and size. Default: 320 x 240 with
1024 spp, 3 timed frames. Every timed frame follows two warm-up frames (the first compiles the frame,
the second the texture rebuild after a change of scaling). Each section prints as it finishes; a failing section prints its error and the others
still run (exit code 1 then). ``--dry-run`` runs every section with llvm_ad_rgb standing in for CUDA at
tiny sizes (48 x 36, 16 spp; slicer 64 x 48, 16 slices, two modes): it checks the script, not a GPU.
"""
from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
import traceback
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import weather_mi as wm  # noqa: E402
from weather_mi.variant import cuda_usable  # noqa: E402

VARIANTS = ("llvm_ad_rgb", "cuda_ad_rgb")
SLICER_SIZES = [(300, 300, 128), (1024, 768, 256)]
SLICER_MODES: list[str] | None = None   # None: every mode of MODES
ACCEL_MODE = "per-species/multiple"
GPU = "cuda_ad_rgb"                     # the variant under test (llvm_ad_rgb in --dry-run)
LINES: list[str] = []


def say(line: str = "") -> None:
    print(line, flush=True)
    LINES.append(line)


def device_name() -> str:
    try:
        out = subprocess.run(["nvidia-smi", "--query-gpu=name,driver_version", "--format=csv,noheader"],
                             capture_output=True, text=True, timeout=20)
        return out.stdout.strip().splitlines()[0] if out.returncode == 0 and out.stdout.strip() else "unknown GPU"
    except (OSError, subprocess.SubprocessError):
        return "unknown GPU"


def z_scores(a, b) -> np.ndarray:
    """(a - b) / sqrt(se_a^2 + se_b^2) over b's cloud pixels (transmittance < 1/2), all channels."""
    cloud = b.transmittance < 0.5
    se = np.sqrt(a.stderr.astype(np.float64) ** 2 + b.stderr.astype(np.float64) ** 2)[cloud]
    return ((a.radiance.astype(np.float64) - b.radiance)[cloud] / np.maximum(se, 1e-30)).ravel()


def reference_section(vol, width: int, height: int, spp: int) -> None:
    small = wm.scene.default_spec(vol, max(8, width // 4), max(6, height // 4))
    say(f"\n## Reference: majorant_volpath, {width} x {height}, {spp} spp in 16 passes, demo supercell")
    say("| variant | first render (s) | s per spp | speed-up vs llvm | cloud mean radiance |")
    say("|---|---:|---:|---:|---:|")
    images, per_spp = [], []
    for k, v in enumerate((VARIANTS[0], GPU)):
        t0 = time.perf_counter()
        wm.render_reference(small, vol, spp=1, passes=1, progress=False, variant=v)
        first = time.perf_counter() - t0
        # the same seed on both (other variants draw other numbers anyway); --dry-run: another seed
        seed = 2 if k and v == VARIANTS[0] else 1
        img = wm.render_reference(wm.scene.default_spec(vol, width, height, seed=seed), vol, spp=spp, passes=16,
                                  progress=False, variant=v)
        assert img.metadata["variant"] == v, img.metadata["variant"]
        images.append(img)
        per_spp.append(img.metadata["seconds"] / spp)
        cloud = img.transmittance < 0.5
        mean = float(img.radiance[cloud].mean()) if cloud.any() else float("nan")
        say(f"| {v} | {first:.1f} | {per_spp[-1]:.4f} | {per_spp[0] / per_spp[-1]:.1f}x | {mean:.5g} |")
    z = z_scores(images[1], images[0])
    cloud_px = int((images[0].transmittance < 0.5).sum())
    say(f"\n{GPU} vs llvm_ad_rgb over {cloud_px} cloud pixels x 3 channels: z mean {z.mean():+.3f}, max |z| "
        f"{np.abs(z).max():.2f}, fraction |z| > 3: {(np.abs(z) > 3).mean():.4f} (Gaussian 0.0027, t15 ~0.009)")
    tm = np.abs(images[1].transmittance - images[0].transmittance).max()
    say(f"eye-ray transmittance (cloud mask), max |{GPU} - llvm|: {tm:.2e}")


def slicer_frames(vol, mode_name: str, w: int, h: int, slices: int, frames: int, accel: bool = False):
    """(median seconds per frame, last frame's radiance) of one mode in the current variant."""
    import mitsuba as mi
    from weather_mi import detail
    from weather_mi.slicing import MODES, SliceParams, SliceRenderer
    mode = MODES[mode_name]
    field = detail.field(vol.shape, seed=0, spacing_m=vol.spacing) if mode.detail else None
    r = SliceRenderer(vol, mode, slices=slices, light_res=128, detail_field=field)
    if accel:  # the texture units' 8-bit interpolation weights, for the comparison only
        r.tex_eye = mi.Texture3f(mi.TensorXf(np.zeros(r.tex_eye.shape, np.float32)), use_accel=True)
        r.tex_light_src = mi.Texture3f(mi.TensorXf(np.zeros(r.tex_light_src.shape, np.float32)), use_accel=True)
    spec = wm.scene.default_spec(vol, w, h)
    img = r.frame(spec)  # warm-up: compiles the frame ...
    img = r.frame(spec, SliceParams(scale={"ice": 0.9}))  # ... and the rebuild of the textures after a change
    t = []
    for i in range(frames):
        img = r.frame(spec, SliceParams(scale={"ice": 1.0 + 0.1 * (i + 1)}))
        t.append(r.timing["total_s"])
    return statistics.median(t), img.radiance


def slicer_section(vol, frames: int) -> None:
    from weather_mi.slicing import MODES
    for w, h, slices in SLICER_SIZES:
        say(f"\n## Slicer: {w} x {h}, {slices} slices, light buffer 128^2 ({frames} timed frame(s) per mode)")
        say(f"| mode | llvm fps | {GPU} fps | ratio | max abs({GPU} - llvm) / max |")
        say("|---|---:|---:|---:|---:|")
        for name in SLICER_MODES or MODES:
            res = []
            for v in (VARIANTS[0], GPU):
                wm.set_variant(v)
                res.append(slicer_frames(vol, name, w, h, slices, frames))
            (tl, a), (tc, b) = res
            diff = float(np.abs(a - b).max() / max(float(a.max()), 1e-30))
            say(f"| {name} | {1 / tl:.2f} | {1 / tc:.2f} | {tl / tc:.1f}x | {diff:.2e} |")


def accel_section(vol, frames: int) -> None:
    wm.set_variant(GPU)
    w, h, slices = SLICER_SIZES[0]
    (t_sw, a), (t_hw, b) = (slicer_frames(vol, ACCEL_MODE, w, h, slices, frames, accel=x) for x in (False, True))
    diff = float(np.abs(a - b).max() / max(float(a.max()), 1e-30))
    rel = np.abs(a - b) / np.maximum(np.abs(a), 1e-6 * float(a.max()))
    say(f"\n## CUDA texture interpolation: {ACCEL_MODE}, {w} x {h}, {slices} slices")
    say("| Texture3f | fps | max abs diff / max vs use_accel=False | median relative diff |")
    say("|---|---:|---:|---:|")
    say(f"| use_accel=False (float weights; what the slicer uses) | {1 / t_sw:.2f} | 0 | 0 |")
    say(f"| use_accel=True (8-bit hardware weights) | {1 / t_hw:.2f} | {diff:.2e} | {float(np.median(rel)):.2e} |")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="~5 min on an H200: smaller reference, 1 timed frame")
    ap.add_argument("--out", type=Path, default=None, help="also write the table (markdown) here")
    ap.add_argument("--dry-run", action="store_true", help="llvm_ad_rgb as both variants, tiny sizes (no GPU)")
    args = ap.parse_args()
    global GPU, SLICER_SIZES, SLICER_MODES
    ok, why = cuda_usable()
    if args.dry_run:
        GPU, SLICER_SIZES, SLICER_MODES = "llvm_ad_rgb", [(64, 48, 16)], ["uniform/low-albedo", ACCEL_MODE]
    elif not ok:
        print(f"benchmarks/gpu.py: no usable CUDA device ({why}); nothing measured")
        return 0
    width, height, spp = (48, 36, 16) if args.dry_run else (160, 120, 256) if args.quick else (320, 240, 1024)
    frames = 1 if args.quick or args.dry_run else 3
    t0 = time.perf_counter()
    vol = wm.optical_volume(wm.synthetic.supercell(), species="physical")
    import drjit as dr
    import mitsuba as mi
    say(f"# weather-mi {wm.__version__} (mitsuba {mi.__version__}, drjit {dr.__version__}) on "
        f"{'no GPU: --dry-run, llvm twice' if args.dry_run else device_name()}; CPU threads {dr.thread_count()}; "
        f"demo supercell {vol.shape}{' (--quick)' if args.quick else ''}")
    failed = 0
    for name, run in (("reference", lambda: reference_section(vol, width, height, spp)),
                      ("slicer", lambda: slicer_section(vol, frames)),
                      ("texture interpolation", lambda: accel_section(vol, max(frames, 2)))):
        try:
            run()
        except Exception:  # report and go on: a later session gets the other sections anyway
            failed += 1
            say(f"\n## {name}: FAILED\n```\n{traceback.format_exc()}```")
        finally:
            wm.set_variant("llvm_ad_rgb")
    say(f"\ntotal {time.perf_counter() - t0:.0f} s")
    if args.out is not None:
        args.out.write_text("\n".join(LINES) + "\n")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
