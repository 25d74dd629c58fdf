"""The picture of a synthetic satellite image (``weather-mi satellite``'s PNG and a loop's frames): the
denoised reflectance (as ``render``'s PNG, ``display.denoise``; the NetCDF keeps the raw, unbiased one),
shown as a band's reflectance (0-1, sRGB-encoded, with a colour bar) or as the true-colour recipe
(``satellite.truecolor``), enlarged to a readable size, with the shorelines (GSHHG, ``io.coastlines``) and a
latitude/longitude graticule drawn where the domain has its own latitude/longitude (not for an ideal case
placed by --lat/--lon: its coastlines would be invented).

Placement: a point (lon, lat) on the WGS84 ellipsoid is at the satellite's scan angles
(``geostationary.lonlat_to_fixed_grid``), the image's column (x - x_0) / step and row (y_0 - y) / step
(pixel centres at integers; step the pixel's scan angle, ``resolution_km`` / height), as the pixels' own
latitude/longitude (``geostationary.pixel_lonlat``) are on the ellipsoid. A cloud's parallax is the
render's: coastlines are where the ground is, clouds where the satellite sees them.
"""
from __future__ import annotations

import numpy as np

MIN_WIDTH_PX = 480  # the picture is enlarged (nearest neighbour, an integer factor) to at least this width
MAX_ZOOM = 8
COAST_RGB = (255, 214, 0)  # yellow, as the operational imagery viewers draw shorelines
GRID_RGB = (150, 190, 230)
GRID_STEPS_DEG = (0.1, 0.2, 0.25, 0.5, 1.0, 2.0, 2.5, 5.0, 10.0, 15.0, 30.0)
COLORBAR_PX = 44


def zoom_for(width: int) -> int:
    """The integer enlargement of an image ``width`` pixels wide: at least ``MIN_WIDTH_PX`` wide, at most
    ``MAX_ZOOM`` times."""
    return int(min(MAX_ZOOM, max(1, -(-MIN_WIDTH_PX // max(int(width), 1)))))


def denoised(ds):
    """A copy of the satellite dataset ``ds`` (``imagery.satellite_dataset`` or ``truecolor.rgb_dataset``)
    whose ``reflectance`` is OIDN-denoised (``denoise.denoise_radiance``, no auxiliary images, the measured
    default): one band as a grey image, a true-colour dataset's bands as its three channels (NaN as 0)."""
    from .denoise import denoise_radiance
    refl = np.nan_to_num(np.asarray(ds["reflectance"].values, np.float32))
    out = ds.copy()
    if "band" in ds["reflectance"].dims:
        axis = ds["reflectance"].dims.index("band")
        den = denoise_radiance(np.moveaxis(refl, axis, -1))
        out["reflectance"] = ds["reflectance"].copy(data=np.moveaxis(den, -1, axis))
    else:
        den = denoise_radiance(np.repeat(refl[..., None], 3, axis=2)).mean(axis=2)
        out["reflectance"] = ds["reflectance"].copy(data=den.astype(np.float32))
    out.attrs["display"] = display_label()
    return out


def shown_dataset(ds, img=None, denoise: bool = True):
    """The dataset a picture shows: ``denoised(ds)`` (and, with ``img``, its render, the same as the render's
    display layer ``img.denoised``, named in ``img.metadata["display"]``), or ``ds`` itself."""
    if not denoise:
        return ds
    shown = denoised(ds)
    if img is not None:
        img.denoised = display_layer(shown)
        img.metadata["display"] = shown.attrs["display"]
    return shown


def display_layer(ds) -> np.ndarray:
    """(H, W, 3) float32 of ``ds``'s reflectance in the channels of its render's image (``Image.denoised``):
    one band in all three, a true-colour render's bands in the order of ``bands.true_color_bands``."""
    refl = ds["reflectance"]
    if "band" not in refl.dims:
        return np.repeat(np.asarray(refl.values, np.float32)[..., None], 3, axis=2)
    from ..satellite.bands import true_color_bands
    from ..satellite.geostationary import satellite
    names = [b.name for b in true_color_bands(satellite(str(ds.attrs["satellite"])))]
    return np.stack([np.asarray(refl.sel(band=n).values, np.float32) for n in names], axis=-1)


def display_label() -> str:
    from .denoise import DEFAULT_AUX, display_label as label
    return label(DEFAULT_AUX)


def base_frame(ds) -> np.ndarray:
    """The 8-bit (H, W, 3) picture of ``ds``'s reflectance at its own pixels: the true-colour recipe where
    it has a band dimension, else the reflectance at exposure 1 (sRGB-encoded, grey)."""
    if "band" in ds["reflectance"].dims:
        from ..satellite.truecolor import true_color8
        return true_color8(ds)
    from ..io.image import to_srgb8
    refl = np.asarray(ds["reflectance"].values, np.float64)
    return to_srgb8(np.repeat(refl[..., None], 3, axis=2), 1.0)


def has_own_place(ds) -> bool:
    """Whether ``ds``'s latitude/longitude are the model file's (not an ideal case placed by --lat/--lon)."""
    return "lat" in ds.coords and str(ds.attrs.get("place_source", "file")) == "file"


def pixel_of(ds, lon_deg, lat_deg) -> tuple[np.ndarray, np.ndarray]:
    """Column and row (floats; pixel centres at integers, NaN where the satellite does not see the point) of
    points on the ellipsoid in ``ds``'s fixed grid."""
    from ..satellite.geostationary import lonlat_to_fixed_grid, satellite
    sat = satellite(str(ds.attrs["satellite"]))
    step = float(ds.attrs["resolution_km"]) * 1000.0 / sat.height_m
    x, y = lonlat_to_fixed_grid(sat, np.asarray(lat_deg, float), np.asarray(lon_deg, float))
    return (x - float(ds.x.values[0])) / step, (float(ds.y.values[0]) - y) / step


def picture(ds, *, denoise: bool = True, overlays: bool = True, colorbar: bool = True) -> np.ndarray:
    """The 8-bit (H', W', 3) picture of one time's satellite dataset (see the module): denoised, enlarged by
    ``zoom_for``, coastlines and graticule where ``has_own_place``, a colour bar beneath a single band."""
    from PIL import Image as PILImage, ImageDraw
    shown = denoised(ds) if denoise else ds
    frame = base_frame(shown)
    k = zoom_for(frame.shape[1])
    img = PILImage.fromarray(np.repeat(np.repeat(frame, k, axis=0), k, axis=1))
    if overlays and has_own_place(ds):
        draw = ImageDraw.Draw(img)
        _graticule(draw, ds, k)
        _coastlines(draw, ds, k)
    out = np.asarray(img)
    if colorbar and "band" not in ds["reflectance"].dims:
        out = np.concatenate([out, colour_bar(out.shape[1], f"reflectance factor, {ds.attrs.get('band_um', '')} um")])
    return out


def write_picture(ds, path, **kw):
    """``picture(ds, **kw)`` as an 8-bit RGB PNG."""
    from ..io.image import write_png8
    return write_png8(path, picture(ds, **kw))


def _to_canvas(ds, k: int, lon, lat) -> np.ndarray:
    """(N, 2) canvas coordinates (PIL: pixel centres at integers) of points in the picture enlarged ``k``x."""
    col, row = pixel_of(ds, lon, lat)
    return np.stack([(col + 0.5) * k - 0.5, (row + 0.5) * k - 0.5], axis=-1)


def _polyline(draw, pts: np.ndarray, fill, width: int) -> None:
    """Draw the finite runs of ``pts``."""
    ok = np.all(np.isfinite(pts), axis=1)
    for run in np.split(pts, np.nonzero(~ok)[0]):
        run = run[np.all(np.isfinite(run), axis=1)]
        if len(run) >= 2:
            draw.line([tuple(p) for p in run], fill=fill, width=width)


def _box(ds):
    lat, lon = np.asarray(ds["lat"].values, float), np.asarray(ds["lon"].values, float)
    centre = float(np.nanmedian(lon))
    lon = (lon - centre + 180.0) % 360.0 + centre - 180.0  # continuous across the date line
    return float(np.nanmin(lon)), float(np.nanmin(lat)), float(np.nanmax(lon)), float(np.nanmax(lat))


def _coastlines(draw, ds, k: int) -> None:
    from ..io.coastlines import coastlines
    resolution = "i" if float(ds.attrs.get("resolution_km", 1.0)) <= 4.0 else "l"
    for line in coastlines(*_box(ds), resolution=resolution, margin_deg=0.2):
        _polyline(draw, _to_canvas(ds, k, line[:, 0], line[:, 1]), COAST_RGB, 2 if k >= 3 else 1)


def graticule_step(span_deg: float) -> float:
    """The graticule's spacing (degrees): the smallest of ``GRID_STEPS_DEG`` giving at most 5 lines."""
    return next((s for s in GRID_STEPS_DEG if span_deg / s <= 5.0), GRID_STEPS_DEG[-1])


def _graticule(draw, ds, k: int) -> None:
    """Meridians and parallels every ``graticule_step``, labelled where they leave the picture's bottom
    (meridians) and left (parallels) edges."""
    from PIL import ImageFont
    lon0, lat0, lon1, lat1 = _box(ds)
    step = graticule_step(max(lon1 - lon0, lat1 - lat0))
    font = ImageFont.load_default(size=11)
    size = draw.im.size  # (width, height) of the canvas
    t = np.linspace(0.0, 1.0, 200)
    for lon in np.arange(np.ceil(lon0 / step) * step, lon1 + 1e-9, step):  # south to north: labelled at the bottom
        pts = _to_canvas(ds, k, np.full_like(t, lon), lat0 - step + (lat1 - lat0 + 2 * step) * t)
        _polyline(draw, pts, GRID_RGB, 1)
        _label(draw, pts, size, _deg_text(lon, "E", "W"), font, bottom=True)
    for lat in np.arange(np.ceil(lat0 / step) * step, lat1 + 1e-9, step):  # west to east: labelled at the left
        pts = _to_canvas(ds, k, lon0 - step + (lon1 - lon0 + 2 * step) * t, np.full_like(t, lat))
        _polyline(draw, pts, GRID_RGB, 1)
        _label(draw, pts, size, _deg_text(lat, "N", "S"), font, bottom=False)


def _deg_text(v: float, pos: str, neg: str) -> str:
    v = (v + 180.0) % 360.0 - 180.0 if pos == "E" else v
    return f"{abs(round(v, 2)):g}\N{DEGREE SIGN}{pos if v >= 0 else neg}"


def _label(draw, pts, size, text: str, font, bottom: bool) -> None:
    """``text`` where the line ``pts`` first enters the canvas (``size``: width, height): at the bottom edge
    below that point (``bottom``) or at the left edge beside it."""
    w, h = size
    inside = np.all(np.isfinite(pts), axis=1) & (pts[:, 0] >= 0) & (pts[:, 0] < w) & (pts[:, 1] >= 0) & (pts[:, 1] < h)
    if not inside.any():
        return
    x, y = pts[np.nonzero(inside)[0][0]]
    x, y = (min(x + 2.0, w - 30), h - 13) if bottom else (2.0, min(y + 1.0, h - 12))
    draw.text((x + 1, y + 1), text, fill=(0, 0, 0), font=font)
    draw.text((x, y), text, fill=GRID_RGB, font=font)


def colour_bar(width: int, title: str, height: int = COLORBAR_PX) -> np.ndarray:
    """An 8-bit (``height``, ``width``, 3) strip: the grey scale of a band's picture (reflectance 0-1 at
    exposure 1, sRGB-encoded as ``base_frame``), ticks every 0.2 and ``title``."""
    from PIL import Image as PILImage, ImageDraw, ImageFont
    from ..io.image import to_srgb8
    strip = PILImage.new("RGB", (width, height), (16, 16, 16))
    draw = ImageDraw.Draw(strip)
    font = ImageFont.load_default(size=11)
    x0, x1, top, bar = 12, width - 12, 4, 12
    values = np.linspace(0.0, 1.0, max(x1 - x0, 2))
    row = to_srgb8(np.repeat(values[None, :, None], 3, axis=2), 1.0)
    strip.paste(PILImage.fromarray(np.repeat(row, bar, axis=0)), (x0, top))
    for v in np.linspace(0.0, 1.0, 6):
        x = x0 + v * (x1 - x0 - 1)
        draw.line([(x, top + bar), (x, top + bar + 3)], fill=(230, 230, 230))
        text = f"{v:.1f}"
        draw.text((x - draw.textlength(text, font=font) / 2, top + bar + 4), text, fill=(230, 230, 230), font=font)
    draw.text(((width - draw.textlength(title, font=font)) / 2, top + bar + 16), title, fill=(230, 230, 230), font=font)
    return np.asarray(strip)


__all__ = ["picture", "write_picture", "shown_dataset", "denoised", "display_layer", "base_frame", "pixel_of", "has_own_place", "zoom_for",
           "colour_bar", "graticule_step", "MIN_WIDTH_PX"]
