"""A text summary of Hydrometeors (``weather-mi info``): the place, projection, valid time and the sun
there (``weather_mi.scene.place``), the terrain, the grid, the per-species mixing ratios and extinction, the
densest column's optical depth."""
from __future__ import annotations

import numpy as np

from ..io.projection import latlon_text
from ..io.hydrometeors import SPECIES_NAMES, spacing_of


def info_text(hyd, species: str = "paper", sizes: str | None = None) -> str:
    """Dimensions, spacing (m), per-species max/mean mixing ratio (g/kg), effective radius range (um), max
    extinction (1/km) and the densest column's vertical optical depth of ``hyd`` with the species table
    ``species`` and the particle sizes ``sizes`` (``optical_volume``'s)."""
    from ..optics.volume import extinction  # not a whole OpticalVolume: the extinction is all it prints
    from ..io.hydrometeors import bbox_of
    beta_total, largest = extinction(hyd, species=species, sizes=sizes)
    dz, dy, dx = spacing_of(hyd)
    nz, ny, nx = beta_total.shape
    (x0, y0, z0), (x1, y1, z1) = bbox_of(hyd)
    lines = [f"source      : {hyd.attrs.get('source', '?')}",
             f"time        : {hyd.attrs.get('time', '-')}    microphysics: {hyd.attrs.get('microphysics', '-')}",
             f"grid (z,y,x): {nz} x {ny} x {nx}    spacing dz, dy, dx = {dz:.1f}, {dy:.1f}, {dx:.1f} m",
             f"extent      : x {x0 / 1e3:.2f}..{x1 / 1e3:.2f} km, y {y0 / 1e3:.2f}..{y1 / 1e3:.2f} km, "
             f"z {z0 / 1e3:.2f}..{z1 / 1e3:.2f} km",
             *place_lines(hyd),
             f"species preset: {species}    particle sizes: {sizes or 'default'}",
             f"{'species':<9}{'max q (g/kg)':>14}{'mean q (g/kg)':>15}{'max beta (1/km)':>17}"
             f"{'r_eff (um)':>16}  from"]
    radii = radius_ranges_um(hyd, species, sizes)
    for name in SPECIES_NAMES:
        q = hyd[f"q_{name}"].values
        lo, hi, where = radii[name]
        r_text = "-" if lo is None else f"{lo:.3g}" if lo == hi else f"{lo:.3g}..{hi:.3g}"
        lines.append(f"{name:<9}{1e3 * float(q.max()):>14.4g}{1e3 * float(q.mean()):>15.4g}"
                     f"{1e3 * largest[name]:>17.4g}{r_text:>16}  {where}")
    tau = beta_total.sum(axis=0, dtype=np.float64) * ((z1 - z0) / nz)  # OpticalVolume.optical_depth_z
    j, i = np.unravel_index(int(np.argmax(tau)), tau.shape)
    lines.append(f"max extinction: {1e3 * float(beta_total.max()):.4g} 1/km")
    lines.append(f"vertical optical depth through the densest column (x={float(hyd.x[i]) / 1e3:.1f} km, "
                 f"y={float(hyd.y[j]) / 1e3:.1f} km): {float(tau[j, i]):.4g}")
    if hyd.attrs.get("n_negative_clipped"):
        lines.append(f"negative mixing ratios clipped: {hyd.attrs['n_negative_clipped']}")
    return "\n".join(lines)


def radius_ranges_um(hyd, species="paper", sizes=None) -> dict[str, tuple]:
    """Each species' (smallest, largest effective radius (um) over the voxels that hold it, or None, None where
    none does; where the radius comes from), as ``optical_volume(hyd, species, sizes=sizes)`` uses them."""
    from ..optics.volume import _species_setup
    sp, use_model = _species_setup(species, None, None, sizes)
    out = {}
    for s in sp:
        has = hyd[f"q_{s.name}"].values > 0
        var = f"r_eff_{s.name}"
        if not has.any():
            out[s.name] = (None, None, "-")
        elif use_model and var in hyd:
            r = hyd[var].values[has]
            r = np.where(r > 0, r, s.radius_m)  # the species table's where the model gives none
            where = hyd.attrs.get(f"r_eff_source_{s.name}", "the input's r_eff")
            out[s.name] = (1e6 * float(r.min()), 1e6 * float(r.max()), where)
        else:
            out[s.name] = (1e6 * s.radius_m, 1e6 * s.radius_m, f"{sp.preset_name if sizes is None else sizes} preset")
    return out


def place_lines(hyd) -> list[str]:
    """Where and when ``hyd`` is: the centre, the extent, the projection and its check against the file's
    latitude/longitude, the valid time, the sun at the centre then and its largest change across the
    domain, and the terrain; a line saying so where there is no latitude/longitude."""
    from ..scene.place import place_of
    from ..io.terrain import Terrain
    place = place_of(hyd)
    lines = []
    if place is None:
        lines.append("place       : none: no latitude/longitude in the input (an ideal case); the sun is "
                     "--sun-azimuth/--sun-elevation, or --lat/--lon/--date place and date it")
    else:
        ew, ns = place.extent_km
        check = hyd.attrs.get("projection_error_max_m")
        checked = (f", matches the file's XLAT/XLONG within {check:.3g} m" if check is not None
                   else f" ({hyd.attrs.get('place', place.source)})")
        lines += [f"place       : centre {latlon_text(place.centre_lat, place.centre_lon)}; extent {ew:.1f} km "
                  f"(east-west) x {ns:.1f} km (north-south)",
                  f"projection  : {place.georef.name} ({place.georef.proj}){checked}"]
        lines += _sun_lines(place)
    terrain = Terrain.of(hyd)
    if terrain is not None:
        lines.append(f"terrain     : {terrain.height_m.min():.0f}..{terrain.height_m.max():.0f} m above MSL; "
                     f"{int(terrain.land.sum())} of {terrain.land.size} columns land; surface albedo "
                     f"{terrain.albedo.min():.3g}..{terrain.albedo.max():.3g} ({terrain.albedo_source})")
        from ..io.land_use import KINDS
        kinds, counts = np.unique(terrain.kinds, return_counts=True)
        lines.append(f"surface     : {', '.join(f'{KINDS[k]} {n}' for k, n in zip(kinds, counts))} columns "
                     f"(land from {hyd.attrs.get('land_source', '?')}"
                     + (f"; snow on {int(np.sum(terrain.snow > 0.5))}" if terrain.snow is not None else "")
                     + (f"; wind 10 m over water {hyd.attrs['wind_10m_water_m_s']:.1f} m/s"
                        if "wind_10m_water_m_s" in hyd.attrs else "") + ")")
    return lines


def _sun_lines(place) -> list[str]:
    if place.valid_time is None:
        return ["valid time  : unknown (an ideal case: --date gives it)"]
    sun = place.sun()
    out = [f"valid time  : {place.valid_time}"]
    if not sun.above_horizon:
        return out + [f"sun         : {-sun.elevation_deg:.2f} deg below the horizon at the centre (no direct sun)"]
    spread = place.sun_spread()
    north = place.grid_north_deg()
    grid = f", {(sun.azimuth_deg - north) % 360:.2f} in the grid's frame" if abs(north) > 0.005 else ""
    return out + [f"sun         : elevation {sun.elevation_deg:.2f} deg (zenith {sun.zenith_deg:.2f}), azimuth "
                  f"{sun.azimuth_deg:.2f} deg from true north{grid}, at the centre",
                  f"one sun     : across the domain the sun's direction changes by up to "
                  f"{spread['max_angle_deg']:.2f} deg (at {latlon_text(*spread['worst_latlon'], 2)}; "
                  f"{spread['columns']} columns); the renderer uses the "
                  "centre's sun everywhere"]

