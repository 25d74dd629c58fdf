"""The chosen Mitsuba variant: the only global state of weather-mi, and plugin registration.

``import weather_mi`` calls :func:`register_lazily`: the plugins (``hydrometeor_mixture``,
``majorant_volpath``) are registered with the variant already selected, if any, and with every variant
selected later (a Mitsuba variant callback); importing selects no variant. Functions that render call
:func:`ensure_registered`, which selects the default variant when none is.
"""
from __future__ import annotations

VARIANTS_RGB = ("llvm_ad_rgb", "scalar_rgb", "cuda_ad_rgb")
_registered: set[str] = set()
_callback_installed = False


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


def _register_current() -> None:
    import mitsuba as mi
    current = mi.variant()
    if current not in _registered:
        from .plugins import hydrometeor_mixture, majorant_volpath
        hydrometeor_mixture.register()
        majorant_volpath.register()
        _registered.add(current)
