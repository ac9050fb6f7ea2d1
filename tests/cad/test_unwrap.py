"""The readers' angle unwrapping (:func:`geomkit.cad.analytic.unwrap`, compiled) gives
``np.unwrap``'s values bit for bit, signs of zero and NaN included."""

from __future__ import annotations

import math

import numpy as np

from geomkit.cad.analytic import unwrap


def _cases(rng):
    for k in range(20_000):
        n = int(rng.integers(2, 80))
        kind = k % 5
        if kind == 0:
            yield rng.uniform(-math.pi, math.pi, n)
        elif kind == 1:
            yield np.cumsum(rng.normal(0, 1.5, n))
        elif kind == 2:  # exactly half a turn apart, both zeros, whole turns
            yield rng.choice([math.pi, -math.pi, 0.0, -0.0, math.pi / 2, 2 * math.pi,
                              -2 * math.pi, 1e-300], n)
        elif kind == 3:  # angles at the branch cut, +-pi by the sign of a zero
            yield np.arctan2(rng.normal(size=n),
                             rng.choice([-1.0, 1.0], n) * rng.uniform(0, 1e-12, n))
        else:
            x = rng.uniform(-10, 10, n)
            x[rng.integers(0, n)] = np.nan
            yield x


def test_unwrap_is_numpys():
    rng = np.random.default_rng(7)
    for x in _cases(rng):
        for period in (2 * math.pi, 1.0):
            a, b = unwrap(x, period), np.unwrap(x, period=period)
            assert np.array_equal(a, b, equal_nan=True), x
            assert np.array_equal(np.signbit(a), np.signbit(b)), x
    strided = np.linspace(-9, 9, 40)[::3]
    assert np.array_equal(unwrap(strided), np.unwrap(strided))
    assert unwrap(np.array([1.5])).tolist() == [1.5]
