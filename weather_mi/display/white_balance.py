"""White balance of a spectral render's picture: the EXR's R, G, B are linear sRGB, whose white is D65, so
shown as they are they are what a camera set to daylight records (a sunset-lit cloud stays orange);
adapted to the scene they are what the eye, adapted to the light there, sees: von Kries adaptation in
CAT02 cone space (CIE 159:2004, colour-science's ``chromatic_adaptation_VonKries``) from the scene's white
(the direct sun's CIE XYZ where the cloud is lit, ``optics.air.sun_xyz``) to D65.
"""
from __future__ import annotations

import numpy as np

WHITE_BALANCE = ("daylight", "scene")


def scene_white_xyz(spec, height_m: float) -> np.ndarray:
    """CIE XYZ of the direct sun that reaches ``height_m`` (m above sea level) in ``spec``: the sun after
    ``spec.atmosphere``, or above the air without one (``optics.spectral.sun_spectrum``)."""
    from ..optics import spectral, spectrum
    if spec.atmosphere is not None:
        from ..optics.air import sun_xyz
        return np.asarray(sun_xyz(spec.atmosphere, float(height_m), spec.sun.mu0), np.float64)
    return spectrum.xyz(spectral.sun_spectrum())


def adapted_to(rgb_linear, white_xyz) -> np.ndarray:
    """Linear sRGB (..., 3) adapted from the white ``white_xyz`` to D65 (CAT02 von Kries): that white then
    shows as sRGB white of its own luminance."""
    import colour
    from ..optics.spectrum import linear_srgb, xyz_of_linear_srgb
    white = np.asarray(white_xyz, np.float64)
    d65 = colour.xy_to_XYZ(colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]) * white[1]
    xyz = colour.adaptation.chromatic_adaptation_VonKries(xyz_of_linear_srgb(rgb_linear), white, d65,
                                                            transform="CAT02")
    return linear_srgb(xyz).astype(np.float32)


__all__ = ["WHITE_BALANCE", "scene_white_xyz", "adapted_to"]
