"""``ViewerSession``: one browser tab of the viewer: its knobs (``widgets.ViewControls``), the frame
canvas and its FrameLoop, the reference (``comparison.ReferencePanel``) and the exports and keyframes
(``exports.Exports``). Nothing is shared between tabs but the Storm (read-only volumes).

Data flow: knob or mouse -> ``ViewState`` -> FrameLoop (slicer thread) -> frame on the page; "Path-trace
this view" -> ReferenceJob (a low-priority process) -> polled twice a second -> B view, difference map
and metrics.
"""
from __future__ import annotations

import panel as pn

from ..scene.framing import default_ground_distance_km
from .canvas import FrameCanvas
from .comparison import ReferencePanel
from .exports import Exports
from .frames import FrameLoop, Storm
from .state import ViewCamera, ViewState
from .widgets import ViewControls

REFERENCE_POLL_MS = 500
DISPLAY_SCALE = 2  # the view is shown at twice its rendered size


def default_distance_km(storm: Storm) -> float:
    """The ground camera's distance from the storm's core (km) at the starting time."""
    return float(default_ground_distance_km(storm.volume(storm.first_time)))


class ViewerSession:
    """Everything of one tab. ``layout``: its Panel object."""

    def __init__(self, storm: Storm, state: ViewState | None = None, reference_kw: dict | None = None):
        self.storm = storm
        self.state = state or ViewState(time=storm.first_time,
                                        camera=ViewCamera(distance_km=default_distance_km(storm)))
        self.doc = pn.state.curdoc
        self.last_mark = 0
        self.closed = False
        s = self.state
        self.canvas = FrameCanvas(view_width=s.width, view_height=s.height, display_width=DISPLAY_SCALE * s.width,
                                  display_height=DISPLAY_SCALE * s.height, status="starting the slicer...")
        self.canvas.on_event(self._on_canvas_msg)
        self.controls = ViewControls(s, storm.species, len(storm.times))
        self.controls.on_change(self._on_knob)
        self.controls.on_live(self._on_live)
        # the reference uses every core, at the lowest priority: the slicer (and the page) come first
        self.reference = ReferencePanel(self, {"threads": None, "nice": 19, **(reference_kw or {})})
        self.exports = Exports(self)
        self.time_label = pn.pane.Markdown(self._time_text(), visible=len(storm.times) > 1, margin=(0, 10))
        self.layout = self._layout()
        self.loop = FrameLoop(storm, self._publish_from_thread, on_error=self._error_from_thread)
        self.loop.submit(self.state, 0, interactive=False)
        self._poller = None
        if self.doc is not None and getattr(self.doc, "session_context", None) is not None:
            self._poller = pn.state.add_periodic_callback(self.reference.poll, period=REFERENCE_POLL_MS)
            pn.state.on_session_destroyed(lambda ctx: self.close())

    def _layout(self):
        c = self.controls.widgets
        species = self.storm.species
        sidebar = pn.Column(
            pn.pane.Markdown(f"### weather-mi\n{self.storm.recipe.label}"),
            c["mode"], c["species_colors"], c["slices"],
            pn.pane.Markdown("**Camera** (drag the view to turn, wheel to zoom)"), c["camera_kind"], c["fov"],
            pn.pane.Markdown("**Sun** (air: none, or a clear atmosphere on the sun's and the eye's paths)"),
            c["sun_azimuth"], c["sun_elevation"], c["atmosphere"],
            pn.Card(*(c[f"scale_{n}"] for n in species), title="Scalings (mixing ratios)", collapsed=False),
            pn.Card(c["own_albedo"], c["albedo"], c["cone"], c["own_forward"], c["forward"], c["ambient"],
                    title="Light transport", collapsed=True),
            pn.Card(*(c[f"detail_{n}"] for n in species), title="Detail per species (detail mode)", collapsed=True),
            c["exposure"], width=320)
        r = self.reference
        main = pn.Column(
            pn.Row(c["time"], self.time_label),
            self.canvas,
            pn.Row(r.show, r.trace, r.cancel_button),
            pn.Row(r.ref_text, r.metric_text),
            *self.exports.rows())
        return pn.Row(sidebar, main)

    def _time_text(self) -> str:
        return f"time {self.state.time}: {self.storm.times[self.state.time]}" if len(self.storm.times) > 1 else ""

    # ------------------------------------------------------------------ inputs
    def _on_knob(self, name, value):
        self.set_state(self.controls.changed(self.state, name, value), interactive=True)

    def _on_live(self, name, value, seq):
        self.last_mark = max(self.last_mark, seq)
        self.set_state(self.controls.changed(self.state, name, value), interactive=True)

    def set_state(self, state: ViewState, interactive: bool = True):
        old, self.state = self.state, state
        self.time_label.object = self._time_text()
        self.reference.view_changed(old, state)
        # the same view again (a slider released where it was last reported): refine it now
        self.loop.submit(state, self.last_mark, interactive=interactive and state != old)

    def _on_canvas_msg(self, msg: dict):
        kind = msg.get("type")
        if kind == "ready":  # the page (re)built the view: send it the newest frame
            self.refresh_canvas()
            return
        if kind == "mark":
            self.last_mark = max(self.last_mark, int(msg.get("seq", 0)))
            return
        if kind == "hold":  # the mouse button pressed or released on the view or a slider (canvas.py)
            self.loop.hold(bool(msg.get("held")))
            return
        self.last_mark = max(self.last_mark, int(msg.get("seq", 0)))
        if kind == "drag":
            self.set_state(self.state.updated(camera=self.state.camera.dragged(msg["dx"], msg["dy"])))
        elif kind == "wheel":
            self.set_state(self.state.updated(camera=self.state.camera.zoomed(msg["dy"])))
        elif kind == "hover":
            self.canvas.show_hover(self.hover_text(msg["x"], msg["y"]))

    def hover_text(self, x: float, y: float) -> str:
        """The read-out under the pointer (pixel ``x``, ``y``): the first dense voxel, its dominant species
        and the mixing ratios as the view shows them (g/kg)."""
        from .pick import first_dense_voxel
        s = self.state
        try:
            spec = s.spec(self.storm.frame, self.storm.ground_m)
            hit = first_dense_voxel(self.storm.mixing_ratios(s.time), self.storm.volume(s.time), spec, x, y)
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

    def snippet(self) -> str:
        """A Python script that reproduces this view (``exports.Exports.snippet``)."""
        return self.exports.snippet()

    # ------------------------------------------------------------------ frames
    def _publish_from_thread(self, frame):
        self.reference.refined(frame)  # the metrics that wait for the view's refined frame
        self.on_loop(self.refresh_canvas)

    def _error_from_thread(self, exc):
        self.on_loop(lambda: setattr(self.canvas, "status", f"error: {exc}"))

    def on_loop(self, fn):
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

    def refresh_canvas(self):
        f = self.loop.last_frame
        if f is None:
            return
        show = self.reference.show.value
        status = (f"{f.state.mode}{' (draft)' if f.draft else ''}: {f.seconds * 1000:.0f} ms "
                  f"(+{f.queued_s * 1000:.0f} queued), {f.spec.width}x{f.spec.height}, {f.slices} slices")
        url = f.url
        if self.reference.showing_reference:
            url = self.reference.overlay_url()
            status = self.reference.status()
        self.canvas.push(url, f.seq, status)
        if not f.draft and show == "A: slicer":  # refined: also the parameter, for a page that re-renders
            self.canvas.param.update(frame=url, frame_seq=f.seq, status=status)

    # ------------------------------------------------------------------ lifetime
    def close(self):
        """Stop everything this tab started (the page closed)."""
        if self.closed:
            return
        self.closed = True
        self.reference.cancel(None)
        if self._poller is not None:
            self._poller.stop()
        self.loop.stop()
        self.reference.close()
