"""Cut cells of a trimmed grid clipped and triangulated in one compiled call.

Each axis-aligned cell is clipped to the region that closed UV polylines bound by the
even-odd rule, and every piece is triangulated by the constrained Delaunay rule:

* the rings are walked so that the region lies on their left
  (:func:`geomkit._kernels.tess_rings.ring_directions`: the sign of a ring's area and
  its nesting depth), and each ring's runs inside the
  closed cell become chains from an entry to an exit point on the cell's edge;
* the pieces are the cycles chain, cell edge (its corners in turn), next chain by the
  entry's place along the edge counter-clockwise (Weiler-Atherton with a rectangle);
* each piece is triangulated by the constrained Delaunay rule
  (:mod:`geomkit._kernels.tess_cdt`).

A cell no ring runs through (rings that touch it at most) is wholly in or out, by the
even-odd rule at its centre.  A cell the walk cannot take surely is left to the
caller (its status says why): a ring wholly inside the closed cell, two chain ends at
one point of the edge, pieces whose edges meet other than at their shared corners
(rings that cross or touch, spurs), or a piece with no ear (rounding).  Crossing
points are computed from the segment in the ring's walking order and the cell edge's
exact coordinate, so two cells sharing an edge get the same point.
"""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit_exact, jit_inline
from .tess_cdt import (_ear_clip, _flip_to_delaunay, _grow, _orient, _segments_meet,
                       emit_triangles, triangulate_polygon)
from .tess_rings import _even_odd

# a cell's status: taken, or left to the caller and why
CLIP_DONE = 0
CLIP_RING_INSIDE = 1  # a hole with no vertex outside the cell touches its edge
CLIP_WALK = 2  # two chain ends at one point of the edge, or the walk meets a chain twice
CLIP_ORIENTATION = 3  # a piece turns clockwise
CLIP_TOUCH = 4  # the pieces' edges meet other than at consecutive corners
CLIP_NO_EAR = 5  # ear clipping found no ear (rounding)


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


@jit_exact
def _chains(P, starts, dirs, bbox, u0, u1, v0, v1, pts, cs, ce, sin_, sout, inner):
    """The chains of every ring in the closed cell: points in ``pts``, chain ``c`` is
    ``pts[cs[c]:ce[c]]`` from its entry (place ``sin_[c]`` along the edge) to its exit
    (``sout[c]``); the rings without a vertex outside the cell in ``inner``.
    ``(n_chains, n_inner, n_points, pts, ok)``; not ok when such a ring is a hole (turns
    clockwise as walked) that touches the cell's edge."""
    nc = 0
    ni = 0
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
        if k0 < 0:  # no vertex outside: an island, or a hole unless it touches the edge
            touch = False
            a2 = 0.0
            for i in range(m):
                q = _vertex(P, s, m, d, i)
                q1 = _vertex(P, s, m, d, i + 1)
                a2 += q[0] * q1[1] - q1[0] * q[1]
                if not (u0 < q[0] < u1 and v0 < q[1] < v1):
                    touch = True
            if touch and a2 <= 0.0:
                return nc, ni, npt, pts, False
            inner[ni] = r
            ni += 1
            continue
        open_ = False
        first = 0
        for j in range(m):
            a = _vertex(P, s, m, d, k0 + j)
            b = _vertex(P, s, m, d, k0 + j + 1)
            ax, ay, bx, by = a[0], a[1], b[0], b[1]
            b_in = _inside(bx, by, u0, u1, v0, v1)
            if not open_:
                if ((ax < u0 and bx < u0) or (ax > u1 and bx > u1) or (ay < v0 and by < v0)
                        or (ay > v1 and by > v1)):
                    continue  # both ends past one edge line: it misses the cell (or
                    # touches it after rounding, which makes no chain either)
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
    return nc, ni, npt, pts, True


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


@jit_exact
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


@jit_exact
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


@jit_exact
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
def _holds(poly, a0, a1, px, py):
    """Whether the open ring ``poly[a0:a1]`` holds (px, py) (ray crossings towards +u)."""
    inside = False
    for i in range(a0, a1):
        j = i + 1 if i + 1 < a1 else a0
        y1 = poly[i, 1]
        y2 = poly[j, 1]
        if (y1 > py) != (y2 > py):
            x = poly[i, 0] + (py - y1) * (poly[j, 0] - poly[i, 0]) / (y2 - y1)
            if px < x:
                inside = not inside
    return inside


@jit_inline
def _open_area2(poly, a0, a1):
    s = 0.0
    for i in range(a0, a1):
        j = i + 1 if i + 1 < a1 else a0
        s += poly[i, 0] * poly[j, 1] - poly[j, 0] * poly[i, 1]
    return s


@jit_exact
def _triangulate_simple(poly, a0, n, x, y, tri, nxt, prv, zero, rs):
    """:func:`geomkit._kernels.tess_cdt.triangulate_polygon` of the simple piece
    ``poly[a0:a0+n]`` in the caller's scratch arrays (of at least ``n`` rows; ``zero``
    zeros, ``rs`` two): ``(count, ok)``, triangles ``tri[:count]`` into ``x, y``."""
    for i in range(n):
        x[i] = poly[a0 + i, 0]
        y[i] = poly[a0 + i, 1]
    nt, ok = _ear_clip(x, y, n, tri, nxt, prv)
    if ok:
        rs[1] = n
        _flip_to_delaunay(x, y, zero, rs, tri, nt)
    return nt, ok


@jit_exact
def clip_cells(cells, P, starts, dirs):
    """The axis-aligned cells ``cells`` (n, 4) ``u0, u1, v0, v1`` clipped to the even-odd
    region of the closed rings ``P[starts[i]:starts[i+1]]`` (walked in ``dirs``, see
    :func:`geomkit._kernels.tess_rings.ring_directions`) and triangulated: ``(tri (t, 3,
    2) counter-clockwise, cell (t,) of each, status (n,), area (n,))``: status
    :data:`CLIP_DONE` with the pieces' area, or why the cell is left to the caller (its
    triangles are not in ``tri``).  Rings wholly inside a cell are its islands (pieces
    of their own) and holes (in the smallest piece holding them)."""
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
    inner = np.empty(nr, dtype=np.int64)
    poly = np.empty((64, 2))
    pstart = np.empty(nseg + nr + 2, dtype=np.int64)
    host = np.empty(nseg + nr + 1, dtype=np.int64)
    parea = np.empty(nseg + nr + 1)
    out = np.empty((16 * cells.shape[0] + 16, 3, 2))
    owner = np.empty(out.shape[0], dtype=np.int64)
    status = np.full(cells.shape[0], CLIP_DONE, dtype=np.int8)
    area = np.zeros(cells.shape[0])
    cap = 64
    sx = np.empty(cap)
    sy = np.empty(cap)
    stri = np.empty((cap, 3), dtype=np.int64)
    snxt = np.empty(cap, dtype=np.int64)
    sprv = np.empty(cap, dtype=np.int64)
    szero = np.zeros(cap, dtype=np.int64)
    srs = np.zeros(2, dtype=np.int64)
    nout = 0
    for c in range(cells.shape[0]):
        u0, u1, v0, v1 = cells[c, 0], cells[c, 1], cells[c, 2], cells[c, 3]
        nc, ni, npt, pts, ok = _chains(P, starts, dirs, bbox, u0, u1, v0, v1, pts, cs, ce,
                                       sin_, sout, inner)
        if not ok:
            status[c] = CLIP_RING_INSIDE
            continue
        if nc == 0:  # no ring runs through the cell's edge: all of it is in or out
            if ni == 0:
                inside = _even_odd(P, starts, 0.5 * (u0 + u1), 0.5 * (v0 + v1))
            else:  # the centre may be in a ring inside: ask at a corner
                inside = _even_odd(P, starts, u0, v0)
            npiece = 0
            if inside:
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
            s = _open_area2(poly, a0, a1)
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
            parea[keep] = 0.5 * s
            k += a1 - a0
            keep += 1
        if k < 0:
            status[c] = CLIP_ORIENTATION
            continue
        # the rings inside, as walked, after the pieces: islands turn counter-clockwise
        for j in range(ni):
            r = inner[j]
            m = starts[r + 1] - starts[r] - 1
            poly = _grow(poly, k + m)
            for i in range(m):
                q = _vertex(P, starts[r], m, dirs[r], i)
                poly[k + i, 0] = q[0]
                poly[k + i, 1] = q[1]
            pstart[keep + j] = k
            parea[keep + j] = 0.5 * _open_area2(poly, k, k + m)
            k += m
        pstart[keep + ni] = k
        if not _simple(poly, pstart, keep + ni):
            status[c] = CLIP_TOUCH
            continue
        # each hole in the smallest piece (islands included) that holds it
        for j in range(keep + ni):
            host[j] = -1
        for j in range(keep, keep + ni):
            if parea[j] < 0.0:
                best = np.inf
                for p in range(keep + ni):
                    if parea[p] > 0.0 and parea[p] < best and _holds(
                            poly, pstart[p], pstart[p + 1], poly[pstart[j], 0],
                            poly[pstart[j], 1]):
                        best = parea[p]
                        host[j] = p
                if host[j] < 0:
                    ok = False
        if not ok:
            status[c] = CLIP_ORIENTATION
            continue
        start = nout
        total = 0.0
        for p in range(keep + ni):
            if parea[p] <= 0.0:
                continue
            # the piece and its holes: rings of one point array
            n = pstart[p + 1] - pstart[p]
            nh = 0
            for j in range(keep, keep + ni):
                if host[j] == p:
                    n += pstart[j + 1] - pstart[j]
                    nh += 1
            if nh == 0:  # a simple piece: scratch arrays, no bridging
                if n > sx.shape[0]:
                    sx = np.empty(2 * n)
                    sy = np.empty(2 * n)
                    stri = np.empty((2 * n, 3), dtype=np.int64)
                    snxt = np.empty(2 * n, dtype=np.int64)
                    sprv = np.empty(2 * n, dtype=np.int64)
                    szero = np.zeros(2 * n, dtype=np.int64)
                nt, ok = _triangulate_simple(poly, pstart[p], n, sx, sy, stri, snxt, sprv,
                                             szero, srs)
                if not ok:
                    break
                total += parea[p]
                out, owner, nout = emit_triangles(out, owner, nout, sx, sy, stri, nt, c)
                continue
            X = np.empty((n, 2))
            rs = np.empty(nh + 2, dtype=np.int64)
            rs[0] = 0
            w = 0
            for i in range(pstart[p], pstart[p + 1]):
                X[w] = poly[i]
                w += 1
            rs[1] = w
            h = 1
            total += parea[p]
            for j in range(keep, keep + ni):
                if host[j] == p:
                    for i in range(pstart[j], pstart[j + 1]):
                        X[w] = poly[i]
                        w += 1
                    h += 1
                    rs[h] = w
                    total += parea[j]
            tri, ok = triangulate_polygon(X, rs)
            if not ok:
                break
            out, owner, nout = emit_triangles(out, owner, nout, X[:, 0], X[:, 1], tri,
                                              tri.shape[0], c)
        if not ok:
            nout = start
            status[c] = CLIP_NO_EAR
            continue
        area[c] = total
        status[c] = CLIP_DONE
    return out[:nout], owner[:nout], status, area
