"""The air along a segment of an eye ray by Gauss-Legendre quadrature (issue 38 part 3: fewer points per coarse
ray at the accuracy of ``eye_air.segment``'s 33 trapezoids).

On x in [0, 1] (s = t0 + L x, or s = t0 + L x^2 dense near the camera: ds = 2 L x dx) the segment's two
integrals are

    tau(x) = int_0^x ext(s(u)) s'(u) du,    T = exp(-tau(1)),    S = int_0^1 src(s(x)) exp(-tau(x)) s'(x) dx

(``eye_air``'s extinction and source: the 1-D air's tables by height, the sun's colour C(h, mu), the storm's
shadow). Both are taken on the n Gauss-Legendre nodes x_i, weights w_i of [0, 1]:

    S = sum_i w_i src_i exp(-tau_i) s'_i,    tau_i = sum_j A_ij ext_j s'_j,    tau(1) = sum_j w_j ext_j s'_j

with A_ij = int_0^{x_i} l_j(u) du the integral of the Lagrange polynomial through the nodes that is 1 at x_j
(Gauss collocation's integration matrix: tau at the nodes exact for a polynomial integrand of degree n - 1,
the sum for S for degree 2n - 1). The air's profile is smooth along a ray (the aerosol's 1.2 km scale height
over a few e-folds): on the demo supercell's drag (sun 4 and 35 deg) S within 0.23% of the trapezoids on 257
points for 99% of the coarse rays (T within 1.5e-3) on 12 nodes, 0.83% on 8, where the 33 trapezoids before
were within 1.3% (T 4e-2). The storm's shadow is a step on the source, which any rule resolves only to its
spacing: 8 nodes missed the cloud ball's long shadow at a 4 deg sun by 8% in blue (tests/test_slicing_air.py,
the trapezoids 4% the other way), 12 by 2.3-2.8%. Each node evaluates the source once (unrolled: no loop, no
storage), the matrix is n^2 multiply-adds per colour; rays whose segment is empty evaluate none. Checked
against the closed forms of a homogeneous path and of an exponential atmosphere along a vertical ray
(tests/test_eye_air_quadrature.py).
"""
from __future__ import annotations

import functools

import numpy as np

NODES = 12   # Gauss-Legendre nodes on the eye rays' segment outside the box (the trapezoids had 33)


@functools.lru_cache(maxsize=8)
def rule(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, w, A): the n Gauss-Legendre nodes and weights on [0, 1] and the integration matrix A_ij =
    int_0^{x_i} l_j(u) du (module docstring), float64."""
    t, wt = np.polynomial.legendre.leggauss(n)
    x, w = 0.5 * (t + 1.0), 0.5 * wt
    a = np.empty((n, n))
    for j in range(n):
        c = np.zeros(n)
        c[j] = 1.0
        # l_j in the Legendre basis on [-1, 1] (exact interpolation through the n nodes), integrated from -1
        lj = np.polynomial.legendre.Legendre.fit(t, c, n - 1, domain=[-1.0, 1.0], window=[-1.0, 1.0])
        integral = lj.integ(lbnd=-1.0)
        a[:, j] = 0.5 * integral(t)
    return x, w, a


def gauss_segment(mi, source, t0, t1, n: int, squared: bool):
    """(T, S) (mi.Color3f) of rays over [t0, t1] on ``n`` Gauss-Legendre nodes (module docstring); ``source``:
    distances s along the rays -> (extinction, source) (mi.Color3f; ``eye_air.source_at``). T = 1, S = 0 where
    t1 <= t0."""
    import drjit as dr
    x, w, a = rule(n)
    length = dr.maximum(t1 - t0, 0.0)

    def integrate(t0, length):
        g_ext, g_src = [], []
        for xi in x:
            xi = float(xi)
            s = t0 + length * (xi * xi if squared else xi)
            jac = length * (2.0 * xi if squared else 1.0)  # ds / dx
            ext, src = source(s)
            g_ext.append(ext * jac)
            g_src.append(src * jac)
        tau_end = sum((float(w[j]) * g_ext[j] for j in range(1, n)), float(w[0]) * g_ext[0])
        S = mi.Color3f(0.0)
        for i in range(n):
            tau_i = sum((float(a[i, j]) * g_ext[j] for j in range(1, n)), float(a[i, 0]) * g_ext[0])
            S += float(w[i]) * g_src[i] * dr.exp(-tau_i)
        return dr.exp(-tau_end), S
    # rays with an empty segment evaluate no node (LLVM skips a packet of them)
    return dr.if_stmt((t0, length), length > 0, integrate, lambda t0, length: (mi.Color3f(1.0), mi.Color3f(0.0)))

__all__ = ["NODES", "gauss_segment", "rule"]
