"""Issue 38's headline: the colour of a sunlit storm at a low sun, with and without the atmosphere, against the
direct sunlight of Bird & Riordan's SPCTRL2 (pvlib) at that sun; and at midday against SPCTRL2's sun and sky.

    .venv/bin/python validation/sun_colour.py [--size 160x120] [--spp 64] [--elevation 4] [--midday 60]

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
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

PRESSURES_HPA = (1013.25, 850.0, 700.0, 500.0)


def spectrl2_direct_xy(elevation_deg: float, pressure_hpa: float, water_cm: float = 1.4, ozone_atm_cm: float = 0.3,
                       turbidity_500: float = 0.1) -> np.ndarray:
    """CIE 1931 chromaticity of SPCTRL2's direct normal irradiance (pvlib ``spectrl2``, Kasten-Young air mass),
    integrated by colour-science over its default 360-780 nm (linear between SPCTRL2's wavelengths)."""
    import colour
    import pvlib
    sza = 90.0 - elevation_deg
    am = float(pvlib.atmosphere.get_relative_airmass(sza, "kastenyoung1989"))
    out = pvlib.spectrum.spectrl2(apparent_zenith=np.array([sza]), aoi=np.array([sza]), surface_tilt=0.0,
                                  ground_albedo=0.2, surface_pressure=pressure_hpa * 100.0,
                                  relative_airmass=np.array([am]), precipitable_water=water_cm, ozone=ozone_atm_cm,
                                  aerosol_turbidity_500nm=turbidity_500, dayofyear=1)
    lam, dni = out["wavelength"], out["dni"][:, 0]
    shape = colour.SpectralShape(360, 780, 1)
    sd = colour.SpectralDistribution(np.interp(shape.wavelengths, lam, dni), shape.wavelengths)
    return np.asarray(colour.XYZ_to_xy(colour.sd_to_XYZ(sd, method="Integration")))


def spectrl2_at_height(elevation_deg: float, height_m: float, water_cm: float = 1.4) -> np.ndarray:
    """SPCTRL2's direct sun at a height: the standard atmosphere's pressure there, the turbidity of the aerosol
    above it (0.1 at sea level, scale height 1.2 km) and the precipitable water above it (``water_cm`` at sea
    level, scale height 2 km): SPCTRL2 itself has no profiles; these are our atmosphere's defaults."""
    from weather_mi.io.standard_atmosphere import standard_temperature_pressure
    from weather_mi.optics.air.water_vapour import SCALE_HEIGHT_M
    pressure_hpa = float(standard_temperature_pressure(height_m)[1]) / 100.0
    return spectrl2_direct_xy(elevation_deg, pressure_hpa, water_cm * np.exp(-height_m / SCALE_HEIGHT_M),
                              turbidity_500=0.1 * np.exp(-height_m / 1200.0))


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


def lit_cloud_xy(spec, vol, spp: int, eye_air: bool = False, sky_air: bool = False):
    """(xy of the lit cloud, median height (m) where its pixels reach optical depth 1, the image); ``eye_air``:
    seen through the air outside the box (``display.aerial``; ``sky_air``: with the air's own sky)."""
    from weather_mi.display.cloud_colour import lit_cloud_pixels, visible_height_m, xy_of_linear_srgb
    from weather_mi.reference.render import render_reference
    img = render_reference(spec, vol, spp=spp, progress=False)
    if eye_air:
        from weather_mi.display.aerial import with_eye_air
        img = with_eye_air(img, spec, vol, sky_air=sky_air)
    mask = lit_cloud_pixels(img.radiance, img.transmittance)
    height = float(np.nanmedian(visible_height_m(spec, vol, mask)))
    return xy_of_linear_srgb(img.radiance[mask].mean(axis=0)), height, img


def spectrl2_global_xy(elevation_deg: float, pressure_hpa: float, water_cm: float = 1.4) -> np.ndarray:
    """CIE 1931 chromaticity of SPCTRL2's global horizontal irradiance (direct normal x cos(zenith) + diffuse
    horizontal: sun and sky), as ``spectrl2_direct_xy``."""
    import colour
    import pvlib
    sza = 90.0 - elevation_deg
    am = float(pvlib.atmosphere.get_relative_airmass(sza, "kastenyoung1989"))
    out = pvlib.spectrum.spectrl2(apparent_zenith=np.array([sza]), aoi=np.array([sza]), surface_tilt=0.0,
                                  ground_albedo=0.2, surface_pressure=pressure_hpa * 100.0,
                                  relative_airmass=np.array([am]), precipitable_water=water_cm, ozone=0.3,
                                  aerosol_turbidity_500nm=0.1, dayofyear=1)
    lam = out["wavelength"]
    ghi = out["dni"][:, 0] * np.cos(np.radians(sza)) + out["dhi"][:, 0]
    shape = colour.SpectralShape(360, 780, 1)
    sd = colour.SpectralDistribution(np.interp(shape.wavelengths, lam, ghi), shape.wavelengths)
    return np.asarray(colour.XYZ_to_xy(colour.sd_to_XYZ(sd, method="Integration")))


CASES = (("none", "sunsky"), ("clear", "air"), ("clear", "sunsky"))  # (--atmosphere, --sky)


def _scene(vol, size, elevation, atmosphere, sky):
    from weather_mi.scene.framing import scene_spec
    return scene_spec(vol, size, sun_elevation=elevation, sun_azimuth=260.0, camera_azimuth=290.0,
                      atmosphere=atmosphere, sky=sky)


def main(argv=None):
    from weather_mi.display.cloud_colour import delta_e_equal_lightness
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--elevation", type=float, default=4.0)
    ap.add_argument("--midday", type=float, default=60.0, help="the midday sun's elevation (deg); negative: none")
    args = ap.parse_args(argv)
    size = tuple(int(v) for v in args.size.split("x"))
    vol = demo_volume()
    refs = {(p, w): spectrl2_direct_xy(args.elevation, p, w) for p in PRESSURES_HPA for w in (1.4, 0.0)}
    print(f"SPCTRL2 direct sun at elevation {args.elevation} deg, xy (1.4 cm water | no water):")
    for p in PRESSURES_HPA:
        print(f"  {p:7.2f} hPa: ({refs[p, 1.4][0]:.3f}, {refs[p, 1.4][1]:.3f}) | ({refs[p, 0.0][0]:.3f}, {refs[p, 0.0][1]:.3f})")
    for atmosphere, sky in CASES:  # render_reference puts spec.atmosphere's air into the box (scene_air)
        spec = _scene(vol, size, args.elevation, atmosphere, sky)
        xy, height, img = lit_cloud_xy(spec, vol, args.spp, atmosphere == "clear", sky == "air")
        de = {k: delta_e_equal_lightness(xy, v) for k, v in refs.items()}
        ours, theirs = own_direct_xy(args.elevation, height), spectrl2_at_height(args.elevation, height)
        name = f"--atmosphere {atmosphere} --sky {sky}"
        print(f"{name}: the lit cloud's light comes from a median height of {height:.0f} m, where "
              f"the direct sun is xy ({ours[0]:.3f}, {ours[1]:.3f}) in our clear air (CIEDE2000 "
              f"{delta_e_equal_lightness(xy, ours):.1f}) and ({theirs[0]:.3f}, {theirs[1]:.3f}) by SPCTRL2 with the "
              f"aerosol and water above that height (CIEDE2000 {delta_e_equal_lightness(xy, theirs):.1f})")
        print(f"{name}: lit cloud xy ({xy[0]:.3f}, {xy[1]:.3f}); CIEDE2000 at equal lightness to "
              "SPCTRL2 (1.4 cm water) " + ", ".join(f"{p:.0f} hPa {de[p, 1.4]:.1f}" for p in PRESSURES_HPA)
              + f"; nearest {min(de[p, 1.4] for p in PRESSURES_HPA):.1f} (no water: "
              f"{min(de[p, 0.0] for p in PRESSURES_HPA):.1f}); {img.metadata['seconds']:.1f} s", flush=True)
    if args.midday < 0:
        return
    glob = {p: spectrl2_global_xy(args.midday, p) for p in (1013.25, 850.0)}
    print(f"SPCTRL2 sun and sky (global horizontal) at elevation {args.midday} deg: "
          + ", ".join(f"{p:.0f} hPa ({v[0]:.3f}, {v[1]:.3f})" for p, v in glob.items()))
    for atmosphere, sky in CASES:
        spec = _scene(vol, size, args.midday, atmosphere, sky)
        xy, height, img = lit_cloud_xy(spec, vol, args.spp, atmosphere == "clear", sky == "air")
        print(f"midday --atmosphere {atmosphere} --sky {sky}: lit cloud xy ({xy[0]:.3f}, {xy[1]:.3f}) from {height:.0f} m; "
              "CIEDE2000 at equal lightness to SPCTRL2's sun and sky "
              + ", ".join(f"{p:.0f} hPa {delta_e_equal_lightness(xy, v):.1f}" for p, v in glob.items())
              + f"; {img.metadata['seconds']:.1f} s", flush=True)


if __name__ == "__main__":
    main()
