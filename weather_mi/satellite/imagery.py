"""Synthetic geostationary imagery: a domain path-traced as a satellite's imager sees it (every pixel from
the satellite's real position, ``rays``), in one band (``bands``), over its surface, optionally
under a molecular atmosphere (``rayleigh``), as a bidirectional reflectance factor on the fixed grid.

Reflectance R = pi L / (E0 cos theta0) with theta0 the solar zenith angle of the one sun that lit the
render (the domain's centre at the valid time, ``place.sun_from_time``); the dataset also carries each
pixel's own solar angles (``solar.sun_angles_at``) and the largest angle between that one sun and a
column's own (``one_sun_max_error_deg``). Top of the atmosphere: no sky emitter (the sky's light is the
molecular scattering, present only with ``rayleigh``).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .bands import DEFAULT_GROUND_ALBEDO, Band, band, band_volume, check_band_on, rgb_volume, true_color_bands
from .geostationary import Satellite, satellite
from ..optics.volume import OpticalVolume
from .rays import SatelliteView, satellite_view
from ..scene.spec import Camera, Ground, SceneSpec, Sun

RAY_START_ABOVE_M = 10.0  # rays start this far above the medium's top


@dataclass(frozen=True)
class SatelliteScene:
    """What ``render_satellite`` renders: the scene (rays from ``view``), the band's volume, the sun's
    metadata (``place.sun_from_time``), the satellite and band; ``bands``: the band of each of the render's
    channels in a true-colour render (``bands.rgb_volume``), else empty."""

    spec: SceneSpec
    vol: OpticalVolume
    view: SatelliteView
    satellite: Satellite
    band: Band
    sun_meta: dict = field(default_factory=dict)
    bands: tuple = ()
    place_source: str = "file"  # "assumed": an ideal case placed by --lat/--lon (no coastlines drawn)


def satellite_scene(hyd, vol: OpticalVolume, sat: str | Satellite = "goes-east", band_name: str = "0.64",
                    resolution_km: float = 1.0, *, rayleigh: bool = False, ground_albedo=None,
                    seed: int = 0, max_vza_deg: float = 80.0, sun_time=None, rgb: bool = False,
                    surface: str = "file", wind_m_s: float | None = None, atmosphere=None,
                    channel_bands=None) -> SatelliteScene:
    """The satellite's view of ``hyd`` (its place and valid time) with ``vol``'s optics in the band;
    ``sun_time`` (UTC): the sun of another time over the same clouds (a study of the sun's elevation);
    ``rgb``: the satellite's true-colour bands in one render (``bands.rgb_volume``; ``band_name`` unused;
    ``ground_albedo`` one value or one per channel; None: ``bands.DEFAULT_GROUND_ALBEDO``), without molecules (their extinction is not grey);
    ``surface``, ``wind_m_s``: the ground under a domain with its own (``scene.surface``: "file", each
    column's surface in the band with the sea's glint; "albedo"; "flat": ``ground_albedo`` everywhere);
    ``atmosphere`` (``optics.air.Atmosphere``): the clear 1-D atmosphere in the band(s) inside the box (from
    ``hyd``'s ``rho_air``), on the sun's path and outside the box (``satellite.air``), in place of ``rayleigh``;
    ``channel_bands``: three ``Band``s of any wavelengths in the channels, as ``rgb`` (the natural view's,
    ``satellite.natural``).

    Raises
    ------
    ValueError
        Where ``hyd`` has no latitude/longitude or valid time (an ideal case without --lat/--lon/--date), the
        sun is below the horizon, or a column is seen at more than ``max_vza_deg`` (named with the angle).
    """
    from ..scene.place import place_of, sun_from_time
    source = str(hyd.attrs.get("source", "input"))
    if sun_time is not None:
        from ..scene.solar import as_utc
        hyd = hyd.copy()
        hyd.attrs["valid_time"] = as_utc(sun_time).strftime("%Y-%m-%dT%H:%M:%SZ")
    place = place_of(hyd)
    if place is None:
        raise ValueError(f"{source}: a satellite view needs the domain's latitude/longitude; the file has none "
                         "(an ideal case: give --lat and --lon, and --date for the sun)")
    sat = satellite(sat) if isinstance(sat, str) else sat
    rgb = rgb or channel_bands is not None
    bands = tuple(channel_bands) if channel_bands is not None else true_color_bands(sat) if rgb else ()
    b = bands[0] if rgb else band(band_name)
    if channel_bands is None:
        check_band_on(b, sat)
    if rayleigh and atmosphere is not None:
        raise ValueError("--rayleigh (the molecules in the box only) and --atmosphere clear (molecules, ozone and "
                         "aerosol in and above the box, on the sun's path) exclude each other: drop --rayleigh")
    if rgb and rayleigh:
        raise ValueError("a true-colour render holds no molecules (one extinction for the three bands): render "
                         "the bands one at a time (satellite.truecolor)")
    top = float(vol.bbox[1][2]) + RAY_START_ABOVE_M
    view = satellite_view(place, sat, resolution_km, top, max_vza_deg, source)
    azimuth, elevation, sun_meta = sun_from_time(hyd)
    from ..scene.surface import with_surface
    bvol = with_surface(rgb_volume(vol, bands) if rgb else band_volume(vol, b),
                        [x.wavelength_m * 1e6 for x in (bands if rgb else (b,))], surface, wind_m_s)
    sun = Sun(azimuth, elevation, (1.0, 1.0, 1.0))
    if bvol.terrain is not None and bvol.terrain.sea:  # the glint where each column's own sun puts it
        from .glint import sea_normals
        bvol = replace(bvol, terrain=replace(bvol.terrain, sea_normal=sea_normals(place, sat, sun_meta, sun)))
    if atmosphere is not None:  # one wavelength per channel: the bands' own air and sun (satellite.air)
        from ..optics.air.inside import with_box_air
        bvol = with_box_air(bvol, hyd, atmosphere, [x.wavelength_m * 1e9 for x in bands] if rgb
                            else [b.wavelength_m * 1e9] * 3)
    if rayleigh:
        from ..optics.rayleigh import with_rayleigh
        bvol = with_rayleigh(bvol, b.wavelength_m, hyd["rho_air"].values)
    (x0, y0, _), (x1, y1, _) = vol.bbox
    extent = max(x1 - x0, y1 - y0)
    cam = Camera.orthographic(center=((x0 + x1) / 2, (y0 + y1) / 2, top + 1000.0), direction=(0.0, 0.0, -1.0),
                              width=extent, height=extent)  # nominal: the rays come from the table
    w, h = view.size
    albedo = DEFAULT_GROUND_ALBEDO if ground_albedo is None else ground_albedo  # the sea's, where not given
    spec = SceneSpec(camera=cam, sun=sun, sky=None, ground=Ground(albedo=albedo), width=w, height=h,
                     seed=seed, rays=view.rays, atmosphere=atmosphere)
    return SatelliteScene(spec, bvol, view, sat, b, sun_meta, bands, place.source)


def render_satellite(scene: SatelliteScene, spp: int = 64, **reference_kw):
    """Path-trace ``scene`` (``render_reference`` with ``normalize="reflectance"``: its passes, checkpoints,
    ``target_rse`` and Dask ``client`` apply). Returns (``xarray.Dataset`` of ``satellite_dataset``, Image)."""
    from ..reference.render import render_reference
    from .air import with_air_outside
    img = render_reference(scene.spec, scene.vol, spp=spp, normalize="reflectance", **reference_kw)
    img = with_air_outside(scene, img)
    return satellite_dataset(scene, img), img


def _grid_mapping(sat: Satellite) -> dict:
    """CF ``geostationary`` grid mapping of the fixed grid (attributes as GOES-R ABI's
    ``goes_imager_projection``)."""
    from .geostationary import WGS84_A_M, WGS84_B_M
    return {"grid_mapping_name": "geostationary", "perspective_point_height": sat.height_m,
            "semi_major_axis": WGS84_A_M, "semi_minor_axis": WGS84_B_M,
            "longitude_of_projection_origin": sat.sub_lon_deg, "latitude_of_projection_origin": 0.0,
            "sweep_angle_axis": sat.sweep, "proj4": sat.proj_string()}


def satellite_dataset(scene: SatelliteScene, img, channel: int | None = None):
    """A CF-1.8 dataset of a satellite render: reflectance and its standard error, solar and view angles,
    latitude/longitude, the cloud and in-domain masks, on the fixed grid (x, y scan angles in radians).
    ``channel``: the reflectance of that channel of the image (a true-colour render's band), else their mean."""
    import xarray as xr
    from ..scene.solar import SolarPosition, sun_angles_at
    v, m = scene.view, scene.sun_meta
    b = scene.bands[channel] if channel is not None and scene.bands else scene.band
    pick = slice(None) if channel is None else slice(channel, channel + 1)
    refl = np.asarray(img.radiance, np.float64)[..., pick].mean(axis=2)
    se = np.asarray(img.stderr, np.float64)[..., pick].mean(axis=2) if img.stderr is not None \
        else np.full_like(refl, np.nan)
    centre = SolarPosition(m["solar_zenith_deg"], m["solar_zenith_geometric_deg"], m["solar_azimuth_true_deg"])
    sza, saa = sun_angles_at(centre, m["centre_lat"], m["centre_lon"], v.lat, v.lon)
    from .rays import crosses_box
    inside = crosses_box(v.rays, scene.vol.bbox)
    cloud = np.zeros_like(inside) if img.transmittance is None else np.asarray(img.transmittance) < 0.5
    dims = ("y", "x")
    gm = "fixed_grid_projection"

    def var(values, long_name, units, **attrs):
        return (dims, np.asarray(values, np.float32),
                {"long_name": long_name, "units": units, "grid_mapping": gm, "coordinates": "lat lon", **attrs})

    ds = xr.Dataset(
        {"reflectance": var(refl, f"bidirectional reflectance factor pi L / (E0 cos theta0), {b.name} um",
                            "1", standard_name="toa_bidirectional_reflectance"),
         "reflectance_standard_error": var(se, "standard error of the reflectance (Monte Carlo)", "1"),
         "solar_zenith_angle": var(sza, "solar zenith angle at the pixel", "degree", standard_name="solar_zenith_angle"),
         "solar_azimuth_angle": var(saa, "solar azimuth angle at the pixel, clockwise from north", "degree",
                                    standard_name="solar_azimuth_angle"),
         "sensor_zenith_angle": var(v.view_zenith_deg, "view zenith angle", "degree", standard_name="sensor_zenith_angle"),
         "sensor_azimuth_angle": var(v.view_azimuth_deg, "view azimuth angle (towards the satellite), clockwise from north",
                                     "degree", standard_name="sensor_azimuth_angle"),
         "cloud": (dims, cloud.astype(np.int8), {"long_name": "cloud pixel: eye-ray transmittance below 1/2",
                                                 "flag_values": [0, 1], "grid_mapping": gm}),
         "in_domain": (dims, inside.astype(np.int8), {"long_name": "line of sight through the model domain's box",
                                                      "flag_values": [0, 1], "grid_mapping": gm}),
         **_surface_var(scene, dims, gm),
         gm: ((), np.int32(0), _grid_mapping(scene.satellite))},
        coords={"x": ("x", v.x_rad, {"standard_name": "projection_x_coordinate", "units": "rad",
                                     "long_name": "fixed grid east-west scan angle"}),
                "y": ("y", v.y_rad, {"standard_name": "projection_y_coordinate", "units": "rad",
                                     "long_name": "fixed grid north-south scan angle"}),
                "lat": (dims, v.lat, {"standard_name": "latitude", "units": "degrees_north"}),
                "lon": (dims, v.lon, {"standard_name": "longitude", "units": "degrees_east"})})
    meta = img.metadata
    ds.attrs = {"Conventions": "CF-1.8", "title": f"weather-mi synthetic {scene.satellite.name} {b.name} um image",
                "source": str(scene.vol.attrs.get("source", "")), "satellite": scene.satellite.name,
                "sub_satellite_longitude_deg": scene.satellite.sub_lon_deg, "band_um": b.name,
                "band_wavelength_m": b.wavelength_m, "resolution_km": v.resolution_km,
                "valid_time": str(m.get("valid_time")), "place_source": scene.place_source,
                "rayleigh": int("rayleigh" in scene.vol.species), **_atmosphere_attrs(scene.spec.atmosphere),
                "rendered_solar_zenith_deg": 90.0 - scene.spec.sun.elevation,
                "one_sun_max_error_deg": float(m.get("one_sun_max_error_deg", np.nan)),
                "spp": int(meta.get("spp", 0)), "seconds": float(meta.get("seconds", np.nan)),
                "cloud_rse_mean": float((meta.get("noise") or {}).get("rse_mean", np.nan)),
                "history": "weather-mi satellite (3-D path tracing, majorant_volpath)",
                **_ecosystem_attrs(scene.satellite, m.get("valid_time"))}
    ds["reflectance"].attrs.update(wavelength=b.wavelength_m * 1e6, wavelength_units="um",
                                   channel=b.channels.get(scene.satellite.imager, ""))
    return ds


def _atmosphere_attrs(atm) -> dict:
    """``atmosphere`` ("none" or "clear") and, where clear, its aerosol optical depth, ozone column and precipitable
    water."""
    if atm is None:
        return {"atmosphere": "none"}
    return {"atmosphere": "clear", "aerosol_optical_depth_550nm": atm.aod_550, "ozone_column_atm_cm": atm.ozone_atm_cm,
            "precipitable_water_cm": atm.water_vapour_cm}


def _surface_var(scene: SatelliteScene, dims, gm) -> dict:
    """``land``: the land/sea mask of the column under each pixel's centre (its ground point), where the
    domain has a ground of its own; none otherwise."""
    terrain = getattr(scene.vol, "terrain", None)
    if terrain is None:
        return {}
    land = terrain.land_at(scene.view.x_m, scene.view.y_m)
    return {"land": (dims, land, {"long_name": "surface under the pixel: 1 land, 0 water (sea or lake), -1 "
                                               "beyond the model grid", "flag_values": [-1, 0, 1],
                                  "grid_mapping": gm, "source": str(scene.vol.attrs.get("land_source", ""))})}


# the names the Pytroll ecosystem (satpy's readers and writers, pyspectral) gives the imagers and the
# satellites at these positions; the image is synthetic, so the platform is named by its position
PLATFORM_NAMES = {"goes-east": "GOES-East", "goes-west": "GOES-West", "himawari": "Himawari", "meteosat": "Meteosat"}


def _ecosystem_attrs(sat: Satellite, valid_time) -> dict:
    """Global attributes satpy-like tools read: ``platform_name``, ``sensor`` (lower case, as satpy's
    ``abi``/``ahi``/``seviri``), ``start_time``/``end_time`` (ISO 8601 UTC; a model time is an instant)."""
    t = "" if valid_time in (None, "None") else str(valid_time)
    return {"platform_name": PLATFORM_NAMES.get(sat.name, sat.name), "sensor": sat.imager,
            "start_time": t, "end_time": t}


def parse_resolution_km(text) -> float:
    """A pixel size "1km", "0.5 km", "500m" or "2" (km) in km; a ValueError naming the option otherwise."""
    t = str(text).strip().lower().replace(" ", "")
    scale = 1e-3 if t.endswith("m") and not t.endswith("km") else 1.0
    try:
        value = float(t.removesuffix("km").removesuffix("m")) * scale
    except ValueError:
        value = float("nan")
    if not (value > 0 and np.isfinite(value)):
        raise ValueError(f"--resolution {text!r}: expected a pixel size such as 1km, 0.5km or 500m")
    return value


def satellite_outputs(output):
    """(NetCDF, EXR, PNG, checkpoint) of ``-o`` (a .nc name; ValueError otherwise): OUT.nc and ``render``'s
    OUT.exr, OUT.png, OUT.exr.ckpt.npz (``output_paths.render_outputs``)."""
    from pathlib import Path
    from ..io.output_paths import render_outputs
    out = Path(output)
    if out.suffix.lower() != ".nc":
        raise ValueError(f"-o {output}: a satellite image is written as NetCDF: expected a name ending in .nc")
    return (out, *render_outputs(out.with_suffix(".exr")))


def write_satellite(ds, img, nc_path, exr_path, png_path=None) -> None:
    """The dataset as NetCDF (written under a temporary name, then renamed), the image as EXR (reflectance in
    R, G, B, its standard error, the metadata, ``img.denoised`` where set) and, where ``png_path`` is given, a
    raw PNG (reflectance 0-1, sRGB-encoded; the command's PNG is ``display.satellite_picture``'s)."""
    from ..io.output_paths import written_atomically
    with written_atomically(nc_path, "NetCDF file") as tmp:
        ds.to_netcdf(tmp)
    img.save(exr_path)
    if png_path is not None:
        img.save_png(png_path, exposure=1.0)


__all__ = ["SatelliteScene", "satellite_scene", "render_satellite", "satellite_dataset", "parse_resolution_km",
           "satellite_outputs", "write_satellite"]
