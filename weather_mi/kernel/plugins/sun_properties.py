"""The properties of ``majorant_volpath``'s own sun (its table row "sun_direction" ... "mvnee"): direction,
irradiance, disk, sampling strategies (MIS, guiding, aureole NEE, MVNEE) and the air on its path
(:func:`.sun.parse_air`). Without ``sun_direction`` the sun, if any, is one of the scene's emitters."""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

from ...scene.spec import MAX_SUN_DIAMETER_DEG
from . import mvnee, sun
from .properties import check, choice


def parse(integ, props) -> None:
    """Set ``integ``'s sun attributes (``sun_mode`` "none", "point" or "disk", ``sun_dir``, ``sun_vmax``,
    ``sun_value``, ``guiding``, ``aureole``, ``sun_sampling``, ``mvnee``, the air's tables) from ``props``;
    any invalid value raises ValueError. Reads ``integ.emitter_nee`` (parsed before)."""
    integ.sun_mode, integ.guiding, integ.aureole, integ.sun_sampling, integ.mvnee, integ.air = "none", 0., 0., "mis", 0., None
    if "sun_direction" not in props:
        for name in ("sun_irradiance", "sun_angular_diameter", "sun_guiding", "aureole_nee", "mvnee") + sun.LIGHT_PROPERTIES:
            check(name not in props, f"'{name}' needs 'sun_direction'")
        return
    # the integrator's own sun (the module docstring of majorant_volpath; without sun_direction the sun, if any, is a scene emitter)
    check(mi.is_rgb or mi.is_spectral, f"the integrator's sun needs an RGB or spectral variant, not {mi.variant()!r}")
    d = np.asarray(props["sun_direction"], np.float64).reshape(3)
    check(np.all(np.isfinite(d)) and np.linalg.norm(d) != 0,
           f"'sun_direction' must be a finite non-zero vector, got {d.tolist()}")
    d = d / np.linalg.norm(d)
    e = np.broadcast_to(np.asarray(props.get("sun_irradiance", 1.0), np.float64), (3,))
    check(np.all(np.isfinite(e)) and not np.any(e < 0), f"'sun_irradiance' must be >= 0, got {e.tolist()}")
    diameter = float(props.get("sun_angular_diameter", 0.0))
    check(0.0 <= diameter <= MAX_SUN_DIAMETER_DEG,
           f"'sun_angular_diameter' must be in [0, {MAX_SUN_DIAMETER_DEG}] degrees, got {diameter}")
    integ.sun_sampling = choice(props, "sun_sampling", "mis", ("mis", "nee", "phase"))
    integ.guiding = float(props.get("sun_guiding", 0.0))
    check(0.0 <= integ.guiding < 1.0, f"'sun_guiding' must be in [0, 1), got {integ.guiding}")
    integ.aureole = float(props.get("aureole_nee", 0.0))
    check(0.0 <= integ.aureole <= 1.0, f"'aureole_nee' must be a probability in [0, 1], got {integ.aureole}")
    check(not (integ.aureole > 0.0 and (integ.guiding > 0.0 or integ.sun_sampling != "mis")),
           "'aureole_nee' works with sun_sampling='mis' and no sun guiding")
    integ.mvnee, integ.mvnee_length = mvnee.parse(props, check)
    check(not (integ.mvnee > 0.0 and (integ.guiding > 0.0 or integ.aureole > 0.0 or integ.sun_sampling != "mis")),
           "'mvnee' works with sun_sampling='mis', no sun guiding and no aureole estimator")
    integ.sun_mode = "disk" if diameter > 0 else "point"
    check(integ.emitter_nee < 1.0, "with the integrator's sun, 'emitter_nee' must be below 1 (the rest of the "
           f"shadow rays go to the sun), got {integ.emitter_nee}")
    vmax, radiance = sun.sun_disk(diameter, e)
    # opaque: a new sun position, size or irradiance reuses the kernel
    integ.sun_dir = mi.Vector3f(*(float(v) for v in d))
    integ.sun_vmax = mi.Float(vmax)                       # versine of the disk's radius
    value = radiance if diameter > 0 else e  # spectral variants: a grey scale of the sun's spectrum
    integ.sun_value = mi.Color3f(*(float(v) for v in value)) if mi.is_rgb else mi.Float(float(np.mean(value)))
    integ.guide_p, integ.aureole_p = mi.Float(integ.guiding), mi.Float(integ.aureole)
    dr.make_opaque(integ.sun_dir, integ.sun_vmax, integ.sun_value, integ.guide_p, integ.aureole_p)
    sun.parse_air(integ, props, check)  # the air on the sun's path (optional)

