"""Curve.param of B-spline curves (stepgeom.Curve._locate, its clamped ends kept per
curve) against the same rule computed afresh on every call (the oracle below), for
every edge vertex on a B-spline curve of the 13 parts and points near a curve's ends."""

from __future__ import annotations

import glob
import os

import numpy as np
import pytest

from geomkit._kernels.bezier import curve_nearest_param
from geomkit.cad.p21 import read_p21
from geomkit.cad.stepgeom import Curve, StepGeometry

PARTS = sorted(glob.glob(os.path.join(os.path.dirname(__file__), "..", "data", "parts",
                                      "*.st*p")))


def _oracle(spline, X):
    p, U, Pw = spline
    X = np.asarray(X, float)
    lo, hi = float(U[p]), float(U[-p - 1])
    P = Pw[:, :3] / Pw[:, 3:]
    near = 1e-6 * float(np.ptp(P, axis=0).max())
    best = None
    for k, t, ends, step in ((0, lo, U[:p + 1], P[1] - P[0]),
                             (-1, hi, U[-p - 1:], P[-2] - P[-1])):
        if not np.all(ends == t):
            continue
        d = P[k] - X
        dd = float(d @ d)
        if dd == 0.0 or (dd <= near * near and step.any() and float(d @ step) >= 0.0):
            if best is None or dd < best[1]:
                best = (t, dd)
    if best is not None:
        return best[0]
    return float(curve_nearest_param(np.ascontiguousarray(Pw, float), int(p),
                                     np.asarray(U, float), np.ascontiguousarray(X, float),
                                     max(65, 8 * (len(U) - p))))


@pytest.mark.parametrize("path", PARTS, ids=os.path.basename)
def test_edge_vertices(path):
    p = read_p21(path)
    g = StepGeometry(p)
    seen = 0
    for e in p.of_type("EDGE_CURVE"):
        _, a = p.get(e)
        try:
            c = g.curve(a[3])
        except Exception:
            continue
        if c.kind not in ("bspline", "polyline"):
            continue
        for v in (a[1], a[2], a[1]):  # (the second ask of a vertex: kept ends)
            X = g.point(p.get(v)[1][1])
            assert c.param(X) == _oracle(c.spline, X)
            seen += 1
    if "ventilator" in path:
        assert seen > 0


def test_points_near_the_ends():
    P = np.array([[0.0, 0, 0], [1, 0, 0], [2, 1, 0], [3, 1, 0]])
    for U, W in ((np.array([0.0, 0, 0, 0.5, 1, 1, 1]), np.ones(4)),
                 (np.array([0.0, 0, 0.2, 0.5, 1, 1, 1]), np.array([1.0, 2, 1, 1])),
                 (np.array([0.0, 0, 0, 0.5, 1, 1, 1.2]), np.ones(4))):
        spline = (2, U, np.column_stack([P * W[:, None], W]))
        c = Curve("bspline", spline=spline)
        for X in ([0, 0, 0], [-1e-7, 0, 0], [1e-7, 0, 0], [-1e-3, 0, 0], [3, 1, 0],
                  [3 + 1e-7, 1, 0], [1.5, 0.4, 0], [0, 1e-7, 0]):
            assert c.param(X) == _oracle(spline, X)
    loop = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 0, 0]])  # closed
    spline = (1, np.array([0.0, 0, 1, 2, 3, 3]), np.column_stack([loop, np.ones(4)]))
    c = Curve("polyline", spline=spline)
    for X in ([0, 0, 0], [1e-9, 0, 0], [0.5, 0.5, 0]):
        assert c.param(X) == _oracle(spline, X)


def test_two_control_points_and_flat_steps():
    """A two-point line (its ends' steps are each other's reverse) and a curve whose
    end control points repeat (a zero step: never the near rule)."""
    line = (1, np.array([0.0, 0, 2, 2]), np.array([[0.0, 0, 0, 1], [2, 0, 0, 1]]))
    flat = (2, np.array([0.0, 0, 0, 1, 1, 1]),
            np.array([[0.0, 0, 0, 1], [0, 0, 0, 1], [1, 1, 0, 1]]))
    for spline in (line, flat):
        c = Curve("bspline", spline=spline)
        for X in ([0, 0, 0], [-1e-7, 0, 0], [2 + 1e-7, 0, 0], [2, 0, 0], [1, 1e-7, 0],
                  [1, 1, 0], [1 + 1e-7, 1, 0], [0, -1e-7, 0]):
            assert c.param(X) == _oracle(spline, X)
