"""A few results kept by the digest of what they are computed from, within one process: tables a render builds
anew from the same inputs each time (the spectral mode's phase values by wavelength, ``kernel.medium``; its lanes'
alias tables, ``kernel.plugins.lane_directions``)."""
from __future__ import annotations

import hashlib


def digest(*parts) -> str:
    """SHA-1 of ``parts``: bytes-like parts (numpy arrays: their bytes; pass contiguous ones) as they are, anything
    else by its repr."""
    h = hashlib.sha1()
    for p in parts:
        h.update(p.tobytes() if hasattr(p, "tobytes") else repr(p).encode())
        h.update(b"|")
    return h.hexdigest()


class Kept:
    """At most ``size`` results by key, the oldest dropped first."""

    def __init__(self, size: int):
        self.size, self._items = int(size), {}

    def get(self, key, make):
        """The result kept under ``key``, else ``make()`` kept under it."""
        if key not in self._items:
            self._items[key] = make()
            while len(self._items) > self.size:
                self._items.pop(next(iter(self._items)))
        return self._items[key]

    def clear(self) -> None:
        self._items.clear()

    def __len__(self) -> int:
        return len(self._items)
