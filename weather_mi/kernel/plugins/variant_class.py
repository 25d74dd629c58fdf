"""Python plugin classes per Mitsuba variant.

A class derived from ``mi.PhaseFunction`` (or any Mitsuba base) is bound to the variant that was
active when the class statement ran; after ``mi.set_variant`` to another variant its instances
cannot be made ("incompatible function arguments"). The plugins therefore write their methods in
a plain class and get, per variant, a class on that variant's base with those methods (nanobind
types take one base, so the methods are copied, not inherited).
"""
from __future__ import annotations

import mitsuba as mi

_CLASSES: dict = {}


def variant_class(methods: type, base: str) -> type:
    """A class named like ``methods`` (minus a leading underscore) on ``mi.<base>`` of the current
    variant, with ``methods``' attributes; made once per variant."""
    key = (mi.variant(), methods, base)
    if key not in _CLASSES:
        attrs = {k: v for k, v in vars(methods).items() if k not in ("__dict__", "__weakref__")}
        _CLASSES[key] = type(methods.__name__.lstrip("_"), (getattr(mi, base),), attrs)
    return _CLASSES[key]
