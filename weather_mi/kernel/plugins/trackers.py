"""The trackers of ``majorant_volpath``: free flights and transmittance along a ray over grids of local
majorants, walked cell by cell with the DDA (:mod:`.dda`), empty cubes of cells crossed in one step.

* :func:`delta_tracking`: free flights. In each cell an exponential step is drawn with that cell's
  majorant; a step that leaves the cell restarts at the cell exit with the next cell's majorant
  (memorylessness). At a tentative collision the collision is real with probability sigma_t / majorant;
  with spectral extinction by history-aware spectral tracking (Kutz et al. 2017).
* :func:`ratio_tracking`: transmittance estimates (Novak et al. 2014), Russian roulette once small.
* :func:`exact_transmittance`: T = exp(-tau), tau integrated exactly by Simpson's rule per texel cell
  (the trilinear interpolant is a cubic along a ray there), with Russian roulette in a render.

The box's air added per level to a grey grid (:mod:`.air_levels`; render's and ``satellite``'s default) costs the
loops little: the walks interpolate the grey grid's texels and add the air's level values; exact transmittance
takes the air's optical depth of the whole segment in closed form once (the air is horizontally homogeneous, the
ray straight), its loop the hydrometeors' alone (a grey air, and the spectral variants' air at the ray's
wavelengths, :func:`_air_on_grey_grid`); the RGB mode's chromatic air's free flights and ratio tracking follow its
largest channel, grey (sigma_g = the hydrometeors' + the air's largest), the channels weighted in closed form by
its excess e_c = sigma_c - sigma_g <= 0 (:func:`_excess_weight`): exp(-integral e_c) over the flight, times
sigma_c / sigma_g at a real collision: the density and escape probability drawn with sigma_g become sigma_c's.

Every function takes the per-render :class:`.medium_setup.Tracking` ``tk``; distances are along the ray.
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .dda import cell_end, cell_interpolant, cell_of, dda_step, locate, ray_box
from .medium_setup import sigma_t_at
from .spectral_air import bind_air

RR_THRESHOLD = 0.1    # ratio tracking: roulette once max(T) drops below this ...
RR_SURVIVE = 0.5      # ... surviving with this probability
EXACT_RR_TAU = 4.6    # exact transmittance in a render: Russian roulette once T < e^-4.6 = 0.01 ...
EXACT_RR_STEP = 2.3   # ... and again each time it falls by another factor e^2.3 = 10 ...
EXACT_RR_SURVIVE = 0.3  # ... surviving with this probability (1: no roulette, stop at TAU_ZERO)
TAU_ZERO = 50.0       # exact transmittance: 0 beyond this optical depth (e^-50 ~ 2e-22)


class _Walk:
    """A ray in a grid's coordinates: q(t) = q0 + dq t, the DDA state where it enters the grid's box
    within [0, t_end] (``cells``, ``nexts``, ``t_near``), ``t_max`` where it leaves, ``active`` where it
    meets the box; ``air`` the grid's air at the ray's wavelengths (``spectral_air.bind_air``)."""

    def __init__(self, tk, grid, texels, ray, t_end, active, tile_only=None, split_air: bool = False):
        self.tk, self.grid, self.texels, self.ray = tk, grid, texels, ray
        self.air = bind_air(grid.air, ray.wavelengths)
        self.bound_air = None if self.air is grid.air else self.air  # spectral: for the medium's lookups too
        o_l, d_l, self.t_near, self.t_max, self.active = ray_box(tk.to_local, ray, t_end, active, tk.bounds(tile_only))
        self.met = mi.Bool(active) & (self.t_near < self.t_max)  # (``active`` is the loops' state, updated in place)
        # the air the walk tracks: the grid's (at the ray's wavelengths), or (``split_air``, RGB) its largest channel,
        # grey, the rest its ``excess``
        self.excess = None
        if split_air:
            self.air, self.excess = grid.air.split_max()
        self.q0 = [o_l[k] * grid.scale[k] + grid.shift for k in range(3)]
        self.dq = [d_l[k] * grid.scale[k] for k in range(3)]
        self.cells, self.nexts = locate(grid, self.q0, self.dq, self.t_near)

    def sigma_t(self, t, active):
        """sigma_t at distance t (in the current texel cell ``cells`` when interpolating texels)."""
        return sigma_t_at(self.tk.ms, self.ray.o + self.ray.d * t, self.ray, active, self.bound_air)

    def tentative(self, sampler, active, t, cells, nexts):
        """One step of a tracker in the current cell: (majorant, k, end of the segment in this cell,
        tentative collision distance tc, whether it lies in the cell, sigma_t there)."""
        grid, q0, dq = self.grid, self.q0, self.dq
        maj, idx = cell_of(grid, cells, active)
        empty = maj <= 0.0
        t_cell, k = cell_end(grid, q0, dq, cells, nexts, idx, empty, active)
        seg_end = dr.minimum(t_cell, self.t_max)
        if self.air is not None:  # the air's cells: the cube's air majorant (.air_levels)
            maj = dr.select(empty, self.air.cube_bound(cells[2], k, grid.lo, active & empty), maj)
        u = sampler.next_1d(active)
        dt = dr.select(maj > 0.0, -dr.log(1.0 - u) / maj, dr.inf)
        tc = t + dt
        collide = active & (tc < seg_end)
        if self.air is not None and self.texels is not None:  # a grey grid's interpolant plus the air per level
            grey = cell_interpolant(self.texels, grid, q0, dq, cells, (tc,), collide & ~empty)[0]
            s_t = self.air.sigma_at(q0[2] + dq[2] * tc, collide) + dr.select(empty, 0.0, grey)
        elif self.air is not None:  # sigma_t in the air's cells from its levels, elsewhere the medium's lookup
            s_t = dr.select(empty, self.air.sigma_at(q0[2] + dq[2] * tc, collide & empty),
                            self.sigma_t(tc, collide & ~empty))
        elif self.texels is None:
            s_t = self.sigma_t(tc, collide)
        else:  # in a texel cell: the interpolant of its 8 texels
            s_t = cell_interpolant(self.texels, grid, q0, dq, cells, (tc,), collide)[0]
        return maj, k, seg_end, tc, collide, s_t

    def advance(self, active, collide, tc, seg_end, cells, nexts, k, stop):
        """To the collision, or to the next cell; returns (t, cells, nexts, active)."""
        t = dr.select(collide, tc, seg_end)
        adv = active & ~collide
        cells, nexts, outside = dda_step(self.grid, self.q0, self.dq, t, cells, nexts, k, adv)
        leave = adv & ((seg_end >= self.t_max) | outside)
        active &= ~(stop | leave)
        return t, cells, nexts, active


def _tracking_walk(tk, ray, t_end, active, tile_only=None):
    """The walk of free flights and ratio tracking: over ``tk.track``, texels interpolated in texel cells (a grey
    grid's: with the air added per level, the air's extinction added to them)."""
    grid = tk.track
    texels = tk.texel_data if (grid is tk.texel and (not tk.ms.spectral or _air_on_grey_grid(tk, grid))) else None
    return _Walk(tk, grid, texels, ray, t_end, active, tile_only, split_air=_split_air(tk, grid, texels))


def _air_on_grey_grid(tk, grid) -> bool:
    """Whether ``grid`` is the medium's grey grid with the box's air added per level (``tk.ms.air``: an RGB
    ``AirLevels`` or the spectral variants' ``ComponentAirLevels`` over wavelength): the walks then interpolate the
    grey grid's texels and add the air (a chromatic RGB air's flights follow its largest channel, :func:`_split_air`;
    a spectral one's are tracked over the ray's 4 wavelengths), and exact transmittance takes the air's optical depth
    in closed form once per segment, its loop the hydrometeors' alone (the extinction's only spectral part is the
    air's). (Gated on grey media alone from c0780af to spectralair38c: the RGB mode took the medium's lookups.)"""
    return tk.ms.air is not None and grid.air is tk.ms.air


def _split_air(tk, grid, texels) -> bool:
    """Whether free flights and ratio tracking follow the air's largest channel, grey, and weight the channels by
    its excess in closed form (:func:`_excess_weight`): a chromatic RGB air added per level to a grey grid whose
    texels the walk interpolates (the only spectral part of the extinction is then the air's)."""
    from .air_levels import AirLevels
    air = grid.air
    return (texels is not None and type(air) is AirLevels and not air.grey and air.channels == 3
            and tk.ms.air is air)


def _excess_weight(walk, end, at_collision, s_g, active):
    """The channels' factor of a walk tracked grey against the air's largest channel (``_split_air``), over
    [t_near, ``end``]: exp(-tau_excess) (<= 0 excess: >= 1), at a real collision (``at_collision``) times
    sigma_c / sigma_g = 1 + excess_c / ``s_g`` (s_g the grey extinction the collision was drawn with). The
    free flight's density and its escape probability are those of sigma_g; these factors make them sigma_c's
    (Color3f; 1 where not ``active``)."""
    ex, q0, dq = walk.excess, walk.q0, walk.dq
    tau = ex.tau(q0[2], dq[2], walk.t_near, end, active)
    at = ex.sigma_at(q0[2] + dq[2] * end, active & at_collision)
    ratio = dr.select(at_collision, 1.0 + at * dr.rcp(dr.select(s_g > 0.0, s_g, 1.0)), 1.0)
    return dr.select(active, ratio * dr.exp(-tau), 1.0)


def _spectral_collision(tr, maj, s_t, xi, collide, found):
    """History-aware spectral tracking at a tentative collision: (stop, tr, found)."""
    s_n = dr.maximum(maj - s_t, 0.0)
    a_t = dr.mean(tr * s_t)
    a_n = dr.mean(tr * s_n)
    a = a_t + a_n
    p_t = dr.select(a > 0.0, a_t / dr.select(a > 0.0, a, 1.0), 0.0)
    stop = collide & (xi < p_t)
    null = collide & ~stop
    w_t = s_t / dr.maximum(maj * p_t, 1e-30)
    w_n = s_n / dr.maximum(maj * (1.0 - p_t), 1e-30)
    tr = dr.select(stop, tr * w_t, dr.select(null, tr * w_n, tr))
    dead = collide & (a <= 0.0)
    stop |= dead
    found |= stop & ~dead
    return stop, tr, found


def _walk_loop(walk, sampler, tr, body, label: str):
    """The symbolic loop of a tracker over the DDA: state (sampler, active, t, cell x/y/z, next crossing
    x/y/z, found, tr), run while a lane is active; returns the final state."""
    cells, nexts = walk.cells, walk.nexts
    return dr.while_loop(
        state=(sampler, walk.active, mi.Float(walk.t_near), cells[0], cells[1], cells[2],
               nexts[0], nexts[1], nexts[2], mi.Bool(False), tr),
        cond=lambda sampler, active, *_: active, body=body, label=label)


def delta_tracking(tk, ray, t_end, sampler, active, weight, tile_only=None):
    """Free flight along ``ray`` over [0, t_end] (clipped to the grid's box) by delta tracking.

    Parameters
    ----------
    tk : medium_setup.Tracking
        The per-render grids and medium.
    ray : mi.Ray3f
        World ray; distances along it.
    t_end : mi.Float
        End of the walk (the next surface).
    sampler
        ``next_1d`` source (a Mitsuba sampler or the persistent lanes' one).
    active : mi.Bool
        Lanes that walk.
    weight : mi.Spectrum
        The path throughput w (used with spectral extinction only).
    tile_only : mi.Bool, optional
        Periodic medium: lanes that meet the medium in the grid's own box only (``Tracking.bounds``).

    Returns
    -------
    found : mi.Bool
        Whether a real collision lies before ``t_end``.
    t : mi.Float
        Its distance.
    weight : mi.Spectrum
        ``weight`` unchanged for grey extinction. With spectral extinction the real-collision probability
        is P = mean(w sigma_t) / (majorant mean(w)) and the weight is w sigma_t / (majorant P) at the real
        collision times the product of w (majorant - sigma_t) / (majorant (1 - P)) over the null
        collisions (unbiased; the mean of the throughput is preserved).
    """
    walk = _tracking_walk(tk, ray, t_end, active, tile_only)
    split = walk.excess is not None  # grey against the air's largest channel (``_split_air``)
    spectral = tk.ms.spectral and not split
    tr = mi.Spectrum(weight) if spectral else mi.Float(0.0 if split else 1.0)

    def body(sampler, active, t, cx, cy, cz, tx, ty, tz, found, tr):
        cells, nexts = [cx, cy, cz], [tx, ty, tz]
        maj, k, seg_end, tc, collide, s_t = walk.tentative(sampler, active, t, cells, nexts)
        xi = sampler.next_1d(collide)
        if spectral:
            stop, tr, found = _spectral_collision(tr, maj, s_t, xi, collide, found)
        else:
            stop = collide & (xi * maj < s_t)
            found |= stop
            if split:  # tr: the grey extinction of the real collision
                tr = dr.select(stop, s_t, tr)
        t, (cx, cy, cz), (tx, ty, tz), active = walk.advance(active, collide, tc, seg_end, cells, nexts, k, stop)
        return sampler, active, t, cx, cy, cz, tx, ty, tz, found, tr

    _, _, t, _, _, _, _, _, _, found, tr = _walk_loop(walk, sampler, tr, body, "majorant_volpath: DDA delta tracking")
    if split:
        end = dr.select(found, t, walk.t_max)
        return found, t, mi.Spectrum(weight) * _excess_weight(walk, end, found, tr, walk.met)
    return found, t, (tr if spectral else weight)


def ratio_tracking(tk, ray, t_end, sampler, active):
    """Transmittance estimate along ``ray`` over [0, t_end] (clipped to the grid's box) by ratio tracking.

    T *= 1 - sigma_t / majorant at each tentative collision, with Russian roulette once max(T) <
    RR_THRESHOLD (survival RR_SURVIVE, weight its inverse): unbiased.

    Parameters
    ----------
    tk, ray, t_end, sampler, active
        As for :func:`delta_tracking`.

    Returns
    -------
    mi.Spectrum
        The transmittance estimate (dimensionless).
    """
    walk = _tracking_walk(tk, ray, t_end, active)
    split = walk.excess is not None  # grey against the air's largest channel (``_split_air``)
    spectral = tk.ms.spectral and not split
    tr = mi.Spectrum(1.0) if spectral else mi.Float(1.0)

    def body(sampler, active, t, cx, cy, cz, tx, ty, tz, found, tr):
        cells, nexts = [cx, cy, cz], [tx, ty, tz]
        maj, k, seg_end, tc, collide, s_t = walk.tentative(sampler, active, t, cells, nexts)
        inv_maj = dr.rcp(dr.select(collide, maj, 1.0))
        tr = dr.select(collide, tr * dr.clip(1.0 - s_t * inv_maj, 0.0, 1.0), tr)
        low = collide & ((dr.max(tr) if spectral else tr) < RR_THRESHOLD)
        xi = sampler.next_1d(low)
        tr = dr.select(low, dr.select(xi < RR_SURVIVE, tr * (1.0 / RR_SURVIVE), 0.0), tr)
        stop = collide & (dr.all(tr <= 0.0) if spectral else (tr <= 0.0))
        t, (cx, cy, cz), (tx, ty, tz), active = walk.advance(active, collide, tc, seg_end, cells, nexts, k, stop)
        return sampler, active, t, cx, cy, cz, tx, ty, tz, found, tr

    *_, tr = _walk_loop(walk, sampler, tr, body, "majorant_volpath: DDA ratio tracking")
    if split:
        return mi.Spectrum(tr) * _excess_weight(walk, walk.t_max, mi.Bool(False), mi.Float(1.0), walk.met)
    return mi.Spectrum(tr) if not spectral else tr


def exact_transmittance(tk, ray, t_end, active, sampler=None):
    """exp(-optical depth) of ``ray`` over [0, t_end] (clipped to the grid's box), computed exactly.

    The trilinear interpolant of sigma_t is one trilinear polynomial in each cell of the texel-centre
    grid (``tk.texel``), so along a ray it is a cubic in t there, which Simpson's rule integrates
    exactly: tau = sum over the cells crossed of (t1 - t0) / 6 (s(t0) + 4 s(tm) + s(t1)), with s the
    medium's own ``sigma_t`` lookup. Cells whose texels are all 0 cost no lookups and empty cubes of
    cells are crossed in one step.

    Parameters
    ----------
    tk : medium_setup.Tracking
        The per-render grids and medium (needs ``tk.texel``).
    ray : mi.Ray3f
        World ray; distances along it.
    t_end : mi.Float
        End of the segment.
    active : mi.Bool
        Lanes to compute.
    sampler : optional
        None: deterministic, 0 once tau > TAU_ZERO (the rest is below e^-TAU_ZERO). Given: Russian
        roulette once tau passes EXACT_RR_TAU and after every further EXACT_RR_STEP (survival
        EXACT_RR_SURVIVE, weight its inverse): unbiased, no cut.

    Returns
    -------
    mi.Spectrum
        The transmittance (dimensionless), or its roulette estimate.
    """
    spectral = tk.ms.spectral
    air = tk.texel.air
    # a grey grid with the air added per level: the air's optical depth over the whole segment in closed form (one
    # evaluation: the air is horizontally homogeneous, the ray straight), the loop the hydrometeors' alone (grey,
    # their interpolant from the texels), as without the air
    split = air is not None and tk.texel_data is not None and (not spectral or _air_on_grey_grid(tk, tk.texel))
    walk = _Walk(tk, tk.texel, tk.texel_data if (split or not spectral) else None, ray, t_end, active)
    grid, texels, q0, dq, t_max = walk.grid, walk.texels, walk.q0, walk.dq, walk.t_max
    air = walk.air  # at the ray's wavelengths (spectral: ``spectral_air.bind_air``)
    t_near, active, cells, nexts = walk.t_near, walk.active, walk.cells, walk.nexts
    tau_air, tau_air_min = None, 0.0
    if split:
        tau_air = dr.select(active, air.tau(q0[2], dq[2], t_near, t_max, active), 0.0)  # 0 where it misses the box
        tau_air_min = tau_air if air.grey else dr.min(tau_air)
        air, spectral = None, False  # the loop's: grey, without the air
        s0 = cell_interpolant(texels, grid, q0, dq, cells, (t_near,), active)[0]
    else:
        s0 = walk.sigma_t(t_near, active)
    tau = dr.zeros(mi.Spectrum) if spectral else mi.Float(0.0)

    rr = sampler is not None and EXACT_RR_SURVIVE < 1.0

    def cond(sampler, active, t, cx, cy, cz, tx, ty, tz, s0, tau, w, next_rr):
        return active

    def body(sampler, active, t, cx, cy, cz, tx, ty, tz, s0, tau, w, next_rr):
        cells, nexts = [cx, cy, cz], [tx, ty, tz]
        maj, idx = cell_of(grid, cells, active)
        empty = maj <= 0.0
        t_cell, k = cell_end(grid, q0, dq, cells, nexts, idx, empty, active)
        seg_end = dr.minimum(t_cell, t_max)
        lookup = active & ~empty
        if texels is None:
            s_m = walk.sigma_t(0.5 * (t + seg_end), lookup)
            s_1 = walk.sigma_t(seg_end, lookup)
        else:  # the cell's 8 texels once, the interpolant at both points from them
            s_m, s_1 = cell_interpolant(texels, grid, q0, dq, cells, (0.5 * (t + seg_end), seg_end), lookup)
        tau = dr.select(lookup, tau + (seg_end - t) * (1.0 / 6.0) * (s0 + 4.0 * s_m + s_1), tau)  # Simpson
        if air is None:
            s0 = dr.select(lookup, s_1, 0.0)  # a cell whose texels are 0 is 0 on its faces
        else:  # the air's cells and cubes in closed form (.air_levels); their faces hold the air alone
            in_air = active & empty
            tau = dr.select(in_air, tau + air.tau(q0[2], dq[2], t, seg_end, in_air), tau)
            s0 = dr.select(lookup, s_1, air.sigma_at(q0[2] + dq[2] * seg_end, in_air))
        t = dr.select(active, seg_end, t)
        (cx, cy, cz), (tx, ty, tz), outside = dda_step(grid, q0, dq, t, cells, nexts, k, active)
        tau_min = (dr.min(tau) if spectral else tau) + tau_air_min
        if rr:  # Russian roulette each time T falls by another EXACT_RR_STEP (weights w)
            low = active & (tau_min > next_rr)
            survive = sampler.next_1d(low) < EXACT_RR_SURVIVE
            w = dr.select(low, w * (1.0 / EXACT_RR_SURVIVE), w)
            next_rr = dr.select(low, next_rr + EXACT_RR_STEP, next_rr)
            w = dr.select(low & ~survive, 0.0, w)
            active &= ~(low & ~survive)
            deep = mi.Bool(False)
        else:
            deep = tau_min > TAU_ZERO
        active &= ~((seg_end >= t_max) | outside | deep)
        return sampler, active, t, cx, cy, cz, tx, ty, tz, s0, tau, w, next_rr

    state = dr.while_loop(state=(sampler if rr else None, active, mi.Float(t_near), cells[0], cells[1], cells[2],
                                 nexts[0], nexts[1], nexts[2], s0, tau, mi.Float(1.0), mi.Float(EXACT_RR_TAU)),
                          cond=cond, body=body, label="majorant_volpath: exact transmittance")
    *_, tau, w, _ = state
    if split:  # the air's part, over the segment the walk crossed
        tau, spectral = tau + tau_air, tk.ms.spectral
    if rr:
        return mi.Spectrum(w * dr.exp(-tau))
    return mi.Spectrum(dr.select((dr.min(tau) if spectral else tau) > TAU_ZERO, 0.0, dr.exp(-tau)))


def shadow_transmittance(tk, exact: bool, scene, sampler, ray, medium, active):
    """Transmittance along a shadow ray: through the medium (``exact``: :func:`exact_transmittance` where
    there is a texel grid, else :func:`ratio_tracking`) and null-BSDF surfaces (the medium's box), 0 at
    opaque ones. ``ray.maxt`` is the distance to the emitter sample; ``medium`` the one the ray starts in.
    Returns mi.Spectrum (0 where not ``active``)."""
    max_dist = mi.Float(ray.maxt)
    has_medium = tk.ms.medium is not None

    def cond(sampler, active, ray, total, medium, tr):
        return active

    def body(sampler, active, ray, total, medium, tr):
        remaining = max_dist - total
        ray.maxt = remaining
        active &= remaining > 0.0
        si = scene.ray_intersect(ray, active)
        if has_medium:
            in_med = active & (medium != None)  # noqa: E711
            if exact and tk.texel is not None:
                tr_seg = exact_transmittance(tk, ray, dr.minimum(si.t, remaining), in_med, sampler)
            else:
                tr_seg = ratio_tracking(tk, ray, dr.minimum(si.t, remaining), sampler, in_med)
            tr = dr.select(in_med, tr * tr_seg, tr)
        hit = active & si.is_valid()
        bsdf = si.bsdf(ray)
        tr = dr.select(hit, tr * bsdf.eval_null_transmission(si, hit), tr)
        total = dr.select(hit, total + si.t, total)
        ray = dr.select(hit, si.spawn_ray(ray.d), ray)
        trans = hit & si.is_medium_transition()
        medium = dr.select(trans, si.target_medium(ray.d), medium)
        active &= hit & dr.any(tr != 0.0)
        return sampler, active, ray, total, medium, tr

    _, _, _, _, _, tr = dr.while_loop(
        state=(sampler, mi.Bool(active), mi.Ray3f(ray), mi.Float(0.0), mi.MediumPtr(medium), mi.Spectrum(1.0)),
        cond=cond, body=body, label="majorant_volpath: shadow ray")
    return dr.select(active, tr, 0.0)
