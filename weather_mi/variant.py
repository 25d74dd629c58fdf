"""The chosen Mitsuba variant: the only global state of weather-mi, and plugin registration."""
from __future__ import annotations

VARIANTS_RGB = ("llvm_ad_rgb", "scalar_rgb", "cuda_ad_rgb")
_registered: set[str] = set()


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
    current = mi.variant()
    if current not in _registered:
        from .plugins import hydrometeor_mixture
        hydrometeor_mixture.register()
        _registered.add(current)
    return current
