"""What a resumable run keeps on disk: the options it was started with (a resumed run with others is
refused before anything is rendered: its finished parts would not match) and, for a tiled render, each
finished tile (``TileStore``: OUT.tiles/tile-K.npz, written whole or not at all), so that a resumed run
renders only the tiles still missing."""
from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np

OPTIONS_FILE = "options.json"


def check_recorded_options(work: Path, options: dict | None, resume: bool, parts: str = "times",
                           run: str = "the loop") -> None:
    """Record ``options`` (JSON-able: what the run's ``parts`` depend on) in ``work``, or, resuming, compare
    them with those recorded: a ValueError naming each that differs (before anything is rendered)."""
    if options is None:
        return
    options = json.loads(json.dumps(options, default=str))
    path = Path(work) / OPTIONS_FILE
    if resume and path.is_file():
        before = json.loads(path.read_text())
        diff = [f"{k} {before.get(k)!r}, now {options.get(k)!r}" for k in sorted(set(before) | set(options))
                if before.get(k) != options.get(k)]
        if diff:
            raise ValueError(f"{work} holds {parts} rendered with other options ({'; '.join(diff)}): resume with "
                             f"the same options, or delete it to render {run} afresh")
    Path(work).mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(options, indent=1, sort_keys=True))


def tiles_folder(output) -> Path:
    """The working folder of a tiled render beside its output: OUT.tiles."""
    output = Path(output)
    return output.with_name(output.name + ".tiles")


class TileStore:
    """Finished tiles of a tiled render in ``folder`` (``tiles_folder``): each tile's arrays (radiance,
    standard error, transmittance) and figures (JSON-able scalars and lists) in tile-K.npz."""

    ARRAYS = ("radiance", "stderr", "transmittance")

    def __init__(self, folder):
        self.folder = Path(folder)

    def path(self, index: int) -> Path:
        return self.folder / f"tile-{int(index)}.npz"

    def unfinished(self) -> bool:
        """Whether the folder holds a run's options or tiles (an unfinished render)."""
        return self.folder.is_dir() and any(self.folder.iterdir())

    def check(self, options: dict, resume: bool) -> None:
        """A ValueError where an unfinished render is here and ``resume`` is false, or it was started with other
        ``options``; then the options recorded (``check_recorded_options``), the old tiles gone when not resuming."""
        if self.unfinished() and not resume:
            raise ValueError(f"{self.folder} holds the tiles of an unfinished render: add --resume to continue it "
                             "(finished tiles are not rendered again), or delete it to render afresh")
        check_recorded_options(self.folder, options, resume, "tiles", "the image")

    def save(self, index: int, result: dict) -> Path:
        """Tile ``index``'s ``result`` (its arrays and figures; ``tile`` is the plan's, not kept), written to a
        temporary file and renamed into place."""
        arrays = {k: np.asarray(result[k]) for k in self.ARRAYS if result.get(k) is not None}
        figures = {k: v for k, v in result.items() if k not in self.ARRAYS and k != "tile"}
        path = self.path(index)
        tmp = path.with_name(path.name + ".part.npz")
        np.savez(tmp, figures=np.array(json.dumps(figures, default=_plain)), **arrays)
        os.replace(tmp, path)
        return path

    def load(self, index: int) -> dict | None:
        """Tile ``index``'s result as ``save`` got it (without ``tile``), or None where it is not finished."""
        path = self.path(index)
        if not path.is_file():
            return None
        with np.load(path) as z:
            out = json.loads(str(z["figures"]))
            for k in self.ARRAYS:
                out[k] = z[k] if k in z.files else None
        return out

    def remove(self) -> None:
        """The folder and everything in it (once the products are written)."""
        shutil.rmtree(self.folder, ignore_errors=True)


def _plain(v):
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, (tuple, np.ndarray)):
        return list(np.asarray(v).tolist())
    return str(v)


__all__ = ["check_recorded_options", "tiles_folder", "TileStore", "OPTIONS_FILE"]
