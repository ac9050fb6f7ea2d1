"""Plane-section kernels: where a section curve leaves its trimmed face.

:func:`outside_binned` is ``Surface.classify_uv((u, v), tol) == OUTSIDE`` for one
point (outside the domain rectangle by more than ``tol``, or outside the trim loops by
:func:`.trim.classify_point`), walking only the trim segments whose v-range (grown by
the band) holds the point's v, found in bins over v (:func:`trim_bins`);
:func:`trim_crossings` bisects along the exact curve
(:func:`.section_project._project_point`) between inside and outside points to the
trim boundary.
"""

from __future__ import annotations

import numpy as np

from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit
from .bezier import de_casteljau_split
from .section_project import _project_point, point_scratch
from .surface import D1, _binomial_table, derivs_scratch
from .trim import (MAX_DEPTH as TRIM_MAX_DEPTH, OUTSIDE as TRIM_OUTSIDE, _segment_winding,
                   classify_point)

MAX_BINS = 512
""":func:`trim_bins` uses at most this many bins (4 per trim segment)."""

@jit
def _off_domain(u, v, box, tol):
    """``(u, v)`` outside the domain rectangle ``box`` (u0, u1, v0, v1) by more than
    ``tol``, as ``Surface.classify_uv`` tests it."""
    d = min(min(u - box[0], box[1] - u), min(v - box[2], box[3] - v))
    return d < -tol


@jit
def trim_bins(seg, seg_deg, tol):
    """Bins over v of the trim segments that can answer for a point at a given v.

    A segment of degree >= 2 adds nothing to the winding number of a point
    :func:`.trim.classify_point` classifies with ``tol`` unless the point's v lies in
    ``[ymin - tol / 4, ymax + tol / 4]`` (``ymin``, ``ymax``: its control points' v
    range, computed as :func:`.trim._segment_winding` does): outside that the first
    test of ``_segment_winding`` finds the point off the grown box, and the chord's
    ends lie in ``[ymin, ymax]``, so no crossing is counted and no boundary seen.  A
    line segment (degree 1, :func:`.trim._line_crossing`) adds nothing unless v lies in
    ``[ymin - g, ymax + g]``, ``g = 2 tol + 1e-15 (|ymin| + |ymax|)``: farther, no
    crossing (v outside the ends' range) and the computed distance exceeds ``tol``
    (the foot's v is computed within ``5 * 2**-53 * max |y|`` of the segment's range,
    so ``|ey| > 2 tol (1 - 2**-53) > tol``).

    The bins built for ``tol`` serve every smaller tolerance too (the grown ranges
    only shrink).

    Returns ``(vlo, w, nb, off, items)``: bin ``k`` covers ``vlo + [k, k+1) w`` and
    holds the segments ``items[off[k]:off[k+1]]`` (in order) whose grown range meets
    it, bin indices by :func:`_bin_of` (monotone in v, so a v in a segment's range
    falls in a bin between those of the range's ends).  Every segment is in bin 0 of
    a single bin when ``tol`` is too small for ``tol**2`` to be a normal number.
    """
    S = seg.shape[0]
    lo = np.empty(S)
    hi = np.empty(S)
    vlo = np.inf
    vhi = -np.inf
    for s in range(S):
        d = seg_deg[s]
        ymin = np.inf
        ymax = -np.inf
        for i in range(d + 1):
            y = seg[s, i, 1] / seg[s, i, 2]
            ymin = min(ymin, y)
            ymax = max(ymax, y)
        if d == 1:
            g = 2.0 * tol + 1e-15 * (abs(ymin) + abs(ymax))
        else:
            g = 0.25 * tol
        lo[s] = ymin - g
        hi[s] = ymax + g
        vlo = min(vlo, lo[s])
        vhi = max(vhi, hi[s])
    nb = min(max(4 * S, 1), MAX_BINS)
    w = (vhi - vlo) / nb
    if not (w > 0.0 and np.isfinite(w) and np.isfinite(vlo) and tol > 1e-150):
        nb = 1
        w = np.inf
        vlo = -np.inf
    count = np.zeros(nb + 1, np.int64)
    for s in range(S):
        for k in range(_bin_of(lo[s], vlo, w, nb), _bin_of(hi[s], vlo, w, nb) + 1):
            count[k + 1] += 1
    off = np.cumsum(count)
    items = np.empty(off[nb], np.int64)
    fill = off[:nb].copy()
    for s in range(S):
        for k in range(_bin_of(lo[s], vlo, w, nb), _bin_of(hi[s], vlo, w, nb) + 1):
            items[fill[k]] = s
            fill[k] += 1
    return vlo, w, nb, off, items


@jit
def _bin_of(y, vlo, w, nb):
    """The bin of :func:`trim_bins` holding ``y`` (monotone in ``y``; 0 when ``nb`` is 1)."""
    if nb == 1:
        return 0
    t = (y - vlo) / w
    if not t > 0.0:
        return 0
    if t >= nb - 1:
        return nb - 1
    return int(t)


TREE_NODES = 2048
""":func:`winding_tree` holds at most this many halved trim segments (a face's trims
past them are walked as :func:`.trim._segment_winding` walks them, halving anew)."""


@jit
def winding_tree(seg):
    """Scratch for :func:`_tree_winding`: the halvings of the trim segments ``seg`` (as
    packed by ``Surface.trim_segments``) made so far, kept for the next points.

    ``(root, pieces, box, child, depth, count)``: ``root[s]`` the node of segment ``s``
    (-1 until needed), ``pieces[k]`` a node's control points, ``box[k]`` its
    ``xmin, xmax, ymin, ymax`` and its ends ``x1, y1, x2, y2`` (as
    :func:`.trim._segment_winding` computes them), ``child[k]`` its first half (-1:
    not halved yet; the second half follows it), ``depth[k]`` its halvings from the
    segment, ``count[0]`` the nodes used.  No room when every segment is a line."""
    S = seg.shape[0]
    p1 = seg.shape[1]
    n = TREE_NODES if p1 > 2 else 0
    return (np.full(S, -1, np.int64), np.empty((n, p1, 3)), np.empty((n, 8)),
            np.empty(n, np.int64), np.empty(n, np.int64), np.zeros(1, np.int64))


@jit
def _tree_node(tree, k, deg, d):
    """Fill node ``k``'s box and ends from its control points; depth ``d``, not halved."""
    _root, pieces, box, child, depth, _count = tree
    xmin = np.inf
    xmax = -np.inf
    ymin = np.inf
    ymax = -np.inf
    for i in range(deg + 1):
        x = pieces[k, i, 0] / pieces[k, i, 2]
        y = pieces[k, i, 1] / pieces[k, i, 2]
        xmin = min(xmin, x)
        xmax = max(xmax, x)
        ymin = min(ymin, y)
        ymax = max(ymax, y)
    box[k, 0] = xmin
    box[k, 1] = xmax
    box[k, 2] = ymin
    box[k, 3] = ymax
    box[k, 4] = pieces[k, 0, 0] / pieces[k, 0, 2]
    box[k, 5] = pieces[k, 0, 1] / pieces[k, 0, 2]
    box[k, 6] = pieces[k, deg, 0] / pieces[k, deg, 2]
    box[k, 7] = pieces[k, deg, 1] / pieces[k, deg, 2]
    child[k] = -1
    depth[k] = d


@jit
def _tree_winding(tree, s, Q, deg, px, py, tol, nodes, stack, depths, left, right):
    """``_segment_winding(Q, deg, px, py, tol, ...)`` of trim segment ``s`` (``Q`` its
    control points), the halvings taken from ``tree`` (:func:`winding_tree`) where an
    earlier point made them, else made and kept there.

    The same answer bit for bit: ``_segment_winding`` visits the nodes of one binary
    tree of halvings (de Casteljau at 1/2 of the segment, of its halves, ...), which
    does not depend on the point; a node's pieces, box and ends are computed from its
    parent's pieces by the same operations, its tests are the same comparisons, and
    the answer (the sum of the crossings of the nodes left whole, or on the boundary
    when any node visited is small or deep) does not depend on the order of the
    visits.  ``nodes`` (MAX_DEPTH + 2,) int scratch; a tree out of room walks the
    segment as ``_segment_winding`` does (``stack``, ``depths``, ``left``, ``right``)."""
    root, pieces, box, child, depth, count = tree
    if deg == 1 or pieces.shape[0] == 0:
        return _segment_winding(Q, deg, px, py, tol, stack, depths, left, right)
    r = root[s]
    if r < 0:
        if count[0] + 1 > pieces.shape[0]:
            return _segment_winding(Q, deg, px, py, tol, stack, depths, left, right)
        r = count[0]
        count[0] += 1
        for i in range(deg + 1):
            for c in range(3):
                pieces[r, i, c] = Q[i, c]
        _tree_node(tree, r, deg, 0)
        root[s] = r
    wind = 0
    grow = 0.25 * tol
    nodes[0] = r
    top = 1
    while top > 0:
        top -= 1
        k = nodes[top]
        xmin = box[k, 0]
        xmax = box[k, 1]
        ymin = box[k, 2]
        ymax = box[k, 3]
        if px < xmin - grow or px > xmax + grow or py < ymin - grow or py > ymax + grow:
            y1 = box[k, 5]
            y2 = box[k, 7]
            up = y1 <= py < y2
            down = y2 <= py < y1
            if (up or down) and px < xmin - grow:
                wind += 1 if up else -1
            continue
        if max(xmax - xmin, ymax - ymin) <= grow or depth[k] >= TRIM_MAX_DEPTH:
            return 0, True
        c = child[k]
        if c < 0:
            if count[0] + 2 > pieces.shape[0]:
                return _segment_winding(Q, deg, px, py, tol, stack, depths, left, right)
            c = count[0]
            count[0] += 2
            de_casteljau_split(pieces[k, :deg + 1], 0.5, pieces[c, :deg + 1],
                               pieces[c + 1, :deg + 1])
            _tree_node(tree, c, deg, depth[k] + 1)
            _tree_node(tree, c + 1, deg, depth[k] + 1)
            child[k] = c
        nodes[top] = c + 1
        nodes[top + 1] = c
        top += 2
    return wind, False


@jit
def outside_binned(seg, seg_deg, seg_loop, nloops, u, v, box, tol, bins, winding, stack,
                   depths, left, right, tree, nodes):
    """``Surface.classify_uv((u, v), tol) == OUTSIDE``: outside the domain rectangle
    ``box`` by more than ``tol`` (:func:`_off_domain`), or outside the trim loops
    (``classify_point(...) == OUTSIDE``, the parity of the loops around the point),
    with ``bins = trim_bins(seg, seg_deg, t)`` for some ``t >= tol``: the same answer
    as ``classify_point``, walking only the segments of the bin holding ``v`` (the
    others add nothing, see :func:`trim_bins`), their halvings kept in ``tree``
    (:func:`winding_tree` of ``seg``; ``nodes`` its scratch, :func:`_tree_winding`)
    unless it is None (each point's halvings made anew: cheaper for points that
    need few, as most of :func:`.section_clip.chain_side`'s do); a ``v`` that is not
    finite walks every segment."""
    if _off_domain(u, v, box, tol):
        return True
    if nloops == 0:
        return False
    if not np.isfinite(v):
        return classify_point(seg, seg_deg, seg_loop, nloops, u, v, tol, winding, stack,
                              depths, left, right) == TRIM_OUTSIDE
    vlo, w, nb, off, items = bins
    for k in range(nloops):
        winding[k] = 0
    b = _bin_of(v, vlo, w, nb)
    for r in range(off[b], off[b + 1]):
        s = items[r]
        if tree is None:
            wd, on = _segment_winding(seg[s], seg_deg[s], u, v, tol, stack, depths, left,
                                      right)
        else:
            wd, on = _tree_winding(tree, s, seg[s], seg_deg[s], u, v, tol, nodes, stack,
                                   depths, left, right)
        if on:
            return False      # on the boundary: not outside
        winding[seg_loop[s]] += wd
    inside = 0
    for k in range(nloops):
        if winding[k] != 0:
            inside += 1
    return inside % 2 == 0


@jit
def trim_crossings(Pw, p, q, U, V, plane, a, b, box, ftol, band, wide_tol, seg, seg_deg,
                   seg_loop, nloops, iters, stop):
    """Bisection along the exact curve between inside points ``a`` (n, 2) and outside
    points ``b`` (n, 2), in place: the curve point at the middle (:func:`project` from
    the UV midpoint, the move limited to ``|b - a|``, to ``|f| <= ftol``) replaces
    ``b`` when it is outside the trimmed face (:func:`outside_binned` with the band
    ``band``, or ``wide_tol`` where ``a[i]`` itself is outside with ``band``: inside
    only within the wide band), else ``a``; until ``|b - a| <= stop`` or
    ``iters`` steps.  ``seg``, ``seg_deg``, ``seg_loop``, ``nloops``: the trim loops as
    packed by ``Surface.trim_segments``."""
    bin_ = _binomial_table(D1)
    scr = derivs_scratch(p, q, D1)
    SKL = np.empty((2, 2, 3))
    p1 = seg.shape[1]
    winding = np.empty(max(nloops, 1), dtype=np.int64)
    cstack = np.empty((TRIM_MAX_DEPTH + 2, p1, 3))
    depths = np.empty(TRIM_MAX_DEPTH + 2, dtype=np.int64)
    left = np.empty((p1, 3))
    right = np.empty((p1, 3))
    bins = trim_bins(seg, seg_deg, max(band, wide_tol))
    _trim_crossings_loop(Pw, p, q, U, V, plane, a, b, box, ftol, seg, seg_deg,
                         seg_loop, nloops, iters, stop, band, wide_tol,
                         (bin_, scr, SKL, winding, cstack, depths, left, right, bins,
                          point_scratch(p, q), winding_tree(seg),
                          np.empty(TRIM_MAX_DEPTH + 2, np.int64)))


@jit
def _trim_crossings_loop(Pw, p, q, U, V, plane, a, b, box, ftol, seg, seg_deg,
                         seg_loop, nloops, iters, stop, band, wide_tol, scratch):
    """The loop of :func:`trim_crossings` over borrowed views of its arrays and the
    caller's scratch (no atomic reference counting, :mod:`.numba_ext.borrow`)."""
    Pw, U, V, plane, a, b, box, seg, seg_deg, seg_loop, scratch = borrow_all((
        Pw, U, V, plane, a, b, box, seg, seg_deg, seg_loop, scratch))
    bin_, scr, SKL, winding, cstack, depths, left, right, bins, sp, tree, nodes = scratch
    for i in range(a.shape[0]):
        tol = band
        if outside_binned(seg, seg_deg, seg_loop, nloops, a[i, 0], a[i, 1], box, band, bins,
                          winding, cstack, depths, left, right, tree, nodes):
            tol = wide_tol
        for _ in range(iters):
            du = b[i, 0] - a[i, 0]
            dv = b[i, 1] - a[i, 1]
            mu, mv, _f = _project_point(Pw, p, q, U, V, plane, 0.5 * (a[i, 0] + b[i, 0]),
                                        0.5 * (a[i, 1] + b[i, 1]),
                                        np.sqrt(du * du + dv * dv), box, ftol, 40, bin_,
                                        scr, SKL, sp)
            if outside_binned(seg, seg_deg, seg_loop, nloops, mu, mv, box, tol, bins, winding,
                              cstack, depths, left, right, tree, nodes):
                b[i, 0] = mu
                b[i, 1] = mv
            else:
                a[i, 0] = mu
                a[i, 1] = mv
            du = b[i, 0] - a[i, 0]
            dv = b[i, 1] - a[i, 1]
            if not np.sqrt(du * du + dv * dv) > stop:
                break
