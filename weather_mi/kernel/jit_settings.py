"""Dr.Jit's core settings that have no Python binding (the LLVM backend's block size and SIMD width),
read and set through ctypes from ``libdrjit-core.so``. Below both the plugins and :mod:`weather_mi.kernel.variant`
(which re-exports these names), so that neither imports the other for them.

Only for LLVM variants: callers apply them while an LLVM variant is selected (``variant.is_llvm``) and
skip them on CUDA, whose kernels read neither setting (one GPU launch over all lanes: no CPU blocks, no
SIMD packets).
"""
from __future__ import annotations

# Lanes per work unit of Dr.Jit's LLVM backend (its default: 16384). A path-tracing pass of a few spp is a
# handful of such blocks, and their lengths differ (long random walks in cloud), so with 16384 one core
# idles while the other finishes the last block; 1024 gives the thread pool enough units to balance.
# benchmarks/llvm_block_size.py: 17% less time per pass on 2 cores, bit-identical images, the slicer unchanged.
LLVM_BLOCK_SIZE = 1024
DRJIT_DEFAULT_BLOCK_SIZE = 16384


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


def llvm_block_size() -> int | None:
    """Dr.Jit's current LLVM block size (None where it cannot be read)."""
    return _core_uint("_Z19jit_llvm_block_sizev")
