"""Plain-Python reference evaluators, independent of geomkit's kernels.

* :func:`basis_all` — every B-spline basis function N_{i,p}(u) by the Cox–de Boor
  recursion (works for clamped *and* unclamped knot vectors; 0/0 := 0).
* :func:`surface_point` — S(u, v) = sum N_i(u) N_j(v) w_ij P_ij / sum N_i(u) N_j(v) w_ij
  straight from the definition (no span search tricks, no homogeneous kernels).
* :func:`bezier_point` — a rational tensor-product Bézier patch evaluated with
  explicit Bernstein polynomials on a sub-domain [u0, u1] x [v0, v1].

They are slow and only meant for tests.
"""

from __future__ import annotations

from math import comb

import numpy as np

__all__ = ["domain_span", "basis_all", "surface_point", "surface_points", "bernstein",
           "bezier_point"]


def domain_span(U, p, n, u):
    """The knot span index used for ``u`` on the domain [U[p], U[n]] (n = #control pts).

    The last ``i`` in ``[p, n-1]`` with ``U[i] <= u`` and ``U[i] < U[i+1]`` (so spans are
    half-open ``[U[i], U[i+1])`` and the right end of the domain belongs to the last
    non-empty span).
    """
    U = [float(x) for x in U]
    best = None
    for i in range(p, n):
        if U[i] < U[i + 1] and U[i] <= u:
            best = i
    if best is None:
        raise ValueError(f"u = {u!r} is left of the domain start {U[p]!r}")
    return best


def basis_all(U, p, n, u):
    """All n basis functions N_{i,p}(u), i = 0..n-1, by Cox–de Boor."""
    U = [float(x) for x in U]
    m = len(U) - 1
    s = domain_span(U, p, n, u)
    # degree 0: indicator of the chosen span (length m)
    N = [1.0 if i == s else 0.0 for i in range(m)]
    for k in range(1, p + 1):
        nxt = []
        for i in range(m - k):
            val = 0.0
            d1 = U[i + k] - U[i]
            if d1 != 0.0 and N[i] != 0.0:
                val += (u - U[i]) / d1 * N[i]
            d2 = U[i + k + 1] - U[i + 1]
            if d2 != 0.0 and N[i + 1] != 0.0:
                val += (U[i + k + 1] - u) / d2 * N[i + 1]
            nxt.append(val)
        N = nxt
    return N[:n]


def surface_point(degree_u, degree_v, knots_u, knots_v, control_points, weights, u, v):
    """S(u, v) from the definition; ``weights`` may be None (non-rational)."""
    P = np.asarray(control_points, float)
    nu, nv = P.shape[:2]
    W = np.ones((nu, nv)) if weights is None else np.asarray(weights, float)
    Nu = basis_all(knots_u, degree_u, nu, float(u))
    Nv = basis_all(knots_v, degree_v, nv, float(v))
    num = [0.0, 0.0, 0.0]
    den = 0.0
    for i in range(nu):
        if Nu[i] == 0.0:
            continue
        for j in range(nv):
            if Nv[j] == 0.0:
                continue
            b = Nu[i] * Nv[j] * W[i, j]
            den += b
            for c in range(3):
                num[c] += b * P[i, j, c]
    return np.array([x / den for x in num])


def surface_points(degree_u, degree_v, knots_u, knots_v, control_points, weights, uv):
    uv = np.asarray(uv, float).reshape(-1, 2)
    return np.array([surface_point(degree_u, degree_v, knots_u, knots_v, control_points,
                                   weights, u, v) for u, v in uv]).reshape(-1, 3)


def bernstein(p, t):
    """[B_{0,p}(t), ..., B_{p,p}(t)] = C(p, i) t^i (1 - t)^(p - i)."""
    return [comb(p, i) * t ** i * (1.0 - t) ** (p - i) for i in range(p + 1)]


def bezier_point(Hw, u, v, u0, u1, v0, v1):
    """Point of a rational Bézier patch with homogeneous net ``Hw`` (p+1, q+1, 4)
    (rows ``(w x, w y, w z, w)``) at (u, v) of its sub-domain [u0, u1] x [v0, v1]."""
    Hw = np.asarray(Hw, float)
    p, q = Hw.shape[0] - 1, Hw.shape[1] - 1
    s = (u - u0) / (u1 - u0)
    t = (v - v0) / (v1 - v0)
    Bu = bernstein(p, s)
    Bv = bernstein(q, t)
    acc = [0.0, 0.0, 0.0, 0.0]
    for i in range(p + 1):
        for j in range(q + 1):
            b = Bu[i] * Bv[j]
            for c in range(4):
                acc[c] += b * Hw[i, j, c]
    return np.array(acc[:3]) / acc[3]
