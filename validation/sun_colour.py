"""Issue 38's headline: the colour of a sunlit storm at a low sun, with and without the atmosphere, against the
direct sunlight of Bird & Riordan's SPCTRL2 (pvlib) at that sun; and at midday against SPCTRL2's sun and sky.

    .venv/bin/python validation/sun_colour.py [--size 160x120] [--spp 64] [--elevation 4] [--midday 60]
        [--spectral] [--cases none:sunsky,clear:air,clear:sunsky] [--camera-distance-km KM] [--seed N]
        [--renders DIR] [--no-through-air]

The scene of ``weather-mi render --demo supercell --sun-elevation 4 --sun-azimuth 260 --camera-azimuth 290``
(its defaults otherwise) rendered with ``--atmosphere none`` (the sky model), and ``--atmosphere clear`` (the
air on the sun's path, inside the box and along the eye rays outside it) with ``--sky air`` (render's default)
and with ``--sky sunsky``; the lit cloud's colour is the mean of the brightest 10 % of the opaque cloud pixels
(``display.cloud_colour``). The reference: SPCTRL2's direct normal spectrum (0.3 atm-cm ozone, AOD 0.1 at 500
nm, 1.4 cm water as in the issue and 0 as in our air, Kasten-Young air mass) at 1013, 850, 700 and 500 hPa, its
chromaticity by colour-science; CIEDE2000 at equal lightness to each and to the nearest. Then the same at the
height the lit cloud's light comes from (median over its pixels of where the eye ray reaches optical depth 1):
our air's direct sun there, and SPCTRL2's with the standard pressure and the aerosol column above that height.
At ``--midday`` (sun elevation, deg) the reference is SPCTRL2's global horizontal irradiance (direct plus
diffuse: sun and sky) at sea level and 850 hPa.

With the air, for the same lit pixels: their colour without the eye rays' air outside the box (the render
before ``display.aerial.with_eye_air``), and an independent model of the eye path: the Rayleigh transmittance
(Beer-Lambert, Bodhaine et al. 1999 Eq. 29 and the U.S. Standard Atmosphere 1976 written out here) from the
camera to where each lit pixel's ray reaches optical depth 1, applied to the SPCTRL2 reference (molecules only:
no ozone, aerosol or light scattered into the path, so a bound on the yellowing, not a prediction).
``--spectral``: Mitsuba's spectral variant and the eye rays' air per wavelength (as ``render --spectral``).

And (unless ``--no-through-air``) the reference for a distant cloud, sun and sky (and the direct sun) at the lit
cloud's height *seen through the same air*: the eye path's transmittance of the whole air and the air's own light
along it from DISORT, on an atmosphere written out in ``validation/seen_through_air.py``, at the render's luminance
(that module's docstring; docs/spectral.md, "The headline against sun and sky seen through the same air").
``--renders DIR`` keeps each render as .npz there and reads it back on a later run.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from validation.seen_through_air import path_transmittance  # noqa: E402

PRESSURES_HPA = (1013.25, 850.0, 700.0, 500.0)


WAVELENGTHS_NM = np.arange(360.0, 781.0)  # colour-science's default integration range, 1 nm


def spectrl2_spectrum(elevation_deg: float, pressure_hpa: float, water_cm: float = 1.4, ozone_atm_cm: float = 0.3,
                      turbidity_500: float = 0.1, sky: bool = False) -> np.ndarray:
    """SPCTRL2's (pvlib ``spectrl2``, Kasten-Young air mass) direct normal irradiance, or with ``sky`` the global
    horizontal one (direct x cos(zenith) + diffuse: sun and sky), on ``WAVELENGTHS_NM`` (linear between
    SPCTRL2's wavelengths)."""
    import pvlib
    sza = 90.0 - elevation_deg
    am = float(pvlib.atmosphere.get_relative_airmass(sza, "kastenyoung1989"))
    out = pvlib.spectrum.spectrl2(apparent_zenith=np.array([sza]), aoi=np.array([sza]), surface_tilt=0.0,
                                  ground_albedo=0.2, surface_pressure=pressure_hpa * 100.0,
                                  relative_airmass=np.array([am]), precipitable_water=water_cm, ozone=ozone_atm_cm,
                                  aerosol_turbidity_500nm=turbidity_500, dayofyear=1)
    e = out["dni"][:, 0] * (np.cos(np.radians(sza)) if sky else 1.0) + (out["dhi"][:, 0] if sky else 0.0)
    return np.interp(WAVELENGTHS_NM, out["wavelength"], e)


def xy_of_spectrum(values, transmittance=1.0) -> np.ndarray:
    """CIE 1931 chromaticity (colour-science, 2 deg observer) of a spectrum on ``WAVELENGTHS_NM`` times a
    transmittance on the same wavelengths."""
    import colour
    shape = colour.SpectralShape(WAVELENGTHS_NM[0], WAVELENGTHS_NM[-1], 1)
    sd = colour.SpectralDistribution(np.asarray(values) * transmittance, shape.wavelengths)
    return np.asarray(colour.XYZ_to_xy(colour.sd_to_XYZ(sd, method="Integration")))


def spectrl2_direct_xy(elevation_deg: float, pressure_hpa: float, water_cm: float = 1.4, ozone_atm_cm: float = 0.3,
                       turbidity_500: float = 0.1) -> np.ndarray:
    """CIE 1931 chromaticity of SPCTRL2's direct normal irradiance (``spectrl2_spectrum``)."""
    return xy_of_spectrum(spectrl2_spectrum(elevation_deg, pressure_hpa, water_cm, ozone_atm_cm, turbidity_500))


def spectrl2_spectrum_at_height(elevation_deg: float, height_m: float, water_cm: float = 1.4,
                                sky: bool = False) -> np.ndarray:
    """SPCTRL2's direct sun (``sky``: sun and sky, global horizontal) at a height on ``WAVELENGTHS_NM``: the
    standard atmosphere's pressure there, the turbidity of the aerosol above it (0.1 at sea level, scale height
    1.2 km) and the precipitable water above it (``water_cm`` at sea level, scale height 2 km): SPCTRL2 itself has
    no profiles; these are our atmosphere's defaults."""
    from weather_mi.io.standard_atmosphere import standard_temperature_pressure
    from weather_mi.optics.air.water_vapour import SCALE_HEIGHT_M
    pressure_hpa = float(standard_temperature_pressure(height_m)[1]) / 100.0
    return spectrl2_spectrum(elevation_deg, pressure_hpa, water_cm * np.exp(-height_m / SCALE_HEIGHT_M),
                             turbidity_500=0.1 * np.exp(-height_m / 1200.0), sky=sky)


def spectrl2_at_height(elevation_deg: float, height_m: float, water_cm: float = 1.4,
                       transmittance=1.0) -> np.ndarray:
    """The xy of SPCTRL2's direct sun at a height (``spectrl2_spectrum_at_height``) seen through
    ``transmittance`` (on ``WAVELENGTHS_NM``)."""
    return xy_of_spectrum(spectrl2_spectrum_at_height(elevation_deg, height_m, water_cm), transmittance)


def own_direct_xy(elevation_deg: float, height_m: float) -> np.ndarray:
    """Chromaticity of the direct sun of our clear atmosphere (defaults) at a height."""
    from weather_mi.optics import spectrum
    from weather_mi.optics.air import Atmosphere, sun_xyz
    return spectrum.chromaticity_xy(sun_xyz(Atmosphere(), height_m, np.sin(np.radians(elevation_deg))))


def headline_scene(vol, size=(160, 120), elevation=4.0, atmosphere="none"):
    from weather_mi.scene.framing import scene_spec
    return scene_spec(vol, size, sun_elevation=elevation, sun_azimuth=260.0, camera_azimuth=290.0,
                      atmosphere=atmosphere)


def demo_volume():
    """The demo supercell's OpticalVolume (which keeps the model's air density per level for the air in the box,
    ``optics.air.inside.scene_air``)."""
    from weather_mi.io.sources import open_source
    from weather_mi.optics.volume import optical_volume
    return optical_volume(open_source(demo="supercell"), species="physical")


def lit_cloud(spec, vol, spp: int, eye_air: bool = False, sky_air: bool = False, spectral: bool = False,
              cache=None) -> dict:
    """The lit cloud of one render: ``xy`` (the lit pixels' mean), ``height`` (median height (m) where their eye
    rays reach optical depth 1), ``mask``, ``img``; ``eye_air``: seen through the air outside the box
    (``display.aerial``; ``sky_air``: with the air's own sky), and then ``xy_box``: the same pixels' colour
    without it (as the box's edge sends it to the camera: the eye path outside the box removed); ``spectral``:
    Mitsuba's spectral variant and the eye rays' air per wavelength (as ``render --spectral``); ``cache``: an
    .npz path that holds the render (read when it exists, written when not)."""
    from weather_mi.display.cloud_colour import lit_cloud_pixels, visible_height_m, xy_of_linear_srgb
    from weather_mi.reference.render import render_reference
    variant = None
    if spectral:
        from weather_mi.kernel.variant import spectral_variant
        variant = spectral_variant()
    saved = Path(cache) if cache else None
    if saved is not None and saved.exists():  # --renders: a render of the same case made before
        import types
        with np.load(saved) as f:
            raw = types.SimpleNamespace(radiance=f["raw"])
            img = types.SimpleNamespace(radiance=f["radiance"], transmittance=f["transmittance"],
                                        metadata={"seconds": float(f["seconds"])})
    else:
        raw = render_reference(spec, vol, spp=spp, progress=False, variant=variant)
        img = raw
        if eye_air:
            from weather_mi.display.aerial import eye_air as eye_air_terms, with_eye_air
            img = with_eye_air(raw, spec, vol, sky_air=sky_air,
                               air=eye_air_terms(spec, vol, sky_air, spectral=spectral))
        if saved is not None:
            saved.parent.mkdir(parents=True, exist_ok=True)
            np.savez_compressed(saved, raw=raw.radiance, radiance=img.radiance, transmittance=img.transmittance,
                                seconds=img.metadata["seconds"])
    mask = lit_cloud_pixels(img.radiance, img.transmittance)
    height = float(np.nanmedian(visible_height_m(spec, vol, mask)))
    rgb = np.asarray(img.radiance, np.float64)[mask].mean(axis=0)
    return {"xy": xy_of_linear_srgb(rgb), "rgb": rgb, "height": height, "mask": mask, "img": img,
            "xy_box": xy_of_linear_srgb(np.asarray(raw.radiance, np.float64)[mask].mean(axis=0))}


def lit_cloud_xy(spec, vol, spp: int, eye_air: bool = False, sky_air: bool = False):
    """(xy of the lit cloud, median height (m) where its pixels reach optical depth 1, the image) of
    :func:`lit_cloud`."""
    out = lit_cloud(spec, vol, spp, eye_air, sky_air)
    return out["xy"], out["height"], out["img"]


def eye_path_rayleigh_transmittance(spec, vol, mask, points: int = 401, paths=None) -> np.ndarray:
    """The eye rays' Rayleigh transmittance (Beer-Lambert) from the camera to where the ``mask`` pixels' rays
    reach optical depth 1 in the cloud (``display.cloud_colour.visible_points_m``), averaged over the pixels,
    on ``WAVELENGTHS_NM``: exp(-sigma(lambda) int n(z) ds), sigma Bodhaine's Eq. 29, n the standard
    atmosphere's, the heights above a flat ground (trapezoid over ``points`` points). Molecules only: no ozone,
    aerosol or in-scattered light (an independent model of what the eye path does to a far white cloud).
    ``paths``: :func:`eye_paths`' (origins, ends) where the caller has them."""
    origins, ends = eye_paths(spec, vol, mask) if paths is None else paths
    return path_transmittance(origins, ends, WAVELENGTHS_NM, points, molecules_only=True).mean(axis=0)


def eye_paths(spec, vol, mask) -> tuple:
    """(origins, ends) (N, 3), m: the camera and where the ``mask`` pixels' eye rays reach optical depth 1 in the
    cloud (``display.cloud_colour.visible_points_m``; the rays that do not left out)."""
    from weather_mi.display.cloud_colour import visible_points_m
    from weather_mi.slicing.geometry import film_rays
    iy, ix = np.nonzero(mask)
    origins, _ = film_rays(spec, ix + 0.5, iy + 0.5)
    ends = visible_points_m(spec, vol, mask)
    ok = np.isfinite(ends[:, 0])
    return origins[ok], ends[ok]


def spectrl2_global_xy(elevation_deg: float, pressure_hpa: float, water_cm: float = 1.4,
                       transmittance=1.0) -> np.ndarray:
    """CIE 1931 chromaticity of SPCTRL2's global horizontal irradiance (sun and sky, ``spectrl2_spectrum``), seen
    through ``transmittance`` (on ``WAVELENGTHS_NM``)."""
    return xy_of_spectrum(spectrl2_spectrum(elevation_deg, pressure_hpa, water_cm, sky=True), transmittance)


CASES = (("none", "sunsky"), ("clear", "air"), ("clear", "sunsky"))  # (--atmosphere, --sky)


def _scene(vol, size, elevation, atmosphere, sky, camera_distance_km=None, seed: int = 0):
    from weather_mi.scene.framing import scene_spec
    return scene_spec(vol, size, sun_elevation=elevation, sun_azimuth=260.0, camera_azimuth=290.0,
                      atmosphere=atmosphere, sky=sky, camera_distance_km=camera_distance_km, seed=seed)


def _render(args, vol, size, elevation, atmosphere, sky):
    spec = _scene(vol, size, elevation, atmosphere, sky, args.camera_distance_km, args.seed)
    cache = None
    if args.renders:
        cam = ("" if args.camera_distance_km is None else f"_cam{args.camera_distance_km:g}km") + \
            (f"_seed{args.seed}" if args.seed else "")
        cache = Path(args.renders) / (f"{args.mode}_sun{elevation:g}_{atmosphere}_{sky}_{size[0]}x{size[1]}_"
                                      f"{args.spp}spp{cam}.npz")
    out = lit_cloud(spec, vol, args.spp, atmosphere == "clear", sky == "air", args.spectral, cache)
    out["spec"] = spec
    if atmosphere == "clear":  # the eye path modelled independently: Rayleigh's Beer-Lambert to the tau = 1 points
        origins, ends = eye_paths(spec, vol, out["mask"])  # once: a ray march per lit pixel
        out["t_eye"] = eye_path_rayleigh_transmittance(spec, vol, out["mask"], paths=(origins, ends))
        if args.through_air:  # and the whole air's: transmittance and path radiance (validation.seen_through_air)
            from validation.seen_through_air import path_radiance
            albedo = 0.0 if spec.ground is None else float(np.mean(spec.ground.albedo))
            l_path, t_air = path_radiance(origins, ends, spec.sun.to_sun, WAVELENGTHS_NM, albedo)
            out["l_path"], out["t_air"] = l_path.mean(axis=0), t_air.mean(axis=0)
    return out


def _through_air_words(r, elevation: float, name: str) -> str:
    """The lit cloud against sun and sky (and the direct sun) at its height seen through the same air
    (``validation.seen_through_air``, Eq. 1), as words; "" without it."""
    if "l_path" not in r:
        return ""
    from validation.seen_through_air import reference_xyz
    from weather_mi.display.cloud_colour import delta_e_equal_lightness as dee
    from weather_mi.optics import spectrum
    y_render = float(spectrum.xyz_of_linear_srgb(r["rgb"])[1])
    i450, i550, i650 = (int(np.argmin(abs(WAVELENGTHS_NM - w))) for w in (450, 550, 650))
    t = r["t_air"]
    words = [f"{name}: the eye path's whole air (molecules, ozone, aerosol) T {t[i450]:.3f} / {t[i550]:.3f} / "
             f"{t[i650]:.3f} at 450/550/650 nm"]
    for label, sky in (("sun and sky", True), ("direct sun", False)):
        e = spectrl2_spectrum_at_height(elevation, r["height"], sky=sky)
        ref = reference_xyz(y_render, e, t, r["l_path"], WAVELENGTHS_NM)
        xy_ref = spectrum.chromaticity_xy(ref["xyz"])
        xy_lit = xy_of_spectrum(e, t)
        words.append(f"SPCTRL2's {label} at {r['height']:.0f} m seen through the same air: xy ({xy_ref[0]:.3f}, "
                     f"{xy_ref[1]:.3f}), the air's own light {ref['path_xyz'][1] / y_render:.0%} of its Y; the lit "
                     f"cloud CIEDE2000 {dee(r['xy'], xy_ref):.1f} from it ({dee(r['xy'], xy_lit):.1f} from the "
                     f"same without the air's light, {dee(r['xy_box'], xy_of_spectrum(e)):.1f} at the box's edge "
                     "from the light itself)")
    return "; ".join(words)


def _eye_path_words(r, de_to) -> str:
    """The lit cloud without the eye path outside the box, and the eye path's Rayleigh transmittance, as words."""
    if "t_eye" not in r:
        return ""
    t = r["t_eye"]
    i450, i550, i650 = (int(np.argmin(abs(WAVELENGTHS_NM - w))) for w in (450, 550, 650))
    xb = r["xy_box"]
    return (f"; without the eye path outside the box xy ({xb[0]:.3f}, {xb[1]:.3f}) (CIEDE2000 {de_to(xb)}); the eye "
            f"path's Rayleigh transmittance to the lit pixels' tau=1 points (Bodhaine Eq. 29, US 1976) "
            f"{t[i450]:.3f} / {t[i550]:.3f} / {t[i650]:.3f} at 450/550/650 nm")


def low_sun(args, vol, size) -> None:
    """The lit cloud at ``args.elevation`` against SPCTRL2's direct sun (the issue's points, and at its height)."""
    from weather_mi.display.cloud_colour import delta_e_equal_lightness as dee
    refs = {(p, w): spectrl2_direct_xy(args.elevation, p, w) for p in PRESSURES_HPA for w in (1.4, 0.0)}
    print(f"SPCTRL2 direct sun at elevation {args.elevation} deg, xy (1.4 cm water | no water):")
    for p in PRESSURES_HPA:
        print(f"  {p:7.2f} hPa: ({refs[p, 1.4][0]:.3f}, {refs[p, 1.4][1]:.3f}) | ({refs[p, 0.0][0]:.3f}, {refs[p, 0.0][1]:.3f})")
    for atmosphere, sky in args.cases:  # render_reference puts spec.atmosphere's air into the box (scene_air)
        r = _render(args, vol, size, args.elevation, atmosphere, sky)
        xy, height, img = r["xy"], r["height"], r["img"]
        de = {k: dee(xy, v) for k, v in refs.items()}
        ours, theirs = own_direct_xy(args.elevation, height), spectrl2_at_height(args.elevation, height)
        name = f"{args.mode} --atmosphere {atmosphere} --sky {sky}"
        print(f"{name}: the lit cloud's light comes from a median height of {height:.0f} m, where "
              f"the direct sun is xy ({ours[0]:.3f}, {ours[1]:.3f}) in our clear air (CIEDE2000 "
              f"{dee(xy, ours):.1f}) and ({theirs[0]:.3f}, {theirs[1]:.3f}) by SPCTRL2 with the "
              f"aerosol and water above that height (CIEDE2000 {dee(xy, theirs):.1f})")
        print(f"{name}: lit cloud xy ({xy[0]:.3f}, {xy[1]:.3f}); CIEDE2000 at equal lightness to "
              "SPCTRL2 (1.4 cm water) " + ", ".join(f"{p:.0f} hPa {de[p, 1.4]:.1f}" for p in PRESSURES_HPA)
              + f"; nearest {min(de[p, 1.4] for p in PRESSURES_HPA):.1f} (no water: "
              f"{min(de[p, 0.0] for p in PRESSURES_HPA):.1f}); {img.metadata['seconds']:.1f} s"
              + _eye_path_words(r, lambda v: f"{dee(v, ours):.1f} / {dee(v, theirs):.1f} to ours / SPCTRL2's"),
              flush=True)
        if "t_eye" in r:
            seen = spectrl2_at_height(args.elevation, height, transmittance=r["t_eye"])
            print(f"{name}: SPCTRL2's direct sun at {height:.0f} m seen through the eye path's Rayleigh "
                  f"transmittance: xy ({seen[0]:.3f}, {seen[1]:.3f}); the lit cloud is CIEDE2000 {dee(xy, seen):.1f} "
                  "from it", flush=True)
        if "l_path" in r:
            print(_through_air_words(r, args.elevation, name), flush=True)


def midday(args, vol, size) -> None:
    """The lit cloud at ``args.midday`` against SPCTRL2's sun and sky (global horizontal)."""
    from weather_mi.display.cloud_colour import delta_e_equal_lightness as dee
    glob = {p: spectrl2_global_xy(args.midday, p) for p in (1013.25, 850.0)}
    print(f"SPCTRL2 sun and sky (global horizontal) at elevation {args.midday} deg: "
          + ", ".join(f"{p:.0f} hPa ({v[0]:.3f}, {v[1]:.3f})" for p, v in glob.items()))
    for atmosphere, sky in args.cases:
        r = _render(args, vol, size, args.midday, atmosphere, sky)
        xy, height, img = r["xy"], r["height"], r["img"]
        name = f"{args.mode} midday --atmosphere {atmosphere} --sky {sky}"
        print(f"{name}: lit cloud xy ({xy[0]:.3f}, {xy[1]:.3f}) from {height:.0f} m; "
              "CIEDE2000 at equal lightness to SPCTRL2's sun and sky "
              + ", ".join(f"{p:.0f} hPa {dee(xy, v):.1f}" for p, v in glob.items())
              + f"; {img.metadata['seconds']:.1f} s"
              + _eye_path_words(r, lambda v: " / ".join(f"{dee(v, g):.1f}" for g in glob.values())), flush=True)
        if "t_eye" in r:
            seen = {p: spectrl2_global_xy(args.midday, p, transmittance=r["t_eye"]) for p in glob}
            print(f"{name}: SPCTRL2's sun and sky seen through the eye path's Rayleigh transmittance: "
                  + ", ".join(f"{p:.0f} hPa ({v[0]:.3f}, {v[1]:.3f})" for p, v in seen.items())
                  + "; the lit cloud is CIEDE2000 " + " / ".join(f"{dee(xy, v):.1f}" for v in seen.values())
                  + " from them", flush=True)
        if "l_path" in r:
            print(_through_air_words(r, args.midday, name), flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--elevation", type=float, default=4.0, help="the low sun's elevation (deg); negative: none")
    ap.add_argument("--midday", type=float, default=60.0, help="the midday sun's elevation (deg); negative: none")
    ap.add_argument("--spectral", action="store_true", help="Mitsuba's spectral variant (render --spectral)")
    ap.add_argument("--cases", default=",".join(f"{a}:{s}" for a, s in CASES),
                    help="--atmosphere:--sky pairs, comma-separated (default: all three)")
    ap.add_argument("--camera-distance-km", type=float, default=None, help="render's --camera-distance-km")
    ap.add_argument("--seed", type=int, default=0, help="the path tracer's seed (render's --seed)")
    ap.add_argument("--renders", default=None, help="a folder: each case's render saved there as .npz (and read "
                    "from there when it exists: the table recomputed without rendering again)")
    ap.add_argument("--no-through-air", dest="through_air", action="store_false",
                    help="leave out the reference seen through the same air (validation/seen_through_air.py: "
                    "DISORT's path radiance, 17 solves per case)")
    args = ap.parse_args(argv)
    args.cases = [tuple(c.split(":")) for c in args.cases.split(",")]
    args.mode = "spectral" if args.spectral else "RGB"
    size = tuple(int(v) for v in args.size.split("x"))
    vol = demo_volume()
    if args.elevation >= 0:
        low_sun(args, vol, size)
    if args.midday >= 0:
        midday(args, vol, size)


if __name__ == "__main__":
    main()
