"""Mitsuba 3 phase function ``hydrometeor_mixture``: the paper's Eq. 8 mixture of tabulated phases.

    P(Theta, x) = sum_s w_s(x) P_s(Theta),   w_s = beta_sca,s / sum_s' beta_sca,s'        (Eq. 8)

Each species table is held piecewise linear in the versine v = 1 - cos(Theta) on one common node
set (the union of the tables' angle grids, so forward peaks, halos and rainbows stay resolved), per
RGB channel, and normalised so that 2 pi * integral p dv = 1 exactly in that representation. The
versine keeps float32 resolution near forward (a 1 mm raindrop's diffraction peak is ~0.02 deg
wide; cos(Theta) cannot tell those angles apart in float32); in ``eval_pdf`` it is computed as
|wo + wi|^2 / 2, which is exact there too. The weights come from a grid (z, y, x, S) on the medium's
bounding box of the species' scattering coefficients beta_sca,s (any common scale), looked up trilinearly
(texel centres at (i + 0.5)/N, as Mitsuba's ``gridvolume``, clamped at the edges) and then normalised:
w_s(x) = beta_sca,s(x) / sum_s' beta_sca,s'(x), Eq. 8 of the medium whose species' coefficients are
trilinear, as its extinction (the sum of theirs) is. Interpolating normalised weights instead mixes the
phase functions of two voxels half and half wherever they meet, however unequal their scattering: on the
WRF plateau's 30 km x 585 m grid a thin ice layer's weights reached into the dense water deck beside it,
and the side-lit view's single scattering came out 1.55 times what a 4x finer grid of the same fields
gives (1.004 times with coefficients).

Sampling: pick species s with probability w_s(x), then draw v from that species' channel-mean
table: its node segment from a Walker alias table (the coin is what is left of the uniform that
chose the species), v within the segment by exact inversion of the segment's linear density (a
quadratic). ``eval_pdf`` returns the per-channel value sum_s w_s p_s,c and pdf = sum_s w_s pbar_s,
which is exactly the density the sampler draws from, so sample weights are value / pdf per channel.

Layout for speed (every scattering event costs one ``sample`` and one ``eval_pdf``):
- ``eval_pdf`` finds the node segment of v without a search over all nodes: a guide table of
  equal buckets in asinh(Theta / 1 mrad) (the tables' grids are linear in Theta near forward and
  logarithmic beyond) bounds it, and at most ``guide_steps`` (<= 3 for the shipped tables) bisection
  steps find it; ``sample`` needs no search at all (alias table). Both replaced binary searches of
  11 dependent loads each.
- The coefficients are held as S channels packed four to a 16-byte texel, so a trilinear lookup is 8
  packet loads per 4 species (``mi.Texture3f`` loads every channel of every corner separately);
  :func:`pack_weights`. Where S = 4 P + 1 (the five species), the last one may be a grid of its own
  (``weights_tail``): 4 bytes per cell for it instead of a packet of 16 that is three quarters padding.
- The table rows of all species at one node are adjacent (N x S x 4: R, G, B and channel-mean pdf,
  which is also what ``sample`` inverts), so one lookup touches two or three cache lines.
- Every table sits in 64-byte aligned memory, see :func:`_storage`.

Spectral variants (``llvm_ad_spectral``: every path carries 4 wavelengths, ``mei.wavelengths``): with
``spectral_values`` (S x N x K, the species' tables at the K uniform wavelengths ``spectral_nm``, nm; what
``kernel.medium`` passes, ``optics.phase.spectral_tables``) a lane's value is read from them, bilinear in v and
wavelength (``spectral_phase``; ``spectral_interpolation`` "stochastic": one wavelength node a lane, unbiased,
``picked_value``), and the sampler draws from the wavelengths' mean; without them the three
channels of ``values`` are the tables at the wavelengths ``channel_wavelengths`` (nm, descending: 650, 550,
450 for the R, G, B tables) and a lane's value is their linear interpolation at its wavelength, held
constant beyond the first and last (:func:`lerp_channels`), drawn from the channel mean. Each lane's weight is
value(lambda) / pdf. ``coalbedo`` (S x (K + 1): 1 - omega_s on the uniform
grid ``coalbedo_nm`` of K wavelengths, and at the reference wavelength) gives the medium's single-scattering
albedo at a lane's wavelength (:meth:`HydrometeorMixture.albedo_at`), used by ``majorant_volpath``.

Properties (Python dict scenes): ``nodes`` (TensorXf, N ascending versines 1 - cos in [0, 2]), ``values``
(TensorXf, S x N x 3, 1/sr), ``weights`` (TensorXf, z x y x x x S: beta_sca,s per voxel, >= 0; or packed as
:func:`pack_weights` makes them, z x y x x x P x 4, kept as given; with ``weights_tail``, TensorXf z x y x x,
the last species' coefficients, the packets hold the first 4 P = S - 1), ``air_weights`` (optional, TensorXf,
levels x A, or levels x A x 3 by colour channel: the box's air per level of the grid, the coefficients of the last
A of the S tables, which the grid then leaves out: ``air_levels.parse_weights``; by channel, each channel's
mixture has its own weights, as Eq. 8 holds per wavelength: molecules scatter 4x more at 450 than at 650 nm, so
inside a cloud their share differs by channel) and ``to_world`` (the bounding box as a transform of the unit cube). From XML: ``filename``, an ``.npz`` written by
:func:`save_npz` with the same arrays plus ``bbox``.
"""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

from ..jitarrays import aligned_empty, aligned_float
from . import air_levels, grid_lookup, linear_segment
from .mixture_tables import (GUIDE_THETA0, alias_table, angle_warp, channel_mean_pdf, common_nodes,  # noqa: F401
                             guide_table, prepare_tables, segment_masses)
from . import spectral_air_weights, spectral_albedo
from .spectral_phase import hash_uniform, mixture_tables, pack_pdf, picked_value, spectral_pdf, spectral_value
from .variant_class import variant_class

PLUGIN_NAME = "hydrometeor_mixture"


def pack_weights(weights: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """(z, y, x, ceil(S / 4), 4) float32: every voxel's S scattering coefficients (negative values as 0,
    infinite ones as float32's largest),
    zero-padded to whole packets of 4. A voxel where nothing scatters holds zeros, and a trilinear lookup
    weighs it by nothing, as the medium's extinction does. ``out``: a flat float32 array of their size to
    write them into (e.g. 64-byte aligned memory, ``jitarrays.aligned_empty``)."""
    w = np.asarray(weights, np.float32)
    n_species = w.shape[3]
    n_packets = max(1, -(-n_species // 4))
    shape = w.shape[:3] + (n_packets * 4,)
    out = np.empty(shape, np.float32) if out is None else out.reshape(shape)
    out[..., n_species:] = 0.0
    np.clip(w, 0.0, np.finfo(np.float32).max, out=out[..., :n_species])  # no temporary copy of the weights
    return out.reshape(w.shape[:3] + (n_packets, 4))


def unpack_weights(packed, grid_shape, n_species: int, tail=None) -> np.ndarray:
    """(z, y, x, S) float32: the coefficients of ``pack_weights``'s packets (flat or shaped) without the padding,
    followed by the ``tail`` grid's (the last species' grid of its own) where given."""
    a = np.asarray(packed, np.float32).reshape(tuple(grid_shape) + (-1,))
    if tail is None:
        return np.ascontiguousarray(a[..., :n_species])
    return np.concatenate([a[..., :n_species - 1], np.asarray(tail, np.float32).reshape(tuple(grid_shape) + (1,))],
                          axis=-1)


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
    """A flat array to gather from: mi.Float in JIT variants, a list of floats in scalar variants.

    JIT arrays come from 64-byte aligned memory (``aligned_float``): ``mi.Float(numpy_array)`` uses
    numpy's memory in place, which is only 16-byte aligned, and on an LLVM variant a source that is
    not aligned to the vector width makes Dr.Jit split every packet gather into one gather per
    channel (drjit-core ``jitc_var_gather_packet``: ``src_v->unaligned``). Which way it went changed
    from process to process with numpy's allocations; the split kernel cost up to 2x per call."""
    flat = np.ascontiguousarray(a, np.float32).ravel()
    if _is_scalar_variant():
        return flat.astype(float).tolist()
    return aligned_float(mi, flat)


def _gather(src, index):
    """src[index] for a JIT array (vectorised) or a Python list (scalar variants)."""
    if isinstance(src, list):
        return src[int(index)]
    return dr.gather(mi.Float, src, index)


def _gather2(src, index):
    """src[2 index : 2 index + 2] as a Vector2f (one packet load per lane in JIT variants)."""
    if isinstance(src, list):
        return mi.Vector2f(*src[2 * int(index): 2 * int(index) + 2])
    return dr.gather(mi.Vector2f, src, index)


def _gather4(src, index):
    """src[4 index : 4 index + 4] as a Vector4f: one packet load per lane in JIT variants."""
    if isinstance(src, list):
        return mi.Vector4f(*src[4 * int(index): 4 * int(index) + 4])
    return dr.gather(mi.Vector4f, src, index)


def channel_bracket(lam, channel_nm):
    """(above the middle channel, t_hi, t_lo) of wavelength ``lam`` (nm) between the channels ``channel_nm``
    (descending): its fraction from channel 1 to 0 (550 -> 650 nm) and from 2 to 1 (450 -> 550 nm), clipped."""
    (l0, l1, l2) = channel_nm
    return lam >= l1, dr.clip((lam - l1) / (l0 - l1), 0.0, 1.0), dr.clip((lam - l2) / (l1 - l2), 0.0, 1.0)


def lerp_channels(value, wavelengths, channel_nm):
    """Per lane of ``wavelengths`` (nm; a 4-lane Spectrum), the three channel values ``value`` (at
    ``channel_nm``, descending) interpolated linearly in wavelength, constant beyond the ends."""
    out = []
    for lane in range(4):
        red, t_hi, t_lo = channel_bracket(wavelengths[lane], channel_nm)
        out.append(dr.select(red, dr.lerp(value[1], value[0], t_hi), dr.lerp(value[2], value[1], t_lo)))
    return mi.Spectrum(*out)


class ByChannel:
    """Eq. 8 weights by colour channel: ``channels[c][s]`` species s's share of channel c's scattering, and
    ``mean[s]`` their mean over the channels (the weights of the channel-mean density directions are drawn from)."""

    def __init__(self, channels):
        self.channels = channels
        self.mean = [(channels[0][s] + channels[1][s] + channels[2][s]) * (1.0 / 3.0) for s in range(len(channels[0]))]

    def of_row(self, row):
        """The weights of table4's row ``row`` (UInt32 per lane: 0..2 a channel, 3 the channel mean)."""
        ch = self.channels
        return [dr.select(row == 0, ch[0][s], dr.select(row == 1, ch[1][s], dr.select(row == 2, ch[2][s], m)))
                for s, m in enumerate(self.mean)]


def _normalised_by_channel(w, air, n_species: int) -> ByChannel:
    """Eq. 8 per colour channel c: w_s / (sum_s w_s + sum_a air_a,c) for the grid's species (one coefficient for
    every channel) and air_a,c / (...) for the air's components (``air``: A lists of 3), 1/S where nothing
    scatters."""
    channels = []
    for c in range(3):
        wc = list(w) + [a[c] for a in air]
        total = wc[0]
        for wi in wc[1:]:
            total = total + wi
        scattering = total > 0.0
        inv = dr.rcp(dr.select(scattering, total, 1.0))
        channels.append([dr.select(scattering, wi * inv, 1.0 / n_species) for wi in wc])
    return ByChannel(channels)


def _channel_mean(w):
    """The weights of one density: the channel mean of weights by channel, or the weights as they are."""
    return w.mean if isinstance(w, ByChannel) else w


class HydrometeorMixture:
    """Eq. 8 mixture of per-species tabulated phase functions with spatially varying weights.

    The methods only: :func:`mixture_class` puts them on the ``mi.PhaseFunction`` of the current
    variant (see ``variant_class``)."""

    def __init__(self, props: mi.Properties):
        mi.PhaseFunction.__init__(self, props)
        if "filename" in props:
            data = np.load(str(props["filename"]))
            nodes, values, weights = data["nodes"], data["values"], data["weights"]
            to_world = bbox_transform(data["bbox"])
            tail = None
        else:
            nodes = np.asarray(props["nodes"], np.float32).ravel()
            values = np.asarray(props["values"], np.float32)
            weights = props["weights"]  # a TensorXf in dict scenes: kept as it is, not copied
            tail = props["weights_tail"] if "weights_tail" in props else None
            to_world = props["to_world"] if "to_world" in props else mi.ScalarTransform4f()
        # the box's air per level (``air_weights``, levels x A): the last A of the S tables, not in the grid
        self.air_weights = air_levels.parse_weights(props, int(values.shape[0]), weights.shape[0], PLUGIN_NAME)
        # spectral variants: the air's weights by wavelength (a lane's phase value; ``spectral_air_weights``)
        self.air_spectral = spectral_air_weights.parse(props, self.air_weights, PLUGIN_NAME, _storage)
        n_grid = int(values.shape[0]) - (0 if self.air_weights is None else self.air_weights.shape[1])
        if values.ndim != 3 or values.shape[1] != nodes.size or values.shape[2] != 3:
            raise ValueError(f"{PLUGIN_NAME}: 'values' must be S x N x 3 with N = len(nodes) = {nodes.size}; "
                             f"got {values.shape}")
        packets = max(1, -(-n_grid // 4))
        if tail is not None:
            packets = (n_grid - 1) // 4
            if n_grid % 4 != 1 or packets < 1 or tuple(weights.shape[3:]) != (packets, 4) or \
                    tuple(tail.shape) != tuple(weights.shape[:3]):
                raise ValueError(f"{PLUGIN_NAME}: with 'weights_tail' (z x y x x), S = 4 P + 1 and 'weights' packed "
                                 f"z x y x x x P x 4; got S = {n_grid}, {tuple(weights.shape)} and "
                                 f"{tuple(tail.shape)}")
        elif not (len(weights.shape) == 4 and weights.shape[3] == n_grid) and \
                tuple(weights.shape[3:]) != (packets, 4):
            raise ValueError(f"{PLUGIN_NAME}: 'weights' must be z x y x x x S with S = {n_grid}, or packed "
                             f"z x y x x x {packets} x 4 (pack_weights); got {tuple(weights.shape)}")
        self.n_species, self.n_grid, self.n_nodes = int(values.shape[0]), n_grid, int(nodes.size)
        self.periodic = bool(props.get("periodic", False))  # x and y wrap (a periodic medium); else clamped
        inverse = np.linalg.inv(np.array(to_world.matrix, dtype=np.float64).reshape(4, 4))
        self.to_local = mi.Transform4f(mi.ScalarTransform4f(inverse.astype(np.float32).tolist()))
        self._set_spectral_tables(props, nodes.size)
        self._set_tables(nodes, values)
        self._set_weights(weights, tail)
        self._set_spectral(props)
        if self.air_spectral is not None and self.spectral_grid is None:
            raise ValueError(f"{PLUGIN_NAME}: '{spectral_air_weights.TABLE_PROPERTY}' needs the tables by wavelength "
                             "('spectral_values', 'spectral_nm')")
        self.m_flags = mi.PhaseFunctionFlags.Anisotropic

    def _set_tables(self, nodes, values):
        # the density directions are drawn from: the mean of the channels, or (tables by wavelength) of the wavelengths
        pbar = channel_mean_pdf(nodes, values if self.spectral_values is None else self.spectral_values)
        self.nodes = _storage(nodes)
        # (N, S, 4): R, G, B value and the channel-mean pdf of every node and species, read as one packet
        table = np.concatenate([np.asarray(values, np.float32), pbar[:, :, None]], axis=2)
        self.table4 = _storage(np.transpose(table, (1, 0, 2)))
        self.spectral_pdf = None if self.spectral_values is None else _storage(pack_pdf(pbar))  # spectral_phase
        # (4, S, N - 1, 2): alias tables of the segment probabilities of every species under the density
        # of each row of table4 (R, G, B, channel mean) (prob, alias as float)
        rows = [np.asarray(values, np.float64)[:, :, c] for c in range(3)] + [pbar]
        alias = [alias_table(m) for row in rows for m in segment_masses(nodes, row)]
        self.alias2 = _storage(np.stack([np.stack([pr, al.astype(np.float64)], axis=1) for pr, al in alias]))
        # (M, 2): first and last node segment of every guide bucket (as float, exact below 2^24)
        guide, self.guide_steps = guide_table(np.asarray(nodes, np.float64))
        self.guide_buckets = int(guide.shape[0])
        self.guide2 = _storage(guide.astype(np.float64))
        self.inv_warp_norm = float(1.0 / np.arcsinh(np.pi / GUIDE_THETA0))

    def _set_weights(self, weights, tail=None):
        """Pack ``weights`` (z x y x x x S) into ``weights4``, the one copy the plugin keeps (written once into
        aligned memory on JIT variants); the ``weights`` parameter is unpacked from it when traversed. Packed
        already, with the last species' ``tail`` grid or without: both held as given."""
        self.grid_shape = tuple(int(n) for n in weights.shape[:3])
        self.n_packets = max(1, -(-int(weights.shape[3]) // 4))
        self.tail = None
        if len(weights.shape) == 5:  # packed already (``medium.phase_arrays``): held as given (in place)
            self.n_packets = int(weights.shape[3])
            self.weights4 = _storage(np.asarray(weights)) if _is_scalar_variant() else weights.array
            if tail is not None:
                self.tail = _storage(np.asarray(tail)) if _is_scalar_variant() else tail.array
        elif _is_scalar_variant():
            self.weights4 = _storage(pack_weights(weights))
        else:
            flat = aligned_empty(int(np.prod(self.grid_shape)) * 4 * self.n_packets)
            pack_weights(weights, out=flat)
            self.weights4 = mi.Float(flat)
        self.weights = None
        self.air_w = None if self.air_weights is None else _storage(self.air_weights)

    def _set_spectral_tables(self, props, n_nodes: int):
        """Spectral variants with ``spectral_values`` and ``spectral_nm``: the phase tables by wavelength
        (``spectral_phase.mixture_tables``); else None (R, G, B interpolated)."""
        for key, value in mixture_tables(props, self.n_species, n_nodes, PLUGIN_NAME, _storage).items():
            setattr(self, key, value)

    def _set_spectral(self, props):
        """Spectral variants: the channels' wavelengths (nm) and the species' co-albedo spectra."""
        self.spectral = bool(mi.is_spectral)
        self.channel_nm = [float(v) for v in np.asarray(props.get("channel_wavelengths", [650.0, 550.0, 450.0]),
                                                         np.float64).ravel()]
        if len(self.channel_nm) != 3 or not self.channel_nm[0] > self.channel_nm[1] > self.channel_nm[2]:
            raise ValueError(f"{PLUGIN_NAME}: 'channel_wavelengths' must be 3 descending wavelengths (nm), "
                             f"got {self.channel_nm}")
        self.coalbedo = None
        if "coalbedo" not in props:
            return
        c = np.asarray(props["coalbedo"], np.float32)
        grid = np.asarray(props["coalbedo_nm"], np.float64).ravel()
        if c.ndim != 2 or c.shape[0] != self.n_species or c.shape[1] != grid.size + 1 or grid.size < 2 \
                or not np.allclose(np.diff(grid), grid[1] - grid[0]) or not (c.min() >= 0 and c.max() <= 1):
            raise ValueError(f"{PLUGIN_NAME}: 'coalbedo' must be S x (K + 1) in [0, 1] with S = {self.n_species} "
                             f"and K the wavelengths of the uniform grid 'coalbedo_nm' (K >= 2); got {c.shape}, "
                             f"{grid.size}")
        self.coalbedo = _storage(spectral_albedo.pack_coalbedo(c))
        self.coalbedo_grid = (float(grid[0]), float(1.0 / (grid[1] - grid[0])), int(grid.size))

    # ------------------------------------------------------------ helpers
    def _at_wavelengths(self, value, mei):
        """The phase value as the variant's Spectrum: the R, G, B channels as they are (RGB variants), or
        each lane's interpolation at its wavelength (spectral: :func:`lerp_channels`)."""
        if not self.spectral:
            return mi.Spectrum(value)
        return lerp_channels(value, mei.wavelengths, self.channel_nm)

    def albedo_at(self, mei, albedo_ref):
        """The mixture's single-scattering albedo at the lanes' wavelengths (spectral variants with
        ``coalbedo``), from the medium's albedo at the reference wavelength ``albedo_ref`` (Float):
        1 - (1 - albedo_ref) sum_s w_s c_s(lambda) / sum_s w_s c_s(ref), c_s the species' co-albedo spectra
        (``optics.spectral``) and w_s their scattering weights (extinction weights to within the co-albedo,
        <= 1e-3): the medium's own albedo at the reference, the species' mix of spectral shapes elsewhere
        (``spectral_albedo``)."""
        return spectral_albedo.albedo_at(self.coalbedo, self.coalbedo_grid, self.n_species,
                                         _channel_mean(self._weights_at(mei)),
                                         mei.wavelengths, albedo_ref, _gather4)

    def _weights_at(self, mei):
        """w_s(x) for s = 0..S-1: the coefficients trilinear on the bbox grid (texel centres at
        (i + 0.5) / n, clamped at the edges), normalised to sum to 1 (1/S each where none scatters)."""
        if self.n_species == 1:
            return [mi.Float(1.0)]  # renormalised weights of one species are 1: no lookup
        p = self.to_local @ mei.p
        nz, ny, nx = self.grid_shape
        corner, frac = grid_lookup.corners(p, self.grid_shape, self.periodic)
        z0, z1 = corner[0]
        fz = frac[0]
        npk = self.n_packets
        lerp = grid_lookup.lerp

        def trilinear(texel):  # the same operations on a packet of 4 and on one value (the tail)
            return grid_lookup.trilinear(texel, corner, frac)

        w = []
        for k in range(npk):
            v = trilinear(lambda z, y, x: _gather4(self.weights4, mi.UInt32(((z * ny + y) * nx + x) * npk + k)))
            w += [dr.maximum(v[c], 0.0) for c in range(4)]
        if self.tail is not None:
            w.append(dr.maximum(trilinear(lambda z, y, x: _gather(self.tail, mi.UInt32((z * ny + y) * nx + x))), 0.0))
        w = w[: self.n_grid]
        if self.air_weights is not None:  # constant in x and y: the trilinear lookup is the levels' lerp in z
            n_a, n_c = self.air_weights.shape[1:]
            air = [[lerp(_gather(self.air_w, mi.UInt32((z0 * n_a + a) * n_c + c)),
                         _gather(self.air_w, mi.UInt32((z1 * n_a + a) * n_c + c)), fz) for c in range(n_c)]
                   for a in range(n_a)]
            if n_c == 3:
                return _normalised_by_channel(w, air, self.n_species)
            w += [a[0] for a in air]
        total = w[0]
        for wi in w[1:]:
            total = total + wi
        scattering = total > 0.0
        inv = dr.rcp(dr.select(scattering, total, 1.0))
        out = [dr.select(scattering, wi * inv, 1.0 / self.n_species) for wi in w]
        if self.air_spectral is not None:  # the point's levels, for the air's weights by wavelength
            return spectral_air_weights.Weights(out, (z0, z1, fz, inv, scattering))
        return out

    def _segment(self, v):
        """Node index i with v_i <= v < v_i+1 and the linear weight t in [0, 1]: the guide bucket of
        v (:func:`angle_warp`) bounds i, and a few bisection steps find it (no loop, no search over
        all nodes)."""
        theta = 2.0 * dr.asin(dr.clip(dr.sqrt(dr.maximum(0.5 * v, 0.0)), 0.0, 1.0))
        m = self.guide_buckets
        j = mi.UInt32(dr.clip(dr.asinh(theta * (1.0 / GUIDE_THETA0)) * (self.inv_warp_norm * m), 0.0, m - 1.0))
        bounds = _gather2(self.guide2, j)
        lo, hi = mi.UInt32(bounds[0]), mi.UInt32(bounds[1])
        for _ in range(self.guide_steps):
            mid = (lo + hi + 1) >> 1
            below = _gather(self.nodes, mid) <= v
            lo = dr.select(below, mid, lo)
            hi = dr.select(below, hi, mid - 1)
        v0 = _gather(self.nodes, lo)
        v1 = _gather(self.nodes, lo + 1)
        t = dr.clip((v - v0) / dr.maximum(v1 - v0, 1e-30), 0.0, 1.0)
        return lo, t

    def _mix_at(self, w, idx, t, mei, wo):
        """(the variant's Spectrum value, pdf) of the mixture: :meth:`_mix`'s channels (at the lanes'
        wavelengths in spectral variants), or the tables by wavelength (``spectral_phase``) where given: bilinear,
        or with ``spectral_interpolation`` "stochastic" one wavelength node a lane (its pick hashed from the
        vertex and ``wo``: ``picked_value``)."""
        if self.spectral_grid is None:
            value, pdf = self._mix(w, idx, t)
            return self._at_wavelengths(value, mei), pdf
        w = _channel_mean(w)  # (a spectral variant's air weights are one value: ``Weights`` as they are)
        lane_w = None if self.air_spectral is None else \
            spectral_air_weights.by_lane(self.air_spectral, w, mei.wavelengths, _gather4)  # the value's, by wavelength
        tables = (self.spectral_grid, self.n_species, w, idx, t, mei.wavelengths)
        flat = (self.spectral_flat, self.spectral_flat_table)
        value = spectral_value(self.spectral_table, *tables, _gather4, lane_w, *flat) if self.spectral_codes is None \
            else picked_value(self.spectral_codes, *tables, hash_uniform(mei.p, wo), _gather4, lane_w, *flat)
        return value, spectral_pdf(self.spectral_pdf, self.n_species, w, idx, t, _gather4)

    def _mix(self, w, idx, t):
        """(per-channel value, pdf) of the mixture with weights w in node segment idx at fraction t (weights by
        channel, ``_normalised_by_channel``: each channel's value with its own, the pdf, of the channel-mean
        density the sampler draws from, with their means)."""
        value = [mi.Float(0.0), mi.Float(0.0), mi.Float(0.0)]
        pdf = mi.Float(0.0)
        n_s = self.n_species
        by_channel = isinstance(w, ByChannel)
        w_mean = w.mean if by_channel else w
        for s in range(n_s):
            k = idx * n_s + s
            f0 = _gather4(self.table4, k)
            f = f0 + (_gather4(self.table4, k + n_s) - f0) * t
            for c in range(3):
                value[c] += (w.channels[c][s] if by_channel else w[s]) * f[c]
            pdf += w_mean[s] * f[3]
        return mi.Color3f(value[0], value[1], value[2]), pdf

    # ------------------------------------------------------------ PhaseFunction interface
    def sample(self, ctx, mei, sample1, sample2, active=True):
        wo, value, pdf, _ = self._sample(mei, mi.UInt32(3), sample1, sample2)
        if self.spectral_grid is None:
            weight = dr.select(pdf > 0.0, value / pdf, 0.0)
            return wo, self._at_wavelengths(weight, mei), pdf
        return wo, dr.select(pdf > 0.0, value / pdf, 0.0), pdf  # the lanes' values already

    def sample_channel(self, ctx, mei, channel, sample1, sample2, active=True, densities=False):
        """A direction drawn from colour channel ``channel``'s density (UInt32 per lane, 0..2: the
        mixture sum_s w_s p_s,c) instead of the channel mean, and the per-channel value there (1/sr).
        For history-aware channel sampling in ``majorant_volpath``, which computes the pdf itself; with
        ``densities`` also the three channels' densities at the direction (Color3f, 1/sr; the pdf's terms,
        from the draw's own weights and node segment: ``lane_channels.continuation_pdf``)."""
        wo, value, _, (w, idx, t) = self._sample(mei, mi.UInt32(channel), sample1, sample2)
        value = value if self.spectral_grid is not None else self._at_wavelengths(value, mei)
        return (wo, value, mi.Color3f(self._mix(w, idx, t)[0])) if densities else (wo, value)

    def _sample(self, mei, row, sample1, sample2):
        """(wo, per-channel value, channel-mean pdf, (weights, node segment, fraction)) of a direction drawn
        from the density in ``row`` of table4 (0..2: a colour channel; 3: the channel mean)."""
        w = self._weights_at(mei)
        # the weights of the row's density: by channel, that channel's (row 0..2) or their mean (row 3)
        w_row = w.of_row(row) if isinstance(w, ByChannel) else w
        # species s with probability w_s (sample1); what is left of sample1 (uniform) is the coin of
        # the alias table
        species = mi.UInt32(0)
        acc, lower, w_sel = mi.Float(0.0), mi.Float(0.0), w_row[0]
        for s in range(self.n_species - 1):
            acc += w_row[s]
            above = sample1 >= acc
            species += mi.UInt32(dr.select(above, 1, 0))
            lower = dr.select(above, acc, lower)
            w_sel = dr.select(above, w_row[s + 1], w_sel)
        coin = dr.clip((sample1 - lower) / dr.maximum(w_sel, 1e-30), 0.0, 1.0)
        # node segment of that species from its alias table (sample2.x picks the bucket; what is
        # left of it, uniform and independent of the choice, places v within the segment)
        n_seg = self.n_nodes - 1
        u = sample2.x * n_seg
        j = mi.UInt32(dr.clip(u, 0.0, n_seg - 1.0))
        r = dr.clip(u - mi.Float(j), 0.0, 1.0)
        entry = _gather2(self.alias2, (row * self.n_species + species) * n_seg + j)
        idx = dr.select(coin < entry[0], j, mi.UInt32(entry[1]))
        k = (idx * self.n_species + species) * 4 + row  # this row's density of the species at node idx
        v0 = _gather(self.nodes, idx)
        v1 = _gather(self.nodes, idx + 1)
        f0 = _gather(self.table4, k)
        f1 = _gather(self.table4, k + 4 * self.n_species)
        v, t = linear_segment.invert(v0, v1, f0, f1, r)  # v within the segment, from its linear density
        wo = linear_segment.direction(mei, v, sample2.y)
        # value and pdf where v was drawn: same weights, same segment (no search, no second lookup)
        if self.spectral_grid is not None:  # the lanes' values from the tables by wavelength
            value, pdf = self._mix_at(w, idx, t, mei, wo)
        else:
            value, pdf = self._mix(w, idx, t)
        return wo, value, pdf, (w, idx, t)

    def eval_pdf(self, ctx, mei, wo, active=True):
        h = wo + mei.wi  # |wo + wi|^2 = 2 (1 - cos Theta): accurate near forward
        idx, t = self._segment(0.5 * dr.squared_norm(h))
        return self._mix_at(self._weights_at(mei), idx, t, mei, wo)

    def traverse(self, cb):
        if self.weights is None:  # the parameter as given (negative values as 0), from the packed copy
            tail = None if self.tail is None else np.asarray(self.tail, np.float32)
            self.weights = mi.TensorXf(unpack_weights(self.weights4, self.grid_shape, self.n_grid, tail))
        cb.put("weights", self.weights, mi.ParamFlags.NonDifferentiable)

    def parameters_changed(self, keys=None):
        if keys and "weights" not in keys:
            return
        w = np.array(self.weights, np.float32).reshape(tuple(self.weights.shape))
        if w.ndim != 4 or w.shape[3] != self.n_grid:
            raise ValueError(f"{PLUGIN_NAME}: 'weights' must be z x y x x x S with S = {self.n_grid}; "
                             f"got {w.shape}")
        self._set_weights(w)  # repacked

    def to_string(self):
        return (f"HydrometeorMixture[species={self.n_species}, nodes={self.n_nodes}, "
                f"weights grid={self.grid_shape}]")


def mixture_class() -> type:
    """The ``hydrometeor_mixture`` phase-function class of the current Mitsuba variant."""
    return variant_class(HydrometeorMixture, "PhaseFunction")


def register() -> None:
    """Register ``hydrometeor_mixture`` with the current Mitsuba variant."""
    cls = mixture_class()
    mi.register_phase(PLUGIN_NAME, lambda props: cls(props))
