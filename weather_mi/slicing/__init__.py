"""The interactive approximation: half-angle slicing (Dr.Jit) with the paper's light transport and a
multiple-scattering light model beyond it; see renderer.py for the modules."""
from __future__ import annotations

from .modes import MODES, TABLE_IV, SliceMode, SliceParams
from .renderer import SliceRenderer


def render_slices(spec, vol, mode: SliceMode = SliceMode(), slices: int = 128, light_res: int | None = None,
                  params: SliceParams | None = None, detail_field=None, uniform_phase=None,
                  forward_peak_deg: float | None = None, **param_kw):
    """Render ``vol`` as seen by ``spec`` with half-angle slicing.

    For many frames, keep a :class:`SliceRenderer` and call its ``frame`` method (nothing recompiles
    between frames).

    Parameters
    ----------
    spec : SceneSpec
        Camera, sun, sky, ground and image size.
    vol : OpticalVolume
        The medium (with phase tables).
    mode : SliceMode, default SliceMode()
        One of ``MODES`` (the paper's Table IV and ``SliceMode(light="multiple")``).
    slices : int, default 128
        Number of slice planes, >= 2.
    light_res : int, optional
        Light-buffer texels per side, >= 4 (None: automatic, ``light.auto_light_res``).
    params : SliceParams, optional
        Interactive parameters; default ``SliceParams(**param_kw)``.
    detail_field : numpy.ndarray, optional
        (z, y, x) multiplier of the extinction for ``mode.detail`` (:func:`weather_mi.optics.detail.field`).
    uniform_phase : phase table, optional
        The one phase function of ``phase="uniform"`` modes (default the first species' table).
    forward_peak_deg : float, optional
        Phase-function peaks within this angle (degrees) count as unscattered light (delta-M, as in the
        reference); None: 3 deg for the "multiple" model, 0 for the paper's modes.
    **param_kw
        Fields of :class:`SliceParams` when ``params`` is not given: scale=, albedo=, cone_angle_deg=,
        forward_fraction=, ambient=, blur_length_m=, ms_extinction=, ms_contribution=,
        ms_eccentricity=, sky_gain=, sky_extinction=, ...

    Returns
    -------
    Image
        Radiance (W/m^2/sr, RGB) in the same units, framing and conventions as ``render_reference``.

    Raises
    ------
    ValueError
        For too few slices, a too small light buffer or bad detail inputs.
    """
    params = params or SliceParams(**param_kw)
    renderer = SliceRenderer(vol, mode, slices, light_res, detail_field=detail_field, uniform_phase=uniform_phase,
                             forward_peak_deg=forward_peak_deg)
    return renderer.frame(spec, params)


__all__ = ["MODES", "SliceMode", "SliceParams", "SliceRenderer", "render_slices", "TABLE_IV"]
