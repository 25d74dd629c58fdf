"""The interactive approximation: half-angle slicing (Dr.Jit) with the paper's light transport and a
multiple-scattering light model beyond it; see renderer.py for the modules."""
from __future__ import annotations

from .modes import MODES, TABLE_IV, SliceMode, SliceParams
from .renderer import SliceRenderer


def render_slices(spec, vol, mode: SliceMode = SliceMode(), slices: int = 128, light_res: int | None = None,
                  params: SliceParams | None = None, detail_field=None, uniform_phase=None,
                  forward_peak_deg: float | None = None, **param_kw):
    """Render ``vol`` as seen by ``spec`` with half-angle slicing; returns an Image in the same units,
    framing and conventions as ``render_reference``. ``mode``: one of ``MODES`` (the paper's Table IV
    and ``SliceMode(light="multiple")``); ``light_res``: light-buffer texels per side (None: automatic);
    ``forward_peak_deg``: phase-function peaks within this angle count as unscattered light (delta-M, as
    in the reference; None: 3 deg for the "multiple" model, 0 for the paper's modes).
    Interactive parameters go in ``params`` (or as keywords: scale=, albedo=, cone_angle_deg=,
    forward_fraction=, ambient=, blur_length_m=, ms_extinction=, ms_contribution=, ms_eccentricity=,
    sky_gain=, sky_extinction=). For many frames, keep a SliceRenderer and call its ``frame`` method
    (nothing recompiles between frames)."""
    params = params or SliceParams(**param_kw)
    renderer = SliceRenderer(vol, mode, slices, light_res, detail_field=detail_field, uniform_phase=uniform_phase,
                             forward_peak_deg=forward_peak_deg)
    return renderer.frame(spec, params)


__all__ = ["MODES", "SliceMode", "SliceParams", "SliceRenderer", "render_slices", "TABLE_IV"]
