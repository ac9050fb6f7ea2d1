"""TrimCurve.polyline's kernel against the numpy route it replaces, value for value,
and the messages of bad input."""

import numpy as np
import pytest


def _numpy_polyline(P):
    """TrimCurve.polyline's former numpy route."""
    seg = np.hypot(*np.diff(P, axis=0).T)
    P = P[np.concatenate([[True], seg > 0])]
    if P.shape[0] < 2:
        return None
    t = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(P, axis=0).T))])
    t /= t[-1]
    return P, np.concatenate([[0.0], t, [1.0]])


def test_polyline_knots_match_numpy():
    from geomkit._kernels.trim_loops import polyline_knots

    rng = np.random.default_rng(3)
    for trial in range(2000):
        n = int(rng.integers(2, 60))
        P = rng.normal(size=(n, 2)) * 10.0 ** rng.uniform(-200, 200)
        if trial % 3 == 0:  # repeated vertices
            rep = rng.integers(1, n, size=max(1, n // 4))
            P[rep] = P[rep - 1]
        if trial % 17 == 0:  # all the same
            P[:] = P[0]
        want = _numpy_polyline(P)
        status, Q, U = polyline_knots(P)
        if want is None:
            assert status == 2
        else:
            assert status == 0
            assert np.array_equal(Q, want[0]) and np.array_equal(U, want[1])
    P = np.zeros((3, 2))
    P[1, 0] = np.inf
    assert polyline_knots(P)[0] == 1


def test_polyline_bad_input_messages():
    from geomkit.errors import InvalidTrimError
    from geomkit.nurbs.trims import TrimCurve

    with pytest.raises(InvalidTrimError, match="non-finite"):
        TrimCurve.polyline(np.array([[0.0, 0], [1, np.nan], [2, 2]]))
    with pytest.raises(InvalidTrimError, match="all points coincide"):
        TrimCurve.polyline(np.ones((4, 2)))
    with pytest.raises(InvalidTrimError, match="expected shape"):
        TrimCurve.polyline(np.ones((4, 3)))
    with pytest.raises(InvalidTrimError, match="at least 2"):
        TrimCurve.polyline(np.ones((1, 2)))
    src = np.array([[0.0, 0], [1, 1], [1, 1], [2, 0]])
    c = TrimCurve.polyline(src)
    assert src.flags.writeable and c.control_points.shape == (3, 2)
