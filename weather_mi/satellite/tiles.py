"""``satellite`` beyond one machine: the image cut into tiles of pixels (``tile_plan``), each tile a Dask
task that reads only its sub-box of the wrfout (its pixels' lines of sight, their sun paths and a halo:
``tile_plan.tile_box``), builds that sub-box's optics, path-traces its pixels (the whole image's rays,
sun and height grid) and returns them; the client puts the tiles together into the image and the CF
dataset of ``imagery.satellite_dataset``, the same NetCDF/EXR/PNG as one process writes.

No process holds the whole domain: the client reads the outline (2-D fields), a worker one sub-box at a
time. With one tile whose sub-box is the whole domain the image is the one-process render bit for bit
(same volume, rays and seed); with several, each tile's seed is ``seed + its index`` and the image agrees
with the one-process render within noise once the halo holds the light that reaches the tile's pixels
(docs/tiles.md measures it).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from .bands import DEFAULT_GROUND_ALBEDO
from .tile_plan import DEFAULT_HALO_KM, DEFAULT_TILE_PX, Outline, Tile, domain_outline, plan_tiles


@dataclass(frozen=True)
class TileJob:
    """What a worker needs for one tile: the file and height grid (``Outline``'s figures), the tile, its
    corner rays, the sun (azimuth in the grid's frame, elevation; degrees), the band and the render's
    options (``optics``: ``optical_volume``'s keywords, ``sizes`` None meaning the file's default;
    ``estimator``: ``render_reference``'s)."""

    path: str
    time_index: int
    grid: tuple            # (dz, bottom, top, dx, dy) in m
    tile: Tile
    rays: object           # scene.spec.RayTable of the tile's pixels
    sun: tuple             # (azimuth, elevation) in degrees
    band: str
    rayleigh: bool = False
    ground_albedo: float = DEFAULT_GROUND_ALBEDO
    seed: int = 0
    read_sizes: bool = True
    optics: dict = field(default_factory=dict)
    estimator: dict = field(default_factory=dict)
    variant: str | None = None
    surface: str = "file"          # ``scene.surface``: the ground under a domain with its own
    wind_m_s: float | None = None
    sun_meta: dict = field(default_factory=dict)   # ``place.sun_from_time``'s, of the whole domain
    satellite: str = "goes-east"
    rgb: bool = False              # the true-colour bands, one per channel (``bands.rgb_volume``)


@dataclass(frozen=True)
class OutlineVolume:
    """What ``imagery.satellite_dataset`` reads of the volume: its box, species, attributes and the ground
    (``io.terrain.Terrain`` of the whole domain from the outline's 2-D fields: the land mask under the pixels)."""

    bbox: tuple
    species: tuple
    attrs: dict
    terrain: object = None


def tile_hydrometeors(job: TileJob):
    """The tile's sub-box of the file as Hydrometeors on the whole domain's height grid, in its frame."""
    from ..io.outline import read_sub_box
    return read_sub_box(job.path, job.time_index, job.grid, job.tile.x, job.tile.y, job.read_sizes)


def render_tile(job: TileJob) -> dict:
    """Read, build and path-trace one tile (in this process): {"tile", "radiance", "stderr", "transmittance",
    "spp", "seconds", "read_seconds", "grid_shape", "volume_bytes", "peak_rss_bytes"}."""
    import resource

    from ..optics.volume import default_sizes, optical_volume
    from ..reference.render import render_reference
    from ..scene.spec import Camera, Ground, SceneSpec, Sun
    from .bands import band, band_volume, rgb_volume, true_color_bands
    from .geostationary import satellite
    t0 = time.perf_counter()
    hyd = tile_hydrometeors(job)
    optics = dict(job.optics)
    optics["sizes"] = optics.get("sizes") or default_sizes(hyd)
    vol = optical_volume(hyd, **optics)
    b = band(job.band)
    bands = true_color_bands(satellite(job.satellite)) if job.rgb else (b,)
    bvol = _with_surface(job, rgb_volume(vol, bands) if job.rgb else band_volume(vol, b), bands, hyd)
    if job.rayleigh:
        from ..optics.rayleigh import with_rayleigh
        bvol = with_rayleigh(bvol, b.wavelength_m, hyd["rho_air"].values)
    grid_shape, nbytes = tuple(int(n) for n in vol.beta_total.shape), _volume_bytes(bvol)
    del hyd, vol
    t_read = time.perf_counter() - t0
    (x0, y0, _), (x1, y1, top) = bvol.bbox
    h, w = job.rays.origins_m.shape[0] - 1, job.rays.origins_m.shape[1] - 1
    cam = Camera.orthographic(center=((x0 + x1) / 2, (y0 + y1) / 2, top + 1000.0), direction=(0.0, 0.0, -1.0),
                              width=max(x1 - x0, y1 - y0), height=max(x1 - x0, y1 - y0))  # nominal: rays from the table
    spec = SceneSpec(camera=cam, sun=Sun(job.sun[0], job.sun[1], (1.0, 1.0, 1.0)), sky=None,
                     ground=Ground(albedo=job.ground_albedo), width=w, height=h, seed=job.seed + job.tile.index,
                     rays=job.rays)
    img = render_reference(spec, bvol, normalize="reflectance", progress=False, variant=job.variant, **job.estimator)
    return {"tile": job.tile, "radiance": img.radiance, "stderr": img.stderr, "transmittance": img.transmittance,
            "spp": int(img.metadata.get("spp", 0)), "seconds": time.perf_counter() - t0, "read_seconds": t_read,
            "grid_shape": grid_shape, "volume_bytes": nbytes,
            "peak_rss_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024}


def _with_surface(job: TileJob, bvol, bands, hyd):
    """The sub-box's ground in ``bands`` as ``imagery.satellite_scene`` puts it (``scene.surface``; the sea's glint
    from each column's own sun, ``glint.sea_normals``, on the sub-box's columns)."""
    from dataclasses import replace

    from ..scene.place import place_of
    from ..scene.spec import Sun
    from ..scene.surface import with_surface
    from .geostationary import satellite
    bvol = with_surface(bvol, [b.wavelength_m * 1e6 for b in bands], job.surface, job.wind_m_s)
    place = place_of(hyd) if "lat" in hyd.coords else None
    if bvol.terrain is not None and bvol.terrain.sea and place is not None:
        from .glint import sea_normals
        normals = sea_normals(place, satellite(job.satellite), job.sun_meta, Sun(job.sun[0], job.sun[1]))
        bvol = replace(bvol, terrain=replace(bvol.terrain, sea_normal=normals))
    return bvol


def _volume_bytes(vol) -> int:
    return int(sum(np.asarray(a).nbytes for a in (vol.beta_ext, vol.beta_total, vol.albedo, vol.weights)))


def _render_tile_task(job: TileJob) -> dict:
    """On a worker: ``render_tile`` on the process's one rendering thread (``dask_passes.on_render_thread``)."""
    from ..reference.dask_passes import on_render_thread
    return on_render_thread(render_tile, job)


@dataclass(frozen=True)
class TiledSatellite:
    """A satellite render planned in tiles: the scene of the whole image (``imagery.SatelliteScene`` over
    an ``OutlineVolume``), the outline and the tiles."""

    scene: object
    outline: Outline
    tiles: tuple
    halo_km: float
    tile_px: int
    surface: str = "file"
    wind_m_s: float | None = None


def tiled_satellite(path, time=None, sat="goes-east", band_name: str = "0.64", resolution_km: float = 1.0, *,
                    tile_px: int = DEFAULT_TILE_PX, halo_km: float = DEFAULT_HALO_KM, rayleigh: bool = False,
                    ground_albedo=DEFAULT_GROUND_ALBEDO, seed: int = 0, max_vza_deg: float = 80.0, lat=None, lon=None,
                    date=None, surface: str = "file", wind_m_s: float | None = None,
                    rgb: bool = False) -> TiledSatellite:
    """The plan of a tiled satellite image of one time of the wrfout ``path`` (``imagery.satellite_scene``'s
    view and sun from the outline; ``lat``/``lon``/``date`` place an ideal case; ``surface``, ``wind_m_s``:
    the ground, as ``satellite_scene``'s, built per tile; ``rgb``: the true-colour bands in one render, one per
    channel, ``ground_albedo`` one value or one per band, None: the sea's per band (``truecolor``'s))."""
    from ..scene.surface import check_surface
    check_surface(surface)
    from ..scene.place import place_of, sun_from_time
    from ..scene.spec import Camera, Ground, SceneSpec, Sun
    from .bands import SEA_ALBEDO, band, check_band_on, true_color_bands
    from .geostationary import satellite
    from .imagery import RAY_START_ABOVE_M, SatelliteScene
    from .rays import satellite_view
    outline = domain_outline(path, time, lat=lat, lon=lon, date=date)
    ds = outline.dataset
    place = place_of(ds)
    if place is None:
        raise ValueError(f"{path}: a satellite view needs the domain's latitude/longitude; the file has none "
                         "(an ideal case: give --lat and --lon, and --date for the sun)")
    sat = satellite(sat) if isinstance(sat, str) else sat
    bands = true_color_bands(sat) if rgb else ()
    b = bands[0] if rgb else band(band_name)
    check_band_on(b, sat)
    if rgb and rayleigh:
        raise ValueError("--tile-size --rgb: not with --rayleigh (the per-band renders of the air and the Rayleigh "
                         "correction need the whole domain's air column); drop one of them")
    if rgb:
        ground_albedo = tuple(SEA_ALBEDO[x.name] if ground_albedo is None else float(ground_albedo) for x in bands)
    elif ground_albedo is None:
        ground_albedo = DEFAULT_GROUND_ALBEDO
    top = outline.top_m + RAY_START_ABOVE_M
    view = satellite_view(place, sat, resolution_km, top, max_vza_deg, str(path))
    azimuth, elevation, sun_meta = sun_from_time(ds)
    tiles = tuple(plan_tiles(outline, view.rays, azimuth, elevation, tile_px, halo_km))
    (x0, y0, _), (x1, y1, _) = outline.bbox
    extent = max(x1 - x0, y1 - y0)
    cam = Camera.orthographic(center=((x0 + x1) / 2, (y0 + y1) / 2, top + 1000.0), direction=(0.0, 0.0, -1.0),
                              width=extent, height=extent)
    w, h = view.size
    spec = SceneSpec(camera=cam, sun=Sun(azimuth, elevation, (1.0, 1.0, 1.0)), sky=None,
                     ground=Ground(albedo=ground_albedo), width=w, height=h, seed=seed, rays=view.rays)
    species = ("rayleigh",) if rayleigh else ()
    from ..io.terrain import Terrain
    terrain = None if surface == "flat" else Terrain.of(ds)
    vol = OutlineVolume(outline.bbox, species, {"source": str(path), "land_source": ds.attrs.get("land_source", "")},
                        terrain)
    return TiledSatellite(SatelliteScene(spec, vol, view, sat, b, sun_meta, bands, place.source), outline, tiles,
                          float(halo_km), int(tile_px), surface, wind_m_s)


def tile_jobs(plan: TiledSatellite, *, optics: dict | None = None, read_sizes: bool = True,
              variant: str | None = None, **estimator) -> list[TileJob]:
    """One ``TileJob`` per tile of ``plan``."""
    from ..scene.spec import RayTable
    o, spec, rgb = plan.outline, plan.scene.spec, bool(plan.scene.bands)
    jobs = []
    for t in plan.tiles:
        rows, cols = slice(t.rows.start, t.rows.stop + 1), slice(t.cols.start, t.cols.stop + 1)
        rays = RayTable(spec.rays.origins_m[rows, cols], spec.rays.directions[rows, cols])
        jobs.append(TileJob(o.path, o.time_index, (o.dz_m, o.bottom_m, o.top_m, o.dx_m, o.dy_m), t, rays,
                            (spec.sun.azimuth, spec.sun.elevation), plan.scene.band.name,
                            "rayleigh" in plan.scene.vol.species,
                            tuple(spec.ground.albedo) if rgb else float(spec.ground.albedo[0]), int(spec.seed),
                            read_sizes, dict(optics or {}), dict(estimator), variant, plan.surface, plan.wind_m_s,
                            dict(plan.scene.sun_meta), plan.scene.satellite.name, rgb))
    return jobs


def render_tiles(plan: TiledSatellite, client=None, *, optics: dict | None = None, read_sizes: bool = True,
                 on_tile=None, store=None, **estimator):
    """Render every tile of ``plan`` (Dask tasks on ``client``, or one after another in this process) and
    put them together: (``xarray.Dataset`` of ``imagery.satellite_dataset``, Image, [per-tile figures]).
    ``estimator``: ``render_reference``'s (spp, target_rse, ...); ``on_tile(figures)`` after each tile rendered;
    ``store``: an ``io.resumable.TileStore`` whose finished tiles are read back instead of rendered, and into
    which each new one is saved."""
    from ..kernel.variant import ensure_registered
    from ..reference.tiled_render import finished_tiles, run_tiles
    variant = ensure_registered()  # this process's variant (the default where none is set): the workers' too
    jobs = tile_jobs(plan, optics=optics, read_sizes=read_sizes, variant=variant, **estimator)
    t0 = time.perf_counter()
    results = finished_tiles(plan.tiles, store)
    for r in run_tiles([j for j in jobs if j.tile.index not in results], render_tile, _render_tile_task, client,
                       variant):
        results[r["tile"].index] = r
        if store is not None:
            store.save(r["tile"].index, r)
        if on_tile:
            on_tile(r)
    return assemble(plan, [results[t.index] for t in plan.tiles if t.index in results], time.perf_counter() - t0)


def assemble(plan: TiledSatellite, results: list[dict], seconds: float):
    """The whole image (Image with the tiles' reflectance, standard error and transmittance, the render's
    metadata) and its dataset from the tiles' ``render_tile`` results."""
    from ..io.image import Image
    from ..reference.estimates import noise_stats
    from .imagery import satellite_dataset
    w, h = plan.scene.view.size
    rad, se = np.full((h, w, 3), np.nan, np.float32), np.full((h, w, 3), np.nan, np.float32)
    trans = np.full((h, w), np.nan, np.float32)
    for r in results:
        t = r["tile"]
        rad[t.rows, t.cols], se[t.rows, t.cols] = r["radiance"], r["stderr"]
        if r["transmittance"] is not None:
            trans[t.rows, t.cols] = r["transmittance"]
    if len(results) != len(plan.tiles) or np.isnan(rad).any():
        raise RuntimeError(f"tiled satellite render: {len(results)} of {len(plan.tiles)} tiles came back")
    noise = noise_stats(rad, se, trans < 0.5)
    tiles = sorted(results, key=lambda r: r["tile"].index)
    meta = {"renderer": "reference", "normalize": "reflectance", "spp": min(r["spp"] for r in results),
            "seconds": float(seconds), "noise": noise,
            "tiles": len(tiles), "tile_px": plan.tile_px, "halo_km": plan.halo_km,
            "tile_seconds": [round(r["seconds"], 3) for r in tiles],
            "tile_grid_shapes": [list(r["grid_shape"]) for r in tiles]}
    img = Image(rad, se, meta, trans)
    if plan.scene.bands:  # true colour: a band per channel, the NetCDF's band dimension
        from .truecolor import rgb_dataset
        return rgb_dataset([satellite_dataset(plan.scene, img, c) for c in range(3)]), img, tiles
    return satellite_dataset(plan.scene, img), img, tiles


__all__ = ["TileJob", "OutlineVolume", "TiledSatellite", "tiled_satellite", "tile_jobs", "render_tile",
           "render_tiles", "assemble", "tile_hydrometeors"]
