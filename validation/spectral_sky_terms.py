"""The approximations of the spectral mode's air outside the box (``--spectral`` with ``--sky air``), measured as
colour differences (CIEDE2000) against the exact spectral products; the numbers of ``docs/spectral.md``.

    .venv/bin/python validation/spectral_sky_terms.py

1. The skylight envmap (``kernel.air_sky``): Mitsuba's ``envmap`` turns each pixel's linear sRGB into a smooth
   spectrum (its sRGB model times D65); DISORT's sky spectrum (13 wavelengths, log-linear between them, times
   ASTM G173's sun) has the same XYZ but another shape. They differ only after a filter by wavelength: the box's
   air (Rayleigh optical depth 0.1 or 0.5 at 550 nm), or a reddening reflector (lambda^2).
2. The eye rays' transmittance on the render's pixels (``display.aerial.SpectralChannels``): T(lambda) as a
   factor per sRGB channel (``skylight.transmittance_rgb``: exact for the top-of-atmosphere sun's light), against
   the exact XYZ of light x T(lambda), for sunlit cloud at a 4 and a 60 deg sun and the blue sky, T of the outside
   air (80 % molecules, 20 % aerosol at 550 nm) of optical depth 0.1-1; and the RGB mode's three wavelengths
   (650/550/450 nm) applied to linear sRGB, for comparison.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def _lab(xyz, white_y):
    import colour
    return colour.XYZ_to_Lab(np.asarray(xyz) / white_y, colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"])


def _de(a, b, white_y) -> float:
    import colour
    return float(colour.delta_E(_lab(a, white_y), _lab(b, white_y), method="CIE 2000"))


def _upsampled(rgb, wl):
    """Mitsuba's envmap's spectrum of a constant linear sRGB (llvm_ad_spectral) at ``wl``."""
    import drjit as dr
    import mitsuba as mi
    em = mi.load_dict({"type": "envmap", "bitmap": mi.Bitmap(np.zeros((4, 8, 3), np.float32) + np.float32(rgb))})
    si = dr.zeros(mi.SurfaceInteraction3f, wl.size)
    si.wi = mi.Vector3f(0, 0, 1)
    si.wavelengths = mi.Spectrum(*(mi.Float(wl.astype(np.float32)) for _ in range(4)))
    return np.array(em.eval(si))[0]


def envmap_upsampling() -> float:
    import mitsuba as mi
    from weather_mi.optics import spectrum
    from weather_mi.optics.air import Atmosphere
    from weather_mi.optics.air.skylight import SKY_WAVELENGTHS_NM as S, spectral_sky
    from weather_mi.optics.rayleigh import cross_section_m2
    mi.set_variant("llvm_ad_spectral")
    wl = spectrum.WAVELENGTHS_NM
    toa = spectrum.solar_toa_w_m2_nm(wl)
    r = cross_section_m2(wl * 1e-9) / cross_section_m2(550e-9)
    filters = {"box air tau 0.1": np.exp(-0.1 * r), "box air tau 0.5": np.exp(-0.5 * r), "lambda^2": (wl / 550) ** 2}
    worst = {k: 0.0 for k in filters}
    for sza in (26.0, 60.0, 86.0):
        rad, _, _ = spectral_sky(Atmosphere(), np.cos(np.radians(sza)), [0.0], [0.0, 45.0, 80.0], [0.0, 90.0, 180.0])
        for iz in range(3):
            for ip in range(3):
                v = np.log(rad[:, 0, iz, ip])
                true = np.exp(np.interp(wl, S, v)) * toa  # log-linear, held beyond 400-700 nm (skylight.rgb)
                up = _upsampled(spectrum.linear_srgb(spectrum.xyz(true)), wl)
                for k, f in filters.items():
                    a, b = spectrum.xyz(true * f), spectrum.xyz(up * f)
                    b = b * a[1] / b[1]
                    de = _de(a, b, spectrum.xyz(true)[1])
                    worst[k] = max(worst[k], de)
        print(f"envmap upsampling, sun zenith {sza:.0f} deg (9 sky directions): worst CIEDE2000 "
              + ", ".join(f"{k} {v:.2f}" for k, v in worst.items()), flush=True)
        worst = {k: 0.0 for k in filters}
    return 0.0


def transmittance_on_pixels() -> None:
    from weather_mi.optics import spectrum
    from weather_mi.optics.air import Atmosphere
    from weather_mi.optics.air.skylight import SKY_WAVELENGTHS_NM as S, spectral_sky, transmittance_rgb
    from weather_mi.optics.air.sunlight import transmittance
    wl = spectrum.WAVELENGTHS_NM
    toa = spectrum.solar_toa_w_m2_nm(wl)
    atm = Atmosphere()

    def t(w, tau):
        return np.exp(-tau * (0.8 * (w / 550.0) ** -4.05 + 0.2 * (w / 550.0) ** -1.3))
    mu4, mu60 = np.sin(np.radians(4.0)), np.sin(np.radians(60.0))
    lights = {"sun 4 deg at 8 km": toa * transmittance(atm, wl, 8000.0, mu4),
              "sun 4 deg at 2 km": toa * transmittance(atm, wl, 2000.0, mu4),
              "sun 60 deg at 5 km": toa * transmittance(atm, wl, 5000.0, mu60),
              "blue sky (zenith, sun at 60 deg)": toa * np.interp(wl, S, spectral_sky(atm, mu60, [0.0], [0.0], [0.0])[0][:, 0, 0, 0])}
    for name, s in lights.items():
        rgb = spectrum.linear_srgb(spectrum.xyz(s))
        row = []
        for tau in (0.1, 0.3, 1.0):
            exact = spectrum.xyz(s * t(wl, tau))
            ours = spectrum.xyz_of_linear_srgb(rgb * transmittance_rgb(t(S, tau)[:, None])[0])
            three = spectrum.xyz_of_linear_srgb(rgb * t(np.array([650.0, 550.0, 450.0]), tau))
            w = spectrum.xyz(s)[1]
            row.append(f"tau {tau}: {_de(exact, ours, w):.2f} (three wavelengths {_de(exact, three, w):.2f})")
        print(f"eye-ray transmittance on {name}: CIEDE2000 " + "; ".join(row), flush=True)


if __name__ == "__main__":
    envmap_upsampling()
    transmittance_on_pixels()
