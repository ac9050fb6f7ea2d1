"""Bounding-volume hierarchy kernels: fitting OBB / AABB / 14-DOP nodes, building
the flattened tree, refitting 14-DOPs after a rigid motion (Papers 3 and 5).

Tree layout (all arrays C-contiguous, node 0 is the root, children have larger
indices than their parent, so a reverse sweep visits children before parents):

* ``child`` (n, 2) int64: left and right child, ``-1`` for a leaf;
* ``rng`` (n, 2) int64: the node's triangles are ``order[rng[i, 0]:rng[i, 1]]``;
* boxes (OBB and AABB trees): ``C`` (n, 3) centre, ``R`` (n, 3, 3) axes as
  *columns* (orthonormal, det +1), ``E`` (n, 3) half extents (>= 0), in the body
  frame; an AABB is an OBB with ``R = I``;
* 14-DOPs: ``K`` (n, 14): ``K[i, 2d]`` / ``K[i, 2d + 1]`` the min / max of
  ``x . D[d]`` over the node's vertices for the 7 directions of :data:`KDOP_DIRS`
  (3 axes + 4 cube diagonals, unnormalised).

Building is top-down: each node's triangles are sorted by the projection of their
centroids on the split direction (the longest axis of the node's box; for 14-DOPs
the longest of x, y, z) and cut at the median, until at most ``leaf_size`` remain.
The depth is therefore ``ceil(log2(m / leaf_size))``.
"""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit, jit_inline

KDOP_DIRS = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0],
                      [1.0, 1.0, 1.0], [1.0, -1.0, 1.0], [1.0, 1.0, -1.0],
                      [-1.0, 1.0, 1.0]])
"""The 7 direction pairs of a 14-DOP (Paper 5): 3 axes and 4 cube diagonals."""

BOX_INFLATE = 1e-12
"""Relative growth of every fitted box / k-DOP (absorbs rounding of the fit)."""


def _kdop_order():
    """Paper 5's test order: after a direction, the one most different from it
    (smallest |cos|, ties broken by the smallest |cos| to all earlier ones)."""
    D = KDOP_DIRS / np.linalg.norm(KDOP_DIRS, axis=1)[:, None]
    order = [0]
    while len(order) < 7:
        rest = [k for k in range(7) if k not in order]
        order.append(min(rest, key=lambda k: (round(abs(D[k] @ D[order[-1]]), 9),
                                              sum(abs(D[k] @ D[j]) for j in order))))
    return np.array(order, dtype=np.int64)


KDOP_ORDER = _kdop_order()


@jit
def triangle_centroids_areas(V, F, cen, area):
    """Centroids (m, 3) and areas (m,) of the triangles ``V[F]``."""
    for i in range(F.shape[0]):
        a, b, c = F[i, 0], F[i, 1], F[i, 2]
        ux, uy, uz = V[b, 0] - V[a, 0], V[b, 1] - V[a, 1], V[b, 2] - V[a, 2]
        wx, wy, wz = V[c, 0] - V[a, 0], V[c, 1] - V[a, 1], V[c, 2] - V[a, 2]
        nx = uy * wz - uz * wy
        ny = uz * wx - ux * wz
        nz = ux * wy - uy * wx
        area[i] = 0.5 * np.sqrt(nx * nx + ny * ny + nz * nz)
        for k in range(3):
            cen[i, k] = (V[a, k] + V[b, k] + V[c, k]) / 3.0


@jit
def _covariance(V, F, idx, lo, hi, cen, area, regions, M):
    """Covariance of the area-weighted triangles ``idx[lo:hi]`` about a centre.

    Second moment of the uniform area density (Gottschalk): per triangle
    ``A/12 (9 m m^T + sum_k p_k p_k^T)``.  The centre is the area centroid
    (``regions == 0``) or, Paper 3's improvement, the mean of the area centroids of
    ``regions`` groups of equal area taken along the longest coordinate axis.
    Falls back to the plain vertex covariance when the total area is 0.
    """
    S = np.zeros((3, 3))
    mu = np.zeros(3)
    tot = 0.0
    for r in range(lo, hi):
        t = idx[r]
        A = area[t]
        tot += A
        for j in range(3):
            mu[j] += A * cen[t, j]
            for k in range(3):
                s = 9.0 * cen[t, j] * cen[t, k]
                for v in range(3):
                    s += V[F[t, v], j] * V[F[t, v], k]
                S[j, k] += A / 12.0 * s
    if not tot > 0.0:
        S[:, :] = 0.0
        mu[:] = 0.0
        n = 0
        for r in range(lo, hi):
            for v in range(3):
                p = V[F[idx[r], v]]
                n += 1
                for j in range(3):
                    mu[j] += p[j]
                    for k in range(3):
                        S[j, k] += p[j] * p[k]
        tot = float(n)
    S /= tot
    mu /= tot
    c = mu.copy()
    if regions > 0 and hi - lo >= regions:
        # equal-area groups along the longest coordinate extent of the centroids
        ax = 0
        best = -1.0
        for k in range(3):
            mn = np.inf
            mx = -np.inf
            for r in range(lo, hi):
                mn = min(mn, cen[idx[r], k])
                mx = max(mx, cen[idx[r], k])
            if mx - mn > best:
                best = mx - mn
                ax = k
        key = np.empty(hi - lo)
        for r in range(lo, hi):
            key[r - lo] = cen[idx[r], ax]
        srt = np.argsort(key)
        gsum = np.zeros((regions, 3))
        garea = np.zeros(regions)
        acc = 0.0
        aa = np.empty(hi - lo)
        for r in range(hi - lo):
            aa[r] = area[idx[lo + srt[r]]] if tot > 0.0 else 1.0
        total = aa.sum()
        for r in range(hi - lo):
            t = idx[lo + srt[r]]
            g = min(regions - 1, int(regions * (acc + 0.5 * aa[r]) / total)) if total > 0 \
                else min(regions - 1, regions * r // (hi - lo))
            acc += aa[r]
            w = aa[r] if total > 0 else 1.0
            garea[g] += w
            for k in range(3):
                gsum[g, k] += w * cen[t, k]
        c[:] = 0.0
        ng = 0
        for g in range(regions):
            if garea[g] > 0.0:
                ng += 1
                for k in range(3):
                    c[k] += gsum[g, k] / garea[g]
        c /= ng
    for j in range(3):
        for k in range(3):
            M[j, k] = S[j, k] - mu[j] * c[k] - c[j] * mu[k] + c[j] * c[k]


@jit
def fit_box(V, F, idx, lo, hi, cen, area, mode, regions, C, R, E):
    """Fit an OBB (``mode == 0``) or AABB (``mode == 1``) to triangles ``idx[lo:hi]``.

    OBB axes are the unit eigenvectors of :func:`_covariance` (Paper 3), made
    right-handed; extents are the projection intervals of the vertices, grown by
    :data:`BOX_INFLATE`; the centre is the middle of those intervals.
    """
    if mode == 0:
        M = np.empty((3, 3))
        _covariance(V, F, idx, lo, hi, cen, area, regions, M)
        w, Q = np.linalg.eigh(M)
        for j in range(3):
            for k in range(3):
                R[j, k] = Q[j, k]
        # right-handed: third axis = first x second
        R[0, 2] = R[1, 0] * R[2, 1] - R[2, 0] * R[1, 1]
        R[1, 2] = R[2, 0] * R[0, 1] - R[0, 0] * R[2, 1]
        R[2, 2] = R[0, 0] * R[1, 1] - R[1, 0] * R[0, 1]
    else:
        R[:, :] = 0.0
        for k in range(3):
            R[k, k] = 1.0
    mn = np.full(3, np.inf)
    mx = np.full(3, -np.inf)
    for r in range(lo, hi):
        t = idx[r]
        for v in range(3):
            p = V[F[t, v]]
            for k in range(3):
                s = p[0] * R[0, k] + p[1] * R[1, k] + p[2] * R[2, k]
                mn[k] = min(mn[k], s)
                mx[k] = max(mx[k], s)
    for k in range(3):
        mid = 0.5 * (mn[k] + mx[k])
        half = 0.5 * (mx[k] - mn[k])
        E[k] = half * (1.0 + BOX_INFLATE) + BOX_INFLATE * max(abs(mn[k]), abs(mx[k]))
        mn[k] = mid
    for j in range(3):
        C[j] = R[j, 0] * mn[0] + R[j, 1] * mn[1] + R[j, 2] * mn[2]


@jit
def _kdop_grow(K, x, y, z):
    K[0] = min(K[0], x)
    K[1] = max(K[1], x)
    K[2] = min(K[2], y)
    K[3] = max(K[3], y)
    K[4] = min(K[4], z)
    K[5] = max(K[5], z)
    s = x + y + z
    K[6] = min(K[6], s)
    K[7] = max(K[7], s)
    s = x - y + z
    K[8] = min(K[8], s)
    K[9] = max(K[9], s)
    s = x + y - z
    K[10] = min(K[10], s)
    K[11] = max(K[11], s)
    s = -x + y + z
    K[12] = min(K[12], s)
    K[13] = max(K[13], s)


@jit
def _kdop_reset(K):
    for d in range(7):
        K[2 * d] = np.inf
        K[2 * d + 1] = -np.inf


@jit
def _kdop_pad(K):
    for d in range(7):
        pad = BOX_INFLATE * max(abs(K[2 * d]), abs(K[2 * d + 1]), K[2 * d + 1] - K[2 * d])
        K[2 * d] -= pad
        K[2 * d + 1] += pad


@jit
def fit_kdop(V, F, idx, lo, hi, K):
    """14-DOP (Paper 5) of the triangles ``idx[lo:hi]`` into ``K`` (14,)."""
    _kdop_reset(K)
    for r in range(lo, hi):
        t = idx[r]
        for v in range(3):
            p = V[F[t, v]]
            _kdop_grow(K, p[0], p[1], p[2])
    _kdop_pad(K)


@jit
def build_tree(V, F, kind, leaf_size, regions):
    """Top-down BVH over the triangles ``V[F]`` (median split, see module docstring).

    ``kind``: 0 OBB, 1 AABB, 2 14-DOP.  Returns ``(order, child, rng, C, R, E, K,
    depth)``; for a 14-DOP tree ``C, R, E`` hold the nodes' AABBs (used to choose
    splits), for box trees ``K`` is empty.
    """
    m = F.shape[0]
    cen = np.empty((m, 3))
    area = np.empty(m)
    triangle_centroids_areas(V, F, cen, area)
    order = np.arange(m)
    cap = max(1, 2 * m)
    child = np.full((cap, 2), -1, dtype=np.int64)
    rng = np.zeros((cap, 2), dtype=np.int64)
    C = np.zeros((cap, 3))
    R = np.zeros((cap, 3, 3))
    E = np.zeros((cap, 3))
    K = np.zeros((cap if kind == 2 else 0, 14))
    st_node = np.empty(cap, dtype=np.int64)
    st_depth = np.empty(cap, dtype=np.int64)
    rng[0, 0] = 0
    rng[0, 1] = m
    n = 1
    top = 0
    st_node[0] = 0
    st_depth[0] = 0
    top = 1
    depth = 0
    while top > 0:
        top -= 1
        node = st_node[top]
        dep = st_depth[top]
        depth = max(depth, dep)
        lo, hi = rng[node, 0], rng[node, 1]
        fit_box(V, F, order, lo, hi, cen, area, 0 if kind == 0 else 1, regions,
                C[node], R[node], E[node])
        if kind == 2:
            fit_kdop(V, F, order, lo, hi, K[node])
        if hi - lo <= leaf_size:
            continue
        ax = 0
        for k in range(1, 3):
            if E[node, k] > E[node, ax]:
                ax = k
        key = np.empty(hi - lo)
        for r in range(lo, hi):
            t = order[r]
            key[r - lo] = cen[t, 0] * R[node, 0, ax] + cen[t, 1] * R[node, 1, ax] + \
                cen[t, 2] * R[node, 2, ax]
        srt = np.argsort(key, kind="mergesort")
        seg = order[lo:hi].copy()
        for r in range(hi - lo):
            order[lo + r] = seg[srt[r]]
        mid = (lo + hi) // 2
        left = n
        n += 2
        child[node, 0] = left
        child[node, 1] = left + 1
        rng[left, 0] = lo
        rng[left, 1] = mid
        rng[left + 1, 0] = mid
        rng[left + 1, 1] = hi
        st_node[top] = left
        st_depth[top] = dep + 1
        st_node[top + 1] = left + 1
        st_depth[top + 1] = dep + 1
        top += 2
    if kind == 2:
        K = K[:n].copy()
    return (order, child[:n].copy(), rng[:n].copy(), C[:n].copy(), R[:n].copy(),
            E[:n].copy(), K, depth)


@jit
def leaf_triangles(V, F, order):
    """Triangle corner coordinates in tree order, (m, 3, 3): leaf tests read them
    contiguously."""
    m = order.shape[0]
    T = np.empty((m, 3, 3))
    for r in range(m):
        t = order[r]
        for v in range(3):
            for k in range(3):
                T[r, v, k] = V[F[t, v], k]
    return T


@jit
def refit_kdop(T, child, rng, Rw, tw, K):
    """14-DOPs of the tree after the motion ``x -> Rw x + tw`` (Paper 5's cheap
    rebuild): leaves from their moved triangles ``T`` (tree order), inner nodes as
    the union of their children, in one reverse sweep.  Cost: one transform per
    triangle corner plus O(nodes)."""
    n = child.shape[0]
    for i in range(n - 1, -1, -1):
        Ki = K[i]
        if child[i, 0] < 0:
            _kdop_reset(Ki)
            for r in range(rng[i, 0], rng[i, 1]):
                for v in range(3):
                    x, y, z = T[r, v, 0], T[r, v, 1], T[r, v, 2]
                    _kdop_grow(Ki, Rw[0, 0] * x + Rw[0, 1] * y + Rw[0, 2] * z + tw[0],
                               Rw[1, 0] * x + Rw[1, 1] * y + Rw[1, 2] * z + tw[1],
                               Rw[2, 0] * x + Rw[2, 1] * y + Rw[2, 2] * z + tw[2])
            _kdop_pad(Ki)
        else:
            a = K[child[i, 0]]
            b = K[child[i, 1]]
            for d in range(7):
                Ki[2 * d] = min(a[2 * d], b[2 * d])
                Ki[2 * d + 1] = max(a[2 * d + 1], b[2 * d + 1])


@jit_inline
def rigid_code(P, tol):
    """Check one rigid pose ``P`` (4, 4): ``(code, value)`` as :func:`pose_status`
    (code 0: rigid).  Inlined: the single-call kernel checks both poses of every call
    (as a call it cost an array reference count round trip each)."""
    for r in range(4):
        for c in range(4):
            if not np.isfinite(P[r, c]):
                return 1, P[r, c]
    if P[3, 0] != 0.0 or P[3, 1] != 0.0 or P[3, 2] != 0.0 or P[3, 3] != 1.0:
        return 2, 0.0
    err = 0.0
    for i in range(3):
        for j in range(3):
            s = P[0, i] * P[0, j] + P[1, i] * P[1, j] + P[2, i] * P[2, j]
            err = max(err, abs(s - (1.0 if i == j else 0.0)))
    if err > tol:
        return 3, err
    det = (P[0, 0] * (P[1, 1] * P[2, 2] - P[1, 2] * P[2, 1])
           - P[0, 1] * (P[1, 0] * P[2, 2] - P[1, 2] * P[2, 0])
           + P[0, 2] * (P[1, 0] * P[2, 1] - P[1, 1] * P[2, 0]))
    if det < 0.0:
        return 4, det
    return 0, 0.0


@jit
def pose_status(P, tol):
    """Check rigid poses ``P`` (n, 4, 4).  Returns ``(k, code, value)`` for the first
    bad pose k (code 1 non-finite, 2 last row not (0, 0, 0, 1), 3 rotation not
    orthonormal within ``tol`` (value: max |R^T R - I|), 4 determinant < 0), or
    ``(-1, 0, 0.0)`` when all are rigid."""
    for k in range(P.shape[0]):
        code, val = rigid_code(P[k], tol)
        if code != 0:
            return k, code, val
    return -1, 0, 0.0
