"""The command line's ``--spectral`` and ``--white-balance daylight|scene`` (``render``): the spectral ground truth
(``docs/spectral.md``) and its PNG's white balance (:mod:`weather_mi.display.white_balance`)."""
from __future__ import annotations


def add_spectral_options(p) -> None:
    p.add_argument("--spectral", action="store_true",
                   help="the spectral ground truth (Mitsuba's llvm_ad_spectral, cuda_ad_spectral on a GPU): 4 "
                        "wavelengths a path, the EXR's R, G, B linear sRGB (D65) of its CIE X, Y, Z (also saved)")
    p.add_argument("--white-balance", default="daylight", choices=("daylight", "scene"),
                   help="with --spectral: the PNG as a camera set to daylight (D65, default) or adapted to the "
                        "direct sun where the cloud is lit (CAT02)")


def check_spectral_options(args) -> None:
    """Before the input is read: --white-balance scene needs --spectral, and --spectral a spectral variant in
    this Mitsuba build (``kernel.variant.spectral_variant`` names what is missing)."""
    if getattr(args, "white_balance", "daylight") != "daylight" and not getattr(args, "spectral", False):
        raise ValueError("--white-balance scene needs --spectral (an RGB render has no spectrum to adapt)")
    variant_of(args)


def variant_of(args):
    """The Mitsuba variant of ``render``: the spectral one with --spectral, else None (the one selected)."""
    if not getattr(args, "spectral", False):
        return None
    from ..kernel.variant import spectral_variant
    return spectral_variant()


def save_png(img, png_path, args, spec, vol):
    """The PNG: as the EXR's R, G, B show (daylight white balance), or adapted to the scene's sun (--white-balance
    scene: the direct sun at the middle of the volume's height)."""
    if getattr(args, "white_balance", "daylight") == "daylight":
        return img.save_png(png_path, exposure=args.exposure)
    from ..display.white_balance import adapted_to, scene_white_xyz
    from ..io.image import write_png
    white = scene_white_xyz(spec, 0.5 * (vol.bbox[0][2] + vol.bbox[1][2]))
    return write_png(png_path, adapted_to(img.display, white), args.exposure)
