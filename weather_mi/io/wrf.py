"""WRF ``wrfout`` NetCDF -> Hydrometeors (see weather_mi.hydrometeors for the contract).

Steps: select a time (index or timestamp) and an optional horizontal sub-box; heights of the w-levels
z_w = (PH + PHB) / g and of the mass levels as their mean (destaggering); dry-air density
rho_d = p / (R_d T (1 + 1.608 q_v)) with p = P + PB, T = (T' + 300 K)(p / 1e5)^(R_d/c_p)
(cross-checked against ALT = 1/rho_d when the file has it); species mass densities rho_d q regridded
conservatively onto a uniform height grid (weather_mi.io.vertical); the horizontal spacing DX, DY over
the mean map factor (weather_mi.io.map_factors, with a warning where it varies). Negative mixing ratios are clipped, counted and reported in a warning (count
and minimum per variable); species the scheme does not carry become zeros with a warning that names the
scheme, while a variable the scheme writes and the file lacks is an error (``schemes.SCHEME_VARS``).
"""
from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from ..errors import WeatherDataError
from ..hydrometeors import from_arrays, warn_clipped
from . import vertical
from .map_factors import horizontal_spacing
from .schemes import MP_SCHEMES, SCHEME_VARS

G = 9.81               # m/s^2, WRF's gravity
R_D = 287.0            # J/(kg K)
RD_OVER_CP = 0.2857
EPS_INV = 1.608        # R_v / R_d: virtual-temperature factor for the vapour mixing ratio
THETA0 = 300.0         # K, WRF's base potential temperature offset of T

SPECIES_VARS = {"cloud": "QCLOUD", "ice": "QICE", "rain": "QRAIN", "snow": "QSNOW", "graupel": "QGRAUP"}
RADIUS_VARS = {"cloud": "RE_CLOUD", "ice": "RE_ICE", "snow": "RE_SNOW"}
REQUIRED = ("P", "PB", "T", "PH", "PHB")
MAP_FACTOR_VARS = ("MAPFAC_M", "MAPFAC_MX", "MAPFAC_MY")



def _time_strings(ds: xr.Dataset) -> list[str]:
    if "Times" not in ds:
        return []
    out = []
    for t in np.atleast_1d(ds["Times"].values):
        s = t.decode() if isinstance(t, bytes) else ("".join(c.decode() for c in t) if np.ndim(t) else str(t))
        out.append(s.strip())
    return out


def wrf_times(path) -> list[str]:
    """The timestamps of a wrfout file, in order (their indices where it has no ``Times``)."""
    with _open(str(path)) as ds:
        return _time_strings(ds) or [str(i) for i in range(ds.sizes.get("Time", 1))]


def _normalise_time(t) -> np.datetime64:
    s = str(t).strip().replace("_", "T")
    return np.datetime64(s, "s")


def _time_index(ds: xr.Dataset, time, path: str) -> tuple[int, str]:
    n = ds.sizes.get("Time", 1)
    stamps = _time_strings(ds)
    if isinstance(time, (int, np.integer)):
        if not -n <= int(time) < n:
            raise WeatherDataError(path, "Times", f"a time index in [{-n}, {n - 1}]", str(time))
        i = int(time) % n
        return i, (stamps[i] if stamps else str(i))
    if not stamps:
        raise WeatherDataError(path, "Times", "a 'Times' variable to select a time by timestamp")
    try:
        want = _normalise_time(time)
        have = [_normalise_time(s) for s in stamps]
    except ValueError as exc:
        raise WeatherDataError(path, "Times", "a timestamp like 2005-09-21_03:00:00", repr(time)) from exc
    for i, h in enumerate(have):
        if h == want:
            return i, stamps[i]
    raise WeatherDataError(path, "Times", f"one of the file's times {stamps}", repr(str(time)))


def _read(ds, name, it, sel, path, shape=None) -> np.ndarray:
    da = ds[name]
    if "Time" in da.dims:
        da = da.isel(Time=it)
    da = da.isel({k: v for k, v in sel.items() if k in da.dims})
    a = np.asarray(da.values, dtype=np.float64)
    if shape is not None and a.shape != shape:
        raise WeatherDataError(path, name, f"shape {shape} (bottom_top, south_north, west_east)", f"shape {a.shape}")
    if not np.all(np.isfinite(a)):
        n = int(a.size - np.count_nonzero(np.isfinite(a)))
        raise WeatherDataError(path, name, "finite values", f"{n} NaN or infinite values")
    return a


def dry_air_density(p_pa, theta_k, qv):
    """rho_d = p / (R_d T (1 + 1.608 q_v)), T = theta (p / 1e5)^(R_d/c_p) (kg/m^3)."""
    t_k = theta_k * (p_pa / 1.0e5) ** RD_OVER_CP
    return p_pa / (R_D * t_k * (1.0 + EPS_INV * qv))


def open_wrf(path, time=None, *, x: slice | None = None, y: slice | None = None,
             dz: float | None = None, top: float | None = None, bottom: float | None = None) -> xr.Dataset:
    """Read one time of a wrfout file into Hydrometeors on a uniform height grid.

    time   : index (negative counts from the end) or timestamp ("2005-09-21_03:00:00" or ISO); or a
             slice, a list or "all": a time series with a ``time`` dimension (``weather_mi.io.series``).
             None: the last time of a file. A list of files is always read as a series (``time``
             counting through all their times in order; None: all of them).
    x, y   : optional slices of mass-point indices (west_east, south_north): a horizontal sub-box.
    dz     : vertical spacing (m); default the native mean layer depth.
    bottom, top : extent of the height grid (m above MSL); default lowest terrain to highest model top.
    """
    from .series import is_series, open_wrf_series
    if is_series(path, time):
        return open_wrf_series(path, "all" if time is None else time, x=x, y=y, dz=dz, top=top, bottom=bottom)
    time = -1 if time is None else time
    path = os.fspath(path)
    if not Path(path).is_file():
        raise WeatherDataError(path, None, "an existing wrfout NetCDF file", "no such file")
    with _open(path) as ds:
        return _convert(ds, path, time, x, y, dz, top, bottom)


def _open(path: str) -> xr.Dataset:
    try:
        return xr.open_dataset(path, decode_times=False, mask_and_scale=True, cache=False)
    except Exception as exc:  # netCDF4/h5py raise many types for non-NetCDF input
        raise WeatherDataError(path, None, "a NetCDF (wrfout) file", f"{type(exc).__name__}: {exc}") from exc


def _convert(ds, path, time, x, y, dz, top, bottom) -> xr.Dataset:
    missing = [v for v in REQUIRED if v not in ds]
    if missing:
        raise WeatherDataError(path, ", ".join(missing), f"the wrfout variables {', '.join(REQUIRED)}", "missing")
    it, stamp = _time_index(ds, time, path)
    sel = {}
    for dim, s in (("west_east", x), ("south_north", y)):
        if s is not None:
            if not isinstance(s, slice):
                raise WeatherDataError(path, dim, "a slice of mass-point indices", repr(s))
            sel[dim] = s
    p = _read(ds, "P", it, sel, path) + _read(ds, "PB", it, sel, path)
    shape = p.shape
    if len(shape) != 3 or min(shape) < 1:
        raise WeatherDataError(path, "P", "a (bottom_top, south_north, west_east) field", f"shape {shape}")
    theta = _read(ds, "T", it, sel, path, shape) + THETA0
    z_w = (_read(ds, "PH", it, sel, path) + _read(ds, "PHB", it, sel, path)) / G
    if z_w.shape != (shape[0] + 1,) + shape[1:]:
        raise WeatherDataError(path, "PH", f"shape {(shape[0] + 1,) + shape[1:]} on bottom_top_stag", f"shape {z_w.shape}")
    if not np.all(np.diff(z_w, axis=0) > 0):
        raise WeatherDataError(path, "PH+PHB", "geopotential heights increasing upward in every column")
    z_mass = 0.5 * (z_w[1:] + z_w[:-1])  # destagger

    mp = int(ds.attrs.get("MP_PHYSICS", -1))
    scheme = MP_SCHEMES.get(mp, f"MP_PHYSICS={mp}" if mp >= 0 else "unknown scheme")
    if "QVAPOR" in ds:
        qv = np.maximum(_read(ds, "QVAPOR", it, sel, path, shape), 0.0)
    else:
        warnings.warn(f"{path}: no QVAPOR; dry-air density computed without the vapour correction", stacklevel=3)
        qv = np.zeros(shape)
    rho = dry_air_density(p, theta, qv)
    attrs = {"source": path, "model": str(ds.attrs.get("TITLE", "WRF")).strip(), "time": stamp,
             "time_index": it, "microphysics": scheme, "mp_physics": mp}
    if "ALT" in ds:
        alt = _read(ds, "ALT", it, sel, path, shape)
        rel = float(np.max(np.abs(rho * alt - 1.0)))
        attrs["alt_max_rel_diff"] = rel
        if rel > 0.01:
            warnings.warn(f"{path}: dry-air density from P, PB, T, QVAPOR differs from 1/ALT by up to "
                          f"{100 * rel:.2f}%", stacklevel=3)

    written = SCHEME_VARS.get(mp, ())
    damaged = [v for v in written if v not in ds]
    if damaged:
        raise WeatherDataError(path, ", ".join(damaged), f"the mixing ratios that {scheme} microphysics "
                               f"(MP_PHYSICS={mp}) writes: {', '.join(written)}", "missing from the file")
    fields, lacking, negatives, minima = {}, [], {}, {}
    for name, var in SPECIES_VARS.items():
        if var not in ds:
            lacking.append(var)
            continue
        q = _read(ds, var, it, sel, path, shape)
        if name == "graupel" and "QHAIL" in ds:  # hail is the dense end of the rimed-ice spectrum
            q = q + _read(ds, "QHAIL", it, sel, path, shape)
        negatives[name] = int(np.count_nonzero(q < 0))
        if negatives[name]:
            minima[var] = (negatives[name], float(q.min()))
        fields[name] = np.maximum(q, 0.0)
    if minima:
        warn_clipped(path, minima, stacklevel=3)
    if not fields:
        raise WeatherDataError(path, "QCLOUD", "at least one hydrometeor mixing ratio (QCLOUD, QRAIN, ...)", "none")
    if lacking:
        warnings.warn(f"{path}: microphysics scheme {scheme} does not provide {', '.join(lacking)}; "
                      "those species are zero", stacklevel=3)
        attrs["species_missing"] = ", ".join(lacking)

    dz = float(dz) if dz is not None else float(np.mean(z_w[-1] - z_w[0]) / shape[0])
    z_lo = float(np.min(z_w[0])) if bottom is None else float(bottom)
    z_hi = float(np.max(z_w[-1])) if top is None else float(top)
    if not (dz > 0 and z_hi > z_lo):
        raise WeatherDataError(path, "dz/top", "dz > 0 and top above bottom", f"dz={dz}, bottom={z_lo}, top={z_hi}")
    nz = max(int(np.ceil((z_hi - z_lo) / dz - 1e-6)), 1)
    edges = z_lo + dz * np.arange(nz + 1)

    frac = vertical.above_ground_fraction(z_w, edges)
    rho_cell = vertical.cell_averages(z_mass, z_w, rho, edges)
    rho_above = np.where(frac > 0, rho_cell / np.maximum(frac, 1e-12), rho[0][None])  # air in the cell's open part
    q_new = {}
    for name, q in fields.items():
        mass = vertical.cell_averages(z_mass, z_w, rho * q, edges)  # kg/m^3 of this species, conserved
        q_new[name] = np.maximum(mass, 0.0) / rho_above
    r_eff = {}
    for name, var in RADIUS_VARS.items():
        if var in ds:
            r = np.maximum(_read(ds, var, it, sel, path, shape), 0.0)
            if name in fields:  # mass-weighted cell average of the radius
                num = vertical.cell_averages(z_mass, z_w, rho * fields[name] * r, edges)
                den = vertical.cell_averages(z_mass, z_w, rho * fields[name], edges)
                r_eff[name] = np.divide(num, den, out=np.zeros_like(num), where=den > 0)

    dx = float(ds.attrs.get("DX", 1000.0))
    dy = float(ds.attrs.get("DY", dx))
    factors = {v: _read(ds, v, it, sel, path, shape[1:]) for v in MAP_FACTOR_VARS if v in ds}
    if "MAPFAC_MX" in factors and "MAPFAC_MY" in factors:
        factors.pop("MAPFAC_M", None)
    dx, dy, grid_attrs = horizontal_spacing(path, dx, dy, factors, stacklevel=3)
    i0 = (x.start or 0) if x is not None else 0
    j0 = (y.start or 0) if y is not None else 0
    attrs.update({"n_negative_clipped_native": int(sum(negatives.values())), "dz_native_mean": dz,
                  "map_proj": int(ds.attrs.get("MAP_PROJ", 0)), **grid_attrs})
    attrs.update({f"n_negative_clipped_{k}": v for k, v in negatives.items()})
    hyd = from_arrays(q_new, np.maximum(rho_above, 1e-6), (dz, dy, dx),
                      (z_lo + dz / 2, j0 * dy, i0 * dx), r_eff=r_eff, attrs=attrs, source=path)
    hyd.attrs["n_negative_clipped"] = int(sum(negatives.values()))
    return hyd
