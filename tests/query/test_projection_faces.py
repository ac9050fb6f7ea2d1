"""Projection onto several faces: shared edges, trimmed faces, approximated faces."""

from __future__ import annotations

import numpy as np
import pytest

import geomkit
from geomkit.query import results as R
from geomkit.nurbs.surface import Surface


def _half_plane(x0, x1, degree=1):
    """The plane z = 0 over [x0, x1] x [0, 10] (bilinear or bicubic)."""
    n = degree + 1
    xs = np.linspace(x0, x1, n)
    ys = np.linspace(0.0, 10.0, n)
    P = np.zeros((n, n, 3))
    P[..., 0] = xs[:, None]
    P[..., 1] = ys[None, :]
    knots = [0.0] * n + [1.0] * n
    return Surface(degree, degree, knots, knots, P)


def test_shared_edge_one_answer():
    """Points above the edge x = 0 shared by two halves of a plane: one answer (the
    lower surface index), the analytic distance, the same status, whichever order
    the faces come in."""
    a = _half_plane(-10.0, 0.0)
    b = _half_plane(0.0, 10.0, degree=3)
    rng = np.random.default_rng(3)
    y = rng.uniform(0.5, 9.5, 200)
    z = rng.uniform(-5.0, 5.0, 200)
    dx = np.r_[np.zeros(100), rng.choice([-1, 1], 100) * 10.0 ** rng.uniform(-15, -13, 100)]
    P = np.c_[dx, y, z]
    for order in ((a, b), (b, a)):
        pr = geomkit.project_points(list(order), P)
        assert np.allclose(pr.distance, np.abs(z), atol=1e-12, rtol=0)
        assert np.all(pr.surface[:100] == 0), "exact ties go to the lowest surface index"
        assert np.all(pr.surface == 0), "ties within rounding go to the lowest index too"
        assert len(set(pr.status[:100].tolist())) == 1
        assert np.all(np.abs(pr.point[:, 0]) <= 1e-12)
    # away from the edge the nearer face still wins
    far = np.array([[-3.0, 5.0, 1.0], [3.0, 5.0, 1.0]])
    pr = geomkit.project_points([a, b], far)
    assert pr.surface.tolist() == [0, 1]
    assert pr.status.tolist() == [R.INTERIOR, R.INTERIOR]


def test_trimmed_face_foot_outside_does_not_hide_another_face():
    """A plane trimmed to a small square and, farther away, an untrimmed plane: the
    trimmed plane's untrimmed Newton foot is nearer than the second plane but lies
    outside its face, so it must not prune the second plane's candidates."""
    P = np.zeros((2, 2, 3))
    P[..., 0] = np.array([0.0, 10.0])[:, None]
    P[..., 1] = np.array([0.0, 10.0])[None, :]
    k = [0, 0, 1, 1]
    sq = [[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.0, 0.1], [0.0, 0.0]]
    small = Surface(1, 1, k, k, P, trim=[sq])          # z = 0, x, y in [0, 1]
    Q = P.copy()
    Q[..., 2] = -1.5                                    # z = -1.5, whole square
    big = Surface(1, 1, k, k, Q)
    X = np.array([[8.0, 8.0, 0.2], [5.0, 5.0, 0.5], [0.5, 0.5, 0.3]])
    pr = geomkit.project_points([small, big], X)
    d_small = np.hypot(np.hypot(np.maximum(X[:, 0] - 1, 0), np.maximum(X[:, 1] - 1, 0)),
                       X[:, 2])
    exact = np.minimum(d_small, X[:, 2] + 1.5)
    assert np.allclose(pr.distance, exact, atol=1e-12, rtol=0)
    assert pr.surface.tolist() == [1, 1, 0]


def test_approx_error_widens_the_lower_bound():
    """A face that is an approximation (offset surfaces read from IGES) states its
    achieved error; projection's lower bound is widened by it."""
    if "approx_error" not in getattr(Surface, "__slots__", ()) and \
            not hasattr(Surface, "approx_error"):
        pytest.skip("Surface.approx_error does not exist on this branch")
    s = _half_plane(0.0, 10.0)
    X = np.array([[5.0, 5.0, 2.0], [5.0, 5.0, 1e-3]])
    lb0 = geomkit.Projector(s).project(X).lower_bound
    s2 = _half_plane(0.0, 10.0)
    s2.approx_error = 0.01
    pr = geomkit.Projector(s2).project(X)
    assert pr.stats["approx_error"] == 0.01
    assert np.allclose(pr.lower_bound, np.maximum(0.0, lb0 - 0.01))
    # the exact distance to the surface the face approximates is >= distance - 0.01
    assert np.all(pr.lower_bound <= np.maximum(0.0, pr.distance - 0.01) + 1e-12)
    assert np.allclose(pr.distance, [2.0, 1e-3])
