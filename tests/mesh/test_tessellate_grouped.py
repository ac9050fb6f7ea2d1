"""The grouped measure of trimmed grids (:func:`geomkit._kernels.tess_lattice.group_deviation`).

* against brute force on a flat, non-uniformly parametrized square: a clipped
  triangle's point is measured to the part of the surface its group covers (dense
  samples of the group's UV triangles), never to the surface beyond the trim;
* a cone cut by a wavy trim (the EUCLID screw's shape) meshed as one trimmed grid
  measured by groups, within ``tol`` of the face both ways (checked independently).
"""

from __future__ import annotations

import numpy as np

from geomkit import Surface
from geomkit._kernels.tess import triangle_deviation
from geomkit._kernels.tess_lattice import group_deviation
from geomkit.mesh.tessellate import tessellate
from geomkit.nurbs.evaluation import evaluate

from helpers import naive
from helpers.tesshelp import REL

S2 = np.sqrt(0.5)

NONUNIFORM_PLANE = dict(degree_u=1, degree_v=2, knots_u=[0, 0, 1, 1],
                        knots_v=[0, 0, 0, 0.123, 1, 1, 1],
                        control_points=[[[x, y, 0.0] for y in (0, 100 / 3, 200 / 3, 100)]
                                        for x in (0.0, 100.0)])


def _bary(k):
    return np.array([(1 - i / k - j / k, i / k, j / k) for i in range(k + 1)
                     for j in range(k + 1 - i)])


def _brute(s, tri_uv, group, t, k):
    """Sample by sample as the kernel measures triangle ``t`` (exact_above 0): the
    larger of the surface point's distance to the nearest triangle of its group and
    the triangle point's distance to the surface over the group's UV triangles
    (dense samples), never more than the gap; the largest over the samples, and the
    dense samples' spacing in 3-D (the longest image of a dense grid step)."""
    g = np.nonzero(group == group[t])[0]
    X3 = evaluate(s, tri_uv.reshape(-1, 2)).reshape(-1, 3, 3)
    n = 200
    ij = np.array([(i, j) for i in range(n) for j in range(n - i)])
    steps = []
    D = []
    for j in g:
        a, b, c = tri_uv[j]
        for di, dj in ((1, 0), (0, 1)):
            p0 = a + np.outer(ij[:, 0] / n, b - a) + np.outer(ij[:, 1] / n, c - a)
            p1 = p0 + (di * (b - a) + dj * (c - a)) / n
            steps.append(np.linalg.norm(evaluate(s, p0) - evaluate(s, p1), axis=1).max())
        D.append(a + np.outer(ij[:, 0] / n, b - a) + np.outer(ij[:, 1] / n, c - a))
    SD = evaluate(s, np.concatenate(D))
    B = _bary(k)
    worst = 0.0
    for b in B:
        if np.isclose(b, 1).any():
            continue
        uv = b @ tri_uv[t]
        P = evaluate(s, uv[None])[0]
        X = b @ X3[t]
        gap = np.linalg.norm(P - X)
        # the square is flat (z = 0): point-to-triangle distances in the plane
        import shapely
        d_st = min(shapely.distance(shapely.Point(P[:2]), shapely.Polygon(X3[j][:, :2]))
                   for j in g)
        d_ts = np.linalg.norm(SD - X, axis=1).min()
        worst = max(worst, min(gap, max(d_st, d_ts)))
    return worst, max(steps)


def test_group_measure_keeps_feet_in_the_group():
    """Clipped-looking triangles of a flat square whose v parametrization is not
    uniform: their flat images stick out of the surface region their UV triangles
    cover.  The kernel's value (an upper bound at each sample) is at least the brute
    force value less the dense sampling's spacing, and positive: feet sought on the
    whole plane would find the square beyond the group and measure ~0."""
    s = Surface(**NONUNIFORM_PLANE)
    tri_uv = np.array([[[0.2, 0.05], [0.6, 0.05], [0.4, 0.6]],     # group 0
                       [[0.6, 0.05], [0.8, 0.6], [0.4, 0.6]],      # group 0
                       [[0.1, 0.3], [0.5, 0.2], [0.3, 0.9]]])      # group 1 alone
    group = np.array([0, 0, 1])
    starts = np.array([0, 2, 3])
    xyz = evaluate(s, tri_uv.reshape(-1, 2)).reshape(-1, 3, 3)
    k = 6
    out = np.empty(3)
    group_deviation(s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                    np.ascontiguousarray(tri_uv), xyz, group, starts, k, 0.0, out)
    alone = np.empty(3)  # feet anywhere in the domain: triangle 1 measures ~0
    triangle_deviation(s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                       np.ascontiguousarray(tri_uv), xyz, k, 0.0, 1.0, 0.0, 1.0, 0.0, alone)
    for t in range(3):
        ref, slack = _brute(s, tri_uv, group, t, k)
        assert out[t] >= ref - slack, (t, out[t], ref, slack)
        if t == 1:  # the case is one where the feet matter
            assert alone[t] < 1e-9 and ref > 2 * slack, (alone[t], ref, slack)


def _cone_with_wavy_trim():
    """A cone of radii 10 -> 5 over height 5 (degree 1 x rational quadratic circle in
    4 quarters, v in [0, 2 pi]) cut by a loop whose upper side is a wave."""
    unit = np.array([[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1],
                     [1, 0]], float)
    w = np.array([1, S2, 1, S2, 1, S2, 1, S2, 1])
    cp = [[[r * a, r * b, z] for a, b in unit] for r, z in ((10.0, 0.0), (5.0, 5.0))]
    tp = 2 * np.pi
    v = np.linspace(0.1, tp - 0.1, 60)
    top = np.c_[0.6 + 0.25 * np.sin(3 * v), v][::-1]
    loop = np.concatenate([[[0.15, 0.1], [0.15, tp - 0.1]], top, [[0.15, 0.1]]])
    return Surface(degree_u=1, degree_v=2, knots_u=[0, 0, 1, 1],
                   knots_v=(np.array([0, 0, 0, .25, .25, .5, .5, .75, .75, 1, 1, 1]) * tp),
                   control_points=cp, weights=[w.tolist(), w.tolist()],
                   trim=[loop.tolist()])


def test_wavy_cone_as_one_grouped_grid():
    s = _cone_with_wavy_trim()
    tol = 1e-3 * s.size
    mesh = tessellate(s, tol)
    st = mesh.stats["surfaces"][0]
    assert st.get("trimmed_grid") and st.get("grouped"), st
    assert mesh.max_deviation <= tol
    r = naive.sample_mesh_deviation(mesh, [s], exact_above=tol)
    assert r["to_surface"] <= tol * REL and r["to_mesh"] <= tol * REL, r
