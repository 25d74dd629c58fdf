"""The effective radius of each species on a wrfout's native grid, for ``weather_mi.io.wrfout``: the file's
RE_CLOUD / RE_ICE / RE_SNOW where it has them (their ``units`` attribute read: m or um), else the scheme's own
size distributions (``weather_mi.io.microphysics``) from the mass content, the number concentrations
(QN*: per kg of dry air, times the density; WDM's per m^3, as ``module_mp_wdm6.F`` uses them) and the
temperature. Bad input is named before anything is rendered: a negative number concentration, an RE_* whose
values do not fit its units; a scheme whose sizes are unknown gets a warning naming it and the fallback.
"""
from __future__ import annotations

import warnings

import numpy as np

from ..errors import WeatherDataError
from . import microphysics

RADIUS_VARS = {"cloud": "RE_CLOUD", "ice": "RE_ICE", "snow": "RE_SNOW"}
RADIUS_UNITS = {"m": 1.0, "meter": 1.0, "meters": 1.0, "metre": 1.0, "um": 1e-6, "micron": 1e-6, "microns": 1e-6,
                "micrometer": 1e-6, "micrometers": 1e-6, "µm": 1e-6, "μm": 1e-6, "1e-6 m": 1e-6}
LARGEST_RADIUS_M = 0.02  # no hydrometeor's effective radius reaches 2 cm: a larger value is in the wrong units


class SizeReader:
    """Where each species' effective radius comes from in one wrfout time (``radius``), and what was used
    (``attrs``). ``t_k``: the native temperature (K), set by the reader where ``needs_temperature``."""

    def __init__(self, ds, path, read_field, mp, scheme, present, sizes: bool, stacklevel: int = 2):
        self.ds, self.path, self.read_field, self.scheme = ds, path, read_field, scheme
        self.file_vars = {n: RADIUS_VARS[n] for n in present if RADIUS_VARS.get(n) in ds}
        rules = microphysics.rules(mp, ds.variables) if sizes else {}
        self.rules = {n: r for n, r in rules.items() if n in present and n not in self.file_vars}
        self.per_m3 = mp in microphysics.WDM_FAMILY
        self.needs_temperature = any(r.needs_temperature for r in self.rules.values())
        self.t_k = None
        self.ranges: dict[str, tuple[float, float]] = {}
        lacking = [n for n in present if n not in self.rules and n not in self.file_vars]
        if sizes and lacking:
            why = (f"weather-mi has no size rules for {scheme} microphysics" if not rules else
                   f"{scheme} sizes them from number concentrations the file lacks "
                   f"({', '.join(microphysics.NUMBER_VARS[n] for n in lacking)})")
            warnings.warn(f"{path}: {why}: the {', '.join(lacking)} radii are the species table's "
                          "(--sizes physical/paper), not the scheme's", stacklevel=stacklevel)

    def radius(self, name, rho_q, rho, shape):
        """The effective radius (m, float32, native grid) of species ``name`` with mass content ``rho_q``
        (kg/m^3), or None where neither the file nor the scheme gives one; ``read_field(var, shape)`` reads a native
        field (float32, checked finite)."""
        if name in self.file_vars:
            r = self._file_radius(self.file_vars[name], rho_q, shape)
        elif name in self.rules:
            rule = self.rules[name]
            number = None
            if rule.number_var is not None:
                number = self.read_field(rule.number_var, shape)
                if np.any(number < 0):
                    raise WeatherDataError(self.path, rule.number_var, "number concentrations >= 0",
                                           f"{int(np.count_nonzero(number < 0))} negative values "
                                           f"(minimum {float(number.min()):.3g})")
                if not self.per_m3:
                    number *= rho  # per kg of dry air -> per m^3
            r = rule.radius(rho_q, number, self.t_k)
            del number
        else:
            return None
        has = rho_q > 0
        if np.any(has):
            self.ranges[name] = (float(r[has].min()), float(r[has].max()))
        return r

    def clip_to_native(self, name, r_cell, mass) -> None:
        """Keep the regridded radii (m, in place) within the native range of species ``name``'s, and give the
        cells with mass but no radius (the two reconstructions disagreeing at a tiny content) the largest."""
        if name in self.ranges:
            lo, hi = self.ranges[name]
            r_cell[(r_cell <= 0) & (mass > 0)] = np.float32(hi)
            np.clip(r_cell, np.float32(lo), np.float32(hi), out=r_cell, where=r_cell > 0)

    def _file_radius(self, var, rho_q, shape):
        r = np.maximum(self.read_field(var, shape), 0.0)
        units = str(self.ds[var].attrs.get("units", "")).strip()
        if units:
            if units.lower() not in RADIUS_UNITS:
                raise WeatherDataError(self.path, var, f"an effective radius in one of {sorted(RADIUS_UNITS)} "
                                       "(its units attribute)", repr(units))
            r *= np.float32(RADIUS_UNITS[units.lower()])
        elif r.size and float(r.max()) > LARGEST_RADIUS_M:  # no units: micrometres where metres cannot be
            r *= np.float32(1e-6)
        largest = float(r[rho_q > 0].max()) if np.any(rho_q > 0) else 0.0
        if largest > LARGEST_RADIUS_M:
            raise WeatherDataError(self.path, var, f"effective radii below {LARGEST_RADIUS_M} m in its units "
                                   f"({units or 'none given'})", f"up to {largest:.3g} m: wrong units")
        return r

    def attrs(self) -> dict:
        """What sized each species, and the native range of its radii (um), for the Hydrometeors' attributes."""
        out = {}
        for name, var in self.file_vars.items():
            out[f"r_eff_source_{name}"] = f"file {var}"
        for name, rule in self.rules.items():
            out[f"r_eff_source_{name}"] = f"{self.scheme}: {rule.formula}"
        for name, (lo, hi) in self.ranges.items():
            out[f"r_eff_native_um_{name}"] = f"{1e6 * lo:.4g}..{1e6 * hi:.4g}"
        return out
