"""What the traced walks need about the scene's one medium, found at each render: the medium, its sigma_t
grid and scale (:class:`MediumSetup`), the unit-cube frame and grids of majorants the trackers walk
(:class:`Tracking`), and the medium lookups (sigma_t at a point, a scattering event).
"""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

from . import air_levels
from .spectral_air import bind_air
from .dda import Grid
from .majorants import empty_space_radius, texel_majorant_grid
from .variant_class import variant_class

PLUGIN_NAME = "majorant_volpath"


class _Children:
    """Collects the direct children and values that an object exposes through ``traverse`` (methods
    of a ``mi.TraversalCallback``, see ``variant_class``)."""

    def __init__(self):
        mi.TraversalCallback.__init__(self)
        self.items = {}

    def put(self, name, value, flags, cpptype=None):
        self.items[name] = (value, cpptype)


def children(obj) -> dict:
    """{name: (value, cpptype)} of the direct children and values ``obj`` exposes through ``traverse``."""
    cb = variant_class(_Children, "TraversalCallback")()
    obj.traverse(cb)
    return cb.items


def _key(obj):
    """An identity of a Mitsuba object (its pointer) for deduplication."""
    return obj.ptr if hasattr(obj, "ptr") else id(obj)


class MediumSetup:
    """The scene's one medium (shapes' and sensors' media and ``sensor_medium``; more than one raises):
    ``medium`` (None: none), its ``sigma_t`` ``volume`` (None unless a ``heterogeneous`` medium), the
    medium's ``scale`` and whether its extinction is ``spectral``. Built at each render. ``air``: the box's air
    per level that the integrator adds to a grey sigma_t grid (:meth:`add_air`; None: none, or in the grid)."""

    def __init__(self, scene, sensor_medium):
        media = {}
        for shape in scene.shapes():
            for m in (shape.interior_medium(), shape.exterior_medium()):
                if m is not None:
                    media.setdefault(_key(m), m)
        for sensor in scene.sensors():
            m = sensor.get_medium() if hasattr(sensor, "get_medium") else None
            if m is not None:
                media.setdefault(_key(m), m)
        if sensor_medium is not None:
            media.setdefault(_key(sensor_medium), sensor_medium)
        if len(media) > 1:
            raise RuntimeError(f"{PLUGIN_NAME}: the scene references {len(media)} different media; "
                               "this integrator handles exactly one (put all the data into one grid)")
        self.medium = next(iter(media.values())) if media else None
        self.volume = None
        self.scale = 1.0
        self.spectral = self.spectral_albedo = False
        self.air = self.air_albedo = None
        if self.medium is None:
            return
        self.spectral = bool(self.medium.has_spectral_extinction())
        # spectral variants: the albedo by wavelength from a ``hydrometeor_mixture`` with co-albedo spectra
        self.spectral_albedo = bool(mi.is_spectral) and getattr(self.medium.phase_function(), "coalbedo", None) is not None
        ch = children(self.medium)
        if "sigma_t" in ch and isinstance(ch["sigma_t"][0], mi.Volume) and "scale" in ch:
            self.volume = ch["sigma_t"][0]
            value, cpptype = ch["scale"]
            self.scale = float(mi.get_property(value, cpptype, self.medium)) if cpptype is not None else float(value)

    def add_air(self, levels, albedo, to_local, periodic: bool) -> None:
        """The box's air per level (``air_levels.AirLevels``) added to the grey sigma_t grid (the unit cube by
        ``to_local``): sigma_t = the grid's + the air's at the point's height, per channel (the extinction is then
        spectral, unless the air is grey: ``levels.grey``, a satellite band's); the albedo the mixture's
        (``air_albedo.MixtureAlbedo``) on the same grid."""
        rx, ry, rz = (int(v) for v in self.volume.resolution()) if self.volume is not None else (0, 0, 0)
        if self.volume is None or albedo is None or self.scale != 1.0 or tuple(albedo.shape) != (rz, ry, rx):
            raise RuntimeError(f"{PLUGIN_NAME}: the air added per level ('air_extinction' with a grey sigma_t grid) "
                               "needs a heterogeneous medium with a sigma_t grid, scale 1, and 'air_albedo' on its grid")
        self.air, self.air_albedo, self.air_to_local, self.air_levels = levels, albedo, to_local, rz
        self.air_periodic, self.beta = bool(periodic), volume_data(self.volume).array
        self.spectral = not levels.grey

    def air_at(self, p, active, wavelengths=None, bound=None):
        """The air's extinction (Color3f, or Float where grey; 1/m) at world point p: linear between the level
        centres (the trilinear lookup of a grid that held it in every voxel); a spectral air
        (``spectral_air.ComponentAirLevels``) at the lanes' ``wavelengths`` (mi.Spectrum), or ``bound`` to them
        already (``spectral_air.bind_air``)."""
        q = (self.air_to_local @ p).z * self.air_levels - 0.5
        return (bind_air(self.air, wavelengths) if bound is None else bound).sigma_at(q, active)


def check_bbox(to_world, vol):
    """The majorant grid must sit on the sigma_t grid: compare the image of the unit cube with
    the volume's bounding box (a mismatch would silently make the majorants non-conservative)."""
    corners = np.array([[x, y, z, 1.0] for x in (0, 1) for y in (0, 1) for z in (0, 1)]) @ to_world.T
    lo, hi = corners[:, :3].min(axis=0), corners[:, :3].max(axis=0)
    bb = vol.bbox()
    vlo = np.array([bb.min.x, bb.min.y, bb.min.z], np.float64)
    vhi = np.array([bb.max.x, bb.max.y, bb.max.z], np.float64)
    tol = 1e-4 * max(float(np.max(vhi - vlo)), 1e-30)
    if np.any(np.abs(lo - vlo) > tol) or np.any(np.abs(hi - vhi) > tol):
        raise RuntimeError(f"{PLUGIN_NAME}: 'to_world' maps the unit cube onto {lo.tolist()} - {hi.tolist()}, "
                           f"but the medium's sigma_t grid covers {vlo.tolist()} - {vhi.tolist()}")


def unit_cube_to_world(to_world, vol) -> np.ndarray:
    """The (4, 4) matrix that maps the unit cube onto the sigma_t grid: the ``to_world`` property
    (checked against the grid's bounding box) or, without it, that box."""
    if to_world is not None:
        to_world = np.array(to_world.matrix, dtype=np.float64).reshape(4, 4)
    elif vol is not None:
        bb = vol.bbox()
        lo = np.array([bb.min.x, bb.min.y, bb.min.z], np.float64)
        hi = np.array([bb.max.x, bb.max.y, bb.max.z], np.float64)
        to_world = np.diag(np.r_[hi - lo, 1.0])
        to_world[:3, 3] = lo
    else:
        raise RuntimeError(f"{PLUGIN_NAME}: 'to_world' is required when the medium has no sigma_t grid")
    if vol is not None:
        check_bbox(to_world, vol)
    return to_world


def volume_data(vol):
    """The data (TensorXf) of a ``gridvolume``."""
    for name, (value, cpptype) in children(vol).items():
        if name == "data":
            return mi.get_property(value, cpptype, vol) if cpptype is not None else value
    raise RuntimeError(f"{PLUGIN_NAME}: cannot read the sigma_t grid data")


def sigma_t_at(ms, p, ray, active, air=None):
    """sigma_t (1/m) of the medium ``ms`` at world point p (Spectrum if spectral extinction, else Float); ``air``:
    the box's spectral air bound to the ray's wavelengths (a tracker's walk's), else bound here."""
    if ms.volume is not None:
        it = _interaction(p, ray)
        if ms.air is not None:  # the grey grid's and the air's at the point's level
            return ms.air_at(p, active, ray.wavelengths, air) + ms.volume.eval_1(it, active)
        if ms.spectral:
            return ms.volume.eval(it, active) * ms.scale
        return ms.volume.eval_1(it, active) * ms.scale
    mei = medium_interaction(ms, ray, p, mi.Float(0.0), active)
    sigma_t = ms.medium.get_scattering_coefficients(mei, active)[2]
    return sigma_t if ms.spectral else sigma_t[0]


def _interaction(p, ray):
    it = dr.zeros(mi.Interaction3f)
    it.p = p
    it.time = ray.time
    it.wavelengths = ray.wavelengths
    return it


def medium_interaction(ms, ray, p, t, active):
    """A medium interaction of ``ms``'s medium at point p, distance t along ``ray`` (t = inf where not ``active``)."""
    mei = dr.zeros(mi.MediumInteraction3f)
    mei.t = dr.select(active, t, dr.inf)
    mei.p = p
    mei.wi = -ray.d
    mei.sh_frame = mi.Frame3f(mei.wi)
    mei.time = ray.time
    mei.wavelengths = ray.wavelengths
    mei.medium = dr.select(active, mi.MediumPtr(ms.medium), dr.zeros(mi.MediumPtr))
    return mei


def scattering_event(ms, ray, t, active):
    """The medium interaction at distance ``t`` along ``ray`` (with sigma_s and sigma_t set) and its
    single-scattering albedo sigma_s / sigma_t (0 where sigma_t = 0)."""
    mei = medium_interaction(ms, ray, ray.o + ray.d * t, t, active)
    if ms.air is not None and hasattr(ms.air_albedo, "event"):  # spectral: the air at the lanes' wavelengths
        return ms.air_albedo.event(ms, ray, t, active)  # (``spectral_air_albedo``)
    if ms.air is not None:  # sigma_t with the air per level (:func:`sigma_t_at`); the albedo grid the mixture's
        sigma_t = sigma_t_at(ms, mei.p, ray, active)
        albedo = ms.air_albedo.at(ms.air_to_local @ mei.p, ms.beta, mi.Color3f(sigma_t), ms.air_periodic, active)
        albedo = dr.select(sigma_t > 0.0, albedo, 0.0)
        mei.sigma_s, mei.sigma_t = albedo * sigma_t, sigma_t
        return mei, albedo
    sigma_s, _, sigma_t = ms.medium.get_scattering_coefficients(mei, active)
    mei.sigma_s, mei.sigma_t = sigma_s, sigma_t
    albedo = dr.select(sigma_t > 0.0, sigma_s / dr.select(sigma_t > 0.0, sigma_t, 1.0), 0.0)
    if ms.spectral_albedo:  # spectral variants: the medium's (grey) albedo at the lanes' wavelengths
        albedo = dr.select(sigma_t > 0.0, ms.medium.phase_function().albedo_at(mei, albedo[0]), 0.0)
    return mei, (mi.Spectrum(albedo) if mi.is_spectral else albedo)  # select gives an Array4f there


def phase_ctx(sampler):
    """A phase-function context; the persistent-lane renderer's samplers (``lanes.job_sampler_class``) are not
    Mitsuba samplers, and no phase function used here reads the context's sampler."""
    return mi.PhaseFunctionContext(sampler if isinstance(sampler, mi.Sampler) else None)


class Tracking:
    """The per-render state of the trackers (:mod:`.trackers`).

    Attributes
    ----------
    ms : MediumSetup
        The scene's medium.
    to_local : mi.Transform4f
        World to the unit cube of the sigma_t grid.
    coarse, texel : dda.Grid
        The coarse majorant grid and the texel-cell grid (None without a sigma_t grid).
    track : dda.Grid
        The grid of free flights and ratio tracking (``texel`` or ``coarse``).
    texel_data : tuple or None
        (sigma_t data, scale) of a grey sigma_t grid, for interpolating in a texel cell; else None.
    periodic : str
        "none", or periodic in x and y (:mod:`weather_mi.optics.periodic`): "view" or "transport" (camera
        rays meet the medium in the grid's own box only).
    reach : int
        Periods walked beyond the grid on each side when periodic.
    """

    def __init__(self, ms, to_local=None, coarse=None, texel=None, track=None, texel_data=None,
                 periodic: str = "none", reach: int = 0):
        self.ms, self.to_local = ms, to_local
        self.coarse, self.texel, self.track, self.texel_data = coarse, texel, track, texel_data
        self.periodic, self.reach = periodic, int(reach)

    def bounds(self, tile_only=None):
        """``dda.ray_box``'s bounds: None (the unit cube), or periodic the extended box in x and y (the unit
        cube on the lanes ``tile_only``, camera rays in "transport" mode)."""
        if self.periodic == "none":
            return None
        r0, r1 = mi.Float(-float(self.reach)), mi.Float(1.0 + self.reach)
        if tile_only is not None:
            r0, r1 = dr.select(tile_only, 0.0, r0), dr.select(tile_only, 1.0, r1)
        return [(r0, r1), (r0, r1), (0.0, 1.0)]


class GridCache:
    """The DDA grids of an integrator, rebuilt only when their data change (keys: the Dr.Jit index of the
    data, the scale and the shape)."""

    def __init__(self):
        self.skip = self.skip_key = None
        self.texel_arrays = self.texel_key = None

    def coarse(self, majorant, vol, scale: float, cell: int) -> Grid:
        """The coarse grid of ``majorant`` (TensorXf (Z, Y, X), 1/m), checked against the medium's sigma_t
        grid ``vol`` (None: the coarse cells tile the unit cube): its shape must be ceil(fine shape / cell)
        and its maximum must bound the medium's maximum sigma_t (a stale grid raises instead of biasing)."""
        nz, ny, nx = (int(s) for s in majorant.shape[:3])
        if vol is not None:
            rx, ry, rz = (int(v) for v in vol.resolution())
            expect = tuple(-(-n // cell) for n in (rz, ry, rx))
            if expect != (nz, ny, nx):
                raise RuntimeError(
                    f"{PLUGIN_NAME}: majorant grid {(nz, ny, nx)} does not match the sigma_t grid {(rz, ry, rx)} "
                    f"with cell = {cell} (expected {expect}); rebuild it with majorant_grid(..., cell)")
            cells_per_unit = (rx / cell, ry / cell, rz / cell)
            # cheap staleness guard: the grid must bound the medium's maximum
            vmax = float(vol.max()) * scale
            mmax = float(np.max(majorant.numpy()))
            if vmax > mmax * (1.0 + 1e-5) + 1e-30:
                raise RuntimeError(
                    f"{PLUGIN_NAME}: the majorant grid (max {mmax:g}) is below the medium's maximum sigma_t "
                    f"({vmax:g} = grid max x scale): it is stale; rebuild it from the current data")
        else:
            cells_per_unit = (nx, ny, nz)
        # opaque: new resolutions / values do not recompile
        maj_key = (majorant.array.index, tuple(majorant.shape))
        if maj_key != self.skip_key:
            self.skip = mi.Int32(empty_space_radius(majorant.numpy()).ravel())
            self.skip_key = maj_key
        return Grid(majorant.array, self.skip, (nx, ny, nz), cells_per_unit, shift=0.0, lo=0)

    def texel(self, vol, scale: float, reach: int | None = None, air=None, grey_air: bool = False, levels=None):
        """(The texel-centre grid, (data, scale) of a grey grid or None); (None, None) without a sigma_t
        grid. Its cells lie between 2 x 2 x 2 texel centres (cells -1 .. N - 1 per axis, the first and last
        halves cut by the box), where the trilinear interpolant is one trilinear polynomial; majorant =
        SAFETY x the maximum of the cell's 8 texels, which is the maximum of the interpolant there.
        ``reach``: periodic in x and y, walked over that many periods on each side (cells 0 .. N - 1 there,
        between texels i and i + 1 modulo N). ``air``: the box's air per level (``air_levels``), whose cells
        count as empty (majorant 0 here; the trackers use the air's own); ``grey_air``: the trackers' extinction is
        grey (not spectral), the air's one channel (``air_levels.AirLevels`` grey); ``levels``: the trackers' air
        object where already built (the medium's, ``MediumSetup.add_air``: an ``AirLevels``; spectral variants:
        ``spectral_air.ComponentAirLevels``, ``air`` then its (levels, K) table over wavelength, which the
        majorants bound)."""
        if vol is None:
            return None, None
        data = volume_data(vol)
        periodic = reach is not None
        key = (data.array.index, scale, periodic, None if air is None else air.tobytes())
        if key != self.texel_key:
            grid = np.asarray(data)  # the medium's grid in place (llvm); scaled in a copy only where scale != 1
            maj = texel_majorant_grid(grid if scale == 1.0 else grid * scale, periodic=periodic)
            if air is not None:
                if scale != 1.0:
                    raise RuntimeError(f"{PLUGIN_NAME}: the medium's air ('air_extinction') needs its scale 1, got {scale}")
                if grid.ndim == 3 or grid.shape[-1] == 1:  # a grey grid of the hydrometeors: the air added per level
                    air_levels.with_texel_air(maj, air)
                else:  # the air in the grid
                    maj[~air_levels.cloud_cells(grid, air, periodic)] = 0.0
            del grid
            empty = empty_space_radius(maj, periodic=True) if periodic else empty_space_radius(maj)
            self.texel_arrays = (mi.Float(maj.ravel()), mi.Int32(empty.ravel()))
            self.texel_key = key
        rx, ry, rz = (int(v) for v in vol.resolution())
        texel_data = (data.array, dr.opaque(mi.Float, float(scale))) if data.shape[-1] == 1 else None
        dims = (rx, ry, rz + 1) if periodic else (rx + 1, ry + 1, rz + 1)
        grid = Grid(*self.texel_arrays, dims, (rx, ry, rz), shift=-0.5, lo=-1, reach=reach)
        grid.air = None if air is None else levels if levels is not None else air_levels.AirLevels(air, grey=grey_air)
        return grid, texel_data
