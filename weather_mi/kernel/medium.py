"""Mitsuba dictionaries for an OpticalVolume: the ``heterogeneous`` medium (extinction grid, albedo
grid) with the ``hydrometeor_mixture`` phase function (Eq. 8) on the volume's bounding box."""
from __future__ import annotations

import numpy as np

from ..optics.forward_peak import is_grey
from ..optics.periodic import pad_levels, padded_bbox
from ..optics.scattering_coefficients import scattering_coefficients
from ..optics.volume import OpticalVolume
from .kept import Kept, digest
from .jitarrays import aligned_empty
from .variant import ensure_registered


def phase_arrays(vol: OpticalVolume, packed: bool = False):
    """(nodes v = 1 - cos (N,), values (S, N, 3), weights (z, y, x, S)) as the plugin takes them: the
    species' scattering coefficients beta_sca,s = w_s beta omega (1/m; w_s the Eq. 8 weights, beta omega the
    voxel's scattering coefficient, channel mean), which the plugin interpolates and then normalises.
    ``packed``: the weights as the plugin keeps them (``hydrometeor_mixture.pack_weights``: (z, y, x, P, 4),
    zero-padded packets of 4), written once into 64-byte aligned memory that a JIT variant uses in place.
    With the air in the box (``air_in_medium``) its two components follow the species (``optics.air.inside``)."""
    from .plugins.hydrometeor_mixture import pack_weights
    air = air_in_medium(vol)
    nodes, values = phase_arrays_tables(vol)
    if air is not None:
        from ..optics.air.inside import medium_grids
        coeffs = medium_grids(vol.beta_total, vol.albedo, vol.weights, air, want=("coeffs",))[2]
        if not packed:
            return nodes, values, coeffs
        lanes = 4 * max(1, -(-coeffs.shape[-1] // 4))
        return nodes, values, pack_weights(coeffs, out=aligned_empty(coeffs[..., 0].size * lanes))
    return _hydrometeor_arrays(vol, nodes, values, packed)


def _hydrometeor_arrays(vol: OpticalVolume, nodes=None, values=None, packed: bool = True):
    """``phase_arrays`` of the hydrometeors alone (without the box's air's components)."""
    from .plugins.hydrometeor_mixture import pack_weights
    n_s, shape = len(vol.weights), tuple(vol.beta_total.shape)
    lanes = 4 * max(1, -(-n_s // 4)) if packed else n_s
    weights = aligned_empty(int(np.prod(shape)) * lanes).reshape(shape + (lanes,))
    flat = weights.reshape(-1, lanes)
    scattering_coefficients(vol.beta_total, vol.albedo, vol.weights, [flat[:, s] for s in range(n_s)])
    if not packed:
        return nodes, values, weights
    return nodes, values, pack_weights(weights[..., :n_s], out=weights)  # in place: padding 0, clipped


def kernel_weights(vol: OpticalVolume, air_in_grid: bool = True):
    """(packets (z, y, x, P, 4), tail (z, y, x) or None): the plugin's coefficients as ``phase_dict`` hands them,
    in 64-byte aligned memory: the hydrometeors' alone (the box's air, one value per level, goes to the plugin
    as ``air_weights``: :func:`air_weights`) unless ``air_in_grid``. S = 4 P + 1 species without the air in the
    grid (the five hydrometeors): the last species' grid of its own (``weights_tail``: 20 bytes per cell for
    five, not 32); otherwise ``phase_arrays(packed=True)``'s padded packets and no tail. The same values either
    way."""
    n_s = len(vol.weights)
    if (air_in_grid and air_in_medium(vol) is not None) or n_s % 4 != 1 or n_s == 1:
        return (phase_arrays(vol, packed=True) if air_in_grid else _hydrometeor_arrays(vol))[2], None
    shape, n = tuple(vol.beta_total.shape), int(np.prod(vol.beta_total.shape))
    packets = aligned_empty(n * (n_s - 1)).reshape(-1, n_s - 1)
    tail = aligned_empty(n)
    scattering_coefficients(vol.beta_total, vol.albedo, vol.weights, [packets[:, s] for s in range(n_s - 1)] + [tail])
    from .plugins.hydrometeor_mixture import pack_weights
    packets = pack_weights(packets.reshape(shape + (n_s - 1,)), out=packets)  # in place (whole packets: no padding)
    np.clip(tail, 0.0, np.finfo(np.float32).max, out=tail)  # as pack_weights clips, in place (not padded to 4)
    return packets, tail.reshape(shape)


def air_weights(air) -> np.ndarray:
    """``hydrometeor_mixture``'s ``air_weights``: the Eq. 8 scattering coefficients of the air's two components per
    level (1/m), (levels, 2, 3) by colour channel: Eq. 8 holds per wavelength, and in a cloud the molecules'
    share of the scattering is ~4x larger at 450 than at 650 nm (with channel means the cloud's blue was ~3% too
    dark and its red ~5% too bright under a Rayleigh column, ``tests/test_clear_sky_disort.py``); (levels, 2) where
    the channels are equal (a satellite's single band, :func:`grey_air`)."""
    sca = np.asarray(air.scattering_levels, np.float32)  # (2, levels, channels)
    if grey_air(air):
        return np.ascontiguousarray(sca.mean(axis=-1).T)
    return np.ascontiguousarray(np.transpose(sca, (1, 0, 2)))


def integrator_air_albedo(vol: OpticalVolume, air) -> dict:
    """``majorant_volpath``'s ``air_albedo`` (the hydrometeors' albedo grid, (z, y, x, C), the volume's own array,
    used in place: one channel where its three agree, a satellite band's, :func:`grey_or_rgb`, not a copy of the
    three; levels padded where periodic) and ``air_scattering`` (the air's scattering per level and channel,
    molecules and aerosol summed, 1/m) (``kernel.plugins.air_albedo``)."""
    import mitsuba as mi
    albedo = np.asarray(vol.albedo)
    albedo = grey_or_rgb(albedo) if albedo.ndim == 4 else albedo[..., None]
    sca = air.scattering_levels.sum(axis=0)
    if vol.periodic:
        albedo, sca = pad_levels(albedo), pad_levels(sca)
    return {"air_albedo": mi.TensorXf(np.ascontiguousarray(albedo, np.float32)),
            "air_scattering": mi.TensorXf(np.ascontiguousarray(sca, np.float32))}


def air_by_integrator(integrator: dict) -> bool:
    """Whether the integrator of this dict adds the box's air per level itself (``majorant_volpath``: the medium's
    grids then hold the hydrometeors' extinction and coefficients alone); stock ``volpath`` needs it in them."""
    return integrator.get("type") == "majorant_volpath"


def air_in_medium(vol: OpticalVolume):
    """The air in the box (``OpticalVolume.air``, ``optics.air.inside.BoxAir``) where the medium holds it; None
    without air. Spectral variants take it over wavelength, added per level by ``majorant_volpath``
    (``kernel.spectral_air``)."""
    return getattr(vol, "air", None)


def _spectral_air_in_grid(air, air_in_grid: bool) -> None:
    """A ValueError for the box's air in the grids (stock ``volpath``) in a spectral variant: its grids are RGB."""
    import mitsuba as mi
    if air is not None and air_in_grid and mi.is_spectral:
        raise ValueError(f"the box's air in {mi.variant()!r} is added per level by majorant_volpath; stock volpath's "
                         "grids hold it at 650 / 550 / 450 nm only (use integrator 'majorant', or no atmosphere)")


def grey_air(air) -> bool:
    """Whether the box's air has one extinction in every channel at every level (a satellite's single band: its
    three channels the same wavelength): the medium's extinction is then grey (one channel), which the trackers
    follow without spectral tracking and interpolate from the texels (issue 38 part 5)."""
    from .plugins.air_levels import equal_channels
    return equal_channels(np.asarray(air.extinction_levels))


def medium_extinction(vol: OpticalVolume) -> np.ndarray:
    """The medium's sigma_t grid (1/m): grey (z, y, x), or (z, y, x, 3) with the air in the box ((z, y, x, 1) with
    a grey air, :func:`grey_air`: the same float32 sums as its three equal channels)."""
    from ..optics.air.inside import medium_extinction as with_air
    air = air_in_medium(vol)
    if air is None:
        return vol.beta_total
    if grey_air(air):  # Eq. 4 plus the air's, one channel
        return np.asarray(vol.beta_total, np.float32)[..., None] + air.extinction_levels[:, None, None, :1]
    return with_air(vol.beta_total, air)


def grid_bbox(vol: OpticalVolume):
    """The box of the kernel's grids: the volume's, or for a periodic volume grown by the copied bottom and
    top levels (``optics.periodic.pad_levels``)."""
    return padded_bbox(vol.bbox, vol.shape[0]) if vol.periodic else vol.bbox


def phase_dict(vol: OpticalVolume) -> dict:
    """``hydrometeor_mixture`` phase function for ``vol`` (periodic: x and y wrapped, levels padded); the box's
    air per level and colour channel (``air_weights``), whichever integrator reads the medium's grids."""
    import mitsuba as mi
    from .plugins.hydrometeor_mixture import bbox_transform
    ensure_registered()
    nodes, values = phase_arrays_tables(vol)
    weights, tail = kernel_weights(vol, air_in_grid=False)
    air = air_in_medium(vol)
    if vol.periodic:
        weights, tail = (None if a is None else _aligned_copy(pad_levels(a)) for a in (weights, tail))
    if air is not None:
        d_air = air_weights(air)
        if mi.is_spectral and d_air.ndim == 3:  # the density directions are drawn from; by wavelength: spectral_air
            d_air = np.ascontiguousarray(d_air.mean(axis=-1))
        d_air = {"air_weights": mi.TensorXf(np.ascontiguousarray(pad_levels(d_air)) if vol.periodic else d_air)}
    d = {"type": "hydrometeor_mixture", "nodes": mi.TensorXf(nodes[:, None]), "values": mi.TensorXf(values),
         "weights": mi.TensorXf(weights),  # packed, used in place (llvm)
         "to_world": bbox_transform(grid_bbox(vol))}
    if tail is not None:
        d["weights_tail"] = mi.TensorXf(tail)
    if air is not None:
        d.update(d_air)
    if vol.periodic:
        d["periodic"] = True
    if mi.is_spectral:
        d.update(spectral_phase_properties(vol, nodes))
        if air is not None:  # the air's weights by wavelength (the hydrometeors' are grey)
            from .spectral_air import phase_properties
            d.update(phase_properties(vol, air))
    return d


def phase_arrays_tables(vol: OpticalVolume):
    """(nodes, values) of ``phase_arrays``: the species' tables (and the box's air's) as the plugin takes them."""
    from .plugins.hydrometeor_mixture import prepare_tables
    air = air_in_medium(vol)
    return prepare_tables(tuple(vol.require_phase_tables()) + (tuple(air.phase_tables) if air is not None else ()))


def _aligned_copy(a: np.ndarray) -> np.ndarray:
    out = aligned_empty(a.size).reshape(a.shape)
    out[...] = a
    return out


def grey_or_rgb(albedo: np.ndarray) -> np.ndarray:
    """The albedo grid (z, y, x, 3) as the medium takes it: one channel (z, y, x, 1) where the three agree
    everywhere (a satellite band's), which a gridvolume holds as given, where three channels it copies."""
    a = np.asarray(albedo)
    if is_grey(a):  # one channel seen three times: that channel, in place
        return a[..., :1]
    for c in (1, 2):
        for k in range(a.shape[0]):  # a level at a time: no whole-grid temporaries
            if not np.array_equal(a[k, ..., 0], a[k, ..., c]):
                return a
    return np.ascontiguousarray(a[..., :1])


def spectral_phase_properties(vol: OpticalVolume, nodes=None) -> dict:
    """Spectral variants: the species' co-albedo spectra (``optics.spectral``), where the volume knows its
    species (none for raw optics: the albedo is then grey at its 550 nm value), and with the mixture's versine
    ``nodes`` its phase tables by wavelength (:func:`spectral_phase_values`), each lane reading one of its two
    bracketing wavelength nodes at random (``spectral_interpolation`` "stochastic": the bilinear value in
    expectation, ``kernel.plugins.spectral_phase.picked_value``)."""
    import mitsuba as mi
    from ..optics.spectral import COALBEDO_NM, coalbedo_table
    species = vol.components or ([vol.species_set[n] for n in vol.species] if vol.species_set is not None else None)
    d = {}
    if nodes is not None and vol.phase_tables is not None:
        from ..optics.phase.spectral_tables import SPECTRAL_NM
        d = {"spectral_values": mi.TensorXf(spectral_phase_values(vol, nodes, species)),
             "spectral_nm": mi.TensorXf(SPECTRAL_NM.astype(np.float32)), "spectral_interpolation": "stochastic"}
    if species is None:
        return d
    c = coalbedo_table(species)
    air = air_in_medium(vol)
    if air is not None:  # the air's components absorb nothing here: its albedo is kernel.plugins.spectral_air_albedo's
        c = np.concatenate([c, np.zeros((len(air.phase_tables), c.shape[1]))])
    return {**d, "coalbedo": mi.TensorXf(c.astype(np.float32)),
            "coalbedo_nm": mi.TensorXf(COALBEDO_NM.astype(np.float32))}


def spectral_phase_values(vol: OpticalVolume, nodes, species=None) -> np.ndarray:
    """(S, N, K) float32: the species' phase tables at ``optics.phase.spectral_tables.SPECTRAL_NM`` on the
    mixture's versine ``nodes``. Mie and the ice recipe by wavelength where ``species`` (objects, in the volume's
    order) are known hydrometeors in the volume's phase mode; otherwise the volume's R, G, B table linear in
    wavelength. A delta-M scaled volume (``optics.forward_peak``: ``forward_peak_deg`` and each species'
    ``forward_peak_fraction`` in its attrs) has every wavelength's table truncated with the species' fraction."""
    from ..optics.forward_peak import truncated_table
    from ..optics.phase.spectral_tables import SPECTRAL_NM, stacks_for
    from .plugins.spectral_phase import prepare_spectral
    tables = vol.require_phase_tables()
    cone = vol.attrs.get("forward_peak_deg")
    fractions = vol.attrs.get("forward_peak_fraction", {})
    own = [None] * len(tables) if species is None or vol.phase_mode not in ("per_species", "paper") else list(species)
    # the fallback (lerp_stack) takes the volume's tables as they are: truncated already where the volume is
    stacks = stacks_for(own, tables, vol.phase_mode, vol.phase_quality, vol.components is not None, SPECTRAL_NM)
    cut = [float(fractions.get(n, 0.0)) if cone and sp is not None else 0.0 for sp, n in zip(own, vol.species)]
    air = air_in_medium(vol)
    if air is not None:  # the air's two components after the species (``kernel.spectral_air``)
        from .spectral_air import air_stacks
        stacks = list(stacks) + air_stacks(air, SPECTRAL_NM)

    def make():  # the delta-M truncation and the node resampling, once per digest
        cut_stacks = [[truncated_table(t, cone, f) for t in stack] if f > 0 else stack
                      for stack, f in zip(stacks, cut + [0.0] * (len(stacks) - len(cut)))]
        return prepare_spectral(nodes, cut_stacks)
    return _SPECTRAL_VALUES.get(_tables_digest(stacks, (cone, cut), nodes), make).copy()


# :func:`spectral_phase_values`' results by :func:`_tables_digest` (S N K float32: ~1 MB for 7 species, 1828 nodes,
# 21 nm): a volume's tables are made anew per render; their delta-M truncation and the node resampling, ~0.2 s for
# the demo's 5 species at 21 wavelengths, then run once
_SPECTRAL_VALUES = Kept(4)


def _tables_digest(stacks, extra, nodes) -> str:
    """The digest of what :func:`spectral_phase_values` computes from: the tables' angles, values and wavelengths,
    ``extra`` (the truncation) and ``nodes``."""
    arrays = [np.ascontiguousarray(np.asarray(a, np.float64)) for stack in stacks for t in stack
              for a in (t.theta, t.values, t.wavelengths_m)]
    return digest(extra, [len(stack) for stack in stacks], *arrays, np.ascontiguousarray(np.asarray(nodes, np.float64)))


def medium_dict(vol: OpticalVolume, air_in_grid: bool = True) -> dict:
    """``heterogeneous`` medium: sigma_t = beta_total (1/m, grey), RGB albedo, mixture phase, all on
    the volume's bounding box (grids indexed [z, y, x, channel], last axis world x). A periodic volume's
    grids wrap in x and y (``wrap_mode`` repeat; their levels padded: ``optics.periodic``).

    With the air in the box (``air_in_medium``) the phase takes the air's Eq. 8 weights per level and colour
    channel (``air_weights``; :func:`phase_dict`). With ``air_in_grid`` (for stock ``volpath``) the sigma_t grid
    (RGB) and the albedo grid are the mixture's of the hydrometeors and the air
    (``optics.air.inside.medium_grids``; the grid volume blends its texels' mixture albedos, stock volpath's only
    way, which at a cloud's edge in absorbing air gives the cloud the air's albedo); otherwise the air is one value per level that ``majorant_volpath``
    adds (``air_extinction``; :func:`air_by_integrator`): the sigma_t grid stays the hydrometeors' grey one, used
    in place, the weights their 20 bytes per cell, and the medium holds no albedo grid (a constant 1, unread): the
    integrator reads the hydrometeors' in place and mixes in the air's point-wise (:func:`integrator_air_albedo`)."""
    import mitsuba as mi
    from .plugins.hydrometeor_mixture import bbox_transform
    to_world = bbox_transform(grid_bbox(vol))
    beta, albedo = vol.beta_total[..., None], vol.albedo
    air = air_in_medium(vol)
    _spectral_air_in_grid(air, air_in_grid)
    if air is not None and air_in_grid:  # RGB extinction (molecules ~ lambda^-4) and albedo of the cloud and the air
        from ..optics.air.inside import medium_grids
        grey = grey_air(air)  # one extinction channel: no 3-channel sigma_t grid built (medium_extinction's)
        beta, albedo, _ = medium_grids(vol.beta_total, vol.albedo, vol.weights, air,
                                       want=("albedo",) if grey else ("sigma_t", "albedo"))
        beta = medium_extinction(vol) if grey else beta
    if air is not None and not air_in_grid:  # majorant_volpath's: the albedo its (``integrator_air_albedo``)
        albedo = None
    elif mi.is_spectral:  # the 550 nm albedo, made spectral by the phase function (``spectral_phase_properties``)
        albedo = np.ascontiguousarray(albedo[..., 1:2])
    else:
        albedo = grey_or_rgb(albedo)
    wrap = {}
    if vol.periodic:
        beta, albedo, wrap = pad_levels(beta), None if albedo is None else pad_levels(albedo), {"wrap_mode": "repeat"}
    # accel False: on CUDA the grids' hardware texture units interpolate with 8-bit weights, while
    # majorant_volpath's trackers interpolate the same texels in float32 (weather_mi/kernel/plugins/dda.py): one medium for
    # both only in software. LLVM has no texture units: no effect there.
    return {
        "type": "heterogeneous",
        "sigma_t": {"type": "gridvolume", "data": mi.TensorXf(beta),
                    "to_world": to_world, "filter_type": "trilinear", "accel": False, **wrap},
        "albedo": 1.0 if albedo is None else {"type": "gridvolume", "data": mi.TensorXf(albedo), "to_world": to_world,
                                              "filter_type": "trilinear", "accel": False, **wrap},
        "scale": 1.0,
        "has_spectral_extinction": air is not None and air_in_grid and beta.shape[-1] > 1,
        "phase": phase_dict(vol),
    }
