"""The sun where and when it was: solar zenith and azimuth from a time (UTC) and a place, through pvlib's
implementation of the NREL Solar Position Algorithm (Reda & Andreas 2004, Solar Energy 76, 577-589;
NREL/TP-560-34302; uncertainty +-0.0003 deg from -2000 to 6000), and how much the sun's direction changes
across a model domain rendered with one sun.

Azimuth: degrees clockwise from true north (docs/design.md). ``elevation_deg`` is the apparent elevation
(refraction-corrected for the standard atmosphere given), where the sun is seen; ``zenith_geometric_deg``
is without refraction (what satellite products tabulate as the solar zenith angle).
"""
from __future__ import annotations

import datetime as dt
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SolarPosition:
    """The sun seen from a place at a time.

    Attributes
    ----------
    zenith_deg : float
        Apparent (refraction-corrected) solar zenith angle (degrees).
    zenith_geometric_deg : float
        Solar zenith angle without refraction (degrees).
    azimuth_deg : float
        Degrees clockwise from true north.
    """

    zenith_deg: float
    zenith_geometric_deg: float
    azimuth_deg: float

    @property
    def elevation_deg(self) -> float:
        """Apparent elevation above the horizon (degrees)."""
        return 90.0 - self.zenith_deg

    @property
    def above_horizon(self) -> bool:
        return self.zenith_deg < 90.0


def as_utc(time) -> dt.datetime:
    """A time (datetime, numpy datetime64, pandas Timestamp or ISO/WRF text "2005-09-21_03:00:00") as an
    aware UTC datetime; a naive time is UTC."""
    import pandas as pd
    if isinstance(time, str):
        time = time.strip().replace("_", "T")
    ts = pd.Timestamp(time)
    ts = ts.tz_localize("UTC") if ts.tzinfo is None else ts.tz_convert("UTC")
    return ts.to_pydatetime()


def solar_position(time, lat_deg: float, lon_deg: float, *, altitude_m: float = 0.0, pressure_pa: float = 101325.0,
                   temperature_c: float = 12.0, delta_t_s: float | None = None) -> SolarPosition:
    """The sun's position at ``time`` seen from (``lat_deg``, ``lon_deg``) (NREL SPA through
    ``pvlib.solarposition.spa_python``).

    Parameters
    ----------
    time : datetime, datetime64, Timestamp or str
        The time (UTC when naive).
    lat_deg, lon_deg : float
        Latitude (north positive) and longitude (east positive), degrees.
    altitude_m : float, default 0
        Height of the observer above sea level (m; topocentric parallax, < 0.003 deg).
    pressure_pa, temperature_c : float
        Surface pressure (Pa) and temperature (C) of the refraction correction.
    delta_t_s : float, optional
        TT - UT1 (s); None: pvlib's estimate for the year.

    Returns
    -------
    SolarPosition
    """
    import pandas as pd
    from pvlib.solarposition import spa_python
    when = pd.DatetimeIndex([as_utc(time)])
    p = spa_python(when, float(lat_deg), float(lon_deg), altitude=float(altitude_m), pressure=float(pressure_pa),
                   temperature=float(temperature_c), delta_t=delta_t_s)
    return SolarPosition(float(p["apparent_zenith"].iloc[0]), float(p["zenith"].iloc[0]), float(p["azimuth"].iloc[0]))


def sun_vector(zenith_deg, azimuth_deg) -> np.ndarray:
    """Unit vectors (..., 3) towards the sun in a local frame x east, y north, z up."""
    z, a = np.radians(zenith_deg), np.radians(azimuth_deg)
    return np.stack([np.sin(z) * np.sin(a), np.sin(z) * np.cos(a), np.cos(z)], axis=-1)


def sun_angles_at(position: SolarPosition, lat0_deg: float, lon0_deg: float, lat_deg, lon_deg):
    """Solar zenith and azimuth (degrees, unrefracted) at many points from the sun's position at one point
    (lat0, lon0) at the same instant: the direction to the sun is the same everywhere (its parallax over the
    earth, 8.8 arcsec at most, is neglected), so it is carried from (lat0, lon0)'s horizon frame into each
    point's. One NREL SPA evaluation for a satellite image's million pixels."""
    from ..io.projection import enu_vectors
    e0, n0, u0 = enu_vectors(lat0_deg, lon0_deg)
    local = sun_vector(position.zenith_geometric_deg, position.azimuth_deg)
    s = local[0] * e0 + local[1] * n0 + local[2] * u0
    e, n, u = enu_vectors(lat_deg, lon_deg)
    se, sn, su = (np.sum(s * v, axis=-1) for v in (e, n, u))
    return np.degrees(np.arccos(np.clip(su, -1.0, 1.0))), np.degrees(np.arctan2(se, sn)) % 360.0


def sun_across_domain(time, lat, lon, grid_north_deg=None, *, points: int = 5) -> dict:
    """How far the sun's direction at the columns of a domain is from the one sun at its centre.

    The renderer lights a domain with one sun, the one at the centre column, in one flat frame (x east,
    y grid north, z up). The true sun at a column, in that column's own horizon frame and turned into the
    grid's frame by the meridian convergence there, differs from it by an angle that grows with the
    domain's size: this measures it on a ``points`` x ``points`` lattice of columns that includes the four
    corners and the edges' midpoints (the angle is smooth and largest on the boundary).

    Parameters
    ----------
    time : the valid time (UTC).
    lat, lon : array_like, (ny, nx)
        Latitude, longitude of every column (degrees).
    grid_north_deg : array_like, optional
        (ny, nx) azimuth of the grid's +y axis, degrees clockwise from true north
        (``Georeference.grid_north_deg``); None: 0 (grid y is true north).
    points : int
        Lattice size per axis.

    Returns
    -------
    dict
        ``centre``: SolarPosition at the centre column; ``max_angle_deg``: the largest angle between a
        column's sun and the centre's (degrees); ``max_zenith_change_deg`` and ``max_azimuth_change_deg``
        (the latter in the grid's frame); ``worst_latlon``: where the largest angle is; ``columns``: how many
        columns were evaluated.
    """
    lat, lon = np.asarray(lat, float), np.asarray(lon, float)
    north = np.zeros_like(lat) if grid_north_deg is None else np.asarray(grid_north_deg, float)
    ny, nx = lat.shape
    js = sorted(set(np.linspace(0, ny - 1, points).round().astype(int)) | {(ny - 1) // 2, ny // 2})
    is_ = sorted(set(np.linspace(0, nx - 1, points).round().astype(int)) | {(nx - 1) // 2, nx // 2})
    jc, ic = (ny - 1) / 2, (nx - 1) / 2
    centre_lat, centre_lon = _centre(lat, lon, jc, ic)
    centre_north = float(north[int(round(jc)), int(round(ic))])
    c = solar_position(time, centre_lat, centre_lon)
    vc = sun_vector(c.zenith_deg, c.azimuth_deg - centre_north)
    worst, where, dzen, daz = 0.0, (centre_lat, centre_lon), 0.0, 0.0
    for j in js:
        for i in is_:
            p = solar_position(time, lat[j, i], lon[j, i])
            v = sun_vector(p.zenith_deg, p.azimuth_deg - north[j, i])
            ang = float(np.degrees(np.arccos(np.clip(np.dot(v, vc), -1.0, 1.0))))
            dzen = max(dzen, abs(p.zenith_deg - c.zenith_deg))
            daz = max(daz, abs((p.azimuth_deg - north[j, i] - c.azimuth_deg + centre_north + 180) % 360 - 180))
            if ang > worst:
                worst, where = ang, (float(lat[j, i]), float(lon[j, i]))
    return {"centre": c, "centre_latlon": (centre_lat, centre_lon), "max_angle_deg": worst,
            "max_zenith_change_deg": dzen, "max_azimuth_change_deg": daz, "worst_latlon": where,
            "columns": len(js) * len(is_)}


def _centre(lat, lon, jc, ic) -> tuple[float, float]:
    """Latitude, longitude at the fractional index (jc, ic): the mean of the up to four nearest columns
    (longitudes unwrapped about the first)."""
    j = sorted({int(np.floor(jc)), int(np.ceil(jc))})
    i = sorted({int(np.floor(ic)), int(np.ceil(ic))})
    la = lat[np.ix_(j, i)]
    lo = lon[np.ix_(j, i)]
    lo = lo.flat[0] + (lo - lo.flat[0] + 180.0) % 360.0 - 180.0
    return float(la.mean()), float((lo.mean() + 180.0) % 360.0 - 180.0)
