"""Planes that contain an edge two faces share (a part's symmetry or datum plane).

Both faces' sections run along that edge.  They are one curve of the section: kept
once, never joined into a closed loop of zero area, and a face's piece of the edge that
lies along a longer piece of its neighbour's adds nothing."""

from __future__ import annotations

import numpy as np

import geomkit
from geomkit.cad.analytic import line_curve, revolve


def _half_cylinder(a0, a1):
    p, q, U, V, P, W = revolve(line_curve([2, 0, 0], [2, 0, 5], 0, 5), [0, 0, 0], [0, 0, 1],
                               a0, a1)
    return geomkit.Surface(p, q, U, V, P, W)


def _patch(P00, P10, P01, P11):
    return geomkit.Surface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1],
                           np.array([[P00, P01], [P10, P11]], float))


def test_two_halves_cut_along_their_seams():
    """A cylinder in two halves, cut by the plane through both seams: two open lines,
    one per seam (each half alone gives both lines)."""
    halves = [_half_cylinder(0.0, np.pi), _half_cylinder(np.pi, 2 * np.pi)]
    one = geomkit.plane_section(halves[0], [0, 1, 0, 0], 1e-6)
    assert len(one.curves) == 2 and not any(one.closed)
    sec = geomkit.plane_section(halves, [0, 1, 0, 0], 1e-6)
    assert len(sec.curves) == 2 and not any(sec.closed)
    xs = sorted(float(c[:, 0].mean()) for c in sec.curves)
    assert np.allclose(xs, [-2, 2])
    for c in sec.curves:
        assert np.ptp(c[:, 2]) == 5.0 and np.abs(c[:, 1]).max() < 1e-12


def test_a_shorter_piece_along_a_neighbours_edge_adds_nothing():
    """Face A's edge runs along the plane from z = 0 to 1.8; face B (a slanted sheet)
    meets it along z in [0.55, 1.8]: the section is A's line, B's piece dropped (NIST
    CTC-05 at its symmetry plane has such pairs)."""
    A = _patch([1, 0, 0], [1, 1, 0], [1, 0, 1.8], [1, 1, 1.8])
    B = _patch([1, 0, 0.55], [2, 1, 0.55], [1, 0, 1.8], [2, 1, 1.8])
    sec = geomkit.plane_section([A, B], [0, 1, 0, 0], 1e-6)
    assert len(sec.curves) == 1 and not sec.closed[0]
    z = sec.curves[0][:, 2]
    assert z.min() == 0.0 and z.max() == 1.8
    assert set(np.unique(sec.surface_index[0]).tolist()) == {0}


def test_a_sliver_piece_is_not_taken_for_a_shared_edge():
    """A piece shorter than the join distance is never dropped (it may be a sliver
    face's whole crossing)."""
    A = _patch([0, 0, -1], [1, 0, -1], [0, 0, 1], [1, 0, 1])       # crossing: x in [0, 1]
    S = _patch([1, 0, -1], [1.0004, 0, -1], [1, 0, 1], [1.0004, 0, 1])
    sec = geomkit.plane_section([A, S], [0, 0, 1, 0], 1e-6, gap=2e-3)
    assert len(sec.curves) == 1
    assert np.isclose(sec.curves[0][:, 0].max(), 1.0004)


def test_plane_through_a_cones_axis_gives_its_two_generators():
    """A cone cut by a plane through its axis meets it in two generators joined at the
    apex (a pole of the patch).  The tracer walks them out and back; the section is the
    open V from base to apex to base (NIST CTC-01 at z = -25 has such a cone)."""
    p, q, U, V, P, W = revolve(line_curve([0, 0, 0], [2, 0, 5], 0, 1), [0, 0, 0], [0, 0, 1],
                               0.0, 2 * np.pi)
    cone = geomkit.Surface(p, q, U, V, P, W)     # apex at u = 0 (the meridian's start)
    sec = geomkit.plane_section(cone, [0, 1, 0, 0], 1e-6)
    assert len(sec.curves) == 1 and not sec.closed[0]
    X = sec.curves[0]
    ends = sorted([tuple(np.round(X[0], 9)), tuple(np.round(X[-1], 9))])
    assert ends == [(-2.0, 0.0, 5.0), (2.0, 0.0, 5.0)]
    assert np.isclose(np.linalg.norm(X, axis=1).min(), 0.0, atol=1e-12)   # through the apex
    # each generator once: the polyline is as long as the two generators
    assert np.isclose(np.linalg.norm(np.diff(X, axis=0), axis=1).sum(), 2 * np.hypot(2, 5))
