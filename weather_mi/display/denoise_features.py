"""Noise-free auxiliary images of a view for the denoiser (``weather_mi.display.denoise``), from one
deterministic ray march per pixel through the volume (no path tracing; a fraction of a second):

albedo   an eye-ray "first-scattering albedo" (RGB, [0, 1]): the integral over the eye ray of
         T(t) beta(t) omega(t) dt, the fraction of light scattered once towards the camera per unit
         incident radiance, plus T_eye x the background's albedo (the ground's albedo where the ray
         meets the ground, the sky's radiance x the image's display exposure, clipped to 1, elsewhere)
normal   a depth-weighted normal-like feature: minus the normalised gradient of the extinction at the
         point where the eye ray's optical depth reaches 1 (the visible "surface" of the cloud), in
         camera space (x right, y up, z towards the camera); -view direction where it never does
transmittance  exp(-tau_eye) (H, W)

The march is the midpoint rule of ``weather_mi.reference.estimates.eye_optical_depth`` over the volume's box.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kernel.scene_dict import recentred, sensor_dict
from ..optics.volume import OpticalVolume
from ..scene.spec import SceneSpec

SURFACE_TAU = 1.0  # the optical depth at which the normal-like feature is taken


@dataclass
class Features:
    """Auxiliary images of one view: ``albedo`` (H, W, 3) in [0, 1], ``normal`` (H, W, 3) unit vectors
    in camera space, ``transmittance`` (H, W) of the eye ray."""
    albedo: np.ndarray
    normal: np.ndarray
    transmittance: np.ndarray


def camera_frame(spec: SceneSpec) -> np.ndarray:
    """(3, 3) rows: the camera's right, up and backward unit vectors in world coordinates."""
    cam = spec.camera
    fwd = np.asarray(cam.target, np.float64) - np.asarray(cam.origin, np.float64)
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, np.asarray(cam.up, np.float64))
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    return np.stack([right, up, -fwd])


def view_features(spec: SceneSpec, vol: OpticalVolume, exposure: float, steps: int = 256) -> Features:
    """The auxiliary images (``Features``) of ``spec``'s view of ``vol``; ``exposure`` (1 / radiance
    unit): the display exposure that maps the sky's radiance to the background's albedo."""
    import mitsuba as mi
    from ..reference.passes import current_or_default_variant
    from ..kernel.variant import set_variant
    set_variant(current_or_default_variant())
    spec_k, vol_k, _ = recentred(spec, vol)
    sensor = mi.load_dict(sensor_dict(spec_k))
    march = _march(sensor, vol_k, spec_k, steps)
    h, w = spec.height, spec.width
    trans = np.exp(-march["tau"]).reshape(h, w)
    albedo = march["albedo"].reshape(h, w, 3) + trans[..., None] * _background_albedo(
        spec_k, march["o"], march["d"], exposure).reshape(h, w, 3)
    grad = march["grad"]
    norm = np.linalg.norm(grad, axis=1)
    hit = march["hit"] & (norm > 0)
    n_world = np.where(hit[:, None], -grad / np.maximum(norm, 1e-30)[:, None], -march["d"])
    normal = (n_world @ camera_frame(spec_k).T).reshape(h, w, 3)
    return Features(np.clip(albedo, 0.0, 1.0).astype(np.float32), normal.astype(np.float32),
                    trans.astype(np.float32))


def _background_albedo(spec: SceneSpec, o: np.ndarray, d: np.ndarray, exposure: float) -> np.ndarray:
    from ..kernel.sky import sky_radiance
    from ..scene.spec import ground_hits
    t = ground_hits(spec, o, d)
    out = np.clip(sky_radiance(spec, d) * exposure, 0.0, 1.0)
    if spec.ground is not None:
        out[np.isfinite(t)] = spec.ground.albedo
    return out


def _march(sensor, vol_k: OpticalVolume, spec: SceneSpec, steps: int) -> dict:
    """Per pixel (flattened): optical depth, the single-scattering albedo integral (N, 3), whether and
    where tau reached SURFACE_TAU and the world gradient (1/m^2) of the extinction there, the ray."""
    import drjit as dr
    import mitsuba as mi
    from ..reference.estimates import eye_rays_in_box
    h, w = spec.height, spec.width
    o, d, t0, seg, ray, ext = eye_rays_in_box(sensor, spec, vol_k.bbox)
    beta = np.ascontiguousarray(vol_k.beta_total, np.float32)
    packed = np.concatenate([beta[..., None], beta[..., None] * np.asarray(vol_k.albedo, np.float32)], axis=-1)
    tex = mi.Texture3f(mi.TensorXf(np.ascontiguousarray(packed)), wrap_mode=dr.WrapMode.Clamp)
    n_steps = dr.opaque(mi.UInt32, steps)
    dt = seg / mi.Float(n_steps)

    def body(i, tau, a, hit, u):
        t = t0 + dt * (mi.Float(i) + 0.5)
        p = [o[k] + d[k] * t for k in range(3)]
        v = tex.eval(mi.Point3f(*p))
        dtau = v[0] * dt
        frac = dr.select(v[0] > 0, (1.0 - dr.exp(-dtau)) * dr.exp(-tau) / dr.maximum(v[0], 1e-30), 0.0)
        a = mi.Color3f(a[0] + frac * v[1], a[1] + frac * v[2], a[2] + frac * v[3])  # Eq. 5's omega beta
        cross = ~hit & (tau + dtau >= SURFACE_TAU)
        u = dr.select(cross, mi.Point3f(*p), u)
        return i + 1, tau + dtau, a, hit | cross, u

    state = (mi.UInt32(0), dr.zeros(mi.Float, h * w), dr.zeros(mi.Color3f, h * w), dr.zeros(mi.Bool, h * w),
             dr.zeros(mi.Point3f, h * w))
    _, tau, a, hit, u = dr.while_loop(state=state, cond=lambda i, *s: i < n_steps, body=body,
                                      label="denoiser features")
    shape = np.asarray(beta.shape[::-1], np.float64)  # texture coordinates (x, y, z) <- array (z, y, x)
    grad = []
    for k in range(3):
        e = [0.0, 0.0, 0.0]
        e[k] = 1.0 / float(shape[k])
        up = tex.eval(mi.Point3f(*(u[j] + e[j] for j in range(3))))[0]
        dn = tex.eval(mi.Point3f(*(u[j] - e[j] for j in range(3))))[0]
        grad.append(np.asarray((up - dn) / (2.0 * e[k] * float(ext[k])), np.float64))
    return {"tau": np.asarray(tau, np.float64), "albedo": np.asarray(a, np.float64).T.reshape(-1, 3),
            "hit": np.asarray(hit, bool), "grad": np.stack(grad, axis=1),
            "o": np.asarray(ray.o, np.float64).T.reshape(-1, 3), "d": np.asarray(ray.d, np.float64).T.reshape(-1, 3)}
