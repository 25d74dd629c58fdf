"""The wavelengths of a spectral path (issue 38, chroma38): drawn for colour, not for luminance alone.

Mitsuba's sensors draw a path's 4 wavelengths from ``sample_rgb_spectrum`` (density 1 / cosh^2(0.0072 (lambda -
538 nm)), stratified: one uniform shifted by 1/4 per lane). That density follows the CIE Y curve and is low where
zbar peaks (445 nm), so a path's CIE Z is noisy: for a solar spectrum the relative spread of one path's X, Y, Z is
0.11, 0.04, 0.49 (its linear sRGB B 0.57), and the spectral mode's chroma noise is mostly this, the luminance
noise of the paths being the same in both modes. Drawing them from the mixture

    p(lambda) = 0.5 p_M(lambda) + 0.3 xbar / int xbar + 0.1 ybar / int ybar + 0.1 zbar / int zbar

(p_M Mitsuba's density; CIE 1931 functions) takes the per-path chromaticity spread (u', v') of a solar, a reddened
and a blue spectrum from 0.039 / 0.022 / 0.066 to 0.010-0.016 (numpy, 2 x 10^4 stratified paths; docs/spectral.md),
at a per-path luminance spread of 0.12 instead of 0.04 (against the paths' own ~1.3 in a storm: +1 % variance).
Same stratification (the sensor's uniform shifted by 1/4 per lane, inverted through this density's CDF; the
density piecewise constant on 1 nm bins, each its mean), the weight 1 / p(lambda): unbiased. Used by the persistent lanes (:mod:`.lanes`, the LLVM renders); ``mi.render``
(CUDA) keeps Mitsuba's."""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

LAMBDA_NM = (360.0, 830.0)    # Mitsuba's CIE range (MI_CIE_MIN, MI_CIE_MAX)
MIX = (0.5, 0.3, 0.1, 0.1)    # Mitsuba's density, xbar, ybar, zbar (each normalised)
GRID_NM = 1.0                 # the sampled density's bins (piecewise constant on them)

_CACHE: dict = {}


def mitsuba_pdf(lam_nm) -> np.ndarray:
    """Mitsuba's ``pdf_rgb_spectrum`` (1/nm over 360-830 nm), written out: 0.003939804229 / cosh^2(0.0072
    (lambda - 538))."""
    return 0.003939804229326285 / np.cosh(0.0072 * (np.asarray(lam_nm, np.float64) - 538.0)) ** 2


def colour_pdf(lam_nm) -> np.ndarray:
    """The density :data:`MIX` (1/nm over 360-830 nm) at ``lam_nm``."""
    from ...optics.spectrum import cmfs_1931
    grid = np.arange(LAMBDA_NM[0], LAMBDA_NM[1] + 0.5 * GRID_NM, GRID_NM)
    cmf = cmfs_1931(grid)  # colour-science's 1 nm table
    m = mitsuba_pdf(grid)
    parts = [m / np.trapezoid(m, grid)] + [cmf[:, k] / np.trapezoid(cmf[:, k], grid) for k in range(3)]
    pdf = sum(w * p for w, p in zip(MIX, parts))
    return np.interp(np.asarray(lam_nm, np.float64), grid, pdf / np.trapezoid(pdf, grid))


def _distribution():
    """(pdf of each 1 nm bin (1/nm), cumulative at the bins' upper edges) of :func:`colour_pdf` made piecewise
    constant on the bins (their mean), as Dr.Jit arrays, per variant."""
    key = mi.variant()
    if key not in _CACHE:
        edges = np.arange(LAMBDA_NM[0], LAMBDA_NM[1] + 0.5 * GRID_NM, GRID_NM)
        fine = np.linspace(LAMBDA_NM[0], LAMBDA_NM[1], 16 * (edges.size - 1) + 1)
        f = colour_pdf(fine)
        bins = 0.5 * (f[:-1] + f[1:]).reshape(edges.size - 1, 16).mean(axis=1)  # trapezoid mean of each bin
        bins /= bins.sum() * GRID_NM
        cdf = np.cumsum(bins) * GRID_NM
        cdf[-1] = 1.0
        _CACHE[key] = (mi.Float(bins), mi.Float(cdf), int(bins.size))
    return _CACHE[key]


def sample_colour(u, active=True):
    """(wavelength nm, pdf 1/nm) for uniforms ``u`` (Float): the bin whose cumulative first exceeds u (binary
    search), the wavelength uniform within it (the density piecewise constant on 1 nm bins)."""
    bins, cdf, n = _distribution()
    i = dr.binary_search(0, n - 1, lambda k: dr.gather(mi.Float, cdf, k, active) <= u)
    lo = dr.select(i > 0, dr.gather(mi.Float, cdf, dr.maximum(i, 1) - 1, active), 0.0)
    p = dr.gather(mi.Float, bins, i, active)
    x = dr.clip((u - lo) / dr.maximum(p * GRID_NM, 1e-30), 0.0, 1.0)
    return LAMBDA_NM[0] + (mi.Float(i) + x) * GRID_NM, p


def pixel_uniform(key, pixel):
    """A uniform number in [0, 1) per (pass key (UInt64), pixel (UInt32)): murmur3's 32-bit finaliser of their
    bits, independent of the samples' own PCG32 streams."""
    h = mi.UInt32(key) ^ (mi.UInt32(key >> 32) * 0x9E3779B9) ^ (pixel * 0x85EBCA6B)
    h ^= h >> 16
    h *= 0x85EBCA6B
    h ^= h >> 13
    h *= 0xC2B2AE35
    h ^= h >> 16
    return mi.Float(h >> 8) * (1.0 / (1 << 24))


def stratified(key, pixel, k, inv_spp):
    """The wavelength uniform of sample ``k`` (UInt32) of ``pixel`` in a pass of 1 / ``inv_spp`` samples a pixel
    (pass key ``key``): frac(r + k / (4 spp)) with r = :func:`pixel_uniform` (a randomly shifted rank-1 lattice).
    Each sample's uniform is uniform (r is); with the 4 lanes shifted by 1/4 (``redrawn``) the pass's 4 spp
    wavelengths of a pixel are r + (k + l spp) / (4 spp), evenly spaced in the density's cumulative, one in each of
    4 spp strata: the wavelength sampling's share of a pixel's colour noise falls faster than 1 / sqrt(spp).
    Passes stay independent (r is drawn per pass)."""
    u = pixel_uniform(key, pixel) + mi.Float(k) * (0.25 * inv_spp)
    return u - dr.floor(u)


def mitsuba_weight(lam_nm):
    """1 / p_M of wavelengths ``lam_nm`` (a Spectrum, nm) as Mitsuba's ``sample_rgb_spectrum`` returns it with
    them, in closed form (Mitsuba 3.9.1, include/mitsuba/core/spectrum.h): 253.82 cosh^2(0.0072 (lambda - 538)),
    the same float32 operations on the same wavelengths."""
    c = dr.cosh(0.0072 * (lam_nm - 538.0))
    return 253.82 * c * c


def redrawn(ray, weight, sample, active):
    """``ray`` and its sensor weight with the 4 wavelengths the sensor drew from ``sample`` (its wavelength
    sample, Mitsuba's density) replaced by the 4 drawn from :func:`colour_pdf` with the same stratified
    uniforms: weight x p_M(old) / p(new), p_M(old) from the sensor's wavelengths (:func:`mitsuba_weight`)."""
    shifted = [sample + 0.25 * i for i in range(4)]
    shifted = [dr.select(s >= 1.0, s - 1.0, s) for s in shifted]  # Mitsuba's sample_shifted
    w_m = mitsuba_weight(ray.wavelengths)  # 1 / p_M of the sensor's wavelengths
    lam, pdf = [], []
    for s in shifted:
        x, p = sample_colour(s, active)
        lam.append(x)
        pdf.append(p)
    ray.wavelengths = mi.Spectrum(*lam)
    ratio = mi.Spectrum(*(dr.select(p > 0.0, dr.rcp(p), 0.0) for p in pdf)) * dr.rcp(w_m)
    return ray, weight * ratio
