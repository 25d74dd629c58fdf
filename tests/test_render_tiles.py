"""``render --tile-size``: the aerial render in tiles of pixels (``reference.tile_plan`` by the camera's rays,
``reference.tiled_render``), each tile reading only its sub-box of the wrfout and a halo, rendering its pixels
with the whole image's seeds; ``satellite --tile-size --rgb`` and ``--resume`` (``io.resumable.TileStore``).
Real data: ../shared/data/wrf/wrfout_quarter_ss_0130.nc (skipped without it)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from weather_mi.io.outline import Outline
from weather_mi.reference import tile_plan as tp
from weather_mi.reference import tiled_render as tr
from weather_mi.scene.spec import Camera, SceneSpec, Sun

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "wrf" / "wrfout_quarter_ss_0130.nc"
needs_data = pytest.mark.skipif(not DATA.is_file(), reason=f"real WRF supercell not found at {DATA}")
ORBIT = ["--camera", "orbit", "--camera-elevation", "50"]


def synthetic_outline(nx=100, ny=75, dx=2000.0, dy=2000.0, bottom=500.0, top=15500.0, nz=30) -> Outline:
    """A domain of nx x ny columns (centres from 0 m) between ``bottom`` and ``top`` without a file."""
    dz = (top - bottom) / nz
    ds = xr.Dataset(coords={"z": bottom + dz * (np.arange(nz) + 0.5), "y": np.arange(ny) * dy, "x": np.arange(nx) * dx})
    return Outline(ds, "none", 0, dz, bottom, top, dx, dy)


def crossed_columns(spec: SceneSpec, outline: Outline, tile, n_rays=400, steps=300, seed=1) -> set:
    """Brute force: the (ix, iy) columns of the domain that rays through random points of the tile's pixels
    (Mitsuba's sensor) cross between the grid's bottom and top, and that the sun paths of their points cross
    on the way up to the top (``steps`` points a ray, 40 a sun path)."""
    import mitsuba as mi

    from weather_mi.kernel.jitarrays import aligned_float
    from weather_mi.kernel.scene_dict import sensor_dict
    from weather_mi.kernel.variant import set_variant
    set_variant()
    rng = np.random.default_rng(seed)
    u = (tile.cols.start + rng.random(n_rays) * (tile.cols.stop - tile.cols.start)) / spec.width
    v = (tile.rows.start + rng.random(n_rays) * (tile.rows.stop - tile.rows.start)) / spec.height
    ray, _ = mi.load_dict(sensor_dict(spec)).sample_ray(0.0, 0.5, mi.Point2f(aligned_float(mi, u), aligned_float(mi, v)),
                                                        mi.Point2f(0.5, 0.5))
    o = np.stack([np.asarray(ray.o[k], np.float64) for k in range(3)], -1)
    d = np.stack([np.asarray(ray.d[k], np.float64) for k in range(3)], -1)
    z = np.linspace(outline.bottom_m, outline.top_m, steps)
    t = (z[None, :] - o[:, 2:3]) / d[:, 2:3]  # (rays, steps): where each ray is at each height
    pts = (o[:, None, :] + d[:, None, :] * t[..., None]).reshape(-1, 3)
    az, el = np.radians(spec.sun.azimuth), np.radians(spec.sun.elevation)
    s = np.array([np.sin(az), np.cos(az)]) / np.tan(el)
    f = np.linspace(0.0, 1.0, 40)
    sun = pts[:, None, :2] + (outline.top_m - pts[:, None, 2:3]) * f[None, :, None] * s
    xy = np.concatenate([pts[:, :2], sun.reshape(-1, 2)])
    ix = np.floor(xy[:, 0] / outline.dx_m + 0.5).astype(int)
    iy = np.floor(xy[:, 1] / outline.dy_m + 0.5).astype(int)
    _, ny, nx = outline.shape
    ok = (ix >= 0) & (ix < nx) & (iy >= 0) & (iy < ny)
    return set(zip(ix[ok].tolist(), iy[ok].tolist()))


def test_a_tiles_sub_box_holds_every_column_its_rays_and_sun_paths_cross():
    """An aerial oblique (orbit camera at 50 deg) over a 200 x 150 km domain, 12 tiles, no halo: every column
    that rays through random points of a tile's pixels cross between bottom and top, or the sun paths of their
    points, lies in the tile's sub-box (brute force, Mitsuba's own sensor); the sub-boxes are smaller than the
    domain; a halo widens each by its width."""
    outline = synthetic_outline()
    spec = SceneSpec(camera=Camera.orbit(outline.bbox, azimuth=200.0, elevation=50.0, fov=45.0),
                     sun=Sun(290.0, 35.0), width=40, height=30)
    plan = tr.plan_render(outline, spec, tile_px=10, halo_km=0.0)
    assert len(plan.tiles) == 12
    _, ny, nx = outline.shape
    for t in plan.tiles:
        cols = crossed_columns(spec, outline, t)
        outside = [(ix, iy) for ix, iy in cols if not (t.x.start <= ix < t.x.stop and t.y.start <= iy < t.y.stop)]
        assert not outside, f"tile {t.index}: {len(outside)} of {len(cols)} columns outside its sub-box {t}"
        assert cols  # the rays do cross the domain: the check is not empty
    assert max(t.cells for t in plan.tiles) < 0.6 * nx * ny  # the sub-boxes are a part of the domain
    wide = tr.plan_render(outline, spec, tile_px=10, halo_km=10.0)  # 10 km: 5 cells more on each side
    t0, t1 = plan.tiles[5], wide.tiles[5]
    assert t1.x.start == max(t0.x.start - 5, 0) and t1.x.stop == min(t0.x.stop + 5, nx)


def test_a_camera_below_the_grid_top_is_refused_and_the_horizon_reaches_the_edge():
    """A ground camera (its rays run through the cloud layer across the domain) is refused with the reason;
    a tile whose rays reach the horizon takes the domain to its edges; rays that all go up keep one column."""
    outline = synthetic_outline()
    ground = SceneSpec(camera=Camera((100e3, -20e3, 1500.0), (100e3, 75e3, 5000.0)), sun=Sun(290.0, 35.0), width=16,
                       height=12)
    with pytest.raises(ValueError, match="below the top of the model's height grid"):
        tr.plan_render(outline, ground, tile_px=8, halo_km=0.0)
    o = np.full((2, 2, 3), [100e3, 75e3, 30e3])
    d = np.array([[[0, 0.7, -0.7], [0, 0.7, -0.7]], [[0, 1.0, 0.01], [0, 1.0, 0.01]]])  # the lower edge: the horizon
    assert tp.rays_box(o, d, 500.0, 15500.0, 290.0, 35.0, 0.0) == (-np.inf, np.inf, -np.inf, np.inf)
    down = np.array([[[0, 0.7, -0.7]] * 2] * 2)  # all descending at 45 deg: 29.5 km to the bottom, 15 km north
    x0, x1, y0, y1 = tp.rays_box(o, down, 500.0, 15500.0, 0.0, 45.0, 0.0)  # the sun due north at 45 deg
    assert (x0, x1) == (100e3, 100e3) and y0 == pytest.approx(75e3 + 14.5e3) and y1 == pytest.approx(75e3 + 44.5e3)
    assert tp.rays_box(o, np.abs(d) + [0, 0, 0.1], 500.0, 15500.0, 290.0, 35.0, 0.0) is None
    assert tp.index_range(-np.inf, np.inf, 0.0, 2000.0, 100) == slice(0, 100)
    assert tp.index_range(-np.inf, -np.inf, 0.0, 2000.0, 100) == slice(0, 1)


def _supercell_spec(width=32, height=24, seed=0, elevation=50.0, sun_elevation=35.0):
    from weather_mi.io.outline import domain_outline
    from weather_mi.scene.framing import scene_spec
    outline = domain_outline(DATA)
    return outline, scene_spec(tr.OutlineBox(outline.bbox), (width, height), camera="orbit",
                               camera_elevation=elevation, sun_elevation=sun_elevation, seed=seed)


def _one_process(spec, spp):
    from weather_mi.io.wrf import open_wrf
    from weather_mi.optics.volume import default_sizes, optical_volume
    from weather_mi.reference.render import render_reference
    from weather_mi.scene.surface import RGB_UM, with_surface
    hyd = open_wrf(DATA)
    vol = with_surface(optical_volume(hyd, species="physical", sizes=default_sizes(hyd)), RGB_UM, "albedo", None)
    return render_reference(spec, vol, spp=spp, progress=False)


@needs_data
def test_one_tile_over_the_domain_is_the_one_process_render_bit_for_bit(tmp_path, capsys):
    """The supercell from an orbit camera: one tile whose sub-box is the domain renders the whole image's pixels
    with their own random numbers (``render_pixels``), the one-process render bit for bit; through the command
    line too (``render --tile-size``), where a ground camera is refused before anything is read."""
    from weather_mi.cli.commands import main
    from weather_mi.io.image import Image
    outline, spec = _supercell_spec()
    one = _one_process(spec, 4)
    plan = tr.plan_render(outline, spec, tile_px=1000, halo_km=1000.0)
    assert len(plan.tiles) == 1 and plan.tiles[0].cells == 100 * 100
    img, _ = tr.render_tiles(plan, optics=dict(species="physical"), spp=4)
    np.testing.assert_array_equal(img.radiance, one.radiance)
    np.testing.assert_array_equal(img.stderr, one.stderr)
    np.testing.assert_array_equal(img.transmittance, one.transmittance)
    out = tmp_path / "tiled.exr"
    assert main(["render", str(DATA), *ORBIT, "--size", "32x24", "--spp", "4", "--tile-size", "1000", "--halo", "1000",
                 "-o", str(out)]) in (0, None)
    np.testing.assert_array_equal(Image.load(out).radiance, one.radiance)
    assert not (tmp_path / "tiled.exr.tiles").exists()  # the finished tiles go once the image is written
    assert main(["render", str(DATA), "--camera", "ground", "--tile-size", "8", "-o", str(tmp_path / "g.exr")]) != 0
    assert "--tile-size 8: not with --camera ground" in capsys.readouterr().err


@needs_data
def test_tiles_agree_with_the_one_process_render_within_noise():
    """Four tiles with the 30 km halo and other seeds than the one-process render (independent noise): block
    chi-square about 1 and the mean within 3 combined standard errors; with the same seed most pixels are the
    one-process render's bit for bit (the paths that never leave their tile's sub-box)."""
    from weather_mi.display.metrics import agreement_in_noise
    outline, spec = _supercell_spec(40, 30)
    one = _one_process(spec, 16)
    from dataclasses import replace
    plan = tr.plan_render(outline, replace(spec, seed=7), tile_px=20, halo_km=30.0)
    assert len(plan.tiles) == 4 and min(t.cells for t in plan.tiles) < 100 * 100
    img, figs = tr.render_tiles(plan, optics=dict(species="physical"), spp=16)
    a = agreement_in_noise(img, one, block=2)
    assert 0.7 < a["block_chi2"] < 1.35 and abs(a["mean_z"]) < 3, a
    same, _ = tr.render_tiles(tr.plan_render(outline, spec, tile_px=20, halo_km=30.0), optics=dict(species="physical"),
                              spp=16)
    assert np.mean(np.all(same.radiance == one.radiance, axis=2)) > 0.5


@needs_data
def test_tiles_render_on_workers_whose_budget_cannot_hold_the_domain(monkeypatch):
    """A LocalCluster whose workers may plan for half of what reading the whole domain needs: the whole file
    fails there before allocating, the tiles (their sub-boxes without a halo) render, and a tile rendered there
    is the same tile rendered in this process bit for bit."""
    import distributed

    from weather_mi.errors import DomainTooLargeError
    from weather_mi.io import budget
    from weather_mi.io.wrf import open_wrf
    from weather_mi.kernel.variant import set_variant
    whole = budget.estimate_bytes((51, 100, 100), "optics")
    monkeypatch.setenv("WEATHER_MI_MAX_MEMORY_GB", f"{whole / 2 / 1e9:.4f}")  # spawned workers inherit it
    outline, spec = _supercell_spec(16, 12, elevation=70.0, sun_elevation=60.0)
    plan = tr.plan_render(outline, spec, tile_px=4, halo_km=0.0)
    assert len(plan.tiles) == 12 and max(t.cells for t in plan.tiles) * 51 * 64 < whole / 2
    fast = dict(optics=dict(species="physical", sizes="physical", phase="paper"), read_sizes=False, spp=2)
    here = tr.render_tile(tr.tile_jobs(plan, variant=set_variant(), **fast)[5])
    lc = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0")
    client = distributed.Client(lc, set_as_default=False)
    try:
        with pytest.raises(DomainTooLargeError):
            client.submit(open_wrf, str(DATA), pure=False).result()
        img, figs = tr.render_tiles(plan, client, **fast)
    finally:
        client.close()
        lc.close()
    assert [r["tile"].index for r in figs] == list(range(12))
    t = here["tile"]
    np.testing.assert_array_equal(img.radiance[t.rows, t.cols], here["radiance"])
    assert np.isfinite(img.radiance).all() and max(r["peak_rss_bytes"] for r in figs) > 0


@needs_data
def test_satellite_tiles_in_true_colour_resume_only_the_missing_tiles(tmp_path, monkeypatch, capsys):
    """``satellite --rgb --tile-size`` interrupted after two tiles keeps them (OUT.nc.tiles); ``--resume`` renders
    only the missing ones and writes the uninterrupted run's NetCDF bit for bit; a resume with other options
    is refused naming them; without --resume the unfinished tiles are named. One tile over the whole domain is
    the one-process true-colour render bit for bit."""
    from weather_mi.cli.commands import main
    from weather_mi.satellite import tiles as st
    args = [str(DATA), "--lat", "35", "--lon", "-97", "--date", "2024-05-20T20:00", "--resolution", "8km", "--spp", "2",
            "--rgb", "--no-denoise", "--tile-size", "8", "--halo", "5", "--phase", "paper", "--sizes", "physical"]
    assert main(["satellite", *args, "-o", str(tmp_path / "whole.nc")]) in (0, None)
    rendered, real = [], st.render_tile

    def failing(job):
        if job.tile.index == 2:
            raise KeyboardInterrupt
        rendered.append(job.tile.index)
        return real(job)
    monkeypatch.setattr(st, "render_tile", failing)
    out = tmp_path / "cut.nc"
    assert main(["satellite", *args, "-o", str(out)]) != 0
    assert sorted(p.name for p in (tmp_path / "cut.nc.tiles").iterdir()) == ["options.json", "tile-0.npz", "tile-1.npz"]
    assert main(["satellite", *args, "-o", str(out)]) != 0
    assert "holds the tiles of an unfinished render: add --resume" in capsys.readouterr().err
    assert main(["satellite", *args, "--seed", "3", "--resume", "-o", str(out)]) != 0
    assert "seed 0, now 3" in capsys.readouterr().err
    monkeypatch.setattr(st, "render_tile", lambda job: (rendered.append(job.tile.index), real(job))[1])
    rendered.clear()
    assert main(["satellite", *args, "--resume", "-o", str(out)]) in (0, None)
    assert rendered == [2, 3] and not (tmp_path / "cut.nc.tiles").exists()
    with xr.open_dataset(tmp_path / "whole.nc") as a, xr.open_dataset(out) as b:
        assert list(a.band.values) == ["0.47", "0.64", "0.86"]
        np.testing.assert_array_equal(a.reflectance.values, b.reflectance.values)
    # one tile over the domain: the one-process true colour
    from weather_mi.io.wrf import open_wrf
    from weather_mi.optics.volume import optical_volume
    from weather_mi.satellite import truecolor as tc
    from weather_mi.scene.place import assume_place
    hyd = assume_place(open_wrf(DATA, sizes=False), 35.0, -97.0, "2024-05-20T20:00")
    vol = optical_volume(hyd, species="physical", sizes="physical", phase="paper")
    ds1, _ = tc.render_true_color(tc.true_color_scenes(hyd, vol, "goes-east", 8.0), spp=2, progress=False)
    plan = st.tiled_satellite(DATA, None, resolution_km=8.0, tile_px=1000, halo_km=1000.0, rgb=True, lat=35.0,
                              lon=-97.0, date="2024-05-20T20:00")
    ds, _, _ = st.render_tiles(plan, optics=dict(species="physical", sizes="physical", phase="paper"),
                               read_sizes=False, spp=2)
    np.testing.assert_array_equal(ds.reflectance.values, ds1.reflectance.values)


@needs_data
def test_a_resumed_aerial_render_renders_only_the_missing_tiles(tmp_path):
    """``render_tiles`` with a ``TileStore``: every tile saved as it comes back; with one tile's file gone, a
    second run renders that tile alone and puts together the same image bit for bit; a store with other
    options is refused without --resume and with other options on --resume."""
    from weather_mi.io.resumable import TileStore
    outline, spec = _supercell_spec(16, 12)
    plan = tr.plan_render(outline, spec, tile_px=8, halo_km=5.0)
    fast = dict(optics=dict(species="physical", sizes="physical", phase="paper"), read_sizes=False, spp=2)
    store = TileStore(tmp_path / "out.exr.tiles")
    store.check({"spp": 2}, resume=False)
    first, _ = tr.render_tiles(plan, store=store, **fast)
    assert sorted(p.name for p in store.folder.glob("tile-*.npz")) == [f"tile-{k}.npz" for k in range(4)]
    store.path(1).unlink()
    rendered = []
    again, figs = tr.render_tiles(plan, store=store, on_tile=lambda r: rendered.append(r["tile"].index), **fast)
    assert rendered == [1] and len(figs) == 4
    np.testing.assert_array_equal(again.radiance, first.radiance)
    np.testing.assert_array_equal(again.stderr, first.stderr)
    with pytest.raises(ValueError, match="add --resume"):
        store.check({"spp": 2}, resume=False)
    with pytest.raises(ValueError, match="spp 2, now 4"):
        store.check({"spp": 4}, resume=True)
