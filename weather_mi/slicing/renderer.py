"""``SliceRenderer``: half-angle slicing (Kniss et al. 2003, as adapted by Riley et al.) in Dr.Jit,
the glue between the modules that do the work:

geometry.py  the half-angle axis and the slice planes (visited from the light's side)
grids.py     the medium's per-species extinction grids and their box
light.py     ``LightVolume``: the light pass and the one light lookup
blur.py      the translucency blur of the light pass (separable taps of an exact variance)
eye.py       the eye pass: composite along camera rays (Eq. 8/9), the ground
view.py      camera rays and background per view, in a bounded cache
rays.py      the per-view arrays (camera and light rays, box and ground hits, phase functions) as float64
             kernels, the same floats as numpy's: a drag of the camera or the sun redoes them every frame

Everything that changes between frames (scalings, sun, camera, albedo, cone angle, forward fraction,
the light model's parameters) enters kernels as opaque values or data, so frames after the first
compile nothing: the frame's kernels read ``frame_inputs.FrameInputs`` and the renderer's declared
constants alone (``frame_inputs.KernelConstants``; anything else raises).
"""
from __future__ import annotations

import math
import time
import weakref

import numpy as np

from ..optics.forward_peak import DEFAULT_CONE_DEG, check_cone_deg, peak_tables
from ..io.image import Image
from ..kernel.jitarrays import kernel_scalar
from ..kernel.scene_dict import terrain_surround_m
from ..optics.volume import OpticalVolume
from ..scene.spec import SceneSpec
from ..kernel.sky import sky_irradiance_horizontal
from .blur import variance_per_metre
from .eye import LightModel, composite
from .eye_air import eye_air_input, light_shadow, seen_through_air
from .eye_air_coarse import applies, seen_through_coarse_air
from .recording import freeze_kernels, raise_recording_error, without_gc
from .frame_inputs import EyeInputs, EyeRays, FrameInputs, KernelConstants, MultipleLight, TextureBuild
from .geometry import slice_geometry, slicing_box
from .grids import set_grids
from .jitter import jitter_rotation, slab_offsets
from .light import LightVolume, auto_light_res
from .modes import SliceMode, SliceParams
from .occupancy import OccupancyMap
from .periodic import PeriodicSlicing
from .rays import Scalars, f32, phase_index, phase_table, phase_values
from .supersample import block_mean, block_mean_jit, fine_spec
from .sun_air import sun_at_height
from .sun_air_table import as_sun_air, sun_air_input
from .texture_storage import ChannelTextures, replace_storage
from .view import ViewCache

# the cone angle whose spread sets the light pass's blur steps (independent of the interactive cone angle)
REFERENCE_CONE_DEG = 20.0
SKY_SLICES, SKY_RES = 48, 48  # the zenith light volume of the "multiple" model (diffuse light: coarse)


class SliceRenderer:
    """An interactive half-angle slicing renderer bound to one OpticalVolume.

    ``frame(spec, params)`` renders; textures, kernels and the last few views' rays are reused.

    Parameters
    ----------
    vol : OpticalVolume
        The medium (with phase tables).
    mode : SliceMode, default SliceMode()
        Phase functions, light model and colouring.
    slices : int, default 128
        Number of slice planes, >= 2.
    light_res : int, optional
        Texels per side of the light buffer, >= 4 (None: ``light.auto_light_res``, 128 for most storms).
    detail_field : numpy.ndarray, optional
        (z, y, x) multiplier of the extinction (:func:`weather_mi.optics.detail.field`), used with
        ``mode.detail``.
    uniform_phase : phase table, optional
        The one phase function of ``phase="uniform"`` modes (default the first species' table).
    differentiable : bool, default False
        Build the frame so that Dr.Jit can differentiate it (``frame(..., return_arrays=True)``).
    detail_noise : numpy.ndarray, optional
        (z, y, x) unit-variance noise (:func:`weather_mi.optics.detail.noise`) for ``mode.detail``: species s's
        extinction is multiplied by exp(a_s n - a_s^2 / 2), a_s from ``SliceParams.detail``. Not with
        ``detail_field``.
    forward_peak_deg : float, optional
        Phase-function peaks within this angle (degrees) count as unscattered light (delta-M); None:
        3 deg for the "multiple" model, 0 for the paper's modes.
    eye_air : bool, default True
        With ``spec.atmosphere``: the air along the eye rays, inside the box and out (``eye_air.py``); False:
        the sun's colour by height alone (the air on the sun's path).

    Raises
    ------
    ValueError
        For too few slices, a too small light buffer, a detail mode without its field or noise (or with
        both), or a detail array of the wrong shape.
    """

    def __init__(self, vol: OpticalVolume, mode: SliceMode = SliceMode(), slices: int = 128,
                 light_res: int | None = None, detail_field: np.ndarray | None = None, uniform_phase=None,
                 differentiable: bool = False, detail_noise: np.ndarray | None = None,
                 forward_peak_deg: float | None = None, eye_air: bool = True):
        from ..kernel.variant import ensure_registered
        ensure_registered()
        import mitsuba as mi
        self.mi = mi
        self.box = slicing_box(vol)                                               # where slices go
        self.periodic = PeriodicSlicing(vol, self.box) if vol.periodic else None  # (slicing/periodic.py)
        if self.periodic is not None:
            self.box = self.periodic.box
        if light_res is None:
            light_res = auto_light_res(self.box, vol.spacing)
        if slices < 2 or light_res < 4:
            raise ValueError(f"need at least 2 slices and a 4 x 4 light buffer, got {slices}, {light_res}")
        if mode.detail and detail_field is None and detail_noise is None:
            raise ValueError("SliceMode(detail=True) needs a detail_field (a (z, y, x) multiplier of the "
                             "extinction, weather_mi.optics.detail.field) or a detail_noise (unit-variance noise, "
                             "weather_mi.optics.detail.noise, amplitudes per species in SliceParams.detail)")
        if detail_field is not None and detail_noise is not None:
            raise ValueError("give a detail_field or a detail_noise, not both")
        self.vol, self.mode = vol, mode
        self.slices, self.light_res = int(slices), int(light_res)
        self.differentiable = differentiable
        self.n_species = len(vol.species)
        set_grids(self, vol, mode, detail_field, detail_noise)  # (grids.py)
        self.voxel_m = float(np.mean(vol.spacing))
        tables = list(vol.require_phase_tables())
        if mode.phase == "uniform":
            u = uniform_phase if uniform_phase is not None else tables[0]
            tables = [u] * self.n_species
        # the forward peaks as unscattered light (delta-M, as the path-traced reference does): the
        # "multiple" model by default, the paper's modes as published (no truncation)
        if forward_peak_deg is None:
            forward_peak_deg = DEFAULT_CONE_DEG if mode.light == "multiple" else 0.0
        self.forward_peak_deg = check_cone_deg(forward_peak_deg)
        self.peak_fraction = np.zeros(self.n_species)  # f_s: each species' peak share of its scattering
        if self.forward_peak_deg > 0:
            self.peak_fraction, tables = peak_tables(tables, self.forward_peak_deg)
        self.tables = tables
        self.albedo_rgb, self.colors = _species_albedo_and_colour(vol)                  # (S, 3) each
        self.groups = _scatter_groups(self.tables, self.colors if mode.species_colors else
                                      self.albedo_rgb / np.maximum(self.albedo_rgb.mean(axis=1, keepdims=True), 1e-12))
        self._make_textures(mode)
        # light and eye rays read the medium only between their first and last occupied block (occupancy.py)
        self.occupancy = None if self.periodic else OccupancyMap(mi, vol.beta_total, self.grid_box, vol.spacing)
        # the "multiple" model's parameters act in the eye pass only: its light pass is not differentiated
        # (one kernel for all slices instead of one per slice)
        self.light = LightVolume(mi, self.box, self.light_res, differentiable and mode.light != "multiple",
                                 occupancy=self.occupancy)
        self.sky_light = None
        if mode.light == "multiple":
            self.sky_light = LightVolume(mi, self.box, min(SKY_RES, self.light_res), occupancy=self.occupancy)
            self._sky_geometry = slice_geometry(np.array([0.0, 0.0, -1.0]), np.array([0.0, 0.0, 1.0]), self.box,
                                                min(SKY_SLICES, self.slices))
        terrain = getattr(vol, "terrain", None)
        self.views = ViewCache(self.box, terrain=terrain, occupancy=self.occupancy,
                               surround_m=None if terrain is None else terrain_surround_m(vol))
        # the cloud's asymmetry parameter for the ground's transmission: species weighted by their scattering
        sca = np.array([float(np.sum(vol.beta_ext[si])) * float(np.mean(self.albedo_rgb[si]))
                        for si in range(self.n_species)]) * (1.0 - self.peak_fraction)
        gs = np.array([float(t.g[1]) for t in self.tables])
        self.g_scattering = float(np.sum(sca * gs) / np.sum(sca)) if np.sum(sca) > 0 else 0.85
        self._texture_key = None  # the per-species inputs of the textures last built (plain numbers)
        self._last = {}  # per-frame numpy work kept from the last frame (``_reuse``)
        self._eye_air = eye_air  # the air along the eye rays with spec.atmosphere (eye_air.py)
        self.timing = {}
        self._t_light = None
        # frames whose inputs keep their structure launch the recorded kernels without tracing Python
        # (dr.freeze; FROZEN_FRAMES False or SliceRenderer.frozen = False: traced every frame)
        self.frozen = FROZEN_FRAMES
        self._frozen_kernels = freeze_kernels(weakref.ref(self))
        self._recording_error = None  # what the kernels raised while being recorded (see recording.freeze_kernels)
        self._constants = KernelConstants(self)  # all of the renderer that its frame's kernels see

    def _make_textures(self, mode: SliceMode):
        """One voxel each until a frame builds them: the eye's texture (beta_sca per group, after beta where
        differentiated) and the light pass's source ((beta, beta_f), or beta where no light is scattered forward).
        One phase function and albedos that agree within UNIFORM_ALBEDO_SPREAD make beta_sca / beta and beta_f /
        beta one number each (``mean_albedo``): the source holds beta alone, the eye's nothing for one group."""
        mi = self.mi
        uniform = mode.phase == "uniform" and _albedos_agree(self.albedo_rgb)
        self.one_scattering_ratio = uniform and len(self.groups) == 1  # beta_sca = omega_bar beta
        self.uniform_forward = mode.light == "translucent" and uniform  # beta_f = f omega_bar beta
        self.light_channels = 2 if mode.light == "translucent" and not self.uniform_forward else 1
        eye_channels = int(self.differentiable) + (0 if self.one_scattering_ratio else len(self.groups))
        texture = (lambda t: mi.Texture3f(t, use_accel=False)) if self.periodic is None else \
            (lambda t: self.periodic.texture(mi, t))  # periodic: wrapping in x and y
        self.tex_eye = ChannelTextures.zeros(texture, mi, eye_channels)  # unpadded (texture_storage.py)
        self.tex_light_src = ChannelTextures.zeros(texture, mi, self.light_channels).parts[0]

    # ------------------------------------------------------------------ per-frame volume data
    def _species_vectors(self, params: SliceParams):
        """Per-species scaling, mean albedo, RGB tint ratio and forward fraction."""
        import drjit as dr
        names = self.vol.species
        for n in params.scale:
            if n not in names:
                raise ValueError(f"unknown species {n!r} in scale; expected one of {names}")
        scale = np.array([float(params.scale.get(n, 1.0)) for n in names])
        albedo = self.albedo_rgb if params.albedo is None else np.full((self.n_species, 3), params.albedo)
        if np.any(self.peak_fraction > 0):
            # delta-M per species (forward_peak.py): sigma_t' = sigma_t (1 - omega f), omega' = omega (1 - f) /
            # (1 - omega f); the kept extinction enters as a factor of the species' scaling
            f = self.peak_fraction
            kept = 1.0 - albedo.mean(axis=1) * f
            albedo = albedo * ((1.0 - f) / kept)[:, None]
            scale = scale * kept
        omega = albedo.mean(axis=1)
        tint = albedo / np.maximum(omega[:, None], 1e-12)
        cone = params.cone_angle_deg
        theta0 = math.radians(float(cone[0]) if dr.is_array_v(cone) else float(cone))
        if self.mode.light != "translucent":
            fwd = np.zeros(self.n_species)
        elif params.forward_fraction is not None:
            fwd = [params.forward_fraction] * self.n_species  # may be a Dr.Jit Float with gradients
        else:
            fwd = self._reuse("cone", theta0, lambda: np.array([float(np.mean(t.cone_fraction(theta0)))
                                                                for t in self.tables]))
        return scale, omega, tint, fwd

    def _reuse(self, name: str, key, make):
        """``make()``, or its value of the last frame where ``key`` is the same (an object compared by
        identity, or plain values by equality): a slider move does not redo the numpy work of the
        sun, the camera or the cone angle."""
        last = self._last.get(name)
        if last is not None and (last[0] is key or (isinstance(key, (tuple, float)) and last[0] == key)):
            return last[1]
        value = make()
        self._last[name] = (key, value)
        return value

    def mean_albedo(self, scale, omega):
        """omega_bar: the species' albedos weighted by their extinction over the volume (a kernel scalar),
        which a medium whose albedos agree within UNIFORM_ALBEDO_SPREAD (cloud, ice, rain, snow, graupel at
        550 nm: within 1e-4) has everywhere, to that spread: beta_sca = omega_bar beta and, with one forward
        fraction f, beta - beta_f = (1 - f omega_bar) beta. ``scale, omega``: of ``_species_vectors``."""
        w = np.asarray(scale, dtype=np.float64) * self.beta_sum_s
        w = w / max(float(w.sum()), 1e-30)
        return kernel_scalar(self.mi, float(np.dot(w, omega)))

    def _detail_amplitudes(self, params: SliceParams) -> list[float]:
        from .modes import DEFAULT_DETAIL
        for n in params.detail:
            if n not in self.vol.species:
                raise ValueError(f"unknown species {n!r} in detail; expected one of {self.vol.species}")
        return [float(params.detail.get(n, DEFAULT_DETAIL)) for n in self.vol.species]

    def _build_textures(self, build: TextureBuild, d: FrameInputs):
        """Eye texture [(beta_ext,) beta_sca per group] and light source [beta_ext, beta_forward] (1/m) from
        ``build``; ``d``: the frame's inputs (the arrays read, the textures written)."""
        mi = self.mi
        import drjit as dr
        S = self.n_species
        sc, om, fw = ([kernel_scalar(mi, v) for v in x] for x in (build.scale, build.omega, build.fwd))
        ext, beta_fwd, sca = mi.Float(0.0), mi.Float(0.0), []
        noise = d.noise
        amp = None if noise is None else [kernel_scalar(mi, a) for a in build.detail]
        for s in range(S):
            b = d.beta_s[s] * sc[s]
            if noise is not None:  # the amount of detail per species (paper section 5.4), log-normal, mean one
                b = b * dr.exp(amp[s] * noise - 0.5 * amp[s] * amp[s])
            ext += b
            sca.append(b * om[s])
            beta_fwd += b * om[s] * fw[s]
        grouped = []
        for members in self.groups:
            g_sca = sca[members[0]]
            for si in members[1:]:
                g_sca = g_sca + sca[si]
            grouped.append(g_sca)
        eye = ([ext] if self.differentiable else []) + ([] if self.one_scattering_ratio else grouped)
        replace_storage(mi, [(d.tex_eye, eye), (d.tex_light, [ext, beta_fwd][:self.light_channels])], self.shape)

    # ------------------------------------------------------------------ public
    def light_at(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Direct and forward-scattered sunlight (fractions of the sun's irradiance) at world points
        (N, 3), read from the last frame's light volume (points between the sun and the volume: 1, 0)."""
        return self.light.light_at(points)

    def frame(self, spec: SceneSpec, params: SliceParams = SliceParams(), return_arrays: bool = False,
              supersample: int = 1):
        """Render one frame.

        Parameters
        ----------
        spec : SceneSpec
            Camera, sun, sky, ground and image size.
        params : SliceParams, default SliceParams()
            Interactive parameters; changing them recompiles nothing.
        return_arrays : bool, default False
            Return the Dr.Jit (radiance, transmittance) arrays instead of an Image, for differentiation.
        supersample : int, default 1
            n >= 1: each pixel the mean over n x n stratified points of its footprint, as the path-traced
            reference's box-filtered pixels are (supersample.py; n^2 times the eye pass's work); 1: the
            pixel centres.

        Returns
        -------
        Image or tuple
            An Image of radiance (W/m^2/sr, RGB) with the frame's metadata; or, with ``return_arrays``,
            the Dr.Jit (radiance, transmittance).
        """
        if supersample != 1:
            return self._supersampled(spec, params, return_arrays, supersample)
        mi = self.mi
        import drjit as dr
        t_start = time.perf_counter()
        scale, omega, tint, fwd = self._species_vectors(params)
        detail = self._detail_amplitudes(params) if self.detail_noise is not None else None
        key = _texture_key(scale, omega, fwd, detail)
        rebuilt = key is None or key != self._texture_key  # a sun or camera move keeps the textures
        self._texture_key = key
        forward, to_sun = np.asarray(spec.camera.forward, float), np.asarray(spec.sun.to_sun, float)
        # the host's waits on kernels first (the sky's irradiance and emitter, the view's sky on the rays that
        # see it), with little queued before them: the frame's other kernels run while Python builds the rest
        sky_irradiance_horizontal(spec, cache=self.views.sky)
        self.views.get(mi, spec)
        g = self._reuse("geometry", (tuple(forward), tuple(to_sun), self.slices),
                        lambda: slice_geometry(forward, to_sun, self.box, self.slices))
        omega_bar = self.mean_albedo(scale, omega) if self.uniform_forward or self.one_scattering_ratio else None
        keep = 1.0 - kernel_scalar(mi, fwd[0]) * omega_bar if self.uniform_forward else None  # f may carry gradients
        inputs = self._frame_inputs(g, spec, params, tint, rebuilt, keep, omega_bar)
        if rebuilt:  # built by the frame's kernels, from opaque values
            inputs.build = TextureBuild(*([kernel_scalar(mi, v) for v in x] for x in (scale, omega, fwd, detail or [])))
        self._constants.check(self)
        if return_arrays or self.differentiable or not self.frozen:
            out, transmittance, store, sky_store = self._constants._kernels(
                inputs, None if return_arrays else self._light_done)
            if return_arrays:
                return out, transmittance
        else:  # the recorded kernels (re-recorded when the structure of the inputs changes)
            result = without_gc(self._frozen_kernels, inputs)
            if result is None:  # the kernels raised while being recorded: drop the recording, raise here
                self._frozen_kernels.clear()
                raise_recording_error(self)
            out, transmittance, store, sky_store = result
        self.light.bind(inputs.sun, store)  # the arrays outside the recording
        if self.sky_light is not None:
            self.sky_light.store, self.sky_light.frame = sky_store, inputs.sky_frame
        t_launch = time.perf_counter()
        dr.eval(out, transmittance)
        dr.sync_thread()
        t_eye = time.perf_counter()
        H, W = spec.height, spec.width
        rgb = np.asarray(dr.ravel(out), dtype=np.float32).reshape(H, W, 3)  # interleaved by Dr.Jit: no transpose
        self.transmittance = np.asarray(transmittance, dtype=np.float32).reshape(H, W)
        self.timing = {"light_s": self._t_light - t_start if self._t_light else float("nan"),
                       "eye_s": t_eye - self._t_light if self._t_light else float("nan"),
                       "launch_s": t_launch - t_start, "total_s": t_eye - t_start}
        self._t_light = None
        plain = lambda v: None if dr.is_array_v(v) else v  # noqa: E731
        meta = {"renderer": "slicing", "mode": self.mode.__dict__, "slices": self.slices,
                "light_res": self.light_res, "forward_peak_deg": self.forward_peak_deg,
                "params": {k: plain(v) for k, v in params.__dict__.items()},
                "seconds": t_eye - t_start, "back_to_front": g.back_to_front,
                "scene": self._reuse("scene", spec, spec.to_dict),
                "species_preset": self.vol.attrs.get("species_preset"), "source": self.vol.attrs.get("source"),
                "forward_fraction_per_species": [None if dr.is_array_v(v) else float(v) for v in fwd]}
        return Image(rgb, np.zeros_like(rgb), meta)

    def _supersampled(self, spec: SceneSpec, params: SliceParams, return_arrays: bool, n):
        """``frame`` with each pixel averaged over n x n stratified points (supersample.py)."""
        import drjit as dr
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ValueError(f"supersample must be an integer >= 1, got {n!r}")
        fine = fine_spec(spec, int(n))
        if return_arrays:
            return tuple(block_mean_jit(dr, self.mi.UInt32, v, spec.width, spec.height, int(n))
                         for v in self.frame(fine, params, return_arrays=True))
        img = self.frame(fine, params)
        self.transmittance = block_mean(self.transmittance, int(n))
        rgb = block_mean(img.radiance, int(n)).astype(np.float32)
        return Image(rgb, np.zeros_like(rgb), dict(img.metadata, supersample=int(n), scene=spec.to_dict()))

    def _frame_inputs(self, g, spec: SceneSpec, params: SliceParams, tint, rebuilt: bool, keep=None,
                      omega_bar=None) -> FrameInputs:
        """Everything the frame's kernels read but the renderer's constants (``FrameInputs``, a Dr.Jit
        PyTree: arrays, opaque scalars, textures; the plain ints and flags in it set the kernels' structure):
        the light passes' plans, the eye pass's per-pixel and per-frame values (``build`` unset). ``keep``:
        (beta - beta_f) / beta where the light source is beta alone; ``omega_bar``: ``mean_albedo`` where the
        eye's texture is beta alone."""
        mi = self.mi
        translucent = self.mode.light == "translucent"
        blur = params.blur_length_m if params.blur_length_m is not None else self.voxel_m
        # offset light planes too (only when asked for: aligned planes keep the default frame as it was)
        jitter = None if _number(params.slab_jitter) == 0.0 else \
            (kernel_scalar(mi, params.slab_jitter), kernel_scalar(mi, jitter_rotation(params.jitter_frame)))
        sun = self.light.plan(g, self.grid_box, translucent,
                              variance_per_metre(params.cone_angle_deg, blur, mi) if translucent else None,
                              variance_per_metre(REFERENCE_CONE_DEG, _number(blur)) if translucent else None, jitter,
                              keep=keep)
        sky, sky_store, sky_frame = None, None, None
        if self.sky_light is not None:
            if rebuilt:  # the zenith sweep depends on the extinction only
                sky = self.sky_light.plan(self._sky_geometry, self.grid_box, False)
                sky_frame = sky.frame
            else:
                sky_store, sky_frame = self.sky_light.store, self.sky_light.frame
        return FrameInputs(self.beta_s, self.detail_noise, self.tex_eye, self.tex_light_src, None, sun, sky,
                           sky_store, sky_frame,
                           self._eye_inputs(spec, params, tint, omega_bar if self.one_scattering_ratio else None))

    def _kernels(self, inputs: FrameInputs, light_done=None):
        """The frame's kernels from ``_frame_inputs``: (radiance, transmittance, sun store, zenith store).
        Runs with ``self`` the renderer's ``KernelConstants`` (``dr.freeze`` records it): reads nothing but
        ``inputs`` and the renderer's declared constants. ``light_done``: None, or called once the light
        passes have run (a traced frame's timing)."""
        import drjit as dr
        for volume in (self.light, self.sky_light):  # their lookups read this frame's light alone
            if volume is not None:
                volume.unbind()
        if inputs.build is not None:
            self._build_textures(inputs.build, inputs)
        store = self.light.run(inputs.sun, inputs.tex_light)
        sky_store = inputs.sky_store
        if inputs.sky is not None:
            sky_store = self.sky_light.run(inputs.sky, inputs.tex_light)
        self.light.bind(inputs.sun, store)
        if self.sky_light is not None:
            self.sky_light.store, self.sky_light.frame = sky_store, inputs.sky_frame
            self.sky_light.n_slices = self._sky_geometry.n_slices
        if light_done is not None:
            dr.sync_thread()  # kernels run asynchronously: wait before reading the clock
            light_done()
        out, transmittance = self._eye_pass(inputs)
        return out, transmittance, store, sky_store

    def _light_done(self):
        self._t_light = time.perf_counter()

    def _eye_inputs(self, spec: SceneSpec, params: SliceParams, tint, sca_ratio=None) -> EyeInputs:
        """The eye pass's inputs (see ``_frame_inputs``); ``sca_ratio``: beta_sca / beta where the eye's
        texture is beta alone."""
        mi = self.mi
        import drjit as dr
        rays = self.views.get(mi, spec)
        sun = np.asarray(spec.sun.irradiance, dtype=np.float64)
        phase_colour, colours, new, indices = [], [], [], {}
        for gi, members in enumerate(self.groups):
            colour = self.colors[members[0]] if self.mode.species_colors else np.mean(tint[members], axis=0)
            key = (gi, tuple(colour * sun))  # per view (and sun): a slider move reuses the uploaded array
            if key not in rays.phase_colour:  # P(Theta) colour E_sun, in kernels (rays.py: numpy's floats)
                table = self.tables[members[0]]  # (its arrays uploaded once: kept while it is the group's table)
                arrays = self._reuse(f"phase {gi}", table, lambda: phase_table(mi, table))
                angles = np.asarray(table.theta).tobytes()  # tables with the same angles: one search
                index = indices[angles] = indices.get(angles) or phase_index(mi, arrays[0], rays.theta)
                p = phase_values(mi, arrays, rays.theta, index)
                k = Scalars(mi, k=colour * sun)
                rays.phase_colour[key] = mi.Color3f(*(f32(mi, p[c] * k[f"k{c}"]) for c in range(3)))
                new.append(rays.phase_colour[key])
            phase_colour.append(rays.phase_colour[key])
            colours.append(tuple(colour * sun / (4 * np.pi)))
        dr.eval(*new)  # (one kernel, the searches shared)
        diffuse_colour = self._reuse("diffuse", tuple(colours), lambda: [_colour(mi, c) for c in colours])
        e_sky = sky_irradiance_horizontal(spec, cache=self.views.sky)
        model = None
        if self.mode.light == "multiple":
            model = MultipleLight(*(kernel_scalar(mi, v) for v in (
                params.ms_extinction, params.ms_contribution, params.ms_eccentricity, params.sky_extinction,
                params.diffusion_gain, params.diffusion_scale, max(float(spec.sun.to_sun[2]), 1e-3), params.leak_gain,
                params.leak_rate, params.diffusion_flux, params.below_shadow, params.diffusion_lobe,
                self.grid_box[0][2] if spec.ground is None else spec.ground.height)),
                incidence=_optional_scalar(mi, params.diffusion_incidence))
            gain = params.sky_gain
        else:
            gain = params.ambient
        ground, below = None, None
        if spec.ground is not None:  # over a terrain the rays carry its albedo and slope (ViewRays.ground_sun/_sky)
            from_sun, from_sky = ground_radiance(spec, e_sky, None if rays.ground_sun is None else np.ones(3))
            ground = (_colour(mi, from_sun), _colour(mi, from_sky))
            if model is not None and self.sky_light is not None:  # "multiple": it lights the medium from below
                sun_g, sky_g = ground_radiance(spec, e_sky)  # the ground's sun after the air above it (sun_air.py)
                sun_g = sun_g * self._reuse("sun at ground", (spec.atmosphere, float(spec.sun.mu0), spec.ground.height),
                                            lambda: sun_at_height(spec, spec.ground.height))
                below = _colour(mi, sun_g + sky_g) * kernel_scalar(mi, gain)
        names = ("origin", "direction", "t0", "t1", "hit_ground", "ground", "background", "pattern", "span_a",
                 "span_b", "n", "ground_sun", "ground_sky")
        return EyeInputs(EyeRays(**{k: getattr(rays, k) for k in names}), self._grid_scalars, phase_colour,
                         diffuse_colour, model, _colour(mi, e_sky / np.pi) * kernel_scalar(mi, gain), ground,
                         kernel_scalar(mi, params.slab_jitter), kernel_scalar(mi, jitter_rotation(params.jitter_frame)),
                         sca_ratio, below, self._reuse("sun air", (spec.atmosphere, float(spec.sun.mu0)),
                                                       lambda: sun_air_input(mi, spec, self.grid_box, self._reuse)),
                         None if not self._eye_air else eye_air_input(mi, spec, self.vol.bbox, self._reuse,
                                                                      not self.vol.periodic))

    def _eye_pass(self, inputs: FrameInputs):
        import drjit as dr
        mi, e, m = self.mi, inputs.eye, inputs.eye.model
        if m is not None:
            model = LightModel(self.light, self.sky_light, self.mode.octaves, m.a, m.b, m.c, m.sky_extinction,
                               m.diffusion_gain, m.diffusion_scale, g=self.g_scattering, mu0=m.mu0,
                               carry=(inputs.tex_light, e.grid), leak_gain=m.leak_gain, leak_rate=m.leak_rate,
                               below=e.below is not None, flux=m.flux, below_shadow=m.below_shadow,
                               diffusion_lobe=m.diffusion_lobe, ground_z=m.ground_z, diffusion_incidence=m.incidence)
        else:
            model = LightModel(self.light, log_forward=self.mode.light == "translucent")
        offset = slab_offsets(dr, e.rays.pattern, e.jitter, e.jitter_rotation)
        out = composite(mi, self.light.frame, self.light.n_slices, e.rays, inputs.tex_eye, self.grid_box,
                        e.phase_colour, e.diffuse_colour, model, e.ambient, e.ground, self.differentiable, offset,
                        e.sca_ratio, e.below, self.tile_box, None if self.differentiable else inputs.tex_light,
                        as_sun_air(mi, e.sun_air), depth=e.eye_air is not None)
        if e.eye_air is None:
            return out
        shadow = light_shadow(mi, self.light, e.eye_air.to_sun)  # the storm's shadow on the air
        through = seen_through_coarse_air if applies(e.eye_air, e.rays.n) else seen_through_air
        return through(mi, e.eye_air, e.rays, *out, shadow=shadow), out[1]  # the air in and out of the box


FROZEN_FRAMES = True
def _optional_scalar(mi, value):
    """None for a plain 0 (the term left out of the kernel: it compiles once when first made nonzero), else
    the opaque kernel scalar."""
    return None if isinstance(value, (int, float)) and value == 0 else kernel_scalar(mi, value)


def ground_radiance(spec: SceneSpec, e_sky, albedo=None) -> tuple[np.ndarray, np.ndarray]:
    """RGB radiance (W/m^2/sr) of ``spec``'s Lambertian ground in the open, from the sun and from the sky:
    rho / pi E_sun mu0 and rho / pi E_sky, E_sky the sky's irradiance on a horizontal plane
    (``sky_irradiance_horizontal``); rho the ground's albedo, or ``albedo``."""
    rho = np.asarray(spec.ground.albedo if albedo is None else albedo, dtype=np.float64)
    sun = np.asarray(spec.sun.irradiance, dtype=np.float64) * max(float(spec.sun.to_sun[2]), 0.0)
    return rho / np.pi * sun, rho / np.pi * np.asarray(e_sky, dtype=np.float64)


def _species_albedo_and_colour(vol) -> tuple[np.ndarray, np.ndarray]:
    """(S, 3) single-scattering albedo and Table III display colour per species; a volume without a
    species set: its mean albedo over the medium for all, white."""
    sp, S = vol.species_set, len(vol.species)
    if sp is not None:
        return np.array([sp[n].albedo_rgb for n in vol.species]), np.array([sp[n].color_rgb for n in vol.species])
    mean_alb = vol.albedo.reshape(-1, 3)[vol.beta_total.ravel() > 0].mean(axis=0) \
        if np.any(vol.beta_total > 0) else np.ones(3)
    return np.broadcast_to(mean_alb, (S, 3)).copy(), np.ones((S, 3))


# a "uniform" medium's textures hold beta alone (beta_sca = omega_bar beta, beta_f = f omega_bar beta) where
# the species' albedos agree within this; otherwise beta_sca and beta_f per voxel
UNIFORM_ALBEDO_SPREAD = 1e-3


def _albedos_agree(albedo_rgb) -> bool:
    """Whether the species' (mean) albedos agree within UNIFORM_ALBEDO_SPREAD."""
    omega = np.asarray(albedo_rgb, dtype=np.float64).mean(axis=1)
    return float(omega.max() - omega.min()) <= UNIFORM_ALBEDO_SPREAD


def _number(value) -> float:
    import drjit as dr
    return float(dr.detach(value)[0]) if dr.is_array_v(value) else float(value)


def _colour(mi, rgb):
    """An RGB constant for a kernel, as opaque values (a new value recompiles nothing)."""
    import drjit as dr
    return mi.Color3f(*(dr.opaque(mi.Float, float(v)) for v in rgb))


def _scatter_groups(tables, colours) -> list[list[int]]:
    """Species that scatter alike into the eye (the same phase table, by content, and the same colour)
    share one channel of the eye texture."""
    groups: list[list[int]] = []
    for si, (t, c) in enumerate(zip(tables, colours)):
        for members in groups:
            t0, c0 = tables[members[0]], colours[members[0]]
            if (t0 is t or (np.array_equal(t0.theta, t.theta) and np.array_equal(t0.values, t.values))) \
                    and np.allclose(c0, c, atol=5e-4):
                members.append(si)
                break
        else:
            groups.append([si])
    return groups


def _texture_key(scale, omega, fwd, detail):
    """The textures' inputs as a hashable value, or None when any is a Dr.Jit array (a differentiated
    parameter: always rebuilt)."""
    import drjit as dr
    values = [*scale, *omega, *fwd, *(detail or ())]
    if any(dr.is_array_v(v) for v in values):
        return None
    return tuple(float(v) for v in values) + (detail is None,)
