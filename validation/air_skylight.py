"""Issue 38 part 1, ``--sky air``: the clear atmosphere's skylight into the box (``kernel.air_sky``) and what it
does to the demo supercell.

    .venv/bin/python validation/air_skylight.py [--size 160x120] [--spp 64] [--out /tmp/air_skylight]

1. The 1-D atmosphere's sky at the ground by DISORT (``optics.air.skylight``) against SPCTRL2 (pvlib): direct and
   diffuse horizontal irradiance at 450/550/650 nm, SZA 30/60/75, ground albedo 0.2.
2. A cloud-free box (10 km wide, 2 km high; 80 km wide, 16 km high) over a Lambertian ground (albedo 0.3), the
   sun at 30 deg: the path tracer's ground radiance with the envmap and without it against DISORT's
   rho / pi (direct + diffuse).
3. The demo supercell (issue 38's headline view: sun azimuth 260, camera azimuth 290; sun elevations 4 and 60
   deg) with ``--atmosphere clear --sky air`` before (no light from the air around the box: ``Sky`` None) and
   after (the envmap), the air along the eye rays composited (``display.aerial``): the luminance of the shaded
   cloud (opaque pixels, eye-ray transmittance < 0.05, below the median luminance of those) and of the lit cloud
   (their brightest 10 %), and the pictures (PNG, one exposure per view for both).
"""
from __future__ import annotations

import argparse
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


WL = [450.0, 550.0, 650.0]


def spectrl2_horizontal(sza: float, albedo: float):
    """SPCTRL2's (direct horizontal, diffuse horizontal) over the extraterrestrial normal irradiance at WL: its
    aerosol turbidity at 500 nm is ours at 550 nm through Angstrom's law (exponent 1.14, SPCTRL2's rural one)."""
    import pvlib
    am = float(pvlib.atmosphere.get_relative_airmass(sza, "kastenyoung1989"))
    out = pvlib.spectrum.spectrl2(apparent_zenith=np.array([sza]), aoi=np.array([sza]), surface_tilt=0.0,
                                  ground_albedo=albedo, surface_pressure=101325.0, relative_airmass=np.array([am]),
                                  precipitable_water=0.0, ozone=0.3, aerosol_turbidity_500nm=0.1 * (500 / 550) ** -1.14,
                                  dayofyear=1)
    lam = out["wavelength"]
    e0, dni, dhi = (np.interp(WL, lam, out[k][:, 0]) for k in ("dni_extra", "dni", "dhi"))
    return math.cos(math.radians(sza)) * dni / e0, dhi / e0


def view_down(sky="air", ground=0.3, elevation=30.0, sun_azimuth=200.0):
    """A 4 x 4 orthographic view straight down from 20 m over a Lambertian ground of albedo ``ground``, the sun
    (a point, irradiance 1) at ``elevation``, the default clear atmosphere, ``sky`` (None: no sky)."""
    from weather_mi.optics.air import Atmosphere
    from weather_mi.scene.spec import Camera, Ground, SceneSpec, Sky, Sun
    cam = Camera.orthographic(center=(0.0, 0.0, 20.0), direction=(0.0, 0.0, -1.0), width=100.0, height=100.0)
    return SceneSpec(camera=cam, sun=Sun(azimuth=sun_azimuth, elevation=elevation, irradiance=1.0,
                                         angular_diameter_deg=0.0),
                     sky=None if sky is None else Sky(sky), ground=Ground(albedo=ground), width=4, height=4,
                     atmosphere=Atmosphere(), seed=5)


def ground_radiance(sky, spp=256, width_m=10e3, height_m=2e3, variant="llvm_ad_rgb"):
    """The path tracer's radiance of the ground under a cloud-free box ``width_m`` wide and ``height_m`` high
    (its own air: ``optics.air.inside``), the sun at 30 deg, against DISORT's rho / pi (direct + diffuse) at the
    ground (linear sRGB; ``variant``: a spectral one's linear sRGB of its CIE XYZ)."""
    from weather_mi.optics.air import Atmosphere
    from weather_mi.optics.air.skylight import sky_table
    from weather_mi.optics.phase.analytic import isotropic
    from weather_mi.optics.volume import OpticalVolume
    from weather_mi.reference.render import render_reference
    vol = OpticalVolume.from_arrays(np.zeros((16, 4, 4), np.float32), 1.0, isotropic(),
                                    ((-width_m / 2, -width_m / 2, 0.0), (width_m / 2, width_m / 2, height_m)))
    img = render_reference(view_down(sky), vol, spp=spp, progress=False, variant=variant)
    r = img.radiance.reshape(-1, 3).astype(np.float64).mean(axis=0)
    se = np.sqrt((img.stderr.reshape(-1, 3).astype(np.float64) ** 2).sum(axis=0)) / 16
    table = sky_table(Atmosphere(), 0.5, [0.0], ground_m=0.0, albedo=0.3)
    return r, se, 0.3 / math.pi * (table.direct_rgb[0] + table.diffuse_rgb[0])


def disort_vs_spectrl2():
    from weather_mi.optics.air import Atmosphere
    from weather_mi.optics.air.skylight import spectral_sky
    print("1. DISORT (ours) / SPCTRL2 at the ground, albedo 0.2, at 450 / 550 / 650 nm:")
    for sza in (30.0, 60.0, 75.0):
        _, down, direct = spectral_sky(Atmosphere(), math.cos(math.radians(sza)), [0.0], [0.0], [0.0], 0.0, 0.2,
                                       wavelengths_nm=WL)
        d_ref, f_ref = spectrl2_horizontal(sza, 0.2)
        print(f"   SZA {sza:4.0f}: direct " + " ".join(f"{v:.3f}" for v in direct[:, 0] / d_ref)
              + "; diffuse " + " ".join(f"{v:.3f}" for v in down[:, 0] / f_ref)
              + " (ours " + " ".join(f"{v:.4f}" for v in down[:, 0]) + " per unit normal irradiance)")


def cloud_free_ground():
    print("2. ground radiance under a cloud-free box / DISORT's rho/pi (direct + diffuse), sun at 30 deg (R G B):")
    for width, height in ((10e3, 2e3), (80e3, 16e3)):
        for label, sky in (("with the envmap   ", "air"), ("without (before)  ", None)):
            r, se, ref = ground_radiance(sky, spp=512, width_m=width, height_m=height)
            print(f"   {width / 1e3:.0f} km x {height / 1e3:.0f} km box, {label}: "
                  + " ".join(f"{v:.3f}" for v in r / ref)
                  + " (se " + " ".join(f"{v:.3f}" for v in se / ref) + ")", flush=True)


def shaded_and_lit(img) -> tuple[float, float]:
    """(median luminance of the shaded cloud, mean luminance of the lit cloud) of a reference image."""
    from weather_mi.display.cloud_colour import lit_cloud_pixels
    y = np.asarray(img.radiance, np.float64) @ [0.2126, 0.7152, 0.0722]
    opaque = np.asarray(img.transmittance) < 0.05
    shaded = opaque & (y < np.median(y[opaque]))
    return float(np.median(y[shaded])), float(y[lit_cloud_pixels(img.radiance, img.transmittance)].mean())


def lit_colour(img, spec, vol, elevation: float) -> str:
    """The lit cloud's xy and its CIEDE2000 at equal lightness to issue 38's targets (``validation.sun_colour``):
    the direct sun at the height its light comes from (ours, SPCTRL2's) and, at a high sun, SPCTRL2's sun and sky
    (global horizontal) at 1013 and 850 hPa."""
    from validation.sun_colour import own_direct_xy, spectrl2_at_height, spectrl2_global_xy
    from weather_mi.display.cloud_colour import (delta_e_equal_lightness, lit_cloud_pixels, visible_height_m,
                                                 xy_of_linear_srgb)
    mask = lit_cloud_pixels(img.radiance, img.transmittance)
    xy = xy_of_linear_srgb(np.asarray(img.radiance, np.float64)[mask].mean(axis=0))
    height = float(np.nanmedian(visible_height_m(spec, vol, mask)))
    text = (f"lit cloud xy ({xy[0]:.3f}, {xy[1]:.3f}) from {height:.0f} m; CIEDE2000 to the direct sun there "
            f"{delta_e_equal_lightness(xy, own_direct_xy(elevation, height)):.1f} (ours), "
            f"{delta_e_equal_lightness(xy, spectrl2_at_height(elevation, height)):.1f} (SPCTRL2)")
    if elevation > 30.0:
        text += "; to SPCTRL2's sun and sky " + ", ".join(
            f"{p:.0f} hPa {delta_e_equal_lightness(xy, spectrl2_global_xy(elevation, p)):.1f}"
            for p in (1013.25, 850.0))
    return text


def demo(size, spp, out: Path):
    from validation.sun_colour import demo_volume
    from weather_mi.display.aerial import with_eye_air
    from weather_mi.io.image import auto_exposure, write_png
    from weather_mi.reference.render import render_reference
    from weather_mi.scene.framing import scene_spec
    vol = demo_volume()
    out.mkdir(parents=True, exist_ok=True)
    print(f"3. demo supercell, --atmosphere clear --sky air, {size[0]}x{size[1]}, {spp} spp: luminance of the "
          "shaded cloud (median) and the lit cloud (brightest 10 %)")
    for elevation in (4.0, 60.0):
        spec = scene_spec(vol, size, sun_elevation=elevation, sun_azimuth=260.0, camera_azimuth=290.0,
                          atmosphere="clear", sky="air")
        imgs = {}
        for label, s in (("before", replace(spec, sky=None)), ("after", spec)):
            img = render_reference(s, vol, spp=spp, progress=False)
            imgs[label] = with_eye_air(img, s, vol, sky_air=True)
        exposure = auto_exposure(imgs["after"].radiance)
        for label, img in imgs.items():
            write_png(out / f"supercell_sun{elevation:.0f}_{label}.png", img.radiance, exposure)
        (sb, lb), (sa, la) = shaded_and_lit(imgs["before"]), shaded_and_lit(imgs["after"])
        for label, img in imgs.items():
            print(f"   sun {elevation:4.0f} deg, {label}: {lit_colour(img, spec, vol, elevation)}")
        print(f"   sun {elevation:4.0f} deg: shaded {sb:.4f} -> {sa:.4f} (x{sa / sb:.2f}), lit {lb:.4f} -> {la:.4f} "
              f"(x{la / lb:.2f}); {imgs['after'].metadata.get('seconds', float('nan')):.0f} s vs "
              f"{imgs['before'].metadata.get('seconds', float('nan')):.0f} s; pictures {out}/supercell_sun"
              f"{elevation:.0f}_{{before,after}}.png", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--out", default="/tmp/air_skylight")
    ap.add_argument("--only", choices=("1", "2", "3"), default=None)
    args = ap.parse_args(argv)
    size = tuple(int(v) for v in args.size.split("x"))
    steps = {"1": disort_vs_spectrl2, "2": cloud_free_ground, "3": lambda: demo(size, args.spp, Path(args.out))}
    for key, step in steps.items():
        if args.only in (None, key):
            step()


if __name__ == "__main__":
    main()
