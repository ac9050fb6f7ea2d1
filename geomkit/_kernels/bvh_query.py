"""BVH traversal kernels: collision and minimum distance of two trees (Papers 3, 5).

Both traversals walk node pairs with an explicit stack (no recursion), descending
the node with the larger extent.  Node tests:

* box trees (OBB, AABB): the 15-axis separating-axis test of Paper 3 (Gottschalk's
  form) with B's box carried into A's frame by the relative motion ``(Rr, tr)``;
  ``SAT_EPS`` is added to every ``|R_ij|`` so that axes from nearly parallel edges
  never separate by rounding (the radii only grow: conservative);
* 14-DOP trees: both trees already refitted in the world frame; the 7 interval
  tests run in :data:`geomkit._kernels.bvh.KDOP_ORDER` (Paper 5: after an
  overlapping direction, the direction most different from it).

Leaf pairs go to the exact triangle kernels of :mod:`.triangles`; triangles are
moved on the fly, A's by ``(MA, mA)`` and B's by ``(MB, mB)`` into the common frame
of the node test (A's frame for boxes, the world for 14-DOPs).

Lower bounds for distance: for boxes, the largest separation over the 15 SAT axes
(normalised; axes from nearly parallel edges skipped), the circumscribed spheres'
gap or the distance of one box to the other's bounding box in its axes, whichever
is largest; for 14-DOPs the largest interval gap over the 7 unit directions; both
shrunk by ``LB_SHRINK``.  Triangle pairs of a leaf pair: their bounding spheres'
gap and the prism bound of each over the other (height over its plane and
distance beyond one of its edges, :func:`_prism_gap`).
"""

from __future__ import annotations

import numpy as np

from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit, jit_inline
from .bvh import refit_kdop
from .triangles import _intersect_point, triangle_triangle_distance
from .voxel import _heap_pop, _heap_push

SAT_EPS = 1e-10
LB_SHRINK = 1.0 - 1e-9
STACK = 1024
LEAF_BUF = 16
INV_SQRT3 = 1.0 / np.sqrt(3.0)
PLANE_SLACK = 1e-9
"""Triangle plane bounds are lowered by ``PLANE_SLACK`` times the distance between
the two triangles' bounding-sphere centres plus their radii (a bound of every
corner-to-plane lever arm): the unit normal's rounding error is below ~1e-11 (see
``_unit_normal``), so each height's is below ~1e-11 of that arm."""


@jit_inline
def _rel_box(CA, RA, CB, RB, i, j, Rr, tr, Rab, T, M):
    """B-node box in the axes of A-node box: ``Rab = RA^T Rr RB``, ``T`` centre
    (``M`` (3, 3) scratch)."""
    for r in range(3):
        for c in range(3):
            M[r, c] = Rr[r, 0] * RB[j, 0, c] + Rr[r, 1] * RB[j, 1, c] + Rr[r, 2] * RB[j, 2, c]
    d0 = Rr[0, 0] * CB[j, 0] + Rr[0, 1] * CB[j, 1] + Rr[0, 2] * CB[j, 2] + tr[0] - CA[i, 0]
    d1 = Rr[1, 0] * CB[j, 0] + Rr[1, 1] * CB[j, 1] + Rr[1, 2] * CB[j, 2] + tr[1] - CA[i, 1]
    d2 = Rr[2, 0] * CB[j, 0] + Rr[2, 1] * CB[j, 1] + Rr[2, 2] * CB[j, 2] + tr[2] - CA[i, 2]
    for r in range(3):
        T[r] = RA[i, 0, r] * d0 + RA[i, 1, r] * d1 + RA[i, 2, r] * d2
        for c in range(3):
            Rab[r, c] = RA[i, 0, r] * M[0, c] + RA[i, 1, r] * M[1, c] + RA[i, 2, r] * M[2, c]


@jit_inline
def box_separation(Rab, T, a, b, early, Ab):
    """Largest normalised separation of two boxes over the 15 SAT axes (Paper 3),
    or (without ``early``) when larger the gap of their circumscribed spheres or
    the distance from one box to the other's bounding box in its axes (the
    positive face-axis separations ``g`` of A, resp. B: every point pair differs by
    at least ``g_k`` along each axis ``k``, so their distance is at least
    ``sqrt(sum g_k^2)``; up to sqrt(3) tighter than the largest ``g_k`` when the
    boxes are apart diagonally and, unlike the spheres, tight for flat boxes).

    ``a``, ``b`` (3,) half extents; B's axes are the columns of ``Rab`` and its
    centre ``T``, in A's box axes.  With ``early`` the first separating axis's
    value is returned at once (a collision test needs only the sign).  A value
    > 0 proves the boxes disjoint and bounds their distance from below.  ``Ab``
    (3, 3) is scratch.  With ``early``, boxes no axis separates are reported
    overlapping (a value <= 0) even when their spheres are apart (possible only
    within the ``SAT_EPS`` inflation): conservative for a culling test.
    """
    return box_bound(Rab, T, a, b, early, Ab, np.inf)


@jit_inline
def _sphere_gap(T, a, b):
    """The boxes' circumscribed spheres: centre distance minus the half diagonals,
    made smaller than any rounding of it."""
    dc = np.sqrt(T[0] * T[0] + T[1] * T[1] + T[2] * T[2])
    rs = np.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) + \
        np.sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2])
    return dc - rs - 1e-12 * (dc + rs)


@jit_inline
def box_bound(Rab, T, a, b, early, Ab, cut):
    """:func:`box_separation`, except that (without ``early``) a bound reaching
    ``cut`` is returned at once: the face axes, the bounding boxes and the spheres
    come first, the 9 edge axes (a division and a square root each) only when
    those stay below ``cut`` (a branch and bound prunes at ``cut`` = the best
    distance so far: most node pairs it bounds are pruned without their edge
    axes)."""
    for r in range(3):
        for c in range(3):
            Ab[r, c] = abs(Rab[r, c]) + SAT_EPS
    best = -np.inf
    ga = 0.0
    gb = 0.0
    for i in range(3):   # A's face normals
        s = abs(T[i]) - a[i] - (b[0] * Ab[i, 0] + b[1] * Ab[i, 1] + b[2] * Ab[i, 2])
        if s > best:
            best = s
            if early and s > 0.0:
                return s
        if s > 0.0:
            ga += s * s
    for j in range(3):   # B's face normals
        s = abs(T[0] * Rab[0, j] + T[1] * Rab[1, j] + T[2] * Rab[2, j]) - b[j] - \
            (a[0] * Ab[0, j] + a[1] * Ab[1, j] + a[2] * Ab[2, j])
        if s > best:
            best = s
            if early and s > 0.0:
                return s
        if s > 0.0:
            gb += s * s
    if not early:
        if best > 0.0:  # the bounding box in the other's axes (only when apart along
            # a face axis: overlapping boxes keep their negative value, which orders
            # the descent towards the deepest overlap)
            best = max(best, np.sqrt(max(ga, gb)))
        s = _sphere_gap(T, a, b)
        if s > best:
            best = s
        if best >= cut:
            return best
    for i in range(3):   # A_i x B_j
        i1 = (i + 1) % 3
        i2 = (i + 2) % 3
        for j in range(3):
            j1 = (j + 1) % 3
            j2 = (j + 2) % 3
            ra = a[i1] * Ab[i2, j] + a[i2] * Ab[i1, j]
            rb = b[j1] * Ab[i, j2] + b[j2] * Ab[i, j1]
            s = abs(T[i2] * Rab[i1, j] - T[i1] * Rab[i2, j]) - ra - rb
            if s > 0.0:
                if early:
                    return s
                ln2 = 1.0 - Rab[i, j] * Rab[i, j]
                if ln2 > 1e-12:
                    s /= np.sqrt(ln2)
                    if s > best:
                        best = s
    return best


@jit_inline
def kdop_separation(KA, KB, i, j, order, early):
    """Largest interval gap of two 14-DOPs over the 7 unit directions (Paper 5)."""
    best = -np.inf
    for q in range(7):
        d = order[q]
        g = max(KA[i, 2 * d] - KB[j, 2 * d + 1], KB[j, 2 * d] - KA[i, 2 * d + 1])
        if d >= 3:
            g *= INV_SQRT3
        if g > best:
            best = g
            if early and g > 0.0:
                return g
    return best


@jit_inline
def _node_sep(kind, i, j, CA, RA, EA, KA, CB, RB, EB, KB, Rr, tr, order, early, Rab, T,
              scr):
    return _node_bound(kind, i, j, CA, RA, EA, KA, CB, RB, EB, KB, Rr, tr, order, early,
                       Rab, T, scr, np.inf)


@jit_inline
def _node_bound(kind, i, j, CA, RA, EA, KA, CB, RB, EB, KB, Rr, tr, order, early, Rab, T,
                scr, cut):
    """:func:`_node_sep` that may stop once the bound reaches ``cut``
    (:func:`box_bound`)."""
    if kind == 2:
        return kdop_separation(KA, KB, i, j, order, early)
    _rel_box(CA, RA, CB, RB, i, j, Rr, tr, Rab, T, scr[0])
    return box_bound(Rab, T, EA[i], EB[j], early, scr[1], cut)


@jit_inline
def _size(kind, E, K, i):
    if kind == 2:
        return max(K[i, 1] - K[i, 0], K[i, 3] - K[i, 2], K[i, 5] - K[i, 4])
    return max(E[i, 0], E[i, 1], E[i, 2])


@jit_inline
def split_a(kind, childA, childB, EA, KA, EB, KB, i, j):
    """The traversal's descent rule for node pair (i, j): split A's node (True) when
    B's is a leaf, or when neither is and A's is at least as large; else split B's."""
    la = childA[i, 0] < 0
    lb = childB[j, 0] < 0
    return lb or (not la and _size(kind, EA, KA, i) >= _size(kind, EB, KB, j))


@jit_inline
def _move(T, r, M, m, out):
    for v in range(3):
        x, y, z = T[r, v, 0], T[r, v, 1], T[r, v, 2]
        for k in range(3):
            out[v, k] = M[k, 0] * x + M[k, 1] * y + M[k, 2] * z + m[k]


@jit_inline
def _unit_normal(t, out):
    """Unit normal ``out[0]`` of triangle ``t`` (3, 3) and the outward unit normals
    ``out[1 + e]`` in its plane of its edges ``t[e] -> t[e + 1]``; all 0 when its
    corners are nearly collinear (``|e x f| <= 1e-4 |e| |f|`` for its edges ``e``,
    ``f`` from corner 0: the normals' rounding errors then stay below ~1e-11, see
    :data:`PLANE_SLACK`)."""
    e0, e1, e2 = t[1, 0] - t[0, 0], t[1, 1] - t[0, 1], t[1, 2] - t[0, 2]
    f0, f1, f2 = t[2, 0] - t[0, 0], t[2, 1] - t[0, 1], t[2, 2] - t[0, 2]
    n0 = e1 * f2 - e2 * f1
    n1 = e2 * f0 - e0 * f2
    n2 = e0 * f1 - e1 * f0
    nn = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    if not nn > 1e-4 * np.sqrt((e0 * e0 + e1 * e1 + e2 * e2) * (f0 * f0 + f1 * f1 + f2 * f2)):
        out[:] = 0.0
        return
    n0 /= nn
    n1 /= nn
    n2 /= nn
    out[0, 0] = n0
    out[0, 1] = n1
    out[0, 2] = n2
    for e in range(3):      # edge x normal points out of a counter-clockwise triangle
        g = (e + 1) % 3
        d0, d1, d2 = t[g, 0] - t[e, 0], t[g, 1] - t[e, 1], t[g, 2] - t[e, 2]
        m0 = d1 * n2 - d2 * n1
        m1 = d2 * n0 - d0 * n2
        m2 = d0 * n1 - d1 * n0
        mm = np.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
        out[1 + e, 0] = m0 / mm
        out[1 + e, 1] = m1 / mm
        out[1 + e, 2] = m2 / mm


@jit_inline
def _prism_gap(n, t, u):
    """A lower bound of the distance of triangles ``t`` and ``u`` (3, 3) from ``t``'s
    normals ``n`` (4, 3) (:func:`_unit_normal`): with ``h`` the smallest height of
    ``u``'s corners over ``t``'s plane when all lie strictly on one side (else 0) and
    ``l`` the largest, over ``t``'s edges, smallest distance of ``u``'s corners
    beyond the edge's line in the outward in-plane direction (else 0), every point
    pair differs by at least ``h`` along the normal and ``l`` along that
    orthogonal direction: ``sqrt(h^2 + l^2)`` (up to the normals' rounding)."""
    lo = np.inf
    hi = -np.inf
    for v in range(3):
        x = n[0, 0] * (u[v, 0] - t[0, 0]) + n[0, 1] * (u[v, 1] - t[0, 1]) + \
            n[0, 2] * (u[v, 2] - t[0, 2])
        lo = min(lo, x)
        hi = max(hi, x)
    h = lo if lo > 0.0 else (-hi if hi < 0.0 else 0.0)
    lat = 0.0
    for e in range(3):
        m = np.inf
        for v in range(3):
            m = min(m, n[1 + e, 0] * (u[v, 0] - t[e, 0]) + n[1 + e, 1] * (u[v, 1] - t[e, 1]) +
                    n[1 + e, 2] * (u[v, 2] - t[e, 2]))
        lat = max(lat, m)
    return np.sqrt(h * h + lat * lat)


@jit_inline
def _sphere(t, out):
    """A sphere around triangle ``t`` (3, 3): centroid ``out[:3]``, radius ``out[3]``
    (largest corner distance)."""
    for k in range(3):
        out[k] = (t[0, k] + t[1, k] + t[2, k]) / 3.0
    r = 0.0
    for v in range(3):
        r = max(r, (t[v, 0] - out[0]) ** 2 + (t[v, 1] - out[1]) ** 2 + (t[v, 2] - out[2]) ** 2)
    out[3] = np.sqrt(r)


@jit
def collide_trees(kind, childA, rngA, CA, RA, EA, KA, TA, orderA,
                  childB, rngB, CB, RB, EB, KB, TB, orderB,
                  Rr, tr, MA, mA, MB, mB, order, first_only, out_pairs):
    """All intersecting triangle pairs of two trees (or the first, ``first_only``).

    Writes up to ``len(out_pairs)`` pairs of original face indices; returns
    ``(n_pairs, bv_tests)`` where ``n_pairs`` may exceed the buffer (call again
    with a larger one).
    """
    st = np.empty((STACK, 2), dtype=np.int64)
    Rab = np.empty((3, 3))
    T = np.empty(3)
    M = np.empty((3, 3))
    Ab = np.empty((3, 3))
    tbs = np.empty((LEAF_BUF, 3, 3))
    hit = np.empty(3)
    ta = np.empty((3, 3))
    cap = out_pairs.shape[0]
    npairs = 0
    tests = 0
    st[0, 0] = 0
    st[0, 1] = 0
    top = 1
    while top > 0:
        top -= 1
        i = st[top, 0]
        j = st[top, 1]
        tests += 1
        # the node test written out (not _node_sep): measured 4x faster per test
        if kind == 2:
            if kdop_separation(KA, KB, i, j, order, True) > 0.0:
                continue
        else:
            _rel_box(CA, RA, CB, RB, i, j, Rr, tr, Rab, T, M)
            if box_separation(Rab, T, EA[i], EB[j], True, Ab) > 0.0:
                continue
        la = childA[i, 0] < 0
        lb = childB[j, 0] < 0
        if la and lb:
            rb0 = rngB[j, 0]
            # B's leaf triangles (at most LEAF_BUF: leaf_size is checked) moved once
            for rb in range(rngB[j, 1] - rb0):
                _move(TB, rb0 + rb, MB, mB, tbs[rb])
            for ra in range(rngA[i, 0], rngA[i, 1]):
                if kind == 2:
                    _move(TA, ra, MA, mA, ta)
                    tra = ta
                else:             # box trees traverse in A's frame: A does not move
                    tra = TA[ra]
                for rb in range(rngB[j, 0], rngB[j, 1]):
                    if _intersect_point(tra, tbs[rb - rb0], hit):
                        if npairs < cap:
                            out_pairs[npairs, 0] = orderA[ra]
                            out_pairs[npairs, 1] = orderB[rb]
                        npairs += 1
                        if first_only:
                            return npairs, tests
            continue
        if split_a(kind, childA, childB, EA, KA, EB, KB, i, j):
            st[top, 0] = childA[i, 1]
            st[top, 1] = j
            st[top + 1, 0] = childA[i, 0]
            st[top + 1, 1] = j
        else:
            st[top, 0] = i
            st[top, 1] = childB[j, 1]
            st[top + 1, 0] = i
            st[top + 1, 1] = childB[j, 0]
        top += 2
    return npairs, tests


@jit
def distance_trees(kind, childA, rngA, CA, RA, EA, KA, TA, orderA,
                   childB, rngB, CB, RB, EB, KB, TB, orderB,
                   Rr, tr, MA, mA, MB, mB, order, margin, out_p, out_q):
    """Minimum distance of two trees by branch and bound (node lower bounds), best
    first: node pairs on a binary heap keyed by their bound (overlapping pairs,
    which no distance can prune, first and depth first), so that once the smallest
    bound left reaches the best distance the search ends.

    ``margin > 0``: stop at the first triangle pair closer than ``margin`` and
    prune every node pair whose bound reaches ``margin``.  Returns ``(d, fa, fb,
    bv_tests)``: the distance (``inf`` if nothing is closer than ``margin``), the
    original face indices (-1 if none) and the number of node bounds computed;
    the closest points go to ``out_p``, ``out_q`` in the common frame.
    """
    # the heap of node pairs (i << 32 | j; it grows) and scratch, owned here: the
    # search reads them, and the trees, through borrowed views (no atomic reference
    # counting in its loop, geomkit._kernels.numba_ext.borrow)
    return _distance_search(
        kind, childA, rngA, CA, RA, EA, KA, TA, orderA, childB, rngB, CB, RB, EB, KB, TB,
        orderB, Rr, tr, MA, mA, MB, mB, order, margin, out_p, out_q,
        (np.empty(STACK), np.empty(STACK, dtype=np.int64)),
        (np.empty(2), np.empty((3, 3)), np.empty(3), np.empty((2, 3, 3)), np.empty(4),
         np.empty((3, 3)), np.empty((LEAF_BUF, 3, 3)), np.empty((LEAF_BUF, 4)),
         np.empty((LEAF_BUF, 4, 3)), np.empty((4, 3)), np.empty(3), np.empty(3)))


@jit
def _distance_search(kind, childA, rngA, CA, RA, EA, KA, TA, orderA,
                     childB, rngB, CB, RB, EB, KB, TB, orderB,
                     Rr, tr, MA, mA, MB, mB, order, margin, out_p, out_q, heap, work):
    """The search of :func:`distance_trees` over borrowed views of its arrays."""
    (childA, rngA, CA, RA, EA, KA, TA, orderA, childB, rngB, CB, RB, EB, KB, TB, orderB,
     Rr, tr, MA, mA, MB, mB, order, out_p, out_q, heap, work) = borrow_all((
        childA, rngA, CA, RA, EA, KA, TA, orderA, childB, rngB, CB, RB, EB, KB, TB, orderB,
        Rr, tr, MA, mA, MB, mB, order, out_p, out_q, heap, work))
    hkey, hval = heap
    cb, Rab, T, scr, sa, ta, tbs, sph, nb, na, p, q = work
    best = margin if margin > 0.0 else np.inf
    fa = -1
    fb = -1
    tests = 1
    b = _node_sep(kind, 0, 0, CA, RA, EA, KA, CB, RB, EB, KB, Rr, tr, order, False,
                  Rab, T, scr) * LB_SHRINK
    hkey, hval, n = _heap_push(hkey, hval, 0, b if b > 0.0 else -1.0, 0)
    while n > 0:
        key = hkey[0]
        i = hval[0] >> 32
        j = hval[0] & 0xFFFFFFFF
        n = _heap_pop(hkey, hval, n)
        if key >= best:  # best first: every pair left is bounded by best or more
            break       # (a negative key: overlapping boxes, bound <= 0 < best)
        la = childA[i, 0] < 0
        lb = childB[j, 0] < 0
        if la and lb:
            rb0 = rngB[j, 0]
            # B's leaf triangles (at most LEAF_BUF: leaf_size is checked) moved once,
            # with their bounding spheres
            for rb in range(rngB[j, 1] - rb0):
                _move(TB, rb0 + rb, MB, mB, tbs[rb])
                _sphere(tbs[rb], sph[rb])
                _unit_normal(tbs[rb], nb[rb])
            for ra in range(rngA[i, 0], rngA[i, 1]):
                _move(TA, ra, MA, mA, ta)
                _sphere(ta, sa)
                _unit_normal(ta, na)
                for rb in range(rngB[j, 1] - rb0):
                    # the two triangles' spheres: skip the exact distance when their
                    # gap (made smaller than any rounding of it) reaches the best
                    dc = np.sqrt((sa[0] - sph[rb, 0]) ** 2 + (sa[1] - sph[rb, 1]) ** 2 +
                                 (sa[2] - sph[rb, 2]) ** 2)
                    rs = sa[3] + sph[rb, 3]
                    if dc - rs - 1e-12 * (dc + rs) >= best:
                        continue
                    # the prism bounds (_prism_gap): tight for the facing, nearly
                    # parallel pairs of a near-continuum of minima
                    cut = best + PLANE_SLACK * (dc + rs)
                    if _prism_gap(na, ta, tbs[rb]) >= cut or _prism_gap(nb[rb], tbs[rb], ta) >= cut:
                        continue
                    d = triangle_triangle_distance(ta, tbs[rb], p, q)
                    if d < best:
                        best = d
                        fa = orderA[ra]
                        fb = orderB[rb0 + rb]
                        out_p[:] = p
                        out_q[:] = q
                        if margin > 0.0 or d == 0.0:
                            return best, fa, fb, tests
            continue
        if split_a(kind, childA, childB, EA, KA, EB, KB, i, j):
            i0, j0, i1, j1 = childA[i, 0], j, childA[i, 1], j
        else:
            i0, j0, i1, j1 = i, childB[j, 0], i, childB[j, 1]
        # (a bound may stop at best / LB_SHRINK: it then prunes its pair all the same;
        # one call site for the two children: the bound is inlined, compile time)
        cut = best / LB_SHRINK
        for c in range(2):
            cb[c] = _node_bound(kind, i0 if c == 0 else i1, j0 if c == 0 else j1, CA, RA, EA,
                                KA, CB, RB, EB, KB, Rr, tr, order, False, Rab, T, scr,
                                cut) * LB_SHRINK
        tests += 2
        # heap keys: a separated pair's bound (best first), overlapping pairs before
        # every separated one and depth first (children keyed below every pending
        # pair: node indices grow with depth), the nearer child first (lower key)
        base = -4.0 * (i + j + 1)
        near = 0 if cb[0] <= cb[1] else 1
        for c in range(2):
            k = near if c == 1 else 1 - near
            if cb[k] < best:
                hkey, hval, n = _heap_push(
                    hkey, hval, n, cb[k] if cb[k] > 0.0 else base - 1.0 - c,
                    ((i0 if k == 0 else i1) << 32) | (j0 if k == 0 else j1))
    if best == margin and margin > 0.0:
        best = np.inf
    return best, fa, fb, tests


@jit
def collide_many_kdops(i0, i1, childA, rngA, KA, TA, orderA, childB, rngB, KB, TB, orderB,
                       PA, PB, order, first_only, colliding, npairs, tests):
    """Serial worker (run by :func:`geomkit._kernels.numba_ext.policy.prun`): 14-DOP trees
    under the pose pairs ``k`` in ``[i0, i1)`` (``PA``, ``PB`` as in
    :func:`collide_many_boxes`).  Each body is refitted in the world frame
    (Paper 5's rebuild, O(triangles)) only when its pose differs from the one of
    its last refit in this worker: a static body is refitted once."""
    empty3 = np.empty((0, 3))
    empty33 = np.empty((0, 3, 3))
    eye = np.eye(3)
    zero = np.zeros(3)
    KAw = np.empty_like(KA)
    KBw = np.empty_like(KB)
    Ra = np.empty((3, 3))
    ta = np.empty(3)
    Rb = np.empty((3, 3))
    tb = np.empty(3)
    buf = np.empty((0, 2), dtype=np.int64)
    ma = PA.shape[0] > 1
    mb = PB.shape[0] > 1
    la = -1
    lb = -1
    for k in range(i0, i1):
        ka = k if ma else 0
        kb = k if mb else 0
        if la < 0 or not _same_pose(PA[la], PA[ka]):
            _split_pose(PA[ka], Ra, ta)
            refit_kdop(TA, childA, rngA, Ra, ta, KAw)
            la = ka
        if lb < 0 or not _same_pose(PB[lb], PB[kb]):
            _split_pose(PB[kb], Rb, tb)
            refit_kdop(TB, childB, rngB, Rb, tb, KBw)
            lb = kb
        c, t = collide_trees(2, childA, rngA, empty3, empty33, empty3, KAw, TA, orderA,
                             childB, rngB, empty3, empty33, empty3, KBw, TB, orderB,
                             eye, zero, Ra, ta, Rb, tb, order, first_only, buf)
        colliding[k] = c > 0
        npairs[k] = c
        tests[k] = t


@jit_inline
def _split_pose(P, R, t):
    for r in range(3):
        t[r] = P[r, 3]
        for c in range(3):
            R[r, c] = P[r, c]


@jit_inline
def _same_pose(P, Q):
    for r in range(3):
        for c in range(4):
            if P[r, c] != Q[r, c]:
                return False
    return True
