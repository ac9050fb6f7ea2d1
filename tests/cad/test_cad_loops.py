"""Trim loops from CAD pcurves: chaining pieces listed out of order, reversed, or on
the other side of a closed surface's seam (a torus face of a STEP part in inches came
with one pcurve a period away from its neighbours and was skipped)."""

from __future__ import annotations

import numpy as np
import pytest

from geomkit.cad.loops import Unsupported, chain, close_gaps
from geomkit.nurbs.surface import TrimCurve

TWO_PI = 2 * np.pi


def _loop():
    """A loop on the torus domain u in [a, a + 2 pi] (the face wraps once), v in
    [2 pi, 2.5 pi]: bottom edge, seam up, a notch at the top, top edge, seam down."""
    a = 0.0913
    P = [[1.5, TWO_PI], [a + TWO_PI, TWO_PI], [a + TWO_PI, 2.5 * np.pi],
         [6.27, 6.92], [6.16, 2.5 * np.pi], [a, 2.5 * np.pi], [a, TWO_PI], [1.5, TWO_PI]]
    return [TrimCurve.polyline([p, q]) for p, q in zip(P, P[1:])], a


def test_chain_moves_a_piece_across_the_seam():
    pieces, a = _loop()
    bad = list(pieces)
    bad[2] = TrimCurve.polyline(pieces[2].control_points - [TWO_PI, 0])  # other period
    bad[2], bad[5] = bad[5], bad[2]  # and out of order
    domain = ((a, a + TWO_PI), (TWO_PI, 2.5 * np.pi))
    with pytest.raises(Unsupported, match="apart in UV"):
        close_gaps(bad, domain, "face")
    fixed = chain(bad, TWO_PI, periods=(TWO_PI, 0.0), domain=domain)
    for c, ref in zip(fixed, pieces):
        assert np.allclose(c.control_points, ref.control_points, atol=1e-15)
    out, gaps = close_gaps(fixed, domain, "face")
    assert len(out) == len(pieces) and gaps == []


def test_chain_without_periods_keeps_pieces_in_place():
    pieces, a = _loop()
    bad = list(pieces)
    bad[2] = TrimCurve.polyline(pieces[2].control_points - [TWO_PI, 0])
    fixed = chain(bad, TWO_PI)  # reordered and reversed at most, never moved
    for c in fixed:
        assert any(np.allclose(c.control_points, b.control_points) or
                   np.allclose(c.control_points[::-1], b.control_points) for b in bad)


def _torus_corner_loop():
    """The rectangle [0, 2 pi]^2 as OCC writes a closed torus face: the four seam and
    boundary edges in the order right, left... with each joint a jump between two UV
    images of the one corner point of the torus (every corner maps to it)."""
    T = TWO_PI
    right = TrimCurve.polyline([[T, 0], [T, T]])
    bottom = TrimCurve.polyline([[0, 0], [T, 0]])
    left = TrimCurve.polyline([[0, T], [0, 0]])
    top = TrimCurve.polyline([[T, T], [0, T]])
    return [right, bottom, left, top]


def test_same_point_jumps_are_rechained_not_bridged():
    """Gaps whose ends are one model point, between pieces that close in another
    order: re-chained (a straight UV bridge between two corners of a torus domain
    would be a diagonal across the face, not a point)."""
    pieces = _torus_corner_loop()
    domain = ((0.0, TWO_PI), (0.0, TWO_PI))
    corners = {(0.0, 0.0), (TWO_PI, 0.0), (0.0, TWO_PI), (TWO_PI, TWO_PI)}

    def same(a, b):   # every corner of the torus domain is one model point
        return (float(a[0]), float(a[1])) in corners and (float(b[0]), float(b[1])) in corners

    out, gaps = close_gaps(pieces, domain, "face", same)
    assert gaps == [] and len(out) == 4            # no bridge added
    assert {id(c) for c in out} == {id(c) for c in pieces}   # the same pieces, none reversed
    for a, b in zip(out, out[1:] + out[:1]):
        assert np.array_equal(a.end, b.start)
    x, y = np.array([c.start for c in out]).T    # the loop is the rectangle, once
    assert abs(0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)) == pytest.approx(
        TWO_PI ** 2, rel=1e-15)


def test_a_pole_gap_is_still_bridged():
    """A loop that cannot close without the jump (a pole: the degenerate top edge is
    missing) keeps its bridge along the pole."""
    T = TWO_PI
    P = [[0, 0], [T, 0], [T, np.pi]]
    pieces = [TrimCurve.polyline([p, q]) for p, q in zip(P, P[1:])] + \
        [TrimCurve.polyline([[0, np.pi], [0, 0]])]
    domain = ((0.0, T), (0.0, np.pi))

    def same(a, b):   # v = pi is the pole
        return a[1] == np.pi and b[1] == np.pi

    out, gaps = close_gaps(pieces, domain, "face", same)
    assert len(out) == 4 and gaps == []      # 3 pieces and the bridge
    bridge = out[2]
    assert np.array_equal(bridge.control_points, [[T, np.pi], [0, np.pi]])


def test_a_clipped_rational_piece_stays_in_the_domain():
    """Control points a rounding outside the domain are snapped onto it and stay
    there on a rational piece (``create``'s ``Q w / w`` rounds some of them back out
    by a unit in the last place, which sent the piece to a 3-D refit), with the
    piece's degree, knots and weights kept."""
    from geomkit.cad.loops import clip_to_domain
    from geomkit.nurbs.surface import TrimCurve

    rng = np.random.default_rng(7)
    dom = ((0.0, 60.000000000000014), (-30.00000000000001, 30.0))
    back_out = 0
    for _ in range(200):
        w = rng.uniform(0.3, 1.0, 5)
        Q = np.column_stack([rng.uniform(0, 60, 5), rng.uniform(-30, 30, 5)])
        Q[2, 0] = dom[0][1] * (1 + 4e-16 * rng.integers(1, 8))  # just outside
        c = TrimCurve.create(2, [0, 0, 0, 0.5, 0.5, 1, 1, 1], Q, w)
        ref = TrimCurve.create(2, c.knots, np.clip(c.control_points, [dom[0][0], dom[1][0]],
                                                   [dom[0][1], dom[1][1]]), c.weights)
        back_out += bool(ref.control_points[:, 0].max() > dom[0][1])
        (got,), moves = clip_to_domain([c], dom, 1e-4)
        assert got.control_points[:, 0].max() <= dom[0][1]
        assert got.degree == 2 and np.array_equal(got.knots, c.knots)
        assert np.array_equal(got.weights, c.weights) and len(moves) == 1
    assert back_out > 0  # the case this guards against occurs


def test_finish_loop_gives_a_packed_loop_the_surface_still_checks():
    """A closed loop inside the domain comes back at once as a TrimLoop packed for the
    surface's check (the arrays of a fresh pack); the surface still refuses it when it
    is not a valid trim (here: it encloses no area)."""
    from geomkit.cad.loops import finish_loop
    from geomkit.errors import InvalidTrimError
    from geomkit.nurbs.surface import Surface
    from geomkit.nurbs.trims import TrimLoop, _packed, loop_pack

    P = np.zeros((2, 2, 3))
    P[1, :, 0] = 1.0
    P[:, 1, 1] = 1.0
    base = Surface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], P)
    sq = [[0.1, 0.1], [0.9, 0.1], [0.9, 0.9], [0.1, 0.9], [0.1, 0.1]]
    pieces = [TrimCurve.polyline([p, q]) for p, q in zip(sq, sq[1:])]
    loop, gaps, repairs = finish_loop(pieces, base, (0.0, 0.0), 1e-9, "face")
    assert isinstance(loop, TrimLoop) and loop.pieces == tuple(pieces)
    assert gaps == [] and repairs == []
    pk = loop_pack(loop)
    assert loop_pack(loop) is pk
    for a, b in zip(pk, _packed(pieces)):
        np.testing.assert_array_equal(a, b)
    s = base.with_trim([loop])
    assert s.trim[0] is loop
    flat = [TrimCurve.polyline([[0.1, 0.5], [0.9, 0.5]]),
            TrimCurve.polyline([[0.9, 0.5], [0.1, 0.5]])]
    loop, _, _ = finish_loop(flat, base, (0.0, 0.0), 1e-9, "face")
    assert isinstance(loop, TrimLoop) and len(loop_pack(loop)) == 6
    with pytest.raises(InvalidTrimError, match="degenerate loop"):
        base.with_trim([loop])
    assert finish_loop([], base, (0.0, 0.0), 1e-9, "face") == ([], [], [])


def test_shift_is_create_of_the_moved_points():
    """loops.shift keeps the piece's checked knots and weights: the same curve as
    TrimCurve.create of the moved points, bit for bit (a rational arc's points as
    Q w / w), and a point moved to infinity is named by create."""
    from geomkit.cad.loops import shift
    from geomkit.errors import InvalidTrimError

    rng = np.random.default_rng(3)
    arc = TrimCurve.create(2, [0, 0, 0, 0.4, 0.4, 1, 1, 1], rng.uniform(0, 1, (5, 2)),
                           [1.0, 0.7071, 1.0, 0.3, 1.0])
    seg = TrimCurve.polyline([[0.1, 0.2], [0.4, 0.9], [0.3, 0.1]])
    more = [TrimCurve.create(2, [0, 0, 0, 0.5, 1, 1, 1], rng.normal(size=(4, 2))
                             * 10.0 ** rng.integers(-8, 8), rng.uniform(0.05, 3.0, 4))
            for _ in range(50)]  # (the compiled route: random weights and scales)
    for c in (arc, seg, *more):
        for d in (np.array([TWO_PI, 0.0]), np.array([0.0, -TWO_PI]), [0.3, 1e-9]):
            got = shift(c, d)
            ref = TrimCurve.create(c.degree, c.knots, np.asarray(c.control_points) + d,
                                   None if np.all(c.weights == 1) else c.weights)
            for a, b in ((got.knots, ref.knots), (got.control_points, ref.control_points),
                         (got.weights, ref.weights)):
                np.testing.assert_array_equal(a, b)
            assert got.degree == ref.degree and not got.control_points.flags.writeable
    with pytest.raises(InvalidTrimError):
        shift(arc, np.array([np.inf, 0.0]))


def test_segment_spread_matches_numpy_route():
    """same_point_3d's kernel against its former numpy route, value for value."""
    from geomkit import Surface
    from geomkit._kernels.trim_loops import segment_spread

    rng = np.random.default_rng(9)
    for trial in range(60):
        p, q = int(rng.integers(1, 4)), int(rng.integers(1, 4))
        nu, nv = p + int(rng.integers(1, 4)), q + int(rng.integers(1, 4))
        ku = np.concatenate([np.zeros(p + 1), np.sort(rng.random(nu - p - 1)), np.ones(p + 1)])
        kv = np.concatenate([np.zeros(q + 1), np.sort(rng.random(nv - q - 1)), np.ones(q + 1)])
        P = rng.normal(size=(nu, nv, 3))
        if trial % 3 == 0:  # a pole: the first row collapsed
            P[0] = P[0, 0]
        W = rng.uniform(0.5, 2.0, (nu, nv)) if trial % 2 else None
        s = Surface(p, q, ku, kv, P, W)
        (u0, u1), (v0, v1) = s.domain
        for _ in range(5):
            a, b = rng.uniform(-0.1, 1.1, 2), rng.uniform(-0.1, 1.1, 2)
            if trial % 3 == 0:
                a[0] = b[0] = 0.0  # along the pole
            t = np.linspace(0.0, 1.0, 17)[:, None]
            uv = (1 - t) * a + t * b
            uv = np.column_stack([np.clip(uv[:, 0], u0, u1), np.clip(uv[:, 1], v0, v1)])
            X = s.evaluate(uv)
            want = min(float(np.linalg.norm(X - X[0], axis=1).max()),
                       float(np.linalg.norm(X - X[-1], axis=1).max()))
            got = segment_spread(s.homogeneous, p, q, s.knots_u, s.knots_v, *a, *b,
                                 u0, u1, v0, v1, 17)
            assert got == want


def test_box_clip_is_the_numpy_route():
    """clip_to_domain's and clip_in_3d's one call (trim_loops.box_clip) against the
    numpy route it replaced: the in-domain test (col_range bounds / element-wise
    comparisons), np.clip of each column (signed zeros, NaN, infinities, points on a
    bound) and the largest move, bit for bit."""
    from geomkit._kernels.ranges import col_range
    from geomkit._kernels.trim_loops import box_clip

    rng = np.random.default_rng(1)
    for _ in range(5000):
        n = int(rng.integers(1, 12))
        u0, u1 = sorted(rng.choice([0.0, -0.0, 1.0, rng.uniform(-1, 1), rng.uniform(-1, 1)], 2))
        v0, v1 = sorted(rng.choice([0.0, -0.0, 2.0, rng.uniform(-1, 1), rng.uniform(-1, 1)], 2))
        if rng.random() < 0.5:
            P = rng.choice([0.0, -0.0, u0, u1, v0, v1, np.nan, np.inf, -np.inf, 1e-300], (n, 2))
        else:
            P = rng.uniform(-1.5, 2.5, (n, 2))
        lo, hi = col_range(P)
        inside = bool(lo[0] >= u0 and hi[0] <= u1 and lo[1] >= v0 and hi[1] <= v1)
        assert inside == bool(((P[:, 0] >= u0) & (P[:, 0] <= u1) & (P[:, 1] >= v0)
                               & (P[:, 1] <= v1)).all())
        with np.errstate(invalid="ignore"):
            Q = np.column_stack([np.clip(P[:, 0], u0, u1), np.clip(P[:, 1], v0, v1)])
            moved = float(np.abs(Q - P).max())
        got_inside, got_Q, got_moved = box_clip(P, float(u0), float(u1), float(v0), float(v1))
        assert got_inside == inside
        np.testing.assert_array_equal(np.signbit(got_Q), np.signbit(Q))
        np.testing.assert_array_equal(got_Q, Q)
        assert got_moved == moved or (np.isnan(got_moved) and np.isnan(moved))
