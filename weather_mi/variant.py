"""The chosen Mitsuba variant: the only global state of weather-mi, and plugin registration; with an
LLVM variant, Dr.Jit's CPU work split (:func:`tune_llvm`) and the SIMD width of path tracing
(:func:`path_tracing_width`).

``import weather_mi`` calls :func:`register_lazily`: the plugins (``hydrometeor_mixture``,
``majorant_volpath``) are registered with the variant already selected, if any, and with every variant
selected later (a Mitsuba variant callback); importing selects no variant. Functions that render call
:func:`ensure_registered`, which selects the default variant when none is.
"""
from __future__ import annotations

import contextlib

VARIANTS_RGB = ("llvm_ad_rgb", "scalar_rgb", "cuda_ad_rgb")
_registered: set[str] = set()
_callback_installed = False
# Lanes per work unit of Dr.Jit's LLVM backend (its default: 16384). A path-tracing pass of a few spp is a
# handful of such blocks, and their lengths differ (long random walks in cloud), so with 16384 one core
# idles while the other finishes the last block; 1024 gives the thread pool enough units to balance.
# benchmarks/llvm_block_size.py: 17% less time per pass on 2 cores, bit-identical images, the slicer unchanged.
LLVM_BLOCK_SIZE = 1024
DRJIT_DEFAULT_BLOCK_SIZE = 16384
# Lanes per SIMD packet while path tracing (``path_tracing_width``; Dr.Jit's default is the CPU's width, 8
# with AVX2). A packet loops until its slowest lane is done, and paths in cloud diverge at every loop (free
# flights, shadow walks and path lengths all heavy-tailed: 24% of the lanes of a packet of 8 busy in the
# inner walks), so 4 lanes waste less: 1.4x faster on the demo side view (benchmarks/reference_noise.py).
# The slicer's coherent kernels keep the CPU's width.
PATH_TRACING_VECTOR_WIDTH = 4
_tuned = False


def default_variant() -> str:
    """``cuda_ad_rgb`` when a CUDA device is usable, else ``llvm_ad_rgb``."""
    import drjit as dr
    try:
        if dr.has_backend(dr.JitBackend.CUDA):
            return "cuda_ad_rgb"
    except Exception:  # no driver
        pass
    return "llvm_ad_rgb"


def set_variant(name: str | None = None) -> str:
    """Select a Mitsuba variant (default :func:`default_variant`) and register our plugins with it."""
    import mitsuba as mi
    name = name or default_variant()
    if name not in mi.variants():
        raise ValueError(f"unknown Mitsuba variant {name!r}; expected one of {sorted(mi.variants())}")
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


def _core_function(name: str):
    """A function exported by Dr.Jit's core library (ctypes), or None where this build lacks it."""
    import ctypes
    import os
    import drjit as dr
    try:
        return getattr(ctypes.CDLL(os.path.join(os.path.dirname(dr.__file__), "libdrjit-core.so")), name)
    except (OSError, AttributeError):
        return None


def tune_llvm(block_size: int = LLVM_BLOCK_SIZE) -> bool:
    """Set Dr.Jit's LLVM block size (lanes per work unit of the CPU thread pool). Dr.Jit exports the
    setting from its core library without a Python binding: called through ctypes, and skipped (False)
    where the symbol is absent (another Dr.Jit build)."""
    import ctypes
    setter = _core_function("_Z23jit_llvm_set_block_sizej")
    if setter is None:
        return False
    setter.argtypes = [ctypes.c_uint32]
    setter(int(block_size))
    return True


def _core_uint(name: str) -> int | None:
    """The unsigned int returned by the argument-less core function ``name`` (None where it is absent)."""
    import ctypes
    getter = _core_function(name)
    if getter is None:
        return None
    getter.restype = ctypes.c_uint32
    return int(getter())


def llvm_vector_width() -> int | None:
    """Lanes per SIMD packet of Dr.Jit's LLVM backend (8 with AVX2; None where it cannot be read)."""
    return _core_uint("_Z21jit_llvm_vector_widthv")


def set_llvm_vector_width(width: int) -> bool:
    """Make Dr.Jit's LLVM backend compile kernels for SIMD packets of ``width`` lanes (keeping its target
    CPU and features; Embree takes 4, 8 or 16). Kernels are cached per width, so switching back and forth
    compiles each once. Through ctypes; False (nothing changed) where this Dr.Jit build lacks the symbols."""
    import ctypes
    cpu_of, features_of = _core_function("_Z19jit_llvm_target_cpuv"), _core_function("_Z24jit_llvm_target_featuresv")
    setter = _core_function("_Z19jit_llvm_set_targetPKcS0_j")
    if cpu_of is None or features_of is None or setter is None:
        return False
    cpu_of.restype = features_of.restype = ctypes.c_char_p   # copies: set_target frees the originals
    cpu, features = cpu_of(), features_of()
    if not cpu:  # the LLVM backend is not initialised
        return False
    setter.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_uint32]
    setter(cpu, features, int(width))
    return True


@contextlib.contextmanager
def path_tracing_width():
    """Within: an LLVM variant compiles for packets of PATH_TRACING_VECTOR_WIDTH lanes (the previous width
    after). Build the Mitsuba scene inside too: its Embree acceleration is made for the width of the day."""
    import mitsuba as mi
    before = llvm_vector_width() if (mi.variant() or "").startswith("llvm") else None
    changed = before is not None and before != PATH_TRACING_VECTOR_WIDTH and set_llvm_vector_width(PATH_TRACING_VECTOR_WIDTH)
    try:
        yield
    finally:
        if changed:
            set_llvm_vector_width(before)


def llvm_block_size() -> int | None:
    """Dr.Jit's current LLVM block size (None where it cannot be read)."""
    return _core_uint("_Z19jit_llvm_block_sizev")


def _register_current() -> None:
    import mitsuba as mi
    current = mi.variant()
    global _tuned
    if not _tuned and current.startswith("llvm"):  # once per process, and only over Dr.Jit's default
        if llvm_block_size() == DRJIT_DEFAULT_BLOCK_SIZE:
            tune_llvm()
        _tuned = True
    if current not in _registered:
        from .plugins import hydrometeor_mixture, majorant_volpath
        hydrometeor_mixture.register()
        majorant_volpath.register()
        _registered.add(current)
