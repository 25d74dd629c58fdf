"""``PhaseTable``: a tabulated, per-RGB-channel phase function p(theta) in 1/sr, and its angle grid.

Representation: p is piecewise linear in the scattering angle theta (radians) between the nodes
``theta`` (ascending, 0 to pi). Every integral below is taken of exactly that interpolant (Gauss-
Legendre quadrature of (linear in theta) x sin(theta) x smooth, exact to rounding), so the
normalisation, the mean cosine, the CDF, the cone fractions, the Legendre moments and the sampler
all describe one and the same function:

    integral over 4 pi of p dOmega = 2 pi * integral_0^pi p(theta) sin(theta) dtheta = 1
"""
from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

RGB_WAVELENGTHS_M = (650e-9, 550e-9, 450e-9)  # R, G, B channel wavelengths (m)
_GL_X, _GL_W = np.polynomial.legendre.leggauss(6)  # 6-point Gauss-Legendre on [-1, 1]
_GL_T, _GL_W = 0.5 * (_GL_X + 1.0), 0.5 * _GL_W  # ... mapped to t in [0, 1]


def angle_grid(n_forward: int = 240, forward_min_deg: float = 1e-3, forward_max_deg: float = 5.0,
               middle_step_deg: float = 0.2, back_start_deg: float = 120.0,
               back_step_deg: float = 0.1, extra_deg: Sequence[float] = ()) -> np.ndarray:
    """Default scattering-angle nodes in radians, ascending from 0 to pi.

    0, then ``n_forward`` geometrically spaced angles from ``forward_min_deg`` to ``forward_max_deg``
    (forward diffraction peaks: ~3.6 % steps by default, fine enough for the 0.02 deg Airy lobe of a
    1 mm drop), ``middle_step_deg`` steps up to ``back_start_deg`` (halos at 22 and 46 deg), and
    ``back_step_deg`` (<= 0.1 deg) steps to 180 deg (rainbows, glory). Never uniform in cos(theta),
    which would starve the forward peak and the bows of nodes. ``extra_deg`` adds nodes.
    """
    if not (0 < forward_min_deg < forward_max_deg < back_start_deg < 180):
        raise ValueError("angle_grid needs 0 < forward_min_deg < forward_max_deg < back_start_deg < 180")
    deg = np.concatenate([
        [0.0],
        np.geomspace(forward_min_deg, forward_max_deg, n_forward),
        np.arange(forward_max_deg, back_start_deg, middle_step_deg),
        np.arange(back_start_deg, 180.0, back_step_deg),
        [180.0],
        np.asarray(extra_deg, np.float64),
    ])
    deg = np.unique(np.round(deg, 10))
    deg = deg[(deg >= 0) & (deg <= 180)]
    theta = np.radians(deg)
    theta[-1] = np.pi
    return theta


def _as_channels(values, n: int) -> np.ndarray:
    v = np.asarray(values, np.float64)
    if v.ndim == 1:
        v = v[:, None]
    if v.ndim != 2 or v.shape[0] != n or v.shape[1] not in (1, 3):
        raise ValueError(f"phase values must have shape ({n},), ({n}, 1) or ({n}, 3), got {np.shape(values)}")
    return np.repeat(v, 3, axis=1) if v.shape[1] == 1 else v.copy()


def _check_theta(theta) -> np.ndarray:
    th = np.asarray(theta, np.float64).ravel().copy()
    if th.size < 2 or not np.all(np.isfinite(th)) or np.any(np.diff(th) <= 0):
        raise ValueError("theta must be a strictly ascending 1-D array of angles in radians")
    if abs(th[0]) > 1e-9 or abs(th[-1] - np.pi) > 1e-9:
        raise ValueError(f"theta must run from 0 to pi radians, got {th[0]!r} .. {th[-1]!r}")
    th[0], th[-1] = 0.0, np.pi
    return th


_MAX_STEP = 0.05  # rad: longer segments are split for quadrature (6-point GL is then exact to ~1e-16)


def _quadrature(theta: np.ndarray, max_step: float = _MAX_STEP):
    """Gauss-Legendre nodes over every segment (split so no piece exceeds ``max_step`` rad).

    Returns (segment index j, t in [0, 1] within segment j, theta at the node, weight in dtheta)."""
    h = np.diff(theta)
    n_sub = np.maximum(1, np.ceil(h / max_step)).astype(np.int64)
    seg = np.repeat(np.arange(h.size), n_sub)
    # sub-piece k of n within its segment
    k = np.arange(seg.size) - np.repeat(np.cumsum(n_sub) - n_sub, n_sub)
    n = n_sub[seg]
    t = ((k[:, None] + _GL_T[None, :]) / n[:, None]).ravel()
    w = ((h[seg] / n)[:, None] * _GL_W[None, :]).ravel()
    seg = np.repeat(seg, _GL_T.size)
    return seg, t, theta[seg] + t * h[seg], w


def _segment_integrals(theta: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(N-1, C): 2 pi * integral over each segment of p(theta) sin(theta) dtheta, p linear in theta."""
    seg, t, th, w = _quadrature(theta)
    p = values[seg] * (1 - t)[:, None] + values[seg + 1] * t[:, None]
    contrib = (2 * np.pi) * (w * np.sin(th))[:, None] * p
    out = np.zeros((theta.size - 1, values.shape[1]))
    np.add.at(out, seg, contrib)
    return out


def _one_minus_cos(x):
    return 2.0 * np.sin(0.5 * x) ** 2


def _sin_minus_x_cos(d):
    """sin(d) - d cos(d) without cancellation (series below 1e-2)."""
    d = np.asarray(d, np.float64)
    d2 = d * d
    series = d * d2 * (1 / 3 - d2 * (1 / 30 - d2 * (1 / 840 - d2 / 45360)))
    return np.where(np.abs(d) < 1e-2, series, np.sin(d) - d * np.cos(d))


def _partial(a, d, fa, s):
    """integral_a^(a+d) (fa + s (t - a)) sin t dt, in closed form, stable for tiny a and d.

    sin(a+d) - sin a - d cos(a+d) = sin a (d sin d - 2 sin^2(d/2)) + cos a (sin d - d cos d)."""
    cos_a_minus_cos = np.sin(a) * np.sin(d) + np.cos(a) * _one_minus_cos(d)  # cos a - cos(a + d)
    lin = np.sin(a) * (d * np.sin(d) - _one_minus_cos(d)) + np.cos(a) * _sin_minus_x_cos(d)
    return fa * cos_a_minus_cos + s * lin


class PhaseTable:
    """A tabulated phase function per RGB channel.

    Attributes
    ----------
    theta : (N,) float64, scattering angles in radians, strictly ascending from 0 to pi.
    values : (N, 3) float64, the PHASE FUNCTION p(theta) in 1/sr per channel (R, G, B), piecewise
        linear in theta between nodes and normalised so that the integral over 4 pi of p dOmega
        = 2 pi * integral_0^pi p sin(theta) dtheta = 1 in every channel (4 pi p = 1 is isotropic).
    wavelengths_m : (3,) the channel wavelengths in metres, (650e-9, 550e-9, 450e-9) for R, G, B.
    name : str, a label.
    g : (3,) asymmetry parameter = mean cosine <cos theta> per channel.
    cdf : (N, 3) cumulative 2 pi integral_0^theta p sin dtheta per channel, 0 at theta = 0, 1 at pi.

    Arrays are read-only; constructors normalise. Build with :meth:`from_values` or
    :meth:`from_function`.
    """

    __slots__ = ("theta", "values", "wavelengths_m", "name", "_cdf", "_g", "_seg")

    def __init__(self, theta, values, wavelengths_m=RGB_WAVELENGTHS_M, name: str = "", normalise: bool = True):
        th = _check_theta(theta)
        v = _as_channels(values, th.size)
        if not np.all(np.isfinite(v)) or np.any(v < 0):
            raise ValueError("phase values must be finite and >= 0")
        seg = _segment_integrals(th, v)
        total = seg.sum(axis=0)
        if np.any(total <= 0):
            raise ValueError("phase values integrate to zero in some channel")
        if normalise:
            v = v / total
            seg = seg / total
        wl = tuple(float(x) for x in np.broadcast_to(np.asarray(wavelengths_m, np.float64), (3,)))
        for arr in (th, v, seg):
            arr.setflags(write=False)
        object.__setattr__(self, "theta", th)
        object.__setattr__(self, "values", v)
        object.__setattr__(self, "wavelengths_m", wl)
        object.__setattr__(self, "name", str(name))
        object.__setattr__(self, "_seg", seg)
        object.__setattr__(self, "_cdf", None)
        object.__setattr__(self, "_g", None)

    def __setattr__(self, key, value):
        raise AttributeError("PhaseTable is immutable")

    def __getstate__(self):  # pickling (Dask workers): every slot exactly as it is
        return {k: getattr(self, k) for k in self.__slots__}

    def __setstate__(self, state):
        for k, v in state.items():
            if isinstance(v, np.ndarray):
                v.setflags(write=False)
            object.__setattr__(self, k, v)

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_values(cls, theta, values, name: str = "", wavelengths_m=RGB_WAVELENGTHS_M) -> "PhaseTable":
        """Table from nodes ``theta`` (radians, 0..pi) and values (N,), (N, 1) or (N, 3) in any
        units proportional to the phase function; normalised to integrate to 1 over 4 pi."""
        return cls(theta, values, wavelengths_m, name)

    @classmethod
    def from_function(cls, f: Callable[[np.ndarray], np.ndarray], theta=None, name: str = "",
                      wavelengths_m=RGB_WAVELENGTHS_M) -> "PhaseTable":
        """Table of ``f(theta)`` (theta in radians; returns (N,) or (N, 3)) on ``theta``
        (default :func:`angle_grid`), normalised."""
        th = angle_grid() if theta is None else np.asarray(theta, np.float64)
        return cls(th, f(th), wavelengths_m, name)

    # ------------------------------------------------------------------ integrals
    @property
    def total(self) -> np.ndarray:
        """(3,) integral over 4 pi of p dOmega (1 after normalisation)."""
        return self._seg.sum(axis=0)

    @property
    def cdf(self) -> np.ndarray:
        """(N, 3) CDF of theta: 2 pi integral_0^theta p(t) sin t dt, from 0 to 1."""
        if self._cdf is None:
            c = np.concatenate([np.zeros((1, 3)), np.cumsum(self._seg, axis=0)])
            c /= c[-1]
            c.setflags(write=False)
            object.__setattr__(self, "_cdf", c)
        return self._cdf

    @property
    def g(self) -> np.ndarray:
        """(3,) asymmetry parameter g = <cos theta> = 2 pi integral p cos(theta) sin(theta) dtheta."""
        if self._g is None:
            seg, t, th, w = _quadrature(self.theta)
            p = self.values[seg] * (1 - t)[:, None] + self.values[seg + 1] * t[:, None]
            g = 2 * np.pi * np.sum((w * np.sin(th) * np.cos(th))[:, None] * p, axis=0)
            g.setflags(write=False)
            object.__setattr__(self, "_g", g)
        return self._g

    def cone_fraction(self, theta0) -> np.ndarray:
        """Fraction of scattered energy within ``theta0`` radians of forward, per channel:
        F = 2 pi integral_0^theta0 p(theta) sin(theta) dtheta (with sin theta). Scalar theta0 gives
        (3,); an array gives shape theta0.shape + (3,)."""
        t0 = np.clip(np.asarray(theta0, np.float64), 0.0, np.pi)
        j = np.clip(np.searchsorted(self.theta, t0, side="right") - 1, 0, self.theta.size - 2)
        a = self.theta[j]
        h = self.theta[j + 1] - a
        fa = self.values[j]
        s = (self.values[j + 1] - fa) / h[..., None]
        part = 2 * np.pi * _partial(a[..., None], (t0 - a)[..., None], fa, s) / self.total
        return np.minimum(self.cdf[j] + part, 1.0)

    def legendre(self, n: int) -> np.ndarray:
        """(n + 1, 3) Legendre moments chi_l = integral over 4 pi of p P_l(cos theta) dOmega, so that
        p(mu) = sum_l (2 l + 1) chi_l P_l(mu) / (4 pi) (DISORT's PMOM convention); chi_0 = 1, chi_1 = g."""
        n = int(n)
        if n < 0:
            raise ValueError("legendre(n) needs n >= 0")
        # split segments so each piece spans at most ~1/4 of P_n's oscillation period (2 pi / n)
        seg, t, th, w = _quadrature(self.theta, max_step=min(_MAX_STEP, np.pi / (2 * max(n, 1))))
        p = self.values[seg] * (1 - t)[:, None] + self.values[seg + 1] * t[:, None]
        wp = (2 * np.pi * w * np.sin(th))[:, None] * p
        mu = np.cos(th)
        out = np.empty((n + 1, 3))
        p_prev, p_cur = np.zeros_like(mu), np.ones_like(mu)
        for ell in range(n + 1):
            out[ell] = p_cur @ wp
            # Bonnet recursion: (l + 1) P_{l+1} = (2 l + 1) mu P_l - l P_{l-1}
            p_prev, p_cur = p_cur, ((2 * ell + 1) * mu * p_cur - ell * p_prev) / (ell + 1)
        return out / out[0]

    # ------------------------------------------------------------------ evaluation and sampling
    def eval(self, theta) -> np.ndarray:
        """p at angles ``theta`` (radians, any shape) per channel: shape theta.shape + (3,), 1/sr."""
        th = np.asarray(theta, np.float64)
        flat = th.ravel()
        out = np.stack([np.interp(flat, self.theta, self.values[:, c]) for c in range(3)], axis=-1)
        return out.reshape(th.shape + (3,))

    def eval_cos(self, mu) -> np.ndarray:
        """p at cos(theta) = ``mu`` per channel: shape mu.shape + (3,), 1/sr."""
        return self.eval(np.arccos(np.clip(np.asarray(mu, np.float64), -1.0, 1.0)))

    def sample(self, u, channel: int = 1) -> np.ndarray:
        """Scattering angles theta (radians) distributed as 2 pi p sin(theta) dtheta in ``channel``
        (0 R, 1 G, 2 B), from uniform numbers ``u`` in [0, 1): exact inversion of the piecewise-
        linear table (bracketed Newton within the segment). Intended for tests and tools."""
        u = np.clip(np.asarray(u, np.float64), 0.0, 1.0)
        c = self.cdf[:, channel]
        j = np.clip(np.searchsorted(c, u, side="right") - 1, 0, self.theta.size - 2)
        a, b = self.theta[j], self.theta[j + 1]
        h = b - a
        fa = self.values[j, channel]
        s = (self.values[j + 1, channel] - fa) / h
        target = (u - c[j]) * self.total[channel] / (2 * np.pi)
        # start: invert the quadratic CDF of the density q = p sin(theta) taken linear in theta
        qa, qb = fa * np.sin(a), self.values[j + 1, channel] * np.sin(b)
        seg_total = np.maximum(0.5 * (qa + qb) * h, 1e-300)
        frac = np.clip(target / _partial(a, h, fa, s).clip(1e-300), 0.0, 1.0)
        dq = qb - qa
        with np.errstate(divide="ignore", invalid="ignore"):
            x = np.where(np.abs(dq) > 1e-12 * (qa + qb),
                         (np.sqrt(np.maximum(qa * qa + 2 * dq * frac * seg_total / h, 0)) - qa) / dq * h,
                         frac * h)
        d = np.clip(np.nan_to_num(x / h, nan=0.5), 0.0, 1.0) * h
        lo, hi = np.zeros_like(a), h.copy()
        active = np.arange(a.size)
        for _ in range(100):
            if active.size == 0:
                break
            aa, dd, ff, ss, hh = a[active], d[active], fa[active], s[active], h[active]
            f = _partial(aa, dd, ff, ss) - target[active]
            l_ = np.where(f < 0, dd, lo[active])
            h_ = np.where(f < 0, hi[active], dd)
            dens = (ff + ss * dd) * np.sin(aa + dd)
            with np.errstate(divide="ignore", invalid="ignore"):
                step = dd - f / dens
            bad = ~np.isfinite(step) | (step <= l_) | (step >= h_)
            d_new = np.where(bad, 0.5 * (l_ + h_), step)
            d[active], lo[active], hi[active] = d_new, l_, h_
            keep = (np.abs(d_new - dd) > 1e-12 * hh) & (h_ - l_ > 1e-12 * hh)
            active = active[keep]
        return a + d

    # ------------------------------------------------------------------ derived tables
    def to_channel_mean(self) -> "PhaseTable":
        """The channel-mean phase function in all three channels."""
        return PhaseTable(self.theta, self.values.mean(axis=1), self.wavelengths_m, self.name + " (mean)")

    def gray(self, channel: int = 1) -> "PhaseTable":
        """One channel's phase function (default green) copied to all three channels."""
        return PhaseTable(self.theta, self.values[:, channel], self.wavelengths_m, f"{self.name} (channel {channel})")

    def renamed(self, name: str) -> "PhaseTable":
        return PhaseTable(self.theta, self.values, self.wavelengths_m, name, normalise=False)

    def to_npz_dict(self) -> dict:
        return {"theta": np.asarray(self.theta), "values": np.asarray(self.values),
                "wavelengths_m": np.asarray(self.wavelengths_m), "name": np.asarray(self.name)}

    @classmethod
    def from_npz_dict(cls, d) -> "PhaseTable":
        return cls(d["theta"], d["values"], tuple(d["wavelengths_m"]), str(d["name"]), normalise=False)

    def __repr__(self) -> str:
        g = ", ".join(f"{x:.4f}" for x in self.g)
        return f"PhaseTable({self.name!r}, {self.theta.size} angles, g=({g}))"

    def __len__(self) -> int:
        return self.theta.size


def mixture(tables: Sequence[PhaseTable], weights, name: str = "mixture") -> PhaseTable:
    """Weighted mixture sum_s w_s p_s / sum_s w_s (Eq. 8 with constant weights, e.g. beta_sca,s),
    on the union of the tables' grids (exact: each piecewise-linear table is unchanged on a
    refined grid). ``weights`` is (S,) or (S, 3) per channel, >= 0."""
    tables = list(tables)
    if not tables:
        raise ValueError("mixture needs at least one table")
    w = np.asarray(weights, np.float64)
    if w.ndim == 1:
        w = np.repeat(w[:, None], 3, axis=1)
    if w.shape != (len(tables), 3) or np.any(w < 0) or not np.all(np.isfinite(w)):
        raise ValueError(f"weights must be {len(tables)} (or {len(tables)} x 3) finite values >= 0")
    wsum = w.sum(axis=0)
    if np.any(wsum <= 0):
        raise ValueError("mixture weights sum to zero")
    w = w / wsum
    theta = np.unique(np.concatenate([t.theta for t in tables]))
    values = sum(w[s] * t.eval(theta) for s, t in enumerate(tables))
    return PhaseTable(theta, values, tables[0].wavelengths_m, name)
