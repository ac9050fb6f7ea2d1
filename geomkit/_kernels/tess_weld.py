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


@jit
def _uv_order(uv):
    """Indices sorting the rows of ``uv`` (n, 2) by u, then v (as numpy sorts complex
    numbers ``u + iv``)."""
    n = uv.shape[0]
    order = np.argsort(uv[:, 0], kind="mergesort")
    a = 0
    while a < n:
        b = a + 1
        while b < n and uv[order[b], 0] == uv[order[a], 0]:
            b += 1
        if b - a > 1:
            run = order[a:b].copy()
            key = np.empty(b - a)
            for k in range(b - a):
                key[k] = uv[run[k], 1]
            sub = np.argsort(key, kind="mergesort")
            for k in range(b - a):
                order[a + k] = run[sub[k]]
        a = b
    return order


@jit
def unique_uv(uv, near, r, w):
    """The distinct rows of ``uv`` (n, 2) sorted by u then v, the index of each row's
    among them (``np.unique`` of ``u + iv`` with its inverse), and, with ``near``, the
    pairs of distinct rows within ``r`` (:func:`close_pairs` along ``w``)."""
    n = uv.shape[0]
    order = _uv_order(uv)
    inv = np.empty(n, dtype=np.int64)
    uniq = np.empty((n, 2))
    m = -1
    for k in range(n):
        i = order[k]
        if m < 0 or uv[i, 0] != uniq[m, 0] or uv[i, 1] != uniq[m, 1]:
            m += 1
            uniq[m, 0] = uv[i, 0]
            uniq[m, 1] = uv[i, 1]
        inv[i] = m
    uniq = uniq[:m + 1]
    if not near or uniq.shape[0] < 2:
        return uniq, inv, np.empty((0, 2), dtype=np.int64)
    big = 0.0
    for i in range(uniq.shape[0]):
        big = max(big, abs(uniq[i, 0]), abs(uniq[i, 1]))
    return uniq, inv, close_pairs(uniq, w, r, 2.0 * r + 1e-14 * big)


@jit
def weld_merge(P, uniq, inv, pairs, u0, u1, v0, v1, eps, r, w):
    """The weld's vertices ``P`` / ``uniq`` merged along ``pairs`` and the pairs of
    domain-boundary vertices (within ``eps`` of the domain's edges) closer than ``r`` in
    3-D (:func:`close_pairs` along ``w``); each component keeps its first member:
    ``(P, F (m, 3), uv, good)``, ``good`` the faces with three distinct corners."""
    n = uniq.shape[0]
    bnd = np.empty(n, dtype=np.int64)
    nb = 0
    for i in range(n):
        if uniq[i, 0] <= u0 + eps or uniq[i, 0] >= u1 - eps or uniq[i, 1] <= v0 + eps \
                or uniq[i, 1] >= v1 - eps:
            bnd[nb] = i
            nb += 1
    root = np.arange(n)
    linked = pairs.shape[0] > 0
    for k in range(pairs.shape[0]):
        _link(root, pairs[k, 0], pairs[k, 1])
    if nb >= 2:
        Q = np.empty((nb, 3))
        big = 0.0
        for k in range(nb):
            for c in range(3):
                Q[k, c] = P[bnd[k], c]
                big = max(big, abs(Q[k, c]))
        bp = close_pairs(Q, w, r, 2.0 * r + 1e-14 * big)
        for k in range(bp.shape[0]):
            _link(root, bnd[bp[k, 0]], bnd[bp[k, 1]])
            linked = True
    m = inv.shape[0] // 3
    F = np.empty((m, 3), dtype=np.int64)
    good = np.empty(m, dtype=np.bool_)
    if not linked:
        for t in range(m):
            for c in range(3):
                F[t, c] = inv[3 * t + c]
            good[t] = F[t, 0] != F[t, 1] and F[t, 1] != F[t, 2] and F[t, 0] != F[t, 2]
        return P, F, uniq, good
    label = np.empty(n, dtype=np.int64)
    nf = 0
    for i in range(n):  # roots are the smallest members: met before their component
        j = _find(root, i)
        if j == i:
            label[i] = nf
            nf += 1
        else:
            label[i] = label[j]
    P2 = np.empty((nf, 3))
    uv2 = np.empty((nf, 2))
    for i in range(n):
        if root[i] == i:
            P2[label[i]] = P[i]
            uv2[label[i]] = uniq[i]
    for t in range(m):
        for c in range(3):
            F[t, c] = label[inv[3 * t + c]]
        good[t] = F[t, 0] != F[t, 1] and F[t, 1] != F[t, 2] and F[t, 0] != F[t, 2]
    return P2, F, uv2, good


@jit
def _find(root, i):
    while root[i] != i:
        root[i] = root[root[i]]
        i = root[i]
    return i


@jit
def _link(root, a, b):
    """Join the components of ``a`` and ``b``, the smaller root leading."""
    ra = _find(root, a)
    rb = _find(root, b)
    if ra < rb:
        root[rb] = ra
    elif rb < ra:
        root[ra] = rb
