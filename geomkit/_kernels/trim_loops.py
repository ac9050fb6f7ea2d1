"""Trim loop validation kernels: a loop's points (every piece in one call), its
enclosed area with a test that it is more than two points (a degenerate loop), and
all of a loop's checks in one call (its joins, its control points in the domain).

:func:`geomkit.nurbs.trims.check_loop` validates every loop of every surface built
(a STEP part: thousands), where numpy's per-call costs were most of the work.
"""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit_exact, jit_plain as jit
from .basis import basis_funs_inline, find_span_inline
from .surface import point_scratch, surface_point


@jit
def _piece_is_polyline(W, r0, r1, p):
    if p != 1:
        return False
    for r in range(r0, r1):
        if W[r] != 1.0:
            return False
    return True


@jit
def _rational_point(Q, W, r0, n, p, U, u0, nu, t, N, left, right, out, k):
    """``out[k]`` = the piece (rows ``r0:r0+n`` of ``Q``, ``W``; knots
    ``U[u0:u0+nu]``) at ``t`` (A2.1, A2.2 and the weighted sum)."""
    Uk = U[u0:u0 + nu]
    span = find_span_inline(n - 1, p, t, Uk)
    basis_funs_inline(span, t, p, Uk, N, left, right)
    x = y = w = 0.0
    for r in range(p + 1):
        row = r0 + span - p + r
        c = N[r] * W[row]
        x += c * Q[row, 0]
        y += c * Q[row, 1]
        w += c
    out[k, 0] = x / w
    out[k, 1] = y / w


@jit
def _per_span(per, spans):
    """Parameters a span of a curved piece of ``spans`` spans gets: ``per``, fewer on a
    piece of more than two spans (at least ``2 per`` over the piece and 2 a span, at
    most ``per``): a quintic of a hundred spans is sampled at 2 a span, not 24."""
    return min(per, max(2, (2 * per + spans - 1) // max(spans, 1)))


@jit
def loop_points(Q, W, off, deg, U, uoff, per):
    """Points along a trim loop's pieces in one call (2-D control points ``Q`` and
    weights ``W`` of piece i in rows ``off[i]:off[i+1]``, its knots
    ``U[uoff[i]:uoff[i+1]]``, its degree ``deg[i]``): a polyline piece's own points
    (degree 1, weights 1), a curved piece at ``per`` evenly spaced parameters a
    non-empty span (:func:`_per_span`: fewer on a piece of many spans) and at its end (what :func:`geomkit.nurbs.trims.loop_samples`
    returns)."""
    m = deg.shape[0]
    total = 0
    pmax = 1
    for i in range(m):
        p = deg[i]
        pmax = max(pmax, p)
        if _piece_is_polyline(W, off[i], off[i + 1], p):
            total += off[i + 1] - off[i]
            continue
        spans = 0
        for j in range(uoff[i] + p, uoff[i + 1] - p - 1):
            if U[j + 1] > U[j]:
                spans += 1
        total += spans * _per_span(per, spans) + 1
    out = np.empty((total, 2))
    N = np.empty(pmax + 1)
    left = np.empty(pmax + 1)
    right = np.empty(pmax + 1)
    _fill_points(Q, W, off, deg, U, uoff, per, out, N, left, right)
    return out


@jit
def _fill_points(Q, W, off, deg, U, uoff, per, out, N, left, right):
    """The points of :func:`loop_points` into ``out``, over borrowed views (no atomic
    reference counting in the per-point knot slices, :mod:`.numba_ext.borrow`)."""
    Q, W, off, deg, U, uoff, out, N, left, right = borrow_all((
        Q, W, off, deg, U, uoff, out, N, left, right))
    m = deg.shape[0]
    k = 0
    for i in range(m):
        p, r0, n = deg[i], off[i], off[i + 1] - off[i]
        u0, nu = uoff[i], uoff[i + 1] - uoff[i]
        if _piece_is_polyline(W, r0, r0 + n, p):
            for r in range(r0, r0 + n):
                out[k, 0] = Q[r, 0]
                out[k, 1] = Q[r, 1]
                k += 1
            continue
        spans = 0
        for j in range(u0 + p, u0 + nu - p - 1):
            if U[j + 1] > U[j]:
                spans += 1
        pp = _per_span(per, spans)
        for j in range(u0 + p, u0 + nu - p - 1):
            a, b = U[j], U[j + 1]
            if not b > a:
                continue
            for q in range(pp):
                _rational_point(Q, W, r0, n, p, U, u0, nu, a + (b - a) * (q / pp), N,
                                left, right, out, k)
                k += 1
        _rational_point(Q, W, r0, n, p, U, u0, nu, U[u0 + nu - 1], N, left, right, out, k)
        k += 1


@jit
def loop_area_spread(P, close):
    """``(area, spread)`` of the closed polygon ``P`` (m, 2): its signed area
    (shoelace, the closing edge included) and whether its points rounded to the grid
    of step ``close`` hold at least three distinct values (not all of the loop within
    two grid cells)."""
    m = P.shape[0]
    s = 0.0
    for i in range(m):
        j = i + 1 if i + 1 < m else 0
        s += P[i, 0] * P[j, 1] - P[j, 0] * P[i, 1]
    a0 = np.rint(P[0, 0] / close)
    b0 = np.rint(P[0, 1] / close)
    second = False
    a1 = b1 = 0.0
    spread = False
    for i in range(1, m):
        a = np.rint(P[i, 0] / close)
        b = np.rint(P[i, 1] / close)
        if a == a0 and b == b0:
            continue
        if not second:
            a1, b1, second = a, b, True
        elif not (a == a1 and b == b1):
            spread = True
            break
    return 0.5 * s, spread


@jit
def loop_joins(Q, off, box):
    """``(gaps, inside)`` of a loop's pieces (2-D control points of piece i in rows
    ``off[i]:off[i+1]`` of ``Q``): the distance from each piece's end to the next
    one's start (the last piece's to the first's) and whether every control point
    lies in ``box`` (u0, u1, v0, v1)."""
    m = off.shape[0] - 1
    gaps = np.empty(m)
    for i in range(m):
        e = off[i + 1] - 1
        s = off[i + 1] if i + 1 < m else 0
        gaps[i] = np.hypot(Q[e, 0] - Q[s, 0], Q[e, 1] - Q[s, 1])
    inside = True
    for r in range(Q.shape[0]):
        if not (Q[r, 0] >= box[0] and Q[r, 0] <= box[1] and Q[r, 1] >= box[2]
                and Q[r, 1] <= box[3]):
            inside = False
            break
    return gaps, inside


@jit_exact
def shifted_points(Q, w, d):
    """A trim curve's control points ``Q`` (n, 2) moved by ``d`` (2,) as
    :func:`geomkit.cad.loops.shift` moves them (``Q + d``, then ``* w / w`` unless every
    weight ``w`` is 1): ``(points, unit, finite)`` with ``finite`` whether every
    ``Q + d`` is (a reader shifts a band's pieces by a period one call each)."""
    n = Q.shape[0]
    unit = True
    for i in range(n):
        if w[i] != 1.0:
            unit = False
            break
    out = np.empty((n, 2))
    finite = True
    for i in range(n):
        for k in range(2):
            x = Q[i, k] + d[k]
            finite = finite and math.isfinite(x)
            out[i, k] = x if unit else x * w[i] / w[i]
    return out, unit, finite


@jit_exact
def box_clip(P, u0, u1, v0, v1):
    """A trim curve's control points ``P`` (n, 2) against the box ``[u0, u1] x [v0,
    v1]``: ``(inside, Q, moved)``, ``inside`` whether every point lies in it (none
    NaN), ``Q`` the points clipped as ``np.clip`` clips each column (NaN kept; the
    point itself where it is not strictly beyond a bound, as numpy keeps it)
    and ``moved`` the largest ``|Q - P|`` (NaN when one is): the numpy route of
    :func:`geomkit.cad.loops.clip_to_domain` in one call."""
    n = P.shape[0]
    Q = np.empty((n, 2))
    inside = True
    moved = 0.0
    nan = False
    for i in range(n):
        for k in range(2):
            x = P[i, k]
            lo = u0 if k == 0 else v0
            hi = u1 if k == 0 else v1
            if not (x >= lo and x <= hi):
                inside = False
            if x != x:
                q = x
            else:
                q = lo if x < lo else x
                q = hi if q > hi else q
            Q[i, k] = q
            d = abs(q - x)
            if d != d:
                nan = True
            elif d > moved:
                moved = d
    return inside, Q, math.nan if nan else moved


@jit
def loop_check(Q, W, off, deg, U, uoff, per, close, box):
    """What :func:`geomkit.nurbs.trims.check_loop` tests, in one call over a loop
    packed as :func:`loop_points` takes it: ``(i, gap, inside, area, spread)`` with
    ``i`` the first piece whose end is more than ``close`` from the next piece's start
    (``gap`` that distance; -1 when none), whether every control point lies in
    ``box`` (u0, u1, v0, v1) (:func:`loop_joins`) and :func:`loop_area_spread` of the
    loop's points."""
    gaps, inside = loop_joins(Q, off, box)
    first, gap = -1, 0.0
    for i in range(gaps.shape[0]):
        if gaps[i] > close:
            first, gap = i, gaps[i]
            break
    area, spread = loop_area_spread(loop_points(Q, W, off, deg, U, uoff, per), close)
    return first, gap, inside, area, spread


@jit
def polyline_knots(P):
    """A polyline's vertices ``P`` (n, 2) as a degree-1 trim curve: ``(status, Q,
    U)`` with ``Q`` the vertices without repeats (a vertex equal to the one before
    it is dropped) and ``U`` (m + 2,) the clamped chord-length knots ``[0, t, 1]``,
    ``t`` the cumulative segment lengths over the total.  ``status`` 1: a
    non-finite coordinate; 2: fewer than two distinct vertices (``Q``, ``U``
    empty).  The values of numpy's ``hypot`` / ``cumsum`` / division route, in one
    call (a reader builds hundreds of short polylines)."""
    n = P.shape[0]
    empty = np.empty((0, 2))
    for i in range(n):
        if not (math.isfinite(P[i, 0]) and math.isfinite(P[i, 1])):
            return 1, empty, np.empty(0)
    idx = np.empty(n, np.int64)
    m = 0
    for i in range(n):
        if i == 0 or math.hypot(P[i, 0] - P[i - 1, 0], P[i, 1] - P[i - 1, 1]) > 0:
            idx[m] = i
            m += 1
    if m < 2:
        return 2, empty, np.empty(0)
    Q = np.empty((m, 2))
    for k in range(m):
        Q[k, 0] = P[idx[k], 0]
        Q[k, 1] = P[idx[k], 1]
    t = np.empty(m)
    t[0] = 0.0
    acc = 0.0
    for k in range(1, m):
        acc += math.hypot(Q[k, 0] - Q[k - 1, 0], Q[k, 1] - Q[k - 1, 1])
        t[k] = acc
    U = np.empty(m + 2)
    U[0] = 0.0
    for k in range(m):
        U[k + 1] = t[k] / t[m - 1]
    U[m + 1] = 1.0
    return 0, Q, U


@jit_exact
def segment_spread(Pw, p, q, U, V, a0, a1, b0, b1, u0, u1, v0, v1, samples):
    """How far the straight UV segment from ``(a0, a1)`` to ``(b0, b1)``, sampled at
    ``samples`` evenly spaced points (``(1 - s) a + s b``, clamped to the domain
    ``[u0, u1] x [v0, v1]``), strays in 3-D from one of its ends: the least over the
    two ends of the largest distance of a sample from that end (a pole or a
    degenerate edge maps to one point: 0).  numpy's values (no contraction here; the
    points are :func:`~geomkit._kernels.surface.surface_point`'s)."""
    Nu, Nv, left, right, tmp = point_scratch(p, q)
    X = np.empty((samples, 3))
    step = 1.0 / (samples - 1)
    for i in range(samples):
        s = 1.0 if i == samples - 1 else i * step
        u = min(max((1 - s) * a0 + s * b0, u0), u1)
        v = min(max((1 - s) * a1 + s * b1, v0), v1)
        surface_point(Pw, p, q, U, V, u, v, Nu, Nv, left, right, tmp, X[i])
    d_first = 0.0
    d_last = 0.0
    for i in range(samples):
        for e in range(2):
            j = 0 if e == 0 else samples - 1
            dx = X[i, 0] - X[j, 0]
            dy = X[i, 1] - X[j, 1]
            dz = X[i, 2] - X[j, 2]
            d = math.sqrt(dx * dx + dy * dy + dz * dz)
            if e == 0:
                d_first = d if d > d_first or d != d else d_first
            else:
                d_last = d if d > d_last or d != d else d_last
    return d_last if d_last < d_first else d_first  # Python's min(d_first, d_last)
