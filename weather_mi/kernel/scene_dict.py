"""SceneSpec + OpticalVolume -> Mitsuba 3 scene dictionary (the kernel side of scene.py)."""
from __future__ import annotations

import functools
from dataclasses import replace

import numpy as np

from .medium import air_by_integrator, air_in_medium, grid_bbox, integrator_air_albedo, medium_dict
from ..optics.periodic import PATH_TILES, extended_box, pad_levels, require_flat_ground
from ..optics.volume import OpticalVolume
from ..scene.spec import Camera, SceneSpec, Sky, Sun
from ..io.terrain import TERRAIN_APRON_M  # the ground continues level this far past a terrain grid's edge
from .variant import ensure_registered

FAR_CLIP_M = 1e8
RAY_EPSILON = 8.9e-5  # Mitsuba's math::RayEpsilon (float32): spawned rays skip (1 + max|p|) x this


def recentred(spec: SceneSpec, vol: OpticalVolume):
    """The scene translated so that the volume's bbox centre is the origin (float32 precision and
    Mitsuba's ray offsets scale with |p|). Returns (spec, vol, offset) with world = shifted + offset."""
    vol2, c = recentred_volume(vol)
    cam = replace(spec.camera, origin=tuple(np.asarray(spec.camera.origin) - c),
                  target=tuple(np.asarray(spec.camera.target) - c))
    rays = None if spec.rays is None else spec.rays.shifted(-c)
    return replace(spec, camera=cam, rays=rays), vol2, c


def recentred_volume(vol: OpticalVolume):
    """``vol`` (and its terrain) translated so that its bbox centre is the origin horizontally:
    (volume, offset), world = shifted + offset (``recentred``)."""
    lo, hi = (np.asarray(p, dtype=np.float64) for p in vol.bbox)
    c = (lo + hi) / 2
    c[2] = 0.0  # keep heights: the ground plane and z-dependent quantities stay readable
    vol2 = replace(vol, bbox=(tuple(lo - c), tuple(hi - c)))
    if getattr(vol, "terrain", None) is not None:  # the ground mesh moves with the volume
        vol2 = replace(vol2, terrain=replace(vol.terrain, x=vol.terrain.x - c[0], y=vol.terrain.y - c[1]))
    return vol2, c


def _look_at(camera: Camera):
    import mitsuba as mi
    return mi.ScalarTransform4f().look_at(origin=list(camera.origin), target=list(camera.target), up=list(camera.up))


def sensor_dict(spec: SceneSpec) -> dict:
    """Perspective (horizontal fov) or orthographic sensor, or the ``raytable`` sensor of ``spec.rays``, with
    a box filter (independent pixels)."""
    import mitsuba as mi
    cam = spec.camera
    film = {"type": "hdrfilm", "width": int(spec.width), "height": int(spec.height),
            "rfilter": {"type": "box"}, "pixel_format": "xyz" if mi.is_spectral else "rgb",  # spectral: CIE XYZ
            "component_format": "float32"}
    if spec.rays is not None:
        from .plugins.raytable_sensor import sensor_dict as raytable_dict
        return raytable_dict(spec.rays.origins_m, spec.rays.directions, film)
    if cam.kind == "orthographic":
        # Mitsuba's orthographic film spans [-1, 1] horizontally and [-1/aspect, 1/aspect] vertically
        aspect = spec.width / spec.height
        to_world = _look_at(cam) @ mi.ScalarTransform4f().scale([cam.ortho_width / 2, cam.ortho_height / 2 * aspect, 1.0])
        return {"type": "orthographic", "to_world": to_world, "film": film,
                "near_clip": 1e-3, "far_clip": FAR_CLIP_M}
    return {"type": "perspective", "fov": float(cam.fov), "fov_axis": "x", "to_world": _look_at(cam),
            "film": film, "near_clip": 1.0, "far_clip": FAR_CLIP_M}


def sun_dict(sun: Sun) -> dict:
    return {"type": "directional", "direction": (-sun.to_sun).tolist(),
            "irradiance": {"type": "rgb", "value": list(sun.irradiance)}}


_SUNSKY_SUN_IRRADIANCE: dict = {}


@functools.lru_cache(maxsize=None)
def _sun_only_sunsky(variant: str, turbidity: float):
    """One sun-only ``sunsky`` per variant and turbidity, its sun moved through ``traverse``: a new
    emitter per sun position would bake the position into a new kernel (a recompilation whenever
    the sun moves)."""
    import mitsuba as mi
    return mi.load_dict({"type": "sunsky", "sun_direction": [0.0, 0.0, 1.0], "sky_scale": 0.0,
                         "turbidity": turbidity})


@functools.lru_cache(maxsize=4)
def _disc_samples(variant: str, n: int):
    """The (seeded) sample points of ``sunsky_sun_irradiance``, uploaded once: the same for every sun (a
    dragged sun asks for a new elevation every frame)."""
    import mitsuba as mi
    from .jitarrays import aligned_float
    rng = np.random.default_rng(1)
    return mi.Point2f(*(aligned_float(mi, u) for u in rng.random((2, n))))


def sunsky_sun_irradiance(sun: Sun, turbidity: float) -> np.ndarray:
    """RGB irradiance normal to the beam of the Hosek-Wilkie sun of Mitsuba's ``sunsky`` for this sun
    position (Monte Carlo over its disc, cached): used to scale its sky to our sun's irradiance."""
    import drjit as dr
    import mitsuba as mi
    key = (mi.variant(), round(sun.elevation, 3), round(float(turbidity), 3))
    if key not in _SUNSKY_SUN_IRRADIANCE:
        emitter = _sun_only_sunsky(mi.variant(), round(float(turbidity), 3))
        params = mi.traverse(emitter)
        params["sun_direction"] = mi.Vector3f(*(float(v) for v in sun.to_sun))
        params.update()
        n = 1 << 16
        it = dr.zeros(mi.Interaction3f, n)
        if mi.is_spectral:  # wavelengths uniform over the CIE range, 4 a sample
            it.wavelengths = mi.Spectrum(*(mi.MI_CIE_MIN + (mi.MI_CIE_MAX - mi.MI_CIE_MIN) * u
                                           for u in np.random.default_rng(2).random((4, n)).astype(np.float32)))
        ds, weight = emitter.sample_direction(it, _disc_samples(mi.variant(), n))
        cos = dr.dot(ds.d, mi.Vector3f(*(dr.opaque(mi.Float, float(v)) for v in sun.to_sun)))  # no literals
        e = np.array(weight * cos)
        if mi.is_spectral:
            _SUNSKY_SUN_IRRADIANCE[key] = _spectral_rgb(e, np.array(it.wavelengths))
        else:
            _SUNSKY_SUN_IRRADIANCE[key] = np.asarray(e).reshape(3, -1).mean(axis=1) if e.ndim > 1 else np.full(3, e.mean())
    return _SUNSKY_SUN_IRRADIANCE[key]


def _spectral_rgb(values, wavelengths) -> np.ndarray:
    """Linear sRGB of a spectrum sampled at uniform random ``wavelengths`` over the CIE range ((4, n) each):
    X, Y, Z = integral S xbar dlambda / integral ybar dlambda (Mitsuba's film's), as RGB variants see it."""
    import mitsuba as mi
    from ..optics.spectrum import linear_srgb
    cmf = np.stack([np.array(c) for c in mi.cie1931_xyz(mi.Float(wavelengths.ravel()))])  # (3, 4 n)
    xyz = (cmf * np.asarray(values).ravel()).mean(axis=1) * (mi.MI_CIE_MAX - mi.MI_CIE_MIN) * mi.MI_CIE_Y_NORMALIZATION
    return linear_srgb(xyz)


def sky_dict(sky: Sky, sun: Sun) -> dict:
    """Constant sky, or Hosek-Wilkie sky (sun part off: the sun is the ``directional`` emitter) with
    the physical sky-to-sun ratio kept: sky_scale = our sun irradiance / the model sun's irradiance."""
    if sky.kind == "constant":
        return {"type": "constant", "radiance": {"type": "rgb", "value": list(sky.radiance)}}
    model_sun = sunsky_sun_irradiance(sun, sky.turbidity)
    scale = float(np.mean(sun.irradiance) / max(float(np.mean(model_sun)), 1e-30))
    return {"type": "sunsky", "sun_direction": sun.to_sun.tolist(), "sun_scale": 0.0, "sky_scale": scale,
            "turbidity": float(sky.turbidity), "albedo": float(sky.ground_albedo)}


def ground_dict(spec: SceneSpec, vol_bbox) -> dict:
    """A Lambertian rectangle at the ground height, wide enough to reach the horizon."""
    import mitsuba as mi
    (x0, y0, _), (x1, y1, _) = vol_bbox
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    half = 1e7  # 10,000 km: the ground reaches the horizon within a fraction of a pixel
    to_world = mi.ScalarTransform4f().translate([cx, cy, spec.ground.height]).scale([half, half, 1.0])
    return {"type": "rectangle", "to_world": to_world,
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(spec.ground.albedo)}}}


_PLY_DIR = None


def _terrain_meshes(terrain, skirt_floor_m: float) -> list:
    """The ground mesh of ``terrain``: ``Terrain.mesh`` with an apron (``Terrain.with_apron``,
    ``TERRAIN_APRON_M``: the edge's heights continued past the domain) and its ``Terrain.skirt`` down to
    ``skirt_floor_m`` (below the surround: no gap for a grazing ray to pass under the wall), as [(PLY file,
    is_sea)]: one Lambertian mesh (vertex colours: the albedo per channel, ``Terrain.vertex_rgb``), and, where
    ``terrain.sea``, the water's faces (two or three water corners) as a second mesh for the sea surface."""
    terrain = terrain.with_apron(TERRAIN_APRON_M)
    v, f, albedo = terrain.mesh()
    sv, sf, _ = terrain.skirt(skirt_floor_m)  # the apron's edge a cliff, not the mesh's underside
    rgb_grid = terrain.vertex_rgb()
    if terrain.albedo_rgb is None:
        rgb = np.repeat(albedo[:, None], 3, axis=1)
        srgb = np.repeat(terrain.skirt(skirt_floor_m)[2][:, None], 3, axis=1)
    else:
        rgb = rgb_grid.reshape(-1, 3)
        srgb = np.stack([replace(terrain, albedo=rgb_grid[..., c]).skirt(skirt_floor_m)[2] for c in range(3)], 1)
    if not terrain.sea:
        return [(_ply_file(np.concatenate([v, sv]), np.concatenate([f, sf + len(v)]), np.r_[rgb, srgb]), False)]
    sea_face = terrain.water.ravel()[f].sum(axis=1) >= 2
    land = _ply_file(np.concatenate([v, sv]), np.concatenate([f[~sea_face], sf + len(v)]), np.r_[rgb, srgb])
    normals = None if terrain.sea_normal is None else terrain.sea_normal.reshape(-1, 3)
    return [(land, False)] + ([(_ply_file(v, f[sea_face], rgb, normals), True)] if np.any(sea_face) else [])


def _ply_file(v, f, rgb, normals=None) -> str:
    """A binary PLY of vertices ``v`` (N, 3), triangles ``f``, per-vertex ``rgb`` (float32 x, y, z and r, g, b,
    clipped to [0, 1]) and, where given, shading ``normals`` (nx, ny, nz) in a directory of this process
    removed at exit, named by its content (the same mesh: the same file)."""
    import hashlib
    import tempfile
    global _PLY_DIR
    names = ("x", "y", "z", "r", "g", "b") + (() if normals is None else ("nx", "ny", "nz"))
    vert = np.empty(len(v), dtype=[(n, "<f4") for n in names])
    for i, n in enumerate("xyz"):
        vert[n] = v[:, i]
    for i, n in enumerate("rgb"):
        vert[n] = np.clip(rgb[:, i], 0.0, 1.0)
    for i, n in enumerate(("nx", "ny", "nz") if normals is not None else ()):
        vert[n] = normals[:, i]
    faces = np.empty(len(f), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    faces["n"], faces["i"] = 3, f
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"element vertex {len(v)}\n" + "".join(f"property float {n}\n" for n in names)
              + f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n").encode()
    data = header + vert.tobytes() + faces.tobytes()
    if _PLY_DIR is None:
        _PLY_DIR = tempfile.TemporaryDirectory(prefix="weather_mi_terrain_")
    from pathlib import Path
    path = Path(_PLY_DIR.name) / f"terrain_{hashlib.sha256(data).hexdigest()[:20]}.ply"
    if not path.is_file():
        path.write_bytes(data)
    return str(path)


def terrain_floor_m(terrain) -> float:
    """The lowest height of a terrain (m)."""
    return float(np.min(terrain.height_m))


def terrain_surround_m(vol: OpticalVolume) -> float:
    """The height (m) of the level ground beyond the terrain's apron in ``scene_dict``'s scene of ``vol``
    (``terrain_ground_dicts`` on the recentred volume: the lowest height less two ``terrain_gap_m``)."""
    vol2, _ = recentred_volume(vol)
    return terrain_floor_m(vol2.terrain) - 2.0 * terrain_gap_m(vol2.terrain, vol2.bbox)


def terrain_gap_m(terrain, bbox) -> float:
    """Three times Mitsuba's ray offset at the scene's largest coordinate (the volume's box, the terrain's
    columns and its apron): the spacing kept between the medium box's floor, the terrain mesh, the
    surround and the skirt's foot (closer faces make spawned rays skip one of them)."""
    extent = max(float(np.max(np.abs(np.asarray(bbox, np.float64)))),
                 float(np.max(np.abs(np.r_[terrain.x, terrain.y]))) + TERRAIN_APRON_M)
    return 3.0 * RAY_EPSILON * (1.0 + extent)


def terrain_ground_dicts(terrain, medium_ref: dict, bbox) -> dict:
    """The ground over a terrain: the height-field mesh through the column centres (``Terrain.mesh``) with
    its apron and skirt (``_terrain_meshes``), Lambertian with the per-vertex albedo (per channel, a
    ``mesh_attribute`` texture; where ``terrain.sea`` the water's faces a second mesh, the sea surface with its
    glint, ``sea_surface``), the medium above it (``exterior``: rays it reflects go on in the cloud's
    medium), and around it out to the horizon a flat rectangle below the medium box's floor (below every
    part of the mesh, so it never shows through a valley; it shows beyond the apron), with the mean albedo
    of the grid's edge columns (the sea surface where ``terrain.sea`` and the edge is mostly water). Heights, from the lowest terrain height lo down (``terrain_gap_m`` g): the
    box's floor lo - g (the whole mesh inside the box), the surround lo - 2 g, the skirt's foot lo - 3 g."""
    import mitsuba as mi
    cx, cy = float(np.mean(terrain.x)), float(np.mean(terrain.y))
    lo, gap = terrain_floor_m(terrain), terrain_gap_m(terrain, bbox)
    half = 1e7
    water = terrain.water
    edge = [terrain.edge_albedo()] * 3 if terrain.albedo_rgb is None else terrain.edge_rgb().tolist()
    bsdf = {"type": "diffuse", "reflectance": {"type": "rgb", "value": edge}}
    sea_bsdf = _sea_bsdf(terrain) if terrain.sea else None
    if terrain.sea and np.mean(np.concatenate([water[0], water[-1], water[1:-1, 0], water[1:-1, -1]])) > 0.5:
        bsdf = sea_bsdf  # beyond the domain the edge's surface: the sea where the edge is mostly water
    surround = {"type": "rectangle",
                "to_world": mi.ScalarTransform4f().translate([cx, cy, lo - 2.0 * gap]).scale([half, half, 1.0]),
                "bsdf": bsdf}
    out = {}
    for k, (ply, is_sea) in enumerate(_terrain_meshes(terrain, lo - 3.0 * gap)):
        out["terrain" if k == 0 else "terrain_sea"] = {
            "type": "ply", "filename": ply, "face_normals": not (is_sea and terrain.sea_normal is not None),
            "exterior": medium_ref,
            "bsdf": sea_bsdf if is_sea else {"type": "diffuse",
                                             "reflectance": {"type": "mesh_attribute", "name": "vertex_color"}}}
    return {**out, "ground": surround}


def _sea_bsdf(terrain) -> dict:
    """The sea surface (``sea_surface.sea_bsdf_dict``) of a terrain: its wind (else the default), the water
    body's Lambertian part as its water columns' albedo (per channel)."""
    from .sea_surface import DEFAULT_WIND_M_S, sea_bsdf_dict
    wind = DEFAULT_WIND_M_S if terrain.wind_m_s is None else terrain.wind_m_s
    rgb = terrain.vertex_rgb()[terrain.water]
    return sea_bsdf_dict(wind, rgb.mean(axis=0) if rgb.size else 0.02)


def medium_box(vol: OpticalVolume, floor_m: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) of the box that holds the medium: the volume's bbox; where its floor lies below three times
    Mitsuba's ray offset g above a ground at ``floor_m`` (coincident or too close faces of the box and the
    ground make rays skip the ground), from g below the ground (or its own floor, if lower) instead: the
    ground inside the box, as over a terrain, the medium down to the ground (a floor g above it lost the
    lowest g of hydrometeors and air alike: 13 m in the demo, 270 m in a periodic box 2,000 km wide, the
    -3 % against DISORT of issue 38; tests/test_box_floor.py); with a ground over a terrain (``vol.terrain``;
    ``floor_m`` then unused) from ``terrain_gap_m`` below its lowest height (the whole mesh inside the box).
    The grids keep the full bbox."""
    lo, hi = (np.asarray(p, dtype=np.float64) for p in vol.bbox)
    if vol.periodic:  # over PATH_TILES periods on each side (optics/periodic.py)
        lo, hi = extended_box(lo, hi, PATH_TILES)
    terrain = getattr(vol, "terrain", None)
    if floor_m is not None and terrain is not None:
        lo[2] = terrain_floor_m(terrain) - terrain_gap_m(terrain, vol.bbox)
    elif floor_m is not None:
        gap = 3.0 * RAY_EPSILON * (1.0 + float(np.max(np.abs(np.r_[lo, hi]))))
        if lo[2] < floor_m + gap:
            lo[2] = min(lo[2], floor_m - gap)
        if hi[2] <= floor_m + gap:
            raise ValueError(f"the volume lies entirely below the ground at {floor_m} m")
    return lo, hi


def medium_shape_dict(vol: OpticalVolume, floor_m: float | None = None, air_in_grid: bool = True) -> dict:
    """The medium's box (:func:`medium_box`) as a ``cube`` with a null BSDF holding the medium."""
    import mitsuba as mi
    lo, hi = medium_box(vol, floor_m)
    to_world = mi.ScalarTransform4f().translate(((lo + hi) / 2).tolist()).scale(((hi - lo) / 2).tolist())
    return {"type": "cube", "to_world": to_world, "bsdf": {"type": "null"}, "interior": medium_dict(vol, air_in_grid)}


def integrator_sun(sun: Sun, guiding: float = 0.0, aureole: float = 0.0, mvnee: float = 0.0) -> dict:
    """Properties of ``majorant_volpath`` that make the sun the integrator's own light (a disk with
    MIS, or a point), sampled at every vertex instead of being one of the scene's emitters, with sun
    guiding, aureole or multiple-vertex next-event estimation (probabilities; ``mvnee`` only where > 0)."""
    return {"sun_direction": sun.to_sun.tolist(), "sun_irradiance": list(sun.irradiance),
            "sun_angular_diameter": float(sun.angular_diameter_deg), "sun_guiding": float(guiding),
            "aureole_nee": float(aureole), **({"mvnee": float(mvnee)} if mvnee > 0 else {})}


def sun_below_air(spec: SceneSpec) -> Sun:
    """The scene's sun as it reaches the ground (sea level without one) through ``spec.atmosphere``: its
    irradiance times the direct sun's colour there (``optics.air.sun_rgb``). The sky model's radiance is
    scaled to this sun, keeping the model's sky-to-sun ratio at the ground."""
    h = 0.0 if spec.ground is None else max(float(spec.ground.height), 0.0)
    rgb = np.asarray(_sun_rgb_at(spec.atmosphere, h, float(spec.sun.mu0)))
    return replace(spec.sun, irradiance=tuple(float(v) for v in np.asarray(spec.sun.irradiance) * rgb))


@functools.lru_cache(maxsize=32)
def _sun_rgb_at(atm, h_m: float, mu0: float) -> tuple:
    """``optics.air.sun_rgb`` at one height and sun, kept (a viewer's sun dragged in azimuth asks it every frame)."""
    from ..optics.air import sun_rgb
    return tuple(sun_rgb(atm, h_m, mu0))


def _air_extent(bbox) -> tuple[float, float]:
    """(The air table's top: 2 km above the box (m above sea level), the box's half width from its centre)."""
    (x0, y0, _), (x1, y1, z1) = bbox
    return max(float(z1), 0.0) + 2000.0, float(np.hypot(max(abs(x0), abs(x1)), max(abs(y0), abs(y1))))


def _air_box(vol: OpticalVolume):
    """The box of the air inside the medium (None without it): the volume's, unbounded in x and y when periodic."""
    if air_in_medium(vol) is None:
        return None
    (x0, y0, z0), (x1, y1, z1) = vol.bbox
    if vol.periodic:
        x0, y0, x1, y1 = -1e12, -1e12, 1e12, 1e12
    return (x0, y0, z0), (x1, y1, z1)


def integrator_air(sun: Sun, atmosphere, bbox, air_box=None, band_nm=None) -> dict:
    """Properties of ``majorant_volpath`` that colour its sun by the air on the sun's path
    (``optics.air.sun_air_table``; the kernel's frame has the box's centre at x = y = 0, heights above sea
    level, the Earth's centre below it): heights up to 2 km above the box, mu over the box's width.
    ``air_box``: the box that holds the air (tracked; None: none), so the sun's colour is the table's where
    the sun ray leaves it (``sun_air_box``), not at the vertex. ``band_nm``: one wavelength per channel (a
    satellite's bands, ``BoxAir.band_nm``): the table holds the direct beam's transmittance there."""
    import mitsuba as mi
    from ..optics.air import sun_air_table
    from ..optics.air.shell import EARTH_RADIUS_M
    top, half = _air_extent(bbox)
    table = sun_air_table(atmosphere, sun.mu0, top_m=top, half_width_m=half, band_nm=band_nm)
    return {"sun_air": mi.TensorXf(table.rgb), "sun_air_h0": float(table.heights_m[0]),
            "sun_air_h1": float(table.heights_m[-1]), "sun_air_mu0": float(table.mu[0]),
            "sun_air_mu1": float(table.mu[-1]), "sun_air_radius": float(EARTH_RADIUS_M),
            **({"sun_air_box": mi.TensorXf(np.array([*air_box[0], *air_box[1]], np.float32))} if air_box is not None else {})}


def integrator_sun_spectrum(sun: Sun, atmosphere, bbox) -> dict:
    """Spectral variants: ``majorant_volpath``'s sun spectrum (``optics.spectral.sun_spectrum``, luminance 1
    above the air), after ``atmosphere`` by height and mu where given (on ``integrator_air``'s grid; None:
    none), times 1 / MI_CIE_Y_NORMALIZATION: Mitsuba's film gives X, Y, Z = integral L xbar dlambda /
    integral ybar dlambda, so a white ground lit by it has the CIE XYZ of ``optics.air.sun_xyz``."""
    import mitsuba as mi
    from ..optics import spectral, spectrum
    wl = spectrum.WAVELENGTHS_NM
    scale = 1.0 / float(mi.MI_CIE_Y_NORMALIZATION)
    d = {"sun_spectrum": mi.TensorXf((spectral.sun_spectrum(wl) * scale).astype(np.float32)),
         "sun_spectrum_nm": mi.TensorXf(np.array([wl[0], wl[-1]], np.float32))}
    if atmosphere is not None:  # the RGB table of integrator_air replaced by the spectra on its grid
        _, _, table = spectral.sun_spectral_table(atmosphere, sun.mu0, *_air_extent(bbox), wl)
        d["sun_air"] = mi.TensorXf(table * np.float32(scale))
    return d


def integrator_dict(vol: OpticalVolume, integrator: str, max_depth: int, rr_depth: int | None = None,
                    cell: int | None = None, sun: Sun | None = None, sun_guiding: float = 0.0, legacy: bool = False,
                    aureole_nee: float = 0.0, mvnee: float = 0.0, atmosphere=None) -> dict:
    """Mitsuba integrator dict: stock ``volpath`` or ``majorant_volpath``.

    Parameters
    ----------
    vol : OpticalVolume
        The volume rendered (kernel-side coordinates): ``majorant_volpath``'s majorant grid is built from
        its extinction (1/m) and placed on its bbox (m).
    integrator : str
        "volpath" or "majorant" (``majorant_volpath``).
    max_depth : int
        Longest path (-1: unbounded).
    rr_depth : int or None
        Depth at which Russian roulette starts (None: the integrators' default, 5; a huge value turns it off).
    cell : int or None
        Fine voxels per coarse majorant cell, ``cell``^3 ("majorant"; None: the plugin's ``DEFAULT_CELL``).
    sun : Sun or None
        A sun that ``majorant_volpath`` samples itself at every vertex (a disk with MIS, or a point);
        None: the sun is a scene emitter.
    sun_guiding, aureole_nee, mvnee : float
        Probabilities of sun guiding, of the aureole estimator and of multiple-vertex NEE (with ``sun``;
        see ``render_reference``).
    legacy : bool
        The estimator before issue 10 ("majorant"; see ``render_reference``).
    atmosphere : optics.air.Atmosphere or None
        The air on the sun's path (``integrator_air``; needs ``sun``); None: the sun as it is given.

    Returns
    -------
    dict
        The integrator's Mitsuba dict (``mi.load_dict``-ready inside a scene dict).
    """
    if vol.periodic and (integrator == "volpath" or legacy):
        raise ValueError("periodic volumes render with majorant_volpath's default estimator only "
                         f"(integrator='majorant', legacy=False), not integrator={integrator!r}, legacy={legacy}")
    if atmosphere is not None and (integrator != "majorant" or sun is None or legacy):
        raise ValueError("the atmosphere on the sun's path needs the integrator's own sun: integrator "
                         "'majorant' without legacy (or atmosphere None)")
    if integrator == "volpath":
        d = {"type": "volpath", "max_depth": int(max_depth)}
    else:
        import mitsuba as mi
        from .plugins.hydrometeor_mixture import bbox_transform
        from .plugins.majorant_volpath import DEFAULT_CELL, majorant_grid
        ensure_registered()
        cell = DEFAULT_CELL if cell is None else cell
        from .plugins.air_levels import with_coarse_air
        beta = pad_levels(vol.beta_total) if vol.periodic else vol.beta_total  # the medium's grids (medium.py)
        majorant = majorant_grid(beta, cell=int(cell))
        air = air_in_medium(vol)
        levels = None
        if air is not None:  # the air's levels, which the trackers cross as empty space (plugins/air_levels.py)
            if mi.is_spectral:  # over wavelength (kernel/spectral_air.py): the majorant bounds every wavelength's
                from .spectral_air import extinction_levels
                levels = extinction_levels(vol, air)
            else:
                levels = air.extinction_levels
                levels = np.ascontiguousarray(pad_levels(levels) if vol.periodic else levels)
            majorant = with_coarse_air(majorant, levels, int(cell))  # a bound of the hydrometeors' and the air's sum
        d = {"type": "majorant_volpath", "max_depth": int(max_depth), "cell": int(cell),
             "majorant": mi.TensorXf(majorant), "to_world": bbox_transform(grid_bbox(vol))}
        if vol.periodic:
            d.update({"periodic": "transport" if vol.periodic == "transport" else "view", "periodic_tiles": PATH_TILES})
        if levels is not None and mi.is_spectral:  # the air over wavelength (kernel/spectral_air.py)
            from .spectral_air import integrator_properties
            d.update(integrator_properties(vol, air))
        elif levels is not None:  # and its albedo with the hydrometeors' (where the medium leaves the air to it)
            d.update({"air_extinction": mi.TensorXf(levels), **integrator_air_albedo(vol, air)})
        if sun is not None:
            d.update(integrator_sun(sun, sun_guiding, aureole_nee, mvnee))
        if atmosphere is not None:
            band_nm = getattr(getattr(vol, "air", None), "band_nm", None)  # a satellite's bands: transmittance
            d.update(integrator_air(sun, atmosphere, vol.bbox, _air_box(vol), band_nm))
        if sun is not None and mi.is_spectral:
            d.update(integrator_sun_spectrum(sun, atmosphere, vol.bbox))
        if legacy:  # the estimator before issue 10 (see render_reference)
            d.update({"rr_mode": "volpath", "phase_channels": "mean", "emitter_nee": 1.0, "tracking_grid": "coarse",
                      "transmittance": "ratio", "persistent_lanes": False})
    if rr_depth is not None:
        d["rr_depth"] = int(rr_depth)
    return d


def _inside(p, box) -> bool:
    lo, hi = box
    return bool(np.all(np.asarray(p) > lo) and np.all(np.asarray(p) < hi))


def scene_dict(spec: SceneSpec, vol: OpticalVolume, integrator: dict) -> dict:
    """The whole Mitsuba scene: camera, sun, sky, ground, the medium in its box, the integrator.
    The sun is a ``directional`` emitter unless the integrator carries it (``integrator_sun``). A
    camera inside the medium's box carries the medium (its rays start in it)."""
    ensure_registered()
    require_flat_ground(vol, vol.periodic)
    terrain = getattr(vol, "terrain", None) if spec.ground is not None else None
    floor = None if spec.ground is None else spec.ground.height  # over a terrain medium_box uses the terrain
    box = medium_shape_dict(vol, floor, not air_by_integrator(integrator))
    sensor = sensor_dict(spec)
    d = {"type": "scene", "integrator": integrator, "sensor": sensor, "medium_box": box}
    if "sun_direction" not in integrator:
        d["sun"] = sun_dict(spec.sun)
    if terrain is not None or _inside(spec.camera.origin, medium_box(vol, floor)):
        d["weather_medium"] = box["interior"]
        box["interior"] = {"type": "ref", "id": "weather_medium"}
        if _inside(spec.camera.origin, medium_box(vol, floor)):
            sensor["medium"] = {"type": "ref", "id": "weather_medium"}
    if spec.has_air_sky:  # the air's diffuse sky into the box, not seen directly
        if spec.sun.mu0 > 0.0:  # spectral variants: the envmap's RGB upsampled by Mitsuba (kernel.air_sky)
            from .air_sky import EMITTER_NEE, air_sky_dict
            d["sky"] = air_sky_dict(spec, vol.bbox)
            nee = {"emitter_nee": EMITTER_NEE} if integrator.get("type") == "majorant_volpath" else {}
            d["integrator"] = {**nee, **integrator, "hide_emitters": True}
    elif spec.sky is not None:
        d["sky"] = sky_dict(spec.sky, spec.sun if spec.atmosphere is None else sun_below_air(spec))
    if terrain is not None:  # the terrain mesh and a flat surround (Ground.height unused; its albedo too)
        d.update(terrain_ground_dicts(terrain, {"type": "ref", "id": "weather_medium"}, vol.bbox))
    elif spec.ground is not None:
        d["ground"] = ground_dict(spec, vol.bbox)
    return d
