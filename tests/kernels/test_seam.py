"""The seam kernels against the numpy formulas they replace, value for value."""

import numpy as np
import pytest

from geomkit._kernels.bezier import insert_knot, restrict_curve
from geomkit._kernels.seam import level_crossing
from geomkit.cad.iges.entities import restrict

TWO_PI = 2.0 * np.pi


def _numpy_level(b, target):
    """The reader's former numpy route (stepseam._split_edge)."""
    m = np.round((b - target) / TWO_PI)
    f = b - (target + TWO_PI * m)
    on = np.flatnonzero(np.abs(f) <= 1e-12 * TWO_PI)
    if on.size:
        return 1, int(on[0]), 0.0
    lo_b, hi_b = np.minimum(b[:-1], b[1:]), np.maximum(b[:-1], b[1:])
    levels = target + TWO_PI * np.floor((lo_b - target) / TWO_PI + 1)
    crossed = np.flatnonzero((lo_b < levels) & (levels < hi_b))
    if crossed.size:
        return 2, int(crossed[0]), float(levels[crossed[0]])
    return 0, -1, 0.0


def test_level_crossing_matches_numpy():
    rng = np.random.default_rng(7)
    for trial in range(3000):
        n = int(rng.integers(2, 300))
        kind = trial % 5
        if kind == 0:  # a smooth turn
            b = np.cumsum(rng.normal(0.0, 0.05, n)) + rng.uniform(-10, 10)
        elif kind == 1:  # a flat stretch (no crossing)
            b = np.full(n, rng.uniform(-3, 3))
        elif kind == 2:  # a sample exactly on a level
            b = np.sort(rng.uniform(-7, 7, n))
            target = rng.uniform(0, TWO_PI)
            b[rng.integers(n)] = target + TWO_PI * rng.integers(-1, 2)
        elif kind == 3:  # NaN samples
            b = np.cumsum(rng.normal(0.0, 0.3, n))
            b[rng.integers(n, size=max(1, n // 10))] = np.nan
        else:  # half-way values (rounding half to even) and large angles
            b = (rng.integers(-9, 9, n) + 0.5) * TWO_PI + rng.uniform(-1, 1)
        if kind != 2:
            target = rng.uniform(0, TWO_PI)
        got = level_crossing(b, target)
        want = _numpy_level(b, target)
        assert (got[0], got[1]) == want[:2], (trial, got, want)
        assert got[2] == want[2]


def _numpy_restrict(p, U, Pw, t0, t1):
    """The former numpy body of restrict (ends already clamped to the domain)."""
    n = Pw.shape[0]
    lo, hi = U[p], U[n]
    eps = 1e-12 * (hi - lo)
    ends = []
    for t in (t0, t1):
        d = np.abs(U - t)
        k = int(d.argmin())
        ends.append(float(U[k]) if d[k] <= eps else t)
    t0, t1 = ends
    if t0 <= lo and t1 >= hi:
        return None
    Pw = np.ascontiguousarray(Pw, float)
    for t in (t0, t1):
        s = int(np.count_nonzero(U == t))
        if s < p:
            Pw, U = insert_knot(Pw, p, U, t, p - s)
    first_a = int(np.nonzero(U == t0)[0][0])
    start = first_a + int(np.count_nonzero(U == t0)) - 1 - p
    first_b = int(np.nonzero(U == t1)[0][0])
    newU = U[start: first_b + p + 1].copy()
    newU[: p + 1] = t0
    newU[-(p + 1):] = t1
    return newU, Pw[start: first_b]


@pytest.mark.parametrize("p", [1, 2, 3, 5])
def test_restrict_curve_matches_numpy(p):
    rng = np.random.default_rng(p)
    for trial in range(400):
        n = int(rng.integers(p + 1, p + 12))
        inner = np.sort(rng.uniform(0.0, 1.0, n - p - 1))
        if trial % 3 == 0 and inner.size:  # repeated interior knots
            inner[: min(p, inner.size)] = inner[0]
        U = np.concatenate([np.zeros(p + 1), inner, np.ones(p + 1)])
        Pw = np.column_stack([rng.normal(size=(n, 3)), rng.uniform(0.5, 2.0, n)])
        a, b = np.sort(rng.uniform(0.0, 1.0, 2))
        if trial % 4 == 1 and inner.size:  # an end within rounding of a knot
            a = inner[0] + 1e-14
        if trial % 4 == 2:  # an end within rounding of the domain's end: whole
            b = 1.0 - 1e-14
        if trial % 5 == 0 and inner.size:  # an end on a knot
            b = inner[-1]
        a = max(a, 0.0)  # restrict's clamping to the domain
        b = min(b, 1.0) if b > a else 1.0
        want = _numpy_restrict(p, U, Pw, a, b)
        whole, U2, P2 = restrict_curve(p, U, Pw, a, b, 1e-12)
        assert whole == (want is None)
        if want is not None:
            assert np.array_equal(U2, want[0]) and np.array_equal(P2, want[1])
            got = restrict(p, U, Pw, a, b)  # the public route
            assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])


def test_restrict_whole_curve_returns_the_input():
    U = np.array([0.0, 0, 0, 0.5, 1, 1, 1])
    Pw = np.ones((4, 4))
    for a, b in ((0.0, 1.0), (1e-15, 1.0), (-1.0, 2.0)):
        got = restrict(2, U, Pw, a, b)
        assert got[0] is U and got[1] is Pw
