"""The storm's shadow outside its box: the transmittance of the hydrometeors (``OpticalVolume.beta_total``, the
gridvolume's trilinear interpolant) along the sun ray from a point outside the box, for the single scattering
of the air along the eye rays (``eye_path.segment_air``).

A point outside the box is shadowed by the whole chord of the box along its sun ray where the box lies towards
the sun from it (the slab method), by nothing otherwise. The chords' optical depths are a shadow map over the
plane normal to the sun: lines at the volume's finest spacing ``h`` across the box's projection, integrated by
the midpoint rule at steps of h / 2 (``scipy.ndimage.map_coordinates``, order 1: the trilinear interpolant with
the gridvolume's clamped borders); a point reads its line bilinearly. Direct light only: the light the storm
scatters forward into its shadow is not added (single scattering of the air).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MAX_LINES = 512  # shadow-map lines per axis at most (the spacing grows beyond)


def _frame(to_sun):
    """(s, u, v): the unit sun direction and two unit vectors normal to it."""
    s = np.asarray(to_sun, np.float64) / np.linalg.norm(to_sun)
    a = np.array([0.0, 0.0, 1.0]) if abs(s[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = np.cross(a, s)
    u /= np.linalg.norm(u)
    return s, u, np.cross(s, u)


@dataclass(frozen=True)
class StormShadow:
    """The shadow map: optical depth ``tau`` (n_u, n_v) of the box's chord along the sun through the points
    ``u0 + i h`` e_u + ``v0 + j h`` e_v of the plane normal to the sun ``s`` (world frame, m)."""

    s: np.ndarray
    u: np.ndarray
    v: np.ndarray
    u0: float
    v0: float
    h: float
    tau: np.ndarray
    bbox: tuple

    def transmittance(self, points) -> np.ndarray:
        """exp(-tau) of the chord ahead towards the sun of each point (..., 3) outside the box (1 where the
        sun ray misses the box or leaves it behind the point)."""
        from scipy.ndimage import map_coordinates
        p = np.asarray(points, np.float64)
        flat = p.reshape(-1, 3)
        lo, hi = (np.asarray(c, np.float64) for c in self.bbox)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / np.where(np.abs(self.s) < 1e-12, 1e-12, self.s)
            t0, t1 = (lo - flat) * inv, (hi - flat) * inv
        t_in = np.max(np.minimum(t0, t1), axis=-1)
        t_out = np.min(np.maximum(t0, t1), axis=-1)
        ahead = (t_out > np.maximum(t_in, 0.0))
        out = np.ones(flat.shape[0])
        if ahead.any():
            q = flat[ahead]
            coords = np.stack([(q @ self.u - self.u0) / self.h, (q @ self.v - self.v0) / self.h])
            out[ahead] = np.exp(-map_coordinates(self.tau, coords, order=1, mode="constant", cval=0.0))
        return out.reshape(p.shape[:-1])


def storm_shadow(beta_total, bbox, to_sun, spacing_m: float | None = None) -> StormShadow:
    """The :class:`StormShadow` of the extinction ``beta_total`` (z, y, x), 1/m, on the box ``bbox`` (m) for the
    sun towards ``to_sun``; lines ``spacing_m`` apart (default the finest voxel spacing, at most MAX_LINES per
    axis)."""
    from scipy.ndimage import map_coordinates
    beta = np.asarray(beta_total, np.float32)
    lo, hi = (np.asarray(c, np.float64) for c in bbox)
    shape = np.array(beta.shape[::-1], np.float64)  # x, y, z
    cell = (hi - lo) / shape
    s, u, v = _frame(to_sun)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    pu, pv, ps = corners @ u, corners @ v, corners @ s
    h = float(spacing_m) if spacing_m is not None else float(cell.min())
    h = max(h, float(max(np.ptp(pu), np.ptp(pv))) / MAX_LINES)
    n_u, n_v = int(np.ceil(np.ptp(pu) / h)) + 2, int(np.ceil(np.ptp(pv) / h)) + 2
    u0, v0 = float(pu.min() - h / 2), float(pv.min() - h / 2)
    step = h / 2
    n_s = int(np.ceil(np.ptp(ps) / step))
    ss = ps.min() + (np.arange(n_s) + 0.5) * (np.ptp(ps) / n_s)
    tau = np.zeros((n_u, n_v))
    uu = u0 + np.arange(n_u) * h
    for j in range(n_v):  # a column of lines at a time
        vv = v0 + j * h
        p = (uu[:, None, None] * u + vv * v + ss[None, :, None] * s)  # (n_u, n_s, 3)
        idx = (p - lo) / cell - 0.5                                      # texel-centre coordinates, x y z
        inside = np.all((p >= lo) & (p <= hi), axis=-1)
        vals = map_coordinates(beta, [idx[..., 2].ravel(), idx[..., 1].ravel(), idx[..., 0].ravel()],
                               order=1, mode="nearest").reshape(inside.shape)
        tau[:, j] = (vals * inside).sum(axis=1) * (np.ptp(ps) / n_s)
    return StormShadow(s=s, u=u, v=v, u0=u0, v0=v0, h=h, tau=tau, bbox=(tuple(lo), tuple(hi)))


__all__ = ["StormShadow", "storm_shadow"]
