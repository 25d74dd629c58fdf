"""The colour of a rendered cloud where the sun lights it, as a photographer would pick it: the mean
linear sRGB of the brightest ``top_fraction`` of the opaque cloud pixels (eye-ray transmittance below
``opaque``), as CIE XYZ and chromaticity, and colour differences at equal lightness (CIEDE2000 of two
chromaticities, both at luminance Y = 1 with the D65 white), the measure of issue 38.
"""
from __future__ import annotations

import numpy as np


def lit_cloud_pixels(radiance: np.ndarray, transmittance: np.ndarray, top_fraction: float = 0.1,
                     opaque: float = 0.05) -> np.ndarray:
    """(H, W) mask of the brightest ``top_fraction`` (by luminance Y) of the pixels of ``radiance`` (H, W, 3)
    whose eye-ray ``transmittance`` (H, W) is below ``opaque``. A ValueError when fewer than 4 pixels are
    opaque."""
    import colour
    rgb = np.asarray(radiance, np.float64)[..., :3]
    mask = np.asarray(transmittance) < opaque
    if mask.sum() < 4:
        raise ValueError(f"the image has {int(mask.sum())} opaque cloud pixels (eye-ray transmittance < {opaque}): "
                         "too few for a lit-cloud colour")
    y = colour.sRGB_to_XYZ(rgb, apply_cctf_decoding=False)[..., 1]
    return mask & (y >= np.quantile(y[mask], 1.0 - top_fraction))


def lit_cloud_rgb(radiance: np.ndarray, transmittance: np.ndarray, top_fraction: float = 0.1,
                  opaque: float = 0.05) -> np.ndarray:
    """Mean linear sRGB (3,) of the :func:`lit_cloud_pixels`."""
    return np.asarray(radiance, np.float64)[..., :3][lit_cloud_pixels(radiance, transmittance, top_fraction,
                                                                      opaque)].mean(axis=0)


def visible_height_m(spec, vol, mask: np.ndarray, tau: float = 1.0, step_m: float = 50.0) -> np.ndarray:
    """Height (m) at which each eye ray of the pixels in ``mask`` (H, W) reaches optical depth ``tau`` in
    ``vol``'s extinction (nearest voxel, steps of ``step_m``): where the light those pixels show comes
    from, about. NaN for a ray that does not reach it."""
    return visible_points_m(spec, vol, mask, tau, step_m)[:, 2]


def visible_points_m(spec, vol, mask: np.ndarray, tau: float = 1.0, step_m: float = 50.0) -> np.ndarray:
    """The points (N, 3), m, scene coordinates, where the eye rays of the pixels in ``mask`` (H, W; row-major
    order) reach optical depth ``tau`` (as :func:`visible_height_m`); NaN rows where a ray does not."""
    from ..slicing.geometry import film_rays
    if np.shape(mask) != (spec.height, spec.width):
        raise ValueError(f"the mask is {np.shape(mask)}, the scene's image (height, width) {(spec.height, spec.width)}")
    iy, ix = np.nonzero(mask)
    origins, dirs = film_rays(spec, ix + 0.5, iy + 0.5)
    lo, hi = (np.asarray(b, np.float64) for b in vol.bbox)
    beta = np.asarray(vol.beta_total, np.float32)
    n = np.array(beta.shape[::-1])  # x, y, z
    out = np.full((iy.size, 3), np.nan)
    for k in range(iy.size):
        o, d = origins[k], dirs[k]
        with np.errstate(divide="ignore", invalid="ignore"):
            ta, tb = (lo - o) / d, (hi - o) / d
        t0, t1 = max(np.nanmax(np.minimum(ta, tb)), 0.0), np.nanmin(np.maximum(ta, tb))
        if not t1 > t0:
            continue
        t = np.arange(t0, t1, step_m) + step_m / 2
        p = o + t[:, None] * d
        i = np.clip(((p - lo) / (hi - lo) * n).astype(int), 0, n - 1)
        depth = np.cumsum(beta[i[:, 2], i[:, 1], i[:, 0]]) * step_m
        j = np.searchsorted(depth, tau)
        if j < t.size:
            out[k] = p[j]
    return out


def xy_of_linear_srgb(rgb) -> np.ndarray:
    """CIE 1931 chromaticity of linear sRGB (..., 3) (D65 white, no adaptation)."""
    import colour
    return colour.XYZ_to_xy(colour.sRGB_to_XYZ(np.asarray(rgb, np.float64), apply_cctf_decoding=False,
                                               chromatic_adaptation_transform=None))


def delta_e_equal_lightness(xy_a, xy_b) -> float:
    """CIEDE2000 between two chromaticities at equal lightness (both at Y = 1, CIELAB with the D65 white)."""
    import colour
    lab = [colour.XYZ_to_Lab(colour.xyY_to_XYZ([float(x), float(y), 1.0])) for x, y in (xy_a, xy_b)]
    return float(colour.delta_E(lab[0], lab[1], method="CIE 2000"))


def delta_e_at_white(xyz_a, xyz_b, white_y: float) -> float:
    """CIEDE2000 between two CIE XYZ colours in CIELAB whose white (the D65 white point) has luminance ``white_y``."""
    import colour
    d65 = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    lab = [colour.XYZ_to_Lab(np.asarray(v, np.float64) / white_y, d65) for v in (xyz_a, xyz_b)]
    return float(colour.delta_E(lab[0], lab[1], method="CIE 2000"))


__all__ = ["lit_cloud_pixels", "lit_cloud_rgb", "visible_height_m", "visible_points_m", "xy_of_linear_srgb",
           "delta_e_equal_lightness", "delta_e_at_white"]
