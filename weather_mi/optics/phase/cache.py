"""Disk cache of computed phase tables (.npz), so that Mie and ray-tracing tables are built once.

Folder: ``$WEATHER_MI_CACHE`` if set, else ``~/.cache/weather-mi/phase/`` (``$XDG_CACHE_HOME`` is
honoured). File name: ``<constructor>-<sha256 of (constructor, parameters, CODE_VERSION)>.npz``.
Bump :data:`CODE_VERSION` whenever a change alters computed tables. Tables loaded once are also
kept in memory for the life of the process. The package ships the default-quality tables of both
species presets in ``weather_mi/phase/data/`` (same file names; regenerate them with
``python -m weather_mi.optics.phase.seed``), so a fresh installation renders without building them.
"""
from __future__ import annotations

import hashlib
import json
import os
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from .table import PhaseTable

CODE_VERSION = "phase-1"
SHIPPED = Path(__file__).resolve().parent / "data"
_MEMORY: dict[str, PhaseTable] = {}


def cache_dir() -> Path:
    """The cache folder (not created here)."""
    env = os.environ.get("WEATHER_MI_CACHE")
    if env:
        return Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "weather-mi" / "phase"


def _canonical(value):
    """JSON-able form of a parameter; arrays are represented by dtype, shape and a hash of bytes."""
    if isinstance(value, np.ndarray):
        arr = np.ascontiguousarray(value)
        return {"dtype": str(arr.dtype), "shape": list(arr.shape), "sha256": hashlib.sha256(arr.tobytes()).hexdigest()}
    if isinstance(value, Mapping):
        return {str(k): _canonical(v) for k, v in sorted(value.items())}
    if isinstance(value, (list, tuple)):
        return [_canonical(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return repr(float(value))
    if isinstance(value, (np.integer, int, bool, str)) or value is None:
        return value.item() if isinstance(value, np.generic) else value
    raise TypeError(f"cannot use {type(value).__name__} as a phase-table cache parameter")


def cache_key(name: str, params: Mapping) -> str:
    """Hex digest identifying a table: constructor name + parameters + code version."""
    blob = json.dumps({"name": name, "params": _canonical(params), "version": CODE_VERSION}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:32]


def cache_path(name: str, params: Mapping) -> Path:
    return cache_dir() / f"{name}-{cache_key(name, params)}.npz"


def load(path: Path) -> PhaseTable | None:
    """The table stored at ``path``, or None when missing or unreadable."""
    try:
        with np.load(path, allow_pickle=False) as d:
            return PhaseTable.from_npz_dict(d)
    except (OSError, KeyError, ValueError):
        return None


def save(path: Path, table: PhaseTable) -> None:
    """Write atomically (temporary file, then rename), so concurrent writers never leave a torn file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.stem, suffix=".tmp.npz")
    try:
        with os.fdopen(fd, "wb") as f:
            np.savez(f, **table.to_npz_dict())
        os.chmod(tmp, 0o644)  # mkstemp creates 0600; a cache is shareable
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def cached_table(name: str, params: Mapping, compute: Callable[[], PhaseTable], use_cache: bool = True) -> PhaseTable:
    """``compute()`` once per (name, params, CODE_VERSION): from memory, else from disk, else computed
    and stored. ``use_cache=False`` always computes and stores nothing."""
    if not use_cache:
        return compute()
    path = cache_path(name, params)
    key = str(path)
    table = _MEMORY.get(key)
    if table is None:
        table = load(path)
        if table is None and (SHIPPED / path.name).is_file():
            table = load(SHIPPED / path.name)
        if table is None:
            table = compute()
            try:
                save(path, table)
            except OSError as err:  # a read-only home is no reason to fail a render
                import warnings
                warnings.warn(f"could not write phase-table cache {path}: {err}", RuntimeWarning, stacklevel=2)
        _MEMORY[key] = table
    return table


def clear_memory() -> None:
    """Forget the in-process copies (the disk cache is kept)."""
    _MEMORY.clear()


__all__ = ["CODE_VERSION", "cache_dir", "cache_key", "cache_path", "cached_table", "clear_memory", "load", "save"]
