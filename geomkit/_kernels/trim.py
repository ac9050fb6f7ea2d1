"""Inside/outside classification of UV points against exact trim loops.

Each loop is a closed chain of rational Bézier segments (homogeneous 2-D control
points).  The winding number of a point around a segment is computed on the exact
curve by adaptive subdivision that refines only near the query point:

* if the point lies outside the bounding box of a piece's control points grown by
  ``tol / 4``, the piece and its chord both lie in that box (convex hull property,
  weights > 0), so the piece winds around the point exactly as its chord does, and
  the chord's crossing of the ray ``{(u, v0): u > u0}`` is decided exactly from the
  box;
* if the grown box contains the point and the box is at most ``tol / 4`` wide, the
  point is within ``tol / sqrt(2)`` of the curve: it is reported on the boundary;
* otherwise the piece is split in half (de Casteljau) and both halves are examined.

Guarantees: a point within ``tol / 4`` of a trim curve is always ``BOUNDARY``; a
``BOUNDARY`` point is within ``tol`` of a trim curve; every other point gets the exact
winding number (points between ``tol / 4`` and ``tol`` may get either answer, both
correct in their sense).
"""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit, jit_inline, prun
from .bezier import de_casteljau_split

OUTSIDE = 0
INSIDE = 1
BOUNDARY = 2

MAX_DEPTH = 64
CLASSIFY_CHUNK = 64


@jit_inline
def _line_crossing(x1, y1, x2, y2, px, py, tol):
    """Signed crossing of segment with the ray to +u; returns (crossing, on_boundary)."""
    # distance from the point to the segment
    dx = x2 - x1
    dy = y2 - y1
    ll = dx * dx + dy * dy
    t = 0.0
    if ll > 0.0:
        t = ((px - x1) * dx + (py - y1) * dy) / ll
        t = min(1.0, max(0.0, t))
    ex = x1 + t * dx - px
    ey = y1 + t * dy - py
    if ex * ex + ey * ey <= tol * tol:
        return 0, True
    up = y1 <= py < y2
    down = y2 <= py < y1
    if not (up or down):
        return 0, False
    xint = x1 + (py - y1) * dx / dy
    if px < xint:
        return (1 if up else -1), False
    return 0, False


@jit
def _segment_winding(Q, deg, px, py, tol, stack, depths, left, right):
    """Winding contribution of one rational Bézier segment ``Q[:deg+1]``.

    Returns (winding, on_boundary).  ``stack`` (MAX_DEPTH+2, p+1, 3) and ``depths``
    (MAX_DEPTH+2,) are scratch.
    """
    if deg == 1:
        return _line_crossing(Q[0, 0] / Q[0, 2], Q[0, 1] / Q[0, 2],
                              Q[1, 0] / Q[1, 2], Q[1, 1] / Q[1, 2], px, py, tol)
    wind = 0
    grow = 0.25 * tol
    for i in range(deg + 1):  # element loops, not slice copies: no shape-check raise
        for c in range(3):
            stack[0, i, c] = Q[i, c]
    depths[0] = 0
    top = 1
    while top > 0:
        top -= 1
        piece = stack[top, : deg + 1, :]
        depth = depths[top]
        xmin = np.inf
        xmax = -np.inf
        ymin = np.inf
        ymax = -np.inf
        for i in range(deg + 1):
            x = piece[i, 0] / piece[i, 2]
            y = piece[i, 1] / piece[i, 2]
            xmin = min(xmin, x)
            xmax = max(xmax, x)
            ymin = min(ymin, y)
            ymax = max(ymax, y)
        if px < xmin - grow or px > xmax + grow or py < ymin - grow or py > ymax + grow:
            x1 = piece[0, 0] / piece[0, 2]
            y1 = piece[0, 1] / piece[0, 2]
            x2 = piece[deg, 0] / piece[deg, 2]
            y2 = piece[deg, 1] / piece[deg, 2]
            up = y1 <= py < y2
            down = y2 <= py < y1
            if (up or down) and px < xmin - grow:
                wind += 1 if up else -1
            continue
        if max(xmax - xmin, ymax - ymin) <= grow or depth >= MAX_DEPTH:
            return 0, True
        de_casteljau_split(piece, 0.5, left[: deg + 1], right[: deg + 1])
        for i in range(deg + 1):
            for c in range(3):
                stack[top, i, c] = right[i, c]
                stack[top + 1, i, c] = left[i, c]
        depths[top] = depth + 1
        depths[top + 1] = depth + 1
        top += 2
    return wind, False


@jit
def classify_point(seg, seg_deg, seg_loop, nloops, px, py, tol, winding, stack, depths,
                   left, right):
    """Classify one point: INSIDE, OUTSIDE or BOUNDARY (parity of loops around it)."""
    for k in range(nloops):
        winding[k] = 0
    for s in range(seg.shape[0]):
        w, on = _segment_winding(seg[s], seg_deg[s], px, py, tol, stack, depths, left, right)
        if on:
            return BOUNDARY
        winding[seg_loop[s]] += w
    inside = 0
    for k in range(nloops):
        if winding[k] != 0:
            inside += 1
    return INSIDE if inside % 2 == 1 else OUTSIDE


@jit
def _classify_points_range(i0, i1, seg, seg_deg, seg_loop, nloops, uv, tol, out):
    p1 = seg.shape[1]
    winding = np.empty(nloops, dtype=np.int64)
    stack = np.empty((MAX_DEPTH + 2, p1, 3))
    depths = np.empty(MAX_DEPTH + 2, dtype=np.int64)
    left = np.empty((p1, 3))
    right = np.empty((p1, 3))
    for i in range(i0, i1):
        out[i] = classify_point(seg, seg_deg, seg_loop, nloops, uv[i, 0], uv[i, 1],
                                tol, winding, stack, depths, left, right)


def classify_points(seg, seg_deg, seg_loop, nloops, uv, tol, out):
    """Batch classification of ``uv`` (n, 2) into ``out`` (n,) int8, parallel."""
    prun(_classify_points_range, uv.shape[0], CLASSIFY_CHUNK, seg, seg_deg, seg_loop, nloops,
         uv, tol, out)
