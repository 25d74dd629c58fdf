"""The box's air per level at a path's wavelengths (spectral variants): ``air_levels.AirLevels`` over the K nodes
of a uniform wavelength grid (``optics.air.spectral_levels``: (levels, K) tables, 1/m) in place of the RGB mode's
three channels, read per lane linearly in wavelength between the two nodes about the lane's wavelength (held
beyond the grid's ends).

Both the extinction at a point and the closed-form optical depth are linear in the table's values, so reading
each node's and interpolating in wavelength is the optical depth of the interpolated extinction, exactly (the
trackers' free flights and ratio tracking then see one medium). At a node (450, 550, 650 nm on the 5 nm grid) the
weight of the other node is 0 and the values are the RGB mode's channel's, to the last bit
(``tests/test_spectral_air.py``).

The kernel reads the same air factored (:class:`ComponentAirLevels`, ``optics.air.spectral_levels.
FactoredAirLevels``: molecules, ozone and aerosol each a profile over the levels times a spectrum): three values per
level as the RGB mode's three channels, and each lane's three spectral factors once per ray, where the table
took eight values per level (two nodes for each of 4 lanes); the same numbers to float rounding
(``tests/test_spectral_box_air.py``). :class:`SpectralAirLevels` (the tables) is its reference.
``majorant_volpath`` takes it from :func:`parse`; the trackers read it through :func:`bind_air`, which fixes a walk's
lanes' wavelengths (its ray's), so that they call ``sigma_at`` and ``tau`` as they do the RGB mode's ``AirLevels``.
"""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

from ..jitarrays import aligned_float
from .air_levels import AirLevels
from .majorants import SAFETY


class SpectralAirLevels(AirLevels):
    """``AirLevels`` of a (levels, K) table on the uniform wavelengths ``grid_nm`` (K,); ``sigma_at`` and ``tau``
    take the lanes' ``wavelengths`` (nm) and return an ``mi.Spectrum`` (one value per lane)."""

    def __init__(self, table: np.ndarray, grid_nm):
        grid = np.asarray(grid_nm, np.float64).ravel()
        table = np.asarray(table, np.float32)
        if table.ndim != 2 or table.shape[1] != grid.size or grid.size < 2 or np.any(np.diff(grid) <= 0) or \
                not np.allclose(np.diff(grid), grid[1] - grid[0]) or not np.all(np.isfinite(table)) or table.min() < 0:
            raise ValueError(f"the air's spectral table must be (levels, K), finite and >= 0, on K uniform ascending "
                             f"wavelengths; got {table.shape} on {grid.size} wavelengths")
        super().__init__(table)
        self.grid = (float(grid[0]), float(1.0 / (grid[1] - grid[0])), int(grid.size))

    def _nodes(self, wavelength):
        """(node j (UInt32), node j + 1, weight of j + 1) of a lane's wavelength (nm) on the grid."""
        lo, inv_step, k = self.grid
        u = dr.clip((wavelength - lo) * inv_step, 0.0, k - 1.0)
        j = dr.minimum(mi.UInt32(u), k - 2)
        return j, j + 1, u - mi.Float(j)

    def _by_lane(self, wavelengths, read):
        """mi.Spectrum of ``read(channels)`` (two Floats, the nodes' values) blended per lane in wavelength."""
        out = []
        for lane in range(len(wavelengths)):
            j0, j1, t = self._nodes(wavelengths[lane])
            a, b = read((j0, j1))
            out.append(dr.fma(b - a, t, a))
        return mi.Spectrum(*out)

    def sigma_at(self, q, active, wavelengths=None):
        """sigma (mi.Spectrum, 1/m) at texel-centre coordinate q and the lanes' ``wavelengths`` (nm)."""
        return self._by_lane(wavelengths, lambda ch: self.sigma_channels(q, ch, active))

    def tau(self, qz0, dqz, t0, t1, active, wavelengths=None):
        """Optical depth (mi.Spectrum) over [t0, t1] of a ray with z texel coordinate qz0 + dqz t (``AirLevels.tau``)
        at the lanes' ``wavelengths`` (nm)."""
        return self._by_lane(wavelengths, lambda ch: self.tau_channels(qz0, dqz, t0, t1, ch, active))


class ComponentAirLevels(AirLevels):
    """The box's air as components m (``optics.air.spectral_levels.FactoredAirLevels``): sigma(z, lambda) = sum_m
    p_m(z) F_m(lambda), ``AirLevels`` of the profiles (levels, M) (its M channels: lerp in z, the closed-form
    cumulative) times each lane's spectral factors F_m (linear between the nodes of ``grid_nm``, held beyond), read
    once per ray (:meth:`factors`). A ray's cube bounds (:meth:`bind`) are sum_m B_m(cube) max_lanes F_m, B_m the
    component's largest profile value at or above the cube (SAFETY x, as ``AirLevels``' over channels): the air at
    the path's 4 wavelengths, not at the grid's bluest (where molecules are 2.4x the 450 nm ones), so a ray in the
    thin air makes fewer null collisions. ``bound`` (for ``cube_bound`` without lanes) is the (levels, K) table's at
    every node (a linear interpolant's largest value is at a node). ``albedo`` (M,) each component's single-scattering
    albedo."""

    def __init__(self, profiles: np.ndarray, spectra: np.ndarray, grid_nm, albedo):
        grid = np.asarray(grid_nm, np.float64).ravel()
        p, f = np.asarray(profiles, np.float32), np.asarray(spectra, np.float32)
        a = np.asarray(albedo, np.float64).ravel()
        if p.ndim != 2 or f.ndim != 2 or f.shape != (grid.size, p.shape[1]) or a.size != p.shape[1] or \
                grid.size < 2 or np.any(np.diff(grid) <= 0) or not np.allclose(np.diff(grid), grid[1] - grid[0]) or \
                not (np.all(np.isfinite(p)) and np.all(np.isfinite(f)) and p.min() >= 0 and f.min() >= 0) or \
                not np.all((a >= 0) & (a <= 1)):
            raise ValueError(f"the air's components must be profiles (levels, M) and spectra (K, M), finite and >= 0, "
                             f"on K uniform ascending wavelengths, with M albedos in [0, 1]; got {p.shape}, {f.shape}, "
                             f"{grid.size} wavelengths, {a.size} albedos")
        super().__init__(p)
        self.full = (p.astype(np.float64) @ f.astype(np.float64).T).astype(np.float32)  # (levels, K): the majorants'
        self.bound = AirLevels(self.full).bound  # the largest over the grid's wavelengths
        n = p.shape[0]
        lo, hi = p[np.clip(np.arange(n + 1) - 1, 0, n - 1)], p[np.clip(np.arange(n + 1), 0, n - 1)]
        cell = (np.maximum(lo, hi) * SAFETY).astype(np.float32)  # per component, texel cells -1 .. n - 1
        self.bound_m = aligned_float(mi, np.ascontiguousarray(np.maximum.accumulate(cell[::-1], axis=0)[::-1]))
        self.m, self.albedo = p.shape[1], [float(v) for v in a]
        self.packets = -(-2 * self.m // 4)
        rec = np.zeros((grid.size - 1, 4 * self.packets), np.float32)  # per cell j: F_m(j), F_m(j + 1) for every m
        rec[:, 0:2 * self.m:2], rec[:, 1:2 * self.m:2] = f[:-1], f[1:]
        self.spectra = aligned_float(mi, rec)
        self.grid = (float(grid[0]), float(1.0 / (grid[1] - grid[0])), int(grid.size))

    def factors(self, wavelengths):
        """The M spectral factors at the lanes' ``wavelengths`` (nm): a list of M mi.Spectrum (:meth:`bind` adds each
        one's largest over the lanes)."""
        lo, inv_step, k = self.grid
        lanes = []
        for lane in range(len(wavelengths)):
            u = dr.clip((wavelengths[lane] - lo) * inv_step, 0.0, k - 1.0)
            j = dr.minimum(mi.UInt32(u), k - 2)
            t = u - mi.Float(j)
            e = []
            for p in range(self.packets):
                packet = dr.gather(mi.Vector4f, self.spectra, j * self.packets + p)
                e += [packet[c] for c in range(4)]
            lanes.append([dr.fma(e[2 * m + 1] - e[2 * m], t, e[2 * m]) for m in range(self.m)])
        return [mi.Spectrum(*(lanes[i][m] for i in range(len(lanes)))) for m in range(self.m)]

    def bind(self, wavelengths):
        """This air at the lanes' ``wavelengths`` (nm): ``AirLevels``' calls, the factors read once."""
        f = self.factors(wavelengths)
        return _Bound(self, f, [dr.max(fm) for fm in f])

    def lanes_bound(self, cz, k, lo: int, fmax, active):
        """The majorant of the empty cube of radius ``k`` about texel cell level ``cz`` at the lanes whose factors'
        largest values are ``fmax`` (M Floats): sum_m B_m fmax_m (class docstring)."""
        i = mi.UInt32(dr.clip(cz - k - lo, 0, self.n)) * self.m
        out = mi.Float(0.0)
        for m in range(self.m):
            out = dr.fma(dr.gather(mi.Float, self.bound_m, i + m, active), fmax[m], out)
        return out

    def combine(self, values, factors, weights=None):
        """sum_m values[m] factors[m] (x weights[m]; terms of weight 0 left out): mi.Spectrum."""
        out = None
        for m in range(self.m):
            w = 1.0 if weights is None else weights[m]
            if w != 0.0:
                term = values[m] * factors[m] * w if w != 1.0 else values[m] * factors[m]
                out = term if out is None else out + term
        return mi.Spectrum(0.0) if out is None else out

    def sigma_at(self, q, active, wavelengths=None, factors=None):
        """sigma (mi.Spectrum, 1/m) at texel-centre coordinate q, at the lanes' ``wavelengths`` (or their
        :meth:`factors`)."""
        f = self.factors(wavelengths) if factors is None else factors
        return self.combine(self.sigma_channels(q, range(self.m), active), f)

    def extinction_scattering(self, q, active, factors):
        """(sigma_t, sigma_s) of the air (mi.Spectrum, 1/m) at q: the components read once."""
        c = self.sigma_channels(q, range(self.m), active)
        return self.combine(c, factors), self.combine(c, factors, self.albedo)

    def tau(self, qz0, dqz, t0, t1, active, wavelengths=None, factors=None):
        """Optical depth (mi.Spectrum) over [t0, t1] of a ray with z texel coordinate qz0 + dqz t (``AirLevels.tau``)
        at the lanes' ``wavelengths`` (or their :meth:`factors`)."""
        f = self.factors(wavelengths) if factors is None else factors
        return self.combine(self.tau_channels(qz0, dqz, t0, t1, range(self.m), active), f)


class _Bound:
    """``ComponentAirLevels`` at fixed lanes' spectral factors (:meth:`ComponentAirLevels.bind`)."""

    grey = False

    def __init__(self, levels: ComponentAirLevels, factors, fmax):
        self.levels, self.f, self.fmax = levels, factors, fmax

    def cube_bound(self, cz, k, lo: int, active):
        return self.levels.lanes_bound(cz, k, lo, self.fmax, active)  # at the ray's wavelengths

    def sigma_at(self, q, active):
        return self.levels.sigma_at(q, active, factors=self.f)

    def tau(self, qz0, dqz, t0, t1, active):
        return self.levels.tau(qz0, dqz, t0, t1, active, factors=self.f)


def bind_air(air, wavelengths):
    """The trackers' air (``dda.Grid.air``: None, ``AirLevels`` or :class:`ComponentAirLevels`) at a walk's lanes'
    ``wavelengths``: a spectral one bound to them (its factors read once), the others as they are."""
    return air.bind(wavelengths) if isinstance(air, ComponentAirLevels) else air


PROPERTIES = ("air_spectra", "air_nm", "air_component_albedo")  # with "air_extinction" (levels, M): the profiles


def parse(props, check):
    """``majorant_volpath``'s spectral air, a :class:`ComponentAirLevels` from ``air_extinction`` (levels, M, the
    components' profiles, 1/m), ``air_spectra`` (K, M), ``air_nm`` (K,) and ``air_component_albedo`` (M,) where
    ``air_nm`` is given (spectral variants only); else None."""
    if not any(n in props for n in PROPERTIES):
        return None
    check(bool(mi.is_spectral), f"'air_nm' (the box's air over wavelength) needs a spectral variant, not {mi.variant()!r}")
    from .air_levels import PROPERTY
    check(all(n in props for n in PROPERTIES + (PROPERTY,)), f"the spectral air needs {PROPERTIES + (PROPERTY,)}")
    try:
        return ComponentAirLevels(props[PROPERTY], props["air_spectra"], props["air_nm"], props["air_component_albedo"])
    except ValueError as exc:
        check(False, f"'{PROPERTY}', 'air_spectra', 'air_nm', 'air_component_albedo': {exc}")


__all__ = ["SpectralAirLevels", "ComponentAirLevels", "bind_air", "parse"]
