"""Mitsuba 3 integrator ``majorant_volpath``: volumetric path tracing over grids of local majorants.

Mitsuba's ``heterogeneous`` medium samples free flights by delta tracking against ONE global majorant,
so in a sparse storm every ray through clear air pays ~majorant x length null collisions. This
integrator walks grids of local majorants along the ray with a 3-D DDA (Amanatides & Woo 1987;
pbrt-v4's ``DDAMajorantIterator``), crossing empty space in one step (Cohen & Sheffer 1994):

* majorants per texel cell (:mod:`.majorants`, exact bounds of the trilinear interpolant) or per coarse
  cell; the DDA in :mod:`.dda`;
* free flights by delta tracking, shadow rays by exact transmittance (Simpson's rule per texel cell) or
  ratio tracking (Novak et al. 2014), in :mod:`.trackers`; spectrally varying extinction by
  history-aware spectral tracking (Kutz et al. 2017);
* the integrator's own sun (a disk or a point, with MIS against the path's continuation, optional sun
  guiding after Buras & Mayer 2011 and aureole next-event estimation) in :mod:`.sun`; multiple-vertex
  next-event estimation towards it (Weber et al. 2017; off by default) in :mod:`.mvnee`;
* history-aware channel sampling of a chromatic phase function (Kutz et al. 2017, applied to directions);
* Russian roulette once per real scattering / surface vertex, survival min(max T, 1) (no weight grows),
  long walks cut by a survival of 1/2 at each depth 2^k >= LONG_WALK_DEPTH;
* persistent lanes (:mod:`.lanes`): ``render_pass`` / ``render_passes``, used by ``reference.render_pass`` on
  LLVM variants; spectral variants (4 wavelengths a path) take ``sun_spectrum`` (:func:`.sun.parse_spectrum`).

Otherwise the structure and estimators of Mitsuba's ``volpath``: analog absorption, phase-function and
BSDF sampling with emitter sampling and MIS (power heuristic), delta emitters by NEE only, null BSDFs
passed through without counting depth, sensors inside media. The path loop is :class:`.path_loop.PathLoop`, stages
over a :func:`.path_state.path_state_class` state; all loops are symbolic (one kernel per render; new
data through ``mi.traverse`` + ``params.update()``, new majorants and emitter parameters reuse it).

Scope: one medium in the scene (any number of shapes may reference it), extinction looked up in its
``sigma_t`` volume when it is a ``heterogeneous`` medium (scale applied; no microflakes), otherwise
through ``get_scattering_coefficients``; no medium emission. The design, the measurements behind every
default and their history: ``docs/reference-estimator.md``.
"""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

from . import air_albedo, air_levels, spectral_air, spectral_air_albedo, sun_properties
from .lanes import MAX_JOBS_PER_LAUNCH, render_passes
from .majorants import DEFAULT_CELL, SAFETY, empty_space_radius, majorant_grid, texel_majorant_grid  # noqa: F401 (re-exported)
from .medium_setup import GridCache, MediumSetup, Tracking, unit_cube_to_world, volume_data
from .path_loop import GUIDE_GROWTH, GUIDE_SEEN, LONG_WALK_DEPTH, PathLoop  # noqa: F401 (re-exported)
from .properties import check as _check, choice as _choice, majorant_property as _majorant_property
from .variant_class import variant_class

PLUGIN_NAME = "majorant_volpath"
DEFAULT_EMITTER_NEE = 0.1  # probability of sampling the scene's emitters (the sky) at a vertex: 1.2x the efficiency of 0.25, 2x that of 0.05 (demo views)
DEFAULT_TRACKING_GRID = "texel"  # free flights: "texel" (majorants per texel cell) or "coarse" (the majorant grid)
DEFAULT_PERSISTENT_LANES = True  # reference.render_pass renders LLVM passes with render_pass (persistent lanes)
DEFAULT_TRANSMITTANCE = "exact"  # shadow rays: "exact" (Simpson per texel cell) or "ratio" (ratio tracking)


# ---------------------------------------------------------------- integrator

class MajorantVolpath:
    """Volumetric path tracer with DDA majorant-grid delta tracking (the module docstring).

    .. pluginparameters::

     * - max_depth, rr_depth
       - |int|
       - Longest path (-1: infinite; default -1); depth from which Russian roulette is played (default 5).
     * - rr_mode
       - |string|
       - "throughput" (default: survival min(max T, 1), long walks cut) or "volpath" (capped at 0.95).
     * - hide_emitters
       - |bool|
       - Hide directly visible emitters (default: false).
     * - majorant, cell
       - |tensor|, |int|
       - Majorants (Z, Y, X) in 1/m (scale applied) from :func:`.majorants.majorant_grid` with ``cell``
         fine voxels per cell (default DEFAULT_CELL); without it built from the medium at each render.
     * - to_world
       - |transform|
       - The unit cube onto the sigma_t grid's box (default and check: the medium's sigma_t volume).
     * - tracking_grid, transmittance
       - |string|
       - Free flights over "texel" cells (default) or the "coarse" grid; shadow rays by "exact"
         transmittance (default) or "ratio" tracking.
     * - persistent_lanes
       - |bool|
       - Whether ``reference.render_pass`` renders with persistent lanes (default: DEFAULT_PERSISTENT_LANES).
     * - phase_channels
       - |string|
       - "history" (default: channels drawn in proportion to the throughput; in spectral variants the R, G, B
         densities in the throughput's shares by wavelength, :mod:`.lane_channels`, without sun guiding, the
         aureole or multiple-vertex NEE) or "mean".
     * - emitter_nee
       - |float|
       - Probability of a shadow ray towards the scene's emitters (the sky), else the sun; in (0, 1].
     * - sun_direction, sun_irradiance
       - |vector|, |color|
       - The integrator's own sun: direction towards it; irradiance normal to the beam (RGB, default 1).
     * - sun_angular_diameter
       - |float|
       - Degrees, <= MAX_SUN_DIAMETER_DEG; 0 (default) is a point sun.
     * - sun_air, sun_air_h0/h1/mu0/mu1/radius, sun_spectrum, sun_spectrum_nm
       - |tensor|, |float|
       - The sun's colour after the air by height and cos(zenith) (:func:`.sun.parse_air`); spectral variants: its spectrum.
     * - sun_sampling
       - |string|
       - "mis" (default), or one strategy alone, "nee" or "phase" (for tests).
     * - sun_guiding, aureole_nee
       - |float|
       - Probabilities of a sun-guided scattering direction ([0, 1)) and of the aureole estimator
         ([0, 1], needs "mis" and no guiding); default 0.
     * - mvnee, mvnee_length
       - |float|, |int|
       - Probability of a multiple-vertex NEE chain (:mod:`.mvnee`; exclusive as the aureole) and its length.
     * - air_extinction
       - |tensor|
       - (levels, 3) the air's extinction per level of the sigma_t grid (1/m), which a 3-channel grid holds added
         and which is added to a grey (1-channel) one, the albedo then the mixture's of ``air_albedo`` and
         ``air_scattering`` (:mod:`.air_albedo`, ``MediumSetup.add_air``) (:mod:`.air_levels`): its cells are
         crossed as empty space, with the air's majorant. An air whose three channels are equal (a satellite
          band's) is tracked grey (``air_levels.equal_channels``); a chromatic one's free flights follow its
          largest channel, grey, the channels weighted in closed form (:mod:`.trackers`). Spectral variants,
          with ``air_spectra``, ``air_nm`` and ``air_component_albedo``: (levels, M) the profiles of the air's
          components, read at the path's wavelengths (:mod:`.spectral_air`; the albedo :mod:`.spectral_air_albedo`).
     * - periodic, periodic_tiles
       - |string|, |int|
       - "none" (default), "view" or "transport": x and y periodic over ``periodic_tiles`` periods on each
         side (:mod:`weather_mi.optics.periodic`; grids with ``wrap_mode`` repeat, "texel" tracking).

    The methods only: :func:`register` puts them on the variant's ``mi.SamplingIntegrator`` (``variant_class``)."""

    def __init__(self, props: mi.Properties):
        mi.SamplingIntegrator.__init__(self, props)
        self._parse(props)
        # per-render state, filled by _setup: the scene's medium, the trackers' grids and frame, and the
        # caches of the grids built from the medium's data
        self._ms = self._tk = None
        self._grids = GridCache()
        self._auto_key = None

    def _parse(self, props):
        """The properties of the table above; any invalid value raises ValueError."""
        get = props.get
        max_depth = int(get("max_depth", -1))
        _check(max_depth >= -1, f"max_depth must be -1 (infinite) or >= 0, got {max_depth}")
        self.max_depth = 0xFFFFFFFF if max_depth == -1 else max_depth
        self.rr_depth, self.hide_emitters_ = int(get("rr_depth", 5)), bool(get("hide_emitters", False))
        _check(self.rr_depth >= 0, f"rr_depth must be >= 0, got {self.rr_depth}")
        self.cell = int(get("cell", DEFAULT_CELL))
        _check(self.cell >= 1, f"cell must be >= 1, got {self.cell}")
        self.auto_majorant = "majorant" not in props
        self.majorant = mi.TensorXf(np.zeros((1, 1, 1), np.float32) if self.auto_majorant
                                    else _majorant_property(props["majorant"]))
        self.to_world = props["to_world"] if "to_world" in props else None
        self.tr_mode = _choice(props, "transmittance", DEFAULT_TRANSMITTANCE, ("exact", "ratio"))
        self.track_mode = _choice(props, "tracking_grid", DEFAULT_TRACKING_GRID, ("texel", "coarse"))
        self.persistent = bool(get("persistent_lanes", DEFAULT_PERSISTENT_LANES))
        self.rr_mode = _choice(props, "rr_mode", "throughput", ("throughput", "volpath"))
        self.emitter_nee = float(get("emitter_nee", DEFAULT_EMITTER_NEE))
        _check(0.0 < self.emitter_nee <= 1.0, f"'emitter_nee' must be in (0, 1], got {self.emitter_nee}")
        self.channels = _choice(props, "phase_channels", "history", ("history", "mean"))
        self.periodic = _choice(props, "periodic", "none", ("none", "view", "transport"))
        self.reach = int(get("periodic_tiles", 0))
        _check(self.periodic == "none" or (self.reach >= 1 and self.track_mode == "texel"),
               f"periodic needs periodic_tiles >= 1 and tracking_grid 'texel', got {self.reach}, {self.track_mode!r}")
        self.air_spectral = spectral_air.parse(props, _check)  # spectral variants: the air over wavelength
        if self.air_spectral is not None:
            self.air_levels = self.air_spectral.full  # (levels, K): what the majorants bound
            self.air_albedo = spectral_air_albedo.parse(props, _check)
        else:
            self.air_levels = air_levels.parse(props, _check)  # the air in the box, per level (optional)
            self.air_albedo = air_albedo.parse(props, self.air_levels, _check)  # with its albedo, where added
        sun_properties.parse(self, props)  # the integrator's own sun (optional)

    # ------------------------------------------------------------ Mitsuba object interface
    def aov_names(self):
        return []

    def to_string(self):
        shape = tuple(self.majorant.shape)
        return (f"MajorantVolpath[max_depth = {self.max_depth if self.max_depth != 0xFFFFFFFF else -1}, "
                f"rr_depth = {self.rr_depth}, hide_emitters = {self.hide_emitters_}, "
                f"majorant = {'auto' if self.auto_majorant else shape}, cell = {self.cell}, "
                f"sun = {self.sun_mode}, sun_guiding = {self.guiding}]")

    def traverse(self, cb):
        cb.put("majorant", self.majorant, mi.ParamFlags.NonDifferentiable)
        if self.sun_mode != "none":
            cb.put("sun_direction", self.sun_dir, mi.ParamFlags.NonDifferentiable)
            cb.put("sun_value", self.sun_value, mi.ParamFlags.NonDifferentiable)
            cb.put("sun_vmax", self.sun_vmax, mi.ParamFlags.NonDifferentiable)
            cb.put("sun_guiding", self.guide_p, mi.ParamFlags.NonDifferentiable)
            cb.put("aureole_nee", self.aureole_p, mi.ParamFlags.NonDifferentiable)

    def parameters_changed(self, keys=[]):
        pass

    # ------------------------------------------------------------ per-render setup
    def _setup(self, scene, sensor_medium):
        """Find the scene's medium and build (or reuse) the trackers' grids: ``self._ms``, ``self._tk``."""
        ms = MediumSetup(scene, sensor_medium)
        self._ms = ms
        self._tk = Tracking(ms)
        if ms.medium is None:
            return
        vol = ms.volume
        to_world = unit_cube_to_world(self.to_world, vol)
        to_local = mi.Transform4f(mi.ScalarTransform4f(np.linalg.inv(to_world).astype(np.float32).tolist()))
        if self.auto_majorant:
            if vol is None:
                raise RuntimeError(f"{PLUGIN_NAME}: no 'majorant' given and the medium has no sigma_t grid")
            data = volume_data(vol)
            key = (data.array.index, ms.scale, self.cell)
            if key != self._auto_key:
                grid = np.asarray(data)  # in place (llvm): a copy only where scaled
                maj = majorant_grid(grid if ms.scale == 1.0 else grid * ms.scale, self.cell)
                if self.air_levels is not None:  # a bound of the hydrometeors' and the air's sum either way
                    maj = air_levels.with_coarse_air(maj, self.air_levels, self.cell)
                self.majorant = mi.TensorXf(maj)
                self._auto_key = key
        levels = None
        if self.air_levels is not None and vol is not None and int(volume_data(vol).shape[-1]) == 1:
            if self.air_spectral is not None:  # spectral variants: the air at the path's wavelengths
                levels = self.air_spectral
            else:
                grey = air_levels.equal_channels(self.air_levels)  # a satellite band's: tracked grey (not spectral)
                levels = air_levels.AirLevels(self.air_levels, grey)
            ms.add_air(levels, self.air_albedo, to_local, self.periodic != "none")
        coarse = self._grids.coarse(self.majorant, vol, ms.scale, self.cell)
        periodic = self.periodic != "none"
        texel, texel_data = self._grids.texel(vol, ms.scale, self.reach if periodic else None, self.air_levels,
                                              grey_air=not ms.spectral, levels=levels)
        track = texel if (texel is not None and self.track_mode == "texel") else coarse
        # (a grey grid's texels lack the air added per level: the trackers add it, ``trackers``)
        self._tk = Tracking(ms, to_local, coarse, texel, track, texel_data, self.periodic, self.reach)

    # ------------------------------------------------------------ main entry
    def sample(self, scene, sampler, ray, medium=None, active=True):
        loop = self._path_loop(scene, medium)
        _, path = dr.while_loop(state=(sampler, loop.initial(mi.Ray3f(ray), medium, mi.Bool(active))),
                                cond=loop.cond, body=loop.body, label="majorant_volpath")
        return path.result, path.valid_ray, []

    def _path_loop(self, scene, medium) -> "PathLoop":
        """The path loop over ``scene`` (after the per-render setup), its paths starting in ``medium``."""
        return PathLoop(self, scene, medium)

    # ------------------------------------------------------------ persistent lanes
    def render_pass(self, scene, spp: int, seed: int, lanes: int | None = None,
                    max_jobs: int = MAX_JOBS_PER_LAUNCH, pixels=None) -> np.ndarray:
        """One pass of ``spp`` samples per pixel with persistent lanes: :meth:`render_passes` of one pass."""
        return self.render_passes(scene, [(spp, seed)], lanes, max_jobs, pixels)[0]

    def render_passes(self, scene, passes, lanes: int | None = None, max_jobs: int = MAX_JOBS_PER_LAUNCH,
                      pixels=None) -> list:
        """Passes ``[(spp, seed), ...]`` rendered together with persistent lanes: :func:`.lanes.render_passes`."""
        return render_passes(self, scene, passes, lanes, max_jobs, pixels, PLUGIN_NAME)


def register() -> None:
    """Register ``majorant_volpath`` with the current Mitsuba variant."""
    cls = variant_class(MajorantVolpath, "SamplingIntegrator")
    mi.register_integrator(PLUGIN_NAME, lambda props: cls(props))
