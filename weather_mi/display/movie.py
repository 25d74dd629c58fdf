"""Frames of an animation for eyes: an MP4 (H.264 through the ffmpeg binary that the imageio-ffmpeg
wheel ships: no system ffmpeg needed) and a contact sheet PNG (every frame, labelled, in a grid).

Frames are 8-bit sRGB (H, W, 3) arrays from ``imageio.to_srgb8`` with one exposure for the whole
series, so that a growing storm gets brighter rather than re-exposed.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

MACRO_BLOCK = 16  # H.264 encodes 16 x 16 blocks: frames are padded (edge pixels repeated) to a multiple


def _padded(frame: np.ndarray) -> np.ndarray:
    h, w = frame.shape[:2]
    ph, pw = -h % MACRO_BLOCK, -w % MACRO_BLOCK
    return np.pad(frame, ((0, ph), (0, pw), (0, 0)), mode="edge") if ph or pw else frame


def write_mp4(path, frames: list[np.ndarray], fps: float = 4.0) -> Path:
    """H.264 MP4 (yuv420p, plays everywhere) of 8-bit sRGB frames of one size."""
    import imageio_ffmpeg
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    frames = [_padded(np.ascontiguousarray(f, np.uint8)) for f in frames]
    if not frames or any(f.shape != frames[0].shape for f in frames):
        raise ValueError("an MP4 needs at least one frame, all of one size")
    h, w = frames[0].shape[:2]
    tmp = path.with_name(path.stem + ".tmp" + path.suffix)
    writer = imageio_ffmpeg.write_frames(str(tmp), (w, h), fps=fps, macro_block_size=1, quality=8,
                                         ffmpeg_log_level="error")
    writer.send(None)  # start ffmpeg
    try:
        for f in frames:
            writer.send(f)
    finally:
        writer.close()
    tmp.replace(path)
    return path


def contact_sheet(path, frames: list[np.ndarray], labels: list[str], columns: int | None = None,
                  label_px: int = 14) -> Path:
    """PNG of every frame in a grid (``columns`` default: about square), each with its label beneath."""
    from PIL import Image, ImageDraw
    n = len(frames)
    if n == 0 or len(labels) != n:
        raise ValueError("a contact sheet needs frames and one label per frame")
    h, w = frames[0].shape[:2]
    columns = columns or int(np.ceil(np.sqrt(n)))
    rows = -(-n // columns)
    gap = 4
    measure = ImageDraw.Draw(Image.new("RGB", (1, 1)))
    cell_w = max(w, max(int(np.ceil(measure.textlength(label))) for label in labels) + 4)  # labels fit
    cell_h = h + label_px + 2
    sheet = Image.new("RGB", (columns * (cell_w + gap) + gap, rows * (cell_h + gap) + gap), (24, 24, 24))
    draw = ImageDraw.Draw(sheet)
    for k, (frame, label) in enumerate(zip(frames, labels)):
        x = gap + (k % columns) * (cell_w + gap)
        y = gap + (k // columns) * (cell_h + gap)
        sheet.paste(Image.fromarray(np.asarray(frame, np.uint8)), (x + (cell_w - w) // 2, y))
        draw.text((x + 2, y + h + 1), label, fill=(230, 230, 230))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    sheet.save(path)
    return path
