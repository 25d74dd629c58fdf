"""What one frame of the slicer reads, declared: ``FrameInputs`` (everything the frame's kernels read that
may change between frames) and ``KernelConstants`` (the only view of the renderer that the kernels get).

``SliceRenderer.frame`` launches its kernels through ``dr.freeze``: the first call with a given structure
of inputs runs Python and records the kernels; later calls with that structure replay the recording on
the new inputs without running Python. A replay sees new values only where ``dr.freeze`` traverses the
inputs: Dr.Jit arrays and textures inside dataclasses (Dr.Jit 1.5 traverses a dataclass's fields in
declaration order, a ``DRJIT_STRUCT`` class's declared fields), lists, tuples and dicts; the field names
and the plain Python values among them (ints, bools, None) are part of the structure (a new value records
again). Anything else the kernels read is baked into the recording: a Python number or a literal array
read from the renderer would be replayed with its value of the recorded frame, without an error (an
evaluated array that is not an input does make the recording fail). Dr.Jit resolves a dataclass's
annotations when it traverses one: the types named below must be importable here.

So the kernels never see the renderer itself: they run as methods of its ``KernelConstants``, a read-only
view of the attributes named in ``KERNEL_CONSTANTS`` (fixed for the renderer's life). Reading any other
attribute raises ``FrameInputError`` (traced and recorded frames alike: the first frame of any test that
renders fails), as does writing one; ``check`` (every frame, before the kernels) raises when a declared
constant no longer is the renderer's, so that a per-frame value cannot be declared a constant either.
"""
from __future__ import annotations

import inspect
import types
from dataclasses import dataclass

import numpy as np

from .light import LookupFrame, SweepPlan
from .eye_air import EyeAir
from .sun_air import SunAir


@dataclass
class TextureBuild:
    """The per-species values the textures are built from (``SliceRenderer._build_textures``), opaque
    Dr.Jit scalars (or Floats with gradients) in the volume's species order."""

    scale: list   # extinction scaling per species (x the part delta-M keeps: 1 - omega f), unitless
    omega: list   # mean single-scattering albedo per species (after delta-M), unitless
    fwd: list     # forward fraction per species (translucent light; else 0), unitless
    detail: list  # detail amplitude a_s per species (extinction x exp(a_s n - a_s^2 / 2)); [] without noise


@dataclass
class EyeRays:
    """The pixel rays of the frame's view (``view.ViewRays`` less its numpy parts), N = width x height."""

    origin: object      # mi.Point3f (N): the camera's position (m)
    direction: object   # mi.Vector3f (N): unit ray directions
    t0: object          # mi.Float (N): where each ray enters the slicing box (m along the ray)
    t1: object          # mi.Float (N): where it leaves it, clipped by the ground (m; t0 > t1: a miss)
    hit_ground: object  # mi.Bool (N): the ray ends on the ground
    ground: object      # mi.Point3f (N): where it meets the ground (m)
    background: object  # mi.Color3f (N): the sky's radiance along the ray (W/m^2/sr; 0 on the ground)
    pattern: object     # mi.Float (N): the pixel's slab-offset pattern in [0, 1) (jitter.py)
    span_a: object      # mi.Float (N) or None: where the ray's occupied span begins (m, occupancy.py)
    span_b: object      # mi.Float (N) or None: and ends (m)
    n: int              # N, the ray count (part of the structure)
    ground_sun: object = None  # mi.Float (N) over a terrain (Color3f: per channel): albedo max(n . s, 0) / mu0; else None
    ground_sky: object = None  # mi.Float (N) (Color3f) over a terrain: albedo x (1 + n_z) / 2; else None


@dataclass
class MultipleLight:
    """The "multiple" light model's parameters (``eye.LightModel``), opaque Dr.Jit scalars."""

    a: object               # octaves' optical-depth factor (SliceParams.ms_extinction), unitless
    b: object               # octaves' weight factor (ms_contribution), unitless
    c: object               # octaves' phase eccentricity factor (ms_eccentricity), unitless
    sky_extinction: object  # diffuse light's optical-depth factor k (sky_extinction), unitless
    diffusion_gain: object  # weight of the diffusion profile (diffusion_gain), unitless
    diffusion_scale: object # transport depth per optical depth (diffusion_scale, ~1 - g), unitless
    mu0: object             # the sun's zenith cosine (>= 1e-3)
    leak_gain: object       # weight of the leaking diffusion (leak_gain), unitless
    leak_rate: object       # its decay per transport depth (leak_rate), unitless
    flux: object            # weight of the diffused light's flux towards the eye (diffusion_flux), unitless
    below_shadow: object    # how much of the ground's shadow dims the light from below (below_shadow), unitless
    diffusion_lobe: object  # the diffused light's part scattered with the phase function (diffusion_lobe), unitless
    ground_z: object        # the flat ground's height (m; the lowest box face without a ground)
    incidence: object = None  # weight of the lit face's slope on the diffused light (diffusion_incidence); None: 0


@dataclass
class EyeInputs:
    """The eye pass's per-frame inputs (``SliceRenderer._eye_pass``)."""

    rays: EyeRays          # the view's pixel rays
    grid: tuple            # (lo corner (m), 1 / span (1/m)) of the grid, mi.Point3f and mi.Vector3f (constant)
    phase_colour: list     # per scattering group: P_g(Theta) colour_g E_sun per pixel, mi.Color3f (N), W/m^2/sr
    diffuse_colour: list   # per scattering group: colour_g E_sun / (4 pi), mi.Color3f, W/m^2/sr
    model: MultipleLight | None  # the "multiple" model's parameters; None for the paper's modes
    ambient: object        # L_amb: the sky's mean radiance x ambient (or sky_gain), mi.Color3f, W/m^2/sr
    ground: tuple | None   # None, or (rho E_sun mu0 / pi, rho E_sky / pi), mi.Color3f each, W/m^2/sr (terrain: rho = 1)
    jitter: object         # slab-offset amplitude (SliceParams.slab_jitter), slice units, opaque Float
    jitter_rotation: object  # slab-offset rotation of the frame index (jitter.py), opaque Float
    sca_ratio: object      # None, or beta_sca / beta where the eye's texture holds beta alone (opaque Float)
    below: object          # None, or the lit ground's radiance x sky_gain lighting the medium from below, mi.Color3f
    sun_air: SunAir | None = None  # None, or the sun's colour per height after the air (spec.atmosphere, sun_air.py; or
    # a new sun's sun_air_table.SunAirSource, its table computed in the frame's kernels)
    eye_air: EyeAir | None = None  # None, or the air along the eye rays, in and outside the box (eye_air.py)


@dataclass
class FrameInputs:
    """Everything the frame's kernels (``SliceRenderer._kernels``) read that is not a constant of the
    renderer (``KERNEL_CONSTANTS``): a Dr.Jit PyTree, what ``dr.freeze`` replays with new values."""

    beta_s: list           # per species: extinction at scaling 1 (1/m), (z, y, x) flattened, mi.Float (constant data)
    noise: object          # None, or the unit-variance detail noise n, (z, y, x) flattened, mi.Float
    tex_eye: object        # the eye's texture (texture_storage.ChannelTextures (z, y, x, C)): beta_sca per group,
    #                        after beta where differentiated (none: one group whose beta_sca is omega_bar beta), 1/m
    tex_light: object      # the light pass's source (z, y, x, 1 or 2): beta (, beta_f), 1/m
    build: TextureBuild | None  # the frame rebuilds both textures from these; None: they are the last frame's
    sun: SweepPlan         # the sun's light pass (rays, slab path, blur, the store's LookupFrame)
    sky: SweepPlan | None  # the zenith light pass ("multiple" model, frames that rebuild the textures); else None
    sky_store: object      # where sky is None: the zenith light volume kept from an earlier frame, mi.Float
    sky_frame: LookupFrame | None  # the zenith light volume's geometry; None without one
    eye: EyeInputs         # the eye pass's inputs


class FrameInputError(RuntimeError):
    """The frame's kernels read (or write) the renderer outside its declared constants, or a declared
    constant changed: a value that changes between frames must enter through ``FrameInputs``. (Not an
    AttributeError: ``getattr(..., default)`` and ``hasattr`` must not swallow it.)"""


# the renderer's attributes that its frame's kernels may read, fixed for its life (see the module docstring)
KERNEL_CONSTANTS = (
    "mi",                    # the mitsuba module (the renderer's variant)
    "differentiable",        # the frame is built for reverse-mode AD
    "n_species",             # number of species
    "shape",                 # the grid's (z, y, x)
    "groups",                # species that scatter alike (lists of species indices): the eye texture's groups
    "one_scattering_ratio",  # the eye's texture holds beta alone (beta_sca = omega_bar beta)
    "light_channels",        # channels of the light pass's source: 1 (beta) or 2 (beta, beta_f)
    "grid_box",              # the grid's (lo, hi) world corners (m), numpy
    "tile_box",              # None, or periodic "transport": the texture coordinates (lo, hi) of the eye's x and y
    "g_scattering",          # the cloud's asymmetry parameter (the ground's transmission, "multiple")
    "mode",                  # SliceMode (frozen): phase functions, light model, octaves, colouring
    "light",                 # the sun's LightVolume (kernels bind its store and frame from the inputs)
    "sky_light",             # the zenith LightVolume, or None (likewise)
    "_sky_geometry",         # the zenith sweep's SliceGeometry ("multiple" model only)
)


class KernelConstants:
    """The renderer as its frame's kernels see it: the attributes named in ``names`` (default
    ``KERNEL_CONSTANTS``; those it has), taken when it is made, read-only, and its class's methods bound to
    this view (so that they read the renderer through it too). Anything else raises ``FrameInputError``."""

    __slots__ = ("_cls", "_values", "_snapshots")

    def __init__(self, owner, names=None):
        names = KERNEL_CONSTANTS if names is None else names
        values = {n: getattr(owner, n) for n in names if hasattr(owner, n)}
        object.__setattr__(self, "_cls", type(owner))
        object.__setattr__(self, "_values", values)
        object.__setattr__(self, "_snapshots", {n: _snapshot(v) for n, v in values.items()})

    def __getattr__(self, name: str):
        values = object.__getattribute__(self, "_values")
        if name in values:
            return values[name]
        if name.startswith("__"):  # Python's own protocols (copy, pickle, ...)
            raise AttributeError(name)
        method = inspect.getattr_static(self._cls, name, None)
        if isinstance(method, types.FunctionType):
            return types.MethodType(method, self)
        raise FrameInputError(
            f"the frame's kernels read renderer.{name}, which is neither among their inputs nor a declared "
            f"constant: a per-frame value must enter through FrameInputs (a recorded frame would replay "
            f"the value of the frame it was recorded with); a constant is declared in KERNEL_CONSTANTS")

    def __setattr__(self, name: str, value):
        raise FrameInputError(f"the frame's kernels write renderer.{name}: they may only return values")

    def check(self, owner) -> None:
        """Raise ``FrameInputError`` when a declared constant is no longer ``owner``'s (reassigned, or
        plain data changed in place): a per-frame value declared as a constant."""
        for name, snap in self._snapshots.items():
            if _snapshot(getattr(owner, name, _MISSING)) != snap:
                raise FrameInputError(
                    f"renderer.{name} changed since the renderer was made, but its frame's kernels read it as "
                    f"a constant (KERNEL_CONSTANTS): a value that changes between frames must enter through "
                    f"FrameInputs")


_MISSING = object()


def _snapshot(value):
    """A comparable record of ``value``: plain data (numbers, strings, numpy arrays, and tuples, lists
    and dicts of them) by content, any other object by identity."""
    if value is None or isinstance(value, (bool, int, float, str, np.generic)):
        return (type(value), value)
    if isinstance(value, np.ndarray):
        return (np.ndarray, value.shape, value.dtype.str, value.tobytes())
    if isinstance(value, (tuple, list)):
        return (type(value), tuple(_snapshot(v) for v in value))
    if isinstance(value, dict):
        return (dict, tuple((k, _snapshot(v)) for k, v in value.items()))
    return ("id", id(value))
