"""The five hydrometeors and their constants (paper Tables II and III, plus particle densities).

Two presets:

* ``"paper"`` reproduces Riley et al. exactly: equivalent radii of Table II (cloud 0.01 mm, ice 1 mm,
  rain 1 mm, snow 2 mm, graupel 2.5 mm), particle densities 1000 / 917 / 1000 / 100 / 400 kg/m^3, the
  two phase-function classes of section 5.2 (water: cloud, rain; ice: ice, snow, graupel) and the
  Table III display colours.
* ``"physical"`` uses radii consistent with WRF bulk microphysics (optics-notes): effective radius
  r_eff = <r^3>/<r^2>, the radius that makes Eq. 4 exact for a size distribution. Cloud 10 um (Thompson
  / Morrison droplets); cloud ice 30 um (WRF effective radii are 10-125 um, typically 20-60 um; the
  paper's 1 mm makes anvils ~30x too transparent); rain, snow and graupel from exponential
  (Marshall-Palmer type) distributions N0 exp(-lambda D) with WSM6 intercepts at typical contents, for
  which r_eff = 1.5 / lambda: rain (N0 = 8e6 m^-4, 1 g/m^3) 0.67 mm -> 0.7 mm; snow (N0 = 2e6, rho 100,
  0.3 g/m^3) 1.25 mm -> 1.2 mm; graupel (N0 = 4e6, rho 500, 1 g/m^3) 0.95 mm -> 1.0 mm.

Single-scattering albedo (RGB at 650 / 550 / 450 nm) follows from weak-absorption geometric optics
(van de Hulst; Bohren & Huffman eq. for k x << 1 << x): Q_abs = 8/3 x k (n^3 - (n^2 - 1)^(3/2)) with
x = 2 pi r / lambda and Q_ext = 2, so omega = 1 - Q_abs / 2. For snow and graupel the absorbing path is
that of solid ice, so the radius is scaled by rho_particle / rho_ice. This gives co-albedos of 1e-7 to
1e-5 for droplets and ~1e-4 for millimetre particles, in line with optics-notes; any visibly lower
albedo is an artistic override (``preset(..., albedo=...)`` or ``with_overrides``).
"""
from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import WeatherDataError
from ..io.hydrometeors import SPECIES_NAMES

RGB_WAVELENGTHS_M = (650e-9, 550e-9, 450e-9)
# refractive indices n - ik at 650 / 550 / 450 nm (optics-notes: Hale & Querry 1973; Warren & Brandt 2008)
WATER_N = (1.331, 1.333, 1.337)
WATER_K = (1.6e-8, 2.0e-9, 1.0e-9)
ICE_N = (1.3080, 1.3110, 1.3157)
ICE_K = (1.4e-8, 2.3e-9, 9e-11)
RHO_WATER = 1000.0
RHO_ICE = 917.0


@dataclass(frozen=True)
class Species:
    """One hydrometeor: equivalent radius (m), particle bulk density (kg/m^3), RGB single-scattering
    albedo, phase-function class ("water" or "ice"), display colour (paper Table III) and scaling."""

    name: str
    radius_m: float
    density_kg_m3: float
    albedo_rgb: tuple[float, float, float]
    phase_class: str
    color_rgb: tuple[float, float, float]
    scale: float = 1.0

    def __post_init__(self):
        src = f"species {self.name!r}"
        if self.name not in SPECIES_NAMES:
            raise WeatherDataError(src, "name", f"one of {', '.join(SPECIES_NAMES)}", repr(self.name))
        if not (self.radius_m > 0 and np.isfinite(self.radius_m)):
            raise WeatherDataError(src, "radius_m", "a positive radius in metres", repr(self.radius_m))
        if not (self.density_kg_m3 > 0 and np.isfinite(self.density_kg_m3)):
            raise WeatherDataError(src, "density_kg_m3", "a positive particle density (kg/m^3)",
                                   repr(self.density_kg_m3))
        alb = tuple(float(a) for a in np.broadcast_to(np.asarray(self.albedo_rgb, float), (3,)))
        if not all(0.0 <= a <= 1.0 for a in alb):
            raise WeatherDataError(src, "albedo_rgb", "three single-scattering albedos in [0, 1]", repr(alb))
        object.__setattr__(self, "albedo_rgb", alb)
        object.__setattr__(self, "color_rgb", tuple(float(c) for c in self.color_rgb))
        if self.phase_class not in ("water", "ice"):
            raise WeatherDataError(src, "phase_class", '"water" or "ice"', repr(self.phase_class))
        if not (self.scale >= 0 and np.isfinite(self.scale)):
            raise WeatherDataError(src, "scale", "a scaling factor >= 0", repr(self.scale))

    def beta_ext_per_m(self, rho_air_kg_m3, q_kg_per_kg, radius_m=None, out=None):
        """Eq. 4: beta = 3 rho_air q / (2 rho_particle R), times the species scaling (1/m). With float32 grids,
        ``out`` (a float32 grid of their shape) receives it in one compiled pass (``mixture_kernels.eq4_grid``,
        the voxel pass's own Eq. 4; a radius grid's values <= 0 are the species' radius)."""
        r = self.radius_m if radius_m is None else radius_m
        if out is None:
            return self.scale * 3.0 * rho_air_kg_m3 * q_kg_per_kg / (2.0 * self.density_kg_m3 * r)
        from .mixture_kernels import eq4_grid
        return eq4_grid(rho_air_kg_m3, q_kg_per_kg, r, self.scale, self.density_kg_m3, self.radius_m, out)


@dataclass(frozen=True)
class SpeciesSet:
    """The five species in the canonical order (cloud, ice, rain, snow, graupel), by name."""

    preset_name: str
    members: tuple[Species, ...] = field(default_factory=tuple)

    def __post_init__(self):
        names = tuple(s.name for s in self.members)
        if names != SPECIES_NAMES:
            raise WeatherDataError(f"species set {self.preset_name!r}", "members",
                                   f"the five species in order {SPECIES_NAMES}", repr(names))

    def __getitem__(self, name: str) -> Species:
        """The species ``name``, or of a size class's component name ("rain#2": rain, ``optics.size_classes``)."""
        name = name.split("#", 1)[0]
        for s in self.members:
            if s.name == name:
                return s
        raise WeatherDataError(f"species set {self.preset_name!r}", name,
                               f"a species name among {', '.join(SPECIES_NAMES)}", repr(name))

    def __iter__(self) -> Iterator[Species]:
        return iter(self.members)

    def __len__(self) -> int:
        return len(self.members)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.members)

    def with_overrides(self, overrides: Mapping[str, Mapping] | None = None, *,
                       scale: Mapping[str, float] | None = None) -> "SpeciesSet":
        """A copy with fields replaced per species (``{"ice": {"radius_m": 30e-6}}``) and scalings set."""
        members = {s.name: s for s in self.members}
        for name, fields in (overrides or {}).items():
            s = self[name]
            unknown = set(fields) - set(Species.__dataclass_fields__) - {"name"}
            if unknown or "name" in fields:
                raise WeatherDataError(f"species override for {name!r}", ", ".join(sorted(unknown)) or "name",
                                       f"fields among {sorted(set(Species.__dataclass_fields__) - {'name'})}")
            members[name] = replace(s, **fields)
        for name, factor in (scale or {}).items():
            members[name] = replace(self[name], scale=float(factor))
        return SpeciesSet(self.preset_name, tuple(members[n] for n in SPECIES_NAMES))


def albedo_weak_absorption(radius_m: float, n_rgb, k_rgb) -> tuple[float, float, float]:
    """omega = 1 - Q_abs/2 with Q_abs = 8/3 x k (n^3 - (n^2-1)^1.5), x = 2 pi r / lambda (k x << 1 << x)."""
    return tuple(float(a) for a in albedo_of_radius(np.float64(radius_m), n_rgb, k_rgb))


def albedo_of_radius(radius_m, n_rgb, k_rgb) -> list:
    """``albedo_weak_absorption`` of a radius or an array of radii (m): the three channels' albedos (float64)."""
    out = []
    for lam, n, k in zip(RGB_WAVELENGTHS_M, n_rgb, k_rgb):
        x = 2.0 * np.pi * radius_m / lam
        q_abs = np.minimum(8.0 / 3.0 * x * k * (n ** 3 - (n * n - 1.0) ** 1.5), 1.0)
        out.append(1.0 - q_abs / 2.0)
    return out


def absorbing_material(phase_class: str, density_kg_m3: float):
    """(radius scale, n_rgb, k_rgb) of ``physical_albedo``: water drops, or ice whose absorbing path is that of
    solid ice (the radius scaled by rho / rho_ice)."""
    if phase_class == "water":
        return None, WATER_N, WATER_K
    return min(density_kg_m3 / RHO_ICE, 1.0), ICE_N, ICE_K


def physical_albedo(phase_class: str, radius_m, density_kg_m3: float) -> list:
    """The weak-absorption albedo (three channels) of particles of ``radius_m`` (a number or an array; m):
    water drops, or ice whose absorbing path is that of solid ice (the radius scaled by rho / rho_ice)."""
    scale, n_rgb, k_rgb = absorbing_material(phase_class, density_kg_m3)
    return albedo_of_radius(radius_m if scale is None else radius_m * scale, n_rgb, k_rgb)


# Table III display colours: cloud red, ice magenta, rain blue, snow yellow, graupel green
TABLE_III_COLORS = {"cloud": (1.0, 0.0, 0.0), "ice": (1.0, 0.0, 1.0), "rain": (0.0, 0.0, 1.0),
                    "snow": (1.0, 1.0, 0.0), "graupel": (0.0, 1.0, 0.0)}
PHASE_CLASS = {"cloud": "water", "rain": "water", "ice": "ice", "snow": "ice", "graupel": "ice"}
_RADII_M = {
    "paper": {"cloud": 0.01e-3, "ice": 1e-3, "rain": 1e-3, "snow": 2e-3, "graupel": 2.5e-3},      # Table II
    "physical": {"cloud": 10e-6, "ice": 30e-6, "rain": 0.7e-3, "snow": 1.2e-3, "graupel": 1.0e-3},
}
_DENSITIES = {
    "paper": {"cloud": 1000.0, "ice": 917.0, "rain": 1000.0, "snow": 100.0, "graupel": 400.0},
    "physical": {"cloud": 1000.0, "ice": 917.0, "rain": 1000.0, "snow": 100.0, "graupel": 500.0},
}


def _make(preset_name: str) -> SpeciesSet:
    members = []
    for name in SPECIES_NAMES:
        r, rho = _RADII_M[preset_name][name], _DENSITIES[preset_name][name]
        albedo = tuple(float(a) for a in physical_albedo(PHASE_CLASS[name], np.float64(r), rho))
        members.append(Species(name, r, rho, albedo, PHASE_CLASS[name], TABLE_III_COLORS[name]))
    return SpeciesSet(preset_name, tuple(members))


PRESETS = ("paper", "physical")


def preset(name: str = "paper", overrides: Mapping[str, Mapping] | None = None, *,
           scale: Mapping[str, float] | None = None, albedo: float | None = None) -> SpeciesSet:
    """The species table of a preset, optionally with per-species field overrides, per-species scalings
    (the paper's interactive "scalings") and one albedo for all.

    Parameters
    ----------
    name : {"paper", "physical"}, default "paper"
        "paper": the radii of the paper's Table II; "physical": typical effective radii.
    overrides : mapping of str to mapping, optional
        Fields replaced per species, e.g. ``{"ice": {"radius_m": 30e-6}}`` (fields of :class:`Species`).
    scale : mapping of str to float, optional
        Scaling factor (>= 0) of each species' extinction, e.g. ``{"snow": 2.0}``.
    albedo : float, optional
        One single-scattering albedo in [0, 1] for every species and channel (``overrides`` win).

    Returns
    -------
    SpeciesSet
        The five species in the canonical order (cloud, ice, rain, snow, graupel).

    Raises
    ------
    WeatherDataError
        For an unknown preset, species or field, or an invalid value.
    """
    if name not in PRESETS:
        raise WeatherDataError("species.preset", "name", f"one of {PRESETS}", repr(name))
    sp = _make(name)
    if albedo is not None:
        overrides = {**{n: {"albedo_rgb": (albedo,) * 3} for n in SPECIES_NAMES}, **(overrides or {})}
    return sp.with_overrides(overrides, scale=scale)
