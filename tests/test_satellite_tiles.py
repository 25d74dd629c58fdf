"""``satellite --tile-size``: the image in tiles of pixels, each reading only its sub-box of the wrfout and a
halo (``satellite.tile_plan``, ``satellite.tiles``), as Dask tasks on workers whose memory budget is smaller
than the whole domain needs. Real data: ../shared/data/wrf/wrfout_quarter_ss_0130.nc (skipped without it)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from weather_mi.satellite import tile_plan as tp
from weather_mi.scene.spec import RayTable

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "wrf" / "wrfout_quarter_ss_0130.nc"
needs_data = pytest.mark.skipif(not DATA.is_file(), reason=f"real WRF supercell not found at {DATA}")
PLACE = dict(lat=35.0, lon=-97.0, date="2024-05-20T20:00")


def slant_rays(vza_deg: float, top_m: float, n: int = 2) -> RayTable:
    """Corner rays (n + 1, n + 1) of parallel lines of sight tilted ``vza_deg`` towards +x (the satellite to
    the west), meeting the ground on a 1 km lattice from the origin, starting at ``top_m``."""
    t = np.radians(vza_deg)
    gx, gy = np.meshgrid(np.arange(n + 1) * 1000.0, np.arange(n + 1) * 1000.0)
    ground = np.stack([gx, gy, np.zeros_like(gx)], -1)
    to_sat = np.array([-np.sin(t), 0.0, np.cos(t)])
    o = ground + to_sat * (top_m / np.cos(t))
    return RayTable(o, np.broadcast_to(-to_sat, o.shape))


def test_the_box_holds_the_parallax_the_sun_path_and_the_halo():
    """Lines of sight at 40 deg from the west through ground points x in [0, 2] km, heights 1-12 km, the sun
    at 30 deg elevation due south (azimuth 180): the box reaches 12 tan(40) km west of the ground points
    (where the lines enter the top), 11 / tan(30) km south of the bottom ends (the sun path from 1 km up to
    12 km) and 3 km (the halo) beyond both, by hand."""
    rays = slant_rays(40.0, 12000.0)
    x0, x1, y0, y1 = tp.tile_box(rays, slice(0, 2), slice(0, 2), 1000.0, 12000.0, 180.0, 30.0, 3000.0)
    t = np.tan(np.radians(40.0))
    assert x0 == pytest.approx(-12000.0 * t - 3000.0, abs=1e-6)
    assert x1 == pytest.approx(2000.0 - 1000.0 * t + 3000.0, abs=1e-6)  # the bottom end is 1 km up the line
    assert y0 == pytest.approx(-11000.0 / np.tan(np.radians(30.0)) - 3000.0, abs=1e-6)
    assert y1 == pytest.approx(2000.0 + 3000.0, abs=1e-6)
    # one pixel of the two: half the box across x, y
    x0b, x1b, *_ = tp.tile_box(rays, slice(0, 2), slice(1, 2), 1000.0, 12000.0, 180.0, 30.0, 0.0)
    assert (x0b, x1b) == pytest.approx((1000.0 - 12000.0 * t, 2000.0 - 1000.0 * t))


def test_index_ranges_and_pixel_blocks():
    """Cells (centres 0, 1, ..., 9 km) overlapping an interval, clipped to the grid, never empty; blocks
    covering an image once."""
    assert tp.index_range(1200.0, 3400.0, 0.0, 1000.0, 10) == slice(1, 4)   # cells 1-3 reach 0.5-3.5 km
    assert tp.index_range(-5e4, 5e4, 0.0, 1000.0, 10) == slice(0, 10)
    assert tp.index_range(2e4, 3e4, 0.0, 1000.0, 10) == slice(9, 10)        # beyond the edge: the last cell
    blocks = tp.pixel_blocks(5, 7, 3)
    cover = np.zeros((5, 7), int)
    for r, c in blocks:
        cover[r, c] += 1
    assert len(blocks) == 6 and (cover == 1).all()
    with pytest.raises(ValueError, match="--tile-size"):
        tp.pixel_blocks(5, 7, 0)


@needs_data
def test_the_outline_is_the_readers_grid_without_its_fields():
    """The outline's height grid and frame are open_wrf's, from two w-levels."""
    from weather_mi.io.wrf import open_wrf
    hyd = open_wrf(DATA)
    o = tp.domain_outline(DATA)
    for d in ("z", "y", "x"):
        np.testing.assert_array_equal(o.dataset[d].values, hyd[d].values)
    from weather_mi.io.hydrometeors import bbox_of
    assert o.bbox == bbox_of(hyd) and o.top_m == pytest.approx(bbox_of(hyd)[1][2], abs=1e-6)
    assert o.dz_m == hyd.attrs["dz_native_mean"] and o.shape == tuple(hyd.sizes[d] for d in ("z", "y", "x"))


@needs_data
def test_one_tile_over_the_whole_domain_is_the_one_process_image_bit_for_bit(tmp_path, capsys):
    """``weather-mi satellite --tile-size`` with one tile whose halo holds the domain writes the reflectance
    of the one-process render (same volume, rays and seed); several tiles change only the noise."""
    import xarray as xr

    from weather_mi.cli.commands import main
    from weather_mi.io.wrf import open_wrf
    from weather_mi.optics.volume import default_sizes, optical_volume
    from weather_mi.satellite import imagery as si
    from weather_mi.scene.place import assume_place
    hyd = assume_place(open_wrf(DATA), **PLACE)
    vol = optical_volume(hyd, species="physical", sizes=default_sizes(hyd))
    ds1, _ = si.render_satellite(si.satellite_scene(hyd, vol, "goes-east", "0.64", 8.0), spp=2, progress=False)
    out = tmp_path / "tiled.nc"
    args = [str(DATA), "--lat", "35", "--lon", "-97", "--date", "2024-05-20T20:00", "--resolution", "8km",
            "--spp", "2", "--no-denoise", "-o", str(out)]
    main(["satellite", *args, "--tile-size", "1000", "--halo", "1000"])
    with xr.open_dataset(out) as ds:
        np.testing.assert_array_equal(ds.reflectance.values, ds1.reflectance.values)
        np.testing.assert_array_equal(ds.cloud.values, ds1.cloud.values)
    assert main(["satellite", "--demo", "supercell", "--tile-size", "8", "-o", str(tmp_path / "x.nc")]) != 0
    assert "--tile-size 8: not with --demo" in capsys.readouterr().err


@needs_data
def test_tiles_render_on_workers_whose_budget_cannot_hold_the_domain(monkeypatch):
    """A LocalCluster whose workers may plan for half of what reading the whole domain needs
    (``WEATHER_MI_MAX_MEMORY_GB``): the whole file fails there before allocating, the 16 tiles (each its
    sub-box and halo) render, and two of them are the same tiles rendered in this process bit for bit."""
    import distributed

    from weather_mi.errors import DomainTooLargeError
    from weather_mi.io import budget
    from weather_mi.io.wrf import open_wrf
    from weather_mi.satellite import tiles as st
    whole = budget.estimate_bytes((51, 100, 100), "optics")  # the larger step's need on the 51-level grid
    monkeypatch.setenv("WEATHER_MI_MAX_MEMORY_GB", f"{whole / 2 / 1e9:.4f}")  # spawned workers inherit it
    plan = st.tiled_satellite(DATA, None, resolution_km=8.0, tile_px=4, halo_km=0.0, **PLACE)
    assert len(plan.tiles) == 16 and max(t.cells for t in plan.tiles) * 51 * 64 < whole / 2
    from weather_mi.kernel.variant import set_variant
    fast = dict(optics=dict(species="physical", sizes="physical", phase="paper"), read_sizes=False, spp=1)
    jobs = st.tile_jobs(plan, variant=set_variant(), **fast)
    here = [st.render_tile(jobs[k]) for k in (0, 5)]
    lc = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0")
    client = distributed.Client(lc, set_as_default=False)
    try:
        with pytest.raises(DomainTooLargeError):
            client.submit(open_wrf, str(DATA), pure=False).result()
        ds, img, figs = st.render_tiles(plan, client, **fast)
    finally:
        client.close()
        lc.close()
    assert sorted(r["tile"].index for r in figs) == list(range(16))
    for r in here:
        t = r["tile"]
        np.testing.assert_array_equal(img.radiance[t.rows, t.cols], r["radiance"])
        np.testing.assert_allclose(ds.reflectance.values[t.rows, t.cols], r["radiance"].mean(axis=2), rtol=1e-6)
    assert np.isfinite(ds.reflectance.values).all() and int(ds.cloud.sum()) > 0


PLATEAU = DATA.parent / "wrf_d01_allvars_cropped.nc"


@pytest.mark.skipif(not PLATEAU.is_file(), reason=f"real WRF plateau file not found at {PLATEAU}")
def test_one_tile_keeps_the_files_ground_bit_for_bit():
    """The Tibetan-plateau wrfout (Lambert grid, terrain above 4 km, its own land and albedo; the ground of
    ``scene.surface``): one tile holding the domain is the one-process image bit for bit, land mask included."""
    from weather_mi.io.wrf import open_wrf
    from weather_mi.optics.volume import default_sizes, optical_volume
    from weather_mi.satellite import imagery as si, tiles as st
    hyd = open_wrf(PLATEAU, 1)
    vol = optical_volume(hyd, species="physical", sizes=default_sizes(hyd))
    ds1, _ = si.render_satellite(si.satellite_scene(hyd, vol, "himawari", "0.64", 12.0), spp=2, progress=False)
    plan = st.tiled_satellite(PLATEAU, 1, "himawari", "0.64", 12.0, tile_px=1000, halo_km=1e4)
    ds, _, _ = st.render_tiles(plan, optics=dict(species="physical"), spp=2)
    assert "land" in ds1 and int(ds1.land.max()) == 1
    for name in ("reflectance", "land", "cloud", "in_domain"):
        np.testing.assert_array_equal(ds[name].values, ds1[name].values)
