"""Trim loop samples for validation (:func:`geomkit.nurbs.trims.loop_samples`, one
compiled call a loop) against each piece evaluated on its own with the curve kernel
at the same parameters: polyline pieces' own points, curved pieces (rational,
repeated knots, degrees 1-5) at ``per`` parameters a non-empty span and their end."""

from __future__ import annotations

import numpy as np
import pytest

from geomkit._kernels.bezier import curve_points
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
        r = np.arange(per) / per
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
