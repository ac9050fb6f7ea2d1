"""``_kernels.arcs.axis2_x`` and ``axis2_zx`` (``StepGeometry.axis2``'s directions)
against the numpy formulas they replaced, within a few ulps scaled by the cancellation
of ``X - (X . Z) Z`` (numpy's dots are OpenBLAS's, whose kernel, and so whose rounding,
depends on the CPU: on a Zen 5 machine a result came out 1 ulp away): random unit and
non-unit ``Z`` and ``X``, ``X`` missing, (nearly) along ``Z``, ``Z`` with zero
components or along an axis, ``|Z[0]|`` about 0.9 (the default +x / +y switch); a
DIRECTION of zero or overflowing norm left to the long way."""

import numpy as np

from geomkit._kernels.arcs import axis2_x, axis2_zx
from geomkit.cad.analytic import norm3
from geomkit.cad.stepgeom import _AXES_XY, _Z_UP


def _numpy_axis2_x(Z, X):
    if X is None or abs(float(X @ Z)) > 1 - 1e-12:
        X = np.array([1.0, 0, 0]) if abs(Z[0]) < 0.9 else np.array([0.0, 1, 0])
    X = X - (X @ Z) * Z
    return X / norm3(X)


def _bits(v):
    return np.ascontiguousarray(v, dtype=np.float64).view(np.int64).tolist()


def _close(got, Z, X):
    """``got`` within a few ulps of the numpy route's X for ``Z``, ``X``: rounding grows
    by the cancellation ``|X| |Z|^2 / |X - (X . Z) Z|`` (the same default decision)."""
    want = _numpy_axis2_x(Z, X)
    if X is None or abs(float(X @ Z)) > 1 - 1e-12:
        X = np.array([1.0, 0, 0]) if abs(Z[0]) < 0.9 else np.array([0.0, 1, 0])
    r = norm3(X - (X @ Z) * Z)
    slack = 16 * np.finfo(float).eps * (1.0 + norm3(X) * max(1.0, norm3(Z)) ** 2 / r)
    return bool(np.all(np.abs(np.asarray(got) - want) <= slack))


def test_axis2_x_is_the_numpy_formula():
    rng = np.random.default_rng(26)
    cases = 0
    for k in range(6000):
        Z = rng.normal(size=3)
        if k % 3:
            Z /= norm3(Z)
        if k % 7 == 0:
            Z[rng.integers(3)] = 0.0
        if k % 11 == 0:
            Z = np.zeros(3)
            Z[rng.integers(3)] = rng.choice([1.0, -1.0])
        if k % 13 == 0:  # |Z[0]| about 0.9
            Z[0] = rng.choice([1.0, -1.0]) * (0.9 + rng.choice([-1.0, 0.0, 1.0]) * 1e-16)
            r = np.sqrt(1 - 0.81) * rng.normal(size=2)
            Z[1:] = r / np.hypot(*r) * np.sqrt(1 - Z[0] ** 2)
        X = rng.normal(size=3)
        if k % 2:
            X /= norm3(X)
        if k % 5 == 0:  # (nearly) along Z: the default replaces it, or just not
            X = Z * rng.choice([1.0, -1.0]) + rng.normal(size=3) * 10.0 ** rng.integers(-17, -10)
        for x in (X, None):
            got = axis2_x(Z, x, _AXES_XY)
            assert _close(got, Z, x), (Z.tolist(), None if x is None else x.tolist())
            # from the records' numbers: StepGeometry.direction's v / norm3(v) first
            Zu = Z / norm3(Z)
            xu = None if x is None else x / norm3(x)
            ZX = axis2_zx(Z, x, _AXES_XY)
            assert np.all(np.abs(ZX[0] - Zu) <= 4 * np.finfo(float).eps)
            # (against the kernel's own unit Z: at |Z[0]| = 0.9 an ulp picks the default)
            assert _close(ZX[1], ZX[0], xu), (Z.tolist(), x)
            cases += 1
    assert cases == 12000


def test_axis2_zx_defaults_and_refusals():
    X = np.array([0.3, -0.4, 2.0])
    for x in (X, None):
        ZX = axis2_zx(_Z_UP, x, _AXES_XY)
        assert _bits(ZX[0]) == _bits(np.array([0.0, 0, 1]))
        xu = None if x is None else x / norm3(x)
        assert _close(ZX[1], np.array([0.0, 0, 1]), xu)
    bad = [np.zeros(3), np.array([1e200, 0, 0]), np.array([np.nan, 0, 1])]
    for v in bad:
        assert axis2_zx(v, X, _AXES_XY).shape == (0, 3)
        assert axis2_zx(X, v, _AXES_XY).shape == (0, 3)
