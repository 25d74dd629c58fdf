"""``ViewControls``: the viewer's knobs as one ``param.Parameterized`` (a parameter per knob), their
widgets (``Widget.from_param`` for Panel's own, a ``LiveSlider`` for the ones that change the picture
while dragged), and how a knob's change becomes a ``ViewState`` (``changed``).

A parameter changes on a widget's value (a click, a slider released); a LiveSlider's moves in between
reach ``on_live`` without touching the parameter. Either way the session turns one knob into one
ViewState update (reading every knob on each slider move costs the event loop more than the change).
"""
from __future__ import annotations

from dataclasses import replace

import panel as pn
import param

from ..slicing.modes import DEFAULT_DETAIL, MODES
from .controls import LiveSlider
from .state import ViewState

SLICE_CHOICES = [16, 32, 48, 64, 96, 128, 192, 256, 384, 512]
WIDGET_DEBOUNCE_MS = 5  # Panel waits this long to merge a widget's changes (its default, 50 ms, is latency)

# the LiveSliders of the view's own knobs: parameter -> (label, start, end, step, decimals, extra keywords)
LIVE_KNOBS = {
    "fov": ("Field of view (deg)", 10, 120, 1, 0, {}),
    "sun_azimuth": ("Sun azimuth (deg)", 0, 360, 1, 0, {"css_classes": ["wm-sun-azimuth"]}),
    "sun_elevation": ("Sun elevation (deg)", -5, 90, 0.5, 1, {}),
    "albedo": ("Albedo", 0.0, 1.0, 0.005, 3, {}),
    "cone": ("Cone angle (deg)", 1, 60, 0.5, 1, {}),
    "forward": ("Forward fraction", 0.0, 1.0, 0.01, 2, {}),
    "ambient": ("Ambient (Table IV modes)", 0.0, 1.0, 0.01, 2, {}),
    "exposure": ("Exposure (EV)", -4, 4, 0.1, 1, {}),
}


class ViewControls(param.Parameterized):
    """The knobs of one tab; ``scale_<species>`` (log10 of the factor) and ``detail_<species>`` are
    added per instance for the storm's species."""

    mode = param.Selector(objects=list(MODES), label="Mode")
    species_colors = param.Boolean(False, label="Species colours (Fig. 2)")
    slices = param.Selector(objects=SLICE_CHOICES, default=128, label="Slices")
    camera_kind = param.Selector(objects=["ground", "orbit"], default="ground", label="Camera")
    atmosphere = param.Selector(objects=["none", "clear"], default="none", label="Air")
    own_albedo = param.Boolean(False, label="One albedo for all species")
    own_forward = param.Boolean(False, label="One forward fraction")
    time = param.Integer(0, label="Time")
    fov = param.Number(70.0)
    sun_azimuth = param.Number(290.0)
    sun_elevation = param.Number(35.0)
    albedo = param.Number(0.99)
    cone = param.Number(10.0)
    forward = param.Number(0.9)
    ambient = param.Number(0.0)
    exposure = param.Number(0.0)

    def __init__(self, state: ViewState, species, n_times: int):
        super().__init__(mode=state.mode, species_colors=state.species_colors, slices=state.slices,
                         camera_kind=state.camera.kind, atmosphere=state.atmosphere, own_albedo=state.albedo is not None,
                         own_forward=state.forward_fraction is not None, time=state.time, fov=state.camera.fov,
                         sun_azimuth=state.sun_azimuth, sun_elevation=state.sun_elevation, albedo=state.albedo or 0.99,
                         cone=state.cone_angle_deg, forward=state.forward_fraction or 0.9, ambient=state.ambient,
                         exposure=state.exposure_ev)
        self.species = list(species)
        self.n_times = n_times
        for n in self.species:
            self.param.add_parameter(f"scale_{n}", param.Number(0.0))
            self.param.add_parameter(f"detail_{n}", param.Number(DEFAULT_DETAIL))
        self.param.time.bounds = (0, max(n_times - 1, 1))
        self._build_widgets()

    def _build_widgets(self) -> None:
        w = pn.widgets
        p = self.param
        self.widgets = {"mode": w.Select.from_param(p.mode), "species_colors": w.Checkbox.from_param(p.species_colors),
                        "slices": w.DiscreteSlider.from_param(p.slices),
                        "camera_kind": w.RadioButtonGroup.from_param(p.camera_kind),
                        "atmosphere": w.RadioButtonGroup.from_param(p.atmosphere, css_classes=["wm-atmosphere"]),
                        "own_albedo": w.Checkbox.from_param(p.own_albedo),
                        "own_forward": w.Checkbox.from_param(p.own_forward),
                        "time": w.Player.from_param(p.time, interval=800, loop_policy="loop", show_value=True,
                                                    visible=self.n_times > 1, width=300, css_classes=["wm-time"])}
        for wd in self.widgets.values():
            wd._debounce = WIDGET_DEBOUNCE_MS
        for name, (label, start, end, step, decimals, kw) in LIVE_KNOBS.items():
            self.widgets[name] = LiveSlider(label=label, start=start, end=end, step=step, value=getattr(self, name),
                                            decimals=decimals, **kw)
        for n in self.species:
            self.widgets[f"scale_{n}"] = LiveSlider(label=f"{n} scaling", start=-2.0, end=2.0, step=0.02, value=0.0,
                                                    log_display=True)
            self.widgets[f"detail_{n}"] = LiveSlider(label=f"{n} detail", start=0.0, end=2.0, step=0.05,
                                                     value=DEFAULT_DETAIL)
        for name, wd in self.widgets.items():
            if isinstance(wd, LiveSlider):  # released: the parameter; moved: ``on_live``
                wd.param.watch(lambda e, name=name: setattr(self, name, e.new), "value")

    @property
    def knobs(self) -> list[str]:
        """The names of the parameters that change the view."""
        return list(self.widgets)

    def on_change(self, callback) -> None:
        """``callback(name, value)`` when a knob's parameter changes."""
        self.param.watch(lambda e: callback(e.name, e.new), self.knobs)

    def on_live(self, callback) -> None:
        """``callback(name, value, seq)`` on every move of a LiveSlider (``seq``: the page's input stamp)."""
        for name, wd in self.widgets.items():
            if isinstance(wd, LiveSlider):
                wd.on_live(lambda v, seq, name=name: callback(name, v, seq))

    def changed(self, state: ViewState, name: str, value) -> ViewState:
        """``state`` with knob ``name`` at ``value`` (the other knobs as ``state`` has them)."""
        if name in ("camera_kind", "fov"):
            cam = {"kind": str(value)} if name == "camera_kind" else {"fov": float(value)}
            return state.updated(camera=replace(state.camera, **cam))
        if name.startswith("scale_"):
            return state.updated(scale=tuple(sorted({**dict(state.scale), name[6:]: round(10.0 ** value, 4)}.items())))
        if name.startswith("detail_"):
            return state.updated(detail=tuple(sorted({**dict(state.detail), name[7:]: float(value)}.items())))
        own = {"own_albedo": ("albedo", bool(value), self.albedo), "albedo": ("albedo", self.own_albedo, value),
               "own_forward": ("forward_fraction", bool(value), self.forward),
               "forward": ("forward_fraction", self.own_forward, value)}
        if name in own:
            field, on, v = own[name]
            return state.updated(**{field: float(v) if on else None})
        simple = {"mode": ("mode", str), "species_colors": ("species_colors", bool), "slices": ("slices", int),
                  "atmosphere": ("atmosphere", str),
                  "sun_azimuth": ("sun_azimuth", lambda v: float(v) % 360.0),
                  "sun_elevation": ("sun_elevation", float), "cone": ("cone_angle_deg", float),
                  "ambient": ("ambient", float), "exposure": ("exposure_ev", float),
                  "time": ("time", lambda v: int(min(v, self.n_times - 1)))}
        field, convert = simple[name]
        return state.updated(**{field: convert(value)})
