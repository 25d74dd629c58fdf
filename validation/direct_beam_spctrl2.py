"""The direct beam of our clear atmosphere against Bird & Riordan's SPCTRL2 (pvlib), issue 38's first target: band
transmittance at 450 / 550 / 650 nm (within 3 % for SZA <= 80) and the direct beam's chromaticity (CIEDE2000 at
equal lightness within 2 at every angle), at sea level and 3 km, SZA 0 / 60 / 80 / 86, with the same water (1.4 cm
at sea level, 2 km scale height), ozone (0.3 atm-cm) and aerosol (turbidity 0.1 at 500 nm, alpha 1.14, the column
above the point). ``tests/test_air.py`` asserts the targets with these functions; this prints the table.

    .venv/bin/python validation/direct_beam_spctrl2.py
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from weather_mi.optics.air import Atmosphere  # noqa: E402


def spectrl2_direct(sza, pressure_pa, water_cm):
    """(wavelengths nm, direct normal irradiance, its extraterrestrial value) of SPCTRL2 (pvlib) at solar zenith
    ``sza`` deg, surface pressure ``pressure_pa``, ``water_cm`` of water, 0.3 atm-cm ozone, turbidity 0.1 at 500
    nm, Kasten-Young air mass."""
    import pvlib
    am = float(pvlib.atmosphere.get_relative_airmass(sza, "kastenyoung1989"))
    out = pvlib.spectrum.spectrl2(apparent_zenith=np.array([sza]), aoi=np.array([sza]), surface_tilt=0.0,
                                  ground_albedo=0.2, surface_pressure=pressure_pa, relative_airmass=np.array([am]),
                                  precipitable_water=water_cm, ozone=0.3, aerosol_turbidity_500nm=0.1, dayofyear=1)
    return out["wavelength"], out["dni"][:, 0], out["dni_extra"][:, 0]


def matched_atmosphere(h_m, water_cm=1.4):
    """Our atmosphere with SPCTRL2's aerosol (turbidity 0.1 at 500 nm, alpha 1.14, the whole column above
    the point, as SPCTRL2 has no height), ozone and water (``water_cm`` above the point; 2 km scale height)."""
    from weather_mi.optics.air.atmosphere import REFERENCE_NM
    from weather_mi.optics.air.water_vapour import SCALE_HEIGHT_M
    aod = 0.1 * (REFERENCE_NM / 500.0) ** -1.14 * np.exp(h_m / 1200.0)
    return Atmosphere(aod_550=aod, ozone_atm_cm=0.3, angstrom=1.14, aerosol_scale_height_m=1200.0,
                      water_vapour_cm=water_cm * np.exp(h_m / SCALE_HEIGHT_M))


def main() -> int:
    from weather_mi.display.cloud_colour import delta_e_equal_lightness
    from weather_mi.io.standard_atmosphere import standard_temperature_pressure
    from weather_mi.optics import spectrum
    from weather_mi.optics.air import sun_xyz, transmittance
    from validation.sun_colour import spectrl2_direct_xy
    print("| height | SZA | ours T 450/550/650 | SPCTRL2 T 450/550/650 | worst rel. diff | direct beam CIEDE2000 |")
    print("|---|---|---|---|---|---|")
    for h in (0.0, 3000.0):
        p = float(standard_temperature_pressure(h)[1])
        atm, water = matched_atmosphere(h), 1.4 * np.exp(-h / 2000.0)
        for sza in (0.0, 60.0, 80.0, 86.0):
            lam, dni, etr = spectrl2_direct(sza, p, water)
            ref = np.interp([450.0, 550.0, 650.0], lam, dni / etr)
            ours = transmittance(atm, [450.0, 550.0, 650.0], h, np.cos(np.radians(sza)))
            de = delta_e_equal_lightness(spectrum.chromaticity_xy(sun_xyz(atm, h, np.cos(np.radians(sza)))),
                                         spectrl2_direct_xy(90.0 - sza, p / 100.0, water_cm=water))
            print(f"| {h / 1000:g} km | {sza:g} | {' / '.join(f'{v:.3f}' for v in ours)} | "
                  f"{' / '.join(f'{v:.3f}' for v in ref)} | {100 * np.max(np.abs(ours / ref - 1)):.1f} % | {de:.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
