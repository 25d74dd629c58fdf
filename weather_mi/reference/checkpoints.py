"""Checkpoints of a reference render: the running estimate after every pass in a ``.npz``, keyed by the
render's fingerprint (scene, volume, phase tables, sample plan, estimator options), so that a resumed
render continues only the render that wrote it. A checkpoint is written under a temporary name and
renamed into place: a failed write (a full disk) leaves the previous pass's checkpoint whole.
"""
from __future__ import annotations

import errno
import hashlib
import json
import os
from pathlib import Path

import numpy as np

from ..errors import OutputWriteError
from ..optics.volume import OpticalVolume
from ..io.output_paths import written_atomically
from ..scene.spec import SceneSpec


def fingerprint(spec: SceneSpec, vol: OpticalVolume, spp_list, *options) -> str:
    """SHA-256 (hex) of what a render's images depend on: the scene, the sample plan ``spp_list`` and the
    estimator ``options`` (JSON), the volume's extinction, albedo, species weights, phase tables and bbox."""
    h = hashlib.sha256()
    h.update(json.dumps([spec.to_dict(), spp_list, *options], sort_keys=True, default=str).encode())
    for a in (vol.beta_total, vol.albedo, vol.weights):  # their buffers as they are: no copy of a grid
        a = np.asarray(a)
        if a.flags.c_contiguous:
            h.update(memoryview(a).cast("B"))
        else:  # a view (a grey albedo: one channel read three times): the same bytes, a level at a time
            for level in a:
                h.update(memoryview(np.ascontiguousarray(level)).cast("B"))
    for t in vol.require_phase_tables():  # the phase functions are part of the scene too
        h.update(np.ascontiguousarray(t.theta, np.float64).tobytes())
        h.update(np.ascontiguousarray(t.values, np.float64).tobytes())
    h.update(json.dumps([list(map(float, p)) for p in vol.bbox]).encode())
    air = getattr(vol, "air", None)
    if air is not None:  # the air in the box (none: the key of before)
        for a in (air.extinction_levels, air.scattering_levels):
            h.update(np.ascontiguousarray(a, np.float32).tobytes())
    if vol.periodic:  # periodic boundaries (none: the key of before)
        h.update(f"periodic={vol.periodic}".encode())
    terrain = getattr(vol, "terrain", None)
    if terrain is not None:  # the ground mesh (no terrain: the key of before)
        for a in (terrain.x, terrain.y, terrain.height_m, terrain.albedo):
            h.update(np.ascontiguousarray(a, np.float64).tobytes())
        if terrain.albedo_rgb is not None or terrain.sea:  # the surface's channels and sea (else: as before)
            h.update(np.ascontiguousarray(terrain.vertex_rgb(), np.float64).tobytes())
            h.update(np.ascontiguousarray(terrain.water, np.int8).tobytes())
            h.update(json.dumps([bool(terrain.sea), terrain.wind_m_s]).encode())
            if terrain.sea_normal is not None:
                h.update(np.ascontiguousarray(terrain.sea_normal, np.float64).tobytes())
    return h.hexdigest()


def save_checkpoint(path: Path, state: dict) -> None:
    """Write ``state`` (key, mean, m2, done, seconds, spp_done) to ``path`` atomically.

    Raises
    ------
    OutputWriteError
        When it cannot be written (a full disk): it names the checkpoint and says that the one of the
        previous pass, if any, is kept whole at ``path`` (a render resumes from it).
    """
    path = Path(path)
    try:
        with written_atomically(path, "checkpoint") as tmp:
            np.savez(tmp, **state)
    except OutputWriteError as exc:
        done = int(state.get("done", 0))
        exc.advice = "the render stopped"
        if path.is_file() and done > 1:
            kept = "its first pass" if done == 2 else f"its first {done - 1} passes"
            when = "there is space" if exc.errno in (errno.ENOSPC, errno.EDQUOT) else "it can be written"
            exc.advice += f"; the checkpoint keeps {kept}, whole, to resume from once {when}"
        raise


def load_checkpoint(path: Path, key: str, spp_list) -> tuple:
    """(mean, m2, passes done, seconds, spp done) from a checkpoint of this render (``key``); ValueError
    naming the file when it is unreadable or belongs to another render."""
    import zipfile
    try:
        with np.load(path) as state:
            stored = str(state["key"])
            if stored == key:
                done = int(state["done"])
                spp_done = int(state["spp_done"]) if "spp_done" in state else sum(spp_list[:done])
                return state["mean"], state["m2"], done, float(state["seconds"]), spp_done
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        raise ValueError(f"checkpoint {path} cannot be read ({type(exc).__name__}: {exc}); delete it to "
                         "render afresh (without resume / --resume)") from exc
    raise ValueError(f"checkpoint {path} belongs to a different scene, volume or sample plan")


def keep_aside(path: Path) -> None:
    """A checkpoint found where a fresh render will write its own: renamed to <stem>.previous.npz, with a
    warning (it is never discarded silently)."""
    import warnings
    aside = path.with_name(f"{path.name[:-len('.npz')] if path.name.endswith('.npz') else path.name}.previous.npz")
    os.replace(path, aside)
    warnings.warn(f"checkpoint {path} exists and resume was not asked for: kept aside as {aside} (pass "
                  "resume=True to continue a render from a checkpoint)", UserWarning, stacklevel=4)
