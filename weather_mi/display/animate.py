"""An animation of a storm's time series (``weather-mi animate``): every time rendered from one camera
(optionally orbiting), by the slicer or the path-traced reference, written as EXR frames, an MP4 and a
contact-sheet PNG with one exposure for the whole series.

With a Dask client, slicer frames are tasks spread over the workers, and reference frames spread their
passes over the workers (``render_reference(client=...)``, one frame after another, each frame
checkpointed so that an interrupted animation resumes where it stopped).
"""
from __future__ import annotations

import uuid
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..io.image import Image, auto_exposure, to_srgb8
from ..optics.volume import OpticalVolume
from ..scene.spec import SceneSpec

RENDERERS = ("slices", "reference")
DEFAULT_SLICER_MODE = "per-species/multiple"


@dataclass
class Animation:
    frames: list[Path]       # EXR, one per time
    mp4: Path
    contact_sheet: Path
    images: list[Image]


def orbit(spec: SceneSpec, pivot_xy, degrees: float) -> SceneSpec:
    """``spec`` with its camera (origin and target) turned clockwise, seen from above, by ``degrees``
    about the vertical axis through ``pivot_xy`` (metres); the sun stays where it is."""
    a = np.radians(degrees)
    c, s = np.cos(a), np.sin(a)
    px, py = (float(v) for v in pivot_xy)

    def turned(p):
        dx, dy = p[0] - px, p[1] - py
        return (px + c * dx + s * dy, py - s * dx + c * dy, float(p[2]))
    return replace(spec, camera=replace(spec.camera, origin=turned(spec.camera.origin),
                                        target=turned(spec.camera.target)))


def storm_centre_xy(volumes: list[OpticalVolume]) -> tuple[float, float]:
    """Horizontal centre of the box holding the cloud of every time: the pivot of an orbit."""
    boxes = np.array([np.asarray(v.occupied_bbox(), np.float64) for v in volumes])  # (T, 2, 3)
    lo, hi = boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)
    return float((lo[0] + hi[0]) / 2), float((lo[1] + hi[1]) / 2)


def _slice_frame_task(spec: SceneSpec, vol: OpticalVolume, variant: str, slices: int, mode: str) -> Image:
    """On a Dask worker: one slicer frame in the client's variant."""
    from ..reference.dask_passes import on_render_thread
    return on_render_thread(_slice_frame, spec, vol, variant, slices, mode)


def _slice_frame(spec, vol, variant, slices, mode):
    from ..kernel.variant import set_variant
    set_variant(variant)
    return slicer_image(spec, vol, slices, mode)


def slicer_image(spec, vol, slices: int, mode: str) -> Image:
    """One slicer frame (``MODES[mode]``): with an atmosphere in ``spec`` the slicer puts the air along the eye
    rays, inside the box and out, on it itself (``slicing.eye_air``)."""
    from ..slicing import MODES, SliceRenderer
    return SliceRenderer(vol, MODES[mode], slices).frame(spec)


def _slicer_frames(specs, volumes, client, slices: int, mode: str, bar):
    if client is None:
        for spec, vol in zip(specs, volumes):
            yield slicer_image(spec, vol, slices, mode)
            bar.update(1)
        return
    import mitsuba as mi

    from ..reference import cluster
    from ..reference.dask_passes import held
    cluster.check_workers(client, None, mi.variant())
    token = uuid.uuid4().hex[:12]
    data = [held(client, vol, f"weather-mi-volume-{token}-{k}") for k, vol in enumerate(volumes)]
    futures = [client.submit(_slice_frame_task, spec, vol, mi.variant(), slices, mode, key=f"weather-mi-frame-{token}-{k}",
                             pure=False) for k, (spec, vol) in enumerate(zip(specs, data))]
    try:
        for f in futures:  # in order; the later frames render meanwhile
            yield f.result()
            bar.update(1)
    finally:
        client.cancel(futures + data, force=True)


def _reference_frames(specs, volumes, client, frames_dir: Path, reference_kw: dict, bar):
    from ..reference.render import render_reference
    for k, (spec, vol) in enumerate(zip(specs, volumes)):
        ckpt = frames_dir / f"frame_{k:04d}.ckpt.npz"
        img = render_reference(spec, vol, client=client, checkpoint=ckpt, resume=ckpt, **reference_kw)
        ckpt.unlink(missing_ok=True)
        yield img
        bar.update(1)


def animate(volumes: list[OpticalVolume], spec: SceneSpec, out_dir, *, renderer: str = "slices",
            labels: list[str] | None = None, orbit_deg: float = 0.0, client=None, fps: float = 4.0,
            exposure: float | None = None, slices: int = 128, mode: str = DEFAULT_SLICER_MODE,
            reference_kw: dict | None = None, progress: bool = True) -> Animation:
    """Render every volume (one per time, same grid) as seen by ``spec`` and write ``out_dir``/frames/
    frame_NNNN.exr, ``out_dir``/animation.mp4 and ``out_dir``/contact_sheet.png.

    orbit_deg   : the camera turns about the storm (``storm_centre_xy``) by this many degrees from the first
                  frame to the last (0: fixed).
    client      : None, a dask Client or a scheduler address (see the module docstring).
    mode        : renderer="slices": one of ``weather_mi.slicing.MODES`` (default the "multiple" light model,
                  the one closest to the path tracer; the paper's Table IV modes render clouds grey).
    reference_kw: arguments of ``render_reference`` for renderer="reference" (spp, target_rse, ...).
    exposure    : of the MP4 and the sheet (None: automatic, one for the whole series)."""
    from tqdm.auto import tqdm

    from ..reference import cluster
    from .movie import contact_sheet, write_mp4
    if renderer not in RENDERERS:
        raise ValueError(f"renderer must be one of {RENDERERS}, got {renderer!r}")
    if not volumes:
        raise ValueError("nothing to animate: no volumes")
    from ..slicing import MODES
    if mode not in MODES:
        raise ValueError(f"slicer mode must be one of {list(MODES)}, got {mode!r}")
    labels = list(labels) if labels is not None else [f"t{k}" for k in range(len(volumes))]
    if len(labels) != len(volumes):
        raise ValueError(f"{len(labels)} labels for {len(volumes)} frames")
    n = len(volumes)
    pivot = storm_centre_xy(volumes)
    angles = [orbit_deg * k / max(n - 1, 1) for k in range(n)]
    specs = [orbit(spec, pivot, a) for a in angles]
    out = Path(out_dir)
    frames_dir = out / "frames"
    frames_dir.mkdir(parents=True, exist_ok=True)
    client, owned = cluster.connect(client) if client is not None else (None, False)
    bar = tqdm(total=n, desc=f"animate ({renderer})", unit="frame", disable=not progress)
    try:
        if renderer == "slices":
            source = _slicer_frames(specs, volumes, client, slices, mode, bar)
        else:
            kw = dict(progress=False, **(reference_kw or {}))
            source = _reference_frames(specs, volumes, client, frames_dir, kw, bar)
        images, paths = [], []
        for k, img in enumerate(source):
            img.metadata.update({"frame": k, "label": labels[k], "orbit_deg": angles[k]})
            paths.append(img.save(frames_dir / f"frame_{k:04d}.exr"))
            images.append(img)
    finally:
        bar.close()
        if owned:
            cluster.close(client)
    exposure = auto_exposure(np.concatenate([im.radiance for im in images], axis=0)) if exposure is None else exposure
    srgb = [to_srgb8(im.radiance, exposure) for im in images]
    mp4 = write_mp4(out / "animation.mp4", srgb, fps=fps)
    sheet = contact_sheet(out / "contact_sheet.png", srgb, labels)
    return Animation(paths, mp4, sheet, images)
