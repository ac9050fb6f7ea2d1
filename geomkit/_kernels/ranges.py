"""Reductions over small point arrays in one call.  Column ranges: numpy's ``X.min(axis=0)`` /
``X.max(axis=0)`` (a NaN in a column gives NaN there) cost a few microseconds each on
the dozens of points per face the readers take the range of, thousands of times per
part."""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.policy import jit, jit_exact


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


@jit
def hull_spread(Pw):
    """:func:`spread` of the Cartesian points ``Pw[:, :3] / Pw[:, 3]`` of homogeneous
    control points (n >= 1, 4), without making them: the largest extent along x, y
    or z of a loop's control points (NaN when a coordinate is)."""
    if Pw.shape[0] == 0:
        raise ValueError("the range of no rows")
    lo = np.empty(3)
    hi = np.empty(3)
    nan = np.zeros(3, dtype=np.bool_)
    for c in range(3):
        a = Pw[0, c] / Pw[0, 3]
        lo[c] = a
        hi[c] = a
        nan[c] = a != a
    for i in range(1, Pw.shape[0]):
        for c in range(3):
            x = Pw[i, c] / Pw[i, 3]
            if x != x:
                nan[c] = True
            elif x < lo[c]:
                lo[c] = x
            elif x > hi[c]:
                hi[c] = x
    out = 0.0
    for c in range(3):
        d = math.nan if nan[c] else hi[c] - lo[c]
        if c == 0:
            out = d
        elif d != d or out != out:
            out = math.nan
        elif d > out:
            out = d
    return out


@jit_exact
def nearest_rows(G, X):
    """For each row of ``X`` (m, 3) the index of its nearest row of ``G`` (n >= 1, 3)
    by brute force (the first of equally near ones; squared distances summed over
    x, y, z in turn, without contraction, as a k-d tree's are): for the few dozen
    points a reader seeds per face, cheaper than building a tree.  A row with a NaN
    gets index 0."""
    out = np.zeros(X.shape[0], np.int64)
    for i in range(X.shape[0]):
        x0, x1, x2 = X[i, 0], X[i, 1], X[i, 2]
        best = math.inf
        for j in range(G.shape[0]):
            d0 = x0 - G[j, 0]
            d1 = x1 - G[j, 1]
            d2 = x2 - G[j, 2]
            d = d0 * d0 + d1 * d1 + d2 * d2
            if d < best:
                best = d
                out[i] = j
    return out
