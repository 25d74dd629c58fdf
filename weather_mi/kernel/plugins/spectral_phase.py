"""``hydrometeor_mixture``'s phase tables by wavelength, for the spectral variants (``llvm_ad_spectral``).

The species' tables at K wavelengths on a uniform grid (``optics.phase.spectral_tables``: 350-850 nm every
25 nm) are resampled onto the mixture's versine nodes (:func:`prepare_spectral`, as ``prepare_tables`` does
the R, G, B ones) and held as one Vector4f per (node segment i, wavelength segment j, species s):

    (p_s(v_i, lambda_j), p_s(v_i, lambda_j+1), p_s(v_i+1, lambda_j), p_s(v_i+1, lambda_j+1))

(:func:`pack_spectral`), so a lane's bilinear value (linear in v between nodes, linear in wavelength between
the grid's wavelengths, held beyond its ends) is one packet load per species and lane (:func:`spectral_value`).
Memory: 16 (N - 1)(K - 1) S bytes (about 3 MB for 5 species on 2000 nodes and 21 wavelengths).

The density directions are drawn from (the species' mean over the K wavelengths, pbar_s) is read for MIS at
every evaluation; :func:`pack_pdf` holds it per node segment as (pbar_s(v_i) for every s, pbar_s(v_i+1) for
every s), so the mixture's pdf is ceil(S / 2) packet loads (:func:`spectral_pdf`; 3 for 5 species) instead of
the 2 S of the R, G, B table ``table4`` (whose colour channels a spectral lane does not read).
"""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

from ..jitarrays import aligned_uint


def prepare_spectral(v: np.ndarray, stacks) -> np.ndarray:
    """(S, N, K) float32: per species (``stacks``: S lists of K PhaseTable-likes, each one wavelength's table in
    its channels) the tables at the versine nodes ``v`` (N,) (linear in v, as ``prepare_tables``), each
    normalised so that 2 pi * integral p dv = 1 in that representation."""
    v = np.asarray(v, np.float64)
    k = len(stacks[0])
    out = np.empty((len(stacks), v.size, k))
    for s, stack in enumerate(stacks):
        if len(stack) != k:
            raise ValueError(f"every species needs {k} wavelengths' tables, species {s} has {len(stack)}")
        for j, t in enumerate(stack):
            th = np.asarray(t.theta, np.float64)
            vals = np.asarray(t.values, np.float64).reshape(th.size, -1)[:, 0]  # one wavelength in every channel
            out[s, :, j] = np.interp(v, 2.0 * np.sin(th / 2) ** 2, vals)
        integral = 2 * np.pi * np.sum(0.5 * (out[s, 1:] + out[s, :-1]) * np.diff(v)[:, None], axis=0)
        out[s] /= integral
    return out.astype(np.float32)


def from_properties(props, n_species: int, n_nodes: int, name: str):
    """(values S x N x K, (first nm, 1 / step, K)) from ``spectral_values`` and ``spectral_nm`` in ``props``
    (spectral variants), checked; (None, None) else."""
    if not (mi.is_spectral and "spectral_values" in props):
        return None, None
    values = np.asarray(props["spectral_values"], np.float32)
    grid = np.asarray(props["spectral_nm"], np.float64).ravel()
    check_spectral(values, grid, n_species, n_nodes, name)
    return values, (float(grid[0]), float(1.0 / (grid[1] - grid[0])), int(grid.size))


def pack_pdf(pbar: np.ndarray) -> np.ndarray:
    """(N - 1, 4 Q) float32 from the densities ``pbar`` (S, N): per node segment i, pbar_s(v_i) for s = 0..S-1,
    then pbar_s(v_i+1), then zeros to Q = ceil(2 S / 4) packets."""
    p = np.asarray(pbar, np.float32)
    n_s, q = p.shape[0], -(-2 * p.shape[0] // 4)
    out = np.zeros((p.shape[1] - 1, 4 * q), np.float32)
    out[:, :n_s], out[:, n_s:2 * n_s] = p[:, :-1].T, p[:, 1:].T
    return out


def spectral_pdf(table, n_species: int, w, idx, t, gather4):
    """sum_s w_s pbar_s(v), v at fraction ``t`` of node segment ``idx``; ``table`` from :func:`pack_pdf` (flat)."""
    q = -(-2 * n_species // 4)
    e = []
    for k in range(q):
        packet = gather4(table, idx * q + k)
        e += [packet[c] for c in range(4)]
    pdf = mi.Float(0.0)
    for s in range(n_species):
        pdf += w[s] * (e[s] + (e[n_species + s] - e[s]) * t)  # as the R, G, B table's pdf (``_mix``)
    return pdf


def pack_spectral(values: np.ndarray) -> np.ndarray:
    """(N - 1, K - 1, S, 4) float32 from (S, N, K): the four corners of every (node, wavelength) cell."""
    a = np.transpose(np.asarray(values, np.float32), (1, 2, 0))  # (N, K, S)
    return np.ascontiguousarray(np.stack([a[:-1, :-1], a[:-1, 1:], a[1:, :-1], a[1:, 1:]], axis=-1))


def check_spectral(values: np.ndarray, grid_nm: np.ndarray, n_species: int, n_nodes: int, name: str) -> None:
    """ValueError unless ``values`` is S x N x K (K >= 2, finite, >= 0) on a uniform ascending ``grid_nm``."""
    ok = (values.ndim == 3 and values.shape[:2] == (n_species, n_nodes) and grid_nm.size == values.shape[2] >= 2
          and np.all(np.diff(grid_nm) > 0) and np.allclose(np.diff(grid_nm), grid_nm[1] - grid_nm[0])
          and np.all(np.isfinite(values)) and values.min() >= 0)
    if not ok:
        raise ValueError(f"{name}: 'spectral_values' must be S x N x K (S = {n_species}, N = {n_nodes}), finite and "
                         f">= 0, on the uniform ascending wavelengths 'spectral_nm' (K >= 2); got {values.shape}, "
                         f"{grid_nm.size} wavelengths")


def flat_species(values: np.ndarray) -> tuple:
    """The species whose tables ``values`` (S, N, K) are the same at every wavelength (Rayleigh's, a
    Henyey-Greenstein's: the box's air), which :func:`spectral_value` reads once for all lanes."""
    v = np.asarray(values)
    return tuple(s for s in range(v.shape[0]) if np.array_equal(v[s], np.broadcast_to(v[s][:, :1], v[s].shape)))


def flat_table(values: np.ndarray, flat: tuple, storage):
    """``storage`` of :func:`pack_spectral` of the flat species' tables (their first two wavelengths:
    (N - 1, 1, F, 4)), :func:`spectral_value`'s ``flat_table``: the per-lane records then hold the species that
    change with wavelength alone (80 bytes for the five hydrometeors, where the box's air's two flat tables made
    them 112)."""
    return storage(pack_spectral(np.asarray(values, np.float32)[list(flat)][:, :, :2]))


def spectral_value(table, grid, n_species: int, w, idx, t, wavelengths, gather4, lane_w=None, flat=(),
                   flat_table=None):
    """mi.Spectrum: per lane of ``wavelengths`` (nm), sum_s w_s p_s(v, lambda) with v at fraction ``t`` of node
    segment ``idx``; ``table`` from :func:`pack_spectral` (flat), ``grid`` = (first nm, 1 / step, K). ``lane_w``:
    each lane's own weights (4 lists of S Floats: the air's by wavelength, ``spectral_air_weights``) in place of w.
    ``flat``: species the same at every wavelength (:func:`flat_species`), one packet load for the 4 lanes; with
    ``flat_table`` (:func:`flat_table`) they are read from it, and ``table`` holds the other species only."""
    lo, inv_step, k = grid
    out, shared = [], {}
    for f, s in enumerate(flat):  # wavelength cell 0: the same values as any other
        e = gather4(table, idx * ((k - 1) * n_species) + s) if flat_table is None else \
            gather4(flat_table, idx * len(flat) + f)
        shared[s] = dr.fma(e[2] - e[0], t, e[0])
    stride = n_species if flat_table is None else n_species - len(flat)
    slot = {s: (s if flat_table is None else s - sum(1 for f in flat if f < s)) for s in range(n_species)}
    for lane in range(4):
        u = dr.clip((wavelengths[lane] - lo) * inv_step, 0.0, k - 1.0001)
        j = mi.UInt32(u)
        tl = u - mi.Float(j)
        base = (idx * (k - 1) + j) * stride
        acc = mi.Float(0.0)
        ws = w if lane_w is None else lane_w[lane]
        for s in range(n_species):
            if s in shared:
                acc += ws[s] * shared[s]
                continue
            e = gather4(table, base + slot[s])
            near = dr.fma(e[1] - e[0], tl, e[0])
            far = dr.fma(e[3] - e[2], tl, e[2])
            acc += ws[s] * dr.fma(far - near, t, near)
        out.append(acc)
    return mi.Spectrum(*out)


HALF_BIAS = 88  # float32 exponent of the 16-bit code 0: codes span 2^-39 .. 2^25 (6 exponent, 10 mantissa bits)
HALF_MAX = 2.0 ** 25 * (1.0 - 2.0 ** -12)


def encode16(values: np.ndarray) -> np.ndarray:
    """uint16 codes of non-negative float32 ``values``: the float's bits from exponent ``HALF_BIAS`` up, rounded to
    10 mantissa bits (relative error <= 2^-11); values below 2^-39 (and 0) as code 0, which decodes to 0."""
    v = np.asarray(values, np.float32)
    if not (np.all(np.isfinite(v)) and v.min(initial=0.0) >= 0.0 and v.max(initial=0.0) < HALF_MAX):
        raise ValueError(f"16-bit phase tables hold values in [0, {HALF_MAX:.4g}) 1/sr; got {v.min()} .. {v.max()}")
    b = v.view(np.uint32).astype(np.int64) - (HALF_BIAS << 23)
    return np.where(b > 0, (b + (1 << 12)) >> 13, 0).astype(np.uint16)


def decode16(codes: np.ndarray) -> np.ndarray:
    """float32 values of :func:`encode16`'s codes (numpy; the kernel decodes the same way, :func:`_decoded`)."""
    c = np.asarray(codes, np.uint32)
    return np.where(c == 0, 0, (c << 13) + (HALF_BIAS << 23)).astype(np.uint32).view(np.float32)


def pack_half_nodes(values: np.ndarray) -> np.ndarray:
    """(K, N, 4) uint32 from (S <= 8, N, K): per wavelength node j and versine node i the S species' values as
    16-bit codes (:func:`encode16`), two to a 32-bit word (species 2 m in the low half of word m), zero-padded to
    8: one 16-byte packet per (j, i), each value once (:func:`picked_value` reads (j, i) and (j, i + 1));
    16 N K bytes, 0.6 MB for 1828 nodes and 21 wavelengths, where :func:`pack_spectral`'s corners take 2.9 MB."""
    v = np.asarray(values, np.float32)
    if v.shape[0] > 8:
        raise ValueError(f"16-bit packets hold at most 8 species; got {v.shape[0]}")
    codes = np.zeros((v.shape[2], v.shape[1], 8), np.uint32)
    codes[..., :v.shape[0]] = np.transpose(encode16(v), (2, 1, 0))
    return (codes[..., 0::2] | (codes[..., 1::2] << 16)).astype(np.uint32)


def _decoded(word, high: bool):
    """The float of the 16-bit code in the low (or ``high``) half of UInt32 ``word`` (:func:`decode16`)."""
    m = ((word >> 3) if high else (word << 13)) & 0x1FFFE000
    return dr.select(m == 0, 0.0, dr.reinterpret_array(mi.Float, m + (HALF_BIAS << 23)))


def hash_uniform(p, wo):
    """A uniform number in [0, 1) per lane from the bits of the point ``p`` and the direction ``wo`` (a
    multiply-xor combination and murmur3's 32-bit finaliser): a pure function of the vertex and the direction,
    so the value at one (vertex, direction) is the same wherever it is evaluated (MIS weights by value), and
    independent of the wavelengths and the angle in all but rounding."""
    bits = [dr.reinterpret_array(mi.UInt32, c) for c in (p.x, p.y, p.z, wo.x, wo.y, wo.z)]
    h = mi.UInt32(0x9E3779B9)
    for b, k in zip(bits, (0x85EBCA6B, 0xC2B2AE35, 0x27D4EB2F, 0x165667B1, 0xD3A2646C, 0xFD7046C5)):
        h = (h ^ b) * k
        h ^= h >> 15
    h ^= h >> 16  # fmix32
    h *= 0x85EBCA6B
    h ^= h >> 13
    h *= 0xC2B2AE35
    h ^= h >> 16
    return mi.Float(h >> 8) * (1.0 / (1 << 24))


def picked_node(grid, wavelength, u, lane: int):
    """Lane ``lane``'s wavelength node (mi.UInt32) on ``grid`` (lo, 1 / step, k): of the two that bracket
    ``wavelength``, the upper with probability equal to its linear weight, from the lane's uniform frac(``u`` +
    lane / 4) (the 4 lanes stratified)."""
    lo, inv_step, k = grid
    x = dr.clip((wavelength - lo) * inv_step, 0.0, k - 1.0001)
    j = mi.UInt32(x)
    ul = u + 0.25 * lane
    ul = dr.select(ul >= 1.0, ul - 1.0, ul)
    return dr.select(ul < x - mi.Float(j), j + 1, j)  # P(j + 1) = the lane's weight of node j + 1


def picked_value(codes, grid, n_species: int, w, idx, t, wavelengths, u, gather4, lane_w=None, flat=(),
                 flat_table=None):
    """mi.Spectrum: as :func:`spectral_value`, but each lane reads ONE of its two bracketing wavelength nodes,
    j + 1 with probability equal to its linear weight there (lane l's uniform: frac(``u`` + l / 4)), and the
    value there linear in v: an unbiased estimate of the bilinear value (its expectation over the pick). Read
    from :func:`pack_half_nodes` (``codes``, a flat UInt32; the species other than ``flat``): two
    16-byte packets a lane from a table a fifth the size of :func:`pack_spectral`'s (it stays in the caches).
    The pdf (:func:`spectral_pdf`) is unchanged: sampling stays exact."""
    k = grid[2]
    n = dr.width(codes) // (4 * k)  # versine nodes
    shared = {}
    for f, s in enumerate(flat):  # the species the same at every wavelength: read once (flat_table)
        e = gather4(flat_table, idx * len(flat) + f)
        shared[s] = dr.fma(e[2] - e[0], t, e[0])
    rest = [s for s in range(n_species) if s not in shared]
    out = []
    for lane in range(4):
        j = picked_node(grid, wavelengths[lane], u, lane)
        near, far = (dr.gather(mi.Vector4u, codes, j * n + idx + d) for d in (0, 1))
        ws = w if lane_w is None else lane_w[lane]
        acc = mi.Float(0.0)
        for s in range(n_species):
            if s in shared:
                acc += ws[s] * shared[s]
                continue
            r = rest.index(s)
            p0, p1 = _decoded(near[r // 2], r % 2 == 1), _decoded(far[r // 2], r % 2 == 1)
            acc += ws[s] * dr.fma(p1 - p0, t, p0)
        out.append(acc)
    return mi.Spectrum(*out)


INTERPOLATIONS = ("linear", "stochastic")


def mixture_tables(props, n_species: int, n_nodes: int, name: str, storage) -> dict:
    """``hydrometeor_mixture``'s attributes for the tables by wavelength: ``spectral_values``, ``spectral_grid``
    (:func:`from_properties`; None without the tables: R, G, B interpolated), ``spectral_interpolation``
    (:func:`interpolation_from`), ``spectral_flat`` and ``spectral_flat_table`` (:func:`flat_table`), and the
    table the lanes read of the species other than the flat ones: for "linear" ``spectral_table``
    (:func:`pack_spectral`'s corners), for "stochastic" ``spectral_codes`` (:func:`pack_half_nodes`, a fifth of
    the corners' size; the JIT variants, else "linear"); the other None."""
    values, grid = from_properties(props, n_species, n_nodes, name)
    how = interpolation_from(props, name)
    if how == "stochastic" and not dr.is_array_v(mi.Float):
        how = "linear"  # scalar variants: the bilinear value
    out = {"spectral_values": values, "spectral_table": None, "spectral_grid": grid, "spectral_flat": (),
           "spectral_flat_table": None, "spectral_codes": None, "spectral_interpolation": how}
    if values is None:
        return out
    flat = flat_species(values)  # species flat in wavelength (the box's air): read once
    rest = [s for s in range(n_species) if s not in flat]
    if flat:
        out.update(spectral_flat=flat, spectral_flat_table=flat_table(values, flat, storage))
    if how == "stochastic":
        out["spectral_codes"] = aligned_uint(mi, pack_half_nodes(values[rest]))
    else:
        out["spectral_table"] = storage(pack_spectral(values[rest]))
    return out


def interpolation_from(props, name: str) -> str:
    """The ``spectral_interpolation`` property: "linear" (default: :func:`spectral_value`, the bilinear value)
    or "stochastic" (:func:`picked_value`, its unbiased one-node estimate; what ``kernel.medium`` renders with)."""
    how = str(props.get("spectral_interpolation", "linear"))
    if how not in INTERPOLATIONS:
        raise ValueError(f"{name}: 'spectral_interpolation' must be one of {INTERPOLATIONS}, got {how!r}")
    return how


__all__ = ["flat_species", "flat_table", "prepare_spectral", "pack_spectral", "check_spectral", "spectral_value",
           "from_properties", "pack_pdf", "spectral_pdf", "pack_half_nodes", "encode16", "decode16", "HALF_BIAS",
           "hash_uniform", "picked_value", "interpolation_from", "INTERPOLATIONS", "mixture_tables"]
