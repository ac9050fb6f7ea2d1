"""Cut cells of a trimmed grid clipped and triangulated in one compiled call.

Each axis-aligned cell is clipped to the region that closed UV polylines bound by the
even-odd rule, and every piece is triangulated by the constrained Delaunay rule:

* the rings are walked so that the region lies on their left (:func:`ring_directions`:
  the sign of a ring's area and its nesting depth), and each ring's runs inside the
  closed cell become chains from an entry to an exit point on the cell's edge;
* the pieces are the cycles chain, cell edge (its corners in turn), next chain by the
  entry's place along the edge counter-clockwise (Weiler-Atherton with a rectangle);
* each piece is ear-clipped, then its diagonals are flipped until every one is
  locally Delaunay: with the piece's edges kept, that is the constrained Delaunay
  triangulation (as GEOS's ``constrained_delaunay_triangles`` makes it: ear clipping
  then flips; ties between cocircular points may be broken the other way).

A cell no ring runs through (rings that touch it at most) is wholly in or out, by the
even-odd rule at its centre.  A cell the walk cannot take surely is left to the
caller (its status says why): a ring wholly inside the closed cell, two chain ends at
one point of the edge, pieces whose edges meet other than at their shared corners
(rings that cross or touch, spurs), or a piece with no ear (rounding).  Crossing points are
computed from the segment in the ring's walking order and the cell edge's exact
coordinate, so two cells sharing an edge get the same point.
"""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit, jit_inline

# a cell's status: taken, or left to the caller and why
CLIP_DONE = 0
CLIP_RING_INSIDE = 1  # a ring reaches the cell with no vertex outside it
CLIP_WALK = 2  # two chain ends at one point of the edge, or the walk meets a chain twice
CLIP_ORIENTATION = 3  # a piece turns clockwise
CLIP_TOUCH = 4  # the pieces' edges meet other than at consecutive corners
CLIP_NO_EAR = 5  # ear clipping found no ear (rounding)
# diagonals flip only when the fourth point is inside the circle by more than this
# fraction of the incircle determinant's magnitude: cocircular corners stay as made
INCIRCLE_REL = 1e-12
# a vertex where the ring turns back within this angle (radians) is a spur's tip
SPUR_REL = 1e-12
# small loops are sought between edges at most this many edges apart
LOOP_SPAN = 4


@jit_inline
def _ring_holds(P, a, b, px, py):
    """Whether the closed ring ``P[a:b]`` holds (px, py): an odd count of its edges
    crossing the ray from it towards +u."""
    inside = False
    for k in range(a, b - 1):
        y1 = P[k, 1]
        y2 = P[k + 1, 1]
        if (y1 > py) != (y2 > py):
            x = P[k, 0] + (py - y1) * (P[k + 1, 0] - P[k, 0]) / (y2 - y1)
            if px < x:
                inside = not inside
    return inside


@jit
def ring_directions(P, starts):
    """(r,) +1 where closed ring ``P[starts[i]:starts[i+1]]`` (last point = first) has the
    even-odd region on its left as stored, -1 where it must be walked backwards: a
    ring nested in an even number of others bounds the region from outside
    (counter-clockwise), in an odd number from inside (clockwise).  Nesting by the
    ring's first point against every other ring."""
    nr = starts.shape[0] - 1
    out = np.empty(nr, dtype=np.int64)
    for i in range(nr):
        a = 0.0
        for k in range(starts[i], starts[i + 1] - 1):
            a += P[k, 0] * P[k + 1, 1] - P[k + 1, 0] * P[k, 1]
        px = P[starts[i], 0]
        py = P[starts[i], 1]
        depth = 0
        for j in range(nr):
            if j != i and _ring_holds(P, starts[j], starts[j + 1], px, py):
                depth += 1
        out[i] = 1 if (a > 0.0) == (depth % 2 == 0) else -1
    return out


@jit
def _drop_spur(Q, k):
    """One spur tip or repeated vertex of the cyclic ring ``Q[:k]`` removed: the new
    count (``k`` when there is none)."""
    for j in range(k):
        a = (j - 1) % k
        c = (j + 1) % k
        ax = Q[j, 0] - Q[a, 0]
        ay = Q[j, 1] - Q[a, 1]
        bx = Q[c, 0] - Q[j, 0]
        by = Q[c, 1] - Q[j, 1]
        same = ax == 0.0 and ay == 0.0
        fold = ax * bx + ay * by < 0.0 and abs(ax * by - ay * bx) <= SPUR_REL * np.sqrt(
            (ax * ax + ay * ay) * (bx * bx + by * by))
        if same or fold:
            for t in range(j, k - 1):
                Q[t] = Q[t + 1]
            return k - 1
    return k


@jit
def _drop_small_loop(Q, k, tiny, buf):
    """One small loop of the cyclic ring ``Q[:k]`` cut off: where edge ``i`` properly
    crosses edge ``i + d`` (``2 <= d <= LOOP_SPAN``) and the loop between them encloses
    at most ``tiny``, the vertices between become the crossing point.  The new count."""
    for i in range(k):
        ax, ay = Q[i, 0], Q[i, 1]
        bx, by = Q[(i + 1) % k, 0], Q[(i + 1) % k, 1]
        for d in range(2, min(LOOP_SPAN, k - 2) + 1):
            j = (i + d) % k
            cx, cy = Q[j, 0], Q[j, 1]
            ex, ey = Q[(j + 1) % k, 0], Q[(j + 1) % k, 1]
            d1 = _orient(cx, cy, ex, ey, ax, ay)
            d2 = _orient(cx, cy, ex, ey, bx, by)
            d3 = _orient(ax, ay, bx, by, cx, cy)
            d4 = _orient(ax, ay, bx, by, ex, ey)
            if not ((d1 > 0.0) != (d2 > 0.0) and d1 != 0.0 and d2 != 0.0
                    and (d3 > 0.0) != (d4 > 0.0) and d3 != 0.0 and d4 != 0.0):
                continue
            t = d1 / (d1 - d2)
            x = ax + t * (bx - ax)
            y = ay + t * (by - ay)
            s = 0.0  # the loop X, Q[i+1], ..., Q[j]
            px, py = x, y
            for e in range(1, d + 1):
                qx, qy = Q[(i + e) % k, 0], Q[(i + e) % k, 1]
                s += px * qy - qx * py
                px, py = qx, qy
            s += px * y - x * py
            if abs(0.5 * s) > tiny:
                continue
            m = 0
            for e in range(k - d):  # Q[j+1], ..., Q[i], then X
                buf[m] = Q[(j + 1 + e) % k]
                m += 1
            buf[m, 0] = x
            buf[m, 1] = y
            m += 1
            for e in range(m):
                Q[e] = buf[e]
            return m
    return k


@jit
def clean_rings(P, starts, tiny):
    """The closed rings ``P[starts[i]:starts[i+1]]`` without their spurs and small loops,
    as GEOS's valid form of the region has them: a vertex where the ring turns straight
    back (its two edges opposed, their cross product within :data:`SPUR_REL` of the
    product of their lengths) goes, so does a vertex equal to the one before it, and a
    loop of at most ``tiny`` area closed by two edges that cross is cut at the crossing;
    repeated until none is left; a ring left with fewer than three vertices goes.  Trim
    pieces overshoot or overlap where they join (by 1e-9 to 1e-7 of the domain): the
    region changes by at most ``tiny`` a loop.  ``(P, starts)``, new arrays."""
    nr = starts.shape[0] - 1
    out = np.empty_like(P)
    ostarts = np.empty_like(starts)
    ostarts[0] = 0
    Q = np.empty_like(P)
    buf = np.empty_like(P)
    n = 0
    nk = 0
    for r in range(nr):
        k = starts[r + 1] - starts[r] - 1  # distinct vertices (the last repeats the first)
        for i in range(k):
            Q[i] = P[starts[r] + i]
        while k >= 3:
            k2 = _drop_spur(Q, k)
            if k2 == k and k >= 5:
                k2 = _drop_small_loop(Q, k, tiny, buf)
            if k2 == k:
                break
            k = k2
        if k < 3:
            continue  # nothing but spurs: no area, no ring
        for j in range(k):
            out[n] = Q[j]
            n += 1
        out[n] = Q[0]
        n += 1
        nk += 1
        ostarts[nk] = n
    return out[:n], ostarts[:nk + 1]


@jit
def _even_odd(P, starts, px, py):
    """Whether (px, py) is inside the region the closed rings bound (even-odd rule)."""
    inside = False
    for r in range(starts.shape[0] - 1):
        if _ring_holds(P, starts[r], starts[r + 1], px, py):
            inside = not inside
    return inside


@jit_inline
def _vertex(P, s, m, d, i):
    """Vertex ``i`` (mod ``m``) of the ring starting at ``s`` with ``m`` distinct
    vertices, walked forwards (``d`` = 1) or backwards."""
    i = i % m
    return P[s + i] if d > 0 else P[s + (m - i) % m]


@jit_inline
def _inside(x, y, u0, u1, v0, v1):
    return u0 <= x <= u1 and v0 <= y <= v1


@jit_inline
def _clip_t(ax, ay, bx, by, u0, u1, v0, v1):
    """Liang-Barsky: ``(t0, t1, e0, e1)``, the parameters where the segment a-b enters
    and leaves the closed box and the edge of each (0 u0, 1 u1, 2 v0, 3 v1; -1 at the
    segment's own end); ``t0 > t1`` when it misses the box."""
    t0 = 0.0
    t1 = 1.0
    e0 = -1
    e1 = -1
    dx = bx - ax
    dy = by - ay
    for k in range(4):
        if k == 0:
            pk, qk = -dx, ax - u0
        elif k == 1:
            pk, qk = dx, u1 - ax
        elif k == 2:
            pk, qk = -dy, ay - v0
        else:
            pk, qk = dy, v1 - ay
        if pk == 0.0:
            if qk < 0.0:
                return 1.0, 0.0, -1, -1
        else:
            r = qk / pk
            if pk < 0.0:
                if r > t0:
                    t0 = r
                    e0 = k
            else:
                if r < t1:
                    t1 = r
                    e1 = k
    return t0, t1, e0, e1


@jit_inline
def _on_edge(ax, ay, bx, by, t, e, u0, u1, v0, v1):
    """The point at ``t`` of the segment a-b on cell edge ``e``: that edge's coordinate
    exactly, the other one clamped to the cell; the segment's end at ``t`` 0 or 1."""
    if t <= 0.0:
        return ax, ay
    if t >= 1.0:
        return bx, by
    if e == 0 or e == 1:
        x = u0 if e == 0 else u1
        y = min(max(ay + t * (by - ay), v0), v1)
    else:
        y = v0 if e == 2 else v1
        x = min(max(ax + t * (bx - ax), u0), u1)
    return x, y


@jit_inline
def _perimeter(x, y, u0, u1, v0, v1):
    """Place of a point of the cell's edge along it counter-clockwise from (u0, v0):
    [0, 1) bottom, [1, 2) right, [2, 3) top, [3, 4) left."""
    if y == v0 and x < u1:
        return (x - u0) / (u1 - u0)
    if x == u1 and y < v1:
        return 1.0 + (y - v0) / (v1 - v0)
    if y == v1 and x > u0:
        return 2.0 + (u1 - x) / (u1 - u0)
    return 3.0 + (v1 - y) / (v1 - v0)


@jit_inline
def _orient(ax, ay, bx, by, cx, cy):
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


@jit_inline
def _segments_meet(ax, ay, bx, by, cx, cy, dx, dy):
    """Whether the closed segments a-b and c-d share a point."""
    d1 = _orient(cx, cy, dx, dy, ax, ay)
    d2 = _orient(cx, cy, dx, dy, bx, by)
    d3 = _orient(ax, ay, bx, by, cx, cy)
    d4 = _orient(ax, ay, bx, by, dx, dy)
    if ((d1 > 0.0 and d2 < 0.0) or (d1 < 0.0 and d2 > 0.0)) and \
            ((d3 > 0.0 and d4 < 0.0) or (d3 < 0.0 and d4 > 0.0)):
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


@jit
def _grow(a, n):
    """``a`` with room for at least ``n`` rows (doubled)."""
    if n <= a.shape[0]:
        return a
    shape = (max(n, 2 * a.shape[0]),) + a.shape[1:]
    b = np.empty(shape, dtype=a.dtype)
    b[:a.shape[0]] = a
    return b


@jit
def _chains(P, starts, dirs, bbox, u0, u1, v0, v1, pts, cs, ce, sin_, sout):
    """The chains of every ring in the closed cell: points in ``pts``, chain ``c`` is
    ``pts[cs[c]:ce[c]]`` from its entry (place ``sin_[c]`` along the edge) to its exit
    (``sout[c]``).  ``(n_chains, n_points, pts, ok)``; not ok when a ring that reaches
    the cell has no vertex strictly outside it."""
    nc = 0
    npt = 0
    for r in range(starts.shape[0] - 1):
        if bbox[r, 1] < u0 or bbox[r, 0] > u1 or bbox[r, 3] < v0 or bbox[r, 2] > v1:
            continue
        s = starts[r]
        m = starts[r + 1] - s - 1
        d = dirs[r]
        k0 = -1
        for i in range(m):
            q = _vertex(P, s, m, d, i)
            if not _inside(q[0], q[1], u0, u1, v0, v1):
                k0 = i
                break
        if k0 < 0:
            return nc, npt, pts, False
        open_ = False
        first = 0
        for j in range(m):
            a = _vertex(P, s, m, d, k0 + j)
            b = _vertex(P, s, m, d, k0 + j + 1)
            ax, ay, bx, by = a[0], a[1], b[0], b[1]
            b_in = _inside(bx, by, u0, u1, v0, v1)
            if not open_:
                t0, t1, e0, e1 = _clip_t(ax, ay, bx, by, u0, u1, v0, v1)
                if t0 > t1:
                    continue
                x0, y0 = _on_edge(ax, ay, bx, by, t0, e0, u0, u1, v0, v1)
                pts = _grow(pts, npt + 2)
                first = npt
                pts[npt, 0] = x0
                pts[npt, 1] = y0
                npt += 1
                if b_in:
                    if bx != x0 or by != y0:
                        pts[npt, 0] = bx
                        pts[npt, 1] = by
                        npt += 1
                    open_ = True
                    continue
                x1, y1 = _on_edge(ax, ay, bx, by, t1, e1, u0, u1, v0, v1)
                if x1 == x0 and y1 == y0:
                    npt = first  # a touch: no chain
                    continue
                pts[npt, 0] = x1
                pts[npt, 1] = y1
                npt += 1
            else:
                pts = _grow(pts, npt + 1)
                if b_in:
                    if bx != pts[npt - 1, 0] or by != pts[npt - 1, 1]:
                        pts[npt, 0] = bx
                        pts[npt, 1] = by
                        npt += 1
                    continue
                t0, t1, e0, e1 = _clip_t(ax, ay, bx, by, u0, u1, v0, v1)
                x1, y1 = _on_edge(ax, ay, bx, by, t1, e1, u0, u1, v0, v1)
                if x1 != pts[npt - 1, 0] or y1 != pts[npt - 1, 1]:
                    pts[npt, 0] = x1
                    pts[npt, 1] = y1
                    npt += 1
                open_ = False
                if npt - first < 2:
                    npt = first  # entered and left at one point
                    continue
            # a chain from pts[first] to pts[npt - 1]
            cs[nc] = first
            ce[nc] = npt
            sin_[nc] = _perimeter(pts[first, 0], pts[first, 1], u0, u1, v0, v1)
            sout[nc] = _perimeter(pts[npt - 1, 0], pts[npt - 1, 1], u0, u1, v0, v1)
            nc += 1
    return nc, npt, pts, True


@jit_inline
def _corner(c, u0, u1, v0, v1):
    c = c % 4
    if c == 0:
        return u0, v0
    if c == 1:
        return u1, v0
    if c == 2:
        return u1, v1
    return u0, v1


@jit
def _pieces(pts, nc, cs, ce, sin_, sout, u0, u1, v0, v1, poly, pstart):
    """The cell's pieces walked from its chains: piece ``k`` is
    ``poly[pstart[k]:pstart[k+1]]`` (open ring, counter-clockwise).  ``(n_pieces,
    poly, ok)``; not ok when two chain ends share a place or the walk meets a chain
    twice."""
    ends = np.empty(2 * nc)
    ends[:nc] = sin_[:nc]
    ends[nc:] = sout[:nc]
    ends.sort()
    for i in range(2 * nc - 1):
        if ends[i] == ends[i + 1]:
            return 0, poly, False
    used = np.zeros(nc, dtype=np.bool_)
    npiece = 0
    n = 0
    for c0 in range(nc):
        if used[c0]:
            continue
        pstart[npiece] = n
        c = c0
        while True:
            used[c] = True
            poly = _grow(poly, n + (ce[c] - cs[c]) + 4)
            for i in range(cs[c], ce[c]):
                poly[n, 0] = pts[i, 0]
                poly[n, 1] = pts[i, 1]
                n += 1
            s = sout[c]
            nxt = -1
            best = 8.0
            for j in range(nc):  # the first entry counter-clockwise after s
                e = sin_[j] if sin_[j] > s else sin_[j] + 4.0
                if e < best:
                    best = e
                    nxt = j
            k = int(np.floor(s)) + 1
            while k < best:
                x, y = _corner(k, u0, u1, v0, v1)
                poly[n, 0] = x
                poly[n, 1] = y
                n += 1
                k += 1
            if nxt == c0:
                break
            if used[nxt]:
                return 0, poly, False
            c = nxt
        npiece += 1
        pstart[npiece] = n
    return npiece, poly, True


@jit_inline
def _same_edge(ax, ay, bx, by, cx, cy, u0, u1, v0, v1):
    """Whether three points lie on one edge line of the cell."""
    return (ax == u0 and bx == u0 and cx == u0) or (ax == u1 and bx == u1 and cx == u1) \
        or (ay == v0 and by == v0 and cy == v0) or (ay == v1 and by == v1 and cy == v1)


@jit
def _drop_edge_runs(poly, a0, a1, u0, u1, v0, v1):
    """The piece ``poly[a0:a1]`` without the points inside a run along one edge line of
    the cell (a ring along the cell's edge: the edge is the piece's side, as the
    neighbour cell, outside the region there, does not use those points): its new end."""
    n = a1 - a0
    changed = True
    while changed and n > 3:
        changed = False
        for i in range(n):
            p = a0 + (i - 1) % n
            q = a0 + (i + 1) % n
            k = a0 + i
            if _same_edge(poly[p, 0], poly[p, 1], poly[k, 0], poly[k, 1], poly[q, 0],
                          poly[q, 1], u0, u1, v0, v1):
                for j in range(k, a0 + n - 1):
                    poly[j, 0] = poly[j + 1, 0]
                    poly[j, 1] = poly[j + 1, 1]
                n -= 1
                changed = True
                break
    return a0 + n


@jit
def _simple(poly, pstart, npiece):
    """Whether the pieces' edges meet only where consecutive edges of one piece share
    their corner (and fold neither back nor onto each other)."""
    for a in range(npiece):
        a0 = pstart[a]
        na = pstart[a + 1] - a0
        for i in range(na):
            i1 = (i + 1) % na
            ax, ay = poly[a0 + i, 0], poly[a0 + i, 1]
            bx, by = poly[a0 + i1, 0], poly[a0 + i1, 1]
            if ax == bx and ay == by:
                return False
            for b in range(a, npiece):
                b0 = pstart[b]
                nb = pstart[b + 1] - b0
                for j in range(i + 1 if b == a else 0, nb):
                    j1 = (j + 1) % nb
                    cx, cy = poly[b0 + j, 0], poly[b0 + j, 1]
                    dx, dy = poly[b0 + j1, 0], poly[b0 + j1, 1]
                    if b == a and (j == i1 or j1 == i):  # consecutive: one shared corner
                        o = _orient(ax, ay, bx, by, dx, dy) if j == i1 else \
                            _orient(cx, cy, dx, dy, bx, by)
                        if o == 0.0:
                            # collinear: fine when straight on, a fold when turned back
                            if j == i1:
                                w = (bx - ax) * (dx - bx) + (by - ay) * (dy - by)
                            else:
                                w = (dx - cx) * (bx - ax) + (dy - cy) * (by - ay)
                            if w <= 0.0:
                                return False
                        continue
                    if _segments_meet(ax, ay, bx, by, cx, cy, dx, dy):
                        return False
    return True


@jit_inline
def _in_closed_triangle(px, py, ax, ay, bx, by, cx, cy):
    return _orient(ax, ay, bx, by, px, py) >= 0.0 and _orient(bx, by, cx, cy, px, py) >= 0.0 \
        and _orient(cx, cy, ax, ay, px, py) >= 0.0


@jit
def _ear_clip(x, y, n, tri, nxt, prv):
    """Triangles (rows of corner indices, counter-clockwise) of the simple
    counter-clockwise polygon ``x, y`` (``n`` points): ``(count, ok)``.  An ear is a
    convex corner whose triangle holds no other remaining point (on its edges
    included)."""
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
                if _in_closed_triangle(x[r], y[r], x[p], y[p], x[i], y[i], x[q], y[q]):
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


@jit
def _flip_to_delaunay(x, y, n, tri, nt):
    """Diagonals of the ear-clipped polygon (``n`` points, triangles ``tri[:nt]``)
    flipped until each is locally Delaunay; the polygon's edges stay."""
    budget = 4 * nt * nt + 8
    changed = True
    while changed and budget > 0:
        changed = False
        for t in range(nt):
            for e in range(3):
                a = tri[t, e]
                b = tri[t, (e + 1) % 3]
                c = tri[t, (e + 2) % 3]
                if (b - a) % n == 1 or (a - b) % n == 1:
                    continue  # an edge of the polygon
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


@jit
def clip_cells(cells, P, starts, dirs):
    """The axis-aligned cells ``cells`` (n, 4) ``u0, u1, v0, v1`` clipped to the even-odd
    region of the closed rings ``P[starts[i]:starts[i+1]]`` (walked in ``dirs``, see
    :func:`ring_directions`) and triangulated: ``(tri (t, 3, 2) counter-clockwise, cell
    (t,) of each, status (n,), area (n,))``: status :data:`CLIP_DONE` with the pieces'
    area, or why the cell is left to the caller (its triangles are not in ``tri``)."""
    nr = starts.shape[0] - 1
    bbox = np.empty((nr, 4))
    for r in range(nr):
        bbox[r, 0] = bbox[r, 2] = np.inf
        bbox[r, 1] = bbox[r, 3] = -np.inf
        for k in range(starts[r], starts[r + 1]):
            bbox[r, 0] = min(bbox[r, 0], P[k, 0])
            bbox[r, 1] = max(bbox[r, 1], P[k, 0])
            bbox[r, 2] = min(bbox[r, 2], P[k, 1])
            bbox[r, 3] = max(bbox[r, 3], P[k, 1])
    nseg = P.shape[0]
    pts = np.empty((64, 2))
    cs = np.empty(nseg + 1, dtype=np.int64)
    ce = np.empty(nseg + 1, dtype=np.int64)
    sin_ = np.empty(nseg + 1)
    sout = np.empty(nseg + 1)
    poly = np.empty((64, 2))
    pstart = np.empty(nseg + 2, dtype=np.int64)
    out = np.empty((16 * cells.shape[0] + 16, 3, 2))
    owner = np.empty(out.shape[0], dtype=np.int64)
    status = np.full(cells.shape[0], CLIP_DONE, dtype=np.int8)
    area = np.zeros(cells.shape[0])
    tri = np.empty((64, 3), dtype=np.int64)
    nxt = np.empty(64, dtype=np.int64)
    prv = np.empty(64, dtype=np.int64)
    x = np.empty(64)
    y = np.empty(64)
    nout = 0
    for c in range(cells.shape[0]):
        u0, u1, v0, v1 = cells[c, 0], cells[c, 1], cells[c, 2], cells[c, 3]
        nc, npt, pts, ok = _chains(P, starts, dirs, bbox, u0, u1, v0, v1, pts, cs, ce,
                                   sin_, sout)
        if not ok:
            status[c] = CLIP_RING_INSIDE
            continue
        if nc == 0:  # rings at most touch the cell: all of it is in or out
            if not _even_odd(P, starts, 0.5 * (u0 + u1), 0.5 * (v0 + v1)):
                continue
            for k in range(4):
                poly[k, 0], poly[k, 1] = _corner(k, u0, u1, v0, v1)
            pstart[0] = 0
            pstart[1] = 4
            npiece = 1
        else:
            npiece, poly, ok = _pieces(pts, nc, cs, ce, sin_, sout, u0, u1, v0, v1, poly,
                                       pstart)
            if not ok:
                status[c] = CLIP_WALK
                continue
        # pieces lying on the cell's edge (a ring along it, the region outside) drop
        k = 0
        keep = 0
        for p in range(npiece):
            a0 = pstart[p]
            a1 = pstart[p + 1]
            on_edge = True
            for i in range(a0, a1):
                if not (poly[i, 0] == u0 or poly[i, 0] == u1 or poly[i, 1] == v0
                        or poly[i, 1] == v1):
                    on_edge = False
                    break
            s = 0.0
            for i in range(a0, a1):
                j = i + 1 if i + 1 < a1 else a0
                s += poly[i, 0] * poly[j, 1] - poly[j, 0] * poly[i, 1]
            if s <= 0.0:
                if on_edge and s > -1e-12 * (u1 - u0) * (v1 - v0):
                    continue
                k = -1
                break
            a1 = _drop_edge_runs(poly, a0, a1, u0, u1, v0, v1)
            for i in range(a0, a1):
                poly[k + i - a0, 0] = poly[i, 0]
                poly[k + i - a0, 1] = poly[i, 1]
            pstart[keep] = k
            k += a1 - a0
            keep += 1
            area[c] += 0.5 * s
        if k < 0:
            area[c] = 0.0
            status[c] = CLIP_ORIENTATION
            continue
        pstart[keep] = k
        if not _simple(poly, pstart, keep):
            area[c] = 0.0
            status[c] = CLIP_TOUCH
            continue
        start = nout
        ok = True
        for p in range(keep):
            a0 = pstart[p]
            n = pstart[p + 1] - a0
            if n > x.shape[0]:
                x = np.empty(2 * n)
                y = np.empty(2 * n)
                nxt = np.empty(2 * n, dtype=np.int64)
                prv = np.empty(2 * n, dtype=np.int64)
                tri = np.empty((2 * n, 3), dtype=np.int64)
            for i in range(n):
                x[i] = poly[a0 + i, 0]
                y[i] = poly[a0 + i, 1]
            nt, ok = _ear_clip(x, y, n, tri, nxt, prv)
            if not ok:
                break
            _flip_to_delaunay(x, y, n, tri, nt)
            out = _grow(out, nout + nt)
            owner = _grow(owner, nout + nt)
            for t in range(nt):
                for v in range(3):
                    out[nout, v, 0] = x[tri[t, v]]
                    out[nout, v, 1] = y[tri[t, v]]
                owner[nout] = c
                nout += 1
        if not ok:
            nout = start
            area[c] = 0.0
            status[c] = CLIP_NO_EAR
            continue
        status[c] = CLIP_DONE
    return out[:nout], owner[:nout], status, area
