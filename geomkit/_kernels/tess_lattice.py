"""Lattice triangulation kernels of the tessellation: the hanging-node rings and
triangles of quadtree cells whose corners are integer lattice points (split out of
:mod:`geomkit._kernels.tess`), the cells' classification against the trim
polylines (:func:`classify_cells`), and the grouped measure of a trimmed grid's
triangles (:func:`group_deviation`)."""

from __future__ import annotations

import numpy as np

from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit, jit_inline
from .surface import surface_point, surface_point_d1_inline as surface_point_d1
from .tess_clip import _clip_t
from .tess_rings import _ring_holds
from .tess import (FOOT_HALVINGS, FOOT_STEPS, TRI_CHUNK, TRI_SERIAL, _dev_scratch,
                   _gap_pass_uv, _run, foot_step)
from .triangles import _dist3, point_triangle_distance

_FAN = np.int64(1)  # triangle kind of a fan piece (non-literal: one compile of _put)


@jit_inline
def _range(keys, major, lo, hi, key):
    """``np.searchsorted(keys, major * key + lo, side="right")`` and
    ``np.searchsorted(keys, major * key + hi, side="left")``: one bisection, then a
    scan over the keys in between (the hanging nodes of one cell edge: a few, as the
    cells are graded), which halves the random memory reads of two bisections."""
    x = major * key + lo
    a = 0
    e = keys.shape[0]
    while a < e:
        mid = (a + e) >> 1
        if keys[mid] <= x:
            a = mid + 1
        else:
            e = mid
    x = major * key + hi
    b = a
    n = keys.shape[0]
    while b < n and keys[b] < x:
        b += 1
    return a, b


@jit
def edge_counts(hkeys, vkeys, key, cells, out):
    """Numbers of lattice points strictly inside the bottom, right, top and left edges
    of each cell (``out`` (N, 4)); ``hkeys`` / ``vkeys`` as in :func:`fill_rings`."""
    # borrowed views of the arguments (the caller holds them): the inlined _range
    # rebinds its array, an atomic reference count per call otherwise (:mod:`.numba_ext.borrow`)
    hkeys, vkeys, cells, out = borrow_all((hkeys, vkeys, cells, out))
    for c in range(cells.shape[0]):
        a, b = _range(hkeys, cells[c, 2], cells[c, 0], cells[c, 1], key)
        out[c, 0] = b - a
        a, b = _range(vkeys, cells[c, 1], cells[c, 2], cells[c, 3], key)
        out[c, 1] = b - a
        a, b = _range(hkeys, cells[c, 3], cells[c, 0], cells[c, 1], key)
        out[c, 2] = b - a
        a, b = _range(vkeys, cells[c, 0], cells[c, 2], cells[c, 3], key)
        out[c, 3] = b - a


@jit
def fill_rings(hkeys, vkeys, key, cells, starts, out):
    """Lattice points around each cell, counter-clockwise from (iu0, iv0).

    ``hkeys`` are sorted ``gv * key + gu`` of all lattice points, ``vkeys`` sorted
    ``gu * key + gv``; ``starts`` (N+1,) are the ring offsets into ``out`` (K, 2).
    """
    hkeys, vkeys, cells, starts, out = borrow_all((hkeys, vkeys, cells, starts, out))
    for c in range(cells.shape[0]):
        iu0 = cells[c, 0]
        iu1 = cells[c, 1]
        iv0 = cells[c, 2]
        iv1 = cells[c, 3]
        w = starts[c]
        out[w, 0] = iu0
        out[w, 1] = iv0
        w += 1
        a, b = _range(hkeys, iv0, iu0, iu1, key)
        for r in range(a, b):
            out[w, 0] = hkeys[r] % key
            out[w, 1] = iv0
            w += 1
        out[w, 0] = iu1
        out[w, 1] = iv0
        w += 1
        a, b = _range(vkeys, iu1, iv0, iv1, key)
        for r in range(a, b):
            out[w, 0] = iu1
            out[w, 1] = vkeys[r] % key
            w += 1
        out[w, 0] = iu1
        out[w, 1] = iv1
        w += 1
        a, b = _range(hkeys, iv1, iu0, iu1, key)
        for r in range(b - 1, a - 1, -1):
            out[w, 0] = hkeys[r] % key
            out[w, 1] = iv1
            w += 1
        out[w, 0] = iu0
        out[w, 1] = iv1
        w += 1
        a, b = _range(vkeys, iu0, iv0, iv1, key)
        for r in range(b - 1, a - 1, -1):
            out[w, 0] = iu0
            out[w, 1] = vkeys[r] % key
            w += 1


@jit
def _edge_nodes(hkeys, vkeys, key, edge, iu0, iu1, iv0, iv1, buf):
    """Hanging nodes of a cell edge in counter-clockwise order; returns their count.

    ``edge``: 0 bottom (A->B), 1 right (B->C), 2 top (C->D), 3 left (D->A).
    """
    n = 0
    if edge == 0 or edge == 2:
        vv = iv0 if edge == 0 else iv1
        a, b = _range(hkeys, vv, iu0, iu1, key)
        for r in range(a, b):
            rr = r if edge == 0 else a + b - 1 - r
            buf[n, 0] = hkeys[rr] % key
            buf[n, 1] = vv
            n += 1
    else:
        uu = iu1 if edge == 1 else iu0
        a, b = _range(vkeys, uu, iv0, iv1, key)
        for r in range(a, b):
            rr = r if edge == 1 else a + b - 1 - r
            buf[n, 0] = uu
            buf[n, 1] = vkeys[rr] % key
            n += 1
    return n


@jit_inline
def _put(out, kind, w, ax, ay, bx, by, cx, cy, k):
    """Write lattice triangle (a, b, c) of kind ``k`` at row ``w``."""
    out[w, 0, 0] = ax
    out[w, 0, 1] = ay
    out[w, 1, 0] = bx
    out[w, 1, 1] = by
    out[w, 2, 0] = cx
    out[w, 2, 1] = cy
    kind[w] = k


@jit
def cell_triangles(hkeys, vkeys, key, cells, counts, diag, starts, out, kind):
    """Triangles of cells whose edges may carry hanging nodes (lattice corners).

    Cell corners A=(iu0,iv0), B=(iu1,iv0), C=(iu1,iv1), D=(iu0,iv1).  ``diag[c]`` 0
    splits along AC, 1 along BD.  A half-triangle (P0, P1, P2) owning cell edges
    P0P1 (hanging nodes a_i) and P1P2 (hanging nodes b_j) is fanned from P2 over
    P0, a_1..a_k and then from a_k over P1, b_1..b_m, P2: every piece is
    non-degenerate and the pieces conform to the finer neighbours.  ``diag[c] == 2``
    fans the whole ring around the cell centre instead.
    ``starts`` (N+1,) are the output offsets (see :func:`count_cell_triangles`);
    ``out`` (T, 3, 2) lattice triangles, counter-clockwise; ``kind[t]`` 0 for a
    plain half of a cell, 1 for a fan piece.
    """
    cmax = 0
    for c in range(counts.shape[0]):  # not counts.max(): its overloads compile slowly
        for e in range(counts.shape[1]):
            cmax = max(cmax, counts[c, e])
    buf = np.empty((cmax + 2, 2), dtype=np.int64)
    _cell_triangles_loop(hkeys, vkeys, key, cells, diag, starts, out, kind, buf,
                         np.empty_like(buf), np.empty((4, 2), dtype=np.int64))


@jit
def _cell_triangles_loop(hkeys, vkeys, key, cells, diag, starts, out, kind, buf, buf2,
                         corners):
    """The loop of :func:`cell_triangles` over borrowed views of its arrays and the
    caller's scratch ``buf``, ``buf2``, ``corners`` (no atomic reference counting,
    :mod:`.numba_ext.borrow`)."""
    hkeys, vkeys, cells, diag, starts, out, kind, buf, buf2, corners = borrow_all((
        hkeys, vkeys, cells, diag, starts, out, kind, buf, buf2, corners))
    for c in range(cells.shape[0]):
        iu0 = cells[c, 0]
        iu1 = cells[c, 1]
        iv0 = cells[c, 2]
        iv1 = cells[c, 3]
        corners[0, 0] = iu0
        corners[0, 1] = iv0
        corners[1, 0] = iu1
        corners[1, 1] = iv0
        corners[2, 0] = iu1
        corners[2, 1] = iv1
        corners[3, 0] = iu0
        corners[3, 1] = iv1
        w = starts[c]
        if diag[c] == 2:
            cu = (iu0 + iu1) // 2
            cv = (iv0 + iv1) // 2
            for e in range(4):
                n = _edge_nodes(hkeys, vkeys, key, e, iu0, iu1, iv0, iv1, buf)
                px = corners[e, 0]
                py = corners[e, 1]
                for r in range(n + 1):
                    if r < n:
                        qx = buf[r, 0]
                        qy = buf[r, 1]
                    else:
                        qx = corners[(e + 1) % 4, 0]
                        qy = corners[(e + 1) % 4, 1]
                    _put(out, kind, w, cu, cv, px, py, qx, qy,
                         _FAN)
                    w += 1
                    px = qx
                    py = qy
            continue
        for half in range(2):
            # the half-triangle (P0, P1, P2), counter-clockwise, owning the cell edges
            # P0 -> P1 (e1) and P1 -> P2 (e2); its third side is the diagonal
            if diag[c] == 0:
                c0, c1, c2 = (0, 1, 2) if half == 0 else (2, 3, 0)
            else:
                c0, c1, c2 = (3, 0, 1) if half == 0 else (1, 2, 3)
            k1 = _edge_nodes(hkeys, vkeys, key, c0, iu0, iu1, iv0, iv1, buf)
            k2 = _edge_nodes(hkeys, vkeys, key, c1, iu0, iu1, iv0, iv1, buf2)
            # fan from P2 over P0, a_1..a_k1 (, P1 when k2 == 0)
            px = corners[c0, 0]
            py = corners[c0, 1]
            last = k1 if k2 > 0 else k1 + 1
            for r in range(last):
                if r < k1:
                    qx = buf[r, 0]
                    qy = buf[r, 1]
                else:
                    qx = corners[c1, 0]
                    qy = corners[c1, 1]
                _put(out, kind, w, corners[c2, 0], corners[c2, 1], px, py, qx, qy,
                     0 if (k1 == 0 and k2 == 0) else 1)
                w += 1
                px = qx
                py = qy
            if k2 == 0:
                continue
            # then fan from a_k1 (or P0) over P1, b_1..b_k2, P2
            ax = px
            ay = py
            px = corners[c1, 0]
            py = corners[c1, 1]
            for r in range(k2 + 1):
                if r < k2:
                    qx = buf2[r, 0]
                    qy = buf2[r, 1]
                else:
                    qx = corners[c2, 0]
                    qy = corners[c2, 1]
                _put(out, kind, w, ax, ay, px, py, qx, qy,
                     _FAN)
                w += 1
                px = qx
                py = qy


@jit
def split_counts(e, eu, ev, target, max_parts, nu, nv):
    """:func:`geomkit.mesh.quadtree.split_counts` elementwise (its numpy formulas, the
    same operations in the same order): children ``nu[i] x nv[i]`` of cell i for the
    estimates ``e`` (the better split's), ``eu``, ``ev`` and ``target``."""
    T = target
    for i in range(e.shape[0]):
        a = eu[i]
        b = ev[i]
        twist = max(a, b) < 0.25 * e[i]
        fu = np.sqrt(2.0 * a / T)
        fv = np.sqrt(2.0 * b / T)
        if fv < 1.0:
            fu = np.sqrt(a / max(T - b, 0.5 * T))
        if fu < 1.0:
            fv = np.sqrt(b / max(T - a, 0.5 * T))
        if twist:
            ft = np.sqrt(e[i] / T)
            fu = max(fu, ft)
            fv = max(fv, ft)
        nu[i] = int(min(max(np.ceil(fu), 1.0), max_parts))
        nv[i] = int(min(max(np.ceil(fv), 1.0), max_parts))


@jit_inline
def _segment_meets_box(x1, y1, x2, y2, u0, u1, v0, v1):
    """Whether the segment (x1, y1)-(x2, y2) meets the closed box ``[u0, u1] x [v0, v1]``
    (Liang-Barsky clipping, :func:`geomkit._kernels.tess_clip._clip_t`; touching
    counts)."""
    t0, t1, _, _ = _clip_t(x1, y1, x2, y2, u0, u1, v0, v1)
    return t0 <= t1


@jit
def classify_cells(P, starts, n_cut, cells, out):
    """``out[c]`` for the UV boxes ``cells`` (N, 4) ``u0, u1, v0, v1``: 2 when a segment
    of the first ``n_cut`` closed polylines ``P[starts[i]:starts[i+1]]`` meets the
    closed box, else 1 when the box's centre is inside the region the polylines bound
    by the even-odd rule over all of them, 0 outside."""
    nl = starts.shape[0] - 1
    for c in range(cells.shape[0]):
        u0 = cells[c, 0]
        u1 = cells[c, 1]
        v0 = cells[c, 2]
        v1 = cells[c, 3]
        state = 0
        for L in range(n_cut):
            for i in range(starts[L], starts[L + 1] - 1):
                if _segment_meets_box(P[i, 0], P[i, 1], P[i + 1, 0], P[i + 1, 1], u0, u1,
                                      v0, v1):
                    state = 2
                    break
            if state == 2:
                break
        if state == 0:
            cu = 0.5 * (u0 + u1)
            cv = 0.5 * (v0 + v1)
            inside = False
            for L in range(nl):
                if _ring_holds(P, starts[L], starts[L + 1], cu, cv):
                    inside = not inside
            state = 1 if inside else 0
        out[c] = state



@jit_inline
def _in_group(u, v, TUV, j0, j1):
    """Whether (u, v) lies in one of the UV triangles ``TUV[j0:j1]`` (edges included)."""
    for j in range(j0, j1):
        a0 = TUV[j, 0, 0]
        a1 = TUV[j, 0, 1]
        b0 = TUV[j, 1, 0]
        b1 = TUV[j, 1, 1]
        c0 = TUV[j, 2, 0]
        c1 = TUV[j, 2, 1]
        d1 = (b0 - a0) * (v - a1) - (b1 - a1) * (u - a0)
        d2 = (c0 - b0) * (v - b1) - (c1 - b1) * (u - b0)
        d3 = (a0 - c0) * (v - c1) - (a1 - c1) * (u - c0)
        if (d1 >= 0.0 and d2 >= 0.0 and d3 >= 0.0) or (d1 <= 0.0 and d2 <= 0.0
                                                       and d3 <= 0.0):
            return True
    return False


@jit_inline
def _foot_in_group(Pw, p, q, U, V, x, y, z, uu, vv, d, d_stop, exact_above, TUV, j0, j1,
                   Nu, Nv, left, right, tmp, Q, SKL, Du, Dv):
    """:func:`geomkit._kernels.tess._foot_descent` with every foot kept in the UV
    triangles ``TUV[j0:j1]`` (a step leaving them is halved like one that does not
    lower the distance): the value returned is ``|X - S(uv')|`` for a ``uv'`` in
    them, an upper bound of X's distance to the part of the surface they cover."""
    for it in range(FOOT_STEPS):
        if d <= d_stop or d <= exact_above:
            break
        surface_point_d1(Pw, p, q, U, V, uu, vv, Du, Dv, left, right, SKL)
        ok, du, dv = foot_step(SKL, x, y, z)
        if not ok:
            break
        moved = False
        dn = d
        nu_ = uu
        nv_ = vv
        for _ in range(FOOT_HALVINGS + 1):
            nu_ = uu + du
            nv_ = vv + dv
            if _in_group(nu_, nv_, TUV, j0, j1):
                surface_point(Pw, p, q, U, V, nu_, nv_, Nu, Nv, left, right, tmp, Q)
                dn = _dist3(x, y, z, Q[0], Q[1], Q[2])
                if dn < d:
                    moved = True
                    break
            du *= 0.5
            dv *= 0.5
        if not moved:
            break
        d = dn
        uu = nu_
        vv = nv_
    return d


@jit
def _group_tri_dev(Pw, p, q, U, V, TUV, TX, t, j0, j1, k, exact_above, Nu, Nv, left,
                   right, tmp, P, Q, SKL, Du, Dv):
    """Deviation of triangle ``t`` (UV ``TUV[t]``, 3-D ``TX[t]``) of the group
    ``j0:j1`` that tiles one cell's part of the face: at each barycentric sample the
    parametric gap, or where it exceeds ``exact_above`` the larger of the surface
    point's distance to the nearest triangle of the group and the triangle point's
    distance to the surface over the group's UV triangles (:func:`_foot_in_group`).
    The gaps are taken first on their own (:func:`.tess._gap_pass_uv`); the exact
    distances only when one exceeds ``exact_above``."""
    worst, over = _gap_pass_uv(Pw, p, q, U, V, TUV[t, 0], TUV[t, 1], TUV[t, 2], TX[t], k,
                               exact_above, Nu, Nv, left, right, tmp, P)
    if not over:
        return worst
    worst = 0.0
    for i in range(k + 1):
        for j in range(k + 1 - i):
            if (i == 0 and j == 0) or i == k or j == k:
                continue  # the corners are exact
            l1 = i / k
            l2 = j / k
            l0 = 1.0 - l1 - l2
            u = l0 * TUV[t, 0, 0] + l1 * TUV[t, 1, 0] + l2 * TUV[t, 2, 0]
            v = l0 * TUV[t, 0, 1] + l1 * TUV[t, 1, 1] + l2 * TUV[t, 2, 1]
            surface_point(Pw, p, q, U, V, u, v, Nu, Nv, left, right, tmp, P)
            x = l0 * TX[t, 0, 0] + l1 * TX[t, 1, 0] + l2 * TX[t, 2, 0]
            y = l0 * TX[t, 0, 1] + l1 * TX[t, 1, 1] + l2 * TX[t, 2, 1]
            z = l0 * TX[t, 0, 2] + l1 * TX[t, 1, 2] + l2 * TX[t, 2, 2]
            gap = _dist3(x, y, z, P[0], P[1], P[2])
            if gap > exact_above and gap > worst:
                d_st = point_triangle_distance(P[0], P[1], P[2], TX[t])
                for g in range(j0, j1):
                    if d_st <= exact_above:
                        break
                    if g != t:
                        d_st = min(d_st, point_triangle_distance(P[0], P[1], P[2], TX[g]))
                d_ts = _foot_in_group(Pw, p, q, U, V, x, y, z, u, v, gap, d_st, exact_above,
                                      TUV, j0, j1, Nu, Nv, left, right, tmp, Q, SKL, Du,
                                      Dv)
                gap = min(gap, max(d_st, d_ts))
            worst = max(worst, gap)
    return worst


@jit
def _group_deviation_range(i0, i1, Pw, p, q, U, V, tri_uv, tri_xyz, group, starts, k,
                           exact_above, out):
    _group_deviation_loop(i0, i1, Pw, p, q, U, V, tri_uv, tri_xyz, group, starts, k,
                          exact_above, out, _dev_scratch(p, q))


@jit
def _group_deviation_loop(i0, i1, Pw, p, q, U, V, tri_uv, tri_xyz, group, starts, k,
                          exact_above, out, scratch):
    """The loop of :func:`_group_deviation_range` over borrowed views (no atomic
    reference counting, :mod:`.numba_ext.borrow`)."""
    (Pw, U, V, tri_uv, tri_xyz, group, starts, out,
     (Nu, Nv, left, right, tmp, P, Q, SKL, Du, Dv)) = borrow_all((
         Pw, U, V, tri_uv, tri_xyz, group, starts, out, scratch))
    for t in range(i0, i1):
        g = group[t]
        out[t] = _group_tri_dev(Pw, p, q, U, V, tri_uv, tri_xyz, t, starts[g],
                                starts[g + 1], k, exact_above, Nu, Nv, left, right, tmp, P,
                                Q, SKL, Du, Dv)


def group_deviation(Pw, p, q, U, V, tri_uv, tri_xyz, group, starts, k, exact_above, out):
    """Measured deviation of triangles that come in groups, each group the mesh of one
    cell's part of the face (the two triangles of a cell inside the trimmed region, or
    the clipped triangles of a cut cell): triangle ``t`` belongs to group ``group[t]``,
    whose triangles are ``starts[g]:starts[g+1]`` (consecutive).  As
    :func:`geomkit._kernels.tess.triangle_deviation`, except where a sample's gap
    exceeds ``exact_above``: the surface point is measured against the nearest
    triangle of its group (all of them are in the mesh, so this bounds its distance to
    the mesh) and the triangle point's foot is sought only inside the group's UV
    triangles (inside the face: a point of a clipped triangle that sticks out past the
    trim is measured to the face, not to the surface beyond it)."""
    _run(_group_deviation_range, tri_uv.shape[0], TRI_CHUNK, TRI_SERIAL, Pw, p, q, U, V,
         tri_uv, tri_xyz, group, starts, k, exact_above, out)
