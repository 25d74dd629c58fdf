"""Where in a picture an approximation is off: pixels sorted into regions by what they show (sunlit cloud
faces, shaded faces, cloud bases, thin edges, ice anvils, the ground in and out of cloud shadow), and the
residual of an image against its reference per region.

A pixel's region comes from the medium along its eye ray, not from either image:
  * the eye ray's total optical depth through the medium, tau (``eye_surface``) and, where tau > 1,
    the surface point p1 where the optical depth from the camera reaches 1 (what the pixel shows);
  * the sunlight's direct transmission D at p1 (or at the ground point), read from the slicer's light
    volume of the frame (``SliceRenderer.light_at``);
  * the face's orientation at p1: a base when the extinction 2 grid levels above p1 exceeds that below;
  * the ice phase's share of the extinction at p1 (ice, snow and graupel).
  * the scattering angle Theta between the sunlight and the eye ray (cos Theta = to_sun . eye direction).
The regions, first match wins: where the eye looks towards the sun (Theta < BACKLIT_DEG: back-lit views),
"back-lit rim" (0.1 < tau <= 2, or tau > 2 with D >= 0.3: the thin and sunlit edges that forward
scattering makes silver linings) and "back-lit core" (tau > 2, D < 0.3: the dark cores); elsewhere
"thin edge" (0.1 < tau <= 2), "ice anvil" (tau > 2, ice share > 1/2),
"cloud base" (tau > 2, a base, D < 0.3), "sunlit face" (tau > 2, D >= 0.3), "shaded face" (tau > 2,
D < 0.3), "ground in shadow" / "ground in sun" (tau <= 0.1, the eye ray meets the ground, D < or >= 1/2).
"""
from __future__ import annotations

import numpy as np

from ..display import metrics
from ..io.image import auto_exposure

REGIONS = ("back-lit rim", "back-lit core", "thin edge", "ice anvil", "cloud base", "sunlit face", "shaded face", "ground in shadow", "ground in sun")
ICE_SPECIES = ("ice", "snow", "graupel")
BACKLIT_DEG = 60.0  # scattering angles below this: the pixel sees sunlight scattered forward (back-lit)


def eye_surface(r, spec, step_m: float | None = None):
    """(p1, tau): per pixel (H, W, 3) the world point where the optical depth along the eye ray reaches 1
    (NaN where it does not), and the ray's total optical depth through the slicing box (H, W); marched
    through ``r``'s extinction (its light source texture's first channel; a ``SliceRenderer`` after a frame) in
    steps of ``step_m`` (default a
    quarter of the grid's finest spacing), the crossing interpolated linearly within a step."""
    import drjit as dr
    mi = r.mi
    rays = r.views.get(mi, spec)
    glo = mi.Point3f(*(float(c) for c in r.grid_box[0]))
    inv = mi.Vector3f(*(1.0 / float(h - l) for l, h in zip(*r.grid_box)))
    dt = float(step_m) if step_m else 0.25 * float(min(r.vol.spacing))
    o, d = rays.origin, rays.direction

    def body(t, tau, t_hit):
        ext = dr.maximum(r.tex_light_src.eval((o + (t + 0.5 * dt) * d - glo) * inv)[0], 0.0)
        tau2 = tau + ext * dt
        crossing = (tau < 1.0) & (tau2 >= 1.0)
        t_hit = dr.select(crossing, t + dt * (1.0 - tau) / dr.maximum(tau2 - tau, 1e-30), t_hit)
        return t + dt, tau2, t_hit

    _, tau, t_hit = dr.while_loop((mi.Float(rays.t0), dr.zeros(mi.Float, rays.n), dr.full(mi.Float, -1.0, rays.n)),
                                  lambda t, tau, th: t < rays.t1, body)
    t_hit = np.asarray(t_hit, dtype=np.float64)
    p = np.asarray(o, dtype=np.float64).T + t_hit[:, None] * np.asarray(d, dtype=np.float64).T
    p[t_hit < 0] = np.nan
    shape = (spec.height, spec.width)
    return p.reshape(shape + (3,)), np.asarray(tau, dtype=np.float64).reshape(shape)


def _grid_values(vol, field: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Nearest-cell values of a (z, y, x) field at world points (N, 3); 0 outside the grid."""
    lo = np.asarray(vol.bbox[0], dtype=np.float64)
    dz, dy, dx = vol.spacing
    finite = np.all(np.isfinite(points), axis=1)
    idx = np.zeros(points.shape, dtype=np.int64)
    idx[finite] = np.floor((points[finite] - lo) / np.array([dx, dy, dz])).astype(np.int64)
    nz, ny, nx = field.shape
    ok = finite & (idx[:, 0] >= 0) & (idx[:, 0] < nx) & (idx[:, 1] >= 0) \
        & (idx[:, 1] < ny) & (idx[:, 2] >= 0) & (idx[:, 2] < nz)
    out = np.zeros(len(points))
    i = idx[ok]
    out[ok] = field[i[:, 2], i[:, 1], i[:, 0]]
    return out


def pixel_regions(r, spec) -> dict:
    """{region: (H, W) bool} for the view ``spec`` of ``r`` (a ``SliceRenderer`` whose last frame was
    ``spec``): see the module docstring. The masks do not overlap; pixels in none (the sky, tau in
    (0.1, ...) without a surface) are in no region."""
    vol = r.vol
    p1, tau = eye_surface(r, spec)
    H, W = tau.shape
    flat = p1.reshape(-1, 3)
    has = np.all(np.isfinite(flat), axis=1)
    D = np.ones(H * W)
    if has.any():
        D[has] = r.light_at(flat[has])[0]
    beta = np.asarray(vol.beta_total, dtype=np.float64)
    dz = float(vol.spacing[0])
    up = _grid_values(vol, beta, flat + np.array([0.0, 0.0, 2.0 * dz]))
    down = _grid_values(vol, beta, flat - np.array([0.0, 0.0, 2.0 * dz]))
    ice = sum((np.asarray(vol.beta_ext[i], dtype=np.float64) for i, n in enumerate(vol.species) if n in ICE_SPECIES),
              np.zeros_like(beta))
    ice_share = _grid_values(vol, ice, flat) / np.maximum(_grid_values(vol, beta, flat), 1e-30)
    rays = r.views.get(r.mi, spec)
    ground = np.asarray(rays.hit_ground, dtype=bool)
    D_ground = r.light_at(np.asarray(rays.ground, dtype=np.float64).T)[0]
    tau_f = tau.ravel()
    thick = (tau_f > 2.0) & has
    thin = (tau_f > 0.1) & (tau_f <= 2.0)
    cos_theta = np.asarray(rays.direction, dtype=np.float64).T @ np.asarray(spec.sun.to_sun, dtype=np.float64)
    forward = cos_theta > np.cos(np.radians(BACKLIT_DEG))
    rules = [("back-lit rim", forward & (thin | (thick & (D >= 0.3)))),
             ("back-lit core", forward & thick & (D < 0.3)),
             ("thin edge", thin),
             ("ice anvil", thick & (ice_share > 0.5)),
             ("cloud base", thick & (up > down) & (D < 0.3)),
             ("sunlit face", thick & (D >= 0.3)),
             ("shaded face", thick & (D < 0.3)),
             ("ground in shadow", (tau_f <= 0.1) & ground & (D_ground < 0.5)),
             ("ground in sun", (tau_f <= 0.1) & ground & (D_ground >= 0.5))]
    taken = np.zeros(H * W, dtype=bool)
    out = {}
    for name, m in rules:
        out[name] = (m & ~taken).reshape(H, W)
        taken |= m
    return out


def region_residuals(ref: np.ndarray, img: np.ndarray, regions: dict, exposure: float | None = None) -> list[dict]:
    """Per region: pixels, the mean signed luminance error relative to the reference's mean luminance
    there (bias; > 0: the approximation is brighter), the relative RMS luminance error, and the mean
    CIEDE2000 (display colours at ``exposure``, default the reference's ``auto_exposure``)."""
    e = auto_exposure(ref) if exposure is None else float(exposure)
    lab_r = metrics.display_lab(metrics.display_srgb(ref, e))
    lab_a = metrics.display_lab(metrics.display_srgb(img, e))
    de = metrics.ciede2000_map(lab_r, lab_a)
    w = np.array([0.2126, 0.7152, 0.0722])
    y_ref, y_img = ref @ w, img @ w
    rows = []
    for name, m in regions.items():
        n = int(np.count_nonzero(m))
        if n == 0:
            rows.append({"region": name, "pixels": 0, "bias": np.nan, "rel_rms": np.nan, "ciede2000": np.nan})
            continue
        mean = max(float(y_ref[m].mean()), 1e-30)
        diff = y_img[m] - y_ref[m]
        rows.append({"region": name, "pixels": n, "bias": float(diff.mean()) / mean,
                     "rel_rms": float(np.sqrt(np.mean(diff ** 2))) / mean, "ciede2000": float(de[m].mean())})
    return rows
