"""Constrained Delaunay triangulation of small polygons, compiled.

A polygon (a counter-clockwise outer ring and clockwise holes inside it) is made one
weakly simple ring by bridging each hole to a vertex it sees (holes taken from the
one reaching furthest in +u, each bridged along the ray from its rightmost vertex, as
earcut does it mirrored), ear-clipped (an ear: a convex corner whose triangle holds no
other remaining point that is not one of its corners), and its diagonals, bridges
included, flipped until each is locally Delaunay: with the rings' edges kept, the
constrained Delaunay triangulation (GEOS's ``constrained_delaunay_triangles`` makes it
the same way; ties between cocircular points may be broken the other way).  The
orientation and incircle tests are plain floating point, compiled without contraction
(:data:`~geomkit._kernels.numba_ext.policy.jit_exact`: a fused multiply-add makes
``orient(a, b, b)`` the rounding error of a product, not 0): a polygon they cannot take
surely (no ear, a bridge that crosses an edge, triangles that do not add up to the
polygon's area) is reported, for the caller's fallback.
"""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit_exact, jit_inline

# diagonals flip only when the fourth point is inside the circle by more than this
# fraction of the incircle determinant's magnitude: cocircular corners stay as made
INCIRCLE_REL = 1e-12


@jit_inline
def _orient(ax, ay, bx, by, cx, cy):
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


@jit_inline
def _opposite(d1, d2):
    """Whether two orientations have strictly opposite signs."""
    return (d1 > 0.0 and d2 < 0.0) or (d1 < 0.0 and d2 > 0.0)


@jit_inline
def _cross_properly(ax, ay, bx, by, cx, cy, dx, dy):
    """Whether the segments a-b and c-d cross at a point inside both."""
    return _opposite(_orient(cx, cy, dx, dy, ax, ay), _orient(cx, cy, dx, dy, bx, by)) \
        and _opposite(_orient(ax, ay, bx, by, cx, cy), _orient(ax, ay, bx, by, dx, dy))


@jit_inline
def _segments_meet(ax, ay, bx, by, cx, cy, dx, dy):
    """Whether the closed segments a-b and c-d share a point."""
    d1 = _orient(cx, cy, dx, dy, ax, ay)
    d2 = _orient(cx, cy, dx, dy, bx, by)
    d3 = _orient(ax, ay, bx, by, cx, cy)
    d4 = _orient(ax, ay, bx, by, dx, dy)
    if _opposite(d1, d2) and _opposite(d3, d4):
        return True
    if d1 == 0.0 and min(cx, dx) <= ax <= max(cx, dx) and min(cy, dy) <= ay <= max(cy, dy):
        return True
    if d2 == 0.0 and min(cx, dx) <= bx <= max(cx, dx) and min(cy, dy) <= by <= max(cy, dy):
        return True
    if d3 == 0.0 and min(ax, bx) <= cx <= max(ax, bx) and min(ay, by) <= cy <= max(ay, by):
        return True
    if d4 == 0.0 and min(ax, bx) <= dx <= max(ax, bx) and min(ay, by) <= dy <= max(ay, by):
        return True
    return False


@jit_exact
def _grow(a, n):
    """``a`` with room for at least ``n`` rows (doubled)."""
    if n <= a.shape[0]:
        return a
    shape = (max(n, 2 * a.shape[0]),) + a.shape[1:]
    b = np.empty(shape, dtype=a.dtype)
    b[:a.shape[0]] = a
    return b


@jit_inline
def _same_point(x, y, a, b):
    return x[a] == x[b] and y[a] == y[b]


@jit_inline
def _in_closed_triangle(px, py, ax, ay, bx, by, cx, cy):
    return _orient(ax, ay, bx, by, px, py) >= 0.0 and _orient(bx, by, cx, cy, px, py) >= 0.0 \
        and _orient(cx, cy, ax, ay, px, py) >= 0.0


@jit_exact
def _ear_clip(x, y, n, tri, nxt, prv):
    """Triangles (rows of corner indices, counter-clockwise) of the weakly simple
    counter-clockwise polygon ``x, y`` (``n`` points; bridged holes repeat points):
    ``(count, ok)``.  An ear is a convex corner whose triangle holds no other remaining
    point (on its edges included) that is not at one of its corners."""
    for i in range(n):
        nxt[i] = (i + 1) % n
        prv[i] = (i - 1) % n
    left = n
    nt = 0
    i = 0
    miss = 0
    while left > 3:
        p = prv[i]
        q = nxt[i]
        ear = _orient(x[p], y[p], x[i], y[i], x[q], y[q]) > 0.0
        if ear:
            r = nxt[q]
            while r != p:
                if not _same_point(x, y, r, p) and not _same_point(x, y, r, i) and \
                        not _same_point(x, y, r, q) and \
                        _in_closed_triangle(x[r], y[r], x[p], y[p], x[i], y[i], x[q], y[q]):
                    ear = False
                    break
                r = nxt[r]
        if ear:
            tri[nt, 0] = p
            tri[nt, 1] = i
            tri[nt, 2] = q
            nt += 1
            nxt[p] = q
            prv[q] = p
            left -= 1
            i = q
            miss = 0
        else:
            i = q
            miss += 1
            if miss > left:
                return nt, False
    i = nxt[i]
    p = prv[i]
    q = nxt[i]
    if not _orient(x[p], y[p], x[i], y[i], x[q], y[q]) > 0.0:
        return nt, False
    tri[nt, 0] = p
    tri[nt, 1] = i
    tri[nt, 2] = q
    return nt + 1, True


@jit_inline
def _incircle(ax, ay, bx, by, cx, cy, dx, dy):
    """Whether d is inside the circle through the counter-clockwise a, b, c by more than
    :data:`INCIRCLE_REL` of the determinant's magnitude."""
    adx = ax - dx
    ady = ay - dy
    bdx = bx - dx
    bdy = by - dy
    cdx = cx - dx
    cdy = cy - dy
    al = adx * adx + ady * ady
    bl = bdx * bdx + bdy * bdy
    cl = cdx * cdx + cdy * cdy
    det = al * (bdx * cdy - bdy * cdx) + bl * (cdx * ady - cdy * adx) \
        + cl * (adx * bdy - ady * bdx)
    mag = al * (abs(bdx * cdy) + abs(bdy * cdx)) + bl * (abs(cdx * ady) + abs(cdy * adx)) \
        + cl * (abs(adx * bdy) + abs(ady * bdx))
    return det > INCIRCLE_REL * mag


@jit_exact
def _flip_to_delaunay(x, y, ring_of, rs, tri, nt):
    """Diagonals of the ear-clipped polygon (triangles ``tri[:nt]`` of the points ``x,
    y``, ring ``ring_of[i]`` of each, ring ``r`` the points ``rs[r]:rs[r+1]`` in order)
    flipped until each is locally Delaunay; the rings' edges stay."""
    budget = 4 * nt * nt + 8
    changed = True
    while changed and budget > 0:
        changed = False
        for t in range(nt):
            for e in range(3):
                a = tri[t, e]
                b = tri[t, (e + 1) % 3]
                c = tri[t, (e + 2) % 3]
                r = ring_of[a]
                if r == ring_of[b]:
                    L = rs[r + 1] - rs[r]
                    if (b - a) % L == 1 or (a - b) % L == 1:
                        continue  # an edge of a ring
                for u in range(nt):
                    if u == t:
                        continue
                    f = -1
                    for g in range(3):
                        if tri[u, g] == b and tri[u, (g + 1) % 3] == a:
                            f = g
                    if f < 0:
                        continue
                    d = tri[u, (f + 2) % 3]
                    if _incircle(x[a], y[a], x[b], y[b], x[c], y[c], x[d], y[d]) and \
                            _orient(x[a], y[a], x[d], y[d], x[c], y[c]) > 0.0 and \
                            _orient(x[d], y[d], x[b], y[b], x[c], y[c]) > 0.0:
                        tri[t, 0] = a
                        tri[t, 1] = d
                        tri[t, 2] = c
                        tri[u, 0] = d
                        tri[u, 1] = b
                        tri[u, 2] = c
                        changed = True
                        budget -= 1
                    break
                if changed:
                    break
            if changed:
                break


@jit_exact
def _bridge_target(X, seq, nxt, start, hx, hy):
    """The position of the ring (linked positions from ``start``, points ``X[seq]``) a
    hole's rightmost point (hx, hy) is bridged to: the nearer end, in +u, of the first
    edge the ray towards +u meets, or the reflex point inside the triangle ray hit -
    that end - (hx, hy) nearest the ray in angle; -1 when the ray meets no edge or
    runs through the hole's point."""
    best = np.inf
    m = -1
    p = start
    while True:
        q = nxt[p]
        ax, ay = X[seq[p], 0], X[seq[p], 1]
        bx, by = X[seq[q], 0], X[seq[q], 1]
        if (ay <= hy <= by or by <= hy <= ay) and ay != by:
            x = ax + (hy - ay) * (bx - ax) / (by - ay)
            if hx <= x < best:
                if x == hx:
                    return -1
                best = x
                m = p if ax > bx else q
        p = q
        if p == start:
            break
    if m < 0:
        return -1
    mx, my = X[seq[m], 0], X[seq[m], 1]
    if mx == best:
        return m  # the ray runs through the ring's point
    # a point inside the triangle (h, ray hit, m) would block the bridge: take the one
    # closest to the ray in angle instead
    tan_best = np.inf
    p = start
    pick = m
    while True:
        px, py = X[seq[p], 0], X[seq[p], 1]
        if p != m and px > hx:
            if my > hy:  # the triangle counter-clockwise
                inside = _in_closed_triangle(px, py, hx, hy, best, hy, mx, my)
            else:
                inside = _in_closed_triangle(px, py, hx, hy, mx, my, best, hy)
        else:
            inside = False
        if inside:
            t = abs(py - hy) / (px - hx)
            if t < tan_best or (t == tan_best and px > X[seq[pick], 0]):
                tan_best = t
                pick = p
        p = nxt[p]
        if p == start:
            break
    return pick


@jit_exact
def _bridge_crosses(X, seq, nxt, start, hx, hy, mx, my):
    """Whether the segment (hx, hy)-(mx, my) properly crosses an edge of the ring."""
    p = start
    while True:
        q = nxt[p]
        ax, ay = X[seq[p], 0], X[seq[p], 1]
        bx, by = X[seq[q], 0], X[seq[q], 1]
        if _cross_properly(hx, hy, mx, my, ax, ay, bx, by):
            return True
        p = q
        if p == start:
            break
    return False


@jit_exact
def triangulate_polygon(X, rs):
    """Constrained Delaunay triangles of the polygon whose rings are ``X[rs[k]:rs[k+1]]``
    (open: the first point not repeated): ring 0 counter-clockwise, the others clockwise
    holes inside it.  ``(tri (t, 3) rows of indices into X, counter-clockwise, ok)``;
    not ok (no triangles) when a hole finds no bridge, ear clipping finds no ear or the
    triangles do not add up to the polygon's area."""
    n = X.shape[0]
    nr = rs.shape[0] - 1
    ring_of = np.empty(n, dtype=np.int64)
    for r in range(nr):
        for i in range(rs[r], rs[r + 1]):
            ring_of[i] = r
    cap = n + 2 * (nr - 1)
    seq = np.empty(cap, dtype=np.int64)  # position -> point
    nxt = np.empty(cap, dtype=np.int64)
    prv = np.empty(cap, dtype=np.int64)
    m = rs[1]
    for i in range(m):
        seq[i] = i
        nxt[i] = (i + 1) % m
    fail = np.empty((0, 3), dtype=np.int64)
    if nr > 1:
        # holes by their rightmost point, furthest first
        right = np.empty(nr - 1)
        at = np.empty(nr - 1, dtype=np.int64)
        for h in range(1, nr):
            k = rs[h]
            for i in range(rs[h], rs[h + 1]):
                if X[i, 0] > X[k, 0] or (X[i, 0] == X[k, 0] and X[i, 1] < X[k, 1]):
                    k = i
            right[h - 1] = -X[k, 0]
            at[h - 1] = k
        for o in np.argsort(right, kind="mergesort"):
            h = o + 1
            k = at[o]
            hx, hy = X[k, 0], X[k, 1]
            t = _bridge_target(X, seq, nxt, 0, hx, hy)
            if t < 0 or _bridge_crosses(X, seq, nxt, 0, hx, hy, X[seq[t], 0],
                                        X[seq[t], 1]):
                return fail, False
            # t -> k, the hole in its order back to k, a copy of k, a copy of t, on
            after = nxt[t]
            L = rs[h + 1] - rs[h]
            prev = t
            for j in range(L + 1):
                i = rs[h] + (k - rs[h] + j) % L
                seq[m] = i
                nxt[prev] = m
                prev = m
                m += 1
            seq[m] = seq[t]
            nxt[prev] = m
            nxt[m] = after
            m += 1
    # the ring in order from position 0
    x = np.empty(m)
    y = np.empty(m)
    canon = np.empty(m, dtype=np.int64)
    p = 0
    for j in range(m):
        canon[j] = seq[p]
        x[j] = X[seq[p], 0]
        y[j] = X[seq[p], 1]
        p = nxt[p]
    tri = np.empty((m, 3), dtype=np.int64)
    nt, ok = _ear_clip(x, y, m, tri, nxt[:m], prv[:m])
    if not ok:
        return fail, False
    out = np.empty((nt, 3), dtype=np.int64)
    got = 0.0
    for t in range(nt):
        for c in range(3):
            out[t, c] = canon[tri[t, c]]
        got += _orient(x[tri[t, 0]], y[tri[t, 0]], x[tri[t, 1]], y[tri[t, 1]],
                       x[tri[t, 2]], y[tri[t, 2]])
    want = 0.0
    for r in range(nr):
        for i in range(rs[r], rs[r + 1]):
            j = i + 1 if i + 1 < rs[r + 1] else rs[r]
            want += X[i, 0] * X[j, 1] - X[j, 0] * X[i, 1]
    if abs(got - want) > 1e-9 * abs(want):
        return fail, False
    _flip_to_delaunay(X[:, 0].copy(), X[:, 1].copy(), ring_of, rs, out, nt)
    return out, True


@jit_exact
def emit_triangles(out, owner, nout, x, y, tri, nt, who):
    """The triangles ``tri[:nt]`` (corner indices into ``x, y``) appended to ``out`` (k,
    3, 2) at ``nout``, ``owner`` ``who`` for each (both grown as needed): ``(out, owner,
    nout)``."""
    out = _grow(out, nout + nt)
    owner = _grow(owner, nout + nt)
    for t in range(nt):
        for v in range(3):
            out[nout, v, 0] = x[tri[t, v]]
            out[nout, v, 1] = y[tri[t, v]]
        owner[nout] = who
        nout += 1
    return out, owner, nout


@jit_exact
def triangulate_polygons(P, rstart, first, last, small):
    """:func:`triangulate_polygon` of many valid polygons (each one shell and holes
    inside it, in either orientation): ring ``r`` is ``P[rstart[r]:rstart[r+1]]`` (its
    last point may repeat the first), polygon ``j`` the rings ``first[j]:last[j]``, its
    shell first.  Polygons of more than ``small`` points are not taken (flipping
    scans every pair of triangles).  ``(tri (t, 3, 2) counter-clockwise, polygon (t,) of
    each, taken (n,) bool)``."""
    n = first.shape[0]
    out = np.empty((16, 3, 2))
    owner = np.empty(16, dtype=np.int64)
    taken = np.zeros(n, dtype=np.bool_)
    nout = 0
    for j in range(n):
        r0 = first[j]
        r1 = last[j]
        m = 0
        for r in range(r0, r1):
            k = rstart[r + 1] - rstart[r]
            if k > 1 and P[rstart[r + 1] - 1, 0] == P[rstart[r], 0] and \
                    P[rstart[r + 1] - 1, 1] == P[rstart[r], 1]:
                k -= 1
            m += k
        if m > small:
            continue
        X = np.empty((m, 2))
        rs = np.empty(r1 - r0 + 1, dtype=np.int64)
        rs[0] = 0
        w = 0
        for r in range(r0, r1):
            a = rstart[r]
            k = rstart[r + 1] - a
            if k > 1 and P[a + k - 1, 0] == P[a, 0] and P[a + k - 1, 1] == P[a, 1]:
                k -= 1
            s = 0.0
            for i in range(k):
                i1 = i + 1 if i + 1 < k else 0
                s += P[a + i, 0] * P[a + i1, 1] - P[a + i1, 0] * P[a + i, 1]
            # the shell counter-clockwise, the holes clockwise
            fwd = (s > 0.0) == (r == r0)
            for i in range(k):
                X[w + i] = P[a + i] if fwd else P[a + k - 1 - i]
            w += k
            rs[r - r0 + 1] = w
        tri, ok = triangulate_polygon(X, rs)
        if not ok:
            continue
        taken[j] = True
        out, owner, nout = emit_triangles(out, owner, nout, X[:, 0], X[:, 1], tri,
                                          tri.shape[0], j)
    return out[:nout], owner[:nout], taken
