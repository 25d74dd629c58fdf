"""The path loop of the ``majorant_volpath`` integrator: one event per iteration (a scattering, a surface or the
escape) in stages over a :func:`.path_state.path_state_class` state. Structure and estimators: the docstring of
:mod:`.majorant_volpath`; the measurements behind the constants: ``docs/reference-estimator.md``."""
from __future__ import annotations

import functools

import drjit as dr
import mitsuba as mi

from . import lane_channels, lane_directions, mvnee, sun
from .medium_setup import phase_ctx, scattering_event
from .path_state import Vertex, path_state_class
from .trackers import delta_tracking, shadow_transmittance

LONG_WALK_DEPTH = 1024  # Russian roulette: long walks survive 1/2 at depths 2^k >= this (docs/reference-estimator.md)
GUIDE_GROWTH = 2.0    # sun guiding: bound of the product of 1 / (1 - eps) along a path
GUIDE_SEEN = 0.1      # sun guiding at full strength where the sun's transmittance estimate is >= this


# ---------------------------------------------------------------- Mitsuba helpers

def _as_interaction(x):
    """The ``Interaction3f`` part of a surface or medium interaction."""
    it = dr.zeros(mi.Interaction3f)
    it.t, it.time, it.wavelengths, it.p, it.n = x.t, x.time, x.wavelengths, x.p, x.n
    return it


# ---------------------------------------------------------------- the path loop

class PathLoop:
    """The path loop of ``majorant_volpath`` over one scene: :meth:`initial` is the :func:`path_state_class`
    state of paths starting with a ray, :meth:`body` advances every alive path by one event (a scattering,
    a surface or the escape) in stages: :meth:`roulette`, :meth:`free_flight`, :meth:`emitters_hit`,
    :meth:`vertex`, :meth:`nee`, :meth:`aureole_nee`, :meth:`sample_phase`, :meth:`sample_bsdf`, which pass
    a :class:`.path_state.Vertex` on (its fields, and the order in which the stages set them, declared there).
    Structure and estimators: the module docstring."""

    def __init__(self, integ, scene, medium):
        integ._setup(scene, medium)
        ms = integ._ms
        self.integ, self.scene, self.ms, self.tk = integ, scene, ms, integ._tk
        self.State = path_state_class()
        self.has_medium = has_medium = ms.medium is not None
        self.max_depth, self.rr_depth, self.hide = integ.max_depth, integ.rr_depth, integ.hide_emitters_
        self.phase = phase = ms.medium.phase_function() if has_medium else None
        self.bsdf_ctx = mi.BSDFContext()
        self.has_emitters = has_emitters = len(scene.emitters()) > 0
        self.sun_mode = sun_mode = integ.sun_mode
        self.guiding = has_medium and sun_mode != "none" and integ.guiding > 0.0
        self.aureole = has_medium and sun_mode != "none" and integ.aureole > 0.0
        self.mvnee = has_medium and sun_mode != "none" and integ.mvnee > 0.0
        # history-aware channel sampling: in RGB variants the throughput's channels are the tables' ...
        self.by_channel = has_medium and integ.channels == "history" and hasattr(phase, "sample_channel") and mi.is_rgb
        # ... in spectral variants the R, G, B densities in the throughput's shares by wavelength (.lane_channels;
        # not with sun guiding, the aureole or multiple-vertex NEE, whose pdfs take the channel mean)
        self.by_lane = (has_medium and integ.channels == "history" and hasattr(phase, "sample_channel")
                        and mi.is_spectral and not (self.guiding or self.aureole or self.mvnee))
        # ... and where the phase has its tables by wavelength, from one lane's own table (.lane_directions)
        self.own_lanes = self.by_lane and lane_directions.applies(phase)
        self.lane_shares = "throughput"  # each lane's probability of lending its table (lane_directions.SHARES)
        self.lane_nodes = "picked"  # each lane's table at one wavelength node a vertex, or "bilinear"
        if self.own_lanes:
            lane_directions.prepare(phase)  # its tables, before the loop is traced
        self.rr_cap = 0.95 if integ.rr_mode == "volpath" else 1.0
        self.c_em = c_em = integ.emitter_nee
        self.c_sky = c_em if sun_mode != "none" else 1.0          # share of shadow rays towards the scene's emitters
        self.c_sun = (1.0 - c_em) if has_emitters else 1.0      # ... towards the integrator's sun
        self.sun_pdf = dr.rcp(dr.two_pi * integ.sun_vmax) if sun_mode == "disk" else None
        self.one_strategy = {"nee": (1.0, 0.0), "phase": (0.0, 1.0)}.get(integ.sun_sampling)
        self.has_env = scene.environment() is not None
        self.mis_weight = mi.ad.integrators.common.mis_weight  # the power heuristic, Mitsuba's own
        self.transmittance = functools.partial(shadow_transmittance, self.tk, integ.tr_mode == "exact")

    def sun_pdf_of(self, val, pdf):
        """The continuation pdf in the sun's MIS: with aureole NEE the channel mean of the phase value (the
        mixture's own pdf; a function of the vertex and the two directions only, so that the aureole
        estimator can weight its vertex B exactly as the path does)."""
        return dr.mean(val) if (self.aureole or self.mvnee) else pdf

    def sun_mis(self, pdf_a, pdf_b, nee=True):
        """Weight of the sun-sampling (``nee``) or of the continuation strategy."""
        if self.one_strategy is None:
            return self.mis_weight(pdf_a, pdf_b)
        return self.one_strategy[0] if nee else self.one_strategy[1]

    def initial(self, ray, medium, active):
        """The state of paths starting with ``ray`` in ``medium`` (the sensor's), alive where ``active``."""
        hide = self.hide
        med0 = dr.zeros(mi.MediumPtr)
        if medium is not None:
            med0 = dr.select(active, mi.MediumPtr(medium), med0)
        return self.State(
            active=active, depth=mi.UInt32(0), ray=ray, throughput=mi.Spectrum(1.0), result=mi.Spectrum(0.0),
            si=dr.zeros(mi.SurfaceInteraction3f), medium=med0, eta=mi.Float(1.0), last_event=dr.zeros(mi.Interaction3f),
            last_pdf=mi.Float(1.0), needs_isect=mi.Bool(True), specular_chain=mi.Bool(active & (not hide)),
            valid_ray=mi.Bool((not hide) and self.has_env), last_long=mi.UInt32(0),
            guide_left=mi.Float(GUIDE_GROWTH), last_pdf_sun=mi.Float(1.0), aur_w=mi.Float(1.0),
            mv_r=mvnee.zeros())

    def cond(self, sampler, p):
        return p.active

    def body(self, sampler, p):
        """One event of every alive path."""
        self.roulette(sampler, p)
        v = self.free_flight(sampler, p)
        self.emitters_hit(p, v)
        self.vertex(sampler, p, v)
        self.nee(sampler, p, v)
        self.aureole_nee(sampler, p, v)
        self.sample_phase(sampler, p, v)
        self.sample_bsdf(sampler, p, v)
        return sampler, p

    def roulette(self, sampler, p):
        """Russian roulette (``rr_mode``; long walks cut at depths 2^k >= LONG_WALK_DEPTH) and the depth limit."""
        p.active &= dr.any(p.throughput != 0.0)
        q = dr.minimum(dr.max(p.throughput) * dr.square(p.eta), self.rr_cap)
        if self.rr_cap == 1.0:  # long walks: survive 1/2 at depths 2^k >= LONG_WALK_DEPTH (weight ~ depth)
            depth = p.depth
            long_walk = (depth >= LONG_WALK_DEPTH) & ((depth & (depth - 1)) == 0) & (depth != p.last_long)
            p.last_long = dr.select(long_walk, depth, p.last_long)
            q = dr.select(long_walk, q * 0.5, q)
        perform_rr = (p.depth > self.rr_depth) & (q < 1.0)
        p.active &= (sampler.next_1d(p.active) < q) | ~perform_rr
        p.throughput = dr.select(perform_rr, p.throughput * dr.rcp(q), p.throughput)
        p.active &= p.depth < self.max_depth

    def free_flight(self, sampler, p) -> Vertex:
        """The next surface, and in the medium the free flight (delta tracking) to a real collision, with
        the absorption weight (throughput *= sigma_s / sigma_t)."""
        v = Vertex()
        isect = p.active & p.needs_isect
        p.si = dr.select(isect, self.scene.ray_intersect(p.ray, isect), p.si)
        p.needs_isect &= ~p.active
        v.act_scatter = mi.Bool(False)
        v.active_surface = mi.Bool(p.active)
        v.mei = dr.zeros(mi.MediumInteraction3f)
        if self.has_medium:
            active_medium = p.active & (p.medium != None)  # noqa: E711
            v.active_surface = p.active & ~active_medium
            t_end = dr.minimum(p.si.t, p.ray.maxt)
            tile_only = (p.depth == 0) if self.tk.periodic == "transport" else None  # camera rays: its own tile
            found, t_coll, w_walk = delta_tracking(self.tk, p.ray, t_end, sampler, active_medium, p.throughput, tile_only)
            p.throughput = dr.select(active_medium, w_walk, p.throughput)
            v.act_scatter = active_medium & found
            v.active_surface |= active_medium & ~found
            v.mei, albedo_w = scattering_event(self.ms, p.ray, t_coll, v.act_scatter)
            p.depth = dr.select(v.act_scatter, p.depth + 1, p.depth)
            p.last_event = dr.select(v.act_scatter, _as_interaction(v.mei), p.last_event)
            p.active &= p.depth < self.max_depth
            v.act_scatter &= p.active
            p.throughput = dr.select(v.act_scatter, p.throughput * albedo_w, p.throughput)
            p.valid_ray |= v.act_scatter
            p.specular_chain &= ~v.act_scatter
        return v

    def emitters_hit(self, p, v):
        """Emitters hit by the ray (environment, area emitters; the sun's disk), MIS against emitter
        sampling at the previous vertex; then the surface's BSDF."""
        count_direct = (p.depth == 0) | p.specular_chain
        emitter = p.si.emitter(self.scene)
        active_e = v.active_surface & (emitter != None)  # noqa: E711
        if self.hide:
            active_e &= p.depth != 0
        ds_hit = mi.DirectionSample3f(self.scene, p.si, p.last_event)
        em_pdf = self.scene.pdf_emitter_direction(p.last_event, ds_hit, active_e & ~count_direct)
        emitted = emitter.eval(p.si, active_e)
        w_hit = dr.select(count_direct, 1.0, self.mis_weight(p.last_pdf, self.c_sky * em_pdf))
        p.result = dr.select(active_e, p.result + p.throughput * w_hit * emitted, p.result)
        if self.sun_mode == "disk":  # a ray that leaves the scene inside the sun's disk sees the sun
            in_sun = v.active_surface & ~p.si.is_valid() & sun.in_disk(self.integ, p.ray.d)
            if self.hide:
                in_sun &= p.depth != 0
            w_hit = dr.select(count_direct, 1.0, self.sun_mis(p.last_pdf_sun, self.c_sun * self.sun_pdf, nee=False))
            p.result = dr.select(in_sun, p.result + p.throughput * w_hit * sun.radiance_at(self.integ, p.ray.o, p.ray.wavelengths), p.result)
        v.active_surface &= p.si.is_valid()
        v.bsdf = p.si.bsdf(p.ray)

    def vertex(self, sampler, p, v):
        """The vertex of emitter sampling (a real collision or a smooth surface) and the channel
        probabilities alpha of history-aware channel sampling (in proportion to the throughput)."""
        v.act_e_surf = v.active_surface & mi.has_flag(v.bsdf.flags(), mi.BSDFFlags.Smooth) & (p.depth + 1 < self.max_depth)
        v.act_e = v.act_e_surf | v.act_scatter
        ref = dr.zeros(mi.Interaction3f)
        ref = dr.select(v.act_scatter, _as_interaction(v.mei), ref)
        v.ref = dr.select(v.act_e_surf, _as_interaction(p.si), ref)
        v.eps = mi.Float(0.0)  # probability of a sun-guided continuation at this vertex
        v.alpha, v.lane_vertex = None, None
        if self.by_channel:
            t_sum = dr.sum(p.throughput)
            v.alpha = p.throughput * dr.select(t_sum > 0.0, dr.rcp(t_sum), 0.0)
        elif self.own_lanes:  # the lanes' shares (.lane_directions)
            v.alpha = lane_directions.shares(p.throughput, self.lane_shares)
            # the lanes' weights (and one node a lane) for the vertex's draw and its NEE
            u = sampler.next_1d(v.act_scatter) if self.lane_nodes == "picked" else None
            v.lane_vertex = lane_directions.at_vertex(self.phase, v.mei, u)
        elif self.by_lane:  # the R, G, B densities' shares (.lane_channels)
            v.alpha = lane_channels.channel_shares(p.throughput, p.ray.wavelengths, self.phase.channel_nm)

    def f_eval(self, sampler, p, v, d):
        """Phase function or BSDF value toward d, and the pdf with which this vertex continues the path in
        direction d (phase: with sun guiding, the mixture of both samplers)."""
        bsdf_val, bsdf_pdf = v.bsdf.eval_pdf(self.bsdf_ctx, p.si, p.si.to_local(d), v.act_e_surf)
        if not self.has_medium:
            return bsdf_val, bsdf_pdf
        if self.by_lane:  # (no guiding: the continuation's density is the lanes' or the channels')
            ph_val, ph_pdf = lane_directions.eval_pdf(self.phase, v.mei, d, v.alpha, v.lane_vertex) \
                if self.own_lanes else lane_channels.eval_pdf(self.phase, v.mei, d, v.alpha)
            return dr.select(v.act_e_surf, bsdf_val, ph_val), dr.select(v.act_e_surf, bsdf_pdf, ph_pdf)
        ph_val, ph_pdf = self.phase.eval_pdf(phase_ctx(sampler), v.mei, d, v.act_scatter)
        ph_pdf = sun.continuation_pdf(self.integ, self.phase, sampler, v.mei, d, ph_val, ph_pdf, v.alpha, v.eps,
                                      v.act_scatter)
        return dr.select(v.act_e_surf, bsdf_val, ph_val), dr.select(v.act_e_surf, bsdf_pdf, ph_pdf)

    def nee(self, sampler, p, v):
        """Next-event estimation: one shadow ray per vertex, towards the integrator's sun with probability
        1 - c and towards one of the scene's emitters (the sky) with probability c; as MIS techniques
        their pdfs are (1 - c) p_sun and c p_emitter. Sets the vertex's sun-guiding probability eps."""
        has_emitters, sun_mode = self.has_emitters, self.sun_mode
        if not (has_emitters or sun_mode != "none"):
            return
        if not has_emitters:
            pick_em = mi.Bool(False)
        elif sun_mode == "none":
            pick_em = mi.Bool(True)
        else:
            pick_em = sampler.next_1d(v.act_e) < self.c_em
        em_val, ds = dr.zeros(mi.Spectrum), dr.zeros(mi.DirectionSample3f)
        if has_emitters:
            ds, em_val = self.scene.sample_emitter_direction(v.ref, sampler.next_2d(v.act_e), False, v.act_e & pick_em)
            em_val = dr.select(ds.pdf != 0.0, em_val, 0.0)
            d = mi.Vector3f(ds.d)
            shadow = v.ref.spawn_ray_to(ds.p)
        if sun_mode != "none":
            wo_s = sun.sun_direction(self.integ, sampler, v.act_e)
            d = dr.select(pick_em, ds.d, wo_s) if has_emitters else wo_s
            shadow_sun = v.ref.spawn_ray(wo_s)
            shadow = dr.select(pick_em, shadow, shadow_sun) if has_emitters else shadow_sun
        # (at a medium boundary the shadow ray starts in the medium on the emitter's side)
        shadow_med = dr.select(v.act_e_surf & p.si.is_medium_transition(), p.si.target_medium(d), p.medium)
        tr = self.transmittance(self.scene, sampler, shadow, shadow_med, v.act_e)
        if self.guiding and sun_mode != "none":
            # guide only where the sun is seen (elsewhere p / q > 1 would only inflate weights) and while the
            # product of the unguided draws' weights <= 1 / (1 - eps) stays below GUIDE_GROWTH; set before
            # f_eval, so both MIS weights see the same continuation pdf
            eps = dr.select(pick_em, 0.0, self.integ.guide_p * dr.minimum(dr.max(tr) * (1.0 / GUIDE_SEEN), 1.0))
            v.eps = dr.select(v.act_scatter & ((1.0 - eps) * p.guide_left >= 1.0), eps, 0.0)
            p.guide_left = dr.select(v.act_scatter, p.guide_left * (1.0 - v.eps), p.guide_left)
        f_val, f_pdf = self.f_eval(sampler, p, v, d)
        w, em_val = self.nee_weight(p, v, pick_em, ds, em_val, f_val, f_pdf)
        p.result = dr.select(v.act_e, p.result + p.throughput * f_val * w * tr * em_val, p.result)

    def nee_weight(self, p, v, pick_em, ds, em_val, f_val, f_pdf):
        """(MIS weight / technique pdf, emitted value) of the shadow ray of :meth:`nee`."""
        w = mi.Float(0.0)
        if self.has_emitters:
            w_em = self.mis_weight(self.c_sky * ds.pdf, dr.select(ds.delta, 0.0, f_pdf)) * (1.0 / self.c_sky)
            w = dr.select(pick_em, w_em, w)
        if self.sun_mode != "none":
            if self.sun_mode == "disk":  # L / pdf_sun x MIS weight against continuing the path
                c_sun, sun_pdf = self.c_sun, self.sun_pdf
                w_s = self.sun_mis(c_sun * sun_pdf, self.sun_pdf_of(f_val, f_pdf)) * dr.rcp(c_sun * sun_pdf)
            else:                        # delta: irradiance, no MIS
                w_s = mi.Float(1.0 / self.c_sun)
            if self.aureole or self.mvnee:  # MIS against the aureole estimator / the chains launched before
                w_s = dr.select(v.act_scatter, w_s * (p.aur_w if self.aureole else mvnee.path_weight(p.mv_r)), w_s)
            w = dr.select(pick_em, w, w_s)
            em_val = dr.select(pick_em, em_val, sun.radiance_at(self.integ, v.ref.p, v.ref.wavelengths))
        return w, em_val

    def aureole_nee(self, sampler, p, v):
        """Aureole next-event estimation (:func:`.sun.aureole_nee`): a second way to the chain
        A -> B -> sun, its direction at A drawn about the sun."""
        v.eps_a = mi.Float(0.0)
        if self.aureole:
            integ = self.integ
            act_x = v.act_scatter & (p.depth + 1 < self.max_depth)
            act_x &= sampler.next_1d(act_x) < integ.aureole_p
            v.eps_a = dr.select(v.act_scatter & (p.depth + 1 < self.max_depth), integ.aureole_p, 0.0)
            p.result = sun.aureole_nee(integ, self.tk, self.transmittance, self.scene, sampler, self.phase, v.mei,
                                       p.medium, p.throughput, v.alpha, v.eps_a, act_x, p.result, self.sun_mis,
                                       self.c_sun, self.sun_pdf)
        if self.mvnee:  # multiple-vertex NEE (.mvnee): a chain towards the sun, launched with probability eps
            act_x = v.act_scatter & (p.depth + 1 < self.max_depth)
            act_x &= sampler.next_1d(act_x) < self.integ.mvnee
            p.result = mvnee.chain(self, sampler, v, p, self.integ.mvnee, self.integ.mvnee_length, act_x)

    def sample_phase(self, sampler, p, v):
        """Phase function sampling at a real collision (with channels and sun guiding: :meth:`guided_phase`)."""
        if not self.has_medium:
            return
        act_scatter = v.act_scatter
        ph_ctx = phase_ctx(sampler)
        if self.guiding or self.by_channel or self.by_lane:
            wo, ph_val, ph_pdf = self.guided_phase(sampler, v, ph_ctx)
            ph_w = ph_val * dr.select(ph_pdf > 0.0, dr.rcp(ph_pdf), 0.0)
        else:
            wo, ph_w, ph_pdf = self.phase.sample(ph_ctx, v.mei, sampler.next_1d(act_scatter),
                                                 sampler.next_2d(act_scatter), act_scatter)
            ph_val = ph_w * ph_pdf
        v.act_scatter = act_scatter = act_scatter & (ph_pdf > 0.0)
        if self.aureole:  # the sun-NEE weight at the next vertex
            p.aur_w = dr.select(act_scatter, ph_pdf * dr.rcp(ph_pdf + v.eps_a * sun.aureole_pdf(
                self.integ, self.phase, sampler, v.mei, wo, act_scatter)), p.aur_w)
        if self.mvnee:
            p.mv_r = mvnee.path_update(self.integ, self.phase, sampler, v.mei, wo, ph_val, self.integ.mvnee,
                                       self.integ.mvnee_length, p.mv_r, act_scatter)
        p.last_pdf_sun = dr.select(act_scatter, self.sun_pdf_of(ph_val, ph_pdf), p.last_pdf_sun)
        p.throughput = dr.select(act_scatter, p.throughput * ph_w, p.throughput)
        p.ray = dr.select(act_scatter, v.mei.spawn_ray(wo), p.ray)
        p.needs_isect |= act_scatter
        p.last_pdf = dr.select(act_scatter, ph_pdf, p.last_pdf)

    def guided_phase(self, sampler, v, ph_ctx):
        """(direction, phase value, continuation pdf) drawn by channel (history-aware) and/or, with
        probability eps, about the sun (half uniform in the disk, half from the phase function about it)."""
        phase, act_scatter, integ = self.phase, v.act_scatter, self.integ
        mei_s = v.mei
        if self.guiding:
            u_g = sampler.next_1d(act_scatter)
            toward_sun = act_scatter & (u_g < v.eps)
            # half the guided draws uniform in the disk, half from the phase function about it
            in_disk = toward_sun & (u_g < 0.5 * v.eps) if self.sun_mode == "disk" else mi.Bool(False)
            mei_s = sun.about_sun(integ, v.mei, toward_sun)
        ph_pdf = None  # with channels, the channel mixture's pdf follows from the values
        if self.own_lanes:  # (no guiding): one lane's own table, q = sum_j c_j g_j(wo)
            return lane_directions.sample(phase, mei_s, v.alpha, sampler.next_1d(act_scatter),
                                          sampler.next_1d(act_scatter), sampler.next_2d(act_scatter), v.lane_vertex)
        if self.by_channel or self.by_lane:
            u = sampler.next_1d(act_scatter)
            alpha = v.alpha
            channel = mi.UInt32(dr.select(u >= alpha[0], 1, 0) + dr.select(u >= alpha[0] + alpha[1], 1, 0))
            drawn = phase.sample_channel(ph_ctx, mei_s, channel, sampler.next_1d(act_scatter),
                                         sampler.next_2d(act_scatter), act_scatter, densities=self.by_lane)
            wo, ph_val = drawn[0], drawn[1]
        else:
            wo, _, _ = phase.sample(ph_ctx, mei_s, sampler.next_1d(act_scatter), sampler.next_2d(act_scatter),
                                    act_scatter)
        if self.guiding:  # the values are needed about the path's own direction
            wo = dr.select(in_disk, sun.sample_disk(integ, sampler.next_2d(act_scatter)), wo)
            ph_val, ph_pdf = phase.eval_pdf(ph_ctx, v.mei, wo, act_scatter)
        if self.by_lane:  # (no guiding): sum_c alpha_c p_c(wo), the densities from the draw's own lookup
            return wo, ph_val, dr.sum(v.alpha * drawn[2])
        ph_pdf = sun.continuation_pdf(integ, phase, sampler, v.mei, wo, ph_val, ph_pdf, v.alpha, v.eps, act_scatter)
        return wo, ph_val, ph_pdf

    def sample_bsdf(self, sampler, p, v):
        """BSDF sampling at a surface (null BSDFs: passed through without counting depth); ends the paths
        that neither scattered nor continue from a surface."""
        si, active_surface = p.si, v.active_surface
        bs, bsdf_w = v.bsdf.sample(self.bsdf_ctx, si, sampler.next_1d(active_surface),
                                   sampler.next_2d(active_surface), active_surface)
        active_surface &= bs.pdf > 0.0
        p.throughput = dr.select(active_surface, p.throughput * bsdf_w, p.throughput)
        p.eta = dr.select(active_surface, p.eta * bs.eta, p.eta)
        p.ray = dr.select(active_surface, si.spawn_ray(si.to_world(bs.wo)), p.ray)
        p.needs_isect |= active_surface
        non_null = active_surface & ~mi.has_flag(bs.sampled_type, mi.BSDFFlags.Null)
        p.depth = dr.select(non_null, p.depth + 1, p.depth)
        p.last_event = dr.select(non_null, _as_interaction(si), p.last_event)
        p.last_pdf = dr.select(non_null, bs.pdf, p.last_pdf)
        p.last_pdf_sun = dr.select(non_null, bs.pdf, p.last_pdf_sun)
        p.aur_w = dr.select(non_null, 1.0, p.aur_w)
        p.mv_r = dr.select(non_null, mvnee.zeros(), p.mv_r)
        p.valid_ray |= non_null
        p.specular_chain |= non_null & mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
        p.specular_chain &= ~(active_surface & mi.has_flag(bs.sampled_type, mi.BSDFFlags.Smooth))
        trans = active_surface & si.is_medium_transition()
        p.medium = dr.select(trans, si.target_medium(p.ray.d), p.medium)
        p.active &= active_surface | v.act_scatter
