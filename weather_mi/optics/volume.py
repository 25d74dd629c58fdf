"""Optics of a Hydrometeors dataset: the paper's Eq. 1-6 and the Eq. 8 mixture weights.

Eq. 1  sigma_ext = 2 pi R^2                       (extinction efficiency 2 for large particles)
Eq. 2  eta = rho_air q / (rho_particle V),  V = 4/3 pi R^3
Eq. 3  beta_ext = sigma_ext eta
Eq. 4  beta_ext = 3 rho_air q / (2 rho_particle R)  (1/m; what this module computes)
Eq. 5  omega = beta_sca / beta_ext
Eq. 6  beta_ext = sum over species
Eq. 8  P(Theta, s) = sum_s P_s(Theta) beta_sca,s(s) / sum_s beta_sca,s(s)  ->  weights w_s
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from ..errors import WeatherDataError
from ..io.hydrometeors import SPECIES_NAMES, bbox_of, check_species_name, validate
from .periodic import check_periodic, periodic_of_attrs
from .species import RGB_WAVELENGTHS_M, SpeciesSet, absorbing_material, physical_albedo, preset
from ..io.terrain import Terrain
from ..io.budget import check_fits


class ReleasedGrid:
    """A grid an OpticalVolume was built without (``optical_volume(keep=...)``), to save its memory where
    nothing reads it: its ``shape`` and ``dtype`` stay; reading its values raises WeatherDataError naming it."""

    def __init__(self, name: str, shape):
        self.name, self.shape, self.dtype = name, tuple(int(n) for n in shape), np.dtype(np.float32)
        self.ndim = len(self.shape)

    def __len__(self):
        return self.shape[0]

    def _refuse(self, *_a, **_k):
        raise WeatherDataError("OpticalVolume", self.name, f"the grid kept (optical_volume(keep=(..., {self.name!r})), "
                               "render_reference(release_volume=False))", "released to save memory")

    __array__ = __getitem__ = __iter__ = _refuse

    def __getattr__(self, attr):  # called only for attributes it lacks: the array's
        if attr.startswith("__") or attr in ("name", "shape", "dtype", "ndim"):
            raise AttributeError(attr)
        self._refuse()


GRIDS = ("beta_ext", "beta_total", "albedo", "weights")  # an OpticalVolume's grids


@dataclass(frozen=True)
class OpticalVolume:
    """Everything both renderers consume (docs/design.md). All grids are float32, indexed [z, y, x].

    Complete and read-only once built: the fields cannot be reassigned and the grids are read-only views
    (the arrays given stay the caller's); ``dataclasses.replace`` makes a changed copy. The one change in place
    is :meth:`release`, which frees grids (reading one then raises).

    Attributes
    ----------
    species : tuple of str
        Species names, in the order of the first axis of ``beta_ext`` and ``weights``.
    beta_ext : numpy.ndarray
        Per-species extinction (S, z, y, x) in 1/m (Eq. 4).
    beta_total : numpy.ndarray
        Total extinction (z, y, x) in 1/m (Eq. 6).
    albedo : numpy.ndarray
        Mixture single-scattering albedo (z, y, x, 3) (Eq. 5).
    weights : numpy.ndarray
        Eq. 8 scattering weights (S, z, y, x); zero where nothing scatters.
    bbox : tuple of 2 tuple of 3 float
        World box ((x0, y0, z0), (x1, y1, z1)) in metres.
    species_set : SpeciesSet or None
        The species the optics came from (None for raw optics).
    phase_mode : str
        "per_species", "paper" or "given".
    phase_quality : str
        "default", "high" or "test": the quality of the tables built at construction.
    attrs : dict
        Attributes (those of the hydrometeors, plus ``species_preset`` and ``model_radii``).
    phase_tables : tuple or None
        One phase table per species, built at construction from ``species_set`` and ``phase_mode``
        when not given; None only for raw optics without a phase function.
    terrain : Terrain or None
        The ground under the grid (:class:`weather_mi.io.terrain.Terrain`, the hydrometeors' terrain
        coordinates; None where they have none): the reference's ground is then a height-field mesh.
    periodic : bool or str
        Horizontal boundaries (:mod:`weather_mi.optics.periodic`): False (an isolated box), True (doubly
        periodic, the camera sees the periodic continuation) or "transport" (periodic light transport, the
        camera sees the domain's own tile only).
    components : tuple of Species or None
        Size classes (``optics.size_classes``): the Species of each entry of ``species`` (its radius the
        class's), whose tables are built by radius; None: one component per species of ``species_set``.
    air : optics.air.inside.BoxAir or None
        The clear air inside the box (molecules, ozone, aerosol per RGB channel; ``with_box_air``), extra
        components of the path tracer's medium; None: vacuum between the hydrometeors.
    air_density : numpy.ndarray or None
        (z,) the model's dry-air density per level, kg/m^3 (its mean over the level; ``optical_volume`` keeps
        it), from which a SceneSpec's ``atmosphere`` builds the air in the box (``optics.air.inside.scene_air``);
        None: the standard atmosphere's there.
    """

    species: tuple[str, ...]
    beta_ext: np.ndarray
    beta_total: np.ndarray
    albedo: np.ndarray
    weights: np.ndarray
    bbox: tuple[tuple[float, float, float], tuple[float, float, float]]
    species_set: SpeciesSet | None = None
    phase_mode: str = "per_species"
    phase_quality: str = "default"
    attrs: dict = field(default_factory=dict)
    phase_tables: tuple | None = field(default=None, repr=False)
    terrain: Terrain | None = field(default=None, repr=False)
    periodic: bool | str = False
    components: tuple | None = field(default=None, repr=False)
    air: object | None = field(default=None, repr=False)
    air_density: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self):
        object.__setattr__(self, "periodic", check_periodic(self.periodic))
        for name in GRIDS:
            if isinstance(getattr(self, name), ReleasedGrid) or getattr(getattr(self, name), "deferred", False):
                continue  # released, or computed where read (``forward_peak.ScaledWeights``)
            view = np.asarray(getattr(self, name)).view()
            view.flags.writeable = False
            object.__setattr__(self, name, view)
        tables = self.phase_tables
        if tables is None and self.species_set is not None:
            from . import phase
            tables = phase.for_species(list(self.components or self.species_set), mode=self.phase_mode,
                                       quality=self.phase_quality, sized=self.components is not None)
        if tables is not None:
            tables = tuple(tables)
            if len(tables) != len(self.species):
                raise WeatherDataError("OpticalVolume", "phase_tables",
                                       f"one table per species ({len(self.species)})", f"{len(tables)} tables")
        object.__setattr__(self, "phase_tables", tables)
        object.__setattr__(self, "attrs", dict(self.attrs))

    def release(self, *names: str) -> None:
        """Free the grids ``names`` (of ``GRIDS``) in place: each becomes a :class:`ReleasedGrid` (its shape kept,
        reading it raises), for a caller whose renderer holds what it needs of them (``render_reference(
        release_volume=True)``: the kernel's own grids replace the volume's as they are built). The memory goes
        once no other volume or array holds the grid."""
        for name in names:
            if name not in GRIDS:
                raise ValueError(f"OpticalVolume.release: {name!r} is not one of {GRIDS}")
            grid = getattr(self, name)
            if not isinstance(grid, ReleasedGrid):
                object.__setattr__(self, name, ReleasedGrid(name, grid.shape))

    def require_phase_tables(self) -> tuple:
        """The phase tables, or WeatherDataError when this volume was built without any."""
        if self.phase_tables is None:
            raise WeatherDataError(str(self.attrs.get("source", "OpticalVolume")), "phase_tables",
                                   "one phase table per species to render (OpticalVolume.from_arrays(..., phase=...))",
                                   "none")
        return self.phase_tables

    @property
    def shape(self) -> tuple[int, int, int]:
        return tuple(self.beta_total.shape)

    @property
    def spacing(self) -> tuple[float, float, float]:
        """(dz, dy, dx) in metres."""
        (x0, y0, z0), (x1, y1, z1) = self.bbox
        nz, ny, nx = self.shape
        return ((z1 - z0) / nz, (y1 - y0) / ny, (x1 - x0) / nx)

    def level_heights_m(self) -> np.ndarray:
        """(z,) the levels' cell-centre heights, m (the box's z axis)."""
        z0, z1, nz = float(self.bbox[0][2]), float(self.bbox[1][2]), self.shape[0]
        return z0 + (np.arange(nz) + 0.5) * (z1 - z0) / nz

    def occupied_bbox(self, threshold_per_m: float = 0.0):
        """World box ((x0, y0, z0), (x1, y1, z1)) of the cells whose extinction exceeds the threshold
        (the whole bbox when none does)."""
        occ = self.beta_total > threshold_per_m
        if not occ.any():
            return self.bbox
        (x0, y0, z0), (x1, y1, z1) = self.bbox
        dz, dy, dx = self.spacing
        lo, hi = [], []
        for axis, start, step in ((2, x0, dx), (1, y0, dy), (0, z0, dz)):
            idx = np.nonzero(occ.any(axis=tuple(a for a in range(3) if a != axis)))[0]
            lo.append(start + idx[0] * step)
            hi.append(start + (idx[-1] + 1) * step)
        return tuple(lo), tuple(hi)

    def optical_depth_z(self) -> np.ndarray:
        """Vertical optical depth of every column (y, x): sum of beta_total dz."""
        return self.beta_total.sum(axis=0, dtype=np.float64) * self.spacing[0]

    @classmethod
    def from_arrays(cls, beta_ext, albedo=1.0, phase=None, bbox=((0, 0, 0), (1, 1, 1)),
                    name: str = "medium") -> "OpticalVolume":
        """Raw optics: one medium with given extinction, albedo and phase function.

        Parameters
        ----------
        beta_ext : array_like
            (z, y, x) extinction grid (1/m), finite and >= 0.
        albedo : float or array_like, default 1.0
            Single-scattering albedo in [0, 1]: a number, (z, y, x) or (z, y, x, 3).
        phase : phase table, optional
            The one phase table of the medium (None: optics without a phase function, not renderable).
        bbox : tuple of 2 tuple of 3 float, default ((0, 0, 0), (1, 1, 1))
            Bounding box ((x0, y0, z0), (x1, y1, z1)) in metres.
        name : str, default "medium"
            The one species name.

        Returns
        -------
        OpticalVolume

        Raises
        ------
        WeatherDataError
            For a grid that is not 3-D, negative or non-finite values, an albedo of the wrong shape or
            outside [0, 1], or an empty box.
        """
        src = "OpticalVolume.from_arrays"
        beta = np.ascontiguousarray(beta_ext, dtype=np.float32)
        if beta.ndim != 3:
            raise WeatherDataError(src, "beta_ext", "a (z, y, x) array in 1/m", f"shape {beta.shape}")
        if not np.all(np.isfinite(beta)) or np.any(beta < 0):
            raise WeatherDataError(src, "beta_ext", "finite extinction >= 0 (1/m)")
        alb = np.asarray(albedo, dtype=np.float32)
        if alb.ndim == 3:
            alb = alb[..., None]
        try:
            alb = np.ascontiguousarray(np.broadcast_to(alb, beta.shape + (3,)), dtype=np.float32)
        except ValueError as exc:
            raise WeatherDataError(src, "albedo", "a number, (z, y, x) or (z, y, x, 3) array",
                                   f"shape {np.shape(albedo)}") from exc
        if np.any(alb < 0) or np.any(alb > 1) or not np.all(np.isfinite(alb)):
            raise WeatherDataError(src, "albedo", "single-scattering albedo in [0, 1]")
        lo, hi = (tuple(float(v) for v in p) for p in bbox)
        if not all(h > l for l, h in zip(lo, hi)):
            raise WeatherDataError(src, "bbox", "((x0, y0, z0), (x1, y1, z1)) with x1 > x0, y1 > y0, z1 > z0")
        weights = (beta > 0).astype(np.float32)[None]
        return cls((name,), beta[None], beta, alb, weights, (lo, hi), None, "given", attrs={"source": src},
                   phase_tables=None if phase is None else (phase,))


def _radius_field(hyd: xr.Dataset, name: str, default_m: float, use_model: bool):
    """Per-voxel equivalent radius (m): the model's effective radius where given (> 0), else the species'."""
    var = f"r_eff_{name}"
    if use_model and var in hyd:
        r = hyd[var].values.astype(np.float32, copy=False)
        return np.where(r > 0, r, np.float32(default_m))
    return default_m


SIZES = ("scheme", "physical", "paper")


def _species_setup(species, scale, model_radii, sizes=None) -> tuple[SpeciesSet, bool]:
    """(the SpeciesSet with the scalings, whether the model's radii are used) of ``optical_volume``'s arguments:
    ``sizes`` "scheme" uses the model's radii, "physical"/"paper" that preset's radii (and their albedos) for
    every species; None leaves both to the species table and ``model_radii``."""
    sp = preset(species) if isinstance(species, str) else species
    for name in scale or {}:
        check_species_name(name, "optical_volume", f"scale[{name!r}]")
    sp = sp.with_overrides(scale={n: sp[n].scale * f for n, f in (scale or {}).items()})
    if sizes is not None and sizes not in SIZES:
        raise WeatherDataError("optical_volume", "sizes", f"one of {SIZES}", repr(sizes))
    if sizes in ("physical", "paper"):
        fixed = preset(sizes)
        sp = sp.with_overrides({s.name: {"radius_m": s.radius_m, "albedo_rgb": s.albedo_rgb} for s in fixed})
    if model_radii is None:
        model_radii = (sp.preset_name != "paper") if sizes is None else sizes == "scheme"
    return sp, bool(model_radii)


def default_sizes(hyd: xr.Dataset) -> str | None:
    """The command line's default particle sizes: "scheme" where ``hyd`` carries effective radii (a WRF file
    of a microphysics scheme weather-mi knows, RE_* fields, an LES file's reff), else None (the preset's)."""
    return "scheme" if any(str(v).startswith("r_eff_") for v in hyd.data_vars) else None


def sizes_used(hyd: xr.Dataset, sp: SpeciesSet, use_model: bool) -> dict[str, str]:
    """Where each species' radius comes from: "model" (the Hydrometeors' ``r_eff_<species>``) or the radius of
    the species table (um)."""
    return {s.name: "model" if use_model and f"r_eff_{s.name}" in hyd else f"{1e6 * s.radius_m:.4g} um"
            for s in sp}


def extinction(hyd: xr.Dataset, species: SpeciesSet | str = "paper", scale: Mapping[str, float] | None = None, *,
               model_radii: bool | None = None, sizes: str | None = None) -> tuple[np.ndarray, dict[str, float]]:
    """The total extinction (Eq. 4, 6; (z, y, x) float32, 1/m) of ``hyd`` and each species' largest extinction
    (1/m), as ``optical_volume`` computes them (same arguments), a species at a time and without the rest of a
    volume (albedo, weights, phase tables): what a summary needs, in 4 bytes per cell and one temporary."""
    validate(hyd)
    sp, use_model = _species_setup(species, scale, model_radii, sizes)
    rho = np.asarray(hyd["rho_air"].values, np.float32)
    total, largest = None, {}
    for s in sp:
        q = hyd[f"q_{s.name}"].values.astype(np.float32, copy=False)
        beta = s.beta_ext_per_m(rho, q, _radius_field(hyd, s.name, s.radius_m, use_model),
                                out=np.empty(rho.shape, np.float32))
        largest[s.name] = float(beta.max())
        total = beta if total is None else np.add(total, beta, out=total)
    return total, largest


def level_density(rho_air_kg_m3) -> np.ndarray:
    """(z,) the dry-air density of each level, kg/m^3: the mean over the level of a (z, y, x) field (the model's
    own density; its horizontal variations, a few per cent, would cost the path tracer its empty-space
    skipping: ``optics.air.inside``), or a (z,) profile as given. A ValueError where it is not finite and >= 0."""
    rho = np.asarray(rho_air_kg_m3)
    if rho.ndim not in (1, 3):
        raise ValueError(f"rho_air must be (z, y, x) or one value per level (z,); got shape {rho.shape}")
    levels = rho.reshape(rho.shape[0], -1)
    mean = levels.mean(axis=1, dtype=np.float64)  # no float64 copy of the grid
    if not np.all(np.isfinite(mean)) or any(float(level.min()) < 0 for level in levels):
        raise ValueError("rho_air (dry-air density, kg/m^3) must be finite and >= 0 for the air in the box")
    return mean


def _species_constants(hyd: xr.Dataset, sp: SpeciesSet, use_model: bool, voxel_albedo: bool) -> dict:
    """``mixture_kernels.voxel_optics``'s per-species constants, each as numpy computes it in the expressions the
    pass replaces: Eq. 4's float32 factors (``Species.beta_ext_per_m``: 3 scale; 2 rho_p R, or 2 rho_p and R
    where the voxel has its own radius, ``_radius_field``), the mixture's albedos, and where each voxel's albedo
    comes from its radius (``voxel_albedo``, with the model's radii: the species with ``r_eff_<species>`` whose
    albedo is the physical one of its radius; an overridden, artistic albedo is kept) the weak-absorption
    constants of ``species.albedo_of_radius``."""
    from .mixture_kernels import GRID, SCALAR, eq4_factors
    n_s = len(sp)
    k = {"mode": np.zeros(n_s, np.int8), "by_radius": np.zeros(n_s, np.bool_), "radius_scale": np.ones(n_s),
         "k_abs": np.zeros((n_s, 3)), "n_term": np.zeros((n_s, 3))}
    for i, s in enumerate(sp):
        grid = use_model and f"r_eff_{s.name}" in hyd
        k["mode"][i] = GRID if grid else SCALAR
        physical = tuple(float(a) for a in physical_albedo(s.phase_class, np.float64(s.radius_m), s.density_kg_m3))
        if grid and voxel_albedo and tuple(s.albedo_rgb) == physical:
            scale, n_rgb, k_rgb = absorbing_material(s.phase_class, s.density_kg_m3)
            k["by_radius"][i], k["radius_scale"][i] = True, 1.0 if scale is None else scale
            k["k_abs"][i] = k_rgb
            k["n_term"][i] = [n ** 3 - (n * n - 1.0) ** 1.5 for n in n_rgb]  # species.albedo_of_radius's
    factors = np.array([eq4_factors(s.scale, s.density_kg_m3, s.radius_m) for s in sp], np.float32)
    k["c3"], k["denom"], k["d2"], k["rdef"] = (np.ascontiguousarray(col) for col in factors.T)
    k["rgb"] = np.asarray([s.albedo_rgb for s in sp], np.float32)
    k["mean_albedo"] = np.asarray([np.float32(np.mean(s.albedo_rgb)) for s in sp], np.float32)
    k["albedo64"] = np.asarray([s.albedo_rgb for s in sp], np.float64)
    k["wavelengths"] = np.asarray(RGB_WAVELENGTHS_M, np.float64)
    return k


def _release(hyd: xr.Dataset, names, kinds) -> None:
    """Drop the fields ``names`` of the ``kinds`` ("q", "r_eff") from ``hyd`` in place (those it has)."""
    for name in names:
        if name.rsplit("_", 1)[0] in kinds and name in hyd:
            del hyd[name]


def _flat32(hyd: xr.Dataset, var: str) -> np.ndarray:
    """The field ``var`` of ``hyd`` as a flat float32 array (its own memory where it is float32 already)."""
    return np.ascontiguousarray(hyd[var].values, np.float32).reshape(-1)


def _optics_arrays(hyd: xr.Dataset, sp: SpeciesSet, use_model: bool, voxel_albedo: bool = False,
                   release: tuple = (), keep: tuple = ("beta_ext", "weights")):
    """(beta_ext (S, z, y, x), beta_total, albedo (z, y, x, 3), weights (S, z, y, x)), float32, in compiled
    passes: species after species (``mixture_kernels.species_pass``; the fields of the ``release`` kinds, "q"
    and "r_eff", dropped from ``hyd`` in place as each species is done, so that they go while the outputs are
    built), then the mixture (``mixture_pass``) and the albedo's finish. A per-species grid not in ``keep`` is
    never built (a :class:`ReleasedGrid` of its shape). Beyond the kept outputs (16 bytes per cell and 4 per
    kept species grid, their pages touched where there is mass) the species' beta_s are held in the weights
    (or beta_ext) grid, or in a grid of them where neither is kept and a voxel's radius sets its albedo."""
    from .mixture_kernels import (CHUNK, albedo_sums, finish_albedo, mixture_pass, radii_with_extinction,
                                  species_pass)
    rho = _flat32(hyd, "rho_air")
    shape = hyd["rho_air"].shape
    grids = (len(SPECIES_NAMES),) + tuple(shape)
    k = _species_constants(hyd, sp, use_model, voxel_albedo)
    out = {name: np.zeros(grids if name in keep else (grids[0], 1), np.float32) for name in ("beta_ext", "weights")}
    flat = {name: grid.reshape(grids[0], -1) for name, grid in out.items()}
    second = "weights" in keep or bool(k["by_radius"].any())  # the mixture's pass: the weights, radii's albedo
    store = flat["beta_ext"] if "beta_ext" in keep else flat["weights"] if "weights" in keep else \
        np.zeros((grids[0], rho.size) if second else (grids[0], 1), np.float32)
    beta_total = np.zeros(shape, np.float32)  # zeros: pages without mass are never written (mixture_kernels)
    albedo = np.zeros(tuple(shape) + (3,), np.float32)
    n_chunks = (rho.size + CHUNK - 1) // CHUNK
    touched, has = np.zeros(n_chunks, np.bool_), np.zeros((grids[0], n_chunks), np.bool_)
    radii = [np.zeros(0, np.float32) for _ in sp]
    for i, s in enumerate(sp):
        q = _flat32(hyd, f"q_{s.name}")
        r = _flat32(hyd, f"r_eff_{s.name}") if k["mode"][i] else np.zeros(1, np.float32)
        species_pass(rho, q, r, k["mode"][i], k["c3"][i], k["denom"][i], k["d2"][i], k["rdef"][i], k["rgb"][i],
                     k["mean_albedo"][i], i == 0, "beta_ext" in keep, flat["beta_ext"][i], second, store[i],
                     beta_total.reshape(-1), albedo.reshape(-1, 3), touched, has[i])
        if k["by_radius"][i]:
            radii[i] = radii_with_extinction(store[i], r, has[i])
        del q, r
        _release(hyd, [f"{kind}_{s.name}" for kind in ("q", "r_eff")], release)
    if second:
        mixture_pass(store, k["mean_albedo"], "weights" in keep, flat["weights"], k["by_radius"], tuple(radii),
                     k["radius_scale"], k["wavelengths"], k["k_abs"], k["n_term"], k["albedo64"],
                     albedo.reshape(-1, 3), touched, has)
    del store, radii
    # mixture albedo (Eq. 5 over the mixture); clear voxels get the mean albedo of the volume so that
    # trilinear interpolation at cloud edges does not blend in a dark value
    total_ext = float(beta_total.sum(dtype=np.float64))
    fill = (albedo_sums(albedo.reshape(-1, 3), beta_total.reshape(-1)) / total_ext) if total_ext > 0 \
        else np.mean([s.albedo_rgb for s in sp], axis=0)
    finish_albedo(albedo.reshape(-1, 3), beta_total.reshape(-1), fill.astype(np.float32))
    kept = {name: out[name] if name in keep else ReleasedGrid(name, grids) for name in out}
    return kept["beta_ext"], beta_total, albedo, kept["weights"]


def optical_volume(hyd: xr.Dataset, species: SpeciesSet | str = "paper",
                   scale: Mapping[str, float] | None = None, *, phase: str = "per_species",
                   phase_tables: Sequence | None = None, model_radii: bool | None = None,
                   phase_quality: str = "default", sizes: str | None = None,
                   size_classes: int | None = None, periodic: bool | str | None = None,
                   release: bool | tuple = False, keep: tuple = ("beta_ext", "weights")) -> OpticalVolume:
    """Optics of ``hyd`` (Eq. 1-6, 8).

    Parameters
    ----------
    hyd : xarray.Dataset
        Hydrometeors (:mod:`weather_mi.io.hydrometeors`).
    species : SpeciesSet or str, default "paper"
        A SpeciesSet or a preset name ("paper", "physical").
    scale : mapping of str to float, optional
        Per-species scaling factors, e.g. {"ice": 2.0} (multiplies that species' mass).
    phase : {"per_species", "paper"}, default "per_species"
        "per_species" (five tables) or "paper" (one water and one ice table), built with the volume.
    phase_tables : sequence, optional
        One phase table per species, used instead of building them.
    model_radii : bool, optional
        Use the model's effective radii (``r_eff_<species>``, m) where present; default True except for
        the "paper" preset, which reproduces the paper's fixed radii.
    phase_quality : {"default", "high", "test"}, default "default"
        Quality of the tables built with the volume ("test": small, fast tables).
    sizes : {"scheme", "physical", "paper"}, optional
        The particle sizes: "scheme" the model's effective radii per voxel (``r_eff_<species>``: the
        microphysics scheme's size distributions, ``weather_mi.io.microphysics``, or the file's RE_*; the
        species table's radius where a species has none), and each voxel's albedo from its radius (Eq. 5 with
        the weak-absorption albedo of ``species.physical_albedo``); "physical" / "paper" that preset's fixed
        radii (and albedos) with the rest of ``species``. None: as ``species`` and ``model_radii`` say (the
        model's radii, the species' albedo).
    size_classes : int, optional
        With the model's radii: each species with ``r_eff_<species>`` split into up to this many size
        classes, Eq. 8 components with their own phase tables (``weather_mi.optics.size_classes``; the
        volume's ``species`` then name the components, e.g. "rain#2"); None or 1: one per species.
    periodic : bool or "transport", optional
        Horizontal boundaries (``OpticalVolume.periodic``); default: "transport" where the hydrometeors say
        they are periodic (``attrs["periodic"]``: the LES reader's doubly periodic domains), else False.
    release : bool or tuple of str, default False
        Drop the mixing ratios and effective radii from ``hyd`` (in place) once their optics are computed, so
        that their memory goes while the volume's grids are built (the command line, which needs them no more;
        ``rho_air`` and the coordinates stay); a tuple: those kinds of field alone ("q", "r_eff"; the viewer
        keeps the mixing ratios for its read-out).
    keep : tuple of str, default ("beta_ext", "weights")
        The per-species grids the volume keeps; one left out is a :class:`ReleasedGrid` (its memory freed
        once the total, the albedo and the weights exist): the path tracer reads no ``beta_ext`` (4 bytes per
        cell and species saved), the slicer no ``weights``.

    Returns
    -------
    OpticalVolume
        Extinction (1/m), albedo and Eq. 8 weights on the hydrometeors' grid, with its world box (m).

    Raises
    ------
    WeatherDataError
        For invalid hydrometeors, an unknown species in ``scale`` or an unknown ``phase``.
    """
    validate(hyd)
    if phase not in ("per_species", "paper"):
        raise WeatherDataError("optical_volume", "phase", '"per_species" or "paper"', repr(phase))
    sp, use_model = _species_setup(species, scale, model_radii, sizes)
    if size_classes is not None and not (isinstance(size_classes, (int, np.integer)) and size_classes >= 1):
        raise WeatherDataError("optical_volume", "size_classes", "a whole number of size classes >= 1",
                               repr(size_classes))  # before the optics (and ``release``) touch hyd
    check_fits(str(hyd.attrs.get("source", "hydrometeors")), hyd["rho_air"].shape, "optics")  # before allocating
    split_later = size_classes is not None and size_classes != 1 and use_model  # size_classes.split reads r_eff
    released = ("q", "r_eff") if release is True else tuple(release or ())
    kinds = tuple(k for k in released if not (split_later and k == "r_eff"))
    beta_ext, beta_total, albedo, weights = _optics_arrays(hyd, sp, use_model, voxel_albedo=sizes == "scheme",
                                                           release=kinds, keep=GRIDS if split_later else keep)
    names, components, attrs_classes = SPECIES_NAMES, None, {}
    if size_classes is not None and int(size_classes) > 1 and use_model:
        from .size_classes import split
        names, beta_ext, weights, components = split(hyd, sp, beta_ext, weights, int(size_classes))
        attrs_classes = {"size_classes": int(size_classes)}
    _release(hyd, [f"r_eff_{s.name}" for s in sp], ("r_eff",) if "r_eff" in released else ())
    attrs = {k: v for k, v in hyd.attrs.items()}
    attrs["species_preset"] = sp.preset_name
    attrs["model_radii"] = use_model
    if sizes is not None:
        attrs["sizes"] = sizes
    attrs.update(attrs_classes)
    if "beta_ext" not in keep:
        beta_ext = ReleasedGrid("beta_ext", beta_ext.shape)
    if "weights" not in keep:
        weights = ReleasedGrid("weights", weights.shape)
    return OpticalVolume(names, beta_ext, beta_total, albedo, weights, bbox_of(hyd), sp, phase,
                         phase_quality, attrs, None if phase_tables is None else tuple(phase_tables),
                         Terrain.of(hyd), periodic_of_attrs(hyd.attrs) if periodic is None else periodic,
                         components, air_density=level_density(hyd["rho_air"].values))
