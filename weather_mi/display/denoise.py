"""The denoised display layer: Intel Open Image Denoise (OIDN 2.5, through ``pyoidn``, CPU) applied to a
reference's radiance, for the picture a person looks at. It is biased (a neural filter): the unbiased
radiance and its standard error stay the image's data and every metric's numbers
(``metrics.compare`` uses ``Image.denoised`` only when asked by name); the denoised image is an extra
layer (``Image.denoised``, EXR ``denoised.R/G/B``) and the PNG, named in ``metadata["display"]``.

Auxiliary images (``AUX``), measured in ``validation/denoiser_bias.py``:

none           the radiance alone
albedo         the eye-ray first-scattering albedo (``denoise_features``), noise-free
albedo+normal  and the normal-like feature at the eye ray's optical depth 1 (camera space)
slicer         the half-angle slicer's frame of the same view (noise-free but biased) as the albedo

Measured on four 64 x 48 views of the study's storms at 64/128/256 spp: the radiance alone ("none") gives
the lowest CIEDE2000; the noise-free albedo and the slicer's frame do not help, and the normal-like
feature hurts (OIDN keeps the voxel-scale structure it outlines, and the noise with it).
"""
from __future__ import annotations

import numpy as np

from ..io.image import Image, auto_exposure

AUX = ("none", "albedo", "albedo+normal", "slicer")
DEFAULT_AUX = "none"  # measured (validation/denoiser_bias.py): lowest CIEDE2000 on 11 of 12 views x spp


def oidn_version() -> str:
    """The version of the OIDN library that ``pyoidn`` bundles, e.g. "2.5.1"."""
    from pyoidn.version import oidn_version as v
    return str(v)


def check_available() -> None:
    """ImportError with what to do when ``pyoidn`` (the denoiser) is not installed."""
    try:
        import pyoidn  # noqa: F401
    except ImportError as exc:
        raise ImportError("the denoised PNG needs pyoidn (pip install -c constraints.txt pyoidn), or pass "
                          "--no-denoise for the raw PNG") from exc


def denoise_radiance(radiance: np.ndarray, albedo: np.ndarray | None = None, normal: np.ndarray | None = None,
                     quality: str = "high") -> np.ndarray:
    """OIDN's HDR "RT" filter on (H, W, 3) radiance (any unit: it is scaled by the display exposure
    before and back after), with optional noise-free auxiliary images (albedo in [0, 1], normal in
    [-1, 1], both (H, W, 3)); float32 (H, W, 3) in the radiance's unit."""
    import pyoidn
    rad = np.asarray(radiance, np.float32)
    if rad.ndim != 3 or rad.shape[2] != 3:
        raise ValueError(f"radiance must be (H, W, 3), got {rad.shape}")
    if not np.all(np.isfinite(rad)):
        raise ValueError("radiance has NaN or infinite values: the denoiser needs finite radiance")
    exposure = auto_exposure(rad)
    color = np.ascontiguousarray(np.maximum(rad, 0.0) * np.float32(exposure))
    aux = {k: None if v is None else np.ascontiguousarray(np.asarray(v, np.float32))
           for k, v in (("albedo", albedo), ("normal", normal))}
    if aux["normal"] is not None and aux["albedo"] is None:
        raise ValueError("OIDN takes a normal image only together with an albedo image")
    for k, v in aux.items():
        if v is not None and v.shape != rad.shape:
            raise ValueError(f"{k} must have the radiance's shape {rad.shape}, got {v.shape}")
    out = pyoidn.denoise(color, albedo=aux["albedo"], normal=aux["normal"], hdr=True,
                         clean_aux=aux["albedo"] is not None, quality=quality)
    return np.asarray(out, np.float32) / np.float32(exposure)


def auxiliaries(aux: str, spec=None, vol=None, radiance: np.ndarray | None = None, slicer_frame=None):
    """(albedo, normal) images of the auxiliary choice ``aux`` (one of ``AUX``) for ``spec``'s view of
    ``vol``; ``slicer_frame``: the slicer's radiance of the view (aux "slicer"; rendered when None)."""
    if aux not in AUX:
        raise ValueError(f"denoiser auxiliaries {aux!r}: expected one of {', '.join(AUX)}")
    if aux == "none":
        return None, None
    if spec is None or vol is None:
        raise ValueError(f"denoiser auxiliaries {aux!r} need the scene and the volume (spec=, vol=)")
    exposure = auto_exposure(radiance) if radiance is not None else 1.0
    if aux == "slicer":
        if slicer_frame is None:
            from ..slicing import MODES, SliceRenderer
            slicer_frame = SliceRenderer(vol, MODES["per-species/multiple"], slices=96).frame(spec).radiance
        return np.clip(np.asarray(slicer_frame) * exposure, 0.0, 1.0), None
    from .denoise_features import view_features
    f = view_features(spec, vol, exposure)
    return f.albedo, (f.normal if aux == "albedo+normal" else None)


def denoise_image(img: Image, spec=None, vol=None, aux: str = DEFAULT_AUX, quality: str = "high",
                  slicer_frame=None) -> Image:
    """``img`` with its denoised display layer (``img.denoised``) and ``metadata["display"]`` naming it
    (in place; returned). The radiance and standard error are untouched. ``aux``: the auxiliary images
    (``AUX``; all but "none" need ``spec`` and ``vol``)."""
    albedo, normal = auxiliaries(aux, spec, vol, img.radiance, slicer_frame)
    img.denoised = denoise_radiance(img.radiance, albedo, normal, quality=quality)
    img.metadata["display"] = display_label(aux, quality)
    return img


def display_label(aux: str, quality: str = "high") -> str:
    """What a denoised PNG shows, for the metadata and the command line's message."""
    return f"denoised (OIDN {oidn_version()}, {quality} quality, auxiliaries: {aux})"
