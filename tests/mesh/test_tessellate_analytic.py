"""Tessellation of the analytic faces real parts are made of (cylinders, cones, tori as
rational NURBS from a STEP reader), against the exact surfaces:

* a face whose trim is only its domain rectangle (the usual STEP cylinder) is meshed
  as the untrimmed surface (the uniform grid), with the same triangles;
* :func:`geomkit.mesh.trim_polylines.domain_rectangle_only` against
  :class:`~geomkit.mesh.trim_polylines.TrimPolylines`' own judgement (never True where
  the polylines keep a loop).
"""

from __future__ import annotations

import numpy as np
import pytest

from geomkit import Surface
from geomkit.mesh.tessellate import tessellate
from geomkit.mesh.trim_polylines import TrimPolylines, domain_rectangle_only

R, H = 2.0, 3.0
W = np.sqrt(0.5)


def _cylinder(trim=None, u_lines=False):
    """A quarter cylinder of radius R, height H: degree 1 along the axis (u in [0, H]),
    a rational quadratic arc in v in [0, 1]."""
    arc = np.array([[R, 0.0], [R, R], [0.0, R]])
    P = np.array([[[a[0], a[1], z] for a in arc] for z in (0.0, H)])
    w = np.array([[1.0, W, 1.0]] * 2)
    return Surface(1, 2, [0, 0, H, H], [0, 0, 0, 1, 1, 1], P, w, trim=trim)


def _exact_gap(mesh):
    """Largest distance from the cylinder of points on the mesh (corners, edge
    midpoints, centroids): radial distance to radius R."""
    V, F = mesh.vertices, mesh.faces
    A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    P = np.concatenate([A, (A + B) / 2, (B + C) / 2, (C + A) / 2, (A + B + C) / 3])
    return float(np.abs(np.hypot(P[:, 0], P[:, 1]) - R).max())


RECT_POLY = [[0, 0], [H, 0], [H, 1], [0, 1], [0, 0]]
RECT_PIECES = [  # four pieces, one a quadratic along v = 1 (its middle point on the edge)
    {"degree": 1, "knots": [0, 0, 1, 1], "control_points": [[0, 0], [H, 0]]},
    {"degree": 1, "knots": [0, 0, 1, 1], "control_points": [[H, 0], [H, 1]]},
    {"degree": 2, "knots": [0, 0, 0, 1, 1, 1], "control_points": [[H, 1], [0.3 * H, 1], [0, 1]],
     "weights": [1, 0.7, 1]},
    {"degree": 1, "knots": [0, 0, 1, 1], "control_points": [[0, 1], [0, 0]]},
]


@pytest.mark.parametrize("trim", [RECT_POLY, RECT_PIECES], ids=["polyline", "pieces"])
@pytest.mark.parametrize("tol", [1e-2, 1e-3])
def test_domain_rectangle_trim_is_meshed_as_the_whole_surface(trim, tol):
    plain = tessellate(_cylinder(), tol)
    s = _cylinder([trim])
    assert domain_rectangle_only(s, 0.5 * tol)
    assert not TrimPolylines(s, 0.5 * tol).loops
    mesh = tessellate(s, tol)
    st = mesh.stats["surfaces"][0]
    assert st.get("uniform_grid") is True
    assert np.array_equal(mesh.faces, plain.faces)
    assert np.array_equal(mesh.vertices, plain.vertices)
    assert mesh.max_deviation <= tol
    assert _exact_gap(mesh) <= tol
    # one cell along the (straight) axis, and about as many across the arc as its
    # chord sag asks for: n arcs of angle a with R (1 - cos(a / 2)) <= tol
    n_min = np.ceil(0.5 * np.pi / (2 * np.arccos(1 - tol / R)))
    assert n_min <= st["cells"] <= 1.25 * n_min + 1 and len(mesh.faces) == 2 * st["cells"]


@pytest.mark.parametrize("trim", [
    [[0, 0], [H, 0], [H, 0.9], [0, 1], [0, 0]],                    # a corner moved in
    [[0, 0], [H, 0], [H, 1], [0, 1], [0, 0.5], [0.1, 0.4], [0, 0]],  # a notch
    [[0, 0], [0.5 * H, 0], [0.5 * H, 1], [0, 1], [0, 0]],           # half the domain
    [{"degree": 2, "knots": [0, 0, 0, 1, 1, 1], "control_points": [[0, 0], [H, 0.2], [H, 1]]},
     {"degree": 1, "knots": [0, 0, 1, 1], "control_points": [[H, 1], [0, 1]]},
     {"degree": 1, "knots": [0, 0, 1, 1], "control_points": [[0, 1], [0, 0]]}],  # curved cut
    RECT_PIECES[:2] + [dict(RECT_PIECES[2], control_points=[[H, 1], [0.3 * H, 0.999],
                                                            [0, 1]])] + RECT_PIECES[3:],
])
def test_real_trims_are_not_taken_for_the_domain(trim):
    s = _cylinder([trim])
    assert not domain_rectangle_only(s, 1e-3)
    assert TrimPolylines(s, 1e-3).loops
    # its trim polylines lie within 0.9 tol of the curves (TRIM_PAIR), which stray
    # 1.2e-3 from the rectangle in the last case
    mesh = tessellate(s, 1e-3)
    assert "uniform_grid" not in mesh.stats["surfaces"][0]
    assert mesh.max_deviation <= 1e-3 and _exact_gap(mesh) <= 1e-3


def _holed(n=97):
    """The quarter cylinder with an elliptic hole (in UV: centre (H/2, 1/2), semi-axes
    0.6 and 0.3) as a polygon of ``n - 1`` sides."""
    a = np.linspace(0, 2 * np.pi, n)
    hole = np.c_[0.5 * H + 0.6 * np.cos(a), 0.5 + 0.3 * np.sin(a)]
    hole[-1] = hole[0]
    return _cylinder([RECT_POLY, hole]), hole


@pytest.mark.parametrize("tol", [1e-2, 1e-3])
def test_trimmed_cylinder_on_one_grid_against_the_cells(tol, monkeypatch):
    """A cylinder with a hole: one uniform grid, cells the trim crosses clipped (the
    ``trimmed_grid`` path), against the adaptive cells (the path before it) and the
    exact cylinder: every triangle within tol (measured and exactly), the same area
    to the boundary's chord error, no triangle in the hole, no more triangles."""
    import geomkit.mesh.tessellate as T

    s, hole = _holed()
    mesh = tessellate(s, tol)
    st = mesh.stats["surfaces"][0]
    assert st.get("trimmed_grid") is True and st["cut_cells"] > 0
    monkeypatch.setattr(T, "_trimmed_grid", lambda *a, **k: None)
    cells = tessellate(s, tol)
    assert "trimmed_grid" not in cells.stats["surfaces"][0]
    for m in (mesh, cells):
        assert m.max_deviation <= tol and _exact_gap(m) <= tol
        c = m.face_uv.mean(axis=1)  # no face centre inside the hole's polygon
        assert (((c[:, 0] - 0.5 * H) / 0.6) ** 2 + ((c[:, 1] - 0.5) / 0.3) ** 2 > 0.99).all()
    # both boundaries are within tol / 2 of the exact hole (3-D length < 5)
    assert abs(mesh.area - cells.area) <= 5 * tol
    assert len(mesh.faces) <= len(cells.faces)


def _cone(rb, hc):
    """A full cone, apex at the origin (the u = 0 row of the net collapsed to it), base
    circle of radius ``rb`` at height ``hc``: four rational quadratic quarter arcs in v."""
    c = np.array([[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1],
                  [1, 0]], float) * rb
    P = np.array([[[0.0, 0.0, 0.0]] * 9, [[a[0], a[1], hc] for a in c]])
    w = np.array([[1, W, 1, W, 1, W, 1, W, 1]] * 2, float)
    h = np.pi / 2
    return Surface(1, 2, [0, 0, 1, 1], [0, 0, 0, h, h, 2 * h, 2 * h, 3 * h, 3 * h, 4 * h,
                                        4 * h, 4 * h], P, w)


@pytest.mark.parametrize("rb,hc,tol", [(0.125, 0.0751, 0.0168), (1, 0.6, 0.03), (1, 2, 0.05),
                                       (1, 2, 0.01)])
def test_cone_apex_on_one_grid(rb, hc, tol, monkeypatch):
    """At a cone's apex the chord estimates miss what the measurement sees; the grid's
    third try (the failing grid refined by its measured excess) takes the cone instead
    of the adaptive cells (FTC-07's small cones).  Against the exact cone (distance
    of a point at radius r, height z: |r cos a - z sin a|, a the half angle) and the
    adaptive cells' triangle count."""
    import geomkit.mesh.tessellate as T

    s = _cone(rb, hc)
    mesh = tessellate(s, tol)
    assert mesh.stats["surfaces"][0].get("uniform_grid") is True
    assert mesh.max_deviation <= tol
    V, F = mesh.vertices, mesh.faces
    A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    X = np.concatenate([A, (A + B) / 2, (B + C) / 2, (C + A) / 2, (A + B + C) / 3])
    a = np.arctan2(rb, hc)
    assert np.abs(np.hypot(X[:, 0], X[:, 1]) * np.cos(a) - X[:, 2] * np.sin(a)).max() <= tol
    monkeypatch.setattr(T.qt, "uniform_grid", lambda *a, **k: None)
    cells = tessellate(s, tol)
    assert cells.max_deviation <= tol
    assert len(mesh.faces) <= 2 * len(cells.faces)  # measured: 0.67x - 1.67x
