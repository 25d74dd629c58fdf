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
from . import microphysics, thompson_graupel
from .size_distributions import combined_radius

RADIUS_VARS = {"cloud": "RE_CLOUD", "ice": "RE_ICE", "snow": "RE_SNOW"}
RADIUS_UNITS = {"m": 1.0, "meter": 1.0, "meters": 1.0, "metre": 1.0, "um": 1e-6, "micron": 1e-6, "microns": 1e-6,
                "micrometer": 1e-6, "micrometers": 1e-6, "µm": 1e-6, "μm": 1e-6, "1e-6 m": 1e-6}
LARGEST_RADIUS_M = 0.02  # no hydrometeor's effective radius reaches 2 cm: a larger value is in the wrong units
SMALLEST_RADIUS_M = 1e-7  # nor is one below 0.1 um (WRF's RE_* floor is 2.51 um): metres labelled um


class SizeReader:
    """Where each species' effective radius comes from in one wrfout time (``radius``), and what was used
    (``attrs``). ``t_k``: the native temperature (K), set by the reader where ``needs_temperature``."""

    def __init__(self, ds, path, read_field, mp, scheme, present, sizes: bool, stacklevel: int = 2):
        self.ds, self.path, self.read_field, self.scheme = ds, path, read_field, scheme
        self.file_vars = {n: RADIUS_VARS[n] for n in present if RADIUS_VARS.get(n) in ds}
        version = thompson_graupel.version_of(ds.attrs.get("TITLE"))
        rules = microphysics.rules(mp, ds.variables, version) if sizes else {}
        hail = rules.pop("hail", None)
        self.rules = {n: r for n, r in rules.items() if n in present and n not in self.file_vars}
        # hail is drawn as graupel: its own rule where the scheme has one, combined with graupel's radius
        self.hail_rule = hail if "QHAIL" in ds and "graupel" in self.rules else None
        self.per_m3 = mp in microphysics.WDM_FAMILY
        self.needs_temperature = any(r.needs_temperature for r in self.rules.values())
        self.t_k = None
        self.ranges: dict[str, tuple[float, float]] = {}
        lacking = [n for n in present if n not in self.rules and n not in self.file_vars]
        if sizes and "QHAIL" in ds and "graupel" in self.rules and self.hail_rule is None:
            warnings.warn(f"{path}: {scheme}: QHAIL is sized with graupel's rule (no hail rule or number "
                          "concentration for it)", stacklevel=stacklevel)
        if sizes and lacking:
            why = (f"weather-mi has no size rules for {scheme} microphysics" if not microphysics.has_rules(mp) else
                   f"{scheme}: " + "; ".join(microphysics.why_unsized(mp, n) for n in lacking))
            warnings.warn(f"{path}: {why}: the {', '.join(lacking)} radii are the species table's "
                          "(--sizes physical/paper), not the scheme's", stacklevel=stacklevel)

    def radius(self, name, rho_q, rho, shape, hail=None):
        """The effective radius (m, float32, native grid) of species ``name`` with mass content ``rho_q``
        (kg/m^3; for graupel, ``hail``: the hail's, sized by ``hail_rule`` and combined), or None where neither
        the file nor the scheme gives one; ``read_field(var, shape)`` reads a native field (float32, checked
        finite)."""
        if name in self.file_vars:
            r = self._file_radius(self.file_vars[name], rho_q, shape)
        elif name in self.rules:
            r = self._rule_radius(self.rules[name], rho_q, rho, shape, hail)
        else:
            return None
        has = rho_q > 0 if hail is None else (rho_q > 0) | (hail > 0)
        if np.any(has):
            self.ranges[name] = (float(r[has].min()), float(r[has].max()))
        return r

    def _rule_radius(self, rule, rho_q, rho, shape, hail=None):
        r, inputs = self._sized(rule, rho_q, rho, shape)
        if hail is not None and self.hail_rule is not None and np.any(hail > 0):
            h = self.hail_rule
            r_hail, hail_inputs = self._sized(h, hail, rho, shape)  # each field read once (its volume's too)
            parts = [(r, self._volume(rule, rho_q, inputs)), (r_hail, self._volume(h, hail, hail_inputs))]
            both = combined_radius(parts)
            r = np.where(hail > 0, np.where(rho_q > 0, both, r_hail), r)
        return r

    def _sized(self, rule, rho_q, rho, shape):
        """(``rule``'s radius of the mass content ``rho_q``, the inputs it read: ``_volume`` reuses them)."""
        inputs = {k: self._input(k, rho, shape) for k in rule.inputs}
        number = self._number(rule.number_var, rho, shape) if rule.number_var is not None else None
        return rule.radius(rho_q, number, self.t_k, **inputs), inputs

    def _number(self, var, rho, shape):
        """Number concentration ``var`` (m^-3), checked >= 0."""
        number = self._checked(var, shape, "number concentrations >= 0")
        if not self.per_m3:
            number *= rho  # per kg of dry air -> per m^3
        return number

    def _input(self, key, rho, shape):
        """A rule's extra input: "rho", a number concentration QN* (m^-3), a particle volume QV* (m^3/m^3,
        >= 0) or a mass content Q* (kg/m^3, negatives as zero)."""
        if key == "rho":
            return rho
        if key.startswith("QN"):
            return self._number(key, rho, shape)
        if key.startswith("QV") and key != "QVAPOR":
            field = self._checked(key, shape, "particle volumes (m^3 per kg) >= 0")
        else:
            field = np.maximum(self.read_field(key, shape), 0.0)
        field *= rho
        return field

    def _checked(self, var, shape, expectation):
        field = self.read_field(var, shape)
        if np.any(field < 0):
            raise WeatherDataError(self.path, var, expectation, f"{int(np.count_nonzero(field < 0))} negative "
                                   f"values (minimum {float(field.min()):.3g})")
        return field

    @staticmethod
    def _volume(rule, rho_q, inputs):
        """The particle volume per m^3 of air of ``rule``'s category: its predicted volume where the file has
        one (above 1e-30; ``inputs``: what the rule read, its ``volume_var`` among them), else rho_q over the
        rule's density."""
        fixed = np.asarray(rho_q, np.float64) / rule.density
        if rule.volume_var and inputs.get(rule.volume_var) is not None:
            v = np.asarray(inputs[rule.volume_var], np.float64)
            return np.where(v > 1e-30, v, fixed)
        return fixed

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
        sized = r[(rho_q > 0) & (r > 0)]
        largest, smallest = (float(sized.max()), float(sized.min())) if sized.size else (0.0, 0.0)
        if largest > LARGEST_RADIUS_M or 0 < smallest < SMALLEST_RADIUS_M:
            raise WeatherDataError(self.path, var, f"effective radii from {SMALLEST_RADIUS_M} to {LARGEST_RADIUS_M} m "
                                   f"in its units ({units or 'none given'})",
                                   f"{smallest:.3g} to {largest:.3g} m where the species is: wrong units")
        return r

    def attrs(self) -> dict:
        """What sized each species, and the native range of its radii (um), for the Hydrometeors' attributes."""
        out = {}
        for name, var in self.file_vars.items():
            out[f"r_eff_source_{name}"] = f"file {var}"
        for name, rule in self.rules.items():
            out[f"r_eff_source_{name}"] = f"{self.scheme}: {rule.formula}"
        if self.hail_rule is not None:
            out["r_eff_source_graupel"] += f"; with QHAIL: {self.hail_rule.formula} (combined, 0.5 sum M3 / sum M2)"
        for name, (lo, hi) in self.ranges.items():
            out[f"r_eff_native_um_{name}"] = f"{1e6 * lo:.4g}..{1e6 * hi:.4g}"
        return out
