"""The paper's rendering modes (Table IV) and the parameters a user adjusts interactively."""
from __future__ import annotations

from dataclasses import dataclass, field, replace

PHASE_MODES = ("uniform", "per_species")
LIGHT_MODES = ("low_albedo", "translucent")


@dataclass(frozen=True)
class SliceMode:
    """phase: "uniform" (one phase function for all species) or "per_species" (Eq. 8 mixture);
    light: "low_albedo" (everything that hits a particle leaves the light) or "translucent" (light
    scattered into a forward cone survives, blurred over the cone); detail: multiply extinction by a
    turbulent detail field; species_colors: paint each species with its Table III colour (Fig. 2)."""

    phase: str = "per_species"
    light: str = "translucent"
    detail: bool = False
    species_colors: bool = False

    def __post_init__(self):
        if self.phase not in PHASE_MODES:
            raise ValueError(f"SliceMode.phase must be one of {PHASE_MODES}, got {self.phase!r}")
        if self.light not in LIGHT_MODES:
            raise ValueError(f"SliceMode.light must be one of {LIGHT_MODES}, got {self.light!r}")


# the four rows of the paper's Table IV
TABLE_IV = {
    "uniform/low-albedo": SliceMode("uniform", "low_albedo"),
    "uniform/translucent": SliceMode("uniform", "translucent"),
    "per-species/translucent": SliceMode("per_species", "translucent"),
    "per-species/translucent/detail": SliceMode("per_species", "translucent", detail=True),
}


@dataclass(frozen=True)
class SliceParams:
    """Interactive parameters (none of them recompiles a kernel).

    scale            : per-species multipliers of the mixing ratios (the paper's "scalings").
    albedo           : None (the species' albedos) or one single-scattering albedo for all.
    cone_angle_deg   : half-angle of the forward cone whose scattered light keeps propagating.
    forward_fraction : None (from the phase tables: the fraction of scattered energy within the
                       cone, per species) or a number for all species (the paper's 0.9).
    ambient          : fraction of the sky's mean radiance added as isotropic in-scattering
                       (0: none, as in the paper).
    """

    scale: dict = field(default_factory=dict)
    albedo: float | None = None
    cone_angle_deg: float = 10.0
    forward_fraction: float | None = None
    ambient: float = 0.0

    def __post_init__(self):
        # values may be Dr.Jit arrays (for differentiation): only plain numbers are range-checked
        number = lambda v: isinstance(v, (int, float))  # noqa: E731
        if number(self.cone_angle_deg) and not 0.0 < self.cone_angle_deg < 90.0:
            raise ValueError(f"cone_angle_deg must be in (0, 90), got {self.cone_angle_deg}")
        if number(self.forward_fraction) and not 0.0 <= self.forward_fraction <= 1.0:
            raise ValueError(f"forward_fraction must be in [0, 1], got {self.forward_fraction}")
        if number(self.albedo) and not 0.0 <= self.albedo <= 1.0:
            raise ValueError(f"albedo must be in [0, 1], got {self.albedo}")
        if any(v < 0 for v in self.scale.values()):
            raise ValueError("scalings must be >= 0")

    def updated(self, **kw) -> "SliceParams":
        return replace(self, **kw)
