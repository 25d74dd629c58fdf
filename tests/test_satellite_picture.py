"""The satellite picture (weather_mi/display/satellite_picture.py, weather_mi/io/coastlines.py; issue 40 part 4):
GSHHG shorelines where published coordinates put them, a coastline vertex on its pixel by the fixed grid's
navigation written out here (GOES-R PUG vol. 3 sec. 5.1.2.8.1 and its sweep-y counterpart), the picture's
coast drawn there and nothing for an ideal case, the colour bar's scale (IEC 61966-2-1), the PNG denoised with
the NetCDF raw; --rgb --rayleigh without a black frame, resumable band by band; a resumed loop with other
options refused."""
from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
import xarray as xr

import weather_mi as wm
from weather_mi.cli import commands as cli
from weather_mi.display import satellite_picture as sp
from weather_mi.io.coastlines import coastlines
from weather_mi.satellite import truecolor as tc
from weather_mi.satellite.geostationary import WGS84_A_M, WGS84_B_M, fixed_grid, pixel_lonlat, satellite

from conftest import SHARED_DATA, WRF_THOMPSON, shared_file

BERMUDA = (32.32, -64.76)  # lat, lon (deg): the island's published centre
QINGHAI_LAKE = (36.9, 100.2)


def _main(argv) -> int:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return cli.main(argv)


def test_gshhg_shorelines_are_where_published_coordinates_put_them():
    """Bermuda's shore (level 1) centred on the island, Qinghai Lake's (level 2) on the lake; every piece
    inside the box (plus the one vertex beyond it that reaches the edge)."""
    for (lat, lon), level, tol in ((BERMUDA, 1, 0.1), (QINGHAI_LAKE, 2, 0.3)):
        lines = coastlines(lon - 1.0, lat - 1.0, lon + 1.0, lat + 1.0, levels=(level,))
        assert lines, (lat, lon)
        v = np.concatenate(lines)
        assert v[:, 1].mean() == pytest.approx(lat, abs=tol) and v[:, 0].mean() == pytest.approx(lon, abs=tol)
    across = coastlines(175.0, 50.0, 185.0, 55.0)  # the Aleutians, across the date line: continuous longitudes
    v = np.concatenate(across)
    assert v[:, 0].min() < 180.0 < v[:, 0].max() and v[:, 0].max() <= 185.5
    with pytest.raises(ValueError, match="coastline resolution"):
        coastlines(0, 0, 1, 1, resolution="f")


def _scan_angles(sat, lat_deg, lon_deg):
    """Scan angles (rad) of a point on the WGS84 ellipsoid, written out: GOES-R PUG vol. 3 5.1.2.8.1 (sweep x);
    for sweep y (Himawari, Meteosat: CGMS LRIT/HRIT navigation) the two angles are taken in the other order."""
    a, b = WGS84_A_M, WGS84_B_M
    lat, dlon = np.radians(lat_deg), np.radians(lon_deg - sat.sub_lon_deg)
    phi_c = np.arctan(b ** 2 / a ** 2 * np.tan(lat))
    e2 = (a ** 2 - b ** 2) / a ** 2
    r_c = b / np.sqrt(1.0 - e2 * np.cos(phi_c) ** 2)
    h = a + sat.height_m
    sx, sy, sz = h - r_c * np.cos(phi_c) * np.cos(dlon), -r_c * np.cos(phi_c) * np.sin(dlon), r_c * np.sin(phi_c)
    if sat.sweep == "x":
        return np.arcsin(-sy / np.sqrt(sx ** 2 + sy ** 2 + sz ** 2)), np.arctan(sz / sx)
    return np.arctan(-sy / sx), np.arcsin(sz / np.sqrt(sx ** 2 + sy ** 2 + sz ** 2))


def _grey_dataset(sat_name, lat, lon, resolution_km=1.0, half_deg=0.4, place_source="file"):
    """A uniform grey one-band dataset on ``sat_name``'s fixed grid around (lat, lon)."""
    sat = satellite(sat_name)
    la, lo = np.meshgrid([lat - half_deg, lat + half_deg], [lon - half_deg, lon + half_deg])
    x, y = fixed_grid(sat, la.ravel(), lo.ravel(), resolution_km)
    plon, plat = pixel_lonlat(sat, *np.meshgrid(x, y))
    return xr.Dataset({"reflectance": (("y", "x"), np.full(plat.shape, 0.3, np.float32))},
                      coords={"x": x, "y": y, "lat": (("y", "x"), plat), "lon": (("y", "x"), plon)},
                      attrs={"satellite": sat_name, "resolution_km": resolution_km, "band_um": "0.64",
                             "place_source": place_source})


@pytest.mark.parametrize("sat_name", ["goes-east", "himawari"])
def test_a_coastline_vertex_lands_on_its_pixel(sat_name):
    """A Bermuda (GOES-East) or Qinghai Lake (Himawari) shore vertex: the picture's pixel coordinates from the
    navigation written out here, within 0.01 pixel; the pixel it lands on has that point inside it (its
    centre's latitude/longitude within a pixel)."""
    lat, lon = BERMUDA if sat_name == "goes-east" else QINGHAI_LAKE
    ds = _grey_dataset(sat_name, lat, lon)
    v = coastlines(lon - 0.3, lat - 0.3, lon + 0.3, lat + 0.3)[0][0]
    sat = satellite(sat_name)
    x, y = _scan_angles(sat, v[1], v[0])
    step = 1000.0 / sat.height_m
    col, row = sp.pixel_of(ds, v[0], v[1])
    assert col == pytest.approx((x - ds.x.values[0]) / step, abs=0.01)
    assert row == pytest.approx((ds.y.values[0] - y) / step, abs=0.01)
    i, j = int(round(float(row))), int(round(float(col)))
    km_per_deg = 111.2
    d_km = np.hypot((ds.lat.values[i, j] - v[1]) * km_per_deg,
                    (ds.lon.values[i, j] - v[0]) * km_per_deg * np.cos(np.radians(v[1])))
    assert d_km < 2.5  # a pixel is 1 km at the sub-satellite point, a few km at these view angles


def test_the_picture_draws_the_coast_on_its_pixels_and_nothing_for_an_ideal_case():
    ds = _grey_dataset("goes-east", *BERMUDA, resolution_km=1.0)
    pic = sp.picture(ds, denoise=False)
    k = sp.zoom_for(ds.sizes["x"])
    h, w = ds.sizes["y"] * k, ds.sizes["x"] * k
    assert pic.shape == (h + sp.COLORBAR_PX, w, 3)
    coast = np.all(pic[:h] == sp.COAST_RGB, axis=-1)
    assert coast.sum() > 20
    for lon, lat in coastlines(BERMUDA[1] - 0.3, BERMUDA[0] - 0.3, BERMUDA[1] + 0.3, BERMUDA[0] + 0.3)[0][::5]:
        x, y = _scan_angles(satellite("goes-east"), lat, lon)
        step = 1000.0 / satellite("goes-east").height_m
        u, v = ((x - ds.x.values[0]) / step + 0.5) * k, ((ds.y.values[0] - y) / step + 0.5) * k
        iu, iv = int(u), int(v)
        assert coast[max(iv - k, 0):iv + k + 1, max(iu - k, 0):iu + k + 1].any(), (lon, lat)
    ideal = sp.picture(_grey_dataset("goes-east", *BERMUDA, place_source="assumed"), denoise=False)
    base = np.repeat(np.repeat(sp.base_frame(ds), k, axis=0), k, axis=1)
    np.testing.assert_array_equal(ideal[:h], base)


def test_the_colour_bar_is_the_pictures_scale():
    """The bar at reflectance 0.5 is sRGB(0.5) = 1.055 x 0.5^(1/2.4) - 0.055 = 0.7354 (188 of 255), at 0 black,
    at 1 white (IEC 61966-2-1)."""
    bar = sp.colour_bar(512, "reflectance factor, 0.64 um")
    x0, x1, row = 12, 512 - 12, 4 + 6
    mid = bar[row, x0 + (x1 - x0) // 2]
    assert abs(int(mid[0]) - 188) <= 1 and mid[0] == mid[1] == mid[2]
    assert bar[row, x0][0] == 0 and bar[row, x1 - 1][0] == 255


def test_the_png_is_denoised_and_the_netcdf_raw(tmp_path):
    """The plateau file (its own Lambert grid) by Himawari: the PNG is the picture of the denoised reflectance
    (with the file's lakes and the graticule), the NetCDF's reflectance the EXR's unbiased one, the EXR keeps
    the display layer."""
    from PIL import Image
    out = tmp_path / "sat.nc"
    assert _main(["satellite", str(shared_file(WRF_THOMPSON)), "--time", "1", "--satellite", "himawari",
                  "--resolution", "10km", "--spp", "4", "-o", str(out)]) == 0
    ds = xr.load_dataset(out)
    png = np.asarray(Image.open(out.with_suffix(".png")))
    np.testing.assert_array_equal(png, sp.picture(ds))
    assert not np.array_equal(png, sp.picture(ds, denoise=False))
    img = wm.Image.load(out.with_suffix(".exr"))
    np.testing.assert_allclose(ds.reflectance.values, np.asarray(img.radiance).mean(axis=2), rtol=1e-6)
    assert img.denoised is not None
    np.testing.assert_allclose(img.denoised[..., 0], sp.denoised(ds).reflectance.values, rtol=1e-6, atol=1e-7)
    assert ds.attrs["place_source"] == "file" and np.all(png[-sp.COLORBAR_PX:, 4] == 16)  # the bar's margin


def test_the_column_fraction_of_a_line_of_sight_is_the_air_it_crosses_in_the_box():
    """Air of scale height 8 km in a 10 x 10 x 20 km box: a vertical line of sight crosses the whole column (1);
    one at 45 deg entering through the side at 6 km height and leaving through the floor crosses
    (1 - exp(-6/8)) / (1 - exp(-20/8)) of it; one that passes beside the box, none."""
    from types import SimpleNamespace
    from weather_mi.scene.spec import RayTable
    nz, hz = 2000, 8000.0
    z = (np.arange(nz) + 0.5) * 20000.0 / nz
    vol = SimpleNamespace(species=["rayleigh"], bbox=((0.0, 0.0, 0.0), (10000.0, 10000.0, 20000.0)),
                          beta_ext=np.broadcast_to(np.exp(-z / hz)[None, :, None, None] * 1e-5, (1, nz, 2, 2)))

    def table(origin, direction):  # one pixel whose four corner rays are the same ray
        return RayTable(np.broadcast_to(np.asarray(origin, float), (2, 2, 3)),
                        np.broadcast_to(np.asarray(direction, float), (2, 2, 3)))

    d45 = np.array([-1.0, 0.0, -1.0]) / np.sqrt(2.0)
    cases = [(table([5000.0, 5000.0, 25000.0], [0, 0, -1]), 1.0),
             (table([10000.0 + 19000.0, 5000.0, 6000.0 + 19000.0], d45),
              (1 - np.exp(-6 / 8)) / (1 - np.exp(-20 / 8))),
             (table([30000.0, 30000.0, 25000.0], [0, 0, -1]), 0.0)]
    for rays, expected in cases:
        assert tc.column_path_fraction(vol, rays)[0, 0] == pytest.approx(expected, abs=1e-4)


def _clear_air_scenes():
    """The demo cumulus's grid with its condensate removed (air alone) placed at 40 N 120 W, seen slant by
    GOES-East (view zenith about 60 deg): lines of sight enter or leave the box through its sides."""
    from weather_mi.scene.place import assume_place
    hyd = wm.open_source(None, "cumulus")
    for v in ("q_cloud", "q_ice", "q_rain", "q_snow", "q_graupel"):
        hyd[v] = hyd[v] * 0
    hyd = assume_place(hyd, 40.0, -120.0, "2013-05-20T20:00")
    vol = wm.optical_volume(hyd, species="physical", phase_quality="test")
    return tc.true_color_scenes(hyd, vol, "goes-east", 1.0, rayleigh=True)


def test_rgb_rayleigh_leaves_no_clear_pixel_black_inside_the_domain():
    """Air alone over the sea: every in-domain pixel, corrected, is a dark blue sea, none black (CIRA value
    below 0.05, reflectance below 0.028); the full column's Rayleigh reflectance subtracted (before the fix)
    blackens the slant lines of sight that cross only part of the box."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        ds, _ = tc.render_true_color(_clear_air_scenes(), spp=512, progress=False)
    inside = ds.in_domain.values == 1
    f = ds.rayleigh_path_fraction.values
    assert inside.sum() > 30 and np.all(f[inside] < 0.99) and np.all(f[~inside] == 0)
    rgb = tc.true_color(ds)
    assert rgb[inside].max(axis=-1).min() > 0.05
    full = ds.copy()
    full["rayleigh_reflectance"] = ds.rayleigh_reflectance / np.where(f > 0, f, 1.0)
    assert (tc.true_color(full)[inside].max(axis=-1) < 0.05).sum() > inside.sum() // 2


def test_rgb_rayleigh_resumes_band_by_band(tmp_path, monkeypatch):
    """--rgb --rayleigh cut during its second band: the first band's checkpoint is read back, the second
    resumed, the third rendered; the reflectance equals an uninterrupted render's."""
    from weather_mi.reference import render as ref_render
    real = ref_render.render_reference
    calls = []

    def cut_in_the_second_band(spec, vol, **kw):
        calls.append(kw.get("resume"))
        if len(calls) == 2 and "cut" not in calls:
            calls.append("cut")
            def stop(_img):
                raise RuntimeError("power cut")
            return real(spec, vol, **kw, on_pass=stop)
        return real(spec, vol, **kw)

    argv = ["satellite", "--demo", "cumulus", "--lat", "25", "--lon", "-75", "--date", "2013-05-20T16:00", "--rgb",
            "--rayleigh", "--resolution", "2km", "--spp", "8"]
    monkeypatch.setattr(ref_render, "render_reference", cut_in_the_second_band)
    cut = tmp_path / "cut" / "tc.nc"
    cut.parent.mkdir()
    assert _main(argv + ["-o", str(cut)]) == 2
    left = sorted(p.name for p in cut.parent.iterdir())
    assert left == ["tc.exr.0.64.ckpt.npz", "tc.exr.0.86.ckpt.npz"], left
    assert _main(argv + ["-o", str(cut)]) == 2  # refused without --resume
    calls[:] = ["cut"]
    assert _main(argv + ["--resume", "-o", str(cut)]) == 0
    assert [c is not None for c in calls[1:]] == [True, True, False]
    assert not list(cut.parent.glob("*.ckpt.npz"))
    monkeypatch.setattr(ref_render, "render_reference", real)
    whole = tmp_path / "whole" / "tc.nc"
    whole.parent.mkdir()
    assert _main(argv + ["-o", str(whole)]) == 0
    np.testing.assert_array_equal(xr.load_dataset(cut).reflectance.values, xr.load_dataset(whole).reflectance.values)


def test_a_resumed_loop_with_other_options_is_refused_before_rendering(tmp_path, monkeypatch, capsys):
    from weather_mi.satellite import imagery
    series = shared_file(SHARED_DATA / "wrf" / "wrfout_quarter_ss_series.nc")
    real = imagery.render_satellite
    calls = []

    def cut_at_the_second_time(scene, **kw):
        calls.append(1)
        if len(calls) == 2:
            raise RuntimeError("power cut")
        return real(scene, **kw)

    argv = ["satellite", str(series), "--time", "0:2", "--lat", "35", "--lon", "-97", "--date", "2024-05-20T21:00",
            "--resolution", "10km", "-o", str(tmp_path / "sat.nc")]
    monkeypatch.setattr(imagery, "render_satellite", cut_at_the_second_time)
    assert _main(argv + ["--spp", "4"]) == 2
    monkeypatch.setattr(imagery, "render_satellite", lambda *a, **k: pytest.fail("rendered"))
    capsys.readouterr()
    assert _main(argv + ["--spp", "8", "--resume"]) == 2
    err = capsys.readouterr().err
    assert len(re.findall(r"other options \(spp 4, now 8\)", err)) == 1, err
    assert (tmp_path / "sat.nc.parts").is_dir() and not (tmp_path / "sat.nc").exists()
