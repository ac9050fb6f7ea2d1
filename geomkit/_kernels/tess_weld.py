"""Close pairs of points for the tessellation's weld, without a k-d tree.

A weld asks for the pairs of a face's points (UV corners, or 3-D vertices on the
domain's boundary) closer than a radius far below their spacing: almost always none,
a few where a seam or pole folds the face or a trim crossing was computed in two
cells.  Building scipy's ``cKDTree`` for that cost tens of microseconds a face; here
the points are sorted by their projection on a direction of length at most 1 and
each is compared with the following ones while their projections stay within the
window (a pair within ``r`` projects within ``r``, plus the projections' rounding:
the caller's ``window``).
"""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit


@jit
def close_pairs(Q, w, r, window):
    """``(k, 2)`` int64 pairs ``(i, j)``, ``i < j``, of the rows of ``Q`` (n, d) whose
    squared distance (the squared differences summed in coordinate order) is at most
    ``r * r`` -- the pairs ``cKDTree(Q).query_pairs(r)`` finds -- in no set order.
    ``w`` (d,): the sorting direction, ``|w| <= 1``; ``window``: at least ``r`` plus
    twice the rounding of the projections ``Q @ w``."""
    n = Q.shape[0]
    d = Q.shape[1]
    proj = np.empty(n)
    for i in range(n):
        acc = 0.0
        for k in range(d):
            acc += Q[i, k] * w[k]
        proj[i] = acc
    order = np.argsort(proj)
    out = np.empty((8, 2), dtype=np.int64)
    m = 0
    r2 = r * r
    for a in range(n):
        i = order[a]
        for b in range(a + 1, n):
            j = order[b]
            if proj[j] - proj[i] > window:
                break
            dd = 0.0
            for k in range(d):
                t = Q[i, k] - Q[j, k]
                dd += t * t
            if dd <= r2:
                if m == out.shape[0]:
                    grown = np.empty((2 * m, 2), dtype=np.int64)
                    grown[:m] = out
                    out = grown
                out[m, 0] = min(i, j)
                out[m, 1] = max(i, j)
                m += 1
    return out[:m]
