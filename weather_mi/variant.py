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
