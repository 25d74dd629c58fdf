"""``Exports``: what one tab hands out: the view as PNG and EXR (the slicer's full-quality frame, or
the reference when B is shown), a Python script that reproduces it (``state.python_snippet``), and a
camera path through keyframes, played in the view or rendered to an MP4 in the background.
"""
from __future__ import annotations

import io
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

import panel as pn

from ..io.image import to_srgb8, write_exr, write_png
from .keyframes import path as keyframe_path
from .state import ViewState, python_snippet


class Exports:
    """The download buttons and the keyframes of one ViewerSession (``session``: its state, storm, frame
    loop, reference panel and event loop)."""

    def __init__(self, session):
        self.session = session
        self.keys: list[ViewState] = []
        self.thread = None  # the MP4 render
        w = pn.widgets
        self.png_download = w.FileDownload(callback=self._png_bytes, filename="weather-mi-view.png", label="PNG",
                                           color="light")
        self.exr_download = w.FileDownload(callback=self._exr_bytes, filename="weather-mi-view.exr", label="EXR",
                                           color="light")
        self.snippet_download = w.FileDownload(callback=lambda: io.BytesIO(self.snippet().encode()),
                                               filename="weather_mi_view.py", label="Python", color="light")
        self.add_key = w.Button(label="Add keyframe")
        self.add_key.on_click(lambda e: self.add_keyframe())
        self.clear_keys = w.Button(label="Clear")
        self.clear_keys.on_click(lambda e: self._set_keys([]))
        self.play_path = w.Button(label="Play path")
        self.play_path.on_click(lambda e: self.play_keyframes())
        self.export_mp4 = w.Button(label="Render MP4")
        self.export_mp4.on_click(lambda e: self.render_mp4())
        self.mp4_download = w.FileDownload(file=None, filename="weather-mi-path.mp4", label="MP4", disabled=True,
                                           color="light")
        self.key_text = pn.pane.Markdown("Keyframes: 0", margin=(0, 10))

    def rows(self) -> list:
        """The export row and the keyframe row of the page."""
        return [pn.Row(pn.pane.Markdown("**Export**"), self.png_download, self.exr_download, self.snippet_download),
                pn.Row(self.add_key, self.clear_keys, self.play_path, self.export_mp4, self.mp4_download,
                       self.key_text)]

    # ------------------------------------------------------------------ the view
    def _full_frame(self):
        s = self.session
        f = s.loop.last_frame
        if f is None or f.draft or f.state != s.state:
            f = s.loop.render(s.state)
        return f

    def _reference_shown(self):
        ref = self.session.reference
        return ref.image if ref.show.value in ("B: reference", "B: denoised") and ref.image is not None else None

    def _png_bytes(self):
        f = self._full_frame()
        ref = self._reference_shown()
        rad = f.radiance if ref is None else ref.radiance
        if ref is not None and self.session.reference.show.value == "B: denoised":  # the PNG shows what B shows
            rad = self.session.reference.denoised()
        with tempfile.TemporaryDirectory() as tmp:
            p = Path(tmp) / "view.png"
            write_png(p, rad, f.exposure)
            return io.BytesIO(p.read_bytes())

    def _exr_bytes(self):
        s = self.session
        f = self._full_frame()
        ref = self._reference_shown()
        with tempfile.TemporaryDirectory() as tmp:
            p = Path(tmp) / "view.exr"
            if ref is not None:
                ref.save(p)
            else:
                write_exr(p, f.radiance, None, {"renderer": "slicing", "viewer_state": s.state.to_dict(),
                                               "scene": f.spec.to_dict(), "source": s.storm.recipe.label})
            return io.BytesIO(p.read_bytes())

    def snippet(self) -> str:
        """A Python script that renders this view with the slicer and the path tracer."""
        s = self.session
        f = self._full_frame()
        return python_snippet(s.state, s.storm.recipe, f.spec, s.storm.times, exposure=f.exposure)

    # ------------------------------------------------------------------ keyframes
    def _set_keys(self, keys):
        self.keys = list(keys)
        self.key_text.object = f"Keyframes: {len(self.keys)}"

    def add_keyframe(self):
        self._set_keys(self.keys + [self.session.state])

    def play_keyframes(self, fps: float = 8.0):
        """Play the path in the view (drafts while it moves, the last keyframe refined)."""
        if len(self.keys) < 2:
            self.key_text.object = "Keyframes: add at least two to play a path"
            return
        frames = keyframe_path(self.keys, fps)
        s = self.session

        def run():
            for st in frames:
                if s.closed:
                    return
                s.loop.submit(st, s.last_mark, interactive=True)
                time.sleep(1.0 / fps)
            s.loop.submit(frames[-1], s.last_mark, interactive=False)
        threading.Thread(target=run, daemon=True, name="weather-mi path").start()

    def render_mp4(self, fps: float = 12.0):
        """Render the path at full quality in the background, then offer it for download."""
        from ..display.movie import write_mp4
        if len(self.keys) < 2:
            self.key_text.object = "Keyframes: add at least two to render a path"
            return
        frames = keyframe_path(self.keys, fps)
        self.export_mp4.disabled = True
        s = self.session

        def run():
            images = []
            for k, st in enumerate(frames):
                if s.closed:
                    return
                f = s.loop.render(st)
                images.append(to_srgb8(f.radiance, f.exposure))
                s.on_loop(lambda k=k: setattr(self.key_text, "object", f"MP4: frame {k + 1} / {len(frames)}"))
            out = Path(tempfile.mkdtemp(prefix="weather-mi-")) / "path.mp4"
            write_mp4(out, images, fps=fps)

            def done():
                self.mp4_download.param.update(file=str(out), disabled=False)
                self.export_mp4.disabled = False
                self.key_text.object = f"MP4: {len(frames)} frames ready"
            s.on_loop(done)
        self.thread = threading.Thread(target=run, daemon=True, name="weather-mi mp4")
        self.thread.start()
