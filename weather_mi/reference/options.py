"""The estimator options of the reference renderer, declared once: ``ReferenceOptions``.

Each field is declared (``option``) with its default, its documentation (units), its check and where it
goes: its flag on the command line (``Flag``), whether the kernel takes it (the keyword of the same name
of ``kernel.scene_dict.integrator_dict``), what enters the checkpoint fingerprint (its resolved value, unless
a reason says otherwise) and when the estimator uses it (the image metadata records None otherwise).
Derived from the declarations:

- ``render_reference``'s estimator keywords, its signature and their docstring (``takes_options``), and
  ``options=ReferenceOptions(...)`` (``ReferenceOptions.of_call``);
- the resolved options of a render (``resolved``: the defaults that depend on other options or on the
  scene, then the checks), which ``passes.PassOptions`` carries to the passes;
- the kernel's keywords (``kernel_options``), the fingerprint's items (``key_items``) and the metadata
  (``metadata``);
- the flags of ``weather-mi render`` and ``satellite`` (``add_flags``, ``flag_values``).

Adding an estimator option is one field below (and its use in the kernel). The arguments of a call that
are not the estimator's (checkpoint, resume, progress, client, worker_variant, on_pass, variant) stay
``render_reference``'s own parameters.
"""
from __future__ import annotations

import dataclasses
import inspect
import textwrap
import typing
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..optics.forward_peak import DEFAULT_CONE_DEG, check_cone_deg
from .passes import DEFAULT_AUREOLE_NEE, DEFAULT_MVNEE, DEFAULT_SUN_GUIDING, plan_passes

INTEGRATORS = ("majorant", "volpath")
NORMALIZE = (None, "reflectance")
TARGET_PIXELS = ("cloud", "all")  # the pixels a render to a target adds passes over
VALUE = "value"  # ``key``: the resolved value enters the checkpoint fingerprint


@dataclass(frozen=True)
class Flag:
    """A field's flag on the command line: its name, help and metavar, and the commands' default where it
    differs from the renderer's (None: the field's). Its type comes from the field (its choices; a
    bool: a switch) and its destination is the field's name."""

    name: str
    help: str | None = None
    metavar: str | None = None
    default: Any = None


@dataclass(frozen=True)
class Declared:
    """What a field of ``ReferenceOptions`` declares besides its default (``option``).

    doc        : its documentation (render_reference's docstring and the class's), with units.
    choices    : the values it takes (None: any the check accepts).
    none_means : (options so far, spec) -> the value a None stands for (None: None stays).
    check      : (value, options so far, spec) -> the value used (converted), or ValueError naming it.
                 ``none_means`` and ``check`` see the fields declared before this one resolved.
    flag       : its flag on the command line (None: none).
    kernel     : ``integrator_dict`` takes it (a keyword of the same name).
    key        : what enters the checkpoint fingerprint: VALUE (its resolved value), None (nothing) or a
                 function of the value; anything but VALUE needs ``key_reason``.
    key_reason : why the value does not enter the fingerprint as it is.
    applies    : options -> whether the estimator uses it (None: always); the metadata records None
                 where it does not.
    positional : ``render_reference`` takes it by position too (after spec and vol, in order).
    """

    doc: str
    choices: tuple | None = None
    none_means: Callable | None = None
    check: Callable | None = None
    flag: Flag | None = None
    kernel: bool = False
    key: Any = VALUE
    key_reason: str = ""
    applies: Callable | None = None
    positional: bool = False


def option(default, doc: str, **declared):
    """A field of ``ReferenceOptions``: its default and its declaration (``Declared``'s fields)."""
    return field(default=default, metadata={"declared": Declared(textwrap.dedent(doc).strip(), **declared)})


# ------------------------------------------------------------------------------------------ checks

def _positive_int(name):
    def check(v, o, spec):
        if not isinstance(v, (int, np.integer)) or v < 1:
            raise ValueError(f"{name} must be a positive integer, got {v!r}")
        return int(v)
    return check


def _point_sun(spec, what: str) -> None:
    if spec.sun.angular_diameter_deg > 0:
        raise ValueError(f"{what} renders the sun as a point (Mitsuba's 'directional' emitter): give "
                         f"Sun(..., angular_diameter_deg=0), or use integrator='majorant' for a sun disk "
                         f"of {spec.sun.angular_diameter_deg} deg")


def _integrator(v, o, spec):
    if v not in INTEGRATORS:
        raise ValueError(f"integrator must be one of {INTEGRATORS}, got {v!r}")
    if v == "volpath":
        _point_sun(spec, "integrator='volpath'")
    return v


def _legacy(v, o, spec):
    if v:
        _point_sun(spec, "legacy=True")
    return v


def _normalize(v, o, spec):
    if v not in NORMALIZE:
        raise ValueError(f"normalize must be None or 'reflectance', got {v!r}")
    if v == "reflectance" and min(spec.sun.irradiance) <= 0:
        raise ValueError(f"normalize='reflectance' divides by the sun's irradiance: every channel must be > 0, "
                         f"got {spec.sun.irradiance}")
    return v


def _target_rse(v, o, spec):
    if v is not None and not (isinstance(v, (int, float)) and 0 < v < 1):
        raise ValueError(f"target_rse must be a relative standard error in (0, 1), got {v!r}")
    return v


def _target_pixels(v, o, spec):
    if v not in TARGET_PIXELS:
        raise ValueError(f"target_pixels must be one of {TARGET_PIXELS}, got {v!r}")
    return v


def _max_seconds(v, o, spec):
    if v is not None and not (isinstance(v, (int, float)) and v > 0):
        raise ValueError(f"max_seconds must be a positive number of seconds, got {v!r}")
    return v


def _sun_guiding(v, o, spec):
    if not (isinstance(v, (int, float)) and 0.0 <= v < 1.0):
        raise ValueError(f"sun_guiding must be a probability in [0, 1), got {v!r}")
    return v


def _mvnee(v, o, spec):
    v = float(v)
    if not 0.0 <= v <= 1.0:
        raise ValueError(f"mvnee must be a probability in [0, 1], got {v}")
    if v > 0 and (o.integrator != "majorant" or o.legacy or o.sun_guiding or o.aureole_nee):
        raise ValueError("mvnee needs integrator='majorant' (not legacy), no sun guiding and no aureole estimator")
    return v


def _own_sun(o) -> bool:
    return o.own_sun


# ------------------------------------------------------------------------------------------ the options

@dataclass(frozen=True)
class ReferenceOptions:
    """The estimator options of a ``render_reference`` call (``None``: the renderer's default, which may
    depend on other options; ``resolved`` fills it in and checks every field).

    Attributes
    ----------
    <ReferenceOptions fields>
    """

    spp: int = option(256, """
        Samples per pixel in total, split into passes (``passes``, default ``passes.MIN_PASSES`` = 16
        batches when spp >= 16). With ``target_rse``: the samples of the first estimate; passes of the
        same size are then added until the target is met.""",
        positional=True, check=_positive_int("spp"),
        # 64: the README demo's denoised PNG at RMS relative error 0.050 over cloud pixels (48: 0.053) in 42 s
        flag=Flag("--spp", "samples per pixel (with --target-rse: of the first estimate)", default=64))
    max_depth: int = option(-1, "Longest path in scattering events (-1: unbounded).",
                            positional=True, check=lambda v, o, spec: int(v), kernel=True)
    integrator: str = option("majorant", """
        "majorant" (delta tracking over a coarse majorant grid; default) or "volpath" (Mitsuba's own,
        one global majorant: the reference's reference; point sun only).""",
        choices=INTEGRATORS, check=_integrator, kernel=True, flag=Flag("--integrator"))
    legacy: bool = option(False, """
        The estimator before issue 10, for benchmarks: the sun one of the scene's emitters (point sun
        only), Russian roulette as Mitsuba's volpath, phase sampling by channel mean.""",
        check=_legacy, kernel=True)
    passes: int | None = option(None, """
        Number of passes (batches) the ``spp`` samples are split into (resolved: the planned passes,
        ``passes.plan_passes``).""",
        check=lambda v, o, spec: len(plan_passes(spec, o.spp, v)))
    normalize: str | None = option(None, """
        None (radiance, W/m^2/sr) or "reflectance" (pi L / (mu0 E) per channel).""",
        choices=NORMALIZE, check=_normalize)
    rr_depth: int | None = option(None, """
        Depth at which Russian roulette starts (None: the integrators' default, 5).""", kernel=True)
    cell: int | None = option(None, """
        Fine voxels per coarse cell of the majorant grid ("majorant" only; None: the default).""",
        kernel=True, applies=lambda o: o.integrator == "majorant", key=None,
        key_reason="speed only: another majorant grid draws other random numbers for the same estimate, "
                   "so passes with either merge into one")
    target_rse: float | None = option(None, """
        Keep adding passes until the mean relative standard error over cloud pixels (eye-ray
        transmittance < 1/2) is at most this, or ``max_seconds`` of rendering have passed. The added
        passes render the cloud pixels only (with persistent lanes; ``mi.render`` renders every pixel
        and the others' values are dropped): the other pixels keep the planned passes (metadata
        ``spp_background``). On the side-lit supercell at 256 x 256 its 6% of cloud pixels take 60% of
        a full pass's time.""",
        check=_target_rse, key=lambda v: v is not None,
        key_reason="the target says when a render stops, not what its passes are: a render resumes towards "
                   "another target; whether the passes past the planned ones cover the cloud pixels only enters",
        flag=Flag("--target-rse", "add passes until the mean relative standard error over cloud pixels is this"))
    max_seconds: float | None = option(None, """
        With ``target_rse``: the time limit of the rendering, in s.""",
        check=_max_seconds, key=None,
        key_reason="the time limit says when a render stops, not what its passes are: a render resumes with "
                   "another limit",
        flag=Flag("--max-seconds", "with --target-rse: time limit"))
    target_pixels: str = option("cloud", """
        With ``target_rse``: the pixels the passes past the planned ones render: "cloud" (the cloud pixels,
        as above) or "all" (every pixel: the sky and the ground seen through the air in the box, which with
        an atmosphere scatters, converge with the cloud instead of keeping the planned passes' noise; the
        stopping test stays over the cloud pixels).""",
        choices=TARGET_PIXELS, check=_target_pixels, applies=lambda o: o.target_rse is not None,
        flag=Flag("--target-pixels", "with --target-rse: the pixels the added passes render (all: the sky and "
                                     "ground too, where the air makes them noisy)"))
    sun_guiding: float | None = option(None, """
        Probability of drawing a scattering direction from the phase function centred on the sun
        ("majorant" only; None: ``passes.DEFAULT_SUN_GUIDING``).""",
        none_means=lambda o, spec: DEFAULT_SUN_GUIDING, check=_sun_guiding, kernel=True, applies=_own_sun,
        flag=Flag("--sun-guiding", "probability of sun-guided scattering directions (default: the renderer's)"))
    forward_peak_deg: float | None = option(None, """
        Scattering by less than this many degrees (the diffraction peaks of rain, snow and graupel)
        counted as unscattered light, delta-M scaling (``weather_mi.optics.forward_peak``; None:
        DEFAULT_CONE_DEG = 3 deg, 0 with ``legacy``; 0: the tables as they are, which reads low at
        practical spp, see ``validation/forward_peak_slabs.py``).""",
        none_means=lambda o, spec: 0.0 if o.legacy else DEFAULT_CONE_DEG, check=lambda v, o, spec: check_cone_deg(v),
        flag=Flag("--forward-peak", "count scattering by less than DEG degrees (the forward peaks of the phase "
                                    "functions) as unscattered light, delta-M (default: the renderer's, 3; 0: off)",
                  metavar="DEG"))
    aureole_nee: float | None = option(None, """
        Probability of the aureole estimator at a scattering vertex ("majorant" only; sun light through
        one more, forward, scattering sampled about the sun; None: ``passes.DEFAULT_AUREOLE_NEE``, 0
        where sun guiding is asked for: the two are exclusive).""",
        # the two are exclusive: sun guiding given, no aureole estimator
        none_means=lambda o, spec: DEFAULT_AUREOLE_NEE if o.sun_guiding == 0 and not o.legacy else 0.0,
        kernel=True, applies=_own_sun,
        flag=Flag("--aureole-nee", "probability of the aureole estimator (sun light reaching a vertex through one "
                                   "more forward scattering) at each scattering (default: the renderer's, 0: off)",
                  metavar="P"))
    mvnee: float | None = option(None, """
        Probability of a multiple-vertex next-event estimation chain towards the sun at a scattering
        vertex ("majorant" with its own sun; ``weather_mi/kernel/plugins/mvnee.py``; None: ``passes.DEFAULT_MVNEE``, off;
        exclusive with sun guiding and the aureole estimator).""",
        none_means=lambda o, spec: (DEFAULT_MVNEE if not (o.legacy or o.sun_guiding or o.aureole_nee
                                                       or o.integrator != "majorant") else 0.0),
        check=_mvnee, kernel=True, applies=_own_sun)

    @property
    def own_sun(self) -> bool:
        """``majorant_volpath`` samples the sun itself (a disk or a point); False: the sun is a scene emitter."""
        return self.integrator == "majorant" and not self.legacy

    @classmethod
    def of_call(cls, options: ReferenceOptions | None, args: tuple, keywords: dict) -> ReferenceOptions:
        """The options of a call ``render_reference(spec, vol, *args, options=options, **keywords)``: ``options`` (None:
        the defaults) with the positional fields ``args`` and the fields named by ``keywords`` replaced
        (TypeError, as Python's, for another keyword or a field given twice)."""
        positional = [f.name for f, d in DECLARED if d.positional]
        if len(args) > len(positional):
            raise TypeError(f"render_reference() takes at most {len(positional)} positional options "
                            f"({', '.join(positional)}) after spec and vol, {len(args)} were given")
        given = dict(zip(positional, args))
        for name, value in keywords.items():
            if name not in _BY_NAME:
                raise TypeError(f"render_reference() got an unexpected keyword argument {name!r}")
            if name in given:
                raise TypeError(f"render_reference() got multiple values for argument {name!r}")
            given[name] = value
        if options is None:
            return cls(**given)
        if not isinstance(options, cls):
            raise TypeError(f"options must be a ReferenceOptions, got {type(options).__name__}")
        return dataclasses.replace(options, **given)

    def resolved(self, spec) -> ReferenceOptions:
        """These options as a render uses them: field by field in declaration order, a None replaced by its
        default (which may depend on the fields before it and on ``spec``, the SceneSpec), then checked and
        converted (ValueError naming the option)."""
        o = self
        for f, d in DECLARED:
            v = getattr(o, f.name)
            if v is None and d.none_means is not None:
                v = d.none_means(o, spec)
            if d.check is not None:
                v = d.check(v, o, spec)
            o = dataclasses.replace(o, **{f.name: v})
        return o

    def kernel_options(self) -> dict:
        """The keywords of ``integrator_dict`` (the fields declared ``kernel``)."""
        return {f.name: getattr(self, f.name) for f, d in DECLARED if d.kernel}

    def key_items(self) -> dict:
        """What of these (resolved) options enters the checkpoint fingerprint: {field: its value, or what its
        ``key`` makes of it}, every field but those whose declared ``key`` is None (a reason given)."""
        out = {}
        for f, d in DECLARED:
            if d.key is None:
                continue
            v = getattr(self, f.name)
            out[f.name] = v if d.key == VALUE else d.key(v)
        return out

    def metadata(self) -> dict:
        """{field: its value (None where the estimator does not use it)} for the image's metadata."""
        return {f.name: getattr(self, f.name) if d.applies is None or d.applies(self) else None
                for f, d in DECLARED}


# ((dataclasses.Field, Declared), ...) of the fields, in declaration order, and by name; each field's type without
# its None (``int | None``: int), for the flags' types
DECLARED = tuple((f, f.metadata["declared"]) for f in dataclasses.fields(ReferenceOptions))
_BY_NAME = {f.name: (f, d) for f, d in DECLARED}
BASE_TYPES = {name: next(t for t in (typing.get_args(hint) or (hint,)) if t is not type(None))
              for name, hint in typing.get_type_hints(ReferenceOptions).items()}


# ------------------------------------------------------------------------------------------ documentation

def _doc_type(f: dataclasses.Field, d: Declared) -> str:
    if d.choices is not None:
        return "{" + ", ".join("None" if c is None else f'"{c}"' for c in d.choices) + "}"
    parts = [p.strip() for p in str(f.type).split("|")]
    base = " or ".join(p for p in parts if p != "None")
    return base + (", optional" if "None" in parts else "")


def fields_doc(indent: str = "    ") -> str:
    """The numpydoc entries of the fields (``name : type`` and the documentation below it)."""
    out = []
    for f, d in DECLARED:
        out.append(f"{indent}{f.name} : {_doc_type(f, d)}")
        out.append(textwrap.indent(textwrap.fill(" ".join(d.doc.split()), 100 - len(indent) - 4),
                                   indent + "    "))
    return "\n".join(out).lstrip()


MARKER = "<ReferenceOptions fields>"
if ReferenceOptions.__doc__:  # (None under python -OO)
    ReferenceOptions.__doc__ = ReferenceOptions.__doc__.replace(MARKER, fields_doc())


def takes_options(func):
    """``func(spec, vol, *args, ..., **estimator)`` presented with the fields of ``ReferenceOptions`` as its
    parameters: ``*args`` become the positional fields (``spp``, ``max_depth``), ``**estimator`` the others
    (keyword-only), in its signature (``inspect.signature``, ``help``) and in its docstring (the line
    ``<ReferenceOptions fields>`` of its Parameters). ``func`` gets them through ``ReferenceOptions.of_call``."""
    fields = DECLARED
    params = []
    for p in inspect.signature(func).parameters.values():
        if p.kind is p.VAR_POSITIONAL:
            params += [inspect.Parameter(f.name, p.POSITIONAL_OR_KEYWORD, default=f.default, annotation=f.type)
                       for f, d in fields if d.positional]
            params += [inspect.Parameter(f.name, p.KEYWORD_ONLY, default=f.default, annotation=f.type)
                       for f, d in fields if not d.positional]
        elif p.kind is not p.VAR_KEYWORD:
            params.append(p)
    func.__signature__ = inspect.signature(func).replace(parameters=params)
    if func.__doc__:
        func.__doc__ = func.__doc__.replace(MARKER, fields_doc())
    return func


# ------------------------------------------------------------------------------------------ command line

def _flagged(names) -> list:
    if names is None:
        return [(f, d) for f, d in DECLARED if d.flag is not None]
    unknown = [n for n in names if n not in _BY_NAME or _BY_NAME[n][1].flag is None]
    if unknown:
        raise ValueError(f"no flag is declared for {unknown}")
    return [_BY_NAME[n] for n in names]


def add_flags(parser, names=None, defaults: dict | None = None) -> None:
    """The flags of the fields ``names`` (None: every field declaring one) on the argparse ``parser``:
    the flag's name, help and metavar; the field's name as destination, its type (its choices; a bool: a
    switch) and its default (the command's own from ``defaults``, else the flag's, else the field's)."""
    defaults = defaults or {}
    for f, d in _flagged(names):
        fl = d.flag
        kw = {"dest": f.name, "default": defaults.get(f.name, f.default if fl.default is None else fl.default)}
        base = BASE_TYPES[f.name]
        if d.choices is not None:
            kw["choices"] = tuple(c for c in d.choices if c is not None)
        elif base is bool:
            kw["action"] = "store_true"
        elif base is not str:
            kw["type"] = base
        if fl.help is not None:
            kw["help"] = fl.help
        if fl.metavar is not None:
            kw["metavar"] = fl.metavar
        parser.add_argument(fl.name, **kw)


def flag_values(args, names=None) -> dict:
    """{field: value} of the flags ``add_flags(parser, names)`` added, from the parsed ``args``."""
    return {f.name: getattr(args, f.name) for f, _ in _flagged(names)}
