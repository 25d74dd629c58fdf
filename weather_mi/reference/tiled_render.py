"""The aerial ``render`` beyond one machine: the image of a camera above the model's grid cut into tiles of
pixels (``reference.tile_plan``, by the camera's own rays), each tile a Dask task that reads only its sub-box
of the wrfout (``io.outline.read_sub_box``: its pixels' camera rays through the grid, their slant sun paths
and a halo), builds that sub-box's optics and path-traces its pixels alone; the client, which never holds a
3-D field, puts the tiles together into the Image (radiance, standard error, transmittance) of the EXR and PNG.

Seeds: a tile renders the whole image's scene (camera, film, seed, passes) over its pixels only
(``render_pixels``: the persistent lanes' pixel subset), so every pixel gets the random numbers it gets in the
one-process render: one tile whose sub-box is the whole domain is that render bit for bit, and several tiles
differ from it only where a path leaves a tile's sub-box (the halo makes that rare; docs/tiles.md measures it).

Framing: the client has no 3-D field to find the cloud's box, so the camera frames the domain's box
(``OutlineBox``; ``scene.framing.scene_spec`` with ``--camera auto``: the aerial oblique for a domain wider than
300 km). A camera below the top of the grid (a ground camera: its rays cross the whole domain) is refused
(``tile_plan.check_above``).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from ..io.outline import Outline
from ..scene.spec import SceneSpec
from .tile_plan import DEFAULT_HALO_KM, DEFAULT_TILE_PX, Tile, check_above, plan_tiles


@dataclass(frozen=True)
class OutlineBox:
    """What ``scene.framing.scene_spec`` reads of a volume, for a domain known by its outline: its box (m),
    which also stands for the cloud's (``occupied_bbox``), and no terrain."""

    bbox: tuple
    terrain: object = None

    def occupied_bbox(self):
        return self.bbox


def corner_rays(spec: SceneSpec) -> tuple[np.ndarray, np.ndarray]:
    """(origins (H + 1, W + 1, 3) m, directions) of the rays through the pixel corners of ``spec``'s sensor
    (Mitsuba's own, ``kernel.scene_dict.sensor_dict``, in the world frame), or of its ray table."""
    if spec.rays is not None:
        return spec.rays.origins_m, spec.rays.directions
    import mitsuba as mi
    from ..kernel.jitarrays import aligned_float
    from ..kernel.scene_dict import sensor_dict
    from ..kernel.variant import set_variant
    from .passes import current_or_default_variant
    set_variant(current_or_default_variant())
    sensor = mi.load_dict(sensor_dict(spec))
    h, w = spec.height, spec.width
    jj, ii = np.meshgrid(np.arange(h + 1), np.arange(w + 1), indexing="ij")
    pos = mi.Point2f(aligned_float(mi, (ii / w).ravel()), aligned_float(mi, (jj / h).ravel()))
    ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
    o = np.stack([np.asarray(ray.o[k], np.float64) for k in range(3)], -1).reshape(h + 1, w + 1, 3)
    d = np.stack([np.asarray(ray.d[k], np.float64) for k in range(3)], -1).reshape(h + 1, w + 1, 3)
    return o, d


@dataclass(frozen=True)
class TiledRender:
    """A render planned in tiles: the whole image's scene, the domain's outline and the tiles."""

    spec: SceneSpec
    outline: Outline
    tiles: tuple
    halo_km: float
    tile_px: int


def plan_render(outline: Outline, spec: SceneSpec, tile_px: int = DEFAULT_TILE_PX,
                halo_km: float = DEFAULT_HALO_KM) -> TiledRender:
    """The tiles of ``spec``'s image over ``outline``'s domain (ValueError for a camera below the grid's top)."""
    o, d = corner_rays(spec)
    check_above(o, outline.top_m)
    tiles = plan_tiles(outline, o, d, spec.sun.azimuth, spec.sun.elevation, tile_px, halo_km)
    return TiledRender(spec, outline, tuple(tiles), float(halo_km), int(tile_px))


@dataclass(frozen=True)
class RenderTileJob:
    """What a worker needs for one tile: the file, its time and the domain's grid (``Outline.grid``), the tile,
    the whole image's scene and the render's options (``optics``: ``optical_volume``'s keywords, ``sizes`` None
    meaning the file's default; ``surface``, ``wind_m_s``: ``scene.surface``'s; ``estimator``:
    ``render_pixels``')."""

    path: str
    time_index: int
    grid: tuple
    tile: Tile
    spec: SceneSpec
    optics: dict = field(default_factory=dict)
    surface: str = "albedo"
    wind_m_s: float | None = None
    read_sizes: bool = True
    estimator: dict = field(default_factory=dict)
    variant: str | None = None


def render_tile(job: RenderTileJob) -> dict:
    """Read, build and path-trace one tile (in this process): {"tile", "radiance", "stderr", "transmittance",
    "spp", "seconds", "read_seconds", "grid_shape", "peak_rss_bytes"}."""
    import resource

    from ..io.outline import read_sub_box
    from ..optics.volume import default_sizes, optical_volume
    from ..scene.surface import RGB_UM, with_surface
    t0 = time.perf_counter()
    hyd = read_sub_box(job.path, job.time_index, job.grid, job.tile.x, job.tile.y, job.read_sizes)
    optics = dict(job.optics)
    optics["sizes"] = optics.get("sizes") or default_sizes(hyd)
    vol = with_surface(optical_volume(hyd, **optics), RGB_UM, job.surface, job.wind_m_s)
    del hyd
    t_read = time.perf_counter() - t0
    out = render_pixels(job.spec, vol, job.tile, variant=job.variant, **job.estimator)
    out.update(tile=job.tile, seconds=time.perf_counter() - t0, read_seconds=t_read,
               grid_shape=[int(n) for n in vol.beta_total.shape],
               peak_rss_bytes=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024)
    return out


def render_pixels(spec: SceneSpec, vol, tile: Tile, variant: str | None = None, **estimator) -> dict:
    """The pixels ``tile.rows`` x ``tile.cols`` of ``render_reference(spec, vol, **estimator)``: the same
    passes, seeds and per-pixel random numbers (persistent lanes over a pixel subset; elsewhere every pixel
    is rendered and the others dropped), merged as ``render_reference`` merges them. {"radiance", "stderr"
    ((h, w, 3) float32), "transmittance" ((h, w) float32), "spp"}. Planned passes only: ValueError for
    ``target_rse`` and ``max_seconds`` (the whole image's noise decides those)."""
    from ..kernel.variant import path_tracing_width, set_variant
    from .estimates import pass_stderr, welford_update
    from .options import ReferenceOptions
    from .passes import PassOptions, PassScene, current_or_default_variant, local_passes, plan_passes
    from .render import _check_inputs, _scale
    o = ReferenceOptions.of_call(None, (), estimator).resolved(spec)
    if o.target_rse is not None or o.max_seconds is not None:
        raise ValueError("--tile-size: a tile renders the planned passes (--spp), not --target-rse or --max-seconds "
                         "(they depend on the whole image's noise)")
    _check_inputs(spec, vol, o.integrator, variant)
    set_variant(variant if variant is not None else current_or_default_variant())
    with path_tracing_width():
        spp_list = plan_passes(spec, o.spp, o.passes)
        job = PassScene(spec, vol, PassOptions(o, planned=len(spp_list)), "")
        pix = tile.pixels(spec.width)
        shape = (tile.rows.stop - tile.rows.start, tile.cols.stop - tile.cols.start, 3)
        mean, m2, scale, n = np.zeros(shape), np.zeros(shape), _scale(spec, o.normalize), 0
        for i, raw, _ in local_passes(job.build(), spec.seed, lambda i: spp_list[i], lambda i: i < len(spp_list), 0,
                                      lambda i: pix, n_pixels=spec.width * spec.height, limit=len(spp_list)):
            n = i + 1
            welford_update(mean, m2, raw.astype(np.float64)[tile.rows, tile.cols, :3] * scale, n)
        transmittance = tile_transmittance(spec, vol, tile)  # at the path tracer's width, as render_reference's
    return {"radiance": mean.astype(np.float32), "stderr": pass_stderr(m2, n).astype(np.float32),
            "transmittance": transmittance, "spp": int(sum(spp_list))}


def tile_transmittance(spec: SceneSpec, vol, tile: Tile) -> np.ndarray:
    """(h, w) eye-ray transmittance of ``vol`` over the tile's pixels (``estimates.eye_optical_depth`` through
    the sensor's film cropped to the tile: the same pixel centres as the whole film's)."""
    import mitsuba as mi
    from ..kernel.scene_dict import recentred, sensor_dict
    from .estimates import eye_optical_depth, view_optical_depth
    h, w = tile.rows.stop - tile.rows.start, tile.cols.stop - tile.cols.start
    if spec.rays is not None or (h, w) == (spec.height, spec.width):  # a ray table has no crop: the whole view
        return np.exp(-view_optical_depth(spec, vol)[tile.rows, tile.cols]).astype(np.float32)
    spec_k, vol_k, _ = recentred(spec, vol)
    d = sensor_dict(spec_k)
    d["film"].update(crop_offset_x=tile.cols.start, crop_offset_y=tile.rows.start, crop_width=w, crop_height=h)
    tau = eye_optical_depth(mi.load_dict(d), vol_k, replace(spec_k, width=w, height=h))
    return np.exp(-tau).astype(np.float32)


def _render_tile_task(job: RenderTileJob) -> dict:
    """On a worker: ``render_tile`` on the process's one rendering thread (``dask_passes.on_render_thread``)."""
    from .dask_passes import on_render_thread
    return on_render_thread(render_tile, job)


def tile_jobs(plan: TiledRender, *, optics: dict | None = None, surface: str = "albedo",
              wind_m_s: float | None = None, read_sizes: bool = True, variant: str | None = None,
              **estimator) -> list[RenderTileJob]:
    """One ``RenderTileJob`` per tile of ``plan``."""
    o = plan.outline
    return [RenderTileJob(o.path, o.time_index, o.grid, t, plan.spec, dict(optics or {}), surface, wind_m_s,
                          read_sizes, dict(estimator), variant) for t in plan.tiles]


def render_tiles(plan: TiledRender, client=None, *, store=None, on_tile=None, **kw):
    """Render the tiles of ``plan`` (Dask tasks on ``client``, or one after another here) and put them
    together: (Image, [per-tile figures]). ``store``: an ``io.resumable.TileStore`` whose finished tiles are
    read back instead of rendered, and into which each new one is saved; ``on_tile(figures)`` after each new
    tile; ``kw``: ``tile_jobs``' (optics, surface, wind_m_s, read_sizes and the estimator's)."""
    from ..kernel.variant import ensure_registered
    variant = ensure_registered()
    t0 = time.perf_counter()
    results, jobs = finished_tiles(plan.tiles, store), []
    for job in tile_jobs(plan, variant=variant, **kw):
        if job.tile.index not in results:
            jobs.append(job)
    for r in run_tiles(jobs, render_tile, _render_tile_task, client, variant):
        results[r["tile"].index] = r
        if store is not None:
            store.save(r["tile"].index, r)
        if on_tile:
            on_tile(r)
    return assemble(plan, [results[t.index] for t in plan.tiles], time.perf_counter() - t0)


def finished_tiles(tiles, store) -> dict:
    """{tile index: result} of the ``tiles`` ``store`` holds (None: none), each with its ``tile``."""
    out = {}
    for t in tiles if store is not None else ():
        r = store.load(t.index)
        if r is not None:
            out[t.index] = dict(r, tile=t)
    return out


def run_tiles(jobs, here, task, client, variant: str):
    """The results of ``jobs`` in order: ``here(job)`` in this process, or ``task(job)`` as Dask tasks on
    ``client`` (its workers checked first; rendered as they come, handed over in order)."""
    if client is None:
        for job in jobs:
            yield here(job)
        return
    from .cluster import check_workers
    check_workers(client, None, variant)
    futures = [client.submit(task, job, pure=False, key=f"weather-mi-tile-{job.tile.index}-{time.time_ns()}")
               for job in jobs]
    try:
        for fut in futures:
            yield fut.result()
    finally:
        for fut in futures:
            fut.cancel()


def assemble(plan: TiledRender, results: list[dict], seconds: float):
    """(Image of the whole view from the tiles' ``render_tile`` results, the results in tile order)."""
    from ..io.image import Image
    from .estimates import noise_stats
    w, h = plan.spec.width, plan.spec.height
    rad, se = np.full((h, w, 3), np.nan, np.float32), np.full((h, w, 3), np.nan, np.float32)
    trans = np.full((h, w), np.nan, np.float32)
    for r in results:
        t = r["tile"]
        rad[t.rows, t.cols], se[t.rows, t.cols], trans[t.rows, t.cols] = r["radiance"], r["stderr"], r["transmittance"]
    if len(results) != len(plan.tiles) or np.isnan(rad).any():
        raise RuntimeError(f"tiled render: {len(results)} of {len(plan.tiles)} tiles came back")
    tiles = sorted(results, key=lambda r: r["tile"].index)
    meta = {"renderer": "reference", "spp": min(r["spp"] for r in tiles), "seconds": float(seconds),
            "noise": noise_stats(rad, se, trans < 0.5), "scene": plan.spec.to_dict(),
            "source": plan.outline.path, "tiles": len(tiles), "tile_px": plan.tile_px, "halo_km": plan.halo_km,
            "tile_seconds": [round(float(r["seconds"]), 3) for r in tiles],
            "tile_grid_shapes": [list(r["grid_shape"]) for r in tiles]}
    return Image(rad, se, meta, trans), tiles


__all__ = ["OutlineBox", "corner_rays", "TiledRender", "plan_render", "RenderTileJob", "render_tile", "render_pixels",
           "tile_transmittance", "tile_jobs", "render_tiles", "finished_tiles", "run_tiles", "assemble"]
