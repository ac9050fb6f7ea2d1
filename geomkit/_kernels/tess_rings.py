"""Trim rings for the compiled clip: which way each is walked so the region lies on its
left (:func:`ring_directions`), the even-odd rule at a point, and the rings cleaned of
the spurs and tiny loops trim pieces leave where they join (:func:`clean_rings`)."""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit_exact, jit_inline
from .tess_cdt import _opposite, _orient

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


@jit_exact
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


@jit_exact
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


@jit_exact
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
            if not (_opposite(d1, d2) and _opposite(d3, d4)):
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


@jit_exact
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


@jit_exact
def _even_odd(P, starts, px, py):
    """Whether (px, py) is inside the region the closed rings bound (even-odd rule)."""
    inside = False
    for r in range(starts.shape[0] - 1):
        if _ring_holds(P, starts[r], starts[r + 1], px, py):
            inside = not inside
    return inside


@jit_exact
def prepared_rings(P, starts, tiny):
    """:func:`clean_rings`, then :func:`ring_directions` and the region's even-odd area
    (each ring's shoelace sum in its walking direction), in one call: ``(P, starts,
    dirs, area)``."""
    Q, qs = clean_rings(P, starts, tiny)
    dirs = ring_directions(Q, qs)
    a = 0.0
    for r in range(qs.shape[0] - 1):
        s = 0.0
        for k in range(qs[r], qs[r + 1] - 1):
            s += Q[k, 0] * Q[k + 1, 1] - Q[k + 1, 0] * Q[k, 1]
        a += dirs[r] * s
    return Q, qs, dirs, 0.5 * a
