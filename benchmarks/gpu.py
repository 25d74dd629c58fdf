"""The GPU path: both renderers under ``cuda_ad_rgb`` against ``llvm_ad_rgb`` in the same process.

    .venv/bin/python benchmarks/gpu.py [--quick] [--out table.md]
    .venv/bin/python benchmarks/gpu.py --dry-run     # the same code on the CPU: LLVM as both variants, tiny

Without a usable CUDA device (``weather_mi.kernel.variant.cuda_usable``: a test kernel must run) it prints one
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
the second the texture rebuild after a change of scaling). Each section prints as it finishes; a failing
section prints its error and the others still run (exit code 1 then). ``--dry-run`` runs every section
with llvm_ad_rgb standing in for CUDA at tiny sizes (48 x 36, 16 spp; slicer 64 x 48, 16 slices, two
modes): it checks the script, not a GPU.

Where the GPU machine has no libLLVM (Dr.Jit's LLVM backend absent: ``variant.llvm_usable``), the LLVM
side cannot run in the same process: ``--save-llvm NPZ`` renders the LLVM reference and the 300 x 300
slicer frames with the same settings on any machine, and ``--llvm-images NPZ`` on the GPU machine
compares with them (z-scores and image differences; LLVM timings then are the other machine's, marked).

On the project's device machine (an H200 with Python 3.12, no mitsuba, probably no libLLVM, nothing
reachable): prepare here, in the repository root (``build/`` is git-ignored; ~3 min on 2 cores)::

    mkdir -p build/gpu /tmp/whl312 /tmp/site312
    python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
        --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 -d /tmp/whl312 mitsuba==3.9.1 drjit==1.5.0
    for w in /tmp/whl312/*.whl; do python3 -m zipfile -e $w /tmp/site312; done
    (cd /tmp/site312 && rm -rf share mitsuba/include mitsuba/cmake mitsuba/pkgconfig mitsuba/mitsuba_stubs \
        drjit/include drjit/cmake mitsuba/{cuda,llvm}_ad_{mono,mono_polarized,spectral,spectral_polarized}.cpython-312* \
        mitsuba/scalar_{mono,mono_polarized,spectral,spectral_polarized}.cpython-312* && find . -name '*.pyi' -delete)
    tar cJf build/gpu/mi312.tar.xz -C /tmp/site312 .     # ~33 MB: the two wheels (67 MB) exceed a call's 64 MiB
    .venv/bin/python benchmarks/gpu.py --quick --save-llvm build/gpu/llvm_quick.npz

then one device call, ``carry=["build/gpu"]``, ``timeout_s=540``::

    mkdir -p /tmp/site && tar xJf build/gpu/mi312.tar.xz -C /tmp/site && ln -s ../plugins weather_mi/plugins &&
    export PYTHONPATH=/tmp/site PYTHONUNBUFFERED=1 && (ldconfig -p | grep -iE 'libLLVM|nvoptix'; nvidia-smi -L);
    python3 benchmarks/gpu.py --quick --llvm-images build/gpu/llvm_quick.npz --out $OUT/gpu.md 2>&1 | tee $OUT/gpu.log;
    python3 -m pytest -q -rs -p no:cacheprovider tests/test_gpu.py 2>&1 | tee $OUT/test_gpu.log

(``weather_mi/plugins`` -> ``plugins``: the package as installed, without installing it.)
"""
from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
import traceback
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import weather_mi as wm  # noqa: E402
from weather_mi.kernel.variant import cuda_usable, llvm_usable  # noqa: E402

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


def ref_spec(vol, width: int, height: int, seed: int):
    return wm.scene.spec.default_spec(vol, width, height, seed=seed)


def render_ref(vol, v: str, width: int, height: int, spp: int, seed: int = 1):
    """(seconds of a first render: compilation + 1 pass of 1 spp at 1/4 size, the Image) in variant v."""
    t0 = time.perf_counter()
    wm.render_reference(ref_spec(vol, max(8, width // 4), max(6, height // 4), seed), vol, spp=1, passes=1,
                        progress=False, variant=v)
    first = time.perf_counter() - t0
    img = wm.render_reference(ref_spec(vol, width, height, seed), vol, spp=spp, passes=16, progress=False, variant=v)
    assert img.metadata["variant"] == v, img.metadata["variant"]
    return first, img


def cloud_mean(img) -> float:
    cloud = img.transmittance < 0.5
    return float(img.radiance[cloud].mean()) if cloud.any() else float("nan")


def saved_reference(saved, width: int, height: int, spp: int):
    """The LLVM reference of ``--llvm-images`` as an Image-like namespace, or None (absent, other settings)."""
    if saved is None:
        return None
    meta = json.loads(str(saved["settings"]))
    if (meta["width"], meta["height"], meta["spp"]) != (width, height, spp):
        say(f"(--llvm-images holds {meta['width']} x {meta['height']} at {meta['spp']} spp, not these settings: "
            f"not used)")
        return None
    return SimpleNamespace(radiance=saved["ref_radiance"], stderr=saved["ref_stderr"],
                           transmittance=saved["ref_transmittance"], meta=meta)


def reference_section(vol, width: int, height: int, spp: int, llvm_here: bool, saved) -> None:
    say(f"\n## Reference: majorant_volpath, {width} x {height}, {spp} spp in 16 passes, demo supercell")
    say("| variant | first render (s) | s per spp | speed-up vs llvm | cloud mean radiance |")
    say("|---|---:|---:|---:|---:|")
    base, base_spp = None, None
    if llvm_here:
        first, base = render_ref(vol, "llvm_ad_rgb", width, height, spp)
        base_spp = base.metadata["seconds"] / spp
        say(f"| llvm_ad_rgb | {first:.1f} | {base_spp:.4f} | 1.0x | {cloud_mean(base):.5g} |")
    else:
        base = saved_reference(saved, width, height, spp)
        if base is not None:
            m = base.meta
            say(f"| llvm_ad_rgb (--llvm-images: {m['host']}, {m['threads']} threads, not this machine) | - | "
                f"{m['seconds'] / spp:.4f} | - | {cloud_mean(base):.5g} |")
    # the same seed as the LLVM render (other variants draw other numbers anyway); --dry-run: another seed
    first, img = render_ref(vol, GPU, width, height, spp, seed=2 if GPU == "llvm_ad_rgb" else 1)
    per = img.metadata["seconds"] / spp
    ratio = f"{base_spp / per:.1f}x" if base_spp else "-"
    say(f"| {GPU} | {first:.1f} | {per:.4f} | {ratio} | {cloud_mean(img):.5g} |")
    if base is None:
        say("\nno LLVM image to compare with (no LLVM backend here and no --llvm-images of these settings)")
        return
    z = z_scores(img, base)
    say(f"\n{GPU} vs llvm_ad_rgb over {int((base.transmittance < 0.5).sum())} cloud pixels x 3 channels: z mean "
        f"{z.mean():+.3f}, max |z| {np.abs(z).max():.2f}, fraction |z| > 3: {(np.abs(z) > 3).mean():.4f} "
        f"(Gaussian 0.0027, t15 ~0.009)")
    tm = np.abs(img.transmittance - base.transmittance).max()
    say(f"eye-ray transmittance (cloud mask), max |{GPU} - llvm|: {tm:.2e}")


def slicer_frames(vol, mode_name: str, w: int, h: int, slices: int, frames: int, accel: bool = False):
    """(median seconds per frame, last frame's radiance) of one mode in the current variant."""
    import mitsuba as mi
    from weather_mi.optics import detail
    from weather_mi.slicing import MODES, SliceParams, SliceRenderer
    from weather_mi.slicing.texture_storage import ChannelTextures
    mode = MODES[mode_name]
    field = detail.field(vol.shape, seed=0, spacing_m=vol.spacing) if mode.detail else None
    r = SliceRenderer(vol, mode, slices=slices, light_res=128, detail_field=field)
    if accel:  # the texture units' 8-bit interpolation weights, for the comparison only
        r.tex_eye = ChannelTextures(tuple(mi.Texture3f(mi.TensorXf(np.zeros((1, 1, 1) + t.shape[-1:], np.float32)),
                                                   use_accel=True) for t in r.tex_eye.parts))
        r.tex_light_src = mi.Texture3f(mi.TensorXf(np.zeros(r.tex_light_src.shape, np.float32)), use_accel=True)
    spec = wm.scene.spec.default_spec(vol, w, h)
    img = r.frame(spec)  # warm-up: compiles the frame ...
    img = r.frame(spec, SliceParams(scale={"ice": 0.9}))  # ... and the rebuild of the textures after a change
    t = []
    for i in range(frames):
        img = r.frame(spec, SliceParams(scale={"ice": 1.0 + 0.1 * (i + 1)}))
        t.append(r.timing["total_s"])
    return statistics.median(t), img.radiance


def slicer_key(name: str, w: int, h: int, slices: int) -> str:
    return f"slicer {name} {w}x{h}x{slices}"


def slicer_section(vol, frames: int, llvm_here: bool, saved) -> None:
    from weather_mi.slicing import MODES
    for w, h, slices in SLICER_SIZES:
        say(f"\n## Slicer: {w} x {h}, {slices} slices, light buffer 128^2 ({frames} timed frame(s) per mode)")
        say(f"| mode | llvm fps | {GPU} fps | ratio | max abs({GPU} - llvm) / max |")
        say("|---|---:|---:|---:|---:|")
        for name in SLICER_MODES or MODES:
            tl, a = None, None
            if llvm_here:
                wm.set_variant("llvm_ad_rgb")
                tl, a = slicer_frames(vol, name, w, h, slices, frames)
            elif saved is not None and slicer_key(name, w, h, slices) in saved:
                a = saved[slicer_key(name, w, h, slices)]   # rendered elsewhere (--llvm-images)
            wm.set_variant(GPU)
            tc, b = slicer_frames(vol, name, w, h, slices, frames)
            diff = f"{float(np.abs(a - b).max() / max(float(a.max()), 1e-30)):.2e}" if a is not None else "-"
            llvm_fps, ratio = (f"{1 / tl:.2f}", f"{tl / tc:.1f}x") if tl else ("-", "-")
            say(f"| {name} | {llvm_fps} | {1 / tc:.2f} | {ratio} | {diff} |")


def save_llvm(path: Path, vol, width: int, height: int, spp: int) -> None:
    """--save-llvm: the LLVM reference and slicer frames (first slicer size) that --llvm-images compares with."""
    import platform

    import drjit as dr
    from weather_mi.slicing import MODES
    wm.set_variant("llvm_ad_rgb")
    _, img = render_ref(vol, "llvm_ad_rgb", width, height, spp)
    out = {"ref_radiance": img.radiance, "ref_stderr": img.stderr, "ref_transmittance": img.transmittance}
    w, h, slices = SLICER_SIZES[0]
    for name in SLICER_MODES or MODES:
        out[slicer_key(name, w, h, slices)] = slicer_frames(vol, name, w, h, slices, 1)[1]
    settings = {"width": width, "height": height, "spp": spp, "seconds": img.metadata["seconds"],
                "host": platform.node(), "threads": int(dr.thread_count())}
    np.savez_compressed(path, settings=json.dumps(settings), **out)
    say(f"saved the LLVM reference ({width} x {height}, {spp} spp, {img.metadata['seconds']:.1f} s) and "
        f"{len(out) - 3} slicer frames ({w} x {h}, {slices} slices) to {path}")


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
    ap.add_argument("--save-llvm", type=Path, default=None, metavar="NPZ",
                    help="render the LLVM images for --llvm-images (same --quick/--dry-run) and stop; no GPU needed")
    ap.add_argument("--llvm-images", type=Path, default=None, metavar="NPZ",
                    help="where this machine has no LLVM backend: compare with these LLVM images (--save-llvm)")
    args = ap.parse_args()
    global GPU, SLICER_SIZES, SLICER_MODES
    ok, why = cuda_usable()
    if args.dry_run:
        GPU, SLICER_SIZES, SLICER_MODES = "llvm_ad_rgb", [(64, 48, 16)], ["uniform/low-albedo", ACCEL_MODE]
    elif not ok and args.save_llvm is None:
        print(f"benchmarks/gpu.py: no usable CUDA device ({why}); nothing measured")
        return 0
    width, height, spp = (48, 36, 16) if args.dry_run else (160, 120, 256) if args.quick else (320, 240, 1024)
    frames = 1 if args.quick or args.dry_run else 3
    t0 = time.perf_counter()
    vol = wm.optical_volume(wm.synthetic.supercell(), species="physical")
    if args.save_llvm is not None:
        save_llvm(args.save_llvm, vol, width, height, spp)
        return 0
    import drjit as dr
    import mitsuba as mi
    llvm_here = llvm_usable()
    saved = np.load(args.llvm_images) if args.llvm_images is not None else None
    say(f"# weather-mi {wm.__version__} (mitsuba {mi.__version__}, drjit {dr.__version__}) on "
        f"{'no GPU: --dry-run, llvm twice' if args.dry_run else device_name()}; CPU threads {dr.thread_count()}; "
        f"LLVM backend {'here' if llvm_here else 'absent here'}; demo supercell {vol.shape}"
        f"{' (--quick)' if args.quick else ''}")
    failed = 0
    for name, run in (("reference", lambda: reference_section(vol, width, height, spp, llvm_here, saved)),
                      ("slicer", lambda: slicer_section(vol, frames, llvm_here, saved)),
                      ("texture interpolation", lambda: accel_section(vol, max(frames, 2)))):
        try:
            run()
        except Exception:  # report and go on: a later session gets the other sections anyway
            failed += 1
            say(f"\n## {name}: FAILED\n```\n{traceback.format_exc()}```")
    say(f"\ntotal {time.perf_counter() - t0:.0f} s")
    if args.out is not None:
        args.out.write_text("\n".join(LINES) + "\n")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
