"""The denoised display layer's bias against a reference (``weather_mi.display.denoise``): per view, raw and
denoised images at a few spp (independent seeds) against a reference of the same view, over the
reference's cloud pixels (its eye-ray transmittance below 1/2):

ciede2000   mean CIEDE2000 (display colour at the reference's exposure; the reference's own noise
            adds to it: it is not removed)
rel_bias    (mean image - mean reference) / mean reference (channel means)
rel_rms     sqrt(mean (X - R)^2 - mean se_R^2) / mean R: the RMS error against the truth, the
            reference's own noise removed by E[(X - R)^2] = MSE(X) + var(R) (X independent of R)
spp_equiv   (denoised rows) the spp the raw image would need for the same CIEDE2000, extrapolated on a
            power law fitted to the raw CIEDE2000 against spp (marked extrapolated beyond the largest)
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..display import metrics

KEYS = ["scene", "lighting", "spp", "image", "ciede2000", "rel_bias", "rel_rms", "spp_equiv"]


def error_figures(ref, x: np.ndarray, mask: np.ndarray) -> dict:
    """CIEDE2000, relative mean bias and the noise-corrected relative RMS error of radiance ``x``
    (H, W, 3) against the reference Image ``ref`` over ``mask`` (see the module docstring)."""
    r = np.asarray(ref.radiance, np.float64)[mask]
    xm = np.asarray(x, np.float64)[mask]
    var_r = np.nan_to_num(np.asarray(ref.stderr, np.float64)[mask] ** 2)
    mean_r = float(r.mean())
    mse = float(np.mean((xm - r) ** 2) - np.mean(var_r))  # Eq.: E[(X-R)^2] = MSE(X) + var(R)
    de = metrics.compare(ref, np.asarray(x), mask=mask)["ciede2000"]
    return {"ciede2000": de, "rel_bias": float(xm.mean() - mean_r) / mean_r,
            "rel_rms": float(np.sqrt(max(mse, 0.0))) / mean_r}


def spp_for_ciede(raw: list[tuple[int, float]], target: float) -> tuple[float, bool]:
    """(spp, extrapolated) at which the raw images' CIEDE2000 reaches ``target``: a least-squares power
    law log dE = a + b log spp through the raw (spp, CIEDE2000) points; extrapolated when beyond them."""
    spp = np.log([s for s, _ in raw])
    de = np.log([d for _, d in raw])
    if len(raw) < 2 or not np.all(np.isfinite(de)):
        return float("nan"), True
    b, a = np.polyfit(spp, de, 1)
    if b >= 0:
        return float("inf"), True
    s = float(np.exp((np.log(target) - a) / b))
    return s, not (np.exp(spp.min()) <= s <= np.exp(spp.max()))


def bias_rows(scene: str, lighting: str, spec, vol, ref, spp_list, aux=None, raw_spp=None,
              integrator: str = "majorant", seed: int = 1, slicer_frame=None) -> list[dict]:
    """Rows (``KEYS`` and ``aux``) of raw and denoised images of ``spec``'s view at each of ``spp_list``
    (raw also at ``raw_spp``, for the CIEDE2000 curve) against ``ref``, denoised with each of ``aux``
    (default: ``weather_mi.display.denoise.DEFAULT_AUX``); images with seeds from ``seed``
    on, independent of the reference's. Returns (rows, {spp: (raw Image, {aux: denoised radiance})})."""
    from ..display.denoise import auxiliaries, denoise_radiance
    from ..display.denoise import DEFAULT_AUX
    from ..reference.render import render_reference
    aux = (DEFAULT_AUX,) if aux is None else tuple(aux)
    mask = np.asarray(ref.transmittance) < 0.5
    if not mask.any():
        return [], {}
    feats = {a: auxiliaries(a, spec, vol, ref.radiance, slicer_frame) for a in aux}
    rows, images, raw_curve = [], {}, []
    for k, spp in enumerate(sorted(set(spp_list) | set(raw_spp or ()))):
        img = render_reference(replace(spec, seed=seed + 1000 * k), vol, spp=spp, integrator=integrator,
                               progress=False)
        raw = error_figures(ref, img.radiance, mask)
        raw_curve.append((spp, raw["ciede2000"]))
        rows.append({"scene": scene, "lighting": lighting, "spp": spp, "image": "raw", **raw})
        if spp not in spp_list:
            continue
        images[spp] = (img, {})
        for a, (alb, nrm) in feats.items():
            d = denoise_radiance(img.radiance, alb, nrm)
            images[spp][1][a] = d
            rows.append({"scene": scene, "lighting": lighting, "spp": spp, "image": f"denoised ({a})",
                         **error_figures(ref, d, mask)})
    for row in rows:
        if row["image"] != "raw":
            s, extra = spp_for_ciede(raw_curve, row["ciede2000"])
            row["spp_equiv"] = f"{s:.0f}{' (extrapolated)' if extra else ''}"
    return rows, images
