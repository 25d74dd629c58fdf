"""The loop state of a path of ``majorant_volpath`` (a ``DRJIT_STRUCT`` with named fields), one class
per Mitsuba variant (its field types are the variant's).
"""
from __future__ import annotations

import mitsuba as mi

_STATE_CLASSES: dict = {}


def path_state_class() -> type:
    """The loop state of a path (a ``DRJIT_STRUCT``, one class per variant).

    Fields: ``active`` (the path is alive), ``depth`` (scattering and non-null surface events so far),
    ``ray`` (the current ray), ``throughput`` and ``result`` (the path weight and the radiance collected),
    ``si`` (the next surface along ``ray``), ``medium`` (the medium ``ray`` travels in), ``eta`` (relative
    IOR product, for roulette), ``last_event`` (the previous vertex) and ``last_pdf`` (its continuation
    pdf, for MIS of emitters hit), ``needs_isect`` (``si`` is stale), ``specular_chain`` (only delta
    events so far: emitters hit count in full), ``valid_ray`` (the sample hit something), ``last_long``
    (the depth of the last long-walk cut), ``guide_left`` (sun guiding's remaining weight budget),
    ``last_pdf_sun`` (the previous vertex's continuation pdf in the sun's MIS), ``aur_w`` (the
    aureole estimator's MIS weight of the next sun NEE) and ``mv_r`` (multiple-vertex NEE's R_1..R_4,
    :mod:`.mvnee`).
    """
    key = mi.variant()
    if key not in _STATE_CLASSES:
        class PathState:
            DRJIT_STRUCT = {
                "active": mi.Bool, "depth": mi.UInt32, "ray": mi.Ray3f, "throughput": mi.Spectrum,
                "result": mi.Spectrum, "si": mi.SurfaceInteraction3f, "medium": mi.MediumPtr, "eta": mi.Float,
                "last_event": mi.Interaction3f, "last_pdf": mi.Float, "needs_isect": mi.Bool,
                "specular_chain": mi.Bool, "valid_ray": mi.Bool, "last_long": mi.UInt32, "guide_left": mi.Float,
                "last_pdf_sun": mi.Float, "aur_w": mi.Float, "mv_r": mi.Vector4f}

            def __init__(self, **fields):
                for name, value in fields.items():
                    setattr(self, name, value)
        PathState.__doc__ = path_state_class.__doc__
        _STATE_CLASSES[key] = PathState
    return _STATE_CLASSES[key]
