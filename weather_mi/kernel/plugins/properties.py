"""Property parsing helpers of ``majorant_volpath``: errors name the plugin and the property."""
from __future__ import annotations

import numpy as np

PLUGIN_NAME = "majorant_volpath"


def check(ok, message: str) -> None:
    """Raise ValueError("majorant_volpath: <message>") unless ``ok``."""
    if not ok:
        raise ValueError(f"{PLUGIN_NAME}: {message}")


def choice(props, name: str, default: str, allowed: tuple) -> str:
    """The string property ``name``, one of ``allowed``."""
    value = str(props.get(name, default))
    options = ", ".join(repr(a) for a in allowed[:-1]) + f" or {allowed[-1]!r}"
    check(value in allowed, f"'{name}' must be {options}, got {value!r}")
    return value


def majorant_property(value) -> np.ndarray:
    """The ``majorant`` property as a finite, non-negative float32 (Z, Y, X) array."""
    m = np.asarray(value, np.float32)
    if m.ndim == 4 and m.shape[3] == 1:
        m = m[..., 0]
    check(m.ndim == 3, f"'majorant' must be a (Z, Y, X) tensor, got shape {m.shape}")
    check(np.all(np.isfinite(m)) and not np.any(m < 0), "'majorant' must be finite and >= 0")
    return np.ascontiguousarray(m)
