"""What a Dask worker has installed, asked before anything is submitted (``weather_mi.reference.cluster``).

This module is sent to workers by value (``cloudpickle.register_pickle_by_value``), not imported there,
so it runs on a worker that lacks weather_mi: keep it to the standard library.
"""
from __future__ import annotations

import importlib


def versions(names: list[str]) -> dict:
    """{package: its __version__, or None when it cannot be imported} and {package: the import error}."""
    found, errors = {}, {}
    for name in names:
        try:
            module = importlib.import_module(name)
        except Exception as exc:  # missing, or broken (a dependency missing): both mean "cannot render"
            found[name], errors[name] = None, f"{type(exc).__name__}: {exc}"
        else:
            found[name] = getattr(module, "__version__", "unknown")
    return {"versions": found, "errors": errors}
