"""Trim polylines for tessellation: one kernel call per surface.

A trim piece ``C(t)`` (a rational 2-D curve) on a surface ``S`` becomes the polyline
through ``C(t_i)``.  Its vertices include every knot where the curve has a corner (and
every knot of a polyline); between them the curve is marched: a segment ``[ta, tb]``
is accepted when the points ``S(C(t))`` (the exact boundary curve) lie within
``curve_tol`` of the 3-D chord ``S(C(ta))``--``S(C(tb))``, the points
``S(C(ta) + f (C(tb) - C(ta)))`` (the image of the UV chord, which the mesh boundary
also follows where it crosses cell edges) within ``chord_tol``, and the curve points
within ``chord_tol`` too or the two largest distances adding up to at most ``pair_tol``
(the mesh boundary, which lies within the second of the chord, then lies within their
sum of the curve; a straight piece inside the domain, whose UV chords map onto the
curve: the curve points within ``curve_tol``), at the quarter points of its part in
each knot span and at the knots it crosses (and, on a curved piece of few spans, at
every point of the knot span's 1/16 grid inside a part longer than a quarter span;
a segment over many spans is first tried at its own quarter points alone); each step is the rest of
the run in equal parts of at most the current step estimate, which a failing part
shrinks by its measured error (chord errors fall with the square of the step) and a
passing one lets grow.  Curve points are clipped to the domain box (trim curves may
stray outside it by the validation tolerance).
"""

from __future__ import annotations

import numpy as np

from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit, jit_inline
from .basis import basis_funs_inline, find_span_inline as find_span
from .surface import surface_point_inline as surface_point

TINY_STEP = 2.0 ** -50
"""A segment this short (a fraction of its knot span) is accepted as it is: the step
has reached rounding."""
MAX_PARTS = 64
"""A failing step shrinks at most this many times."""
SMOOTH_SIN = 1e-9
"""A knot of full multiplicity is crossed by segments when the control polygon's
directions before and after it agree within this sine (the curve is tangent-
continuous there); any other such knot, and every knot of a polyline, is a vertex."""
MAX_BEND = 0.3
"""A segment is split whenever its curve lies more than this times its chord's length
from the chord (an arc of ~120 degrees: ``tan(a / 4) / 2`` for an arc of angle ``a``),
whatever the tolerance: a loop small against the tolerance keeps at least three
edges (a circle of radius ``tol`` became two chords of its diameter, a loop of no area).
Not below a 16th of the run, nor for a curve within ``1e-6 chord_tol`` of its chord
(rounding, as at a pole, where the chord is as short)."""
QUICK_SPANS = 4
"""A segment over at least this many knot spans is first tested at its own quarter
points only (:func:`_quick_gap`): a long first try of a run fails on them at a few
evaluations instead of four a span."""
SPLIT_AIM = 0.8
"""Parts are sized for a predicted chord error of ``SPLIT_AIM`` times the allowed one
(the segment's error in units of ``chord_tol``, :func:`_trim_loop`)."""


@jit
def _curve_at(Pc, pc, Uc, t, lo0, lo1, hi0, hi1, N, left, right):
    """``C(t)`` of a rational 2-D curve (homogeneous ``Pc`` (n, 3)), clipped to the
    box; no allocation (A2.1, A2.2, then the weighted sum)."""
    return _curve_in_span(Pc, pc, Uc, find_span(Pc.shape[0] - 1, pc, t, Uc), t, lo0, lo1,
                          hi0, hi1, N, left, right)


@jit_inline
def _span_of(Pc, pc, Uc, t, span):
    """``find_span`` of ``t`` on the curve, ``span`` itself when ``t`` lies inside it
    above the domain's start (there the binary search finds the same index: the one
    non-empty span holding ``t``)."""
    if Uc[span] <= t < Uc[span + 1] and t > Uc[pc]:
        return span
    return find_span(Pc.shape[0] - 1, pc, t, Uc)


@jit_inline
def _curve_in_span(Pc, pc, Uc, span, t, lo0, lo1, hi0, hi1, N, left, right):
    """:func:`_curve_at` with the knot span of ``t`` known (inlined, as its basis
    functions: the same code)."""
    basis_funs_inline(span, t, pc, Uc, N, left, right)
    x = 0.0
    y = 0.0
    w = 0.0
    for r in range(pc + 1):
        b = N[r]
        x += b * Pc[span - pc + r, 0]
        y += b * Pc[span - pc + r, 1]
        w += b * Pc[span - pc + r, 2]
    return min(max(x / w, lo0), hi0), min(max(y / w, lo1), hi1)


@jit_inline
def _chord_of(Pa, Pb):
    """``(d0, d1, d2, ll)``: the 3-D chord ``Pb - Pa`` and its squared length."""
    d0 = Pb[0] - Pa[0]
    d1 = Pb[1] - Pa[1]
    d2 = Pb[2] - Pa[2]
    return d0, d1, d2, d0 * d0 + d1 * d1 + d2 * d2


@jit_inline
def _chord_gap(X, Pa, d0, d1, d2, ll):
    """Distance of the point ``X`` from the 3-D chord from ``Pa`` along ``d``
    (``ll = |d|^2``)."""
    e0 = X[0] - Pa[0]
    e1 = X[1] - Pa[1]
    e2 = X[2] - Pa[2]
    w = 0.0
    if ll > 0.0:
        w = (e0 * d0 + e1 * d1 + e2 * d2) / ll
        w = min(1.0, max(0.0, w))
    g0 = e0 - w * d0
    g1 = e1 - w * d1
    g2 = e2 - w * d2
    return np.sqrt(g0 * g0 + g1 * g1 + g2 * g2)


@jit_inline
def _smooth_knot(CP, a0, Uc, pc, i):
    """Whether the curve is tangent-continuous at its knot ``Uc[i]`` (first of its
    copies): a multiplicity below the degree, or the control points before and after
    the knot's point (``CP[a0 + i - 1]`` at full multiplicity) in one direction."""
    m = 1
    while i + m < Uc.shape[0] and Uc[i + m] == Uc[i]:
        m += 1
    if m < pc:
        return True
    if m > pc:
        return False
    r = a0 + i - 1
    l0 = CP[r, 0] - CP[r - 1, 0]
    l1 = CP[r, 1] - CP[r - 1, 1]
    r0 = CP[r + 1, 0] - CP[r, 0]
    r1 = CP[r + 1, 1] - CP[r, 1]
    ll = np.sqrt(l0 * l0 + l1 * l1)
    rr = np.sqrt(r0 * r0 + r1 * r1)
    if not (ll > 0.0 and rr > 0.0):
        return False
    return l0 * r0 + l1 * r1 > 0.0 and abs(l0 * r1 - l1 * r0) <= SMOOTH_SIN * ll * rr


@jit
def _segment_gap(Pc, pc, Uc, ta, tb, ua, va, ub, vb, Pa, Pb, dense, uv_chords, lo0, lo1,
                 hi0, hi1, Pw, p, q, U, V, Nc, lc, rc, Nu, Nv, left, right, tmp, X,
                 grid_pts, grid_stamp, stamp):
    """``(curve, chord)``: the largest distance from the 3-D chord ``Pa``--``Pb`` of
    the segment ``[ta, tb]`` (UV ends ``(ua, va)``, ``(ub, vb)``) of the curve's points,
    and (with ``uv_chords``; else 0) of the UV chord's images at the same fractions of
    the segment: on
    each knot span the segment overlaps, at the quarter points of its part there and
    at the knot ending it, and, on a ``dense`` piece where that part is longer than a
    quarter of the span, at the span's 1/16 grid inside it (see
    :func:`trim_polylines`).  ``grid_pts[span, e]``: ``S(C(t))`` at the 1/16 grid
    point ``e`` of the knot span ``span``, valid where ``grid_stamp[span, e] ==
    stamp`` (the piece's number; 0: no cache): a grid point is the same ``t`` in
    every segment (and retry) that holds it, so its point is evaluated once per piece
    (the same bits)."""
    d0, d1, d2, ll = _chord_of(Pa, Pb)
    worst = 0.0
    worst_chord = 0.0
    span = find_span(Pc.shape[0] - 1, pc, ta, Uc)
    k0 = Uc[span]
    while True:
        k1 = Uc[span + 1]
        s0 = max(ta, k0)
        s1 = min(tb, k1)
        h = (k1 - k0) / 16.0
        grid = dense and s1 - s0 > 4.0 * h  # (a part of at most a quarter span: its
        for e in range(1, 20):              # quarter points are as dense as the grid)
            if e < 4:
                t = s0 + (s1 - s0) * (0.25 * e)
            elif e == 4:
                if s1 >= tb:
                    continue  # the segment's end: a chord end
                t = s1  # the knot ending the part
            else:
                if not grid:
                    break
                t = k0 + (e - 4) * h
                if t <= s0:
                    continue
                if t >= s1:
                    break
            if e > 4 and stamp > 0 and grid_stamp[span, e - 4] == stamp:
                X[0] = grid_pts[span, e - 4, 0]
                X[1] = grid_pts[span, e - 4, 1]
                X[2] = grid_pts[span, e - 4, 2]
            else:
                su, sv = _curve_in_span(Pc, pc, Uc, _span_of(Pc, pc, Uc, t, span), t, lo0,
                                        lo1, hi0, hi1, Nc, lc, rc)
                surface_point(Pw, p, q, U, V, su, sv, Nu, Nv, left, right, tmp, X)
                if e > 4 and stamp > 0:
                    grid_stamp[span, e - 4] = stamp
                    grid_pts[span, e - 4, 0] = X[0]
                    grid_pts[span, e - 4, 1] = X[1]
                    grid_pts[span, e - 4, 2] = X[2]
            worst = max(worst, _chord_gap(X, Pa, d0, d1, d2, ll))
            if uv_chords:
                f = (t - ta) / (tb - ta)
                surface_point(Pw, p, q, U, V, ua + (ub - ua) * f, va + (vb - va) * f, Nu,
                              Nv, left, right, tmp, X)
                worst_chord = max(worst_chord, _chord_gap(X, Pa, d0, d1, d2, ll))
        if s1 >= tb:
            break
        span += 1
        while Uc[span + 1] <= k1:
            span += 1
        k0 = k1
    return worst, worst_chord


@jit_inline
def _spans_over(Uc, pc, ta, tb, most):
    """How many non-empty knot spans the segment ``[ta, tb]`` overlaps, counted up to
    ``most``."""
    span = find_span(Uc.shape[0] - pc - 2, pc, ta, Uc)
    k = 1
    while k < most and Uc[span + 1] < tb:
        span += 1
        if Uc[span + 1] > Uc[span]:
            k += 1
    return k


@jit
def _quick_gap(Pc, pc, Uc, ta, tb, ua, va, ub, vb, Pa, Pb, uv_chords, lo0, lo1, hi0, hi1,
               Pw, p, q, U, V, Nc, lc, rc, Nu, Nv, left, right, tmp, X):
    """:func:`_segment_gap` at the segment's own quarter points only: ``(curve,
    chord)``, each at most the full test's would be with these points added."""
    d0, d1, d2, ll = _chord_of(Pa, Pb)
    worst = 0.0
    worst_chord = 0.0
    for e in range(1, 4):
        f = 0.25 * e
        su, sv = _curve_at(Pc, pc, Uc, ta + (tb - ta) * f, lo0, lo1, hi0, hi1, Nc, lc, rc)
        surface_point(Pw, p, q, U, V, su, sv, Nu, Nv, left, right, tmp, X)
        worst = max(worst, _chord_gap(X, Pa, d0, d1, d2, ll))
        if uv_chords:
            surface_point(Pw, p, q, U, V, ua + (ub - ua) * f, va + (vb - va) * f, Nu, Nv,
                          left, right, tmp, X)
            worst_chord = max(worst_chord, _chord_gap(X, Pa, d0, d1, d2, ll))
    return worst, worst_chord


@jit_inline
def _bent(gc, Pa, Pb):
    """Whether a segment whose curve lies up to ``gc`` from its 3-D chord ``Pa``--``Pb``
    turns too far to stand for it: ``gc > MAX_BEND |Pb - Pa|`` (a chord of length 0
    with the curve off it: a closed piece's first try)."""
    return gc * gc > MAX_BEND * MAX_BEND * _chord_of(Pa, Pb)[3]


@jit_inline
def _emit(out, n, t, u, v):
    """Row ``n`` of ``out`` set to ``(t, u, v)``: ``n + 1``, or -1 when ``out`` is full."""
    if n >= out.shape[0]:
        return -1
    out[n, 0] = t
    out[n, 1] = u
    out[n, 2] = v
    return n + 1


@jit
def trim_polylines(CP, W, K, deg, cp_off, k_off, dense_spans, lo0, lo1, hi0, hi1, Pw, p, q,
                   U, V, curve_tol, chord_tol, pair_tol, uv_chords, cross_knots, out,
                   counts, grid_cache):
    """Polylines of many trim pieces on one surface, in one call.

    Piece ``c`` has degree ``deg[c]``, control points ``CP[cp_off[c]:cp_off[c+1]]``
    (n, 2) with weights ``W[...]`` and knots ``K[k_off[c]:k_off[c+1]]``.  Each piece
    keeps as vertices its knots (with ``cross_knots``, only those where it is not
    tangent-continuous, :func:`_smooth_knot`, and every knot of a polyline; without,
    every edge of the polyline lies on one knot span of its piece, which the
    projector's certificate boxes need) and is marched between them (see
    the module docstring); a segment is tested at its parts' quarter points in every
    knot span it overlaps and at the knots it crosses (:func:`_segment_gap`).  A segment
    ``[ta, tb]`` is accepted when the curve points ``S(C(t))`` are within ``curve_tol``
    of the 3-D chord, the UV-chord points (``uv_chords``; False for a surface that is
    an affine map of its parameters, where they lie on the 3-D chord) within
    ``chord_tol``, and the curve points within ``chord_tol`` too or the two largest
    distances adding up to at most ``pair_tol`` (``curve_tol = chord_tol``: each within
    ``chord_tol``; a straight piece inside the domain is its own UV chord's image: its
    curve points within ``curve_tol``), at its quarter points and, for a curved piece of at most
    ``dense_spans``
    spans, when the segment is longer than a quarter of its knot span, at every point
    of the span's 1/16 grid inside it: sample spacing at most 1/16 of the span on every
    segment, as when such pieces started from 5 seeds a span and checked quarter
    points (the route before, which put 1.2-1.7x the points on gentle curves).  A
    failing segment shortens the step by its measured error (see the module
    docstring).  A degree-1 non-rational piece with distinct knots keeps its control
    points exactly as its seeds (``C(t_i) = P_i``).

    Writes ``(t, u, v)`` rows into ``out`` piece after piece (each piece from its
    first knot to its last), ``counts[c]`` rows for piece ``c``; returns the row
    count, or -1 when ``out`` is too small (call again with a larger one).  The
    scratch is made here, the work done by :func:`_trim_loop` on borrowed views;
    ``grid_cache``: each grid point's ``S(C(t))`` evaluated once per piece (False:
    at every test, the route before; the same output)."""
    mm = max(p, q) + 1
    mc = 1
    ncp = 1
    nk = 1
    for c in range(deg.shape[0]):
        mc = max(mc, deg[c] + 1)
        ncp = max(ncp, cp_off[c + 1] - cp_off[c])
        nk = max(nk, k_off[c + 1] - k_off[c])
    scratch = (np.empty(p + 1), np.empty(q + 1), np.empty(mm), np.empty(mm), np.empty(4),
               np.empty(3), np.empty(3), np.empty(3), np.empty((ncp, 3)), np.empty(mc),
               np.empty(mc), np.empty(mc), np.empty((nk, 16, 3)),
               np.zeros((nk, 16), dtype=np.int64))
    return _trim_loop(CP, W, K, deg, cp_off, k_off, dense_spans, lo0, lo1, hi0, hi1, Pw,
                      p, q, U, V, curve_tol, chord_tol, pair_tol, uv_chords, cross_knots, out,
                      counts, scratch, grid_cache)


@jit
def _trim_loop(CP, W, K, deg, cp_off, k_off, dense_spans, lo0, lo1, hi0, hi1, Pw, p, q,
               U, V, curve_tol, chord_tol, pair_tol, uv_chords, cross_knots, out, counts,
               scratch, grid_cache):
    """The loop of :func:`trim_polylines` over borrowed views (no atomic reference
    counting in the many evaluations, :mod:`.numba_ext.borrow`); ``scratch`` holds
    the surface's and the pieces' evaluation arrays (the pieces' at their largest
    degree and control point count)."""
    CP, W, K, deg, cp_off, k_off, Pw, U, V, out, counts = borrow_all(
        (CP, W, K, deg, cp_off, k_off, Pw, U, V, out, counts))
    Nu, Nv, left, right, tmp, Pa, Pb, X, Pbuf, Nc, lc, rc, grid_pts, grid_stamp = \
        borrow_all(scratch)
    n = 0
    to_curve = chord_tol / curve_tol  # (1 exactly when curve_tol = chord_tol: the test of
    to_pair = chord_tol / pair_tol    # each within chord_tol)
    for c in range(deg.shape[0]):
        pc = deg[c]
        a0 = cp_off[c]
        ncp = cp_off[c + 1] - a0
        Pc = Pbuf[:ncp]
        rational = False
        for r in range(ncp):
            w = W[a0 + r]
            Pc[r, 0] = CP[a0 + r, 0] * w
            Pc[r, 1] = CP[a0 + r, 1] * w
            Pc[r, 2] = w
            if w != 1.0:
                rational = True
        Uc = K[k_off[c]:k_off[c + 1]]
        stamp = c + 1 if grid_cache else 0
        kend = Uc.shape[0] - pc  # the domain's knots: Uc[pc:kend]
        spans = 0
        for j in range(pc + 1, kend):
            if Uc[j] > Uc[j - 1]:
                spans += 1
        polyline = pc == 1 and not rational
        exact = polyline and spans == ncp - 1  # seeds are the control points
        # a straight piece inside the domain box (not clipped) is its own UV chord: the
        # chord points would be the curve points again
        chords = uv_chords
        if polyline:
            inside = True
            for r in range(ncp):
                x = CP[a0 + r, 0]
                y = CP[a0 + r, 1]
                if not (lo0 <= x <= hi0 and lo1 <= y <= hi1):
                    inside = False
            chords = uv_chords and not inside
        own_chord = uv_chords and not chords
        dense = (not polyline) and spans <= dense_spans
        start = n
        ta = Uc[pc]
        if exact:
            ua = min(max(CP[a0, 0], lo0), hi0)
            va = min(max(CP[a0, 1], lo1), hi1)
        else:
            ua, va = _curve_at(Pc, pc, Uc, ta, lo0, lo1, hi0, hi1, Nc, lc, rc)
        surface_point(Pw, p, q, U, V, ua, va, Nu, Nv, left, right, tmp, Pa)
        seed = 0
        i = pc + 1
        while i < kend:
            if not Uc[i] > Uc[i - 1]:
                i += 1
                continue
            # the run [A, B]: from here over the knots the curve is smooth across (a
            # polyline stops at every knot: its corners stay vertices)
            seed += 1
            A = ta
            while (cross_knots and not polyline and i < kend - 1
                   and _smooth_knot(CP, a0, Uc, pc, i)):
                i += 1
                while i < kend and not Uc[i] > Uc[i - 1]:
                    i += 1
            B = Uc[i]
            i += 1
            if exact:
                ub = min(max(CP[a0 + seed, 0], lo0), hi0)
                vb = min(max(CP[a0 + seed, 1], lo1), hi1)
            else:
                ub, vb = _curve_at(Pc, pc, Uc, B, lo0, lo1, hi0, hi1, Nc, lc, rc)
            surface_point(Pw, p, q, U, V, ub, vb, Nu, Nv, left, right, tmp, Pb)
            # march from A to B: each step is the rest of the run in equal parts of at
            # most `step`, the first part tested (:func:`_segment_gap`); a failing part
            # shrinks `step` by its measured error (chord errors fall with the square
            # of the step), a passing one is emitted and lets `step` grow by its margin
            ue = ub
            ve = vb
            e0 = Pb[0]
            e1 = Pb[1]
            e2 = Pb[2]
            tiny = (B - A) * TINY_STEP
            step = B - A
            while ta < B:
                rest = B - ta
                parts = max(1, int(np.ceil(rest / step - 1e-9)))
                tb = ta + rest / parts if parts > 1 else B
                if tb >= B:
                    tb = B
                    ub = ue
                    vb = ve
                    Pb[0] = e0
                    Pb[1] = e1
                    Pb[2] = e2
                else:
                    ub, vb = _curve_at(Pc, pc, Uc, tb, lo0, lo1, hi0, hi1, Nc, lc, rc)
                    surface_point(Pw, p, q, U, V, ub, vb, Nu, Nv, left, right, tmp, Pb)
                # a segment over many spans is tried at its quarter points first
                quick = _spans_over(Uc, pc, ta, tb, QUICK_SPANS) >= QUICK_SPANS
                while True:
                    if quick:
                        gc, gu = _quick_gap(Pc, pc, Uc, ta, tb, ua, va, ub, vb, Pa, Pb,
                                            chords, lo0, lo1, hi0, hi1, Pw, p, q, U, V,
                                            Nc, lc, rc, Nu, Nv, left, right, tmp, X)
                    else:
                        gc, gu = _segment_gap(Pc, pc, Uc, ta, tb, ua, va, ub, vb, Pa, Pb,
                                              dense, chords, lo0, lo1, hi0, hi1, Pw, p, q,
                                              U, V, Nc, lc, rc, Nu, Nv, left, right, tmp, X,
                                              grid_pts, grid_stamp, stamp)
                    # the error in units of chord_tol: the image within it, the curve
                    # within curve_tol and within it or the pair within pair_tol; a piece
                    # that is its own UV chord (the mesh boundary's points all on the
                    # curve): the curve within curve_tol
                    if own_chord:
                        worst = gc * to_curve
                    else:
                        worst = max(max(gc * to_curve, gu), min(gc, (gc + gu) * to_pair))
                    bend = (gc > 1e-6 * chord_tol and 16.0 * (tb - ta) > B - A
                            and _bent(gc, Pa, Pb))
                    fail = (worst > chord_tol or bend) and tb - ta > tiny
                    if fail or not quick:
                        break
                    quick = False
                if fail:
                    r = np.sqrt(SPLIT_AIM * chord_tol / worst) if worst > chord_tol else 1.0
                    if bend:
                        r = min(r, 0.5)
                    step = (tb - ta) * min(max(r, 1.0 / MAX_PARTS), 0.9)
                    continue
                n = _emit(out, n, ta, ua, va)
                if n < 0:
                    return -1
                grow = 2.0 if not worst > 0.0 else min(max(
                    np.sqrt(SPLIT_AIM * chord_tol / worst), 1.0), 2.0)
                step = max(step, (tb - ta) * grow)
                ta = tb
                ua = ub
                va = vb
                Pa[0] = Pb[0]
                Pa[1] = Pb[1]
                Pa[2] = Pb[2]
        n = _emit(out, n, ta, ua, va)
        if n < 0:
            return -1
        counts[c] = n - start
    return n


@jit
def domain_rectangle_gap(CP, deg, cp_off, loop_first, u0, u1, v0, v1, hi):
    """How far the trim loops' control polygons are from the domain rectangle's edges
    (see :func:`geomkit.mesh.trim_polylines.domain_rectangle_only`): the largest of,
    over the loops (pieces ``loop_first[i]:loop_first[i+1]``, control points
    ``CP[cp_off[c]:cp_off[c+1]]``), a degree-1 segment's distance from its nearest
    edge line (both ends), a curved piece's largest distance from its nearest edge
    line (all its control points), and the loop's shoelace area's shortfall from the
    rectangle's, divided by ``u1 - u0 + v1 - v0``.  ``inf`` as soon as a piece starts
    more than ``hi`` from every edge line or a loop's value exceeds ``hi``."""
    for c in range(deg.shape[0]):
        x = CP[cp_off[c], 0]
        y = CP[cp_off[c], 1]
        if min(abs(x - u0), abs(x - u1), abs(y - v0), abs(y - v1)) > hi:
            return np.inf
    full = (u1 - u0) * (v1 - v0)
    worst = 0.0
    for i in range(loop_first.shape[0] - 1):
        a = cp_off[loop_first[i]]
        b = cp_off[loop_first[i + 1]]
        for c in range(loop_first[i], loop_first[i + 1]):
            if deg[c] > 1:  # all its control points near one edge line
                m0 = 0.0
                m1 = 0.0
                m2 = 0.0
                m3 = 0.0
                for r in range(cp_off[c], cp_off[c + 1]):
                    m0 = max(m0, abs(CP[r, 0] - u0))
                    m1 = max(m1, abs(CP[r, 0] - u1))
                    m2 = max(m2, abs(CP[r, 1] - v0))
                    m3 = max(m3, abs(CP[r, 1] - v1))
                worst = max(worst, min(min(m0, m1), min(m2, m3)))
            else:  # each segment within the piece on one edge line (both ends)
                for r in range(cp_off[c], cp_off[c + 1] - 1):
                    s0 = max(abs(CP[r, 0] - u0), abs(CP[r + 1, 0] - u0))
                    s1 = max(abs(CP[r, 0] - u1), abs(CP[r + 1, 0] - u1))
                    s2 = max(abs(CP[r, 1] - v0), abs(CP[r + 1, 1] - v0))
                    s3 = max(abs(CP[r, 1] - v1), abs(CP[r + 1, 1] - v1))
                    worst = max(worst, min(min(s0, s1), min(s2, s3)))
        area = CP[b - 1, 0] * CP[a, 1] - CP[a, 0] * CP[b - 1, 1]
        for r in range(a, b - 1):
            area += CP[r, 0] * CP[r + 1, 1] - CP[r + 1, 0] * CP[r, 1]
        worst = max(worst, abs(0.5 * abs(area) - full) / (u1 - u0 + v1 - v0))
        if worst > hi:
            return np.inf
    return worst


@jit
def loop_rectangle_gap(pts, u0, u1, v0, v1):
    """``(gap, area_gap)`` of a closed UV polyline ``pts`` (k, 2): the largest distance
    of a point from its nearest domain edge line, and ``|area - (u1 - u0)(v1 - v0)|``
    (shoelace area): the loop is the domain rectangle within ``eps`` when ``gap <=
    eps`` and ``area_gap <= eps (u1 - u0 + v1 - v0)``."""
    gap = 0.0
    area = 0.0
    for i in range(pts.shape[0]):
        x = pts[i, 0]
        y = pts[i, 1]
        gap = max(gap, min(min(abs(x - u0), abs(x - u1)), min(abs(y - v0), abs(y - v1))))
        if i + 1 < pts.shape[0]:
            area += x * pts[i + 1, 1] - pts[i + 1, 0] * y
    return gap, abs(0.5 * abs(area) - (u1 - u0) * (v1 - v0))


@jit
def rectangle_of(pts, chord_tol, P, Pw, p, q, U, V):
    """:meth:`geomkit.mesh.trim_polylines.TrimPolylines.rectangle` of the closed UV
    polyline ``pts`` on the surface ``P``, ``Pw``, ``p``, ``q``, ``U``, ``V``: ``(ok, a0,
    a1, b0, b1)``, its bounding box when every point lies within ``eps`` of the box's
    edge lines and its area within ``eps`` times the perimeter of the box's, for ``eps``
    ``1e-6`` of the box's size and the domain rectangle test's ``domain_eps`` (the
    surface's :func:`speed_bound_of`, taken only then)."""
    a0 = np.inf
    b0 = np.inf
    a1 = -np.inf
    b1 = -np.inf
    for i in range(pts.shape[0]):
        a0 = min(a0, pts[i, 0])
        a1 = max(a1, pts[i, 0])
        b0 = min(b0, pts[i, 1])
        b1 = max(b1, pts[i, 1])
    size_uv = max(a1 - a0, b1 - b0)
    if not size_uv > 0:
        return False, a0, a1, b0, b1
    gap, area_gap = loop_rectangle_gap(pts, a0, a1, b0, b1)
    hi = 1e-6 * size_uv
    perimeter = a1 - a0 + b1 - b0
    if not (gap <= hi and area_gap <= hi * perimeter):
        return False, a0, a1, b0, b1
    speed = speed_bound_of(P, Pw, p, q, U, V)
    eps = max(min(1e-6 * size_uv, 1e-3 * chord_tol / max(speed, 1e-300)), 1e-12 * size_uv)
    return gap <= eps and area_gap <= eps * perimeter, a0, a1, b0, b1


@jit
def line_rectangle_of(CP, W, K, deg, cp_off, k_off, loop_first, u0, u1, v0, v1, chord_tol,
                      P, Pw, p, q, U, V):
    """:func:`geomkit.mesh.trim_polylines.line_rectangle` in one call: ``(ok, a0, a1, b0,
    b1)`` for a single loop of straight pieces (degree 1, unit weights, distinct knots),
    its control polygon (clipped to the domain) tested by :func:`rectangle_of`; not
    ``ok`` for other loops or one within ``1e-6`` of the domain rectangle."""
    if loop_first.shape[0] != 2:
        return False, 0.0, 0.0, 0.0, 0.0
    m = deg.shape[0]
    for c in range(m):
        if deg[c] != 1:
            return False, 0.0, 0.0, 0.0, 0.0
    for i in range(W.shape[0]):
        if W[i] != 1.0:
            return False, 0.0, 0.0, 0.0, 0.0
    for c in range(m):  # distinct knots: the control points are the vertices
        for j in range(k_off[c] + 1, k_off[c + 1] - 2):
            if not K[j + 1] > K[j]:
                return False, 0.0, 0.0, 0.0, 0.0
    n = CP.shape[0] - m + 1
    pts = np.empty((n, 2))
    r = 0
    c = 1
    for i in range(CP.shape[0]):
        if r == n - 1:
            break
        if c < m and i == cp_off[c]:  # each later piece's first point: the last one's end
            c += 1
            continue
        pts[r, 0] = min(max(CP[i, 0], u0), u1)
        pts[r, 1] = min(max(CP[i, 1], v0), v1)
        r += 1
    pts[n - 1, 0] = pts[0, 0]  # closed exactly
    pts[n - 1, 1] = pts[0, 1]
    size_uv = max(u1 - u0, v1 - v0)
    gap, area_gap = loop_rectangle_gap(pts, u0, u1, v0, v1)
    if gap <= 1e-6 * size_uv and area_gap <= 1e-6 * size_uv * (u1 - u0 + v1 - v0):
        return False, 0.0, 0.0, 0.0, 0.0
    return rectangle_of(pts, chord_tol, P, Pw, p, q, U, V)


@jit
def speed_bound_of(P, Pw, p, q, U, V):
    """:func:`geomkit.mesh.trim_polylines.speed_bound` of the surface with control
    points ``P`` (nu, nv, 3), homogeneous net ``Pw`` (its weights ``Pw[..., 3]``) and
    knots ``U``, ``V``: ``sum over u, v of 4 deg (w_max / w_min) D / h`` (``D`` the net's
    box diagonal, ``h`` the shortest non-empty knot span)."""
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    wmin = np.inf
    wmax = -np.inf
    for i in range(P.shape[0]):
        for j in range(P.shape[1]):
            for k in range(3):
                lo[k] = min(lo[k], P[i, j, k])
                hi[k] = max(hi[k], P[i, j, k])
            wmin = min(wmin, Pw[i, j, 3])
            wmax = max(wmax, Pw[i, j, 3])
    d0 = hi[0] - lo[0]
    d1 = hi[1] - lo[1]
    d2 = hi[2] - lo[2]
    D = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    ratio = wmax / wmin
    total = 0.0
    for deg, K in ((p, U), (q, V)):
        h = np.inf
        for i in range(K.shape[0] - 1):
            d = K[i + 1] - K[i]
            if d > 0.0:
                h = min(h, d)
        total += 4.0 * deg * ratio * D / h
    return total


@jit
def speed_bounds(P, Pw, pw_off, nets, U, u_off, V, v_off, faces):
    """:func:`speed_bound_of` of each face ``faces[i]`` of flat nets (face ``f``: the
    rows ``pw_off[f]:pw_off[f+1]`` of its Cartesian control points ``P`` (n, 3) and
    homogeneous ones ``Pw`` (n, 4), ``nets[f] = (nu, nv, p, q)``, knots
    ``U[u_off[f]:u_off[f+1]]``, ``V[v_off[f]:v_off[f+1]]``), in one call."""
    out = np.empty(faces.shape[0])
    for i in range(faces.shape[0]):
        f = faces[i]
        a = pw_off[f]
        b = pw_off[f + 1]
        shape = (nets[f, 0], nets[f, 1])
        out[i] = speed_bound_of(np.ascontiguousarray(P[a:b]).reshape(shape + (3,)),
                                np.ascontiguousarray(Pw[a:b]).reshape(shape + (4,)),
                                nets[f, 2], nets[f, 3], U[u_off[f]:u_off[f + 1]],
                                V[v_off[f]:v_off[f + 1]])
    return out
