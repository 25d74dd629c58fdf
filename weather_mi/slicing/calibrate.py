"""Fitting the slicer's light-model parameters to path-traced references by gradient descent (Adam)
with Dr.Jit reverse-mode AD through whole frames.

The loss compares display colours, as the accuracy metrics do: over each view's cloud pixels, the mean
squared difference of sqrt(min(L x exposure, 1)) (exposure: the reference's ``auto_exposure``), which
bounds the weight of the reference's Monte Carlo outliers; views are averaged. Parameters are optimised
in unconstrained coordinates (logit for those in [0, 1], log for gains).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .modes import MODES, SliceMode, SliceParams
from .renderer import SliceRenderer

# the "multiple" light model's parameters and their range: "unit" in (0, 1), "positive" > 0
MULTIPLE_PARAMS = {"ms_extinction": "unit", "ms_contribution": "unit", "ms_eccentricity": "unit",
                   "sky_gain": "positive", "sky_extinction": "positive", "diffusion_gain": "positive",
                   "diffusion_scale": "unit", "leak_gain": "positive", "leak_rate": "positive", "diffusion_flux": "unit",
                   "below_shadow": "unit", "diffusion_lobe": "unit", "diffusion_incidence": "unit"}
# where a fit starts from: close to single scattering with a faint, lightly shadowed sky and a faint
# diffusion term whose transport optical depth is (1 - g) tau for g = 0.85, scattered with half its flux and
# 0.3 of it in its forward lobe, the light from below half dimmed by the shadow beneath
FIT_START = SliceParams(ms_extinction=0.5, ms_contribution=0.05, ms_eccentricity=0.5, sky_gain=0.05,
                        sky_extinction=0.5, diffusion_gain=0.5, diffusion_scale=0.15, leak_gain=0.2, leak_rate=1.0,
                        diffusion_flux=0.5, below_shadow=0.5, diffusion_lobe=0.3, diffusion_incidence=0.5)


@dataclass
class TrainingView:
    """One view to fit: the volume, the scene spec, the reference radiance (H, W, 3) and the cloud mask."""

    vol: object
    spec: object
    reference: np.ndarray
    mask: np.ndarray


def _to_free(v: float, kind: str) -> float:
    if kind == "unit":
        v = min(max(v, 1e-4), 1 - 1e-4)
        return math.log(v / (1 - v))
    return math.log(max(v, 1e-6))


def _plain(t: float, kind: str) -> float:
    """The parameter of a free coordinate (the inverse of ``_to_free``)."""
    return 1 / (1 + math.exp(-t)) if kind == "unit" else math.exp(t)


def _from_free(dr, x, kind: str):
    return dr.rcp(1 + dr.exp(-x)) if kind == "unit" else dr.exp(x)


def calibrate(views: list[TrainingView], mode: SliceMode = MODES["per-species/multiple"],
              start: SliceParams = FIT_START, names: dict = MULTIPLE_PARAMS, iterations: int = 40,
              learning_rate: float = 0.1, slices: int = 64, light_res: int = 64, progress: bool = False,
              supersample: int = 1, on_step=None):
    """Fit the parameters ``names`` (name -> "unit" | "positive") of ``mode`` to the views, their frames
    with ``supersample`` x ``supersample`` points per pixel (``SliceRenderer.frame``). ``on_step(iteration,
    loss, {name: value})``, if given, receives each iteration's loss with the parameters it was measured at
    (before that iteration's step: a long fit can be stopped and its best iterate kept). Returns (fitted
    SliceParams, loss per iteration)."""
    import drjit as dr
    import mitsuba as mi
    from tqdm.auto import tqdm
    renderers = {}
    for v in views:
        if id(v.vol) not in renderers:
            renderers[id(v.vol)] = SliceRenderer(v.vol, mode, slices=slices, light_res=light_res, differentiable=True)
    targets = []
    for v in views:
        from ..io.image import auto_exposure
        e = auto_exposure(v.reference)
        w = v.mask.reshape(-1).astype(np.float32)
        ref = np.sqrt(np.minimum(v.reference.reshape(-1, 3) * e, 1.0)).astype(np.float32)
        targets.append((mi.Color3f(*(mi.Float(ref[:, c]) for c in range(3))), mi.Float(w),
                        dr.opaque(mi.Float, e), dr.opaque(mi.Float, 1.0 / max(3.0 * float(w.sum()), 1.0))))
    theta = np.array([_to_free(float(getattr(start, n)), k) for n, k in names.items()])
    m1, m2 = np.zeros_like(theta), np.zeros_like(theta)
    history = []
    for it in tqdm(range(iterations), desc="calibration", disable=not progress):
        total, grads = 0.0, np.zeros_like(theta)
        for v, (tgt, w, e, norm) in zip(views, targets):
            x = [dr.opaque(mi.Float, float(t)) for t in theta]  # opaque: a literal would recompile every step
            for xi in x:
                dr.enable_grad(xi)
            params = start.updated(**{n: _from_free(dr, xi, k) for xi, (n, k) in zip(x, names.items())})
            out, _ = renderers[id(v.vol)].frame(v.spec, params, return_arrays=True, supersample=supersample)
            disp = dr.sqrt(dr.minimum(dr.maximum(out * e, 0.0), 1.0) + 1e-6)
            diff = disp - tgt
            loss = dr.sum(w * (diff[0] * diff[0] + diff[1] * diff[1] + diff[2] * diff[2])) * norm
            dr.backward(loss)
            total += float(loss[0])
            grads += np.array([float(dr.grad(xi)[0]) for xi in x])
        history.append(total / len(views))
        if on_step is not None:
            on_step(it, history[-1], {n: _plain(float(t), k) for t, (n, k) in zip(theta, names.items())})
        g = grads / len(views)
        m1 = 0.9 * m1 + 0.1 * g
        m2 = 0.999 * m2 + 0.001 * g * g
        theta -= learning_rate * (m1 / (1 - 0.9 ** (it + 1))) / (np.sqrt(m2 / (1 - 0.999 ** (it + 1))) + 1e-8)
        theta = np.clip(theta, -8.0, 3.0)
    fitted = start.updated(**{n: _plain(float(t), k) for t, (n, k) in zip(theta, names.items())})
    return fitted, history
