"""Continuous collision kernels: exact first contact of two translating meshes.

Relative motion: A is held fixed and B translates with the constant relative
velocity ``w`` (both in the common frame of the traversal: A's body frame for box
trees, the world for 14-DOP trees).  Every contact time is a ray cast of ``w``
against a feature of the Minkowski difference of two triangles:

* a vertex ``p`` of B hitting a face of A: ``p + t w`` in the triangle (and a
  vertex of A hitting a face of B along ``-w``);
* an edge ``p0 + s eb`` of B hitting an edge ``q0 + u ea`` of A: the ray from
  ``p0`` along ``w`` against the parallelogram ``q0 + u ea - s eb``, a 3x3
  system solved by Cramer's rule;
* a vertex against an edge (solved in the plane of ``w`` and the edge): only
  needed in degenerate configurations (``w`` parallel to a face, parallel edges,
  coplanar triangles) where the two cases above are singular.

The first contact of two closed triangles is the smallest of these times.

Culling: branch and bound over node pairs on *time*.  For a pair of boxes, the
projections on each of the 15 SAT axes overlap during one interval of ``t``
(the centre distance is linear in ``t``); the boxes can touch only in the
intersection of the 15 intervals, whose start is a lower bound of the pair's
first contact (14-DOPs: the 7 directions).  Pairs whose bound exceeds the best
time found so far are pruned; the nearer child pair is visited first.
"""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit_plain as jit
from .bvh import KDOP_DIRS
from .bvh_query import (LB_SHRINK, SAT_EPS, STACK, _move, _rel_box, box_separation,
                        split_a)
from .triangles import triangle_triangle_distance

BARY_EPS = 1e-12
"""Relative slack of the closed-feature tests (a hit on a shared edge is seen by
both neighbouring triangles despite rounding)."""
SLACK = 1e-12
"""Relative growth of node radii in the time intervals (conservative rounding)."""


@jit
def _axis_window(D, wl, r, lo, hi):
    """Interval of t in [lo, hi] where |D + t wl| <= r, as (t0, t1) (t0 > t1: never)."""
    r = r * (1.0 + SLACK) + SLACK * abs(D)
    if wl == 0.0:
        if abs(D) <= r:
            return lo, hi
        return np.inf, -np.inf
    t0 = (-r - D) / wl
    t1 = (r - D) / wl
    if t0 > t1:
        t0, t1 = t1, t0
    return max(t0, lo), min(t1, hi)


@jit
def box_time_window(Rab, T, wn, a, b, lo, hi, Ab):
    """Earliest time in [lo, hi] at which two boxes can overlap under translation.

    ``Rab``, ``T`` as in :func:`geomkit._kernels.bvh_query.box_separation` (B in
    A's box axes at t = 0), ``wn`` (3,) B's velocity in A's box axes.  Returns the
    start of the intersection of the 15 per-axis overlap intervals, or ``inf``.
    """
    for r in range(3):
        for c in range(3):
            Ab[r, c] = abs(Rab[r, c]) + SAT_EPS
    t0 = lo
    t1 = hi
    for i in range(3):
        s0, s1 = _axis_window(T[i], wn[i], a[i] + b[0] * Ab[i, 0] + b[1] * Ab[i, 1]
                              + b[2] * Ab[i, 2], lo, hi)
        t0 = max(t0, s0)
        t1 = min(t1, s1)
        if t0 > t1:
            return np.inf
    for j in range(3):
        D = T[0] * Rab[0, j] + T[1] * Rab[1, j] + T[2] * Rab[2, j]
        wl = wn[0] * Rab[0, j] + wn[1] * Rab[1, j] + wn[2] * Rab[2, j]
        s0, s1 = _axis_window(D, wl, b[j] + a[0] * Ab[0, j] + a[1] * Ab[1, j]
                              + a[2] * Ab[2, j], lo, hi)
        t0 = max(t0, s0)
        t1 = min(t1, s1)
        if t0 > t1:
            return np.inf
    for i in range(3):
        i1 = (i + 1) % 3
        i2 = (i + 2) % 3
        for j in range(3):
            j1 = (j + 1) % 3
            j2 = (j + 2) % 3
            ra = a[i1] * Ab[i2, j] + a[i2] * Ab[i1, j]
            rb = b[j1] * Ab[i, j2] + b[j2] * Ab[i, j1]
            D = T[i2] * Rab[i1, j] - T[i1] * Rab[i2, j]
            wl = wn[i2] * Rab[i1, j] - wn[i1] * Rab[i2, j]
            s0, s1 = _axis_window(D, wl, ra + rb, lo, hi)
            t0 = max(t0, s0)
            t1 = min(t1, s1)
            if t0 > t1:
                return np.inf
    return t0


@jit
def kdop_time_window(KA, KB, i, j, wd, lo, hi):
    """Earliest time in [lo, hi] at which two world 14-DOPs can overlap when B
    translates by ``t w`` (``wd`` (7,) = ``KDOP_DIRS @ w``), or ``inf``."""
    t0 = lo
    t1 = hi
    for d in range(7):
        alo, ahi = KA[i, 2 * d], KA[i, 2 * d + 1]
        blo, bhi = KB[j, 2 * d], KB[j, 2 * d + 1]
        # overlap: blo + t wd <= ahi and bhi + t wd >= alo; as |D + t wd| <= r
        D = 0.5 * ((blo + bhi) - (alo + ahi))
        r = 0.5 * ((ahi - alo) + (bhi - blo))
        s0, s1 = _axis_window(D, wd[d], r, lo, hi)
        t0 = max(t0, s0)
        t1 = min(t1, s1)
        if t0 > t1:
            return np.inf
    return t0


@jit
def _det3(ax, ay, az, bx, by, bz, cx, cy, cz):
    return ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)


@jit
def _ray_triangle(px, py, pz, wx, wy, wz, T, tmax):
    """Smallest t in [0, tmax] with p + t w in the closed triangle T (3, 3), or inf.
    Cramer's rule on p + t w = T0 + u e1 + v e2; inf when w is parallel to T."""
    e1x, e1y, e1z = T[1, 0] - T[0, 0], T[1, 1] - T[0, 1], T[1, 2] - T[0, 2]
    e2x, e2y, e2z = T[2, 0] - T[0, 0], T[2, 1] - T[0, 1], T[2, 2] - T[0, 2]
    # [e1 e2 -w] (u v t)^T = p - T0
    det = _det3(e1x, e1y, e1z, e2x, e2y, e2z, -wx, -wy, -wz)
    sc = np.sqrt((e1x * e1x + e1y * e1y + e1z * e1z) * (e2x * e2x + e2y * e2y + e2z * e2z)
                 * (wx * wx + wy * wy + wz * wz))
    if not abs(det) > 1e-14 * sc:
        return np.inf
    rx, ry, rz = px - T[0, 0], py - T[0, 1], pz - T[0, 2]
    u = _det3(rx, ry, rz, e2x, e2y, e2z, -wx, -wy, -wz) / det
    v = _det3(e1x, e1y, e1z, rx, ry, rz, -wx, -wy, -wz) / det
    t = _det3(e1x, e1y, e1z, e2x, e2y, e2z, rx, ry, rz) / det
    if u < -BARY_EPS or v < -BARY_EPS or u + v > 1.0 + BARY_EPS:
        return np.inf
    if t < 0.0 or t > tmax:
        return np.inf
    return t


@jit
def _ray_edge_edge(p0x, p0y, p0z, ebx, eby, ebz, q0x, q0y, q0z, eax, eay, eaz,
                   wx, wy, wz, tmax):
    """Smallest t in [0, tmax] with p0 + s eb + t w = q0 + u ea, s, u in [0, 1]
    (edge of B moving along w against an edge of A), or inf when singular."""
    # [eb, -ea, w] (s u t)^T = q0 - p0
    det = _det3(ebx, eby, ebz, -eax, -eay, -eaz, wx, wy, wz)
    sc = np.sqrt((ebx * ebx + eby * eby + ebz * ebz) * (eax * eax + eay * eay + eaz * eaz)
                 * (wx * wx + wy * wy + wz * wz))
    if not abs(det) > 1e-14 * sc:
        return np.inf
    rx, ry, rz = q0x - p0x, q0y - p0y, q0z - p0z
    s = _det3(rx, ry, rz, -eax, -eay, -eaz, wx, wy, wz) / det
    u = _det3(ebx, eby, ebz, rx, ry, rz, wx, wy, wz) / det
    t = _det3(ebx, eby, ebz, -eax, -eay, -eaz, rx, ry, rz) / det
    if s < -BARY_EPS or s > 1.0 + BARY_EPS or u < -BARY_EPS or u > 1.0 + BARY_EPS:
        return np.inf
    if t < 0.0 or t > tmax:
        return np.inf
    return t


@jit
def _ray_vertex_edge(px, py, pz, wx, wy, wz, q0x, q0y, q0z, ex, ey, ez, tmax, scale):
    """Smallest t in [0, tmax] with p + t w on the segment q0 + u e (u in [0, 1]),
    or inf (degenerate configurations: the ray and the segment are coplanar)."""
    rx, ry, rz = q0x - px, q0y - py, q0z - pz
    ww = wx * wx + wy * wy + wz * wz
    ee = ex * ex + ey * ey + ez * ez
    we = wx * ex + wy * ey + wz * ez
    det = ww * ee - we * we
    tol = 1e-12 * scale
    if det > 1e-20 * ww * ee:
        # least squares [w, -e](t, u) = r
        wr = wx * rx + wy * ry + wz * rz
        er = ex * rx + ey * ry + ez * rz
        t = (ee * wr - we * er) / det
        u = (we * wr - ww * er) / det
        if u < -BARY_EPS or u > 1.0 + BARY_EPS or t < 0.0 or t > tmax:
            return np.inf
        dx = px + t * wx - q0x - u * ex
        dy = py + t * wy - q0y - u * ey
        dz = pz + t * wz - q0z - u * ez
        if dx * dx + dy * dy + dz * dz > tol * tol:
            return np.inf
        return t
    # w parallel to e: the ray runs along the segment's line or misses it
    if ee == 0.0 or ww == 0.0:
        return np.inf
    # distance of p from the line
    er = ex * rx + ey * ry + ez * rz
    cx = rx - er / ee * ex
    cy = ry - er / ee * ey
    cz = rz - er / ee * ez
    if cx * cx + cy * cy + cz * cz > tol * tol:
        return np.inf
    wr = wx * rx + wy * ry + wz * rz
    ta = wr / ww                                    # reaches q0
    tb = (wr + (wx * ex + wy * ey + wz * ez)) / ww  # reaches q0 + e
    lo = min(ta, tb)
    hi = max(ta, tb)
    if hi < 0.0:
        return np.inf
    t = max(lo, 0.0)
    return t if t <= tmax else np.inf


@jit
def triangle_toi(TA, TB, w, tmax, out_p):
    """First contact time in [0, tmax] of the static closed triangle ``TA`` and
    ``TB`` translating by ``t w`` (both (3, 3)), or ``inf``; writes the contact
    point (on ``TA``) to ``out_p``.  The triangles are assumed disjoint at t = 0
    (the caller checks it)."""
    wx, wy, wz = w[0], w[1], w[2]
    best = tmax
    found = False
    kind = -1
    scale = 0.0
    for v in range(3):
        for c in range(3):
            scale = max(scale, abs(TA[v, c]), abs(TB[v, c]))
    # vertex of B on face of A, vertex of A on face of B (along -w)
    for v in range(3):
        t = _ray_triangle(TB[v, 0], TB[v, 1], TB[v, 2], wx, wy, wz, TA, best)
        if t <= best:
            best = t
            found = True
            for c in range(3):
                out_p[c] = TB[v, c] + t * w[c]
        t = _ray_triangle(TA[v, 0], TA[v, 1], TA[v, 2], -wx, -wy, -wz, TB, best)
        if t <= best:
            best = t
            found = True
            for c in range(3):
                out_p[c] = TA[v, c]
    # edge of B against edge of A
    for i in range(3):
        i1 = (i + 1) % 3
        p0x, p0y, p0z = TB[i, 0], TB[i, 1], TB[i, 2]
        ebx, eby, ebz = TB[i1, 0] - p0x, TB[i1, 1] - p0y, TB[i1, 2] - p0z
        for j in range(3):
            j1 = (j + 1) % 3
            q0x, q0y, q0z = TA[j, 0], TA[j, 1], TA[j, 2]
            eax, eay, eaz = TA[j1, 0] - q0x, TA[j1, 1] - q0y, TA[j1, 2] - q0z
            t = _ray_edge_edge(p0x, p0y, p0z, ebx, eby, ebz, q0x, q0y, q0z, eax, eay, eaz,
                               wx, wy, wz, best)
            if t <= best:
                # the point on A's edge: solve again for u by projection
                ee = eax * eax + eay * eay + eaz * eaz
                found = True
                best = t
                # closest point of the moved edge of B to A's edge lies on A's edge
                u = 0.0
                if ee > 0.0:
                    # p0 + s eb + t w = q0 + u ea  =>  u from the 3x3 solution
                    det = _det3(ebx, eby, ebz, -eax, -eay, -eaz, wx, wy, wz)
                    rx, ry, rz = q0x - p0x, q0y - p0y, q0z - p0z
                    u = _det3(ebx, eby, ebz, rx, ry, rz, wx, wy, wz) / det
                    u = min(max(u, 0.0), 1.0)
                out_p[0] = q0x + u * eax
                out_p[1] = q0y + u * eay
                out_p[2] = q0z + u * eaz
            # degenerate cases: vertices against edges
            t = _ray_vertex_edge(p0x, p0y, p0z, wx, wy, wz, q0x, q0y, q0z, eax, eay, eaz,
                                 best, scale)
            if t <= best:
                best = t
                found = True
                for c in range(3):
                    out_p[c] = TB[i, c] + t * w[c]
            t = _ray_vertex_edge(q0x, q0y, q0z, -wx, -wy, -wz, p0x, p0y, p0z, ebx, eby, ebz,
                                 best, scale)
            if t <= best:
                best = t
                found = True
                out_p[0], out_p[1], out_p[2] = q0x, q0y, q0z
    if not found:
        return np.inf
    return best


@jit
def toi_trees(kind, childA, rngA, CA, RA, EA, KA, TA, orderA,
              childB, rngB, CB, RB, EB, KB, TB, orderB,
              Rr, tr, MA, mA, MB, mB, w, t_max, out_p):
    """First contact time in [0, t_max] of two trees when B translates by ``t w``
    relative to A (``w`` in the common frame), by branch and bound on time.

    Box trees: common frame = A's body frame, ``(Rr, tr)`` carries B's nodes into
    it; 14-DOP trees: both ``K`` refitted in the world at t = 0.  Returns ``(t,
    fa, fb, bv_tests)`` (``t = inf``, ``fa = fb = -1`` when no contact); the
    contact point (common frame, on A) goes to ``out_p``.
    """
    st = np.empty((STACK, 2), dtype=np.int64)
    stlb = np.empty(STACK)
    Rab = np.empty((3, 3))
    T = np.empty(3)
    scr = np.empty((2, 3, 3))
    wn = np.empty(3)
    wd = np.empty(7)
    for d in range(7):
        wd[d] = KDOP_DIRS[d, 0] * w[0] + KDOP_DIRS[d, 1] * w[1] + KDOP_DIRS[d, 2] * w[2]
    ta = np.empty((3, 3))
    tb = np.empty((3, 3))
    p = np.empty(3)
    best = t_max
    found = False
    fa = -1
    fb = -1
    tests = 1
    st[0, 0] = 0
    st[0, 1] = 0
    stlb[0] = _node_time(kind, 0, 0, CA, RA, EA, KA, CB, RB, EB, KB, Rr, tr, w, wd, best,
                         Rab, T, wn, scr)
    top = 1 if stlb[0] <= best else 0
    while top > 0:
        top -= 1
        if stlb[top] > best:
            continue
        i = st[top, 0]
        j = st[top, 1]
        la = childA[i, 0] < 0
        lb = childB[j, 0] < 0
        if la and lb:
            for ra in range(rngA[i, 0], rngA[i, 1]):
                _move(TA, ra, MA, mA, ta)
                for rb in range(rngB[j, 0], rngB[j, 1]):
                    _move(TB, rb, MB, mB, tb)
                    t = triangle_toi(ta, tb, w, best, p)
                    if t <= best:
                        best = t
                        found = True
                        fa = orderA[ra]
                        fb = orderB[rb]
                        out_p[:] = p
            continue
        if split_a(kind, childA, childB, EA, KA, EB, KB, i, j):
            i0, j0, i1, j1 = childA[i, 0], j, childA[i, 1], j
        else:
            i0, j0, i1, j1 = i, childB[j, 0], i, childB[j, 1]
        b0 = _node_time(kind, i0, j0, CA, RA, EA, KA, CB, RB, EB, KB, Rr, tr, w, wd, best,
                        Rab, T, wn, scr)
        b1 = _node_time(kind, i1, j1, CA, RA, EA, KA, CB, RB, EB, KB, Rr, tr, w, wd, best,
                        Rab, T, wn, scr)
        tests += 2
        if b0 > b1:
            i0, j0, b0, i1, j1, b1 = i1, j1, b1, i0, j0, b0
        if b1 <= best:
            st[top, 0] = i1
            st[top, 1] = j1
            stlb[top] = b1
            top += 1
        if b0 <= best:
            st[top, 0] = i0
            st[top, 1] = j0
            stlb[top] = b0
            top += 1
    if not found:
        return np.inf, -1, -1, tests
    return best, fa, fb, tests


@jit
def _node_time(kind, i, j, CA, RA, EA, KA, CB, RB, EB, KB, Rr, tr, w, wd, hi, Rab, T, wn,
               scr):
    if kind == 2:
        return kdop_time_window(KA, KB, i, j, wd, 0.0, hi)
    _rel_box(CA, RA, CB, RB, i, j, Rr, tr, Rab, T, scr[0])
    for r in range(3):
        wn[r] = RA[i, 0, r] * w[0] + RA[i, 1, r] * w[1] + RA[i, 2, r] * w[2]
    return box_time_window(Rab, T, wn, EA[i], EB[j], 0.0, hi, scr[1])


# ------------------------------------------------------------------ swept distance
GOLDEN_ITERS = 64
"""Golden-section iterations per triangle pair (interval shrinks to 0.618^64 ~ 4e-14)."""


@jit
def _pair_dist_at(ta, tb, w, s, tbs, p, q):
    for v in range(3):
        for c in range(3):
            tbs[v, c] = tb[v, c] + s * w[c]
    return triangle_triangle_distance(ta, tbs, p, q)


@jit
def pair_sweep_min(ta, tb, w, best, out_p, out_q):
    """Minimum over s in [0, 1] of dist(ta, tb + s w), a convex function of s
    (distance of a moving point to the convex Minkowski difference), by golden
    section.  Returns ``(d, s)``; closest points at that s to ``out_p``/``out_q``
    (only written when ``d < best``)."""
    tbs = np.empty((3, 3))
    p = np.empty(3)
    q = np.empty(3)
    g = 0.6180339887498949
    lo = 0.0
    hi = 1.0
    x1 = hi - g * (hi - lo)
    x2 = lo + g * (hi - lo)
    f1 = _pair_dist_at(ta, tb, w, x1, tbs, p, q)
    f2 = _pair_dist_at(ta, tb, w, x2, tbs, p, q)
    for _ in range(GOLDEN_ITERS):
        if f1 <= f2:
            hi = x2
            x2 = x1
            f2 = f1
            x1 = hi - g * (hi - lo)
            f1 = _pair_dist_at(ta, tb, w, x1, tbs, p, q)
        else:
            lo = x1
            x1 = x2
            f1 = f2
            x2 = lo + g * (hi - lo)
            f2 = _pair_dist_at(ta, tb, w, x2, tbs, p, q)
        if f1 == 0.0 or f2 == 0.0:
            break
    # compare with the ends (a minimum at s = 0 or 1)
    s = x1 if f1 <= f2 else x2
    d = min(f1, f2)
    for e in (0.0, 1.0):
        fe = _pair_dist_at(ta, tb, w, e, tbs, p, q)
        if fe < d:
            d = fe
            s = e
    if d < best:
        _pair_dist_at(ta, tb, w, s, tbs, out_p, out_q)
    return d, s


@jit
def _node_sweep_sep(kind, i, j, CA, RA, EA, KA, CB, RB, EB, KB, Rr, tr, w, wd, Rab, T, eb,
                    scr):
    """Lower bound of the distance of node i of A and node j of B swept along
    ``s w``, s in [0, 1]: B's box is grown to contain box + segment (centre moved
    to the middle, extents + |axis . w| / 2); 14-DOP intervals widened."""
    if kind == 2:
        best = -np.inf
        for q in range(7):
            d = q
            lo = KB[j, 2 * d] + min(0.0, wd[d])
            hi = KB[j, 2 * d + 1] + max(0.0, wd[d])
            g = max(KA[i, 2 * d] - hi, lo - KA[i, 2 * d + 1])
            if d >= 3:
                g *= 0.5773502691896258
            best = max(best, g)
        return best
    _rel_box(CA, RA, CB, RB, i, j, Rr, tr, Rab, T, scr[0])
    for r in range(3):
        # B's axes in the common frame are columns of Rr RB[j]; w . axis
        ax = 0.0
        for c in range(3):
            ax += (Rr[c, 0] * RB[j, 0, r] + Rr[c, 1] * RB[j, 1, r]
                   + Rr[c, 2] * RB[j, 2, r]) * w[c]
        eb[r] = EB[j, r] + 0.5 * abs(ax)
    for r in range(3):
        T[r] += 0.5 * (RA[i, 0, r] * w[0] + RA[i, 1, r] * w[1] + RA[i, 2, r] * w[2])
    return box_separation(Rab, T, EA[i], eb, False, scr[1])


@jit
def sweep_distance_trees(kind, childA, rngA, CA, RA, EA, KA, TA, orderA,
                         childB, rngB, CB, RB, EB, KB, TB, orderB,
                         Rr, tr, MA, mA, MB, mB, w, out_p, out_q):
    """Minimum over s in [0, 1] of the distance between A and B translated by
    ``s w`` (common frame), by branch and bound on swept node bounds; triangle
    pairs by :func:`pair_sweep_min`.  Returns ``(d, s, fa, fb, bv_tests)``;
    closest points (at that s) to ``out_p``, ``out_q``."""
    st = np.empty((STACK, 2), dtype=np.int64)
    stlb = np.empty(STACK)
    Rab = np.empty((3, 3))
    T = np.empty(3)
    eb = np.empty(3)
    scr = np.empty((2, 3, 3))
    wd = np.empty(7)
    for d in range(7):
        wd[d] = KDOP_DIRS[d, 0] * w[0] + KDOP_DIRS[d, 1] * w[1] + KDOP_DIRS[d, 2] * w[2]
    ta = np.empty((3, 3))
    tb = np.empty((3, 3))
    p = np.empty(3)
    q = np.empty(3)
    best = np.inf
    best_s = 0.0
    fa = -1
    fb = -1
    tests = 1
    st[0, 0] = 0
    st[0, 1] = 0
    stlb[0] = _node_sweep_sep(kind, 0, 0, CA, RA, EA, KA, CB, RB, EB, KB, Rr, tr, w, wd,
                              Rab, T, eb, scr) * LB_SHRINK
    top = 1
    while top > 0:
        top -= 1
        if stlb[top] >= best:
            continue
        i = st[top, 0]
        j = st[top, 1]
        la = childA[i, 0] < 0
        lb = childB[j, 0] < 0
        if la and lb:
            for ra in range(rngA[i, 0], rngA[i, 1]):
                _move(TA, ra, MA, mA, ta)
                for rb in range(rngB[j, 0], rngB[j, 1]):
                    _move(TB, rb, MB, mB, tb)
                    d, s = pair_sweep_min(ta, tb, w, best, p, q)
                    if d < best:
                        best = d
                        best_s = s
                        fa = orderA[ra]
                        fb = orderB[rb]
                        out_p[:] = p
                        out_q[:] = q
                        if d == 0.0:
                            return best, best_s, fa, fb, tests
            continue
        if split_a(kind, childA, childB, EA, KA, EB, KB, i, j):
            i0, j0, i1, j1 = childA[i, 0], j, childA[i, 1], j
        else:
            i0, j0, i1, j1 = i, childB[j, 0], i, childB[j, 1]
        b0 = _node_sweep_sep(kind, i0, j0, CA, RA, EA, KA, CB, RB, EB, KB, Rr, tr, w, wd,
                             Rab, T, eb, scr) * LB_SHRINK
        b1 = _node_sweep_sep(kind, i1, j1, CA, RA, EA, KA, CB, RB, EB, KB, Rr, tr, w, wd,
                             Rab, T, eb, scr) * LB_SHRINK
        tests += 2
        if b0 > b1:
            i0, j0, b0, i1, j1, b1 = i1, j1, b1, i0, j0, b0
        if b1 < best:
            st[top, 0] = i1
            st[top, 1] = j1
            stlb[top] = b1
            top += 1
        if b0 < best:
            st[top, 0] = i0
            st[top, 1] = j0
            stlb[top] = b0
            top += 1
    return best, best_s, fa, fb, tests


# frame coherence: in motion_front (re-exported for geomkit.motion / geomkit.scene)
from .motion_front import collapse_front, collide_front  # noqa: E402,F401
