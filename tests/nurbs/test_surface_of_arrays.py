"""``Surface.of_arrays``: the constructor's surface from a reader's arrays, and the
constructor's error for anything it does not take as they are."""

import numpy as np
import pytest

from geomkit import Surface
from geomkit.cad.analytic import line_curve, revolve
from geomkit.errors import InvalidSurfaceError

_FIELDS = ("knots_u", "knots_v", "control_points", "homogeneous")


def _args(rng, rational=True):
    O, A = rng.normal(size=3), rng.normal(size=3)
    X = np.cross(A, rng.normal(size=3))
    p, q, U, V, P, W = revolve(line_curve(O + X, O + X + A, 0.0, 1.0), O,
                               A / np.linalg.norm(A), 0.3, 2.5)
    return (p, q, U, V, P, W) if rational else (p, q, U, V, P, None)


def _same(a, b):
    assert (a.degree_u, a.degree_v, a.name, a.approx_error, a.trim) == \
        (b.degree_u, b.degree_v, b.name, b.approx_error, b.trim)
    for f in _FIELDS:
        x, y = getattr(a, f), getattr(b, f)
        assert x.dtype == y.dtype and np.array_equal(x, y) and not y.flags.writeable
    assert (a.weights is None) == (b.weights is None)
    if a.weights is not None:
        assert np.array_equal(a.weights, b.weights)


@pytest.mark.parametrize("rational", [True, False])
def test_same_surface_as_the_constructor(rational):
    rng = np.random.default_rng(3)
    for _ in range(5):
        args = _args(rng, rational)
        _same(Surface(*args, name="f"), Surface.of_arrays(*args, name="f"))


def test_unit_weights_make_a_polynomial_surface():
    p, q, U, V, P, W = _args(np.random.default_rng(4))
    s = Surface.of_arrays(p, q, U, V, P, np.ones_like(W))
    assert s.weights is None and s.is_rational is False


def test_inputs_are_not_frozen_or_shared():
    args = _args(np.random.default_rng(5))
    s = Surface.of_arrays(*args)
    assert all(a.flags.writeable for a in args[2:])
    args[4][0, 0, 0] += 1.0
    assert s.control_points[0, 0, 0] != args[4][0, 0, 0]


@pytest.mark.parametrize("fault, field", [
    (lambda a: (a[0], a[1], a[2], a[3], a[4] * np.nan, a[5]), "control_points"),
    (lambda a: (a[0], a[1], a[2], a[3], a[4], -a[5]), "weights"),
    (lambda a: (a[0], a[1], a[2][::-1].copy(), a[3], a[4], a[5]), "knots_u"),
    (lambda a: (a[0], a[1], a[2], a[3][:-1].copy(), a[4], a[5]), "knots_v"),
    (lambda a: (a[0], a[1], a[2], a[3], a[4], a[5][:1]), "weights"),
    (lambda a: (a[0], a[1], a[2], a[3], a[4][:, :2], a[5][:, :2]), "control_points"),
    (lambda a: (a[0], a[1], a[2], np.array([0.3, 0.3, 0.3, 0.3, 1.4, 2.5, 2.5, 2.5]),
                a[4], a[5]), "knots_v"),
    (lambda a: (0, a[1], a[2], a[3], a[4], a[5]), "degree_u"),
    (lambda a: (a[0], a[1], a[2], a[3], a[4].astype(np.float32), a[5]), None),
])
def test_faults_are_the_constructors(fault, field):
    bad = fault(_args(np.random.default_rng(6)))
    try:
        ref = Surface(*bad)
    except InvalidSurfaceError as exc:
        with pytest.raises(InvalidSurfaceError) as got:
            Surface.of_arrays(*bad)
        assert str(got.value) == str(exc) and field in str(exc)
    else:  # taken by the constructor (float32 points): the same surface
        assert field is None
        _same(ref, Surface.of_arrays(*bad))
