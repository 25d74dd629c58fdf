"""``ViewerSession``: one browser tab of the viewer (Panel widgets, the frame canvas, its FrameLoop and
its reference job). Nothing is shared between tabs but the Storm (read-only volumes).

Data flow: widget or mouse -> ``ViewState`` -> FrameLoop (slicer thread) -> frame on the page; "Path-trace
this view" -> ReferenceJob (a low-priority process) -> polled twice a second -> B view, difference map
and metrics. A change of anything the path tracer sees (camera, sun, time, scalings, size) cancels the
reference; a change of the slicer's approximation knobs keeps it, to compare against.
"""
from __future__ import annotations

import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import panel as pn

from ..imageio import to_srgb8, write_exr, write_png
from ..slicing.modes import DEFAULT_DETAIL, MODES
from .canvas import FrameCanvas
from .controls import LiveSlider
from .frames import FrameLoop, Storm, jpeg_url
from .keyframes import path as keyframe_path
from .state import ViewCamera, ViewState, python_snippet

SLICE_CHOICES = [16, 32, 48, 64, 96, 128, 192, 256, 384, 512]
PHYSICAL_FIELDS = ("camera", "sun_azimuth", "sun_elevation", "sun_diameter_deg", "width", "height", "scale", "time",
                   "sky", "ground_albedo")  # what the path tracer sees
REFERENCE_POLL_MS = 500
DIFF_MAX_DE = 20.0
DISPLAY_SCALE = 2  # the view is shown at twice its rendered size
WIDGET_DEBOUNCE_MS = 5  # Panel waits this long to merge a widget's changes (its default, 50 ms, is latency)  # the difference map's colour scale: CIEDE2000 0 .. 20


class ViewerSession:
    """Everything of one tab. ``layout``: its Panel object."""

    def __init__(self, storm: Storm, state: ViewState | None = None, reference_kw: dict | None = None):
        self.storm = storm
        # the reference uses every core, at the lowest priority: the slicer (and the page) come first
        self.reference_kw = {"threads": None, "nice": 19, **(reference_kw or {})}
        self.state = state or ViewState(time=storm.first_time,
                                        camera=ViewCamera(distance_km=default_distance_km(storm)))
        self.doc = pn.state.curdoc
        self.last_mark = 0
        self.dragging = False
        self.reference = None        # ReferenceJob
        self.ref_image = None        # the newest reference estimate (Image) and its state
        self.ref_state = None
        self.metrics = None
        self._overlay = None         # (key, data URL) of the last B or difference picture
        self.keys: list[ViewState] = []
        self.export_thread = None
        self.closed = False
        self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="weather-mi metrics")
        self._build_widgets()
        self.loop = FrameLoop(storm, self._publish_from_thread, on_error=self._error_from_thread)
        self.loop.submit(self.state, 0, interactive=False)
        self._poller = None
        if self.doc is not None and getattr(self.doc, "session_context", None) is not None:
            self._poller = pn.state.add_periodic_callback(self._poll_reference, period=REFERENCE_POLL_MS)
            pn.state.on_session_destroyed(lambda ctx: self.close())

    # ------------------------------------------------------------------ widgets
    def _build_widgets(self):
        s = self.state
        w = pn.widgets
        self.canvas = FrameCanvas(view_width=s.width, view_height=s.height, display_width=DISPLAY_SCALE * s.width,
                                  display_height=DISPLAY_SCALE * s.height, status="starting the slicer...")
        self.canvas.on_event(self._on_canvas_msg)
        self.mode = w.Select(label="Mode", options=list(MODES), value=s.mode)
        self.species_colors = w.Checkbox(label="Species colours (Fig. 2)", value=s.species_colors)
        self.slices = w.DiscreteSlider(label="Slices", options=SLICE_CHOICES, value=s.slices)
        self.camera_kind = w.RadioButtonGroup(label="Camera", options=["ground", "orbit"], value=s.camera.kind)
        self.fov = LiveSlider(label="Field of view (deg)", start=10, end=120, step=1, value=s.camera.fov, decimals=0)
        self.sun_azimuth = LiveSlider(label="Sun azimuth (deg)", start=0, end=360, step=1, value=s.sun_azimuth,
                                      decimals=0, css_classes=["wm-sun-azimuth"])
        self.sun_elevation = LiveSlider(label="Sun elevation (deg)", start=-5, end=90, step=0.5,
                                        value=s.sun_elevation, decimals=1)
        self.scales = {n: LiveSlider(label=f"{n} scaling", start=-2.0, end=2.0, step=0.02, value=0.0, log_display=True)
                       for n in self.storm.species}
        self.details = {n: LiveSlider(label=f"{n} detail", start=0.0, end=2.0, step=0.05, value=DEFAULT_DETAIL)
                        for n in self.storm.species}
        self.own_albedo = w.Checkbox(label="One albedo for all species", value=s.albedo is not None)
        self.albedo = LiveSlider(label="Albedo", start=0.0, end=1.0, step=0.005, value=s.albedo or 0.99, decimals=3)
        self.cone = LiveSlider(label="Cone angle (deg)", start=1, end=60, step=0.5, value=s.cone_angle_deg, decimals=1)
        self.own_forward = w.Checkbox(label="One forward fraction", value=s.forward_fraction is not None)
        self.forward = LiveSlider(label="Forward fraction", start=0.0, end=1.0, step=0.01,
                                  value=s.forward_fraction or 0.9)
        self.ambient = LiveSlider(label="Ambient (Table IV modes)", start=0.0, end=1.0, step=0.01, value=s.ambient)
        self.exposure = LiveSlider(label="Exposure (EV)", start=-4, end=4, step=0.1, value=s.exposure_ev, decimals=1)
        n_times = len(self.storm.times)
        self.time = w.Player(label="Time", start=0, end=max(n_times - 1, 1), value=s.time, interval=800, loop_policy="loop",
                             show_value=True, visible=n_times > 1, width=300, css_classes=["wm-time"])
        self.time_label = pn.pane.Markdown(self._time_text(), visible=n_times > 1, margin=(0, 10))
        widgets = [self.mode, self.species_colors, self.slices, self.camera_kind, self.fov, self.sun_azimuth,
                   self.sun_elevation, self.own_albedo, self.albedo, self.cone, self.own_forward, self.forward,
                   self.ambient, self.exposure, self.time, *self.scales.values(), *self.details.values()]
        self._updates = self._field_updates()
        for wd in widgets:
            wd.param.watch(self._on_widget, "value")
            if isinstance(wd, LiveSlider):
                wd.on_live(lambda v, seq, wd=wd: self._on_live(wd, v, seq))
            else:
                wd._debounce = WIDGET_DEBOUNCE_MS
        # reference, A/B, metrics
        self.show = w.RadioButtonGroup(label="Show", options=["A: slicer", "B: reference", "difference"],
                                       value="A: slicer", color="default")
        self.show.param.watch(lambda e: self._refresh_canvas(), "value")
        self.trace = w.Button(label="Path-trace this view", color="primary")
        self.trace.on_click(lambda e: self.start_reference())
        self.cancel = w.Button(label="Cancel", color="warning", disabled=True)
        self.cancel.on_click(lambda e: self.cancel_reference("cancelled"))
        self.ref_text = pn.pane.Markdown("Reference: none", margin=(0, 10))
        self.metric_text = pn.pane.Markdown("", margin=(0, 10))
        # export
        self.png_download = w.FileDownload(callback=self._png_bytes, filename="weather-mi-view.png", label="PNG",
                                           color="light")
        self.exr_download = w.FileDownload(callback=self._exr_bytes, filename="weather-mi-view.exr", label="EXR",
                                           color="light")
        self.snippet_download = w.FileDownload(callback=self._snippet_bytes, filename="weather_mi_view.py",
                                               label="Python", color="light")
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

        sidebar = pn.Column(
            pn.pane.Markdown(f"### weather-mi\n{self.storm.recipe.label}"),
            self.mode, self.species_colors, self.slices,
            pn.pane.Markdown("**Camera** (drag the view to turn, wheel to zoom)"), self.camera_kind, self.fov,
            pn.pane.Markdown("**Sun**"), self.sun_azimuth, self.sun_elevation,
            pn.Card(*self.scales.values(), title="Scalings (mixing ratios)", collapsed=False),
            pn.Card(self.own_albedo, self.albedo, self.cone, self.own_forward, self.forward, self.ambient,
                    title="Light transport", collapsed=True),
            pn.Card(*self.details.values(), title="Detail per species (detail mode)", collapsed=True),
            self.exposure, width=320)
        main = pn.Column(
            pn.Row(self.time, self.time_label),
            self.canvas,
            pn.Row(self.show, self.trace, self.cancel),
            pn.Row(self.ref_text, self.metric_text),
            pn.Row(pn.pane.Markdown("**Export**"), self.png_download, self.exr_download, self.snippet_download),
            pn.Row(self.add_key, self.clear_keys, self.play_path, self.export_mp4, self.mp4_download, self.key_text))
        self.layout = pn.Row(sidebar, main)

    def _time_text(self) -> str:
        return f"time {self.state.time}: {self.storm.times[self.state.time]}" if len(self.storm.times) > 1 else ""

    # ------------------------------------------------------------------ inputs
    def _field_updates(self) -> dict:
        """For each widget, how its value changes the ViewState (one widget per event: reading all of them
        on every slider move costs the event loop more than the change itself)."""
        def camera(**kw):
            return lambda v: {"camera": ViewCamera(**{**self.state.camera.__dict__, **{k: f(v) for k, f in kw.items()}})}
        fields = {
            self.mode: lambda v: {"mode": v},
            self.species_colors: lambda v: {"species_colors": bool(v)},
            self.slices: lambda v: {"slices": int(v)},
            self.camera_kind: camera(kind=str),
            self.fov: camera(fov=float),
            self.sun_azimuth: lambda v: {"sun_azimuth": float(v) % 360.0},
            self.sun_elevation: lambda v: {"sun_elevation": float(v)},
            self.own_albedo: lambda v: {"albedo": float(self.albedo.value) if v else None},
            self.albedo: lambda v: {"albedo": float(v) if self.own_albedo.value else None},
            self.cone: lambda v: {"cone_angle_deg": float(v)},
            self.own_forward: lambda v: {"forward_fraction": float(self.forward.value) if v else None},
            self.forward: lambda v: {"forward_fraction": float(v) if self.own_forward.value else None},
            self.ambient: lambda v: {"ambient": float(v)},
            self.exposure: lambda v: {"exposure_ev": float(v)},
            self.time: lambda v: {"time": int(min(v, len(self.storm.times) - 1))},
        }
        for n, sl in self.scales.items():
            fields[sl] = lambda v, n=n: {"scale": tuple(sorted({**dict(self.state.scale), n: round(10.0 ** v, 4)}.items()))}
        for n, sl in self.details.items():
            fields[sl] = lambda v, n=n: {"detail": tuple(sorted({**dict(self.state.detail), n: float(v)}.items()))}
        return fields

    def _on_widget(self, event):
        self.set_state(self.state.updated(**self._updates[event.obj](event.new)), interactive=True)

    def _on_live(self, widget, value, seq):
        self.last_mark = max(self.last_mark, seq)
        self.set_state(self.state.updated(**self._updates[widget](value)), interactive=True)

    def set_state(self, state: ViewState, interactive: bool = True):
        old, self.state = self.state, state
        self.time_label.object = self._time_text()
        if self.reference is not None or self.ref_image is not None:
            if any(getattr(old, f) != getattr(state, f) for f in PHYSICAL_FIELDS):
                self.cancel_reference("the view changed: path-trace it again")
        # the same view again (a slider released where it was last reported): refine it now
        self.loop.submit(state, self.last_mark, interactive=interactive and state != old)

    def _on_canvas_msg(self, msg: dict):
        kind = msg.get("type")
        if kind == "ready":  # the page (re)built the view: send it the newest frame
            self._refresh_canvas()
            return
        if kind == "mark":
            self.last_mark = max(self.last_mark, int(msg.get("seq", 0)))
            return
        self.last_mark = max(self.last_mark, int(msg.get("seq", 0)))
        if kind == "drag":
            self.set_state(self.state.updated(camera=self.state.camera.dragged(msg["dx"], msg["dy"])))
        elif kind == "wheel":
            self.set_state(self.state.updated(camera=self.state.camera.zoomed(msg["dy"])))
        elif kind == "hover":
            self.canvas.show_hover(self.hover_text(msg["x"], msg["y"]))

    def hover_text(self, x: float, y: float) -> str:
        from .pick import first_dense_voxel
        s = self.state
        try:
            spec = s.spec(self.storm.frame, self.storm.ground_m)
            hit = first_dense_voxel(self.storm.hydrometeors(s.time), self.storm.volume(s.time), spec, x, y)
        except Exception as exc:  # the read-out must never break the view
            return f"read-out failed: {exc}"
        if hit is None:
            return ""
        k, j, i = hit["index"]
        lines = [f"voxel ({i}, {j}, {k}) at {hit['position_m'][2] / 1000:.1f} km, {hit['distance_m'] / 1000:.1f} km away",
                 f"dominant: {hit['dominant']}"]
        scale = dict(s.scale)  # the mixing ratios as the view shows them: the data times the scalings
        lines += [f"q_{n}: {q * scale.get(n, 1.0) * 1000:.3g} g/kg" + (f" (x{scale[n]:.3g})" if scale.get(n, 1.0) != 1.0 else "")
                  for n, q in hit["mixing_ratio_kg_per_kg"].items() if q > 0]
        return "\n".join(lines)

    # ------------------------------------------------------------------ frames
    def _publish_from_thread(self, frame):
        self._on_loop(self._refresh_canvas)

    def _error_from_thread(self, exc):
        self._on_loop(lambda: setattr(self.canvas, "status", f"error: {exc}"))

    def _on_loop(self, fn):
        """Run ``fn`` on the session's event loop (from any thread), or now without a server."""
        if self.closed:
            return
        doc = self.doc
        if doc is not None and getattr(doc, "session_context", None) is not None:
            try:
                doc.add_next_tick_callback(fn)
            except Exception:  # the session closed meanwhile
                pass
        else:
            fn()

    def _refresh_canvas(self):
        f = self.loop.last_frame
        if f is None:
            return
        show = self.show.value
        status = (f"{f.state.mode}{' (draft)' if f.draft else ''}: {f.seconds * 1000:.0f} ms "
                  f"(+{f.queued_s * 1000:.0f} queued), {f.spec.width}x{f.spec.height}, {f.slices} slices")
        url = f.url
        if show != "A: slicer" and self.ref_image is not None:
            url = self._overlay_url(show)
            status = self._reference_status()
        self.canvas.push(url, f.seq, status)
        if not f.draft and show == "A: slicer":  # refined: also the parameter, for a page that re-renders
            self.canvas.param.update(frame=url, frame_seq=f.seq, status=status)

    # ------------------------------------------------------------------ reference
    def start_reference(self):
        from .reference_job import ReferenceJob
        self.cancel_reference(None)
        s = self.state
        spec = s.spec(self.storm.frame, self.storm.ground_m)
        recipe = self.storm.recipe if len(self.storm.times) < 2 else self.storm.recipe.at(s.time)
        self.reference = ReferenceJob(recipe, spec, dict(s.scale) or None, **self.reference_kw)
        self.reference.start()
        self.ref_state, self.ref_image, self.metrics = s, None, None
        self.ref_text.object = "Reference: starting (a background process at low priority)..."
        self.metric_text.object = ""
        self.cancel.disabled = False

    def cancel_reference(self, why: str | None):
        job, self.reference = self.reference, None
        if job is not None:
            job.cancel()
        self.cancel.disabled = True
        if why is not None:
            self.ref_image, self.ref_state, self.metrics = None, None, None
            self.ref_text.object = f"Reference: {why}"
            self.metric_text.object = ""
            if self.show.value != "A: slicer":
                self._refresh_canvas()

    def _poll_reference(self):
        job = self.reference
        if job is None:
            return
        upd = job.poll()
        if upd is None:
            return
        if upd.error:
            self.ref_text.object = f"Reference failed: {upd.error}"
            self.cancel_reference(None)
            return
        self.ref_image = upd.image
        rse = "n/a" if upd.rse_mean is None else f"{upd.rse_mean:.3f}"
        self.ref_text.object = (f"Reference: {upd.passes} passes, {upd.spp} spp, {upd.seconds:.0f} s, "
                                f"cloud RSE {rse}{' (done)' if upd.done else ''}")
        if upd.done:
            self.reference = None
            self.cancel.disabled = True
        self._executor.submit(self._update_metrics, upd.image, self.state)

    def _update_metrics(self, ref_img, state):
        """Metrics of the slicer's full-quality frame of this view against the reference (metrics thread)."""
        from ..metrics import compare
        try:
            f = self.loop.last_frame
            if f is None or f.draft or f.state != state:
                f = self.loop.render(state)  # this thread: the session's render thread stays free
            m = compare(ref_img, f.radiance, mask="cloud", transmittance=f.transmittance, exposure=f.exposure)
            self.metrics = (m, f)
            text = (f"**A vs B** over {m['n_pixels']} cloud pixels: CIEDE2000 {m['ciede2000']:.2f}, "
                    f"FLIP {m['flip']:.3f}, reference noise floor {m['noise_floor']:.3g}")
        except Exception as exc:
            text = f"metrics failed: {exc}"
        self._on_loop(lambda: self._show_metrics(text))

    def _show_metrics(self, text):
        self.metric_text.object = text
        if self.show.value != "A: slicer":
            self._refresh_canvas()

    def _reference_status(self) -> str:
        return self.ref_text.object.replace("Reference: ", "reference: ")

    def _overlay_url(self, show: str) -> str:
        """The B or difference picture, encoded once per reference update, metrics frame and exposure (not
        once per slicer frame: the slicer keeps publishing while the user drags in the B view)."""
        f = self.loop.last_frame
        key = (show, id(self.ref_image), id(self.metrics), f.exposure if f else None)
        if self._overlay is None or self._overlay[0] != key:
            self._overlay = (key, self._reference_url() if show == "B: reference" else self._difference_url())
        return self._overlay[1]

    def _reference_url(self) -> str:
        f = self.loop.last_frame
        return jpeg_url(to_srgb8(self.ref_image.radiance, f.exposure if f else None))

    def _difference_url(self) -> str:
        from matplotlib import colormaps
        from ..metrics import ciede2000_map, display_lab, display_srgb
        f = self.loop.last_frame
        full = self.metrics[1] if self.metrics else f
        if full is None or full.radiance.shape != self.ref_image.radiance.shape:
            return self._reference_url()
        lab_r = display_lab(display_srgb(self.ref_image.radiance, full.exposure))
        lab_a = display_lab(display_srgb(full.radiance, full.exposure))
        de = np.clip(ciede2000_map(lab_r, lab_a) / DIFF_MAX_DE, 0, 1)
        rgb = (colormaps["magma"](de)[..., :3] * 255).astype(np.uint8)
        return jpeg_url(rgb)

    # ------------------------------------------------------------------ export
    def _current_full_frame(self):
        f = self.loop.last_frame
        if f is None or f.draft or f.state != self.state:
            f = self.loop.render(self.state)
        return f

    def _png_bytes(self):
        import io
        f = self._current_full_frame()
        with tempfile.TemporaryDirectory() as tmp:
            p = Path(tmp) / "view.png"
            if self.show.value == "B: reference" and self.ref_image is not None:
                write_png(p, self.ref_image.radiance, f.exposure)
            else:
                write_png(p, f.radiance, f.exposure)
            return io.BytesIO(p.read_bytes())

    def _exr_bytes(self):
        import io
        f = self._current_full_frame()
        with tempfile.TemporaryDirectory() as tmp:
            p = Path(tmp) / "view.exr"
            if self.show.value == "B: reference" and self.ref_image is not None:
                self.ref_image.save(p)
            else:
                write_exr(p, f.radiance, None, {"renderer": "slicing", "viewer_state": self.state.to_dict(),
                                               "scene": f.spec.to_dict(), "source": self.storm.recipe.label})
            return io.BytesIO(p.read_bytes())

    def snippet(self) -> str:
        f = self._current_full_frame()
        return python_snippet(self.state, self.storm.recipe, f.spec, self.storm.times, exposure=f.exposure)

    def _snippet_bytes(self):
        import io
        return io.BytesIO(self.snippet().encode())

    # ------------------------------------------------------------------ keyframes
    def _set_keys(self, keys):
        self.keys = list(keys)
        self.key_text.object = f"Keyframes: {len(self.keys)}"

    def add_keyframe(self):
        self._set_keys(self.keys + [self.state])

    def play_keyframes(self, fps: float = 8.0):
        """Play the path in the view (drafts while it moves, the last keyframe refined)."""
        if len(self.keys) < 2:
            self.key_text.object = "Keyframes: add at least two to play a path"
            return
        frames = keyframe_path(self.keys, fps)

        def run():
            for st in frames:
                if self.closed:
                    return
                self.loop.submit(st, self.last_mark, interactive=True)
                time.sleep(1.0 / fps)
            self.loop.submit(frames[-1], self.last_mark, interactive=False)
        threading.Thread(target=run, daemon=True, name="weather-mi path").start()

    def render_mp4(self, fps: float = 12.0):
        """Render the path at full quality in the background, then offer it for download."""
        from ..movie import write_mp4
        if len(self.keys) < 2:
            self.key_text.object = "Keyframes: add at least two to render a path"
            return
        frames = keyframe_path(self.keys, fps)
        self.export_mp4.disabled = True

        def run():
            images = []
            for k, st in enumerate(frames):
                if self.closed:
                    return
                f = self.loop.render(st)
                images.append(to_srgb8(f.radiance, f.exposure))
                self._on_loop(lambda k=k: setattr(self.key_text, "object", f"MP4: frame {k + 1} / {len(frames)}"))
            out = Path(tempfile.mkdtemp(prefix="weather-mi-")) / "path.mp4"
            write_mp4(out, images, fps=fps)

            def done():
                self.mp4_download.param.update(file=str(out), disabled=False)
                self.export_mp4.disabled = False
                self.key_text.object = f"MP4: {len(frames)} frames ready"
            self._on_loop(done)
        self.export_thread = threading.Thread(target=run, daemon=True, name="weather-mi mp4")
        self.export_thread.start()

    # ------------------------------------------------------------------ lifetime
    def close(self):
        """Stop everything this tab started (the page closed)."""
        if self.closed:
            return
        self.closed = True
        self.cancel_reference(None)
        if self._poller is not None:
            self._poller.stop()
        self.loop.stop()
        self._executor.shutdown(wait=False, cancel_futures=True)


def default_distance_km(storm: Storm) -> float:
    from ..framing import default_ground_distance_km
    return float(default_ground_distance_km(storm.volume(storm.first_time)))


class Viewer(pn.viewable.Viewer):
    """The viewer in a notebook: displays as the app; ``close()`` stops its render thread and reference."""

    def __init__(self, session: ViewerSession, **params):
        super().__init__(**params)
        self.session = session

    def __panel__(self):
        return self.session.layout

    def close(self) -> None:
        self.session.close()


def view(source, *, state: ViewState | None = None, time=None, size: tuple[int, int] = (320, 240),
         **recipe_kw) -> Viewer:
    """The viewer for a Jupyter notebook (run ``pn.extension()`` first): ``source`` is a Hydrometeors
    Dataset, a file path, a demo name ("supercell", "cumulus") or a VolumeRecipe; ``time``: the WRF
    time to start at; ``recipe_kw``: preset=, phase=."""
    import xarray as xr
    from .recipe import VolumeRecipe
    from .serve import prepare
    if isinstance(source, VolumeRecipe):
        recipe = source
    elif isinstance(source, xr.Dataset):
        recipe = VolumeRecipe(dataset=source, **recipe_kw)
    elif str(source) in ("supercell", "cumulus"):
        recipe = VolumeRecipe(demo=str(source), **recipe_kw)
    else:
        recipe = VolumeRecipe(path=str(source), **recipe_kw)
    storm, first = prepare(recipe, time, progress=lambda *a: None, size=size, warm=False)
    return Viewer(ViewerSession(storm, state or first))
