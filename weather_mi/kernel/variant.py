"""The chosen Mitsuba variant: the only global state of weather-mi, and plugin registration; with an
LLVM variant, Dr.Jit's CPU work split (:func:`tune_llvm`) and the SIMD width of path tracing
(:func:`path_tracing_width`); whether this process can run CUDA at all (:func:`cuda_usable`: a tiny
kernel, not just a driver library that loads).

Settings of Dr.Jit's LLVM backend are applied only while an LLVM variant is selected (:func:`is_llvm`):
on CUDA (and scalar) variants they are skipped, not an error. They are set through ctypes symbols of
``libdrjit-core.so`` that only the CPU thread pool and the LLVM code generator read; on a GPU the kernel
is one CUDA launch over all lanes, so a CPU block size or a SIMD packet width means nothing there.

``import weather_mi`` calls :func:`register_lazily`: the plugins (``hydrometeor_mixture``,
``majorant_volpath``) are registered with the variant already selected, if any, and with every variant
selected later (a Mitsuba variant callback); importing selects no variant. Functions that render call
:func:`ensure_registered`, which selects the default variant when none is.
"""
from __future__ import annotations

import contextlib

from .jit_settings import (DRJIT_DEFAULT_BLOCK_SIZE, LLVM_BLOCK_SIZE, llvm_block_size,  # noqa: F401 (re-exported)
                           llvm_vector_width, set_llvm_vector_width, tune_llvm)

VARIANTS_RGB = ("llvm_ad_rgb", "scalar_rgb", "cuda_ad_rgb")
_registered: set[str] = set()
_callback_installed = False
# Lanes per SIMD packet while path tracing (``path_tracing_width``; Dr.Jit's default is the CPU's width, 8
# with AVX2). A packet loops until its slowest lane is done, and paths in cloud diverge at every loop (free
# flights, shadow walks and path lengths all heavy-tailed: 24% of the lanes of a packet of 8 busy in the
# inner walks), so 4 lanes waste less: 1.4x faster on the demo side view (benchmarks/reference_noise.py).
# The slicer's coherent kernels keep the CPU's width.
PATH_TRACING_VECTOR_WIDTH = 4
_tuned = False


_cuda_probe: tuple[bool, str] | None = None   # this process's cuda_usable() result (a GPU does not come and go)


def is_llvm(variant: str | None = None) -> bool:
    """Whether ``variant`` (default: the selected one) is an LLVM variant, the only kind whose kernels the
    LLVM-backend settings of :mod:`weather_mi.kernel.jit_settings` touch."""
    if variant is None:
        import mitsuba as mi
        variant = mi.variant()
    return bool(variant) and variant.startswith("llvm")


def cuda_usable() -> tuple[bool, str]:
    """(whether this process can render with ``cuda_ad_rgb``, why or why not), probed once per process.

    True only when Mitsuba has the variant compiled in, Dr.Jit's CUDA backend initialises (a driver and a
    device) and a tiny kernel runs there and returns the right numbers: ``dr.has_backend`` alone is true
    with a driver library whose device is unusable (taken, too old for the PTX, out of memory). Without a
    driver ``mi.set_variant("cuda_ad_rgb")`` raises ImportError ("jit_init_thread_state(): the CUDA
    backend hasn't been initialized ...") and leaves the previous variant selected."""
    global _cuda_probe
    if _cuda_probe is None:
        _cuda_probe = _probe_cuda()
    return _cuda_probe


def _probe_cuda() -> tuple[bool, str]:
    import drjit as dr
    import mitsuba as mi
    if "cuda_ad_rgb" not in mi.variants():
        return False, "this Mitsuba build has no cuda_ad_rgb variant"
    try:
        if not dr.has_backend(dr.JitBackend.CUDA):
            return False, "Dr.Jit found no usable CUDA driver/device (drjit.has_backend(CUDA) is False)"
        import drjit.cuda
        got = probe_kernel(drjit.cuda)
    except Exception as exc:  # a driver that loads but cannot run: any failure means "no"
        return False, f"a CUDA test kernel failed ({type(exc).__name__}: {exc})"
    if got != 12.0:
        return False, f"a CUDA test kernel returned {got}, expected 12"
    return True, "a CUDA test kernel ran"


def probe_kernel(backend) -> float:
    """2 (1 + 2 + 3) computed by one kernel of the Dr.Jit backend module ``backend`` (``drjit.cuda``,
    ``drjit.llvm``) and read back to the host: 12.0 where the backend works."""
    import drjit as dr
    x = backend.Float(1.0, 2.0, 3.0)
    return float(dr.sum(x * 2.0).numpy()[0])


def llvm_usable() -> bool:
    """Whether Dr.Jit's LLVM backend initialises in this process (a libLLVM >= 16 found, or the one
    ``DRJIT_LIBLLVM_PATH`` names): a GPU machine may have CUDA and no libLLVM."""
    import drjit as dr
    try:
        return bool(dr.has_backend(dr.JitBackend.LLVM))
    except Exception:
        return False


def default_variant() -> str:
    """``cuda_ad_rgb`` where this process can run it (:func:`cuda_usable`), else ``llvm_ad_rgb``."""
    return "cuda_ad_rgb" if cuda_usable()[0] else "llvm_ad_rgb"


def spectral_variant() -> str:
    """The spectral ground truth's variant: ``cuda_ad_spectral`` where this process can run CUDA, else
    ``llvm_ad_spectral``; a RuntimeError naming what is missing when this Mitsuba build has neither."""
    import mitsuba as mi
    names = [v for v in (("cuda_ad_spectral",) if cuda_usable()[0] else ()) + ("llvm_ad_spectral",)
             if v in mi.variants()]
    if not names:
        raise RuntimeError("this Mitsuba build has no spectral variant (llvm_ad_spectral or cuda_ad_spectral; "
                           f"it has {sorted(mi.variants())}): install the mitsuba wheel, which ships them, or "
                           "render without --spectral")
    return names[0]


def set_variant(name: str | None = None) -> str:
    """Select a Mitsuba variant (default :func:`default_variant`) and register our plugins with it."""
    import mitsuba as mi
    name = name or default_variant()
    if name not in mi.variants():
        raise ValueError(f"unknown Mitsuba variant {name!r}; expected one of {sorted(mi.variants())}")
    if name.startswith("cuda") and mi.variant() != name and not cuda_usable()[0]:
        # checked first: mi.set_variant raises a bare ImportError from Dr.Jit's core otherwise
        raise RuntimeError(f"Mitsuba variant {name!r} cannot run in this process: {cuda_usable()[1]}; "
                           f"use 'llvm_ad_rgb' (the CPU)")
    if mi.variant() != name:
        mi.set_variant(name)
    ensure_registered()
    return name


def ensure_registered() -> str:
    """Register the weather-mi plugins with the current variant (choosing the default if none is set)."""
    import mitsuba as mi
    if mi.variant() is None:
        mi.set_variant(default_variant())
    _register_current()
    return mi.variant()


def register_lazily() -> None:
    """Register the plugins with the current variant, if one is selected, and with each variant selected
    from now on (once per variant); selects none."""
    global _callback_installed
    import mitsuba as mi
    if not _callback_installed:
        mi.detail.add_variant_callback(_on_variant_change)
        _callback_installed = True
    if mi.variant() is not None:
        _register_current()


def _on_variant_change(old: str | None, new: str | None) -> None:
    if new is not None:
        _register_current()


@contextlib.contextmanager
def path_tracing_width():
    """Within: an LLVM variant compiles for packets of PATH_TRACING_VECTOR_WIDTH lanes (the previous width
    after). Build the Mitsuba scene inside too: its Embree acceleration is made for the width of the day.
    Other variants: nothing (CUDA has no SIMD packets to size: a warp is 32 lanes in hardware, and
    OptiX, not Embree, traces its rays)."""
    before = llvm_vector_width() if is_llvm() else None
    changed = before is not None and before != PATH_TRACING_VECTOR_WIDTH and set_llvm_vector_width(PATH_TRACING_VECTOR_WIDTH)
    try:
        yield
    finally:
        if changed:
            set_llvm_vector_width(before)


def _register_current() -> None:
    import mitsuba as mi
    current = mi.variant()
    global _tuned
    # the LLVM block size splits work among CPU threads: set once per process on the first LLVM variant,
    # and only over Dr.Jit's default; on CUDA skipped (a launch is not split into CPU blocks)
    if not _tuned and is_llvm(current):
        if llvm_block_size() == DRJIT_DEFAULT_BLOCK_SIZE:
            tune_llvm()
        _tuned = True
    if current not in _registered:
        from .plugins import hydrometeor_mixture, majorant_volpath, raytable_sensor
        hydrometeor_mixture.register()
        majorant_volpath.register()
        raytable_sensor.register()
        _registered.add(current)
