"""``LiveSlider``: a slider for values that change the picture while they are dragged.

A Panel/Bokeh slider reports every mouse move as a document patch (about 4 ms of the server's event
loop each, plus a 50 ms debounce), which at 60 moves a second halves the frame rate of a 2-core
machine. This one is a plain ``<input type=range>`` that sends at most one message per animation
frame while it moves ("live": a cheap custom event, like the view's drag) and sets its ``value``
parameter once, on release. The message carries the page's input stamp, so latency is measured from
the slider's own events (see canvas.py).
"""
from __future__ import annotations

import param
from panel.custom import JSComponent

_ESM = r"""
export function render({ model, el }) {
  const wrap = document.createElement("div");
  wrap.className = "wm-live";
  const label = document.createElement("div");
  label.className = "wm-live-label";
  const input = document.createElement("input");
  input.type = "range";
  input.min = model.start; input.max = model.end; input.step = model.step; input.value = model.value;
  wrap.append(label, input);
  const fmt = (v) => model.log_display ? "\u00d7" + Math.pow(10, v).toPrecision(2) : (+v).toFixed(model.decimals);
  const show = (v) => { label.textContent = model.label + ": " + fmt(v); };
  let pending = null, scheduled = false;
  const flush = () => {
    scheduled = false;
    if (pending === null) return;
    const S = window.wmStats || {seq: 0};
    model.send_msg({type: "live", value: pending, seq: S.seq});
    pending = null;
  };
  input.addEventListener("input", () => {
    const v = parseFloat(input.value);
    show(v);
    pending = v;
    if (!scheduled) { scheduled = true; requestAnimationFrame(flush); }
  });
  input.addEventListener("change", () => { flush(); model.value = parseFloat(input.value); });
  model.on("value", () => { input.value = model.value; show(model.value); });
  show(model.value);
  return wrap;
}
"""

_CSS = """
.wm-live { display: flex; flex-direction: column; width: 100%; font: 13px sans-serif; }
.wm-live-label { margin: 2px 0; }
.wm-live input { width: 100%; margin: 0; }
"""


class QuietEvents:
    """Mixin for the viewer's JSComponents: their custom messages (tens per second while dragging) skip
    Panel's busy-indicator bookkeeping (a list rebuilt and two parameter watchers per event, about a
    tenth of the server's event loop in benchmarks/viewer.py) and go straight to ``_handle_msg``.
    Relies on Panel 1.x's ``_process_bokeh_event``/``DataEvent`` (pinned in pyproject)."""

    def _process_bokeh_event(self, doc, event) -> None:
        from panel.io.state import set_curdoc
        from panel.models.esm import DataEvent
        if isinstance(event, DataEvent):
            with set_curdoc(doc):
                self._handle_msg(event.data)
            return
        super()._process_bokeh_event(doc, event)


class LiveSlider(QuietEvents, JSComponent):
    """A float slider whose moves reach Python as ``on_live(callback)`` calls (value, input stamp) at
    most once per animation frame, and whose ``value`` parameter is set on release."""

    label = param.String(default="")
    start = param.Number(default=0.0)
    end = param.Number(default=1.0)
    step = param.Number(default=0.01)
    value = param.Number(default=0.0)
    decimals = param.Integer(default=2, doc="digits after the point in the label")
    log_display = param.Boolean(default=False, doc="the value is log10 of a factor: show x10^value")

    _esm = _ESM
    _stylesheets = [_CSS]

    def __init__(self, **params):
        params.setdefault("sizing_mode", "stretch_width")
        params.setdefault("margin", (4, 10))
        super().__init__(**params)
        self._live_callbacks = []

    def on_live(self, callback) -> None:
        """``callback(value, seq)`` on every live move."""
        self._live_callbacks.append(callback)

    def _handle_msg(self, msg) -> None:
        if isinstance(msg, dict) and msg.get("type") == "live":
            for cb in self._live_callbacks:
                cb(float(msg["value"]), int(msg.get("seq", 0)))

