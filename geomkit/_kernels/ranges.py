"""Column ranges of small point arrays in one call: numpy's ``X.min(axis=0)`` /
``X.max(axis=0)`` (a NaN in a column gives NaN there) cost a few microseconds each on
the dozens of points per face the readers take the range of, thousands of times per
part."""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.policy import jit


@jit
def col_range(X):
    """``(lo, hi)``: the least and largest value of each column of ``X`` (n >= 1
    rows), NaN where the column holds one."""
    if X.shape[0] == 0:
        raise ValueError("the range of no rows")
    k = X.shape[1]
    lo = np.empty(k)
    hi = np.empty(k)
    for c in range(k):
        a = X[0, c]
        b = a
        nan = a != a
        for i in range(1, X.shape[0]):
            x = X[i, c]
            if x != x:
                nan = True
            elif x < a:
                a = x
            elif x > b:
                b = x
        lo[c] = math.nan if nan else a
        hi[c] = math.nan if nan else b
    return lo, hi


@jit
def spread(X):
    """The largest extent along a column of ``X`` (n >= 1 rows): numpy's
    ``np.ptp(X, axis=0).max()``, NaN when a value is."""
    lo, hi = col_range(X)
    out = hi[0] - lo[0]
    for c in range(1, X.shape[1]):
        d = hi[c] - lo[c]
        if d != d or out != out:
            out = math.nan
        elif d > out:
            out = d
    return out
