"""Images out of either renderer: radiance with its standard error, metadata and (a reference's) eye-ray
transmittance; EXR for data (OpenEXR: R, G, B, stderr.R/G/B, transmittance.Y, the denoised display layer denoised.R/G/B, a spectral render's CIE X, Y, Z and the metadata as JSON), PNG for eyes (sRGB transfer function from colour-science). Files are written under a unique temporary
name and renamed into place (``output_paths``)."""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .output_paths import image_format, write_error, written_atomically

TRANSMITTANCE_CHANNEL = "transmittance.Y"  # the EXR layer of Image.transmittance
DENOISED_LAYER = "denoised"  # the EXR layer (denoised.R/G/B) of Image.denoised


@dataclass
class Image:
    """A rendered image with its standard error, metadata and, for a reference, its eye-ray transmittance.

    Attributes
    ----------
    radiance : ndarray, (H, W, 3) float32
        Radiance per RGB channel in W/m^2/sr, row 0 at the top of the picture (or reflectance
        pi L / (mu0 E) when ``metadata['normalize']`` says so).
    stderr : ndarray, (H, W, 3) float32
        Standard error of ``radiance``, same units (NaN where unknown).
    metadata : dict
        What made the image (JSON-serialisable; the EXR header keeps it).
    transmittance : ndarray, (H, W) float32, or None
        Transmittance of the medium along each pixel's central eye ray (``render_reference``: exp of
        minus the optical depth of the full extinction), the fraction of the background seen through the
        cloud: its cloud pixels are those below 1/2. ``metrics.compare(..., mask="cloud")`` uses it.
        None where unknown (the slicer's images, a scalar variant's reference).
    denoised : ndarray, (H, W, 3) float32, or None
        The denoised display layer (``weather_mi.display.denoise``; biased): what the PNG shows when present,
        named in ``metadata["display"]``. Never the data: ``radiance`` and ``stderr`` are.
    xyz : ndarray, (H, W, 3) float32, or None
        A spectral render's CIE 1931 X, Y, Z (the same units as ``radiance``, which is then their linear
        sRGB, D65 white); None for RGB renders.
    """

    radiance: np.ndarray
    stderr: np.ndarray | None = None
    metadata: dict = field(default_factory=dict)
    transmittance: np.ndarray | None = None
    denoised: np.ndarray | None = None
    xyz: np.ndarray | None = None

    def __post_init__(self):
        self.radiance = np.ascontiguousarray(self.radiance, dtype=np.float32)
        if self.radiance.ndim != 3 or self.radiance.shape[2] != 3:
            raise ValueError(f"Image radiance must be (H, W, 3), got {self.radiance.shape}")
        if self.stderr is None:
            self.stderr = np.full_like(self.radiance, np.nan)
        self.stderr = np.ascontiguousarray(self.stderr, dtype=np.float32)
        if self.transmittance is not None:
            self.transmittance = np.ascontiguousarray(self.transmittance, dtype=np.float32)
            if self.transmittance.shape != self.radiance.shape[:2]:
                raise ValueError(f"Image transmittance must be (H, W) = {self.radiance.shape[:2]}, got "
                                 f"{self.transmittance.shape}")
        for name in ("denoised", "xyz"):
            layer = getattr(self, name)
            if layer is not None:
                setattr(self, name, np.ascontiguousarray(layer, dtype=np.float32))
                if layer.shape != self.radiance.shape:
                    raise ValueError(f"Image {name} must be (H, W, 3) = {self.radiance.shape}, got {layer.shape}")

    @property
    def shape(self) -> tuple[int, int]:
        return self.radiance.shape[:2]

    def relative_stderr(self, mask: np.ndarray | None = None) -> float:
        """Mean over pixels (optionally masked) of stderr / radiance, channel-averaged."""
        lum = self.radiance.mean(axis=2)
        err = self.stderr.mean(axis=2)
        ok = lum > 0 if mask is None else (mask & (lum > 0))
        return float(np.mean(err[ok] / lum[ok])) if np.any(ok) else float("nan")

    def save(self, path) -> Path:
        """Write the image in the format of the name's extension: ``.exr`` (R, G, B radiance, stderr.R/G/B,
        transmittance.Y when known, denoised.R/G/B when present, and the metadata as a JSON header attribute) or ``.png`` (as
        :meth:`save_png`); ValueError else, ``OutputWriteError`` naming the file when it cannot be written."""
        if image_format(path) == "png":
            return self.save_png(path)
        return write_exr(path, self.radiance, self.stderr, self.metadata, transmittance=self.transmittance,
                         denoised=self.denoised, xyz=self.xyz)

    @property
    def display(self) -> np.ndarray:
        """The radiance a person looks at: the denoised layer when present, else the radiance."""
        return self.radiance if self.denoised is None else self.denoised

    def save_png(self, path, exposure: float | None = None) -> Path:
        """Write a tone-mapped sRGB preview (a ``.png`` name) of :attr:`display` (the denoised layer when
        present, else the radiance) x exposure, clipped, sRGB-encoded. The default exposure maps the
        99.5th percentile of the radiance's luminance to 1."""
        if image_format(path) != "png":
            raise ValueError(f"{path}: save_png writes PNG data: expected a name ending in .png")
        return write_png(path, self.display, auto_exposure(self.radiance) if exposure is None else exposure)

    @classmethod
    def load(cls, path) -> "Image":
        """The image an EXR written by :meth:`save` holds (radiance, stderr, metadata, transmittance,
        denoised)."""
        radiance, stderr, metadata, transmittance = read_exr_layers(path)
        return cls(radiance, stderr, metadata, transmittance, read_layer(path, DENOISED_LAYER),
                   read_layer(path, "", "XYZ"))


def write_exr(path, radiance: np.ndarray, stderr: np.ndarray | None = None, metadata: dict | None = None,
              transmittance: np.ndarray | None = None, denoised: np.ndarray | None = None,
              xyz: np.ndarray | None = None) -> Path:
    """Write an EXR (ZIP-compressed float32 scanlines): R, G, B (radiance), stderr.R/G/B when given,
    transmittance.Y ((H, W)) when given, denoised.R/G/B (the display layer) when given, ``metadata`` as the JSON header attribute ``weather_mi``;
    ``OutputWriteError`` naming the file when it cannot be written (a full disk)."""
    import OpenEXR
    path = Path(path)
    channels = {c: np.ascontiguousarray(radiance[..., i], dtype=np.float32) for i, c in enumerate("RGB")}
    for layer, rgb in (("stderr", stderr), (DENOISED_LAYER, denoised)):
        if rgb is not None:
            for i, c in enumerate("RGB"):
                channels[f"{layer}.{c}"] = np.ascontiguousarray(rgb[..., i], dtype=np.float32)
    if xyz is not None:  # a spectral render's CIE XYZ: channels X, Y, Z
        channels.update({c: np.ascontiguousarray(xyz[..., i], dtype=np.float32) for i, c in enumerate("XYZ")})
    if transmittance is not None:
        channels[TRANSMITTANCE_CHANNEL] = np.ascontiguousarray(transmittance, dtype=np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "weather_mi": json.dumps(metadata or {}, default=_json_default)}
    with written_atomically(path, "EXR image") as tmp, OpenEXR.File(header, channels) as f:
        try:
            f.write(str(tmp))
        except RuntimeError as exc:  # OpenEXR's I/O errors ("... No space left on device.")
            raise write_error(path, "EXR image", exc, tmp) from exc
    return path


def read_exr(path):
    """(radiance, stderr or None, metadata) from an EXR written by :func:`write_exr` (or any RGB EXR)."""
    return read_exr_layers(path)[:3]


def read_exr_layers(path):
    """(radiance, stderr or None, metadata, transmittance or None) from an EXR written by :func:`write_exr`."""
    import OpenEXR
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = f.channels()
        meta = f.header().get("weather_mi")
        metadata = json.loads(meta) if isinstance(meta, str) else {}
        radiance = np.stack([np.asarray(ch[c].pixels, np.float32) for c in "RGB"], axis=-1)
        stderr = None
        if all(f"stderr.{c}" in ch for c in "RGB"):
            stderr = np.stack([np.asarray(ch[f"stderr.{c}"].pixels, np.float32) for c in "RGB"], axis=-1)
        transmittance = None
        if TRANSMITTANCE_CHANNEL in ch:
            transmittance = np.array(ch[TRANSMITTANCE_CHANNEL].pixels, np.float32)
    return radiance, stderr, metadata, transmittance


def read_layer(path, layer: str, names: str = "RGB"):
    """The (H, W, 3) float32 layer ``layer`` (channels LAYER.R/G/B, or of ``names``; "" the top level's) of an
    EXR, or None without it."""
    import OpenEXR
    prefix = f"{layer}." if layer else ""
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = f.channels()
        if not all(f"{prefix}{c}" in ch for c in names):
            return None
        return np.stack([np.asarray(ch[f"{prefix}{c}"].pixels, np.float32) for c in names], axis=-1)


def auto_exposure(radiance: np.ndarray, percentile: float = 99.5) -> float:
    lum = radiance.mean(axis=2)
    ref = float(np.percentile(lum[np.isfinite(lum)], percentile)) if lum.size else 1.0
    return 1.0 / ref if ref > 0 else 1.0


def to_srgb8(radiance: np.ndarray, exposure: float | None = None) -> np.ndarray:
    """Display colour shared by every image of the project: linear radiance x exposure, clipped to
    [0, 1], sRGB transfer function (IEC 61966-2-1, colour-science), 8 bits."""
    import colour
    exposure = auto_exposure(radiance) if exposure is None else float(exposure)
    linear = np.clip(np.nan_to_num(radiance * exposure), 0.0, 1.0)
    return np.round(colour.cctf_encoding(linear, function="sRGB") * 255).astype(np.uint8)


def write_png(path, radiance: np.ndarray, exposure: float | None = None) -> Path:
    """Write the sRGB preview (:func:`to_srgb8`) of ``radiance`` as an 8-bit RGB PNG; ``OutputWriteError``
    naming the file when it cannot be written (a full disk)."""
    return write_png8(path, to_srgb8(radiance, exposure))


def write_png8(path, frame: np.ndarray) -> Path:
    """Write 8-bit (H, W, 3) display values as an RGB PNG, as it is (no transfer function); an
    ``OutputWriteError`` naming the file when it cannot be written."""
    from PIL import Image as PILImage
    path = Path(path)
    with written_atomically(path, "PNG image") as tmp:
        PILImage.fromarray(np.ascontiguousarray(frame, np.uint8)).save(tmp, format="PNG")
    return path


def _json_default(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON-serialisable: {type(o).__name__}")
