"""Terrain as the ground of the path-traced reference (issue 23 item 3): the height-field mesh of
``Terrain.mesh`` in the Mitsuba scene, against numbers not from our code."""
from __future__ import annotations

import numpy as np
import pytest

import mitsuba as mi

import weather_mi as wm
from weather_mi.kernel.scene_dict import integrator_dict, recentred, scene_dict
from weather_mi.io.terrain import Terrain

NZ, NY, NX, D = 4, 6, 7, 1000.0  # 1 km columns
ORIGIN = (4500.0, 20000.0, -30000.0)  # (z0, y0, x0) cell centres: off the origin, so recentring shows


def hydrometeors(height, albedo, q_cloud=0.0):
    """Clear (or thin-cloud) hydrometeors over a terrain (m above MSL) of (NY, NX) heights and albedos."""
    q = np.full((NZ, NY, NX), q_cloud)
    hyd = wm.from_arrays({"cloud": q}, 0.8, (D, D, D), origin=ORIGIN)
    dims = ("y", "x")
    return hyd.assign_coords(terrain_height=(dims, np.asarray(height, float)),
                             land=(dims, np.ones((NY, NX), np.int8)),
                             surface_albedo=(dims, np.broadcast_to(np.asarray(albedo, float), (NY, NX)).copy()))


def relief():
    y, x = np.mgrid[0:NY, 0:NX]
    return 3000.0 + 400.0 * np.sin(x * 0.9) * np.cos(y * 0.7) + 50.0 * x


def volume(hyd):
    return wm.optical_volume(hyd, phase_quality="test")


def nadir_spec(vol, elevation=50.0, irradiance=2.0, w=8, h=6):
    (x0, y0, _), (x1, y1, z1) = vol.bbox
    cam = wm.Camera.orthographic(center=((x0 + x1) / 2, (y0 + y1) / 2, z1 + 1000.0), direction=(0.0, 0.0, -1.0),
                                 width=(x1 - x0) * 0.5, height=(y1 - y0) * 0.5, up=(0.0, 1.0, 0.0))
    return wm.SceneSpec(camera=cam, sun=wm.Sun(140.0, elevation, irradiance=(irradiance,) * 3, angular_diameter_deg=0.0),
                        width=w, height=h, sky=None, ground=wm.Ground(albedo=(0.5, 0.5, 0.5), height=0.0), seed=3)


def test_terrain_travels_with_the_optical_volume():
    hyd = hydrometeors(relief(), 0.25)
    vol = volume(hyd)
    assert vol.terrain is not None
    np.testing.assert_array_equal(vol.terrain.height_m, hyd["terrain_height"].values)
    assert volume(wm.from_arrays({"cloud": np.zeros((NZ, NY, NX))}, 0.8, (D, D, D))).terrain is None
    spec_k, vol_k, c = recentred(nadir_spec(vol), vol)
    np.testing.assert_allclose(vol_k.terrain.x + c[0], hyd.x.values)
    np.testing.assert_allclose(vol_k.terrain.y + c[1], hyd.y.values)


def test_vertical_rays_hit_the_terrain_at_the_column_centres():
    h = relief()
    hyd = hydrometeors(h, 0.25)
    vol = volume(hyd)
    spec_k, vol_k, c = recentred(nadir_spec(vol), vol)
    scene = mi.load_dict(scene_dict(spec_k, vol_k, integrator_dict(vol_k, "volpath", -1)))
    gx, gy = np.meshgrid(hyd.x.values - c[0], hyd.y.values - c[1])
    # 1 cm towards the middle: a ray exactly on the mesh's outer boundary edge may miss it (the slope
    # changes the height by < 1 cm there)
    gx, gy = gx - 0.01 * np.sign(gx - gx.mean()), gy - 0.01 * np.sign(gy - gy.mean())
    n = gx.size
    o = mi.Point3f(mi.Float(gx.ravel()), mi.Float(gy.ravel()), mi.Float(np.full(n, 20000.0)))
    ray = mi.Ray3f(o, mi.Vector3f(mi.Float(np.zeros(n)), mi.Float(np.zeros(n)), mi.Float(-np.ones(n))))
    # the cube is null: step through it until an opaque surface (the terrain) is hit
    hit_z = np.full(n, np.nan)
    for _ in range(6):
        si = scene.ray_intersect(ray)
        z = np.array(si.p.z)
        valid = np.array(si.is_valid())
        null = np.array(mi.has_flag(si.bsdf().flags(), mi.BSDFFlags.Null)) & valid
        opaque = valid & ~null & np.isnan(hit_z)
        hit_z[opaque] = z[opaque]
        ray = si.spawn_ray(ray.d)
    np.testing.assert_allclose(hit_z, h.ravel(), atol=1.0)


@pytest.mark.parametrize("integrator", ["volpath", "majorant"])
def test_clear_sky_plateau_radiance_is_albedo_e_sin_e_over_pi(integrator):
    albedo, e, irr = 0.3, 50.0, 2.0
    vol = volume(hydrometeors(np.full((NY, NX), 4000.0), albedo))
    sp = nadir_spec(vol, elevation=e, irradiance=irr)
    img = wm.render_reference(sp, vol, spp=8, passes=2, progress=False, integrator=integrator, max_depth=4)
    want = albedo * irr * np.sin(np.radians(e)) / np.pi
    se = np.maximum(np.nan_to_num(img.stderr), 1e-6 * want)
    assert np.all(np.abs(img.radiance - want) <= 3 * se + 1e-5 * want), (img.radiance.mean(), want)


def test_no_terrain_scene_dict_unchanged():
    vol = volume(wm.from_arrays({"cloud": np.full((NZ, NY, NX), 1e-5)}, 0.8, (D, D, D), origin=ORIGIN))
    assert vol.terrain is None
    spec_k, vol_k, _ = recentred(nadir_spec(vol), vol)
    d = scene_dict(spec_k, vol_k, integrator_dict(vol_k, "volpath", -1))
    assert "terrain" not in d and "weather_medium" not in d and d["ground"]["type"] == "rectangle"
    assert d["medium_box"]["interior"]["type"] != "ref"


def test_skirt_faces_outwards_and_hides_the_mesh_underside():
    """The wall under the mesh's boundary: every face's normal (from its winding, as Mitsuba's face normals)
    points away from the grid's centre and is horizontal, no face is degenerate, and the faces' area is the
    wall's: per side, the trapezoids between the edge heights and the floor (by the trapezoid rule on the
    grid's boundary rows and columns)."""
    h = relief()
    hyd = hydrometeors(h, 0.25)
    terrain = wm.terrain.Terrain.of(hyd)
    floor = float(h.min())
    v, f, albedo = terrain.skirt(floor)
    assert len(albedo) == len(v)
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    centre = np.array([terrain.x.mean(), terrain.y.mean()])
    mid = v[f].mean(axis=1)[:, :2] - centre
    assert np.all(np.einsum("ij,ij->i", n[:, :2], mid) > 0) and np.allclose(n[:, 2], 0.0, atol=1e-6 * np.abs(n).max())
    area = 0.5 * np.linalg.norm(n, axis=1)
    assert np.all(area > 0)
    wall = sum(np.trapezoid(side - floor, dx=D) for side in (h[0], h[-1], h[:, 0], h[:, -1]))
    assert area.sum() == pytest.approx(wall, rel=1e-9)


def test_height_field_rays_meet_the_reference_mesh():
    """The slicer's ray-height-field intersection (``Terrain.ray_hits`` on ``Terrain.surface_at``) against
    Mitsuba's intersection of the reference's PLY mesh: the same points for slanted rays over the relief."""
    from weather_mi.kernel.scene_dict import _terrain_meshes
    terrain = Terrain.of(hydrometeors(relief(), 0.3))
    wm.set_variant("llvm_ad_rgb")
    scene = mi.load_dict({"type": "scene", "t": {"type": "ply", "filename": _terrain_meshes(terrain, 2000.0)[0][0]}})
    rng = np.random.default_rng(4)
    n = 500
    o = np.stack([rng.uniform(terrain.x[0], terrain.x[-1], n), rng.uniform(terrain.y[0], terrain.y[-1], n),
                  np.full(n, 8000.0)], 1)
    d = np.stack([rng.normal(size=n), rng.normal(size=n), -1.5 - rng.random(n)], 1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    t = terrain.ray_hits(o, d)
    si = scene.ray_intersect(mi.Ray3f(mi.Point3f(*(mi.Float(o[:, k]) for k in range(3))),
                                      mi.Vector3f(*(mi.Float(d[:, k]) for k in range(3)))))
    t_mesh = np.array(si.t)
    inside = np.isfinite(t_mesh) & (np.abs(o[:, 0] + t * d[:, 0] - terrain.x.mean()) < 2500)
    assert inside.sum() > 100
    np.testing.assert_allclose(t[inside], t_mesh[inside], atol=0.05)
    _, _, normal = terrain.surface_at(*(o + t[:, None] * d)[inside, :2].T)
    np.testing.assert_allclose(normal, np.array(si.n)[:, inside].T, atol=1e-4)


def test_slicer_ground_is_the_terrain_as_the_reference_sees_it():
    """Clear sky over the relief, nadir view, point sun, no sky: the slicer (numpy height field, albedo x
    E max(n . s, 0) / pi) and the path tracer (the PLY mesh, Lambertian, face normals) see the same ground:
    pixels within one facet agree within 0.5% (the median within 0.2%); pixels that straddle a facet edge
    differ (the reference's box filter averages a pixel's footprint, the slicer takes its centre), so 75% of
    them are asked to. The relief's slopes and albedo vary the radiance by over 10%."""
    from weather_mi.slicing import render_slices
    hyd = hydrometeors(relief(), np.linspace(0.2, 0.4, NX)[None, :] * np.ones((NY, 1)))
    vol = volume(hyd)
    spec = nadir_spec(vol, elevation=40.0, w=48, h=36)
    ref = wm.render_reference(spec, vol, spp=64, progress=False, max_depth=2).radiance[..., 0]  # direct light
    sl = np.asarray(render_slices(spec, vol, slices=16).radiance)[..., 0]
    assert np.std(ref) / np.mean(ref) > 0.1  # slopes and albedo show
    rel = np.abs(sl / ref - 1.0)
    assert np.median(rel) < 0.002 and np.mean(rel < 0.005) > 0.75, (np.median(rel), np.mean(rel < 0.005))
    assert abs(sl.mean() / ref.mean() - 1.0) < 0.01


def test_slicer_rays_meet_the_reference_ground_beyond_the_domain():
    """``Terrain.scene_hits`` against Mitsuba's intersection of the reference's whole ground
    (``terrain_ground_dicts``: the mesh with its apron and skirt, the surround beyond): rays from a camera
    250 km south of a plateau, over the domain, the apron and the surround out to the horizon, meet the
    same surfaces at the same distances, with the same normals and albedos. (The terrain's level
    continuation without apron and surround put the far ground at the edge's albedo: a dark wedge beyond
    the WRF plateau's domain, CIEDE2000 20.)"""
    from weather_mi.kernel.scene_dict import terrain_ground_dicts
    hyd = hydrometeors(relief(), np.linspace(0.1, 0.4, NX)[None, :] * np.ones((NY, 1)))
    terrain = Terrain.of(hyd)
    wm.set_variant("llvm_ad_rgb")
    vol = volume(hyd)
    grounds = terrain_ground_dicts(terrain, {"type": "homogeneous", "sigma_t": 0.0, "albedo": 0.0}, vol.bbox)
    scene = mi.load_dict({"type": "scene", **grounds})
    rng = np.random.default_rng(7)
    n = 4000
    o = np.tile([terrain.x.mean(), terrain.y.mean() - 250e3, 40e3], (n, 1))
    d = np.stack([rng.uniform(-0.6, 0.6, n), np.ones(n), -rng.uniform(0.02, 0.3, n)], 1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    floor = float(np.array(grounds["ground"]["to_world"].matrix)[2, 3])  # the scene's surround rectangle
    t, albedo, normal = terrain.scene_hits(o, d, floor_m=floor)
    si = scene.ray_intersect(mi.Ray3f(mi.Point3f(*(mi.Float(o[:, k]) for k in range(3))),
                                      mi.Vector3f(*(mi.Float(d[:, k]) for k in range(3)))))
    t_ref = np.array(si.t)
    hit = np.isfinite(t_ref) & np.isfinite(t)
    assert np.array_equal(np.isfinite(t), np.isfinite(t_ref))
    x = o[:, 0] + t * d[:, 0]
    beyond = hit & (np.abs(x - terrain.x.mean()) > 150e3)
    on_skirt = hit & (np.abs(normal[:, 2]) < 1e-6)
    assert beyond.sum() > 200 and on_skirt.sum() > 5 and (hit & ~beyond & ~on_skirt).sum() > 200
    np.testing.assert_allclose(t[hit], t_ref[hit], rtol=2e-5, atol=1.0)
    n_ref = np.array(si.n).T
    np.testing.assert_allclose(normal[hit], n_ref[hit] * np.sign(np.sum(n_ref[hit] * normal[hit], 1))[:, None], atol=1e-3)
    assert np.all(np.sum(n_ref[hit] * -d[hit], 1) > 0)  # every surface met faces the ray
    np.testing.assert_allclose(albedo[beyond], terrain.edge_albedo(), rtol=1e-6)
    # the slicer's surround height (terrain_surround_m) is that of the recentred scene the reference renders
    from weather_mi.kernel.scene_dict import recentred_volume, terrain_surround_m
    vol2, _ = recentred_volume(vol)
    rendered = terrain_ground_dicts(vol2.terrain, {"type": "homogeneous", "sigma_t": 0.0, "albedo": 0.0}, vol2.bbox)
    assert terrain_surround_m(vol) == pytest.approx(float(np.array(rendered["ground"]["to_world"].matrix)[2, 3]), abs=1e-3)


def test_slicer_ground_per_channel_is_the_references():
    """A terrain with an albedo per render channel (``Terrain.albedo_rgb``: ``scene.surface``'s ``file``): the
    slicer and the path tracer see the same coloured ground, channel by channel, as for one grey albedo."""
    from dataclasses import replace
    from weather_mi.slicing import render_slices
    hyd = hydrometeors(relief(), 0.3)
    vol = volume(hyd)
    gx = np.linspace(0.0, 1.0, NX)[None, :] * np.ones((NY, 1))
    rgb = np.stack([0.1 + 0.3 * gx, 0.25 * np.ones_like(gx), 0.4 - 0.3 * gx], -1)
    vol = replace(vol, terrain=replace(vol.terrain, albedo=rgb.mean(-1), albedo_rgb=rgb))
    spec = nadir_spec(vol, elevation=40.0, w=48, h=36)
    ref = np.asarray(wm.render_reference(spec, vol, spp=64, progress=False, max_depth=2).radiance)
    sl = np.asarray(render_slices(spec, vol, slices=16).radiance)
    assert np.corrcoef(ref[..., 0].ravel(), ref[..., 2].ravel())[0, 1] < 0  # the channels differ across x
    for c in range(3):
        rel = np.abs(sl[..., c] / ref[..., c] - 1.0)
        assert np.median(rel) < 0.002 and np.mean(rel < 0.005) > 0.75, (c, np.median(rel), np.mean(rel < 0.005))
