"""The loop state of a path of ``majorant_volpath`` (a ``DRJIT_STRUCT`` with named fields), one class
per Mitsuba variant (its field types are the variant's), and ``Vertex``, what the stages of one
iteration of its path loop pass on to the later ones.
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


class Vertex:
    """What the stages of one iteration of the path loop (``path_loop.PathLoop.body``) pass on to
    the later ones: made anew by every iteration (``free_flight``), not loop state, so a plain class, its
    fields declared as its annotations (its ``__slots__``): a field not declared here cannot be set, and one that no stage has set
    yet cannot be read (AttributeError while tracing). Dr.Jit types of the variant, one lane per path.

    The stages set the fields in this order (``STAGES``; a stage reads only what it or an earlier one set):

    ============  ============================================  ===============================================
    stage         sets                                          reads
    ============  ============================================  ===============================================
    free_flight   act_scatter, active_surface, mei              (its own)
    emitters_hit  active_surface (&= a valid surface), bsdf     active_surface
    vertex        act_e_surf, act_e, ref, eps (0), alpha,       active_surface, bsdf, act_scatter, mei
                  lane_vertex
    nee           eps (sun guiding)                             act_e, act_e_surf, act_scatter, ref, bsdf, mei,
                                                                alpha, lane_vertex, eps
    aureole_nee   eps_a                                         act_scatter, mei, alpha (``mvnee.chain``: mei)
    sample_phase  act_scatter (&= a phase pdf > 0)              act_scatter, mei, alpha, lane_vertex, eps, eps_a
    sample_bsdf   --                                            active_surface, bsdf, act_scatter
    ============  ============================================  ===============================================
    """

    act_scatter: mi.Bool                 # a real collision in the medium where the path scatters (phase sampling)
    active_surface: mi.Bool              # the path reaches p.si (or escapes; emitters_hit keeps valid surfaces)
    mei: mi.MediumInteraction3f          # the collision: t (m along the ray), p (m, world), sigma_t (1/m), ...
    bsdf: mi.BSDFPtr                     # the BSDF of the surface interaction ``p.si``
    act_e_surf: mi.Bool                  # emitter sampling at a smooth surface
    act_e: mi.Bool                       # emitter sampling at this vertex (a smooth surface or a collision)
    ref: mi.Interaction3f                # the vertex's position (m, world) for emitter sampling
    eps: mi.Float                        # probability of a sun-guided continuation here (0 without guiding)
    alpha: mi.Spectrum | None            # channel probabilities (throughput / its sum); None: no channel sampling
    lane_vertex: object | None           # each lane's weights and table node (.lane_directions.LaneVertex)
    eps_a: mi.Float                      # probability of the aureole estimator here (0 without it)
    __slots__ = tuple(__annotations__)

    # (stage, the fields it sets), in the order PathLoop.body runs the stages
    STAGES = (("free_flight", ("act_scatter", "active_surface", "mei")),
              ("emitters_hit", ("active_surface", "bsdf")),
              ("vertex", ("act_e_surf", "act_e", "ref", "eps", "alpha", "lane_vertex")),
              ("nee", ("eps",)),
              ("aureole_nee", ("eps_a",)),
              ("sample_phase", ("act_scatter",)),
              ("sample_bsdf", ()))
