"""Exact triangle kernels (Paper 3 narrow phase) against independent oracles.

* distance: coal's one-triangle BVH distance (independent code) and, as a
  feasibility check, dense random sampling of both triangles (an upper bound); the
  kernel's points lie on their triangles at the reported distance;
* intersection: an independent numpy separating-axis test (2 normals, 9 edge
  crosses and, for coplanar pairs, 6 in-plane edge normals) on well-conditioned
  random pairs, and ``intersect <=> distance == 0`` everywhere;
* hand-made degenerate cases: shared vertex/edge, coplanar overlap, parallel
  planes, zero-area triangles.
"""

from __future__ import annotations

import numpy as np
import pytest

from geomkit._kernels.triangles import (segment_segment_closest, triangle_triangle_distance,
                                        triangles_intersect)


def dist(T1, T2):
    p = np.empty(3)
    q = np.empty(3)
    d = triangle_triangle_distance(np.ascontiguousarray(T1, float),
                                   np.ascontiguousarray(T2, float), p, q)
    return d, p, q


def coal_distance(T1, T2):
    """Independent: coal's distance between two one-triangle BVH models."""
    coal = pytest.importorskip("coal")

    def bvh(T):
        m = coal.BVHModelOBBRSS()
        m.beginModel(1, 3)
        m.addVertices(np.asarray(T, float))
        m.addTriangles(np.array([[0, 1, 2]]))
        m.endModel()
        return m
    res = coal.DistanceResult()
    return coal.distance(bvh(T1), coal.Transform3s(), bvh(T2), coal.Transform3s(),
                         coal.DistanceRequest(), res)


def sampled_distance(T1, T2, n=1500, seed=0):
    """Independent upper bound: closest pair among random points of both triangles
    (corners and edge points included)."""
    rng = np.random.default_rng(seed)
    w = np.vstack([np.eye(3), rng.dirichlet([1, 1, 1], n),
                   rng.dirichlet([1, 1], n // 3) @ np.eye(3)[:2]])
    X = w @ T1
    Y = w @ T2
    return np.sqrt(((X[:, None, :] - Y[None, :, :]) ** 2).sum(-1).min())


def on_triangle(X, T, tol):
    """Distance from X to the plane + barycentric inside test, tolerant."""
    A, B, C = T
    n = np.cross(B - A, C - A)
    M = np.column_stack([B - A, C - A, n])
    u, v, h = np.linalg.solve(M, X - A)
    return abs(h) * np.linalg.norm(n) <= tol and u >= -tol and v >= -tol and u + v <= 1 + tol


def sat_intersect(T1, T2):
    """Independent numpy SAT for non-degenerate triangles; None if ill-conditioned."""
    e1 = np.roll(T1, -1, axis=0) - T1
    e2 = np.roll(T2, -1, axis=0) - T2
    n1 = np.cross(e1[0], e1[1])
    n2 = np.cross(e2[0], e2[1])
    axes = [n1, n2] + [np.cross(a, b) for a in e1 for b in e2]
    if np.linalg.norm(np.cross(n1, n2)) < 1e-6 * np.linalg.norm(n1) * np.linalg.norm(n2):
        axes += [np.cross(n1, e) for e in e1] + [np.cross(n1, e) for e in e2]
    margin = np.inf
    for L in axes:
        ln = np.linalg.norm(L)
        if ln < 1e-9:
            continue
        L = L / ln
        a = T1 @ L
        b = T2 @ L
        gap = max(a.min() - b.max(), b.min() - a.max())
        if gap > 0:
            return False if gap > 1e-9 else None
        margin = min(margin, -gap)
    return True if margin > 1e-9 else None


def random_pairs(n, seed):
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        T1 = rng.normal(size=(3, 3))
        T2 = rng.normal(size=(3, 3)) * rng.choice([0.2, 1.0, 3.0]) + rng.normal(size=3) * \
            rng.choice([0.0, 0.5, 2.0])
        out.append((T1, T2))
    return out


def test_distance_matches_qp_and_points_are_valid():
    worst = 0.0
    for k, (T1, T2) in enumerate(random_pairs(300, 1)):
        d, p, q = dist(T1, T2)
        ref = coal_distance(T1, T2)
        assert abs(d - ref) <= 1e-9 * (1 + ref), (T1.tolist(), T2.tolist(), d, ref)
        worst = max(worst, abs(d - ref))
        if k % 10 == 0:
            assert d <= sampled_distance(T1, T2) + 1e-12
        assert abs(np.linalg.norm(p - q) - d) <= 1e-14 * (1 + d)
        assert on_triangle(p, T1, 1e-9) and on_triangle(q, T2, 1e-9)
        # symmetric
        d2, p2, q2 = dist(T2, T1)
        assert abs(d - d2) <= 1e-12 * (1 + d)


def test_intersect_matches_independent_sat():
    checked = hits = 0
    rng = np.random.default_rng(2)
    for k in range(3000):
        T1 = rng.normal(size=(3, 3))
        T2 = rng.normal(size=(3, 3)) + rng.normal(size=3) * 0.7
        ref = sat_intersect(T1, T2)
        got = triangles_intersect(T1, T2)
        d, p, q = dist(T1, T2)
        assert got == (d == 0.0)
        if got:
            assert on_triangle(p, T1, 1e-9) and on_triangle(p, T2, 1e-9)
        if ref is None:
            continue
        checked += 1
        hits += got
        assert got == ref, (T1.tolist(), T2.tolist())
    assert checked > 2500 and 200 < hits < checked - 200


def test_touching_and_coplanar_cases():
    A = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    # shared vertex, shared edge, coplanar overlap, coplanar disjoint
    assert triangles_intersect(A, np.array([[0.0, 0, 0], [-1, 0, 0], [0, -1, 0]]))
    assert triangles_intersect(A, np.array([[1.0, 0, 0], [0, 1, 0], [1, 1, 0]]))
    assert triangles_intersect(A, A + [0.2, 0.2, 0])
    assert triangles_intersect(A, A * 0.1 + [0.1, 0.1, 0])   # contained
    far = A + [2.0, 0, 0]
    assert not triangles_intersect(A, far)
    d, p, q = dist(A, far)
    assert d == pytest.approx(1.0)
    # vertex touching the face interior from above; edge crossing the interior
    assert triangles_intersect(A, np.array([[0.2, 0.2, 0], [0.2, 0.2, 1], [0.5, 0.2, 1]]))
    T = np.array([[0.2, 0.2, -1], [0.2, 0.2, 1], [3, 3, 0]])
    assert triangles_intersect(A, T)
    d, p, q = dist(A, T)
    assert d == 0.0 and on_triangle(p, A, 1e-12)
    # parallel planes
    d, p, q = dist(A, A + [0.1, 0.1, 0.5])
    assert d == pytest.approx(0.5, rel=1e-14) and not triangles_intersect(A, A + [0, 0, 0.5])
    # vertex above the face interior: face foot is the closest point
    U = np.array([[0.2, 0.3, 0.7], [0.2, 0.3, 5], [1, 1, 5]])
    d, p, q = dist(A, U)
    assert d == pytest.approx(0.7) and np.allclose(p, [0.2, 0.3, 0])


def test_degenerate_triangles():
    A = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    seg = np.array([[0.2, 0.2, -1], [0.2, 0.2, 1], [0.2, 0.2, 0.5]])   # zero area
    assert triangles_intersect(A, seg) and triangles_intersect(seg, A)
    pt = np.array([[0.3, 0.3, 0.0]] * 3)                                 # a point
    assert triangles_intersect(A, pt)
    d, p, q = dist(A, pt + [0, 0, 0.25])
    assert d == pytest.approx(0.25)
    d, p, q = dist(pt + [0, 0, 0.25], A)
    assert d == pytest.approx(0.25)
    d, p, q = dist(seg + [2, 0, 0], A)
    assert d == pytest.approx(coal_distance(seg + [2, 0, 0], A), abs=1e-9)


def test_segment_segment_parallel_and_points():
    P = np.array([0.0, 0, 0])
    Q = np.array([1.0, 0, 0])
    d2, s, t = segment_segment_closest(P, Q, np.array([0.5, 1, 0]), np.array([3.0, 1, 0]))
    assert d2 == pytest.approx(1.0)
    d2, s, t = segment_segment_closest(P, P, np.array([0.5, 1, 0]), np.array([0.5, -1, 0]))
    assert d2 == pytest.approx(0.25)
