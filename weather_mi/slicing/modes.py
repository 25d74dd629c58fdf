"""The slicer's modes (the paper's Table IV and a multiple-scattering light model beyond it) and the
parameters a user adjusts interactively."""
from __future__ import annotations

from dataclasses import dataclass, field, replace

PHASE_MODES = ("uniform", "per_species")
LIGHT_MODES = ("low_albedo", "translucent", "multiple")


@dataclass(frozen=True)
class SliceMode:
    """A mode of the slicer: its phase functions, light model and colouring.

    Parameters
    ----------
    phase : {"uniform", "per_species"}, default "per_species"
        "uniform": one phase function for all species; "per_species": the Eq. 8 mixture.
    light : {"low_albedo", "translucent", "multiple"}, default "translucent"
        "low_albedo": everything that hits a particle leaves the light; "translucent" (the paper):
        light scattered into a forward cone survives and diffuses sideways; "multiple" (beyond the
        paper): single scattering plus multiple-scattering octaves driven by the optical depth towards
        the sun, a diffusion term of the cloud column along the sun ray, and skylight shadowed by the
        optical depth towards the zenith, in the medium with its forward peaks as unscattered light
        (see light.py and eye.py).
    detail : bool, default False
        Multiply extinction by a turbulent detail field.
    species_colors : bool, default False
        Paint each species with its Table III colour (Fig. 2).
    octaves : int, default 4
        Number of scattering orders of the "multiple" model, 1..8 (octave 0 is single scattering).

    Raises
    ------
    ValueError
        For an unknown phase or light mode, or octaves out of range.
    """

    phase: str = "per_species"
    light: str = "translucent"
    detail: bool = False
    species_colors: bool = False
    octaves: int = 4

    def __post_init__(self):
        if self.phase not in PHASE_MODES:
            raise ValueError(f"SliceMode.phase must be one of {PHASE_MODES}, got {self.phase!r}")
        if self.light not in LIGHT_MODES:
            raise ValueError(f"SliceMode.light must be one of {LIGHT_MODES}, got {self.light!r}")
        if not 1 <= int(self.octaves) <= 8:
            raise ValueError(f"SliceMode.octaves must be in 1..8, got {self.octaves}")


# the four rows of the paper's Table IV
TABLE_IV = {
    "uniform/low-albedo": SliceMode("uniform", "low_albedo"),
    "uniform/translucent": SliceMode("uniform", "translucent"),
    "per-species/translucent": SliceMode("per_species", "translucent"),
    "per-species/translucent/detail": SliceMode("per_species", "translucent", detail=True),
}
# every mode the study and the benchmark run: Table IV and the light model beyond the paper
MODES = {**TABLE_IV, "per-species/multiple": SliceMode("per_species", "multiple")}

# Defaults of the "multiple" light model: fitted by validation/calibrate_slicer.py (Adam through Dr.Jit
# reverse-mode AD, weather_mi.slicing.calibrate) on the demo supercell, the demo cumulus and the thin demo
# cumulus, front-, side- and back-lit (64 x 48, references of 128 spp), with the forward peaks within 3 deg
# as unscattered light in both renderers: first 50 iterations from calibrate.FIT_START in the frames the
# evaluation renders (128 slices, the automatic light buffer, 2 x 2 points per pixel, slab jitter 1), then,
# with the diffused light's flux term (diffusion_flux, issue 41), refitted 15 iterations from those
# defaults at 64 slices and 1 point per pixel (--start defaults --fit-slices 64 --fit-supersample 1), and
# with the diffused light's forward lobe and the shadowed ground below (diffusion_lobe, below_shadow, issue
# 41 part 2) refitted 16 iterations from those defaults the same way (learning rate 0.15); last refitted
# 16 iterations from those (learning rate 0.05) with real fields at times not held out added to the training
# views: the WRF supercell at 01:00 and 02:00 and the WRF plateau at 00:00 (18 views);
# judged on the real WRF supercell, WRF plateau, BOMEX and RICO storms, front-, side- and back-lit, against
# references of 2% cloud RSE or 150 s (validation/README.md, "The slicer against the path tracer"). Issue 38:
# refitted with the lit face's incidence (diffusion_incidence, Eq. D2) and 7 training views at a 6 deg sun with
# the clear atmosphere (25 views): 12 iterations from those defaults (learning rate 0.1), then 8 more (0.05)
# against references of the point-wise air albedo; the iterate of lowest training loss (validation/README.md,
# "The slicer at a low sun with the air"). refit38: 21 iterations from those (0.05) with the 18 training views
# also seen with the clear air at their own sun and the air's own sky (43 views; the slicer's air scattering
# more than once, its sky under Sky("air")); the iterate of lowest training loss (validation/README.md, "The
# refit with the air at today's sun").
MULTIPLE_DEFAULTS = {"ms_extinction": 0.3319, "ms_contribution": 0.3765, "ms_eccentricity": 0.9526,
                     "sky_gain": 0.5797, "sky_extinction": 0.026, "diffusion_gain": 1.1817,
                     "diffusion_scale": 0.3669, "leak_gain": 1.7395, "leak_rate": 1.5818, "diffusion_flux": 0.5446,
                     "below_shadow": 0.5823, "diffusion_lobe": 0.4138, "diffusion_incidence": 0.8573}


DEFAULT_DETAIL = 0.5  # the detail mode's noise amplitude (the study's detail field, detail.field(amplitude=0.5))


@dataclass(frozen=True)
class SliceParams:
    """Interactive parameters (none of them recompiles a kernel).

    Values may be Dr.Jit arrays (for differentiation); only plain numbers are range-checked.

    Parameters
    ----------
    scale : dict of str to float, default {}
        Per-species multipliers (>= 0) of the mixing ratios (the paper's "scalings").
    albedo : float, optional
        None (the species' albedos) or one single-scattering albedo in [0, 1] for all.
    cone_angle_deg : float, default 10.0
        Half-angle (degrees, in (0, 90)) of the forward cone whose scattered light keeps propagating.
    forward_fraction : float, optional
        None (from the phase tables: the fraction of scattered energy within the cone, per species) or
        a number in [0, 1] for all species (the paper's 0.9).
    ambient : float, default 0.0
        Table IV modes: fraction of the sky's mean radiance added as unshadowed, isotropic
        in-scattering (0: none, as in the paper).
    blur_length_m : float, optional
        Translucent light: the forward-scattered light spreads sideways like a diffusion whose variance
        grows by tan^2(cone) x blur_length_m (m) per metre travelled; None: the grid's mean voxel size,
        which reproduces the paper's blur of dl tan(cone) per slice at one slice per voxel (the paper's
        setting), and, unlike a blur per slice, does not change with the slice count.
    ms_extinction : float, default MULTIPLE_DEFAULTS["ms_extinction"]
        "multiple" light (Wrenninge et al. 2013), in [0, 1]: octave i sees the optical depth towards
        the sun scaled by ms_extinction^i.
    ms_contribution : float, default MULTIPLE_DEFAULTS["ms_contribution"]
        In [0, 1]: octave i contributes ms_contribution^i.
    ms_eccentricity : float, default MULTIPLE_DEFAULTS["ms_eccentricity"]
        In [0, 1]: octave i's phase function is blended towards isotropic,
        ms_eccentricity^i p + (1 - ms_eccentricity^i) / (4 pi).
    sky_gain : float, default MULTIPLE_DEFAULTS["sky_gain"]
        "multiple" light, >= 0: in-scattering of diffuse light, sky_gain x [the sky's mean radiance x
        T(sky_extinction x the optical depth above) + the lit ground's radiance x T(sky_extinction x the
        optical depth below)], T: a delta-Eddington layer's transmission of diffuse light (eye.py).
    sky_extinction : float, default MULTIPLE_DEFAULTS["sky_extinction"]
        >= 0: the factor on the optical depths above and below that the diffuse light crosses.
    diffusion_gain : float, default MULTIPLE_DEFAULTS["diffusion_gain"]
        "multiple" light, >= 0: isotropic in-scattering of diffused sunlight, diffusion_gain x
        E_sun / (4 pi) x the 1-D diffusion profile of the cloud column along the sun ray
        (eye.diffusion_profile: brightest a transport depth inside, falling linearly to the shadowed
        side; little in thin cloud).
    diffusion_scale : float, default MULTIPLE_DEFAULTS["diffusion_scale"]
        In [0, 1]: the profile is in transport optical depths diffusion_scale x tau (~ 1 - g).
    leak_gain : float, default MULTIPLE_DEFAULTS["leak_gain"]
        "multiple" light, >= 0: isotropic in-scattering of diffused sunlight that a finite cloud loses
        through its sides, leak_gain x E_sun / (4 pi) x (1 - exp(-X)) exp(-leak_rate x) (x, X: the
        transport optical depths of the diffusion profile): bright at the sunlit faces, dark in the
        shadowed parts, unlike the 1-D profile, which does not decay into a thick cloud.
    leak_rate : float, default MULTIPLE_DEFAULTS["leak_rate"]
        >= 0: its decay per transport optical depth.
    diffusion_flux : float, default MULTIPLE_DEFAULTS["diffusion_flux"]
        In [0, 1]: the diffused light (diffusion and leak terms) is scattered towards the eye with its
        flux along the sun ray, (phi + 3 diffusion_flux F . w_eye) / (4 pi) (the P1 radiance scattered
        with asymmetry ~ diffusion_flux; eye.diffused_towards_eye): back-lit, the light flowing through
        a cloud away from the sun brightens its shadowed side; 0: isotropic.
    below_shadow : float, default MULTIPLE_DEFAULTS["below_shadow"]
        "multiple" light, in [0, 1]: the ground that lights the medium from below is the ground beneath
        the point, in the storm's shadow: its radiance x (1 - below_shadow (1 - S)), S the sunlight factor
        of the ground straight below (the same delta-Eddington column transmission that lights the ground
        the eye sees); 0: the ground in the open everywhere.
    diffusion_lobe : float, default MULTIPLE_DEFAULTS["diffusion_lobe"]
        "multiple" light, in [0, 1]: the part of the diffused light (diffusion and leak terms) that is still
        travelling along the sunlight and is scattered towards the eye with the phase function instead of
        isotropically, diffusion_lobe x exp(-x) at transport depth x = diffusion_scale x tau (the sunlight's
        direction is forgotten over a transport mean free path; eye.LightModel.terms): front- and
        side-lit it dims the diffused light (P(Theta) < 1 / (4 pi) there), back-lit it makes the forward
        lobe of silver linings and lit cores; 0: isotropic.
    diffusion_incidence : float, default MULTIPLE_DEFAULTS["diffusion_incidence"]
        "multiple" light, in [0, 1]: the diffused light (diffusion and leak terms) enters the cloud through a
        lit face at incidence cosine cos i, estimated from the optical depths towards the sun and the zenith
        (eye.incidence_cosine: mu0 inside a horizontal layer, 1 beside a sunlit side), and diffuses along its
        normal with the flux E cos i (eye.diffusion_profile, Eq. D1): at a low sun a wide layer's top takes
        mu0 of the sunlight a face turned to the sun takes; the weight blends cos i towards 1
        (0: every face normal to the sun, as before).
    slab_jitter : float, default 0.0
        In [0, 1]: each pixel's slabs are offset by up to +-slab_jitter / 2 slice (jitter.py), which
        turns the terraces of the slab planes on lit faces into fine grain (0: aligned slabs, as before;
        the default by measurement, see jitter.py). Nonzero also offsets the light buffer's planes per
        texel (a first nonzero value compiles once; values after it compile nothing).
    jitter_frame : int, default 0
        Rotates the slab offsets (a different but equally stable pattern per index): frames averaged
        over successive indices converge to the smooth slab average.
    detail : dict of str to float, default {}
        Detail modes with a ``detail_noise`` renderer: the amount of simulated detail per species
        (paper section 5.4), the amplitude s in [0, 3] of the log-normal multiplier exp(s n - s^2/2) of
        its extinction (n: the unit-variance noise; 0: none; species not named: DEFAULT_DETAIL).

    Raises
    ------
    ValueError
        For a plain number out of its range.
    """

    scale: dict = field(default_factory=dict)
    albedo: float | None = None
    cone_angle_deg: float = 10.0
    forward_fraction: float | None = None
    ambient: float = 0.0
    blur_length_m: float | None = None
    ms_extinction: float = MULTIPLE_DEFAULTS["ms_extinction"]
    ms_contribution: float = MULTIPLE_DEFAULTS["ms_contribution"]
    ms_eccentricity: float = MULTIPLE_DEFAULTS["ms_eccentricity"]
    sky_gain: float = MULTIPLE_DEFAULTS["sky_gain"]
    sky_extinction: float = MULTIPLE_DEFAULTS["sky_extinction"]
    diffusion_gain: float = MULTIPLE_DEFAULTS["diffusion_gain"]
    diffusion_scale: float = MULTIPLE_DEFAULTS["diffusion_scale"]
    leak_gain: float = MULTIPLE_DEFAULTS["leak_gain"]
    leak_rate: float = MULTIPLE_DEFAULTS["leak_rate"]
    diffusion_flux: float = MULTIPLE_DEFAULTS["diffusion_flux"]
    below_shadow: float = MULTIPLE_DEFAULTS["below_shadow"]
    diffusion_lobe: float = MULTIPLE_DEFAULTS["diffusion_lobe"]
    diffusion_incidence: float = MULTIPLE_DEFAULTS["diffusion_incidence"]
    slab_jitter: float = 0.0
    jitter_frame: int = 0
    detail: dict = field(default_factory=dict)

    def __post_init__(self):
        # values may be Dr.Jit arrays (for differentiation): only plain numbers are range-checked
        number = lambda v: isinstance(v, (int, float))  # noqa: E731
        if number(self.cone_angle_deg) and not 0.0 < self.cone_angle_deg < 90.0:
            raise ValueError(f"cone_angle_deg must be in (0, 90), got {self.cone_angle_deg}")
        if number(self.forward_fraction) and not 0.0 <= self.forward_fraction <= 1.0:
            raise ValueError(f"forward_fraction must be in [0, 1], got {self.forward_fraction}")
        if number(self.albedo) and not 0.0 <= self.albedo <= 1.0:
            raise ValueError(f"albedo must be in [0, 1], got {self.albedo}")
        if number(self.blur_length_m) and not self.blur_length_m >= 0.0:
            raise ValueError(f"blur_length_m must be >= 0, got {self.blur_length_m}")
        for name in ("ms_extinction", "ms_contribution", "ms_eccentricity", "diffusion_scale", "slab_jitter",
                     "diffusion_flux", "below_shadow", "diffusion_lobe", "diffusion_incidence"):
            v = getattr(self, name)
            if number(v) and not 0.0 <= v <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {v}")
        for name in ("sky_gain", "sky_extinction", "ambient", "diffusion_gain", "leak_gain", "leak_rate"):
            v = getattr(self, name)
            if number(v) and v < 0.0:
                raise ValueError(f"{name} must be >= 0, got {v}")
        if any(v < 0 for v in self.scale.values()):
            raise ValueError("scalings must be >= 0")
        if any(not 0 <= v <= 3 for v in self.detail.values()):
            raise ValueError(f"detail amplitudes must be in [0, 3], got {self.detail}")

    def updated(self, **kw) -> "SliceParams":
        """A copy with the given fields replaced."""
        return replace(self, **kw)
