"""The sky as Mitsuba's emitter gives it, for what renders outside Mitsuba's path loop (the slicer's
background and ground light, the denoiser's features): radiance along rays and irradiance on a horizontal
surface, the same as the reference's sky. ``Sky("air")`` (the clear atmosphere's own sky) has no radiance
along rays here: the slicer puts the air's sky on its frames itself (``slicing.eye_air``, as the reference's
``display.aerial``); its irradiance on a horizontal surface is the 1-D atmosphere's diffuse flux at the envmap's
reference point (``kernel.air_sky.sky_irradiance``), the light the slicer's cloud and ground take from it."""
from __future__ import annotations

import numpy as np

from ..scene.spec import SceneSpec


def _ground_height(spec: SceneSpec):
    """The ground's height (m), or None: with an atmosphere the sky is scaled to the sun there."""
    return None if spec.ground is None else float(spec.ground.height)


def _no_model(spec: SceneSpec) -> bool:
    """No sky model here: no sky, or the air's (module docstring)."""
    return spec.sky is None or spec.has_air_sky


def _sky_emitter(spec: SceneSpec, cache: dict | None):
    """Mitsuba's sky emitter for this spec. With a ``cache`` (a renderer's), one instance per variant
    and sky is kept and updated in place (sun direction, scale), so a moving sun recompiles nothing."""
    import mitsuba as mi
    from .scene_dict import sky_dict, sun_below_air
    cache = {} if cache is None else cache
    last = cache.get("last")  # (the sky and sun of the last call: a camera move keeps them)
    if last is not None and last[0] == (mi.variant(), spec.sky, spec.sun, spec.atmosphere, _ground_height(spec)):
        return last[1], last[2]
    # with an atmosphere, the sky scaled to the sun at the ground, as the reference's (scene_dict.scene_dict)
    d = sky_dict(spec.sky, spec.sun if spec.atmosphere is None else sun_below_air(spec))
    key = (mi.variant(), spec.sky.turbidity, spec.sky.ground_albedo)
    if key not in cache:
        cache[key] = mi.load_dict({**d, "sky_scale": 1.0})  # the scale is applied outside: it is a
    emitter = cache[key]                                     # kernel literal in Mitsuba's sunsky
    sun_key = (key, "sun")
    if cache.get(sun_key) != tuple(d["sun_direction"]):      # updating recomputes the sky's tables
        params = mi.traverse(emitter)
        params["sun_direction"] = mi.Vector3f(*d["sun_direction"])
        params.update()
        cache[sun_key] = tuple(d["sun_direction"])
    cache["last"] = ((mi.variant(), spec.sky, spec.sun, spec.atmosphere, _ground_height(spec)), emitter, d["sky_scale"])
    return emitter, d["sky_scale"]


def sky_radiance(spec: SceneSpec, dirs: np.ndarray, cache: dict | None = None) -> np.ndarray:
    """Sky radiance (N, 3) seen along unit directions (N, 3); zero without a sky."""
    dirs = np.asarray(dirs, dtype=np.float64).reshape(-1, 3)
    if _no_model(spec) or dirs.shape[0] == 0:  # no pixel sees the sky: Mitsuba cannot evaluate 0 lanes
        return np.zeros_like(dirs)
    if spec.sky.kind == "constant":
        return np.broadcast_to(np.asarray(spec.sky.radiance), dirs.shape).copy()
    import mitsuba as mi
    from .jitarrays import aligned_float
    return _eval_numpy(spec, lambda: mi.Vector3f(*(aligned_float(mi, dirs[:, i]) for i in range(3))), cache)


def _eval_numpy(spec: SceneSpec, upload, cache):
    """``sky_radiance`` of a sky emitter along the directions that ``upload()`` gives as a mi.Vector3f
    (called after the emitter's update: its kernel's inputs in the same order every call)."""
    import drjit as dr
    import mitsuba as mi
    emitter, scale = _sky_emitter(spec, cache)
    dirs = upload()
    si = dr.zeros(mi.SurfaceInteraction3f, dr.width(dirs))
    si.wi = -dirs
    return scale * np.asarray(emitter.eval(si), dtype=np.float64).T.reshape(-1, 3)


def sky_radiance_arrays(spec: SceneSpec, dirs, cache: dict | None = None, active=None):
    """``sky_radiance`` as a kernel's mi.Color3f (float32, as ``jitarrays.aligned_float`` rounds it) along
    unit directions given as a mi.Vector3f (float32): no round trip through numpy. ``active``: None, or a
    mi.Bool of the lanes that need the sky (the emitter is evaluated on those alone; 0 elsewhere)."""
    import drjit as dr
    import mitsuba as mi
    n = dr.width(dirs)
    if _no_model(spec):
        return dr.zeros(mi.Color3f, n)
    if spec.sky.kind == "constant":
        value = mi.Color3f(*(dr.opaque(mi.Float, float(v)) for v in spec.sky.radiance)) + dr.zeros(mi.Color3f, n)
        return value if active is None else dr.select(active, value, 0.0)
    index = None
    if active is not None:  # the lanes that see the sky, packed (the emitter's model is costly)
        index = dr.compress(active)
        if dr.width(index) == 0:  # Mitsuba cannot evaluate 0 lanes
            return dr.zeros(mi.Color3f, n)
        dirs = dr.gather(mi.Vector3f, dirs, index)
    dr.eval(dirs)
    emitter, scale = _sky_emitter(spec, cache)
    si = dr.zeros(mi.SurfaceInteraction3f, dr.width(dirs))
    # a copy made after the emitter's update, as sky_radiance's upload is: the kernel's inputs come in the
    # same order every frame (the same kernel, none compiled anew)
    si.wi = -dr.copy(dirs)
    value = emitter.eval(si)
    k = dr.opaque(mi.Float64, float(scale))
    value = mi.Color3f(*(mi.Float(mi.Float64(value[c]) * k) for c in range(3)))
    if index is None:
        return value
    out = dr.zeros(mi.Color3f, n)
    dr.scatter(out, value, index)
    return out


def sky_irradiance_horizontal(spec: SceneSpec, n: int = 1 << 14, cache: dict | None = None) -> np.ndarray:
    """Irradiance (W/m^2, RGB) of the sky on a horizontal surface: pi L for a constant sky; for the
    Hosek-Wilkie sky, pi x the mean radiance over cosine-distributed directions (stratified); for the air's,
    ``air_sky.sky_irradiance`` (module docstring)."""
    if spec.has_air_sky:
        from .air_sky import sky_irradiance
        return sky_irradiance(spec)
    if _no_model(spec):
        return np.zeros(3)
    if spec.sky.kind == "constant":
        return np.pi * np.asarray(spec.sky.radiance)
    memo = (spec.sky, spec.sun, spec.atmosphere, _ground_height(spec), n)
    if cache is not None and memo in cache:
        return cache[memo]
    import drjit as dr
    import mitsuba as mi
    dirs_key = ("horizontal directions", mi.variant(), n)
    uploaded = None if cache is None else cache.get(dirs_key)
    if uploaded is None:  # the directions are the same for every sun: uploaded once per cache
        from .jitarrays import aligned_float
        side = int(np.sqrt(n))
        u, v = np.meshgrid((np.arange(side) + 0.5) / side, (np.arange(side) + 0.5) / side)
        r, phi = np.sqrt(u.ravel()), 2 * np.pi * v.ravel()
        dirs = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(1 - r * r, 0))], axis=1)
        uploaded = mi.Vector3f(*(aligned_float(mi, dirs[:, i]) for i in range(3)))
        if cache is not None:
            cache[dirs_key] = uploaded
    e = np.pi * _eval_numpy(spec, lambda: dr.copy(uploaded), cache).mean(axis=0)
    if cache is not None:
        cache[memo] = e
    return e
