"""``FrameCanvas``: the view of the viewer, a browser component (Panel ``JSComponent``) that shows the
frames streamed from Python and sends the mouse back: drag (orbit), wheel (zoom) and hover (read-out).

Latency is measured where the user is: every pointer, wheel or input event on the page gets a client
sequence number and time (a capture listener on the document, so slider drags count too); the number
goes to Python ahead of the change it causes (same websocket, same order), each frame comes back with
the newest number it has seen, and the page records input-to-frame latency when the frame is decoded.
``window.wmStats`` holds the counters (frames, their arrival times, latencies) for benchmarks/viewer.py.
"""
from __future__ import annotations

import param
from panel.custom import JSComponent

from .controls import QuietEvents

_ESM = r"""
export function render({ model, el }) {
  const root = document.createElement("div");
  root.className = "wm-canvas";
  const img = document.createElement("img");
  img.className = "wm-frame";
  img.draggable = false;
  const overlay = document.createElement("div");
  overlay.className = "wm-overlay";
  const hover = document.createElement("div");
  hover.className = "wm-hover";
  root.append(img, overlay, hover);

  const S = window.wmStats = window.wmStats || {frames: 0, arrivals: [], latencies: [], inputs: {}, seq: 0, statuses: []};
  // input stamps: at most one per MARK_MS (each costs the server an event); the inputs in between are
  // not timed, the timed ones are timed exactly
  const MARK_MS = 45;
  const markInput = () => {
    const now = performance.now();
    if (now - (S.lastMark || -1e9) < MARK_MS) return;
    S.lastMark = now;
    S.seq += 1;
    S.inputs[S.seq] = now;
    model.send_msg({type: "mark", seq: S.seq});
  };
  if (!window.wmMarking) {  // one listener per page: slider drags and key presses are inputs too
    window.wmMarking = true;
    for (const kind of ["pointerdown", "wheel", "keydown", "change"]) {
      document.addEventListener(kind, markInput, {capture: true, passive: true});
    }
    // the button held on the view or a slider: the server holds the refine back while a drag may go on
    const onControl = (e) => e.composedPath().some((n) => n.classList && (n.classList.contains("wm-frame") || n.classList.contains("wm-live")));
    let held = false;
    document.addEventListener("pointerdown", (e) => {
      if (onControl(e)) { held = true; model.send_msg({type: "hold", held: true}); }
    }, {capture: true, passive: true});
    for (const kind of ["pointerup", "pointercancel"]) {
      document.addEventListener(kind, () => {
        if (held) { held = false; model.send_msg({type: "hold", held: false}); }
      }, {capture: true, passive: true});
    }
    document.addEventListener("pointermove", (e) => {
      if (!e.buttons) return;
      if (onControl(e)) {
        S.seq += 1; S.inputs[S.seq] = performance.now();  // the drag or live message carries it
      } else { markInput(); }
    }, {capture: true, passive: true});
  }

  // the frame on screen: its input stamp and status travel with it (a pushed message, or the parameters)
  let shown = {url: model.frame, seq: model.frame_seq, status: model.status};
  const size = () => {
    img.style.width = model.display_width + "px";
    img.style.height = model.display_height + "px";
  };
  const display = (url, seq, status) => {
    shown = {url: url, seq: seq, status: status};
    if (url && img.src !== url) { img.src = url; } else { overlay.textContent = status; }
  };
  img.addEventListener("load", () => {
    const now = performance.now();
    S.frames += 1;
    S.arrivals.push(now);
    S.statuses.push(shown.status);
    overlay.textContent = shown.status;
    const t0 = S.inputs[shown.seq];
    if (t0 !== undefined && shown.seq > (S.lastAnswered || 0)) {
      S.latencies.push(now - t0);
      S.lastAnswered = shown.seq;
    }
  });
  const showHover = (text) => { hover.textContent = text; hover.style.display = text ? "block" : "none"; };
  model.on("msg:custom", (msg) => {
    if ("hover" in msg) { showHover(msg.hover); return; }
    display(msg.frame, msg.seq, msg.status);
  });
  model.on("frame", () => display(model.frame, model.frame_seq, model.status));
  // a patch of the parameters arrives field by field: "frame" may come before its "status", and the frame then
  // shown reads the status it had (the page's "starting the slicer..."): the status that follows is the frame's
  model.on("status", () => {
    if (!model.frame) { overlay.textContent = model.status; return; }
    if (shown.url === model.frame) { shown.status = model.status; overlay.textContent = model.status; }
  });
  model.on("display_width", size);

  // drag: orbit; wheel: zoom; plain move: hover read-out (pixel coordinates of the rendered view)
  let dragging = false, last = null, pendingHover = null;
  const toPixel = (e) => {
    const r = img.getBoundingClientRect();
    return [(e.clientX - r.left) / r.width * model.view_width, (e.clientY - r.top) / r.height * model.view_height];
  };
  img.addEventListener("pointerdown", (e) => {
    dragging = true; last = [e.clientX, e.clientY];
    img.setPointerCapture(e.pointerId);
    model.send_msg({type: "drag_start", seq: S.seq});
  });
  // drag moves are summed and sent once per animation frame (one message, not one per mouse event)
  let acc = [0, 0], scheduled = false;
  const flush = () => {
    scheduled = false;
    if (acc[0] || acc[1]) model.send_msg({type: "drag", dx: acc[0], dy: acc[1], seq: S.seq});
    acc = [0, 0];
  };
  img.addEventListener("pointermove", (e) => {
    if (dragging) {
      acc[0] += e.clientX - last[0]; acc[1] += e.clientY - last[1];
      last = [e.clientX, e.clientY];
      if (!scheduled) { scheduled = true; requestAnimationFrame(flush); }
    } else {
      if (pendingHover === null) {
        setTimeout(() => { model.send_msg({type: "hover", x: pendingHover[0], y: pendingHover[1]}); pendingHover = null; }, 120);
      }
      pendingHover = toPixel(e);
    }
  });
  const end = (e) => {
    if (!dragging) return;
    dragging = false;
    model.send_msg({type: "drag_end", seq: S.seq});
  };
  img.addEventListener("pointerup", end);
  img.addEventListener("pointercancel", end);
  img.addEventListener("pointerleave", () => { if (!dragging) showHover(""); });
  img.addEventListener("wheel", (e) => {
    e.preventDefault();
    model.send_msg({type: "wheel", dy: e.deltaY, seq: S.seq});
  }, {passive: false});
  size();
  display(model.frame, model.frame_seq, model.status);
  model.send_msg({type: "ready"});  // the server answers with the newest frame (it may predate this view)
  return root;
}
"""

_CSS = """
.wm-canvas { position: relative; display: inline-block; background: #111; user-select: none; }
.wm-frame { display: block; image-rendering: auto; cursor: grab; touch-action: none; }
.wm-overlay { position: absolute; left: 6px; bottom: 4px; color: #eee; font: 12px monospace;
              text-shadow: 0 0 3px #000; pointer-events: none; white-space: pre; }
.wm-hover { position: absolute; right: 6px; top: 4px; color: #fff; background: rgba(0,0,0,0.6);
            font: 12px monospace; padding: 3px 5px; pointer-events: none; white-space: pre; display: none; }
"""


class FrameCanvas(QuietEvents, JSComponent):
    """Frames (data URLs) in, mouse events out (``on_event(callback)``: drag, drag_start, drag_end, wheel,
    hover, mark). ``push(url, seq, status)`` sends a frame as a message (cheap); the ``frame`` parameter
    holds the last refined one, for a page that (re)renders the view."""

    frame = param.String(default="", doc="the current frame as a data URL (JPEG or PNG)")
    frame_seq = param.Integer(default=0, doc="the newest client input sequence number the frame answers")
    status = param.String(default="", doc="one line over the frame (mode, timings, reference progress)")
    view_width = param.Integer(default=320, doc="width of the rendered view in pixels (for hover)")
    view_height = param.Integer(default=240)
    display_width = param.Integer(default=640, doc="on-screen size in CSS pixels")
    display_height = param.Integer(default=480)

    _esm = _ESM
    _stylesheets = [_CSS]

    def __init__(self, **params):
        super().__init__(**params)
        self._event_callbacks = []

    def on_event(self, callback) -> None:
        self._event_callbacks.append(callback)

    def _handle_msg(self, msg) -> None:
        for cb in self._event_callbacks:
            cb(msg)

    def show_hover(self, text: str) -> None:
        """The hover read-out (empty: hidden)."""
        self._send_msg({"hover": text})

    def push(self, url: str, seq: int, status: str) -> None:
        """Show a frame now (a custom message, no document patch)."""
        self._send_msg({"frame": url, "seq": int(seq), "status": status})
