"""One time of an open wrfout Dataset -> Hydrometeors (see weather_mi.io.hydrometeors for the contract):
the conversion both ``open_wrf`` (one time) and ``open_wrf_series`` (several, on one grid) are made of.

Steps: an optional horizontal sub-box; heights of the w-levels z_w = (PH + PHB) / g and of the mass
levels as their mean (destaggering); dry-air density rho_d = p / (R_d T (1 + 1.608 q_v)) with
p = P + PB, T = (T' + 300 K)(p / 1e5)^(R_d/c_p) (cross-checked against ALT = 1/rho_d when the file has
it); species mass densities rho_d q regridded conservatively onto a uniform height grid
(weather_mi.io.vertical); the horizontal spacing DX, DY over the mean map factor
(weather_mi.io.map_factors, with a warning where it varies); the place, valid time and ground
(weather_mi.io.georef: lat/lon, the map projection checked against XLAT/XLONG, HGT, land, albedo) as
(y, x) coordinates and attributes. Negative mixing ratios are clipped, counted
and reported in a warning (count and minimum per variable); species the scheme does not carry become
zeros with a warning that names the scheme, while a variable the scheme writes and the file lacks is an
error (``schemes.SCHEME_VARS``).

Warnings are raised with ``stacklevel`` counted from ``convert``'s caller's caller (the user's call of
``open_wrf``), one more per helper below ``convert``.
"""
from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from ..errors import WeatherDataError
from .hydrometeors import from_arrays, validate, warn_clipped
from . import budget, vertical
from .georef import place_coords
from .map_factors import horizontal_spacing
from .schemes import MP_SCHEMES, SCHEME_VARS
from . import particle_sizes

G = 9.81               # m/s^2, WRF's gravity
R_D = 287.0            # J/(kg K)
RD_OVER_CP = 0.2857
EPS_INV = 1.608        # R_v / R_d: virtual-temperature factor for the vapour mixing ratio
THETA0 = 300.0         # K, WRF's base potential temperature offset of T

SPECIES_VARS = {"cloud": "QCLOUD", "ice": "QICE", "rain": "QRAIN", "snow": "QSNOW", "graupel": "QGRAUP"}
REQUIRED = ("P", "PB", "T", "PH", "PHB")
MAP_FACTOR_VARS = ("MAPFAC_M", "MAPFAC_MX", "MAPFAC_MY")


CHUNK_CACHE_BYTES = 4 << 20  # per variable: each variable is read whole, once; netCDF's default 64 MiB
# of chunk cache for every variable read stayed allocated while the file was open (0.25 GB on 400 x 400 x 50)


def open_dataset(path: str) -> xr.Dataset:
    """The wrfout NetCDF file at ``path``, lazily (a WeatherDataError naming it where it is no NetCDF), with
    a small chunk cache per variable (``CHUNK_CACHE_BYTES``)."""
    import netCDF4
    before = netCDF4.get_chunk_cache()
    netCDF4.set_chunk_cache(CHUNK_CACHE_BYTES, before[1], before[2])
    try:
        return xr.open_dataset(path, decode_times=False, mask_and_scale=True, cache=False)
    except Exception as exc:  # netCDF4/h5py raise many types for non-NetCDF input
        raise WeatherDataError(path, None, "a NetCDF (wrfout) file", f"{type(exc).__name__}: {exc}") from exc
    finally:
        netCDF4.set_chunk_cache(*before)


def read(ds, name, it, sel, path, shape=None, dtype=np.float64) -> np.ndarray:
    """Variable ``name`` at time index ``it`` on the sub-box ``sel`` (as ``dtype``: the 3-D fields are read
    as float32, as written), checked for ``shape`` and for finite values."""
    da = ds[name]
    if "Time" in da.dims:
        da = da.isel(Time=it)
    da = da.isel({k: v for k, v in sel.items() if k in da.dims})
    a = np.asarray(da.values, dtype=dtype)
    if shape is not None and a.shape != shape:
        raise WeatherDataError(path, name, f"shape {shape} (bottom_top, south_north, west_east)", f"shape {a.shape}")
    if not np.isfinite(a).all():
        n = int(a.size - np.count_nonzero(np.isfinite(a)))
        raise WeatherDataError(path, name, "finite values", f"{n} NaN or infinite values")
    return a


def w_level_heights(ds, it, sel, path, dtype=np.float64) -> np.ndarray:
    """Heights of the w-levels z_w = (PH + PHB) / g (m above MSL), (bottom_top_stag, south_north, west_east)."""
    z_w = read(ds, "PH", it, sel, path, dtype=dtype)
    z_w += read(ds, "PHB", it, sel, path, dtype=dtype)
    z_w /= z_w.dtype.type(G)
    return z_w


def temperature(p_pa, theta_k):
    """T = theta (p / 1e5)^(R_d/c_p) (K)."""
    return theta_k * (p_pa / 1.0e5) ** RD_OVER_CP


def dry_air_density(p_pa, theta_k, qv, t_k=None):
    """rho_d = p / (R_d T (1 + 1.608 q_v)), T = theta (p / 1e5)^(R_d/c_p) (kg/m^3; ``t_k``: T already computed)."""
    t_k = temperature(p_pa, theta_k) if t_k is None else t_k
    return p_pa / (R_D * t_k * (1.0 + EPS_INV * qv))


def check_required(ds, path) -> None:
    """A WeatherDataError naming the variables of ``REQUIRED`` that ``ds`` lacks."""
    missing = [v for v in REQUIRED if v not in ds]
    if missing:
        raise WeatherDataError(path, ", ".join(missing), f"the wrfout variables {', '.join(REQUIRED)}", "missing")


def convert(ds, path, it: int, stamp: str, x, y, dz, top, bottom, sizes: bool = True) -> xr.Dataset:
    """Hydrometeors of time index ``it`` (timestamp ``stamp``) of the open wrfout ``ds`` (see the module).

    x, y : slices of mass-point indices (west_east, south_north) or None. dz : vertical spacing (m), None:
    the native mean layer depth. bottom, top : the height grid's extent (m above MSL), None: lowest terrain
    to highest model top. sizes : the scheme's effective radii as ``r_eff_<species>`` (m;
    ``weather_mi.io.particle_sizes``); the file's RE_CLOUD/RE_ICE/RE_SNOW are read either way.

    Memory: float32 fields, the species read and regridded one at a time through one shared
    ``vertical.VerticalPlan``; the peak is the output (one field per species and the density) and a few
    native fields."""
    check_required(ds, path)
    sel = _sub_box(path, x, y)
    mp = int(ds.attrs.get("MP_PHYSICS", -1))
    scheme = MP_SCHEMES.get(mp, f"MP_PHYSICS={mp}" if mp >= 0 else "unknown scheme")
    attrs = {"source": path, "model": str(ds.attrs.get("TITLE", "WRF")).strip(), "time": stamp,
             "time_index": it, "microphysics": scheme, "mp_physics": mp}
    present = _species_present(ds, path, scheme, mp, attrs)
    sizer = particle_sizes.SizeReader(ds, path, lambda var, shape: read(ds, var, it, sel, path, shape, np.float32), mp,
                                      scheme, present, sizes, stacklevel=5)
    step = "reading_sizes" if sizer.rules else "reading"
    budget.check_fits(path, _native_shape(ds, sel), step)  # before reading anything
    shape, z_w, rho = _air(ds, path, it, sel, attrs, sizer)
    dz, z_lo, edges = _height_grid(path, z_w, shape, dz, top, bottom)
    budget.check_fits(path, (len(edges) - 1,) + shape[1:], step)  # the target grid, before regridding
    plan = vertical.VerticalPlan(z_w, edges)
    rho_above = _air_above(plan, z_w, rho, edges)
    q_new, r_eff, negatives = _regrid_species(ds, path, it, sel, shape, plan, rho, rho_above, present, sizer)
    del plan, rho
    sizer.t_k = None
    dx, dy, grid_attrs = _spacing(ds, path, it, sel, shape)
    i0 = (x.start or 0) if x is not None else 0
    j0 = (y.start or 0) if y is not None else 0
    attrs.update({"n_negative_clipped_native": int(sum(negatives.values())), "dz_native_mean": dz,
                  "map_proj": int(ds.attrs.get("MAP_PROJ", 0)), **grid_attrs})
    attrs.update({f"n_negative_clipped_{k}": v for k, v in negatives.items()})
    attrs.update(sizer.attrs())
    hyd = from_arrays(q_new, rho_above, (dz, dy, dx), (z_lo + dz / 2, j0 * dy, i0 * dx), r_eff=r_eff,
                      attrs=attrs, source=path, copy=False)
    del q_new, r_eff, rho_above
    hyd.attrs["n_negative_clipped"] = int(sum(negatives.values()))
    coords, place_attrs = place_coords(ds, path, it, stamp, sel, z_w[0].astype(np.float64))
    hyd = hyd.assign_coords(coords)
    hyd.attrs.update(place_attrs)
    return validate(hyd)


def _native_shape(ds, sel) -> tuple[int, int, int]:
    """(bottom_top, south_north, west_east) of the mass grid on the sub-box ``sel``, from the file's dimensions."""
    dims = ("bottom_top", "south_north", "west_east")
    n = {d: int(ds.sizes.get(d, 1)) for d in dims}
    return tuple(len(range(*sel[d].indices(n[d]))) if d in sel else n[d] for d in dims)


def _sub_box(path, x, y) -> dict:
    sel = {}
    for dim, s in (("west_east", x), ("south_north", y)):
        if s is not None:
            if not isinstance(s, slice):
                raise WeatherDataError(path, dim, "a slice of mass-point indices", repr(s))
            sel[dim] = s
    return sel


def _air(ds, path, it, sel, attrs, sizer):
    """(shape of the mass grid, z_w (m), dry-air density (kg/m^3) on the mass points), float32; ``attrs`` gets
    the ALT cross-check; ``sizer`` the temperature (K) where its rules need it."""
    p = read(ds, "P", it, sel, path, dtype=np.float32)
    shape = p.shape
    if len(shape) != 3 or min(shape) < 1:
        raise WeatherDataError(path, "P", "a (bottom_top, south_north, west_east) field", f"shape {shape}")
    p += read(ds, "PB", it, sel, path, shape, np.float32)
    theta = read(ds, "T", it, sel, path, shape, np.float32)
    theta += np.float32(THETA0)
    z_w = w_level_heights(ds, it, sel, path, np.float32)
    if z_w.shape != (shape[0] + 1,) + shape[1:]:
        raise WeatherDataError(path, "PH", f"shape {(shape[0] + 1,) + shape[1:]} on bottom_top_stag", f"shape {z_w.shape}")
    if not all(bool((z_w[k + 1] > z_w[k]).all()) for k in range(shape[0])):
        raise WeatherDataError(path, "PH+PHB", "geopotential heights increasing upward in every column")
    if "QVAPOR" in ds:
        qv = np.maximum(read(ds, "QVAPOR", it, sel, path, shape, np.float32), 0.0)
    else:
        warnings.warn(f"{path}: no QVAPOR; dry-air density computed without the vapour correction", stacklevel=4)
        qv = np.zeros(shape, np.float32)
    t_k = temperature(p, theta)
    rho = dry_air_density(p, theta, qv, t_k)
    sizer.t_k = t_k if sizer.needs_temperature else None
    del p, theta, qv, t_k
    if "ALT" in ds:
        alt = read(ds, "ALT", it, sel, path, shape, np.float32)
        alt *= rho
        alt -= np.float32(1.0)
        rel = float(np.max(np.abs(alt)))
        del alt
        attrs["alt_max_rel_diff"] = rel
        if rel > 0.01:
            warnings.warn(f"{path}: dry-air density from P, PB, T, QVAPOR differs from 1/ALT by up to "
                          f"{100 * rel:.2f}%", stacklevel=4)
    return shape, z_w, rho


def _species_present(ds, path, scheme, mp, attrs) -> list[str]:
    """The species whose mixing ratio the file has (a WeatherDataError where the scheme writes one the file
    lacks, or where there is none; a warning naming those the scheme does not carry)."""
    written = SCHEME_VARS.get(mp, ())
    damaged = [v for v in written if v not in ds]
    if damaged:
        raise WeatherDataError(path, ", ".join(damaged), f"the mixing ratios that {scheme} microphysics "
                               f"(MP_PHYSICS={mp}) writes: {', '.join(written)}", "missing from the file")
    present = [name for name, var in SPECIES_VARS.items() if var in ds]
    lacking = [var for var in SPECIES_VARS.values() if var not in ds]
    if not present:
        raise WeatherDataError(path, "QCLOUD", "at least one hydrometeor mixing ratio (QCLOUD, QRAIN, ...)", "none")
    if lacking:
        warnings.warn(f"{path}: microphysics scheme {scheme} does not provide {', '.join(lacking)}; "
                      "those species are zero", stacklevel=4)
        attrs["species_missing"] = ", ".join(lacking)
    return present


def _height_grid(path, z_w, shape, dz, top, bottom):
    """(dz (m), the grid's bottom (m above MSL), its nz + 1 cell edges (m))."""
    dz = float(dz) if dz is not None else float(np.mean(z_w[-1] - z_w[0], dtype=np.float64) / shape[0])
    z_lo = float(np.min(z_w[0])) if bottom is None else float(bottom)
    z_hi = float(np.max(z_w[-1])) if top is None else float(top)
    if not (dz > 0 and z_hi > z_lo):
        raise WeatherDataError(path, "dz/top", "dz > 0 and top above bottom", f"dz={dz}, bottom={z_lo}, top={z_hi}")
    nz = max(int(np.ceil((z_hi - z_lo) / dz - 1e-6)), 1)
    return dz, z_lo, z_lo + dz * np.arange(nz + 1)


def _air_above(plan, z_w, rho, edges) -> np.ndarray:
    """The dry-air density of each target cell's part above ground (kg/m^3, float32, at least 1e-6): the
    cell's air over its open fraction, the lowest mass level's air where the cell is all below ground."""
    frac = vertical.above_ground_fraction(z_w, edges)
    out = plan.average(rho)
    np.divide(out, np.maximum(frac, np.float32(1e-12)), out=out, where=frac > 0)
    np.copyto(out, np.broadcast_to(rho[0], out.shape), where=frac <= 0)
    np.maximum(out, np.float32(1e-6), out=out)
    return out


def _regrid_species(ds, path, it, sel, shape, plan, rho, rho_above, present, sizer):
    """({species: mixing ratio on the target grid (kg/kg, mass conserved)}, {species: effective radius (m),
    the cell's mass over its mass / r_eff, so that Eq. 4's extinction is conserved}, {species: negatives
    clipped}), one species read and regridded at a time."""
    q_new, r_eff, negatives, minima = {}, {}, {}, {}
    for name in present:
        var = SPECIES_VARS[name]
        q = read(ds, var, it, sel, path, shape, np.float32)
        hail = None
        if name == "graupel" and "QHAIL" in ds:  # hail is the dense end of the rimed-ice spectrum
            hail = read(ds, "QHAIL", it, sel, path, shape, np.float32)
            if sizer.hail_rule is None:  # one content, sized (if at all) as graupel
                q += hail
                hail = None
        negatives[name] = int(np.count_nonzero(q < 0))
        if negatives[name]:
            minima[var] = (negatives[name], float(q.min()))
        np.maximum(q, 0.0, out=q)
        q *= rho  # kg/m^3 of this species, conserved by the regridding
        if hail is not None:  # hail sized by its own rule, then added to graupel's content
            n_hail = int(np.count_nonzero(hail < 0))
            if n_hail:
                minima["QHAIL"] = (n_hail, float(hail.min()))
                negatives[name] += n_hail
            np.maximum(hail, 0.0, out=hail)
            hail *= rho
        r_native = sizer.radius(name, q, rho, shape, hail)  # the file's RE_* or the scheme's (m), or None
        if hail is not None:
            q += hail
            del hail
        mass = plan.average(q)
        np.maximum(mass, 0.0, out=mass)
        if r_native is not None:  # Eq. 4 conserved: the cell's rho q over its average of rho q / r_eff
            np.divide(q, r_native, out=r_native, where=r_native > 0)  # (0 where no radius: q has none there)
            del q  # (each grid freed as soon as it is used: the reader's peak is the sizes' step)
            ext = plan.average(r_native)
            del r_native
            has = (ext > 0) & (mass > 0)
            np.divide(mass, ext, out=ext, where=has)  # r_eff, in place of the average
            np.copyto(ext, np.float32(0), where=~has)
            r_eff[name] = ext
            del ext, has
            sizer.clip_to_native(name, r_eff[name], mass)  # the reconstructions' ratio where both are tiny
        else:
            del q
        mass /= rho_above
        q_new[name] = mass
    if minima:
        warn_clipped(path, minima, stacklevel=4)
    return q_new, r_eff, negatives


def _spacing(ds, path, it, sel, shape):
    """(dx, dy (m), attrs) of the horizontal grid: DX, DY over the mean map factor."""
    dx = float(ds.attrs.get("DX", 1000.0))
    dy = float(ds.attrs.get("DY", dx))
    factors = {v: read(ds, v, it, sel, path, shape[1:]) for v in MAP_FACTOR_VARS if v in ds}
    if "MAPFAC_MX" in factors and "MAPFAC_MY" in factors:
        factors.pop("MAPFAC_M", None)
    return horizontal_spacing(path, dx, dy, factors, stacklevel=4)
