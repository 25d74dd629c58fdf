"""Image metrics for an approximation (the half-angle slicer) against a ground truth (the path tracer).

Definitions (all in :func:`compare`):

- **Display colour**, shared by the display-referred metrics and identical to
  :func:`weather_mi.io.image.to_srgb8` except that it is not quantised to 8 bits: linear radiance x
  exposure, clipped to [0, 1], sRGB transfer function (IEC 61966-2-1, colour-science). The exposure
  is the reference's by default (:func:`weather_mi.io.image.auto_exposure`: 1 / 99.5th percentile of
  the reference's channel-mean luminance) and the SAME exposure is applied to both images.
- **CIELAB**: display sRGB -> CIE XYZ (sRGB primaries, D65, colour-science ``sRGB_to_XYZ``) ->
  CIE L*a*b* with the D65 white (``XYZ_to_Lab``), L* in [0, 100].
- ``rmse``: sqrt(mean over masked pixels and the 3 channels of (a - r)^2), linear radiance units.
- ``rel_mse``: relative MSE of the rendering literature (Rousselle, Knaus & Zwicker 2011):
  mean over masked pixels and channels of (a - r)^2 / (r^2 + eps), with eps = 1e-2 * mean(r)^2
  (mean of the reference over the masked pixels and channels), so that the metric does not depend on
  the radiance unit and dark pixels do not dominate. Linear radiance.
- ``ssim``: Wang, Bovik, Sheikh & Simoncelli (2004) SSIM on display lightness L*/100 (data range 1),
  Gaussian window sigma 1.5 (truncated at 3.5 sigma: 11 x 11), K1 = 0.01, K2 = 0.03, population
  (co)variances; implemented with scipy.ndimage (scikit-image is not a dependency), borders by
  reflection. The SSIM map is averaged over the masked pixels (all pixels, borders included).
- ``ciede2000``: mean over masked pixels of the CIEDE2000 colour difference between the CIELAB
  images (``colour.delta_E(..., method="CIE 2000")``).
- ``flip``: LDR-FLIP (Andersson et al. 2020, ``flip-evaluator``, default 67 pixels per degree) on the
  display sRGB images; the FLIP map is computed on the whole image and averaged over the mask.
- ``noise_floor``: sqrt(mean of stderr^2) of the reference over the mask: the RMSE that the
  reference's own Monte Carlo noise accounts for (NaN when the reference carries no standard error).

Masks: ``"all"``, ``"cloud"`` (pixels whose transmittance, the fraction of the background seen
through the cloud, is below ``threshold``: the one given, else the reference's, see :func:`compare`)
or a boolean (H, W) array.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..io.image import Image, auto_exposure

__all__ = ["compare", "noise_floor", "cloud_mask", "display_srgb", "display_lab", "ssim_map",
           "ciede2000_map", "flip_map"]

SSIM_SIGMA = 1.5
SSIM_K1, SSIM_K2 = 0.01, 0.03
REL_MSE_EPS = 1e-2


LAYERS = ("radiance", "denoised")  # the layers of an approximation compare can measure, by name


def _radiance(x, what: str, layer: str = "radiance") -> np.ndarray:
    if layer not in LAYERS:
        raise ValueError(f"layer {layer!r}: expected one of {', '.join(LAYERS)}")
    if layer == "denoised":
        if not isinstance(x, Image) or x.denoised is None:
            raise ValueError(f"layer='denoised': {what} must be an Image with a denoised layer (weather_mi.display.denoise)")
        rad = x.denoised
    else:  # the unbiased radiance, never the denoised display layer
        rad = x.radiance if isinstance(x, Image) else np.asarray(x)
    rad = np.asarray(rad, dtype=np.float64)
    if rad.ndim != 3 or rad.shape[2] != 3:
        raise ValueError(f"{what} must be an Image or an (H, W, 3) radiance array, got shape {rad.shape}")
    bad = rad.size - int(np.count_nonzero(np.isfinite(rad)))
    if bad:
        raise ValueError(f"{what} has {bad} NaN or infinite radiance values")
    return rad


def display_srgb(radiance: np.ndarray, exposure: float) -> np.ndarray:
    """The project's display colour, unquantised: sRGB-encoded clip(radiance x exposure, 0, 1), float64."""
    import colour
    linear = np.clip(np.nan_to_num(np.asarray(radiance, dtype=np.float64) * float(exposure)), 0.0, 1.0)
    return np.asarray(colour.cctf_encoding(linear, function="sRGB"), dtype=np.float64)


def display_lab(srgb: np.ndarray) -> np.ndarray:
    """CIE L*a*b* (D65 white, L* in [0, 100]) of display sRGB values in [0, 1]."""
    import colour
    d65 = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    xyz = colour.sRGB_to_XYZ(srgb, illuminant=d65, apply_cctf_decoding=True)
    return np.asarray(colour.XYZ_to_Lab(xyz, illuminant=d65), dtype=np.float64)


def ssim_map(x: np.ndarray, y: np.ndarray, data_range: float = 1.0, sigma: float = SSIM_SIGMA,
             k1: float = SSIM_K1, k2: float = SSIM_K2) -> np.ndarray:
    """Per-pixel SSIM (Wang et al. 2004) of two grey images (H, W): Gaussian window, reflected borders."""
    from scipy.ndimage import gaussian_filter
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)

    def blur(a):
        return gaussian_filter(a, sigma, mode="reflect", truncate=3.5)

    mx, my = blur(x), blur(y)
    sxx = blur(x * x) - mx * mx
    syy = blur(y * y) - my * my
    sxy = blur(x * y) - mx * my
    c1, c2 = (k1 * data_range) ** 2, (k2 * data_range) ** 2
    return ((2 * mx * my + c1) * (2 * sxy + c2)) / ((mx * mx + my * my + c1) * (sxx + syy + c2))


def ciede2000_map(lab_ref: np.ndarray, lab_approx: np.ndarray) -> np.ndarray:
    """Per-pixel CIEDE2000 difference (H, W) of two CIELAB images (colour-science)."""
    import colour
    return np.asarray(colour.delta_E(lab_ref, lab_approx, method="CIE 2000"), dtype=np.float64)


def flip_map(srgb_ref: np.ndarray, srgb_approx: np.ndarray) -> np.ndarray:
    """Per-pixel LDR-FLIP error (H, W), in [0, 1], of two display sRGB images in [0, 1]."""
    try:
        import flip_evaluator
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError("the FLIP metric needs the 'flip-evaluator' package (pip install flip-evaluator==1.7)") from exc
    err, _, _ = flip_evaluator.evaluate(np.ascontiguousarray(srgb_ref, dtype=np.float32),
                                        np.ascontiguousarray(srgb_approx, dtype=np.float32), "LDR",
                                        inputsRGB=True, applyMagma=False, computeMeanError=False)
    return np.asarray(err, dtype=np.float64).reshape(srgb_ref.shape[:2])


def cloud_mask(transmittance: np.ndarray, threshold: float = 0.99) -> np.ndarray:
    """Cloud pixels: transmittance (fraction of background seen through the cloud) below threshold."""
    t = np.asarray(transmittance, dtype=np.float64)
    return t < float(threshold)


def _own_transmittance(ref):
    """The transmittance a reference Image carries: ``metadata["transmittance"]`` where one was put there,
    else its own eye-ray transmittance (``Image.transmittance``: ``render_reference`` keeps it, an EXR
    round trip too); ValueError without either."""
    meta = ref.metadata if isinstance(ref, Image) else {}
    if meta.get("transmittance") is not None:
        return meta["transmittance"]
    own = getattr(ref, "transmittance", None)
    if own is None:
        raise ValueError("mask='cloud' needs the per-pixel transmittance: pass transmittance= (an (H, W) "
                         "array, e.g. SliceRenderer.transmittance), or give a reference Image that carries it "
                         "(render_reference's images do, except on scalar variants: Image.transmittance, or "
                         "metadata['transmittance'])")
    return own


def _resolve_mask(mask, shape, ref, transmittance, threshold) -> np.ndarray:
    if isinstance(mask, str):
        if mask == "all":
            return np.ones(shape, bool)
        if mask != "cloud":
            raise ValueError(f"mask must be 'all', 'cloud' or a boolean (H, W) array, got {mask!r}")
        if transmittance is None:
            transmittance = _own_transmittance(ref)
        t = np.asarray(transmittance, dtype=np.float64)
        if t.shape != tuple(shape):
            raise ValueError(f"transmittance must have the image shape {tuple(shape)}, got {t.shape}")
        m = cloud_mask(t, threshold)
    else:
        m = np.asarray(mask)
        if m.shape != tuple(shape):
            raise ValueError(f"mask must have the image shape {tuple(shape)}, got {m.shape}")
        m = m.astype(bool)
    if not m.any():
        raise ValueError("the mask selects no pixels")
    return m


def noise_floor(ref, *, mask="all", transmittance=None, threshold: float = 0.99) -> float:
    """RMSE attributable to the reference's own Monte Carlo noise: sqrt(mean(stderr^2)) over the mask
    (pixels and channels). NaN when the reference has no (finite) standard error."""
    if not isinstance(ref, Image):
        raise ValueError("noise_floor needs a weather_mi.io.image.Image with a stderr")
    m = _resolve_mask(mask, ref.shape, ref, transmittance, threshold)
    se = np.asarray(ref.stderr, dtype=np.float64)[m]
    if not np.all(np.isfinite(se)):
        return float("nan")
    return float(np.sqrt(np.mean(se ** 2)))


def compare(ref, approx, *, exposure: float | None = None, mask="all", transmittance=None,
            threshold: float = 0.99, error_map=None, layer: str = "radiance") -> dict:
    """Metrics of ``approx`` against ``ref``.

    Parameters
    ----------
    ref, approx : Image or ndarray
        Each an Image or an (H, W, 3) radiance array (W/m^2/sr, or any one unit for both).
    exposure : float, optional
        Display exposure (1 / radiance unit) for SSIM, CIEDE2000 and FLIP, applied to both images;
        default ``auto_exposure(ref)``.
    mask : {"all", "cloud"} or ndarray of bool
        The pixels measured: all, the cloud pixels (transmittance < ``threshold``) or an (H, W) mask.
    transmittance : ndarray, optional
        (H, W) transmittance (fraction of the background seen through the cloud) for mask="cloud";
        default ``ref.metadata["transmittance"]``, else the reference's own eye-ray transmittance
        (``ref.transmittance``, which images of ``render_reference`` and their EXR files carry; their
        noise figures count the pixels below 1/2 as cloud: ``threshold=0.5`` gives those pixels).
    threshold : float
        Transmittance below which a pixel is a cloud pixel (mask="cloud").
    error_map : path, optional
        Write a PNG with both display images and the CIEDE2000 and FLIP maps.
    layer : {"radiance", "denoised"}
        The layer of ``approx`` measured: its (unbiased) radiance, the default, or, only when asked for by
        this name, its denoised display layer (``Image.denoised``). The reference's radiance is always used.

    Returns
    -------
    dict
        Floats rmse (radiance unit), rel_mse, ssim, ciede2000, flip, noise_floor (radiance unit),
        exposure, and ``n_pixels`` (int, pixels in the mask). See the module docstring for the
        definitions.
    """
    r = _radiance(ref, "ref")
    a = _radiance(approx, "approx", layer)
    if r.shape != a.shape:
        raise ValueError(f"images differ in shape: ref {r.shape}, approx {a.shape}")
    m = _resolve_mask(mask, r.shape[:2], ref, transmittance, threshold)
    exposure = auto_exposure(r) if exposure is None else float(exposure)
    if not (np.isfinite(exposure) and exposure > 0):
        raise ValueError(f"exposure must be a positive number, got {exposure}")

    diff2 = (a - r)[m] ** 2
    rm = r[m]
    eps = max(REL_MSE_EPS * float(np.mean(rm)) ** 2, np.finfo(np.float64).tiny)
    srgb_r, srgb_a = display_srgb(r, exposure), display_srgb(a, exposure)
    lab_r, lab_a = display_lab(srgb_r), display_lab(srgb_a)
    ssim = ssim_map(lab_r[..., 0] / 100.0, lab_a[..., 0] / 100.0)
    de = ciede2000_map(lab_r, lab_a)
    flip = flip_map(srgb_r, srgb_a)
    out = {
        "rmse": float(np.sqrt(np.mean(diff2))),
        "rel_mse": float(np.mean(diff2 / (rm ** 2 + eps))),
        "ssim": float(np.mean(ssim[m])),
        "ciede2000": float(np.mean(de[m])),
        "flip": float(np.mean(flip[m])),
        "noise_floor": noise_floor(ref, mask=m) if isinstance(ref, Image) else float("nan"),
        "exposure": float(exposure),
        "n_pixels": int(np.count_nonzero(m)),
    }
    if error_map is not None:
        _write_error_map(error_map, srgb_r, srgb_a, de, flip, m, out)
    return out


def _write_error_map(path, srgb_r, srgb_a, de, flip, m, metrics) -> Path:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    h, w = de.shape
    fig = Figure(figsize=(4 * 3.2, 3.2 * h / w + 0.9), constrained_layout=True)
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 4)
    axes[0].imshow(srgb_r, interpolation="nearest")
    axes[0].set_title("reference")
    axes[1].imshow(srgb_a, interpolation="nearest")
    axes[1].set_title("approximation")
    de_max = max(float(np.percentile(de, 99.5)), 1.0)
    im = axes[2].imshow(de, cmap="viridis", vmin=0.0, vmax=de_max, interpolation="nearest")
    fig.colorbar(im, ax=axes[2], fraction=0.046, label="CIEDE2000")
    axes[2].set_title(f"CIEDE2000 (mean {metrics['ciede2000']:.2f})")
    im = axes[3].imshow(flip, cmap="magma", vmin=0.0, vmax=1.0, interpolation="nearest")
    fig.colorbar(im, ax=axes[3], fraction=0.046, label="FLIP")
    axes[3].set_title(f"LDR-FLIP (mean {metrics['flip']:.3f})")
    if not m.all():
        for ax in axes[2:]:
            ax.contour(m.astype(float), levels=[0.5], colors="white", linewidths=0.6)
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(f"RMSE {metrics['rmse']:.4g}  relMSE {metrics['rel_mse']:.4g}  SSIM {metrics['ssim']:.4f}  "
                 f"({metrics['n_pixels']} px)", fontsize=9)
    fig.savefig(path, dpi=100)
    return path


def agreement_in_noise(a, b, region=np.s_[:, :], block: int = 4) -> dict:
    """How two path-traced images (``Image``s with ``stderr``, independent samples) differ in units of their
    combined standard error, over pixels ``region``: ``mean_z``, the difference of the region's means over
    its standard error (within +-3 where they agree), and ``block_chi2``, the mean over blocks of block x
    block pixels of (difference of the block sums / its standard error)^2 (~1 where they agree; blocks,
    because a pixel's standard error from a few passes is itself noisy, and its t^2 has a heavy tail).
    Channels are averaged first (they are not independent)."""
    d = (np.asarray(a.radiance, np.float64) - np.asarray(b.radiance, np.float64))[region].mean(axis=2)
    v = (np.asarray(a.stderr, np.float64) ** 2 + np.asarray(b.stderr, np.float64) ** 2)[region].mean(axis=2)
    h, w = (n // block * block for n in d.shape)
    ds = d[:h, :w].reshape(h // block, block, w // block, block).sum(axis=(1, 3))
    vs = v[:h, :w].reshape(h // block, block, w // block, block).sum(axis=(1, 3))
    return {"mean_z": float(d.sum() / np.sqrt(v.sum())), "block_chi2": float(np.mean(ds ** 2 / vs))}
