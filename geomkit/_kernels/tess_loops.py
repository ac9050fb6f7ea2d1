"""The closed trim loops of many faces in one call, and their mesh vertices.

Per face, :func:`.tess_trim.trim_polylines` makes the polylines of its trim pieces; here
they are joined into closed loops (each piece after a loop's first drops its first row,
which repeats the previous piece's last; the last row is set to the first, closing the
loop exactly: pieces join within the closure tolerance) and each loop's distance from
its face's domain rectangle is measured (:func:`.tess_trim.loop_rectangle_gap`).  The
Python route did this face by face with a dozen numpy calls each: on the trimmed planes
of a part (90 on a Pro/ENGINEER part) that glue cost more than the polylines.
"""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit, jit_exact, jit_inline
from .surface import surface_points_range
from .tess_trim import loop_rectangle_gap, trim_polylines


@jit
def _grow(a, n):
    """``a`` (m, k) with room for at least ``n`` rows (doubled), rows kept."""
    if n <= a.shape[0]:
        return a
    b = np.empty((max(n, 2 * a.shape[0]), a.shape[1]))
    b[:a.shape[0]] = a
    return b


@jit
def face_loops(CP, W, K, deg, cp_off, k_off, loop_first, face_piece, face_loop, Pw, pw_off,
               nets, U, u_off, V, v_off, domains, dense_spans, curve_tol, chord_tol, pair_tol,
               uv_chords, cross_knots):
    """The closed UV polylines of the trim loops of faces ``f`` (``len(face_piece) - 1``).

    Face ``f``: surface net ``Pw[pw_off[f]:pw_off[f+1]]`` rows of ``(x w, y w, z w, w)``
    (``nets[f] = (nu, nv, p, q)``, row-major), knots ``U[u_off[f]:u_off[f+1]]``,
    ``V[v_off[f]:v_off[f+1]]``, domain ``domains[f] = (u0, u1, v0, v1)``; trim pieces
    ``face_piece[f]:face_piece[f+1]`` (piece ``c``: degree ``deg[c]``, control points
    ``CP[cp_off[c]:cp_off[c+1]]`` with weights ``W``, knots ``K[k_off[c]:k_off[c+1]]``),
    loops ``face_loop[f]:face_loop[f+1]`` (loop ``l``: pieces
    ``loop_first[l]:loop_first[l+1]``).  The other arguments are
    :func:`.tess_trim.trim_polylines`'.

    Returns ``(pts (n, 2), start (L+1,), gaps (L, 2))``: loop ``l``'s closed polyline
    ``pts[start[l]:start[l+1]]`` and its :func:`.tess_trim.loop_rectangle_gap`."""
    nf = face_piece.shape[0] - 1
    nl = loop_first.shape[0] - 1
    start = np.zeros(nl + 1, dtype=np.int64)
    gaps = np.empty((nl, 2))
    pts = np.empty((64, 2))
    n = 0
    for f in range(nf):
        c0 = face_piece[f]
        c1 = face_piece[f + 1]
        nu = nets[f, 0]
        nv = nets[f, 1]
        Pf = np.ascontiguousarray(Pw[pw_off[f]:pw_off[f + 1]]).reshape((nu, nv, 4))
        Uf = U[u_off[f]:u_off[f + 1]]
        Vf = V[v_off[f]:v_off[f + 1]]
        u0 = domains[f, 0]
        u1 = domains[f, 1]
        v0 = domains[f, 2]
        v1 = domains[f, 3]
        counts = np.empty(c1 - c0, dtype=np.int64)
        rows = np.empty((8 * (k_off[c1] - k_off[c0]) + 64, 3))
        while True:
            m = trim_polylines(CP, W, K, deg[c0:c1], cp_off[c0:c1 + 1], k_off[c0:c1 + 1],
                               dense_spans, u0, v0, u1, v1, Pf, nets[f, 2], nets[f, 3], Uf,
                               Vf, curve_tol, chord_tol, pair_tol, uv_chords, cross_knots,
                               rows, counts, True)
            if m >= 0:
                break
            rows = np.empty((4 * rows.shape[0], 3))
        r = 0  # the face's rows, piece after piece
        for lp in range(face_loop[f], face_loop[f + 1]):
            a = n
            for c in range(loop_first[lp], loop_first[lp + 1]):
                k = counts[c - c0]
                skip = 0 if c == loop_first[lp] else 1
                pts = _grow(pts, n + k)
                for i in range(skip, k):
                    pts[n, 0] = rows[r + i, 1]
                    pts[n, 1] = rows[r + i, 2]
                    n += 1
                r += k
            if n > a:
                pts[n - 1, 0] = pts[a, 0]  # close exactly
                pts[n - 1, 1] = pts[a, 1]
            start[lp + 1] = n
            g, ga = loop_rectangle_gap(pts[a:n], u0, u1, v0, v1)
            gaps[lp, 0] = g
            gaps[lp, 1] = ga
    return pts[:n], start, gaps


@jit
def faces_points(Pw, pw_off, nets, U, u_off, V, v_off, uv, face_start):
    """``S_f(uv)`` (n, 3) of the rows ``face_start[f]:face_start[f+1]`` of ``uv`` on
    face ``f``'s surface (the flat nets of :func:`face_loops`), each point as
    :func:`.surface.surface_points_range` makes it."""
    out = np.empty((uv.shape[0], 3))
    for f in range(face_start.shape[0] - 1):
        a = face_start[f]
        b = face_start[f + 1]
        if b == a:
            continue
        Pf = np.ascontiguousarray(Pw[pw_off[f]:pw_off[f + 1]]).reshape(
            (nets[f, 0], nets[f, 1], 4))
        surface_points_range(a, b, Pf, nets[f, 2], nets[f, 3], U[u_off[f]:u_off[f + 1]],
                             V[v_off[f]:v_off[f + 1]], uv, out)
    return out


@jit
def _face_rings(f, start, face_loop, kept, rect, shell, out, sizes, r):
    """Face ``f``'s rings (see :func:`plane_rings`) as loop numbers into ``out``
    (-1: the domain rectangle) and their sizes into ``sizes``, from row ``r``: the
    next row, or -1 when a ring has fewer than 4 points."""
    if rect[f]:
        out[r] = -1
        sizes[r] = 5
        r += 1
    else:
        out[r] = shell[f]
        sizes[r] = start[shell[f] + 1] - start[shell[f]]
        r += 1
    for lp in range(face_loop[f], face_loop[f + 1]):
        if kept[lp] and (rect[f] or lp != shell[f]):
            out[r] = lp
            sizes[r] = start[lp + 1] - start[lp]
            r += 1
    for i in range(r):
        if sizes[i] < 4:
            return -1
    return r


@jit
def plane_rings(pts, start, face_loop, kept, rect, shell, domains):
    """The rings of each face's trimmed region as one polygon with holes, for shapely's
    vectorised constructors.  Face ``f`` (loops ``face_loop[f]:face_loop[f+1]``, loop
    ``l``'s closed polyline ``pts[start[l]:start[l+1]]``): when ``rect[f]``, the domain
    rectangle ``(u0, v0), (u1, v0), (u1, v1), (u0, v1), (u0, v0)`` of ``domains[f] =
    (u0, u1, v0, v1)`` then its loops with ``kept[l]``, in order; else loop ``shell[f]``
    then its other kept loops, in order.  A face with a ring of fewer than 4 points is
    left out.

    Returns ``(coords (n, 2), ring_size (R,), ring_face (R,), faces (F,))``: the kept
    faces' rings one after another, each ring's face as its rank in ``faces`` (the
    faces kept, ascending)."""
    nf = face_loop.shape[0] - 1
    most = 1
    for f in range(nf):
        most = max(most, face_loop[f + 1] - face_loop[f] + 1)
    ring = np.empty(most, dtype=np.int64)
    size = np.empty(most, dtype=np.int64)
    nr = 0
    npt = 0
    nk = 0
    ok = np.zeros(nf, dtype=np.bool_)
    for f in range(nf):
        r = _face_rings(f, start, face_loop, kept, rect, shell, ring, size, 0)
        if r < 0:
            continue
        ok[f] = True
        nk += 1
        nr += r
        for i in range(r):
            npt += size[i]
    coords = np.empty((npt, 2))
    ring_size = np.empty(nr, dtype=np.int64)
    ring_face = np.empty(nr, dtype=np.int64)
    faces = np.empty(nk, dtype=np.int64)
    k = 0
    q = 0
    n = 0
    for f in range(nf):
        if not ok[f]:
            continue
        r = _face_rings(f, start, face_loop, kept, rect, shell, ring, size, 0)
        faces[k] = f
        for i in range(r):
            ring_size[q] = size[i]
            ring_face[q] = k
            q += 1
            lp = ring[i]
            if lp < 0:  # (u0, v0), (u1, v0), (u1, v1), (u0, v1), (u0, v0)
                for c in range(5):
                    coords[n + c, 0] = domains[f, 1] if c == 1 or c == 2 else domains[f, 0]
                    coords[n + c, 1] = domains[f, 3] if c == 2 or c == 3 else domains[f, 2]
                n += 5
            else:
                for j in range(start[lp], start[lp + 1]):
                    coords[n, 0] = pts[j, 0]
                    coords[n, 1] = pts[j, 1]
                    n += 1
        k += 1
    return coords, ring_size, ring_face, faces


@jit
def loop_areas(pts, start):
    """``(area2 (L,), err (L,))``: ``|sum x_i y_(i+1) - sum x_(i+1) y_i|`` over each closed
    polyline ``pts[start[l]:start[l+1]]`` (twice its shoelace area; each sum in order)
    and a bound of the rounding error of that value computed in any order of the sums,
    the other's too (``4 (k + 2) 2^-53`` times the sum of the terms' magnitudes, twice
    the standard bound of a sum of ``k`` products)."""
    nl = start.shape[0] - 1
    area = np.empty(nl)
    err = np.empty(nl)
    for lp in range(nl):
        a = 0.0
        b = 0.0
        m = 0.0
        for i in range(start[lp], start[lp + 1] - 1):
            x = pts[i, 0] * pts[i + 1, 1]
            y = pts[i + 1, 0] * pts[i, 1]
            a += x
            b += y
            m += abs(x) + abs(y)
        area[lp] = abs(a - b)
        err[lp] = 4.0 * (start[lp + 1] - start[lp] + 2) * 2.0 ** -53 * m
    return area, err


@jit_inline
def _uv_less(us, vs, i, j):
    """Whether corner ``i`` comes before corner ``j`` by (u, v)."""
    return us[i] < us[j] or (us[i] == us[j] and vs[i] < vs[j])


@jit
def _sort_uv(us, vs, order, buf, k):
    """``order[:k]``: the indices ``0..k-1`` sorted by ``(us, vs)``, stably (equal corners
    keep their order, as numpy's lexsort): insertion-sorted runs of 8, then bottom-up
    merges through ``buf``."""
    for r in range(k):
        order[r] = r
    for lo in range(0, k, 8):
        for r in range(lo + 1, min(lo + 8, k)):
            x = order[r]
            q = r
            while q > lo and _uv_less(us, vs, x, order[q - 1]):
                order[q] = order[q - 1]
                q -= 1
            order[q] = x
    src = order
    dst = buf
    width = 8
    in_buf = False
    while width < k:
        for lo in range(0, k, 2 * width):
            mid = min(lo + width, k)
            hi = min(lo + 2 * width, k)
            i = lo
            j = mid
            for o in range(lo, hi):
                if j < hi and (i >= mid or _uv_less(us, vs, src[j], src[i])):
                    dst[o] = src[j]
                    j += 1
                else:
                    dst[o] = src[i]
                    i += 1
        src, dst = dst, src
        in_buf = not in_buf
        width *= 2
    if in_buf:
        order[:k] = buf[:k]


@jit_exact
def polygon_meshes(tri, idx, n):
    """Indexed meshes of triangles given by their corners, ``tri`` (T, 3, 2) of polygon
    ``idx`` (T,) (ascending, below ``n``): triangles of zero area dropped (twice the
    signed area ``a_u b_v - a_v b_u`` of the edges from the first corner, without
    contraction: numpy's values), the others counter-clockwise (a clockwise one's
    corners reversed), each polygon's distinct corners sorted by u, then v (a stable
    sort, as numpy's lexsort; equal corners merged into the first in that order).

    Returns ``(uv (N, 2), faces (M, 3), vstart (n+1,), tstart (n+1,))``: polygon ``j``'s
    vertices ``uv[vstart[j]:vstart[j+1]]`` and its triangles ``faces[tstart[j]:
    tstart[j+1]]``, indices into its own vertices."""
    T = tri.shape[0]
    corner = np.empty((3 * T, 2))  # the kept triangles' corners, in their order
    own = np.empty(T, dtype=np.int64)
    m = 0
    for t in range(T):
        a0 = tri[t, 1, 0] - tri[t, 0, 0]
        a1 = tri[t, 1, 1] - tri[t, 0, 1]
        b0 = tri[t, 2, 0] - tri[t, 0, 0]
        b1 = tri[t, 2, 1] - tri[t, 0, 1]
        area2 = a0 * b1 - a1 * b0
        if area2 == 0:
            continue
        for c in range(3):
            k = 2 - c if area2 < 0 else c
            corner[3 * m + c, 0] = tri[t, k, 0]
            corner[3 * m + c, 1] = tri[t, k, 1]
        own[m] = idx[t]
        m += 1
    uv = np.empty((3 * m, 2))
    faces = np.empty((m, 3), dtype=np.int64)
    vstart = np.zeros(n + 1, dtype=np.int64)
    tstart = np.zeros(n + 1, dtype=np.int64)
    order = np.empty(3 * m, dtype=np.int64)
    buf = np.empty(3 * m, dtype=np.int64)
    nv = 0
    t0 = 0
    for j in range(n):
        t1 = t0
        while t1 < m and own[t1] == j:
            t1 += 1
        vstart[j] = nv
        tstart[j] = t0
        if t1 > t0:
            us = corner[3 * t0:3 * t1, 0]
            vs = corner[3 * t0:3 * t1, 1]
            k = us.shape[0]
            _sort_uv(us, vs, order, buf, k)
            first = nv
            for r in range(k):
                i = order[r]
                if r == 0 or us[i] != uv[nv - 1, 0] or vs[i] != uv[nv - 1, 1]:
                    uv[nv, 0] = us[i]
                    uv[nv, 1] = vs[i]
                    nv += 1
                faces[t0 + i // 3, i % 3] = nv - 1 - first
        t0 = t1
    vstart[n] = nv
    tstart[n] = m
    return uv[:nv], faces, vstart, tstart
