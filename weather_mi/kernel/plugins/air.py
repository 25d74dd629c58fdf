"""The air inside the medium's box on the sun's path (``majorant_volpath``'s ``sun_air_box``): where the box
holds the air (``optics.air.inside``), the medium's tracking already attenuates the sun ray inside it, so
the sun's colour from the air table is looked up where the sun ray leaves the box, not at the vertex.

:func:`parse_box` reads ``sun_air_box`` (x0, y0, z0, x1, y1, z1 in the kernel's frame, m);
:func:`sun_exit_point` the point where the ray p + t sun_dir (t >= 0) leaves it (p itself where the ray
misses the box or p lies beyond it: the slab method).
"""
from __future__ import annotations

import numpy as np

import drjit as dr
import mitsuba as mi

BOX_PROPERTY = "sun_air_box"


def parse_box(sun, props, check) -> None:
    """``sun.air_box``: None, or (x0, y0, z0, x1, y1, z1) as opaque floats."""
    sun.air_box = None
    if BOX_PROPERTY not in props:
        return
    box = np.asarray(props[BOX_PROPERTY], np.float64).ravel()
    check(box.size == 6 and np.all(np.isfinite(box)) and np.all(box[3:] > box[:3]),
          f"'{BOX_PROPERTY}' must be 6 finite numbers x0, y0, z0, x1, y1, z1 with x1 > x0, ..., got {box.tolist()}")
    check(getattr(sun, "air", None) is not None or getattr(sun, "spectrum_air", False),
          f"'{BOX_PROPERTY}' needs the air's table 'sun_air'")
    sun.air_box = [mi.Float(float(v)) for v in box]
    dr.make_opaque(*sun.air_box)


def sun_exit_point(sun, p):
    """Where the sun ray from p leaves ``sun.air_box`` (p where it does not cross the box ahead of p)."""
    b, d = sun.air_box, sun.sun_dir
    t_near, t_far = mi.Float(-dr.inf), mi.Float(dr.inf)
    for axis, coord in enumerate((p.x, p.y, p.z)):
        inv = dr.rcp(dr.select(dr.abs(d[axis]) < 1e-12, 1e-12, d[axis]))  # a slab parallel to the ray is never left
        t0 = (b[axis] - coord) * inv
        t1 = (b[3 + axis] - coord) * inv
        t_near = dr.maximum(t_near, dr.minimum(t0, t1))
        t_far = dr.minimum(t_far, dr.maximum(t0, t1))
    t = dr.select((t_far > dr.maximum(t_near, 0.0)), t_far, 0.0)
    return p + mi.Vector3f(sun.sun_dir) * t
