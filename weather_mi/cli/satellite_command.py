"""``weather-mi satellite``: its parser and its command (one band, true colour, a loop or tiles)."""
from __future__ import annotations

import argparse
from pathlib import Path

from ..io.sources import DEMOS, check_time
from ..optics.volume import default_sizes
from ..reference.options import add_flags, flag_values
from ..satellite.bands import DEFAULT_GROUND_ALBEDO, SEA_ALBEDO
from .options import add_dask_options, add_place_options, add_sizes_option, add_surface_options, check_unfinished, \
    open_placed, surface_kw
from .periodic_option import add_periodic_option, periodic_value
from .satellite_air_option import add_satellite_air_options, check_natural_view, satellite_atmosphere
from .satellite_tiles import add_tile_options, check_tile_options, satellite_tiles_command


SATELLITE_ESTIMATOR = ("spp", "target_rse", "max_seconds")  # the rest: render_satellite's (reflectance)


def satellite_command(args) -> Path:
    """A synthetic geostationary image (``satellite.imagery``): checked (outputs, an unfinished render, place,
    visibility) before rendering, written as NetCDF + EXR + PNG."""
    from ..io.output_paths import OutputLock, check_writable_folder
    from ..satellite import imagery as si
    resolution = si.parse_resolution_km(args.resolution)
    nc, exr, png, ckpt = si.satellite_outputs(args.output)
    from .satellite_loop import satellite_loop_command, wants_loop
    check_natural_view(args, wants_loop(args))
    check_satellite_bands(args)
    check_tile_options(args)
    satellite_atmosphere(args)
    if args.denoise:
        from ..display.denoise import check_available
        check_available()
    if wants_loop(args):  # several times: one NetCDF with a time dimension, a PNG per time, an MP4
        check_writable_folder(nc)
        with OutputLock(nc):
            return satellite_loop_command(args, resolution, nc, flag_values(args, SATELLITE_ESTIMATOR))
    check_time(args.file, args.demo, args.time)
    check_writable_folder(nc)
    with OutputLock(nc):
        from ..satellite.truecolor import band_checkpoints
        from ..satellite.natural import natural_checkpoints
        for c in band_checkpoints(ckpt) + natural_checkpoints(ckpt):  # a checkpoint per band or render
            check_unfinished(c, args.resume)
        if args.tile_size is not None:  # tiles as Dask tasks, no process reading the whole domain
            return satellite_tiles_command(args, resolution, nc, exr, png, flag_values(args, SATELLITE_ESTIMATOR))
        return _satellite(args, resolution, nc, exr, png, ckpt)


def check_satellite_bands(args) -> None:
    """The band options against the satellite, before the input is read: ``--rgb`` or one ``--band`` (not
    both), a band the satellite's imager has."""
    from ..satellite.bands import band, check_band_on, true_color_bands
    from ..satellite.geostationary import satellite
    sat = satellite(args.satellite)
    if args.view == "natural":  # its own wavelengths (check_natural_view)
        return
    if args.rgb and args.band is not None:
        raise ValueError(f"--rgb renders the true-colour bands ({', '.join(b.name for b in true_color_bands(sat))} "
                         f"um on {sat.name}) in one run: drop --band {args.band}, or drop --rgb for one band")
    if args.rgb:
        true_color_bands(sat)
    else:
        check_band_on(band(args.band or "0.64"), sat)


def _satellite(args, resolution, nc, exr, png, ckpt) -> Path:
    from ..satellite import imagery as si
    from ..reference.cluster import session
    from ..optics.volume import optical_volume
    hyd = open_placed(args)
    vol = optical_volume(hyd, species=args.preset, phase=args.phase, sizes=args.sizes or default_sizes(hyd),
                         size_classes=args.size_classes,
                         periodic=periodic_value(args), release=True,
                         keep=("beta_ext", "weights") if args.rgb or args.rayleigh or args.view == "natural"
                         else ("weights",))  # the air: beta_s
    atm = satellite_atmosphere(args)
    # --rayleigh's air needs rho_air; the clear air's box reads its level means (the volume's ``air_density``)
    hyd = hyd.drop_vars([v for v in hyd.data_vars if v != "rho_air" or not args.rayleigh])  # in vol now
    if args.view == "natural":
        return _satellite_natural(args, hyd, vol, resolution, nc, exr, png, ckpt, atm)
    if args.rgb:
        return _satellite_rgb(args, hyd, vol, resolution, nc, exr, png, ckpt, atm)
    scene = si.satellite_scene(hyd, vol, args.satellite, args.band or "0.64", resolution, rayleigh=args.rayleigh,
                               ground_albedo=args.ground_albedo,
                               seed=args.seed, atmosphere=atm, **surface_kw(args))
    del vol, hyd  # the scene holds the band's volume (its own albedo) and air: the RGB albedo and rho_air go
    w, h = scene.view.size
    print(f"{scene.satellite.name} (sub-satellite longitude {scene.satellite.sub_lon_deg}), band {scene.band.name} um: "
          f"{w} x {h} pixels of {resolution:g} km, view zenith {scene.view.view_zenith_deg.min():.1f}-"
          f"{scene.view.view_zenith_deg.max():.1f} deg, solar zenith {90 - scene.spec.sun.elevation:.2f} deg at the "
          f"centre ({scene.sun_meta['valid_time']}; one sun, up to {scene.sun_meta['one_sun_max_error_deg']:.2f} deg "
          "from a column's own)")
    # release_volume: the kernel's grids replace the band volume's; the outside air (satellite.air) reads its bbox,
    # periodic and air.band_nm only
    with session(args.scheduler, args.workers) as client:
        ds, img = si.render_satellite(scene, **flag_values(args, SATELLITE_ESTIMATOR), checkpoint=ckpt,
                                      resume=ckpt if args.resume else None, client=client, release_volume=True)
    from ..display.satellite_picture import shown_dataset, write_picture
    shown = shown_dataset(ds, img, args.denoise)
    si.write_satellite(ds, img, nc, exr)
    write_picture(shown, png, denoise=False)
    ckpt.unlink(missing_ok=True)
    print(f"wrote {nc}, {exr} and {png} ({img.metadata['spp']} spp, {img.metadata['seconds']:.1f} s; cloud pixels "
          f"{int(ds.cloud.sum())}, mean relative standard error {ds.attrs['cloud_rse_mean']:.3f}; reflectance "
          f"{float(ds.reflectance.where(ds.in_domain == 1).mean()):.3f} mean over the domain)")
    return nc


def _satellite_rgb(args, hyd, vol, resolution, nc, exr, png, ckpt, atm) -> Path:
    """``satellite --rgb``: the true-colour bands in one render (per band with --rayleigh), the NetCDF with a
    band dimension, the EXR (the bands in R, G, B) and the PNG of the operational recipe
    (``satellite.truecolor``)."""
    from ..satellite import truecolor as tc
    from ..reference.cluster import session
    scenes = tc.true_color_scenes(hyd, vol, args.satellite, resolution, rayleigh=args.rayleigh,
                                  ground_albedo=args.ground_albedo, seed=args.seed, atmosphere=atm,
                                  **surface_kw(args))
    s = scenes[0]
    w, h = s.view.size
    names = ", ".join(sc.band.name for sc in scenes) if len(scenes) > 1 else ", ".join(b.name for b in s.bands)
    how = "one render per band (the air's extinction differs)" if len(scenes) > 1 else "one render, one band per channel"
    print(f"{s.satellite.name} (sub-satellite longitude {s.satellite.sub_lon_deg}), true colour from {names} um, "
          f"{how}: {w} x {h} pixels of {resolution:g} km, solar zenith {90 - s.spec.sun.elevation:.2f} deg at the "
          f"centre ({s.sun_meta['valid_time']})")
    with session(args.scheduler, args.workers) as client:
        ds, img = tc.render_true_color(scenes, **flag_values(args, SATELLITE_ESTIMATOR), checkpoint=ckpt,
                                       resume=ckpt if args.resume else None, client=client,
                                       release_volume=len(scenes) == 1)  # later bands (--rayleigh) read it
    from ..display.satellite_picture import shown_dataset, write_picture
    from ..satellite.imagery import write_satellite
    shown = shown_dataset(ds, img, args.denoise)
    write_satellite(ds, img, nc, exr)
    write_picture(shown, png, denoise=False)
    for c in tc.band_checkpoints(ckpt):
        c.unlink(missing_ok=True)
    means = ", ".join(f"{b} {float(ds.reflectance.sel(band=b).where(ds.in_domain == 1).mean()):.3f}"
                      for b in ds.band.values)
    print(f"wrote {nc}, {exr} and {png} ({img.metadata['spp']} spp, {img.metadata['seconds']:.1f} s; cloud pixels "
          f"{int(ds.cloud.sum())}; reflectance over the domain {means}; the PNG: sun-zenith"
          f"{', Rayleigh' if 'rayleigh_reflectance' in ds else ''} corrected, CIRA-stretched true colour)")
    return nc


def _satellite_natural(args, hyd, vol, resolution, nc, exr, png, ckpt, atm) -> Path:
    """``satellite --view natural``: the reflectance at ``satellite.natural.NATURAL_NM`` (three renders), as
    CIE X, Y, Z and linear sRGB (NetCDF; the EXR's R, G, B) and a PNG white-balanced for daylight."""
    from ..satellite import natural as sn
    from ..satellite.imagery import write_satellite
    from ..reference.cluster import session
    scenes = sn.natural_scenes(hyd, vol, args.satellite, resolution, atmosphere=atm,
                               ground_albedo=args.ground_albedo, seed=args.seed, **surface_kw(args))
    s = scenes[0]
    w, h = s.view.size
    print(f"{s.satellite.name} (sub-satellite longitude {s.satellite.sub_lon_deg}), natural colour from "
          f"{len(scenes) * 3} wavelengths ({len(scenes)} renders), atmosphere {'clear' if atm else 'none'}: {w} x {h} "
          f"pixels of {resolution:g} km, solar zenith {90 - s.spec.sun.elevation:.2f} deg ({s.sun_meta['valid_time']})")
    with session(args.scheduler, args.workers) as client:
        ds, img = sn.render_natural(scenes, **flag_values(args, SATELLITE_ESTIMATOR), checkpoint=ckpt,
                                    resume=ckpt if args.resume else None, client=client)
    write_satellite(ds, img, nc, exr)
    _natural_png(img, png)
    for c in sn.natural_checkpoints(ckpt):
        c.unlink(missing_ok=True)
    inside = ds.in_domain.values == 1
    xy = ds[["X", "Y", "Z"]].to_array().values[:, inside].mean(axis=1)
    print(f"wrote {nc}, {exr} and {png} ({img.metadata['spp']} spp, {img.metadata['seconds']:.1f} s; over the domain "
          f"Y {xy[1]:.3f}, chromaticity x {xy[0] / xy.sum():.4f}, y {xy[1] / xy.sum():.4f})")
    return nc


def _natural_png(img, png) -> None:
    """The natural view's linear sRGB as an 8-bit sRGB PNG (``io.image.to_srgb8``, Y = 1 at full scale): white
    balanced for daylight (D65 is white; the sun above the air a little warm), enlarged as the satellite pictures
    are (``display.satellite_picture.zoom_for``)."""
    import numpy as np
    from ..display.satellite_picture import zoom_for
    from ..io.image import to_srgb8, write_png8
    frame = to_srgb8(np.asarray(img.radiance, np.float64), 1.0)
    k = zoom_for(frame.shape[1])
    write_png8(png, np.repeat(np.repeat(frame, k, axis=0), k, axis=1))


def add_satellite_parser(sub) -> None:
    from ..satellite.bands import BANDS
    from ..satellite.geostationary import SATELLITES
    sat = sub.add_parser("satellite", help="synthetic geostationary imagery: reflectance on the satellite's fixed "
                                           "grid, 3-D path-traced (NetCDF + EXR + PNG)")
    sat.add_argument("file", nargs="*", help="wrfout NetCDF or LES text file; several wrfout files: a loop of "
                                             "their times in order")
    sat.add_argument("--demo", choices=DEMOS, help="a built-in demo storm")
    sat.add_argument("--time", default=None, help="time index or timestamp (WRF files; default the last); "
                     '"all", START:STOP[:STEP] or a comma list: a loop (a time dimension, a PNG per time, an MP4)')
    sat.add_argument("--fps", type=float, default=4.0, help="a loop's MP4: frames per second")
    add_place_options(sat)
    sat.add_argument("--satellite", default="goes-east", choices=tuple(SATELLITES))
    sat.add_argument("--band", default=None, choices=tuple(BANDS), help="central wavelength (um), rendered "
                                                                      "monochromatically (default 0.64)")
    sat.add_argument("--rgb", action="store_true",
                     help="true colour: the 0.47, 0.64, 0.86 um bands (himawari: 0.47, 0.51, 0.64) in one render, "
                          "a NetCDF with a band dimension and the operational products' RGB as the PNG")
    sat.add_argument("--resolution", default="1km", help="pixel size at the sub-satellite point (e.g. 1km, 500m)")
    sat.add_argument("--rayleigh", action="store_true",
                     help="the old option: molecular scattering of the air in the domain only (with --atmosphere none; "
                          "--atmosphere clear holds the molecules in, above and around the domain)")
    add_satellite_air_options(sat)
    sat.add_argument("--preset", default="physical", choices=("paper", "physical"), help="species table")
    add_sizes_option(sat)
    sat.add_argument("--phase", default="per_species", choices=("per_species", "paper"))
    add_periodic_option(sat)
    sat.add_argument("--ground-albedo", type=float, default=None,
                     help=f"surface albedo where the file has none (default {DEFAULT_GROUND_ALBEDO:g}, the sea; with --rgb "
                          f"the sea per band, {SEA_ALBEDO['0.47']:g} at 0.47 um to {SEA_ALBEDO['0.86']:g} at 0.86 um)")
    add_surface_options(sat, "file")
    add_flags(sat, SATELLITE_ESTIMATOR)
    sat.add_argument("--seed", type=int, default=0)
    sat.add_argument("--denoise", action=argparse.BooleanOptionalAction, default=True,
                     help="the PNG shows the OIDN-denoised reflectance (the EXR's denoised.R/G/B; the NetCDF and the "
                          "EXR's R, G, B stay the unbiased reflectance); --no-denoise: the raw reflectance")
    sat.add_argument("--resume", action="store_true", help="continue from OUTPUT.exr.ckpt.npz (--rgb --rayleigh: "
                                                           "OUTPUT.exr.<band>.ckpt.npz)")
    add_dask_options(sat)
    add_tile_options(sat)
    sat.add_argument("-o", "--output", default="weather-mi-satellite.nc", help="output NetCDF (.nc)")
