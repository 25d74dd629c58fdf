"""The ground under a model grid: terrain height (m above sea level) and a surface albedo per column, on
the Hydrometeors (y, x) grid, as data a renderer can turn into a height-field mesh (``Terrain.mesh``).

Readers put them in a Hydrometeors Dataset as (y, x) coordinates, not data variables, so that they never
mix with the hydrometeors: ``terrain_height`` (m above MSL: WRF's HGT), ``land`` (1 land, 0 water, from
LANDMASK, else XLAND, else LU_INDEX's water and lake classes, else the offline global mask at the columns'
latitude/longitude, ``land_mask``), ``surface_albedo`` (WRF's broadband ALBEDO where the file has it, else
ALBBCK, else the default of the column's class), ``surface_kind`` (``land_use.KINDS``: sea, lake, forest, ...,
from LU_INDEX and its MMINLU table where the file has it, else land or sea) and, where the file says,
``snow_cover`` (SNOWC, SNOWH or SNOW). The default albedos are WRF's own all-season land/water table
(``LW12`` in WRF's ``run/LANDUSE.TBL``: land 20 %, water 8 %); a file with none of the land sources (no
mask, no land use, no latitude/longitude) is taken as land. ``Terrain.in_band`` gives the albedo in an
imager's band (``land_use.band_albedo``).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .land_use import KIND, WATER_KINDS, band_albedo, kinds_from_land_use, snow_cover

LAND_ALBEDO = 0.20   # WRF run/LANDUSE.TBL, table LW12, class 1 'Land' (ALBD 20 %)
WATER_ALBEDO = 0.08  # WRF run/LANDUSE.TBL, table LW12, class 2 'Water' (ALBD 8 %; the USGS 'Water Bodies' too)
COORDS = ("terrain_height", "land", "surface_albedo", "surface_kind", "snow_cover")
TERRAIN_APRON_M = 100e3  # a rendered ground continues level this far past the grid's edge (``scene_hits``)


@dataclass(frozen=True)
class Terrain:
    """Terrain of a Hydrometeors grid.

    Attributes
    ----------
    x, y : numpy.ndarray
        Column centres (m) in the Hydrometeors frame (x east, y grid north), (nx,) and (ny,).
    height_m : numpy.ndarray
        (ny, nx) terrain height above mean sea level (m).
    land : numpy.ndarray
        (ny, nx) bool, True over land.
    albedo : numpy.ndarray
        (ny, nx) broadband surface albedo in [0, 1].
    albedo_source : str
        Where the albedo came from (a variable of the file, or the default table).
    kind : numpy.ndarray or None
        (ny, nx) surface kinds (``land_use.KINDS``); None: land or sea by ``land``.
    snow : numpy.ndarray or None
        (ny, nx) snow-covered fraction, where the file gives one.
    wind_m_s : float or None
        Wind speed 10 m above the water (m/s; the mean over the water columns of the file's U10/V10), None
        where the file has none; it sets the sea surface's roughness (``kernel.sea_surface``).
    albedo_rgb : numpy.ndarray or None
        (ny, nx, 3) albedo per render channel (``in_bands``: a band per channel), None: ``albedo`` in all three.
    sea : bool
        Whether a renderer draws the water columns as the sea surface (Fresnel, Cox-Munk glint at
        ``wind_m_s``: ``kernel.sea_surface``) instead of Lambertian with ``albedo`` (``with_sea``).
    sea_normal : numpy.ndarray or None
        (ny, nx, 3) unit shading normals of the sea surface (``satellite.glint``: the glint where each column's
        own sun puts it), None: up.
    """

    x: np.ndarray
    y: np.ndarray
    height_m: np.ndarray
    land: np.ndarray
    albedo: np.ndarray
    albedo_source: str
    kind: np.ndarray | None = None
    snow: np.ndarray | None = None
    wind_m_s: float | None = None
    albedo_rgb: np.ndarray | None = None
    sea: bool = False
    sea_normal: np.ndarray | None = None

    @classmethod
    def of(cls, hyd) -> Terrain | None:
        """The terrain stored in a Hydrometeors Dataset (None where it has none: LES, arrays, demos)."""
        if "terrain_height" not in hyd.coords:
            return None
        opt = {name: np.asarray(hyd[name].values) for name in ("surface_kind", "snow_cover") if name in hyd.coords}
        wind = hyd.attrs.get("wind_10m_water_m_s")
        return cls(np.asarray(hyd.x.values, float), np.asarray(hyd.y.values, float),
                   np.asarray(hyd["terrain_height"].values, float), np.asarray(hyd["land"].values) > 0,
                   np.asarray(hyd["surface_albedo"].values, float),
                   str(hyd.attrs.get("surface_albedo_source", "?")),
                   None if "surface_kind" not in opt else opt["surface_kind"].astype(np.int8),
                   None if "snow_cover" not in opt else opt["snow_cover"].astype(float),
                   None if wind is None else float(wind))

    @property
    def kinds(self) -> np.ndarray:
        """(ny, nx) surface kinds (``land_use.KINDS``): the file's, else land or sea by ``land``."""
        if self.kind is not None:
            return self.kind
        return np.where(self.land, KIND["land"], KIND["sea"]).astype(np.int8)

    @property
    def water(self) -> np.ndarray:
        """(ny, nx) bool, True over the sea and lakes (their surface is the sea surface's, with its glint)."""
        return np.isin(self.kinds, WATER_KINDS)

    def in_band(self, wavelength_um: float) -> "Terrain":
        """This terrain with its albedo at ``wavelength_um`` (``land_use.band_albedo``: the file's broadband
        albedo shaped by each column's kind and snow, or the kind's own where the file has none; over water the
        water body's Lambertian part)."""
        from_file = self.albedo_source in ("ALBEDO", "ALBBCK")
        a = band_albedo(self.kinds, wavelength_um, self.albedo if from_file else None, self.snow)
        return replace(self, albedo=a, albedo_rgb=None,
                       albedo_source=f"{self.albedo_source} at {wavelength_um:g} um (land_use)")

    def in_bands(self, wavelengths_um) -> "Terrain":
        """This terrain with the albedo at ``wavelengths_um[c]`` in render channel c (``albedo_rgb``; ``albedo``
        their mean, for what reads one albedo)."""
        rgb = np.stack([self.in_band(w).albedo for w in wavelengths_um], axis=-1)
        return replace(self, albedo=rgb.mean(axis=-1), albedo_rgb=rgb,
                       albedo_source=f"{self.albedo_source} at {'/'.join(f'{w:g}' for w in wavelengths_um)} um")

    def with_sea(self, wind_m_s: float | None = None) -> "Terrain":
        """This terrain with its water drawn as the sea surface (``sea``) at ``wind_m_s`` (m/s; None: the
        file's U10/V10 over the water, else ``kernel``'s default, 5 m/s); a ValueError for a negative or
        non-finite wind."""
        if wind_m_s is not None and not (np.isfinite(float(wind_m_s)) and float(wind_m_s) >= 0.0):
            raise ValueError(f"--wind {wind_m_s}: expected a wind speed >= 0 m/s (10 m above the sea)")
        return replace(self, sea=True, wind_m_s=self.wind_m_s if wind_m_s is None else float(wind_m_s))

    def land_at(self, x_m, y_m) -> np.ndarray:
        """The land flag (int8: 1 land, 0 water) of the nearest column to points (x_m, y_m) (m), -1 beyond the
        grid (more than half a spacing outside it)."""
        x, y = np.asarray(x_m, float), np.asarray(y_m, float)
        dx = (self.x[1] - self.x[0]) if self.x.size > 1 else 1.0
        dy = (self.y[1] - self.y[0]) if self.y.size > 1 else 1.0
        fi, fj = np.rint((x - self.x[0]) / dx), np.rint((y - self.y[0]) / dy)
        inside = (fi >= 0) & (fi < self.x.size) & (fj >= 0) & (fj < self.y.size)
        i = np.clip(np.nan_to_num(fi), 0, self.x.size - 1).astype(int)
        j = np.clip(np.nan_to_num(fj), 0, self.y.size - 1).astype(int)
        return np.where(inside, (~self.water[j, i]).astype(np.int8), np.int8(-1)).astype(np.int8)

    def vertex_rgb(self) -> np.ndarray:
        """(ny, nx, 3) albedo per render channel: ``albedo_rgb``, else ``albedo`` in all three."""
        return self.albedo_rgb if self.albedo_rgb is not None else np.repeat(self.albedo[..., None], 3, axis=-1)

    def mesh(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A height-field triangle mesh through the column centres: vertices (ny * nx, 3) at (x, y,
        height) in metres, triangles (2 (ny - 1)(nx - 1), 3) of vertex indices, counter-clockwise seen from
        above (normals up), and the albedo per vertex (ny * nx,)."""
        ny, nx = self.height_m.shape
        gx, gy = np.meshgrid(self.x, self.y)
        vertices = np.stack([gx.ravel(), gy.ravel(), self.height_m.ravel()], axis=1)
        k = np.arange(ny * nx).reshape(ny, nx)
        a, b, c, d = k[:-1, :-1].ravel(), k[:-1, 1:].ravel(), k[1:, 1:].ravel(), k[1:, :-1].ravel()
        faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
        return vertices, faces, self.albedo.ravel()

    def edge_albedo(self) -> float:
        """The mean albedo of the grid's boundary columns (the surround's, beyond the apron)."""
        a = self.albedo
        return float(np.mean(np.concatenate([a[0], a[-1], a[1:-1, 0], a[1:-1, -1]])))

    def edge_rgb(self) -> np.ndarray:
        """(3,) the mean albedo per render channel of the grid's boundary columns (``vertex_rgb``): the
        surround's beyond the apron."""
        a = self.vertex_rgb()
        return np.mean(np.concatenate([a[0], a[-1], a[1:-1, 0], a[1:-1, -1]]), axis=0)

    def _cells(self, x_m, y_m):
        """Cell indices (j, i, j + 1, i + 1), the position (u, v) in the cell, the lower-triangle mask
        (u >= v: triangle (j, i), (j, i + 1), (j + 1, i + 1); else (j, i), (j + 1, i + 1), (j + 1, i)),
        clamped to the grid (the edge continues level beyond it), and the spacing (dx, dy)."""
        x, y = np.asarray(x_m, float), np.asarray(y_m, float)
        ny, nx = self.height_m.shape
        dx, dy = (self.x[1] - self.x[0]) if nx > 1 else 1.0, (self.y[1] - self.y[0]) if ny > 1 else 1.0
        fi = np.clip((x - self.x[0]) / dx, 0.0, nx - 1.0)
        fj = np.clip((y - self.y[0]) / dy, 0.0, ny - 1.0)
        i, j = np.minimum(fi.astype(int), max(nx - 2, 0)), np.minimum(fj.astype(int), max(ny - 2, 0))
        u, v = fi - i, fj - j
        return j, i, np.minimum(j + 1, ny - 1), np.minimum(i + 1, nx - 1), u, v, u >= v, dx, dy

    @staticmethod
    def _linear(f, cells):
        """``f`` (ny, nx) linear on the cells' triangles: (value, df/du, df/dv)."""
        j, i, j1, i1, u, v, lower, _, _ = cells
        a, b, c, d = f[j, i], f[j, i1], f[j1, i1], f[j1, i]
        du, dv = np.where(lower, b - a, c - d), np.where(lower, c - b, d - a)
        return a + u * du + v * dv, du, dv

    def height_at(self, x_m, y_m) -> np.ndarray:
        """Height (m) of the mesh (``mesh``'s triangles, linear on each; level beyond the grid) at (x_m, y_m)."""
        return self._linear(self.height_m, self._cells(x_m, y_m))[0]

    def surface_at(self, x_m, y_m):
        """Height (m), albedo and unit normal (..., 3) of the mesh (``mesh``: the same triangles, split along
        each cell's diagonal from its (j, i) corner to its (j + 1, i + 1) corner, linear on each) at points
        (x_m, y_m); beyond the grid the edge continues level (``with_apron``)."""
        x, y = np.asarray(x_m, float), np.asarray(y_m, float)
        cells = self._cells(x, y)
        dx, dy = cells[-2:]
        h, hu, hv = self._linear(self.height_m, cells)
        albedo = self._linear(self.albedo, cells)[0]
        hx = np.where((x < self.x[0]) | (x > self.x[-1]), 0.0, hu / dx)
        hy = np.where((y < self.y[0]) | (y > self.y[-1]), 0.0, hv / dy)
        n = np.stack([-hx, -hy, np.ones_like(h)], -1)
        return h, albedo, n / np.linalg.norm(n, axis=-1, keepdims=True)

    def ray_hits(self, origins, dirs, max_steps: int = 2048, bisections: int = 40) -> np.ndarray:
        """Distance along each ray (N, 3) to its first hit of the surface (``height_at``), inf where it has
        none: marched in steps of a quarter cell (horizontally) through the heights the terrain spans, the
        crossing then bisected."""
        o, d = np.asarray(origins, float), np.asarray(dirs, float)
        lo, hi = float(self.height_m.min()), float(self.height_m.max())
        dz = d[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            t_a = np.where(o[:, 2] > hi, (hi - o[:, 2]) / dz, 0.0)
            t_b = np.where(dz < 0, (lo - o[:, 2]) / dz, np.inf)
        live = (dz < 0) & (t_a >= 0) & np.isfinite(t_b)
        t_hit = np.full(len(o), np.inf)
        if not np.any(live):
            return t_hit
        cell = min(abs(self.x[1] - self.x[0]) if self.x.size > 1 else 1e3, abs(self.y[1] - self.y[0]) if self.y.size > 1 else 1e3)
        horiz = np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-12)
        step = np.maximum(cell / 4.0 / horiz, (t_b - t_a) / max_steps)

        def above(t, rows):
            p = o[rows] + t[:, None] * d[rows]
            return p[:, 2] - self.height_at(p[:, 0], p[:, 1])

        rows = np.nonzero(live)[0]
        t_prev = t_a[rows]
        for _ in range(max_steps + 1):
            t_next = np.minimum(t_prev + step[rows], t_b[rows])
            below = above(t_next, rows) <= 0.0
            if np.any(below):
                lo_t, hi_t, r = t_prev[below], t_next[below], rows[below]
                for _ in range(bisections):
                    mid = 0.5 * (lo_t + hi_t)
                    m_below = above(mid, r) <= 0.0
                    hi_t, lo_t = np.where(m_below, mid, hi_t), np.where(m_below, lo_t, mid)
                t_hit[r] = hi_t
            keep = ~below & (t_next < t_b[rows])
            rows, t_prev = rows[keep], t_next[keep]
            if rows.size == 0:
                break
        return t_hit

    def scene_hits(self, origins, dirs, apron_m: float = TERRAIN_APRON_M, floor_m: float | None = None,
                   rgb: bool = False):
        """The first hit of each ray (N, 3) with the ground a rendered scene has over this terrain, the
        path tracer's (``kernel.scene_dict.terrain_ground_dicts``): the mesh, level for ``apron_m`` past the grid's
        edge (``with_apron``), a vertical skirt from the apron's edge down to the lowest height (``skirt``),
        and beyond it a level surround at ``floor_m`` (default: the lowest height; the path tracer's is a
        few ray offsets below it) with the edge albedo (``edge_albedo``). Returns (distance (N,), inf where
        none; albedo (N,), or with ``rgb`` (N, 3) per render channel (``vertex_rgb``, ``edge_rgb``); unit
        normal (N, 3))."""
        o, d = np.asarray(origins, float), np.asarray(dirs, float)
        lo_xy = np.array([self.x[0] - apron_m, self.y[0] - apron_m])
        hi_xy = np.array([self.x[-1] + apron_m, self.y[-1] + apron_m])
        floor = float(self.height_m.min()) if floor_m is None else float(floor_m)
        with np.errstate(divide="ignore", invalid="ignore"):
            ta, tb = (lo_xy - o[:, :2]) / d[:, :2], (hi_xy - o[:, :2]) / d[:, :2]
            near = np.nan_to_num(np.minimum(ta, tb), nan=-np.inf)
            t_in, t_out = near.max(axis=1), np.nan_to_num(np.maximum(ta, tb), nan=np.inf).min(axis=1)
            t_floor = np.where(d[:, 2] < 0, (floor - o[:, 2]) / d[:, 2], np.inf)
        crosses = t_out > np.maximum(t_in, 0.0)                # the ray passes over the apron's rectangle
        t_mesh = self.ray_hits(o, d)                           # (level beyond the grid: kept inside the rectangle)
        t_mesh = np.where(crosses & (t_mesh >= t_in - 1e-6) & (t_mesh <= t_out + 1e-6), t_mesh, np.inf)
        entry = o + np.maximum(t_in, 0.0)[:, None] * d          # where it enters the rectangle from outside
        skirt = crosses & (t_in > 0) & (entry[:, 2] < self.height_at(entry[:, 0], entry[:, 1])) & (entry[:, 2] >= floor)
        t_skirt = np.where(skirt, t_in, np.inf)
        pf = o + np.where(np.isfinite(t_floor), t_floor, 0.0)[:, None] * d
        outside = np.any((pf[:, :2] < lo_xy) | (pf[:, :2] > hi_xy), axis=1)
        t_surround = np.where(outside & (t_floor > 0), t_floor, np.inf)
        t = np.minimum(np.minimum(t_mesh, t_skirt), t_surround)
        p = o + np.where(np.isfinite(t), t, 0.0)[:, None] * d
        _, albedo, normal = self.surface_at(p[:, 0], p[:, 1])
        wall = np.zeros_like(normal)                           # the skirt faces outwards, towards the ray
        axis = np.argmax(near, axis=1)
        wall[np.arange(len(o)), axis] = -np.sign(d[np.arange(len(o)), axis])
        on_skirt = np.isfinite(t) & (t == t_skirt)
        on_surround = np.isfinite(t) & (t == t_surround) & ~on_skirt
        normal = np.where(on_skirt[:, None], wall, np.where(on_surround[:, None], [0.0, 0.0, 1.0], normal))
        albedo = np.where(on_surround, self.edge_albedo(), albedo)
        if rgb:
            cells, channels = self._cells(p[:, 0], p[:, 1]), self.vertex_rgb()
            per = np.stack([self._linear(channels[..., c], cells)[0] for c in range(3)], -1)
            albedo = np.where(on_surround[:, None], self.edge_rgb(), per)
        return t, albedo, normal

    def with_apron(self, distance_m: float) -> "Terrain":
        """This terrain with one more ring of columns ``distance_m`` (m) beyond its edge, at the edge's
        heights and albedo: the ground continues level past the domain instead of ending in a cliff at it
        (a slanted view sees past the domain's edge: 20 km of cloud at 67 deg is 47 km of parallax)."""
        x = np.r_[self.x[0] - distance_m, self.x, self.x[-1] + distance_m]
        y = np.r_[self.y[0] - distance_m, self.y, self.y[-1] + distance_m]
        def pad(a):
            return None if a is None else np.pad(a, ((1, 1), (1, 1)) + ((0, 0),) * (a.ndim - 2), mode="edge")
        return Terrain(x, y, pad(self.height_m), pad(self.land), pad(self.albedo), self.albedo_source, pad(self.kind),
                       pad(self.snow), self.wind_m_s, pad(self.albedo_rgb), self.sea, pad(self.sea_normal))

    def skirt(self, floor_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A vertical wall from the mesh's boundary down to ``floor_m`` (m), facing outwards, as
        (vertices, triangles, albedo) like :meth:`mesh` (the boundary's albedo). Without it, a slanted line
        of sight that passes under the mesh's edge (the edge stands above the flat surround, e.g. a
        plateau) meets the mesh's underside, black to a one-sided diffuse surface: a dark line along the
        domain's edge in a satellite's view. With it, the domain's edge is a cliff, lit as one."""
        ny, nx = self.height_m.shape
        k = np.arange(ny * nx).reshape(ny, nx)
        ring = np.concatenate([k[0, :-1], k[:-1, -1], k[-1, :0:-1], k[:0:-1, 0]])  # counter-clockwise from above
        gx, gy = np.meshgrid(self.x, self.y)
        top = np.stack([gx.ravel()[ring], gy.ravel()[ring], self.height_m.ravel()[ring]], 1)
        bottom = top.copy()
        bottom[:, 2] = float(floor_m)
        n = ring.size
        a_top, a_bot = np.arange(n), n + np.arange(n)
        b_top, b_bot = np.roll(a_top, -1), np.roll(a_bot, -1)
        tall = top[:, 2] > float(floor_m)  # a wall of no height has no triangle (a zero-area face)
        faces = np.concatenate([np.stack([a_top, b_bot, b_top], 1)[np.roll(tall, -1)],
                                np.stack([a_top, a_bot, b_bot], 1)[tall]])
        albedo = np.r_[self.albedo.ravel()[ring], self.albedo.ravel()[ring]]
        return np.concatenate([top, bottom]), faces, albedo


def land_and_kind(read2d, has, shape, attrs=None, latlon=None, source: str = "input"):
    """(land (bool), surface kinds (int8, ``land_use.KINDS``), land source) of a grid: land from LANDMASK, else
    XLAND, else LU_INDEX (not its water or lake classes), else the global mask (``land_mask``) at ``latlon``
    ((lat, lon) in degrees, (y, x)), else land everywhere; kinds from LU_INDEX where the file has it (with
    the land of the first sources kept: a land column of a water class becomes unknown land, a water column
    of a land class sea), else land or sea."""
    kind = kinds_from_land_use(read2d("LU_INDEX"), attrs or {}, source) if has("LU_INDEX") else None
    if has("LANDMASK"):
        land, land_source = read2d("LANDMASK") > 0.5, "LANDMASK"
    elif has("XLAND"):
        land, land_source = read2d("XLAND") < 1.5, "XLAND"
    elif kind is not None:
        land, land_source = ~np.isin(kind, WATER_KINDS), f"LU_INDEX ({str((attrs or {}).get('MMINLU', '')).strip()})"
    elif latlon is not None:
        from . import land_mask
        land, land_source = land_mask.is_land(*latlon), land_mask.SOURCE
    else:
        land, land_source = np.ones(shape, bool), "none in the file: land assumed"
    if kind is None:
        kind = np.where(land, KIND["land"], KIND["sea"]).astype(np.int8)
    else:
        water = np.isin(kind, WATER_KINDS)
        kind = np.where(land & water, KIND["land"], np.where(~land & ~water, KIND["sea"], kind)).astype(np.int8)
    return land, kind, land_source


def surface_fields(read2d, has, z_surface_m: np.ndarray, attrs=None, latlon=None,
                   source: str = "input") -> tuple[dict, dict]:
    """Terrain coordinates and attributes of a wrfout time.

    Parameters
    ----------
    read2d : callable
        ``read2d(name)``: the variable's (y, x) values at that time and sub-box.
    has : callable
        ``has(name)``: whether the file has the variable.
    z_surface_m : numpy.ndarray
        (y, x) height of the lowest w-level (m above MSL), the terrain where the file has no HGT.
    attrs : dict, optional
        The file's global attributes (MMINLU, ISWATER, ISLAKE, ISICE for LU_INDEX).
    latlon : (numpy.ndarray, numpy.ndarray), optional
        The columns' latitude and longitude (degrees), for the global land mask where the file has no land.
    source : str
        The file, named in errors.

    Returns
    -------
    (dict, dict)
        Coordinates name -> ((y, x), array, attributes) for ``terrain_height`` (m), ``land`` (int8),
        ``surface_albedo``, ``surface_kind`` (int8) and ``snow_cover`` (where the file has snow); attributes
        ``surface_albedo_source``, ``land_source``, ``terrain_source`` and, where the file has U10/V10 and
        water, ``wind_10m_water_m_s`` (the mean 10 m wind speed over the water columns).
    """
    hgt, hgt_source = (read2d("HGT"), "HGT") if has("HGT") else (z_surface_m, "lowest w-level (PH + PHB) / g")
    land, kind, land_source = land_and_kind(read2d, has, hgt.shape, attrs, latlon, source)
    albedo_var = next((v for v in ("ALBEDO", "ALBBCK") if has(v)), None)
    if albedo_var:
        albedo, albedo_source = np.clip(read2d(albedo_var), 0.0, 1.0), albedo_var
    else:
        albedo = np.where(land, LAND_ALBEDO, WATER_ALBEDO)
        albedo_source = f"default of WRF's LW12 table (land {LAND_ALBEDO}, water {WATER_ALBEDO}) by {land_source}"
    dims = ("y", "x")
    from .land_use import KINDS
    coords = {"terrain_height": (dims, np.asarray(hgt, np.float64),
                                 {"units": "m", "long_name": "terrain height above MSL", "source": hgt_source}),
              "land": (dims, land.astype(np.int8), {"long_name": "1 land, 0 water", "source": land_source}),
              "surface_albedo": (dims, np.asarray(albedo, np.float64),
                                 {"units": "1", "long_name": "surface albedo", "source": albedo_source}),
              "surface_kind": (dims, kind, {"long_name": "surface kind: " + ", ".join(f"{k} {n}" for k, n in
                                                                               enumerate(KINDS)),
                                            "source": "LU_INDEX" if has("LU_INDEX") else land_source})}
    snow, snow_source = snow_cover(read2d, has)
    if snow is not None:
        coords["snow_cover"] = (dims, np.asarray(snow, np.float64),
                                {"units": "1", "long_name": "snow-covered fraction", "source": snow_source})
    out = {"surface_albedo_source": albedo_source, "land_source": land_source, "terrain_source": hgt_source}
    water = np.isin(kind, WATER_KINDS)
    if has("U10") and has("V10") and np.any(water):
        out["wind_10m_water_m_s"] = float(np.mean(np.hypot(read2d("U10"), read2d("V10"))[water]))
    return coords, out
