"""Mitsuba 3 phase function ``hydrometeor_mixture``: the paper's Eq. 8 mixture of tabulated phases.

    P(Theta, x) = sum_s w_s(x) P_s(Theta),   w_s = beta_sca,s / sum_s' beta_sca,s'        (Eq. 8)

Each species table is held piecewise linear in the versine v = 1 - cos(Theta) on one common node
set (the union of the tables' angle grids, so forward peaks, halos and rainbows stay resolved), per
RGB channel, and normalised so that 2 pi * integral p dv = 1 exactly in that representation. The
versine keeps float32 resolution near forward (a 1 mm raindrop's diffraction peak is ~0.02 deg
wide; cos(Theta) cannot tell those angles apart in float32); in ``eval_pdf`` it is computed as
|wo + wi|^2 / 2, which is exact there too. The weights w_s(x) are a
grid (z, y, x, S) on the medium's bounding box, looked up trilinearly (texel centres at (i + 0.5)/N,
as Mitsuba's ``gridvolume``) and renormalised to sum to 1 (equal weights where all are zero).

Sampling: pick species s with probability w_s(x), then invert the CDF of that species'
channel-mean table (exact inversion of a piecewise-linear density: a quadratic per segment).
``eval_pdf`` returns the per-channel value sum_s w_s p_s,c and pdf = sum_s w_s pbar_s, which is
exactly the density the sampler draws from, so sample weights are value / pdf per channel.

Properties (Python dict scenes): ``nodes`` (TensorXf, N ascending versines 1 - cos in [0, 2]), ``values``
(TensorXf, S x N x 3, 1/sr), ``weights`` (TensorXf, z x y x x x S) and ``to_world`` (the bounding box
as a transform of the unit cube). From XML: ``filename``, an ``.npz`` written by
:func:`save_npz` with the same arrays plus ``bbox``.
"""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

PLUGIN_NAME = "hydrometeor_mixture"


# ---------------------------------------------------------------- numpy side: table preparation

def common_nodes(tables, max_nodes: int = 16384) -> np.ndarray:
    """Ascending versine nodes v = 1 - cos(theta): the union of the tables' theta grids (thinned if
    too many), distinct in float32."""
    theta = np.unique(np.concatenate([np.asarray(t.theta, np.float64) for t in tables] + [[0.0, np.pi]]))
    theta = theta[(theta >= 0) & (theta <= np.pi)]
    if theta.size > max_nodes:
        keep = np.unique(np.round(np.linspace(0, theta.size - 1, max_nodes)).astype(int))
        theta = theta[keep]
    v = np.unique((2.0 * np.sin(theta / 2) ** 2).astype(np.float32)).astype(np.float64)  # 1 - cos, accurately
    v[0], v[-1] = 0.0, 2.0
    return v


def _normalise(v: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Scale p (N, ...) so that 2 pi * trapezoid(p, v) = 1 (piecewise linear in v = 1 - cos)."""
    integral = 2 * np.pi * np.sum(0.5 * (p[1:] + p[:-1]) * np.diff(v)[:, None], axis=0)
    return p / integral


def prepare_tables(tables, max_nodes: int = 16384):
    """(nodes v = 1 - cos (N,), values (S, N, 3)) in 1/sr from PhaseTable-like objects (``theta``
    ascending in radians, ``values`` (len(theta), 3) in 1/sr), resampled linearly in v."""
    v = common_nodes(tables, max_nodes)
    out = np.empty((len(tables), v.size, 3))
    for s, t in enumerate(tables):
        th = np.asarray(t.theta, np.float64)
        vals = np.asarray(t.values, np.float64).reshape(th.size, -1)
        if vals.shape[1] == 1:
            vals = np.repeat(vals, 3, axis=1)
        tv = 2.0 * np.sin(th / 2) ** 2
        for c in range(3):
            out[s, :, c] = np.interp(v, tv, vals[:, c])
        out[s] = _normalise(v, out[s])
    return v.astype(np.float32), out.astype(np.float32)


def marginal_cdf(v: np.ndarray, values: np.ndarray):
    """Channel-mean density pbar (S, N) and its CDF in v (S, N), 0 forward (v = 0), 1 at v = 2."""
    v = np.asarray(v, np.float64)
    pbar = _normalise(v, np.asarray(values, np.float64).mean(axis=2).T).T
    seg = 2 * np.pi * 0.5 * (pbar[:, 1:] + pbar[:, :-1]) * np.diff(v)[None]
    cdf = np.concatenate([np.zeros((pbar.shape[0], 1)), np.cumsum(seg, axis=1)], axis=1)
    cdf /= cdf[:, -1:]
    return pbar, cdf


def bbox_transform(bbox) -> "mi.ScalarTransform4f":
    """The transform mapping the unit cube onto ((x0, y0, z0), (x1, y1, z1))."""
    lo, hi = (np.asarray(p, np.float64) for p in bbox)
    return mi.ScalarTransform4f().translate(lo.tolist()).scale((hi - lo).tolist())


def save_npz(path, nodes, values, weights, bbox) -> None:
    """Write everything the plugin needs for use from a Mitsuba XML file (``filename`` property)."""
    np.savez(path, nodes=np.asarray(nodes, np.float32), values=np.asarray(values, np.float32),
             weights=np.asarray(weights, np.float32), bbox=np.asarray(bbox, np.float64))


# ---------------------------------------------------------------- Mitsuba side

def _is_scalar_variant() -> bool:
    return not dr.is_array_v(mi.Float)


def _storage(a: np.ndarray):
    """A flat array to gather from: mi.Float in JIT variants, a list of floats in scalar variants."""
    flat = np.ascontiguousarray(a, np.float32).ravel()
    return flat.astype(float).tolist() if _is_scalar_variant() else mi.Float(flat)


def _gather(src, index):
    """src[index] for a JIT array (vectorised) or a Python list (scalar variants)."""
    if isinstance(src, list):
        return src[int(index)]
    return dr.gather(mi.Float, src, index)


def _gather4(src, index):
    """src[4 index : 4 index + 4] as a Vector4f: one packet load per lane in JIT variants."""
    if isinstance(src, list):
        return mi.Vector4f(*src[4 * int(index): 4 * int(index) + 4])
    return dr.gather(mi.Vector4f, src, index)


class HydrometeorMixture(mi.PhaseFunction):
    """Eq. 8 mixture of per-species tabulated phase functions with spatially varying weights."""

    def __init__(self, props: mi.Properties):
        mi.PhaseFunction.__init__(self, props)
        if "filename" in props:
            data = np.load(str(props["filename"]))
            nodes, values, weights = data["nodes"], data["values"], data["weights"]
            to_world = bbox_transform(data["bbox"])
        else:
            nodes = np.asarray(props["nodes"], np.float32).ravel()
            values = np.asarray(props["values"], np.float32)
            weights = np.asarray(props["weights"], np.float32)
            to_world = props["to_world"] if "to_world" in props else mi.ScalarTransform4f()
        if values.ndim != 3 or values.shape[1] != nodes.size or values.shape[2] != 3:
            raise ValueError(f"{PLUGIN_NAME}: 'values' must be S x N x 3 with N = len(nodes) = {nodes.size}; "
                             f"got {values.shape}")
        if weights.ndim != 4 or weights.shape[3] != values.shape[0]:
            raise ValueError(f"{PLUGIN_NAME}: 'weights' must be z x y x x x S with S = {values.shape[0]}; "
                             f"got {weights.shape}")
        self.n_species, self.n_nodes = int(values.shape[0]), int(nodes.size)
        inverse = np.linalg.inv(np.array(to_world.matrix, dtype=np.float64).reshape(4, 4))
        self.to_local = mi.Transform4f(mi.ScalarTransform4f(inverse.astype(np.float32).tolist()))
        self._set_tables(nodes, values)
        self.weights = mi.Texture3f(mi.TensorXf(np.ascontiguousarray(weights)), use_accel=False)
        self.m_flags = mi.PhaseFunctionFlags.Anisotropic

    def _set_tables(self, nodes, values):
        pbar, cdf = marginal_cdf(nodes, values)
        self.nodes = _storage(nodes)
        # (S, N, 4): R, G, B value and the channel-mean pdf of every node, read as one packet
        self.table4 = _storage(np.concatenate([np.asarray(values, np.float32), pbar[:, :, None]], axis=2))
        self.pbar = _storage(pbar)
        self.cdf = _storage(cdf)

    # ------------------------------------------------------------ helpers
    def _weights_at(self, mei):
        """w_s(x) for s = 0..S-1, trilinear on the bbox grid, renormalised to sum to 1."""
        if self.n_species == 1:
            return [mi.Float(1.0)]  # renormalised weights of one species are 1: no lookup
        p = self.to_local @ mei.p
        w = self.weights.eval(mi.Point3f(p.x, p.y, p.z))
        w = [dr.maximum(wi, 0.0) for wi in w]
        total = w[0]
        for wi in w[1:]:
            total = total + wi
        empty = total <= 0.0
        inv = dr.rcp(dr.select(empty, 1.0, total))
        return [dr.select(empty, 1.0 / self.n_species, wi * inv) for wi in w]

    def _segment(self, v):
        """Node index i with v_i <= v < v_i+1 and the linear weight t in [0, 1]."""
        n = self.n_nodes
        idx = dr.binary_search(1, n - 1, lambda k: _gather(self.nodes, k) <= v) - 1
        idx = dr.clip(idx, 0, n - 2)
        v0 = _gather(self.nodes, idx)
        v1 = _gather(self.nodes, idx + 1)
        t = dr.clip((v - v0) / dr.maximum(v1 - v0, 1e-30), 0.0, 1.0)
        return idx, t

    def _mix(self, w, idx, t):
        """(per-channel value, pdf) of the mixture with weights w in node segment idx at fraction t."""
        value = [mi.Float(0.0), mi.Float(0.0), mi.Float(0.0)]
        pdf = mi.Float(0.0)
        for s in range(self.n_species):
            k = idx + s * self.n_nodes
            f0 = _gather4(self.table4, k)
            f = f0 + (_gather4(self.table4, k + 1) - f0) * t
            for c in range(3):
                value[c] += w[s] * f[c]
            pdf += w[s] * f[3]
        return mi.Color3f(value[0], value[1], value[2]), pdf

    def _eval(self, mei, v, active):
        """(per-channel value, pdf) of the mixture at versine v = 1 - cos(Theta)."""
        idx, t = self._segment(v)
        return self._mix(self._weights_at(mei), idx, t)

    # ------------------------------------------------------------ PhaseFunction interface
    def sample(self, ctx, mei, sample1, sample2, active=True):
        w = self._weights_at(mei)
        # pick a species with probability w_s (sample1), then invert its CDF in v (sample2.x)
        species = mi.UInt32(0)
        acc = mi.Float(0.0)
        for s in range(self.n_species - 1):
            acc += w[s]
            species += mi.UInt32(dr.select(sample1 >= acc, 1, 0))
        n = self.n_nodes
        base = species * n
        u = sample2.x
        idx = dr.binary_search(1, n - 1, lambda k: _gather(self.cdf, base + k) <= u) - 1
        idx = dr.clip(idx, 0, n - 2)
        k = base + idx
        c0 = _gather(self.cdf, k)
        v0 = _gather(self.nodes, idx)
        v1 = _gather(self.nodes, idx + 1)
        f0 = _gather(self.pbar, k) * (2.0 * dr.pi)
        f1 = _gather(self.pbar, k + 1) * (2.0 * dr.pi)
        # solve f0 x + (f1 - f0) x^2 / (2 dv) = u - c0 for x in [0, dv] (stable root)
        dmu = v1 - v0
        r = dr.maximum(u - c0, 0.0)
        a = (f1 - f0) / (2.0 * dmu)
        disc = dr.maximum(f0 * f0 + 4.0 * a * r, 0.0)
        x = dr.select(f0 + dr.sqrt(disc) > 0.0, 2.0 * r / (f0 + dr.sqrt(disc)), 0.5 * dmu)
        x = dr.clip(x, 0.0, dmu)
        v = dr.clip(v0 + x, 0.0, 2.0)
        cos_theta = 1.0 - v
        sin_theta = dr.safe_sqrt(v * (2.0 - v))
        sin_phi, cos_phi = dr.sincos(2.0 * dr.pi * sample2.y)
        wo = mei.to_world(mi.Vector3f(sin_theta * cos_phi, sin_theta * sin_phi, -cos_theta))
        # value and pdf where v was drawn: same weights, same segment (no second search or lookup)
        value, pdf = self._mix(w, idx, dr.clip(x / dr.maximum(dmu, 1e-30), 0.0, 1.0))
        weight = dr.select(pdf > 0.0, value / pdf, 0.0)
        return wo, mi.Spectrum(weight), pdf

    def eval_pdf(self, ctx, mei, wo, active=True):
        h = wo + mei.wi  # |wo + wi|^2 = 2 (1 - cos Theta): accurate near forward
        value, pdf = self._eval(mei, 0.5 * dr.squared_norm(h), active)
        return mi.Spectrum(value), pdf

    def traverse(self, cb):
        cb.put("weights", self.weights.tensor(), mi.ParamFlags.NonDifferentiable)

    def parameters_changed(self, keys=None):
        self.weights.set_tensor(self.weights.tensor())

    def to_string(self):
        return (f"HydrometeorMixture[species={self.n_species}, nodes={self.n_nodes}, "
                f"weights grid={tuple(self.weights.shape)}]")


def register() -> None:
    """Register ``hydrometeor_mixture`` with the current Mitsuba variant."""
    mi.register_phase(PLUGIN_NAME, lambda props: HydrometeorMixture(props))
