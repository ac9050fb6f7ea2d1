"""Exact triangle kernels: the closest point of a triangle to a point, and the
triangle–triangle intersection test and minimum distance.

Both kernels share one predicate, the *closed segment / closed triangle* crossing
test (:func:`segment_hits_triangle`), built on orientation determinants:

* two closed triangles intersect iff some edge of one meets the other (the
  intersection is a convex set; its extreme points lie on a triangle boundary);
* an edge ``PQ`` meets a triangle ``ABC`` that it crosses transversally iff the
  signs of ``orient(A,B,C,P)`` and ``orient(A,B,C,Q)`` are not both strictly equal
  and the line ``PQ`` passes the three edges on one side (``orient(P,Q,A,B)``,
  ``orient(P,Q,B,C)``, ``orient(P,Q,C,A)`` share a sign, zeros allowed);
* a segment lying in the triangle's plane (both orientations exactly zero) is
  decided in 2-D, projected along the dominant axis of the normal (coplanar case);
* a zero-area triangle (collinear or coincident corners) is its three edges: the
  test falls back to segment/segment distance ``<= DEGENERATE_REL * scale``.

This is the Paper 3 narrow phase ("11-axis SAT") in predicate form: it decides the
same question without axis normalisation, so nearly parallel edges need no
epsilon.  The predicates are evaluated in double precision (not adaptive exact
arithmetic): a sign can be wrong only when the determinant is within rounding of 0,
i.e. when the triangles touch to within ~1e-16 of their size.

:func:`triangle_triangle_distance` returns 0 and a common point exactly when
:func:`triangles_intersect` is true (same predicate); otherwise the minimum over
the 9 edge/edge pairs and the 6 vertex/face pairs, which is the exact distance of
two disjoint triangles (a closest pair always involves an edge pair or a vertex
and a face interior).  Vertex/face distances come from
:func:`point_triangle_distance` (the one point–triangle
routine in geomkit) as a filter; the plane foot is taken as closest point only when
that pair beats every edge pair *and* the foot lies inside the face (otherwise the
closest point is on an edge and an edge pair already has it).
"""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.policy import jit, jit_inline

@jit_inline
def _dist3(a0, a1, a2, b0, b1, b2):
    d0 = a0 - b0
    d1 = a1 - b1
    d2 = a2 - b2
    return np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)


@jit
def _seg_closest(px, py, pz, ax, ay, az, bx, by, bz):
    """Closest point of segment ab: returns (squared distance, parameter)."""
    d0 = bx - ax
    d1 = by - ay
    d2 = bz - az
    ll = d0 * d0 + d1 * d1 + d2 * d2
    t = 0.0
    if ll > 0.0:
        t = ((px - ax) * d0 + (py - ay) * d1 + (pz - az) * d2) / ll
        t = min(1.0, max(0.0, t))
    ex = ax + t * d0 - px
    ey = ay + t * d1 - py
    ez = az + t * d2 - pz
    return ex * ex + ey * ey + ez * ez, t


DEGENERATE_REL2 = 1e-24
"""A triangle with ``|ab x ac|^2 <= DEGENERATE_REL2 |ab|^2 |ac|^2`` (sine of its angle at
a below 1e-12) is handled as its three edges by :func:`closest_on_triangle`."""


@jit
def _closest_on_edges(px, py, pz, ax, ay, az, bx, by, bz, cx, cy, cz):
    """:func:`closest_on_triangle` of a degenerate triangle: the nearest of its edges."""
    e0, t0 = _seg_closest(px, py, pz, ax, ay, az, bx, by, bz)
    e1, t1 = _seg_closest(px, py, pz, bx, by, bz, cx, cy, cz)
    e2, t2 = _seg_closest(px, py, pz, ax, ay, az, cx, cy, cz)
    if e0 <= e1 and e0 <= e2:
        return math.sqrt(e0), t0, 0.0
    if e1 <= e2:
        return math.sqrt(e1), 1.0 - t1, t1
    return math.sqrt(e2), 0.0, t2


@jit
def closest_on_triangle(px, py, pz, ax, ay, az, bx, by, bz, cx, cy, cz):
    """Closest point of the triangle abc to p (Ericson, Real-Time Collision Detection
    5.1.5, closest-feature regions).

    Returns ``(distance, s, w)``: the closest point is ``a + s (b - a) + w (c - a)``.
    A degenerate (collinear) triangle is handled as the nearest of its edges.
    """
    abx, aby, abz = bx - ax, by - ay, bz - az
    acx, acy, acz = cx - ax, cy - ay, cz - az
    nx = aby * acz - abz * acy
    ny = abz * acx - abx * acz
    nz = abx * acy - aby * acx
    if not (nx * nx + ny * ny + nz * nz
            > DEGENERATE_REL2 * (abx * abx + aby * aby + abz * abz)
            * (acx * acx + acy * acy + acz * acz)):
        # collinear or coincident corners: with contracted (fused) products the
        # region tests below do not cancel exactly and could send the point into
        # the "interior" with arbitrary barycentrics (b == c gave distances off by
        # hundreds); the nearest of the three edges is exact
        return _closest_on_edges(px, py, pz, ax, ay, az, bx, by, bz, cx, cy, cz)
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:
        return _dist3(px, py, pz, ax, ay, az), 0.0, 0.0
    bpx, bpy, bpz = px - bx, py - by, pz - bz
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0.0 and d4 <= d3:
        return _dist3(px, py, pz, bx, by, bz), 1.0, 0.0
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0 and d1 - d3 > 0.0:
        s = d1 / (d1 - d3)
        return _dist3(px, py, pz, ax + s * abx, ay + s * aby, az + s * abz), s, 0.0
    cpx, cpy, cpz = px - cx, py - cy, pz - cz
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0.0 and d5 <= d6:
        return _dist3(px, py, pz, cx, cy, cz), 0.0, 1.0
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0 and d2 - d6 > 0.0:
        w = d2 / (d2 - d6)
        return _dist3(px, py, pz, ax + w * acx, ay + w * acy, az + w * acz), 0.0, w
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0 and (d4 - d3) + (d5 - d6) > 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return (_dist3(px, py, pz, bx + w * (cx - bx), by + w * (cy - by), bz + w * (cz - bz)),
                1.0 - w, w)
    den = va + vb + vc
    if not den > 0.0:  # degenerate after all: nearest of its three edges
        return _closest_on_edges(px, py, pz, ax, ay, az, bx, by, bz, cx, cy, cz)
    s = vb / den
    w = vc / den
    return (_dist3(px, py, pz, ax + abx * s + acx * w, ay + aby * s + acy * w,
                   az + abz * s + acz * w), s, w)


@jit_inline
def point_triangle_distance(px, py, pz, T):
    """Euclidean distance from a point to the 3-D triangle T (3, 3)."""
    return closest_on_triangle(px, py, pz, T[0, 0], T[0, 1], T[0, 2], T[1, 0], T[1, 1],
                               T[1, 2], T[2, 0], T[2, 1], T[2, 2])[0]


@jit_inline
def point_triangle_closest(px, py, pz, V, a, b, c):
    """:func:`closest_on_triangle` for the triangle ``V[a], V[b], V[c]``."""
    return closest_on_triangle(px, py, pz, V[a, 0], V[a, 1], V[a, 2], V[b, 0], V[b, 1],
                               V[b, 2], V[c, 0], V[c, 1], V[c, 2])


DEGENERATE_REL = 1e-14
"""Relative contact tolerance used only for zero-area (degenerate) triangles."""


@jit
def _orient(ax, ay, az, bx, by, bz, cx, cy, cz, dx, dy, dz):
    """det[b - a, c - a, d - a] (positive if d is above the plane a, b, c ccw)."""
    ux, uy, uz = bx - ax, by - ay, bz - az
    vx, vy, vz = cx - ax, cy - ay, cz - az
    wx, wy, wz = dx - ax, dy - ay, dz - az
    return (ux * (vy * wz - vz * wy) - uy * (vx * wz - vz * wx)
            + uz * (vx * wy - vy * wx))


@jit
def _o2(ax, ay, bx, by, cx, cy):
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


@jit
def segment_segment_closest(P, Q, A, B):
    """Closest points of segments PQ and AB (each (3,)), Ericson 5.1.9.

    Returns ``(d2, s, t)``: squared distance and parameters of the points
    ``P + s (Q - P)`` and ``A + t (B - A)`` (s, t in [0, 1]); zero-length segments
    are points.
    """
    d1x, d1y, d1z = Q[0] - P[0], Q[1] - P[1], Q[2] - P[2]
    d2x, d2y, d2z = B[0] - A[0], B[1] - A[1], B[2] - A[2]
    rx, ry, rz = P[0] - A[0], P[1] - A[1], P[2] - A[2]
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    s = 0.0
    t = 0.0
    if a <= 0.0 and e <= 0.0:
        pass
    elif a <= 0.0:
        t = min(1.0, max(0.0, f / e))
    else:
        c = d1x * rx + d1y * ry + d1z * rz
        if e <= 0.0:
            s = min(1.0, max(0.0, -c / a))
        else:
            b = d1x * d2x + d1y * d2y + d1z * d2z
            den = a * e - b * b
            if den > 0.0:
                s = min(1.0, max(0.0, (b * f - c * e) / den))
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(1.0, max(0.0, -c / a))
            elif t > 1.0:
                t = 1.0
                s = min(1.0, max(0.0, (b - c) / a))
    dx = P[0] + s * d1x - A[0] - t * d2x
    dy = P[1] + s * d1y - A[1] - t * d2y
    dz = P[2] + s * d1z - A[2] - t * d2z
    return dx * dx + dy * dy + dz * dz, s, t


@jit
def _seg_in_plane(P, Q, T, ax, out):
    """Coplanar closed segment PQ vs closed triangle T in 2-D (drop axis ``ax``)."""
    i = 1 if ax == 0 else 0
    j = 1 if ax == 2 else 2
    area = _o2(T[0, i], T[0, j], T[1, i], T[1, j], T[2, i], T[2, j])
    sg = 1.0 if area > 0.0 else -1.0
    # endpoints inside the closed triangle
    for k in range(2):
        X = P if k == 0 else Q
        inside = True
        for e in range(3):
            a = T[e]
            b = T[(e + 1) % 3]
            if sg * _o2(a[i], a[j], b[i], b[j], X[i], X[j]) < 0.0:
                inside = False
                break
        if inside:
            out[0] = X[0]
            out[1] = X[1]
            out[2] = X[2]
            return True
    # proper or touching crossing of PQ with an edge (collinear overlaps put an
    # endpoint of one segment on the other; PQ's endpoints were handled above)
    for e in range(3):
        A = T[e]
        B = T[(e + 1) % 3]
        o1 = _o2(P[i], P[j], Q[i], Q[j], A[i], A[j])
        o2 = _o2(P[i], P[j], Q[i], Q[j], B[i], B[j])
        o3 = _o2(A[i], A[j], B[i], B[j], P[i], P[j])
        o4 = _o2(A[i], A[j], B[i], B[j], Q[i], Q[j])
        hit = False
        if o1 == 0.0 and o2 == 0.0:   # collinear: overlap iff A or B inside PQ
            lo = min(P[i], Q[i]) if P[i] != Q[i] else min(P[j], Q[j])
            hi = max(P[i], Q[i]) if P[i] != Q[i] else max(P[j], Q[j])
            c = i if P[i] != Q[i] else j
            for X in (A, B):
                if lo <= X[c] <= hi:
                    out[0] = X[0]
                    out[1] = X[1]
                    out[2] = X[2]
                    return True
        elif ((o1 <= 0.0 <= o2) or (o2 <= 0.0 <= o1)) and \
                ((o3 <= 0.0 <= o4) or (o4 <= 0.0 <= o3)):
            hit = True
        if hit:
            _, s, _ = segment_segment_closest(P, Q, A, B)
            for c in range(3):
                out[c] = P[c] + s * (Q[c] - P[c])
            return True
    return False


@jit
def segment_hits_triangle(P, Q, T, out):
    """Does the closed segment PQ (3,) meet the closed triangle T (3, 3)?

    On True, a common point is written to ``out`` (3,).  See the module docstring
    for the predicate and its degenerate / coplanar branches.
    """
    ax, ay, az = T[0, 0], T[0, 1], T[0, 2]
    bx, by, bz = T[1, 0], T[1, 1], T[1, 2]
    cx, cy, cz = T[2, 0], T[2, 1], T[2, 2]
    nx = (by - ay) * (cz - az) - (bz - az) * (cy - ay)
    ny = (bz - az) * (cx - ax) - (bx - ax) * (cz - az)
    nz = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    if nx == 0.0 and ny == 0.0 and nz == 0.0:
        # zero-area triangle: its three edges
        scale = 0.0
        for r in range(3):
            for c in range(3):
                scale = max(scale, abs(T[r, c]), abs(P[c]), abs(Q[c]))
        tol = DEGENERATE_REL * max(scale, 1e-300)
        for e in range(3):
            d2, s, _ = segment_segment_closest(P, Q, T[e], T[(e + 1) % 3])
            if d2 <= tol * tol:
                for c in range(3):
                    out[c] = P[c] + s * (Q[c] - P[c])
                return True
        return False
    sp = _orient(ax, ay, az, bx, by, bz, cx, cy, cz, P[0], P[1], P[2])
    sq = _orient(ax, ay, az, bx, by, bz, cx, cy, cz, Q[0], Q[1], Q[2])
    if (sp > 0.0 and sq > 0.0) or (sp < 0.0 and sq < 0.0):
        return False
    if sp == 0.0 and sq == 0.0:
        anx, any_, anz = abs(nx), abs(ny), abs(nz)
        axis = 0 if (anx >= any_ and anx >= anz) else (1 if any_ >= anz else 2)
        return _seg_in_plane(P, Q, T, axis, out)
    u = _orient(P[0], P[1], P[2], Q[0], Q[1], Q[2], ax, ay, az, bx, by, bz)
    v = _orient(P[0], P[1], P[2], Q[0], Q[1], Q[2], bx, by, bz, cx, cy, cz)
    w = _orient(P[0], P[1], P[2], Q[0], Q[1], Q[2], cx, cy, cz, ax, ay, az)
    if not ((u >= 0.0 and v >= 0.0 and w >= 0.0) or (u <= 0.0 and v <= 0.0 and w <= 0.0)):
        return False
    t = sp / (sp - sq)
    for c in range(3):
        out[c] = P[c] + t * (Q[c] - P[c])
    return True


@jit
def _plane_rejects(T1, T2):
    """True if all corners of T1 lie strictly on one side of T2's plane."""
    ax, ay, az = T2[0, 0], T2[0, 1], T2[0, 2]
    bx, by, bz = T2[1, 0], T2[1, 1], T2[1, 2]
    cx, cy, cz = T2[2, 0], T2[2, 1], T2[2, 2]
    pos = 0
    neg = 0
    for k in range(3):
        o = _orient(ax, ay, az, bx, by, bz, cx, cy, cz, T1[k, 0], T1[k, 1], T1[k, 2])
        if o > 0.0:
            pos += 1
        elif o < 0.0:
            neg += 1
    return pos == 3 or neg == 3


@jit
def _intersect_point(T1, T2, out):
    if _plane_rejects(T1, T2) or _plane_rejects(T2, T1):
        return False
    for e in range(3):
        if segment_hits_triangle(T1[e], T1[(e + 1) % 3], T2, out):
            return True
    for e in range(3):
        if segment_hits_triangle(T2[e], T2[(e + 1) % 3], T1, out):
            return True
    return False


@jit
def triangles_intersect(T1, T2):
    """Do the closed triangles T1, T2 (3, 3) share a point?  (Paper 3 narrow phase.)

    Exact up to the sign of double-precision orientation determinants (see the
    module docstring); coplanar and zero-area triangles are handled.
    """
    buf = np.empty(3)
    return _intersect_point(T1, T2, buf)


@jit
def triangle_triangle_distance(T1, T2, out_p, out_q):
    """Minimum distance between the closed triangles T1, T2 (3, 3).

    Writes the closest points to ``out_p`` (on T1) and ``out_q`` (on T2), each (3,),
    and returns ``|out_p - out_q|``.  Returns exactly 0 with ``out_p == out_q`` a
    common point iff :func:`triangles_intersect` is true.  Degenerate (zero-area),
    coplanar and parallel triangles are handled.
    """
    if _intersect_point(T1, T2, out_p):
        for c in range(3):
            out_q[c] = out_p[c]
        return 0.0
    best = np.inf
    # 9 edge / edge pairs
    for i in range(3):
        P = T1[i]
        Q = T1[(i + 1) % 3]
        for j in range(3):
            A = T2[j]
            B = T2[(j + 1) % 3]
            d2, s, t = segment_segment_closest(P, Q, A, B)
            if d2 < best:
                best = d2
                for c in range(3):
                    out_p[c] = P[c] + s * (Q[c] - P[c])
                    out_q[c] = A[c] + t * (B[c] - A[c])
    best = np.sqrt(best)
    # 6 vertex / face pairs: only a foot strictly inside the face can do better
    for side in range(2):
        S = T1 if side == 0 else T2
        F = T2 if side == 0 else T1
        ex, ey, ez = F[1, 0] - F[0, 0], F[1, 1] - F[0, 1], F[1, 2] - F[0, 2]
        fx, fy, fz = F[2, 0] - F[0, 0], F[2, 1] - F[0, 1], F[2, 2] - F[0, 2]
        nx = ey * fz - ez * fy
        ny = ez * fx - ex * fz
        nz = ex * fy - ey * fx
        nn = nx * nx + ny * ny + nz * nz
        if not nn > 0.0:
            continue
        for k in range(3):
            d = point_triangle_distance(S[k, 0], S[k, 1], S[k, 2], F)
            if not d < best:
                continue
            h = ((S[k, 0] - F[0, 0]) * nx + (S[k, 1] - F[0, 1]) * ny
                 + (S[k, 2] - F[0, 2]) * nz) / nn
            px = S[k, 0] - h * nx
            py = S[k, 1] - h * ny
            pz = S[k, 2] - h * nz
            inside = True
            for e in range(3):
                g = (e + 1) % 3
                ux, uy, uz = F[g, 0] - F[e, 0], F[g, 1] - F[e, 1], F[g, 2] - F[e, 2]
                wx, wy, wz = px - F[e, 0], py - F[e, 1], pz - F[e, 2]
                if ((uy * wz - uz * wy) * nx + (uz * wx - ux * wz) * ny
                        + (ux * wy - uy * wx) * nz) < 0.0:
                    inside = False
                    break
            if not inside:
                continue   # the closest point is on an edge: an edge pair has it
            if side == 0:
                out_p[0], out_p[1], out_p[2] = S[k, 0], S[k, 1], S[k, 2]
                out_q[0], out_q[1], out_q[2] = px, py, pz
            else:
                out_q[0], out_q[1], out_q[2] = S[k, 0], S[k, 1], S[k, 2]
                out_p[0], out_p[1], out_p[2] = px, py, pz
            best = d
    dx = out_p[0] - out_q[0]
    dy = out_p[1] - out_q[1]
    dz = out_p[2] - out_q[2]
    return np.sqrt(dx * dx + dy * dy + dz * dz)
