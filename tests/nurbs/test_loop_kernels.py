"""Trim loop validation kernels (:mod:`geomkit._kernels.trim_loops`) against numpy
references: the loop's samples (:func:`geomkit.nurbs.trims.loop_samples`, one
compiled call a loop) against each piece evaluated on its own with the curve kernel
at the same parameters (polyline pieces' own points, curved pieces, rational, with
repeated knots, degrees 1-5, at ``per`` parameters a non-empty span and their end);
the loop's area and its three-distinct-grid-points test; the joins' gaps and the
domain-box test (``loop_joins``) and all of a loop's checks in one call
(``loop_check``)."""

from __future__ import annotations

import numpy as np
import pytest

from geomkit._kernels.bezier import curve_points
from geomkit._kernels.trim_loops import loop_area_spread
from geomkit.nurbs.surface import TrimCurve
from geomkit.nurbs.trims import TrimLoop, loop_samples


def _reference(loop, per):
    out = []
    for c in loop.pieces:
        if c.is_polyline:
            out.append(c.control_points)
            continue
        a, b = c.knots[c.degree:-c.degree - 1], c.knots[c.degree + 1:-c.degree]
        a, b = a[b > a], b[b > a]
        k = min(per, max(2, -(-2 * per // len(a))))  # fewer a span on many spans
        r = np.arange(k) / k
        t = np.concatenate([(a[:, None] + (b - a)[:, None] * r).ravel(), c.knots[-1:]])
        res = np.empty((t.shape[0], 1, 2))
        curve_points(c.homogeneous, c.degree, c.knots, t, 0, res)
        out.append(res[:, 0, :])
    return np.concatenate(out)


def _random_piece(rng, start):
    p = int(rng.integers(1, 6))
    n = p + 1 + int(rng.integers(0, 5))
    inner = np.sort(rng.choice([0.2, 0.4, 0.5, 0.7], n - p - 1))  # repeats allowed,
    if n - p - 1 and np.unique(inner, return_counts=True)[1].max() > p:  # up to p
        inner = np.linspace(0, 1, n - p + 1)[1:-1]
    U = np.concatenate([np.zeros(p + 1), inner, np.ones(p + 1)]) * rng.uniform(0.5, 3)
    Q = rng.uniform(0, 1, (n, 2))
    Q[0] = start
    w = None if rng.random() < 0.4 else rng.uniform(0.2, 5, n)
    return TrimCurve.create(p, U, Q, w)


@pytest.mark.parametrize("seed", range(3))
def test_loop_samples_are_the_pieces_evaluated_one_by_one(seed):
    rng = np.random.default_rng(seed)
    for _ in range(200):
        pieces, start = [], rng.uniform(0, 1, 2)
        for _ in range(int(rng.integers(1, 6))):
            c = _random_piece(rng, start)
            pieces.append(c)
            start = c.end
        loop = TrimLoop(tuple(pieces))
        for per in (1, 3, 24):
            a, b = loop_samples(loop, per), _reference(loop, per)
            assert a.shape == b.shape
            # the same formulas; the compiled one may fuse a multiply and an add
            np.testing.assert_allclose(a, b, rtol=0, atol=4e-15 * max(1.0, np.abs(b).max()))


def _area_reference(P):
    x, y = P[:, 0], P[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    return 0.5 * float(np.sum(x * yn - xn * y))


def _spread_reference(P, close):
    q = np.round(P / close)
    return len(np.unique(q, axis=0)) >= 3


@pytest.mark.parametrize("seed", range(3))
def test_loop_area_and_spread(seed):
    """The shoelace area (sequential sum: within rounding of numpy's pairwise one) and
    the three-distinct-grid-points test, exactly, on loops spread out, on slivers and
    on loops collapsed into one or two grid cells (points at half steps included)."""
    rng = np.random.default_rng(seed)
    for k in range(3000):
        m = int(rng.integers(1, 60))
        close = 10.0 ** rng.uniform(-6, -1)
        kind = k % 4
        if kind == 0:
            P = rng.uniform(-1, 1, (m, 2))
        elif kind == 1:   # within two grid cells
            cells = rng.integers(-3, 3, (2, 2)).astype(float)
            P = (cells[rng.integers(0, 2, m)] + rng.uniform(-0.49, 0.49, (m, 2))) * close
        elif kind == 2:   # on half steps: rounding to even decides
            P = (rng.integers(-4, 4, (m, 2)) + 0.5) * close
        else:             # a sliver along a line
            t = rng.uniform(0, 1, m)
            P = np.column_stack([t, 2 * t + rng.normal(0, close / 10, m)])
        area, spread = loop_area_spread(P, close)
        assert area == pytest.approx(_area_reference(P), rel=1e-12, abs=1e-15)
        assert spread == _spread_reference(P, close)


@pytest.mark.parametrize("seed", range(3))
def test_loop_check_against_numpy(seed):
    """``loop_check``'s first wide gap, box test and area against the numpy formulas
    it replaced, on random loops with gaps, some leaving the box."""
    from geomkit._kernels.trim_loops import loop_check
    from geomkit.nurbs.trims import _packed
    rng = np.random.default_rng(10 + seed)
    seen = {"gap": 0, "out": 0}
    for _ in range(200):
        pieces, start = [], rng.uniform(0, 1, 2)
        for _ in range(int(rng.integers(1, 6))):
            c = _random_piece(rng, start)
            pieces.append(c)
            start = c.end + (rng.normal(0, 0.01, 2) if rng.random() < 0.3 else 0.0)
        if rng.random() < 0.7:  # closed
            last = pieces[-1]
            Q = last.control_points.copy()
            Q[-1] = pieces[0].start
            pieces[-1] = TrimCurve.create(last.degree, last.knots, Q, last.weights)
        loop = TrimLoop(tuple(pieces))
        close = float(rng.choice([1e-9, 1e-3, 2e-2]))
        box = np.array([0.05, 0.95, 0.05, 0.95]) if rng.random() < 0.5 else \
            np.array([-1.0, 2.0, -1.0, 2.0])
        i, gap, inside, area, spread = loop_check(*_packed(loop.pieces), 24, close, box)
        E = np.array([c.control_points[-1] for c in pieces])
        S = np.array([c.control_points[0] for c in pieces])
        gaps = np.hypot(*(E - np.concatenate([S[1:], S[:1]])).T)
        wide = np.flatnonzero(gaps > close)
        assert i == (int(wide[0]) if wide.size else -1)
        if wide.size:
            assert gap == gaps[wide[0]]
            seen["gap"] += 1
        P = np.concatenate([c.control_points for c in pieces])
        assert inside == bool(((P[:, 0] >= box[0]) & (P[:, 0] <= box[1])
                               & (P[:, 1] >= box[2]) & (P[:, 1] <= box[3])).all())
        seen["out"] += not inside
        ref = loop_area_spread(loop_samples(loop), close)
        assert (area, spread) == ref
    assert seen["gap"] > 20 and seen["out"] > 20


def test_loop_joins_against_numpy():
    """Every join's gap and the box test of ``loop_joins`` against numpy."""
    from geomkit._kernels.trim_loops import loop_joins
    rng = np.random.default_rng(21)
    box = np.array([0.0, 1.0, 0.0, 1.0])
    outside = 0
    for _ in range(300):
        sizes = rng.integers(2, 6, int(rng.integers(1, 6)))
        Q = rng.uniform(-0.1, 1.1, (int(sizes.sum()), 2))
        off = np.concatenate([[0], np.cumsum(sizes)])
        gaps, inside = loop_joins(Q, off, box)
        E, S = Q[off[1:] - 1], Q[off[:-1]]
        assert np.array_equal(gaps, np.hypot(*(E - np.concatenate([S[1:], S[:1]])).T))
        assert inside == bool(((Q[:, 0] >= 0) & (Q[:, 0] <= 1) & (Q[:, 1] >= 0)
                               & (Q[:, 1] <= 1)).all())
        outside += not inside
    assert 0 < outside < 300
