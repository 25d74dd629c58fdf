"""The box's air per level at a path's wavelengths (spectral variants): ``air_levels.AirLevels`` over the K nodes
of a uniform wavelength grid (``optics.air.spectral_levels``: (levels, K) tables, 1/m) in place of the RGB mode's
three channels, read per lane linearly in wavelength between the two nodes about the lane's wavelength (held
beyond the grid's ends).

Both the extinction at a point and the closed-form optical depth are linear in the table's values, so reading
each node's and interpolating in wavelength is the optical depth of the interpolated extinction, exactly (the
trackers' free flights and ratio tracking then see one medium). At a node (450, 550, 650 nm on the 5 nm grid) the
weight of the other node is 0 and the values are the RGB mode's channel's, to the last bit
(``tests/test_spectral_air.py``).

``majorant_volpath`` takes the tables as ``air_extinction`` and ``air_scattering`` (levels, K) with ``air_nm`` (K,)
(:func:`parse`); the trackers read them through :func:`bind_air`, which fixes a walk's lanes' wavelengths (its ray's),
so that they call ``sigma_at`` and ``tau`` as they do the RGB mode's ``AirLevels``.
"""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

from .air_levels import AirLevels


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

    def bind(self, wavelengths):
        """This air at the lanes' ``wavelengths`` (nm): an object with ``AirLevels``' ``sigma_at``, ``tau`` and
        ``cube_bound`` without the wavelengths argument (the trackers' calls)."""
        return _Bound(self, wavelengths)

    def sigma_at(self, q, active, wavelengths=None):
        """sigma (mi.Spectrum, 1/m) at texel-centre coordinate q and the lanes' ``wavelengths`` (nm)."""
        return self._by_lane(wavelengths, lambda ch: self.sigma_channels(q, ch, active))

    def tau(self, qz0, dqz, t0, t1, active, wavelengths=None):
        """Optical depth (mi.Spectrum) over [t0, t1] of a ray with z texel coordinate qz0 + dqz t (``AirLevels.tau``)
        at the lanes' ``wavelengths`` (nm)."""
        return self._by_lane(wavelengths, lambda ch: self.tau_channels(qz0, dqz, t0, t1, ch, active))


class _Bound:
    """``SpectralAirLevels`` at fixed lanes' wavelengths (:meth:`SpectralAirLevels.bind`)."""

    grey = False

    def __init__(self, levels: SpectralAirLevels, wavelengths):
        self.levels, self.wavelengths = levels, wavelengths

    def cube_bound(self, cz, k, lo: int, active):
        return self.levels.cube_bound(cz, k, lo, active)  # the largest over every wavelength of the grid

    def sigma_at(self, q, active):
        return self.levels.sigma_at(q, active, self.wavelengths)

    def tau(self, qz0, dqz, t0, t1, active):
        return self.levels.tau(qz0, dqz, t0, t1, active, self.wavelengths)


def bind_air(air, wavelengths):
    """The trackers' air (``dda.Grid.air``: None, ``AirLevels`` or :class:`SpectralAirLevels`) at a walk's lanes'
    ``wavelengths``: a spectral one bound to them, the others as they are."""
    return air.bind(wavelengths) if isinstance(air, SpectralAirLevels) else air


NM_PROPERTY = "air_nm"


def parse(props, check):
    """``majorant_volpath``'s spectral air: (``air_extinction`` (levels, K) float32 numpy, ``air_nm`` (K,) the
    uniform ascending wavelengths, nm) where ``air_nm`` is given (spectral variants only), else None."""
    if NM_PROPERTY not in props:
        return None
    check(bool(mi.is_spectral), f"'{NM_PROPERTY}' (the box's air over wavelength) needs a spectral variant, "
                                f"not {mi.variant()!r}")
    from .air_levels import PROPERTY
    nm = np.asarray(props[NM_PROPERTY], np.float64).ravel()
    check(PROPERTY in props, f"'{NM_PROPERTY}' needs '{PROPERTY}'")
    a = np.asarray(props[PROPERTY], np.float32)
    check(a.ndim == 2 and a.shape[0] >= 1 and a.shape[1] == nm.size >= 2 and np.all(np.isfinite(a)) and a.min() >= 0
          and np.all(np.diff(nm) > 0) and np.allclose(np.diff(nm), nm[1] - nm[0]),
          f"'{PROPERTY}' must be a finite, non-negative (levels, K) tensor on the K uniform ascending wavelengths "
          f"'{NM_PROPERTY}'; got shape {np.shape(props[PROPERTY])} on {nm.size} wavelengths")
    return np.ascontiguousarray(a), nm


__all__ = ["SpectralAirLevels", "bind_air", "parse"]
