"""The RGB and the spectral mode's renders of one view compared by region (issue 38, spectralsky38): the lit
cloud (the brightest 10 % of the opaque pixels of the two renders' mean display layer), all opaque cloud, the
clear sky (upper half, eye-ray transmittance 1) and the ground and haze (lower half): each region's mean linear
sRGB in both, CIE xy, luminance Y, CIEDE2000 at equal lightness and in full (CIELAB white at twice the brighter Y).

    weather-mi render --demo supercell --sun-elevation 4 --sun-azimuth 260 --camera-azimuth 290 --size 160x120 \
        --spp 64 --seed 1 [--spectral] -o /tmp/sc_4_{rgb,spectral}.exr          (and --sun-elevation 60: sc_60_*)
    .venv/bin/python validation/spectral_sky_renders.py /tmp/sc 4 60
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def _full_de(a, b, white_y) -> float:
    import colour
    from weather_mi.optics.spectrum import xyz_of_linear_srgb
    d65 = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    la, lb = (colour.XYZ_to_Lab(xyz_of_linear_srgb(v) / white_y, d65) for v in (a, b))
    return float(colour.delta_E(la, lb, method="CIE 2000"))


def regions(rgb_img, spectral_img) -> dict:
    """The regions' masks (H, W) of the module docstring."""
    from weather_mi.display.cloud_colour import lit_cloud_pixels
    r, s = rgb_img, spectral_img
    both = 0.5 * (r.radiance + s.radiance)
    if r.denoised is not None and s.denoised is not None:
        both = 0.5 * (r.denoised + s.denoised)
    rows = np.arange(s.radiance.shape[0])[:, None]
    clear, upper = s.transmittance > 0.999, rows < s.radiance.shape[0] // 2
    return {"lit cloud": lit_cloud_pixels(both, np.minimum(r.transmittance, s.transmittance)),
            "all opaque cloud": np.maximum(r.transmittance, s.transmittance) < 0.05,
            "sky (upper half, clear)": clear & upper, "ground and haze (lower half, clear)": clear & ~upper}


def main(argv=None) -> None:
    from weather_mi.display.cloud_colour import delta_e_equal_lightness, xy_of_linear_srgb
    from weather_mi.io.image import Image
    from weather_mi.optics.spectrum import xyz_of_linear_srgb
    argv = sys.argv[1:] if argv is None else argv
    prefix = argv[0]
    for tag in argv[1:]:
        r, s = Image.load(f"{prefix}_{tag}_rgb.exr"), Image.load(f"{prefix}_{tag}_spectral.exr")
        for name, mask in regions(r, s).items():
            if not mask.any():
                print(f"sun {tag}: {name}: no pixels")
                continue
            a, b = r.radiance[mask].astype(float).mean(0), s.radiance[mask].astype(float).mean(0)
            xa, xb = xy_of_linear_srgb(a), xy_of_linear_srgb(b)
            ya, yb = xyz_of_linear_srgb(a)[1], xyz_of_linear_srgb(b)[1]
            print(f"sun {tag}: {name} ({int(mask.sum())} px): RGB xy ({xa[0]:.3f}, {xa[1]:.3f}) Y {ya:.4f}; spectral "
                  f"xy ({xb[0]:.3f}, {xb[1]:.3f}) Y {yb:.4f}; CIEDE2000 at equal lightness "
                  f"{delta_e_equal_lightness(xa, xb):.2f}, full {_full_de(a, b, 2 * max(ya, yb)):.2f}")


if __name__ == "__main__":
    main()
