"""The regridding's compiled column passes (``io.vertical.VerticalPlan``, its ``average``) against the numpy
expressions they replaced (written out here), bit for bit, on terrain-following columns whose target cells reach
below the surface and above the model top; and against closed forms: a linear profile is reproduced exactly,
a column's integral is conserved."""
from __future__ import annotations

import numpy as np
import pytest

from weather_mi.io.vertical import VerticalPlan, cell_averages


def numpy_nodes(z_w, z_mass):
    z_w = np.asarray(z_w, np.float64)
    z_mass = 0.5 * (z_w[1:] + z_w[:-1]) if z_mass is None else z_mass
    return np.concatenate([z_w[:1], z_mass, z_w[-1:]], axis=0, dtype=np.float64)


def numpy_plan(z_w, edges, z_mass):
    """(k, t): the plan's numpy expressions (weather-mi before the compiled pass)."""
    nodes, n = numpy_nodes(z_w, z_mass), z_w.shape[0] - 1
    k_all, t_all = [], []
    for e in np.asarray(edges, np.float64):
        k = np.clip((nodes <= e).sum(axis=0) - 1, 0, n)
        z0 = np.take_along_axis(nodes, k[None], 0)[0]
        z1 = np.take_along_axis(nodes, k[None] + 1, 0)[0]
        k_all.append(k)
        t_all.append(np.clip(e - z0, 0.0, z1 - z0).astype(np.result_type(z_w.dtype, np.float32)))
    return np.stack(k_all), np.stack(t_all)


def numpy_average(z_w, edges, z_mass, f, dtype):
    """The average's numpy expressions (weather-mi before the compiled pass)."""
    k_all, t_all = numpy_plan(z_w, edges, z_mass)
    nodes = numpy_nodes(z_w, z_mass)
    out = np.empty((len(edges) - 1,) + f.shape[1:], dtype)
    dz = np.diff(np.asarray(edges, np.float64))
    vals = np.concatenate([f[:1], f, f[-1:]], axis=0, dtype=np.float64)
    slope = np.diff(vals, axis=0)
    h = np.diff(nodes, axis=0)
    np.divide(slope, h, out=slope, where=h > 0)
    slope[h <= 0] = 0.0
    seg = 0.5 * (vals[1:] + vals[:-1]) * np.diff(nodes, axis=0)
    cum = np.concatenate([np.zeros_like(seg[:1]), np.cumsum(seg, axis=0)], axis=0)
    prev = None
    for j in range(len(edges)):
        k = k_all[j][None].astype(np.intp)
        t = t_all[j].astype(np.float64)
        nxt = np.take_along_axis(cum, k, 0)[0] + t * (np.take_along_axis(vals, k, 0)[0]
                                                      + 0.5 * np.take_along_axis(slope, k, 0)[0] * t)
        if prev is not None:
            out[j - 1] = (nxt - prev) / dz[j - 1]
        prev = nxt
    return out


def columns(n=30, ny=7, nx=9, seed=0):
    rng = np.random.default_rng(seed)
    ground = rng.uniform(0, 1500, (ny, nx))
    depth = np.cumsum(rng.uniform(50, 900, (n, ny, nx)), axis=0)
    z_w = np.concatenate([ground[None], ground[None] + depth]).astype(np.float32)
    return z_w, rng.gamma(0.5, 1e-3, (n, ny, nx)).astype(np.float32)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("given_mass", [False, True, "unordered"])
def test_compiled_plan_and_average_equal_the_numpy_expressions_bit_for_bit(dtype, given_mass):
    from weather_mi.io.vertical import COLUMNS
    z_w, f = columns(ny=23, nx=29)
    assert z_w[0].size > 2 * COLUMNS and z_w[0].size % COLUMNS  # several blocks of columns, a partial last one
    z_mass = (0.3 * z_w[1:] + 0.7 * z_w[:-1]).astype(np.float32) if given_mass else None
    if given_mass == "unordered":  # nodes out of order in some columns: counted, not walked
        z_mass[[3, 4], :2] = z_mass[[4, 3], :2] + np.float32(5000.0)
    edges = np.linspace(-300.0, float(z_w[-1].max()) + 700.0, 41)  # below every surface, above every top
    plan = VerticalPlan(z_w, edges, z_mass)
    k, t = numpy_plan(z_w, edges, z_mass)
    assert np.array_equal(plan.k, k) and plan.t.dtype == t.dtype and np.array_equal(plan.t, t)
    got = plan.average(f, dtype=dtype)
    assert got.dtype == dtype and np.array_equal(got, numpy_average(z_w, edges, z_mass, f, dtype))
    below = edges[1:, None, None] <= z_w[0][None]  # cells under the surface, over the top: empty
    above = edges[:-1, None, None] >= z_w[-1][None]
    assert below.any() and above.any() and np.all(got[below | above] == 0) and np.any(got > 0)


def test_a_linear_profile_is_kept_and_the_column_integral_conserved():
    z_w, _ = columns(seed=1)
    z_w = z_w.astype(np.float64)
    z_mass = 0.5 * (z_w[1:] + z_w[:-1])
    f = 2e-3 + 1e-7 * z_mass  # linear in height
    edges = np.linspace(float(z_mass[0].max()), float(z_mass[-1].min()), 25)  # between every column's mass levels
    got = cell_averages(z_mass, z_w, f, edges)
    mid = 0.5 * (edges[1:] + edges[:-1])
    np.testing.assert_allclose(got, np.broadcast_to((2e-3 + 1e-7 * mid)[:, None, None], got.shape), rtol=1e-12)
    full = np.linspace(float(z_w[0].min()) - 100, float(z_w[-1].max()) + 100, 200)
    integral = cell_averages(z_mass, z_w, f, full).sum(axis=0) * (full[1] - full[0])
    # the reconstruction: linear between mass levels, constant to the surface and to the top
    dz_w = np.diff(z_w, axis=0)
    exact = (f * dz_w).sum(axis=0)  # the trapezoids of a linear f are exact except the two end pieces
    lo = (z_mass[0] - z_w[0]) * (f[0] - (2e-3 + 1e-7 * 0.5 * (z_w[0] + z_mass[0])))
    hi = (z_w[-1] - z_mass[-1]) * (f[-1] - (2e-3 + 1e-7 * 0.5 * (z_w[-1] + z_mass[-1])))
    np.testing.assert_allclose(integral, exact + lo + hi, rtol=1e-10)
