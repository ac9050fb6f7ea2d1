"""A model-space edge on a surface of revolution as a UV pcurve of piecewise quintics.

The reader's edges on cylinders, cones, spheres and tori that are not iso-lines are
carried into the surface's NURBS parameters by interpolation (the method of
:mod:`geomkit.cad.uvmap`, where it is documented): the edge point at loop parameter
``s`` is inverted in closed form to local coordinates ``(a, b)`` (height or angle,
angle about the axis), each angle kept on the branch of the reference samples, then
mapped by the arc parametrisation (:func:`angle_to_param` of
:mod:`geomkit.cad.analytic`).  Spans of quintic Bézier interpolants at 6 parameters
are checked at 9 more and split until within ``tol``.

One call fits one edge with no Python between rounds (a part has hundreds of such
edges, each needing several rounds of small evaluations).
"""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit_exact, jit_plain as jit, jit_inline
from .basis import (basis_funs_inline, ders_basis_funs_inline, ders_scratch,
                    find_span_inline)
from .ranges import spread

CYLINDER, CONE, SPHERE, TORUS, PLANE = 0, 1, 2, 3, 4
TWO_PI = 2.0 * math.pi


@jit_inline
def arc_consts(th0, th1):
    """``(n, d, tan(d / 4))`` of the arc ``[th0, th1]``: its count of quarter-turn
    spans, their angle, and the tangent :func:`angle_param_at` divides by."""
    n = max(1, int(math.ceil((th1 - th0) / (0.5 * math.pi) - 1e-12)))
    d = (th1 - th0) / n
    return n, d, math.tan(d / 4)


@jit_inline
def angle_param_at(th, th0, th1, n, d, td):
    """The arc parameter at angle ``th`` of the arc ``[th0, th1]`` (its quarter-turn
    spans; :func:`geomkit.cad.analytic.angle_to_param`), given the arc's
    :func:`arc_consts` (a fit maps thousands of angles on one arc)."""
    k = math.floor((th - th0) / d)
    k = min(max(k, 0.0), n - 1.0)
    mid = th0 + (k + 0.5) * d
    r = 0.5 * (math.tan(0.5 * (th - mid)) / td + 1.0)
    return min(max(th0 + (k + r) * d, th0), th1)


@jit
def _angle_param(th, th0, th1):
    """:func:`angle_param_at` of one angle."""
    n, d, td = arc_consts(th0, th1)
    return angle_param_at(th, th0, th1, n, d, td)


@jit_inline
def _interp(x, xs, ys):
    """``np.interp`` at one point (``xs`` increasing)."""
    n = xs.shape[0]
    if x <= xs[0]:
        return ys[0]
    if x >= xs[n - 1]:
        return ys[n - 1]
    lo, hi = 0, n - 1
    while hi - lo > 1:
        m = (lo + hi) // 2
        if xs[m] <= x:
            lo = m
        else:
            hi = m
    if xs[hi] == xs[lo]:
        return ys[hi]
    return ys[lo] + (x - xs[lo]) * (ys[hi] - ys[lo]) / (xs[hi] - xs[lo])


@jit_inline
def _local_xyz(px, py, pz, kind, frame, R, r, tan_a):
    """Local coordinates ``(a, b)`` of the model point ``(px, py, pz)`` and its distance
    from the axis (closed form, :meth:`geomkit.cad.brep.Analytic.local`): PLANE
    ``(x, y)`` in the plane's frame (distance 1); CYLINDER / CONE ``(height,
    angle)``; SPHERE ``(latitude, longitude)``; TORUS ``(minor angle, major angle)``
    (CYLINDER with ``R = 0`` gives height and angle about any axis).  ``frame``:
    ``O, X, Y, A`` (12,)."""
    dx = px - frame[0]
    dy = py - frame[1]
    dz = pz - frame[2]
    x = dx * frame[3] + dy * frame[4] + dz * frame[5]
    y = dx * frame[6] + dy * frame[7] + dz * frame[8]
    if kind == PLANE:
        return x, y, 1.0
    z = dx * frame[9] + dy * frame[10] + dz * frame[11]
    rho = math.hypot(x, y)
    th = math.atan2(y, x)
    if kind == CYLINDER or kind == CONE:
        a = z
        if kind == CONE and R + z * tan_a < 0:  # beyond the apex the radius is
            # negative: the generator there lies at the angle th + pi
            th += math.pi
    elif kind == SPHERE:
        a = math.atan2(z, rho)
    else:
        a = math.atan2(z, rho - R)
        if r > R and abs(math.hypot(rho + R, z) - r) < abs(math.hypot(rho - R, z) - r):
            # a spindle torus's inner (lemon) part passes the axis: its points lie
            # at the angle th + pi
            a = math.atan2(z, -rho - R)
            th += math.pi
    return a, th, rho


@jit
def local_points(P, kind, frame, R, r, tan_a):
    """:func:`_local_xyz` of the points ``P`` (n, 3): ``(ab (n, 2), rho (n,))``."""
    n = P.shape[0]
    ab = np.empty((n, 2))
    rho = np.empty(n)
    for i in range(n):
        ab[i, 0], ab[i, 1], rho[i] = _local_xyz(P[i, 0], P[i, 1], P[i, 2], kind, frame,
                                                R, r, tan_a)
    return ab, rho


@jit
def residuals(P, kind, frame, R, r, alpha):
    """The largest distance of the points ``P`` (n >= 1, 3) from the analytic surface
    (the closed forms of each kind's distance: a cone's two nappes, a
    spindle torus's inner part; NaN when a point's is)."""
    ca, ta = math.cos(alpha), math.tan(alpha)
    worst = 0.0
    for i in range(P.shape[0]):
        dx = P[i, 0] - frame[0]
        dy = P[i, 1] - frame[1]
        dz = P[i, 2] - frame[2]
        h = dx * frame[9] + dy * frame[10] + dz * frame[11]
        ex, ey, ez = dx - h * frame[9], dy - h * frame[10], dz - h * frame[11]
        rho = math.sqrt(ex * ex + ey * ey + ez * ez)
        if kind == PLANE:
            d = abs(h)
        elif kind == CYLINDER:
            d = abs(rho - R)
        elif kind == CONE:
            d = abs(rho - abs(R + h * ta)) * ca
        elif kind == SPHERE:
            d = abs(math.hypot(rho, h) - R)
        else:
            d = abs(math.hypot(rho - R, h) - r)
            if r > R:
                d = min(d, abs(math.hypot(rho + R, h) - r))
        if d != d:
            return math.nan
        if d > worst:
            worst = d
    return worst


@jit_inline
def _curve_point(Pw, p, U, t, dN, ndu, left, right, a):
    """The curve's point at ``t``: :func:`~geomkit._kernels.bezier.curve_derivs` at
    order 0 with its scratch given (the same operations in the same order: the same
    point)."""
    span = find_span_inline(Pw.shape[0] - 1, p, t, U)
    ders_basis_funs_inline(span, t, p, 0, U, dN, ndu, left, right, a)
    x = y = z = w = 0.0
    for k in range(p + 1):
        N = dN[0, k]
        row = span - p + k
        x += N * Pw[row, 0]
        y += N * Pw[row, 1]
        z += N * Pw[row, 2]
        w += N * Pw[row, 3]
    return x / w, y / w, z / w


@jit
def curve_at(Pw, p, U, t):
    """The curve's points (m, 3) at the parameters ``t``: those of
    :func:`geomkit.cad.analytic.curve_eval`, bit for bit, in one call with its scratch
    allocated once (the readers sample thousands of short edges)."""
    X = np.empty((t.shape[0], 3))
    dN = np.empty((1, p + 1))
    ndu, left, right, a = ders_scratch(p)
    for i in range(t.shape[0]):
        X[i, 0], X[i, 1], X[i, 2] = _curve_point(Pw, p, U, t[i], dN, ndu, left, right, a)
    return X


@jit_exact
def _even_param(i, step, t0):
    """``i * step + t0`` rounded twice (numpy's ``arange * step + start``: no fused
    multiply-add, whatever the caller's flags)."""
    return float(i) * step + t0


@jit
def curve_at_even(Pw, p, U, t0, t1, n):
    """:func:`curve_at` at ``n >= 2`` evenly spaced parameters of ``[t0, t1]``, the
    reader's ``np.linspace`` values (each ``i * step + t0`` rounded twice, the last
    ``t1``) made here: the same points in one call without the parameter array."""
    X = np.empty((n, 3))
    dN = np.empty((1, p + 1))
    ndu, left, right, a = ders_scratch(p)
    step = (t1 - t0) / (n - 1)
    for i in range(n):
        t = t1 if i == n - 1 else _even_param(i, step, t0)
        X[i, 0], X[i, 1], X[i, 2] = _curve_point(Pw, p, U, t, dN, ndu, left, right, a)
    return X


@jit
def edge_local(Pw, p, U, t0, t1, n, kind, frame, R, r, tan_a):
    """The curve at ``n`` evenly spaced parameters of ``[t0, t1]`` (``n >= 2``; the
    reader's linspace, bit for bit; the points those of
    :func:`geomkit.cad.analytic.curve_eval` to rounding: the parameters are fused
    here) and their :func:`local_points`: ``(X (n, 3), ab (n, 2), rho (n,))`` in one
    call."""
    X = np.empty((n, 3))
    ab = np.empty((n, 2))
    rho = np.empty(n)
    dN = np.empty((1, p + 1))
    ndu, left, right, a = ders_scratch(p)
    _edge_local_fill(Pw, p, U, t0, t1, n, kind, frame, R, r, tan_a, X, ab, rho,
                     (dN, ndu, left, right, a))
    return X, ab, rho


@jit
def _edge_local_fill(Pw, p, U, t0, t1, n, kind, frame, R, r, tan_a, X, ab, rho, scratch):
    """The loop of :func:`edge_local` over borrowed views (no atomic reference counting
    in the inlined evaluations, :mod:`.numba_ext.borrow`)."""
    Pw, U, frame, X, ab, rho, (dN, ndu, left, right, a) = borrow_all((
        Pw, U, frame, X, ab, rho, scratch))
    step = (t1 - t0) / (n - 1)
    for i in range(n):
        t = t1 if i == n - 1 else float(i) * step + t0
        x, y, z = _curve_point(Pw, p, U, t, dN, ndu, left, right, a)
        X[i, 0], X[i, 1], X[i, 2] = x, y, z
        ab[i, 0], ab[i, 1], rho[i] = _local_xyz(x, y, z, kind, frame, R, r, tan_a)


@jit
def edge_turn(X, have_x, Pw, p, U, t0, t1, n, rev, wrap0, wrap1, kind, frame, R, r,
              tan_a):
    """An edge's ``n`` samples on a surface of revolution with what the seam cut and
    the loop chain read of them, in one call: the samples ``X`` (:func:`edge_local`'s
    unless ``have_x``: then the given ones), their :func:`local_points` ``ab, rho``
    (curve order), the least ``rho`` (``-inf`` when one is NaN), the largest extent
    of ``X`` along x, y or z (NaN propagates), and ``W`` (n, 2): ``ab`` in loop order
    (reversed when ``rev``) with coordinate ``c`` unwrapped (:func:`unwrap_angles`)
    where ``wrap_c``."""
    if have_x:
        ab, rho = local_points(X, kind, frame, R, r, tan_a)
    else:
        X, ab, rho = edge_local(Pw, p, U, t0, t1, n, kind, frame, R, r, tan_a)
    nearest = math.inf
    for i in range(n):
        if rho[i] != rho[i]:
            nearest = -math.inf
            break
        if rho[i] < nearest:
            nearest = rho[i]
    W = np.empty((n, 2))
    for i in range(n):
        j = n - 1 - i if rev else i
        W[i, 0] = ab[j, 0]
        W[i, 1] = ab[j, 1]
    for c in range(2):
        if (wrap0 if c == 0 else wrap1):
            col = unwrap_angles(W[:, c].copy(), TWO_PI)
            for i in range(n):
                W[i, c] = col[i]
    return X, ab, rho, nearest, spread(X), W


@jit
def iso_ends(ab, tol, maps):
    """Whether an edge's local coordinates ``ab`` (n, 2) keep coordinate 0 / 1 within
    ``tol`` of the first sample's (an iso-line: a circle, a generator), and the UV
    segment between its ends: ``(iso0, iso1, q (2, 2))``, each iso coordinate held
    at the first sample's, coordinate ``c`` mapped by the arc ``maps[c]`` when
    ``maps[c, 0] > 0`` (:func:`_angle_param`).  A NaN sample is never iso; ends
    that are not finite give None (the caller names them)."""
    n = ab.shape[0]
    for c in range(2):
        if not (math.isfinite(ab[0, c]) and math.isfinite(ab[n - 1, c])):
            return None
    dev = np.zeros(2)
    for c in range(2):
        for i in range(n):
            d = abs(ab[i, c] - ab[0, c])
            if not d <= dev[c]:
                dev[c] = d
                if d != d:
                    break
    iso0 = dev[0] <= tol
    iso1 = dev[1] <= tol
    q = np.empty((2, 2))
    for c in range(2):
        iso = iso0 if c == 0 else iso1
        for j in range(2):
            v = ab[0, c] if iso or j == 0 else ab[n - 1, c]
            if maps[c, 0] > 0:
                v = _angle_param(v, maps[c, 1], maps[c, 2])
            q[j, c] = v
    return iso0, iso1, q


@jit_inline
def local_at(te, Pw, p, U, kind, frame, R, r, tan_a, N, left, right):
    """Local coordinates ``(a, angle)`` of the curve point at ``te`` about a surface of
    revolution (:func:`_local_xyz`).  ``N``, ``left``, ``right``: scratch of length
    p + 1."""
    span = find_span_inline(Pw.shape[0] - 1, p, te, U)
    basis_funs_inline(span, te, p, U, N, left, right)
    wx = wy = wz = w = 0.0
    for j in range(p + 1):
        q = span - p + j
        wx += N[j] * Pw[q, 0]
        wy += N[j] * Pw[q, 1]
        wz += N[j] * Pw[q, 2]
        w += N[j] * Pw[q, 3]
    a, th, _ = _local_xyz(wx / w, wy / w, wz / w, kind, frame, R, r, tan_a)
    return a, th


@jit_inline
def _mapped(t, Pw, p, U, e0, e1, rev, kind, frame, R, r, tan_a, sref, ref, periodic,
            maps, T, S, N, left, right, arc):
    """The mapped UV point ``(u, v)`` at the pcurve parameter ``t``; ``arc`` (2, 3):
    the :func:`arc_consts` of each mapped coordinate."""
    t = min(max(t, T[0]), T[T.shape[0] - 1])
    s = min(max(_interp(t, T, S), 0.0), 1.0)
    te = e0 + ((1.0 - s) if rev else s) * (e1 - e0)
    out0, out1 = local_at(te, Pw, p, U, kind, frame, R, r, tan_a, N, left, right)
    for c in range(2):
        v = out0 if c == 0 else out1
        if periodic[c]:
            rf = _interp(s, sref, ref[:, c])
            v = rf + ((v - rf + math.pi) % TWO_PI) - math.pi
        if maps[c, 0] > 0:
            v = angle_param_at(v, maps[c, 1], maps[c, 2], int(arc[c, 0]), arc[c, 1],
                               arc[c, 2])
        if c == 0:
            out0 = v
        else:
            out1 = v
    return out0, out1


@jit
def fit_edge_pcurve(Pw, p, U, e0, e1, rev, kind, frame, R, r, tan_a, ref, periodic, maps,
                    T, S, tol, binv, check, cb, max_spans, max_split):
    """Quintic spans of the mapped pcurve of one edge.

    ``Pw`` (n, 4), ``p``, ``U``: the edge's homogeneous NURBS over ``[e0, e1]``, run
    backwards when ``rev``; ``kind`` one of CYLINDER / CONE / SPHERE / TORUS;
    ``frame`` (12,): origin, X, Y, A of the surface; ``R``, ``r``, ``tan_a``: its radii
    and the cone's half-angle tangent; ``ref`` (m, 2): local coordinates at ``m``
    equally spaced loop parameters (the branch each angle is kept on); ``periodic``
    (2,) int; ``maps`` (2, 3): per coordinate ``(mapped?, th0, th1)``; ``T``, ``S``:
    the pcurve parameter at the loop parameters ``S`` (the starting span ends);
    ``binv`` (6, 6), ``check`` (9,), ``cb`` (9, 6): interpolation and check matrices.

    Returns ``(starts (k,), bez (k, 6, 2), error)``: the spans (unsorted), their Bézier
    points and the largest check error of the accepted spans.
    """
    nb = binv.shape[0]
    nc = check.shape[0]
    scratch = (np.empty(ref.shape[0]), np.empty(p + 1), np.empty(p + 1), np.empty(p + 1),
               np.zeros((2, 3)), np.empty((nb, 2)), np.empty((nc, 2)), np.empty((nb, 2)))
    return _fit_loop(Pw, p, U, e0, e1, rev, kind, frame, R, r, tan_a, ref, periodic, maps,
                     T, S, tol, binv, check, cb, max_spans, max_split, scratch)


@jit
def _fit_loop(Pw, p, U, e0, e1, rev, kind, frame, R, r, tan_a, ref, periodic, maps, T, S,
              tol, binv, check, cb, max_spans, max_split, scratch):
    """The work of :func:`fit_edge_pcurve` over borrowed views of its arguments and
    scratch (no atomic reference counting in the many inlined evaluations,
    :mod:`.numba_ext.borrow`); the arrays it makes and returns are its own."""
    Pw, U, frame, ref, periodic, maps, T, S, binv, check, cb = borrow_all((
        Pw, U, frame, ref, periodic, maps, T, S, binv, check, cb))
    sref, N, left, right, arc, X, C, B = borrow_all(scratch)
    nb = binv.shape[0]
    nc = check.shape[0]
    for i in range(sref.shape[0]):
        sref[i] = i / (sref.shape[0] - 1)
    for c in range(2):
        if maps[c, 0] > 0:
            arc[c, 0], arc[c, 1], arc[c, 2] = arc_consts(maps[c, 1], maps[c, 2])
    a = T[:-1].copy()
    b = T[1:].copy()
    hmin = 1e-9 * (T[T.shape[0] - 1] - T[0])
    cap = max(16, 4 * a.shape[0])
    out_a = np.empty(cap)
    out_b = np.empty((cap, nb, 2))
    nout = 0
    err = 0.0
    while a.shape[0] > 0:
        k = a.shape[0]
        m = np.zeros(k, dtype=np.int64)
        bez = np.empty((k, nb, 2))
        e = np.empty(k)
        for i in range(k):
            h = b[i] - a[i]
            for j in range(nb):
                X[j, 0], X[j, 1] = _mapped(a[i] + h * (j / (nb - 1)), Pw, p, U, e0, e1, rev,
                                           kind, frame, R, r, tan_a, sref, ref, periodic,
                                           maps, T, S, N, left, right, arc)
            for j in range(nc):
                C[j, 0], C[j, 1] = _mapped(a[i] + h * check[j], Pw, p, U, e0, e1, rev, kind,
                                           frame, R, r, tan_a, sref, ref, periodic, maps,
                                           T, S, N, left, right, arc)
            for j in range(nb):
                for c in range(2):
                    acc = 0.0
                    for q in range(nb):
                        acc += binv[j, q] * X[q, c]
                    B[j, c] = acc
                    bez[i, j, c] = acc
            ei = 0.0
            for j in range(nc):
                for c in range(2):
                    acc = 0.0
                    for q in range(nb):
                        acc += cb[j, q] * B[q, c]
                    ei = max(ei, abs(acc - C[j, c]))
            e[i] = ei
            if ei > tol and h > hmin:
                mi = math.ceil(1.25 * (ei / tol) ** (1.0 / 6.0))
                m[i] = min(max(mi, 2), max_split)
        if nout + m.sum() > max_spans:
            m[:] = 0  # give up refining: the error found is returned
        nxt = 0
        for i in range(k):
            if m[i] == 0:
                if nout == out_a.shape[0]:
                    grown_a = np.empty(2 * nout)
                    grown_a[:nout] = out_a
                    grown_b = np.empty((2 * nout, nb, 2))
                    grown_b[:nout] = out_b
                    out_a, out_b = grown_a, grown_b
                out_a[nout] = a[i]
                out_b[nout] = bez[i]
                nout += 1
                err = max(err, e[i])
            else:
                nxt += m[i]
        na = np.empty(nxt)
        nbb = np.empty(nxt)
        j = 0
        for i in range(k):
            mi = m[i]
            if mi == 0:
                continue
            step = (b[i] - a[i]) / mi
            for q in range(mi):
                na[j] = a[i] + q * step
                nbb[j] = b[i] if q + 1 == mi else a[i] + (q + 1) * step
                j += 1
        a, b = na, nbb
    return out_a[:nout].copy(), out_b[:nout].copy(), err


@jit
def spans_net(starts, bez, end):
    """The C0 chain of Bézier spans ``bez`` (k, d + 1, 2) that start at the
    parameters ``starts`` (any order; a stable sort) and end, the last one, at
    ``end``: ``(ok, knots, points)`` with interior knots of multiplicity d.  ``ok``:
    the points are finite and the starts increase strictly, below ``end`` (else the
    arrays are returned for the checks that name the fault)."""
    k = starts.shape[0]
    d = bez.shape[1] - 1
    order = np.argsort(starts, kind="mergesort")
    pts = np.zeros((k * d + 1, 2))
    knots = np.zeros(k * d + d + 2)
    ok = True
    for i in range(k):
        j = order[i]
        a = starts[j]
        if i == 0:
            pts[0, 0] = bez[j, 0, 0]
            pts[0, 1] = bez[j, 0, 1]
            for m in range(d + 1):
                knots[m] = a
        else:
            ok = ok and a > starts[order[i - 1]]
            for m in range(d):
                knots[d + 1 + (i - 1) * d + m] = a
        for m in range(1, d + 1):
            pts[1 + i * d + m - 1, 0] = bez[j, m, 0]
            pts[1 + i * d + m - 1, 1] = bez[j, m, 1]
    for m in range(d + 1):
        knots[k * d + 1 + m] = end
    ok = ok and k > 0 and starts[order[0]] < end and starts[order[k - 1]] < end
    for i in range(pts.shape[0]):
        ok = ok and math.isfinite(pts[i, 0]) and math.isfinite(pts[i, 1])
    return ok, knots, pts


@jit
def unwrap_angles(x, period):
    """``np.unwrap(x, period=period)`` of a 1-D float array (the same values: each
    step's correction as numpy computes it, summed in order; the readers unwrap
    thousands of short edges, where numpy's dozen calls cost more than the work)."""
    n = x.shape[0]
    out = x.copy()
    half = period / 2
    c = 0.0
    for i in range(n - 1):
        d = x[i + 1] - x[i]
        corr = 0.0
        if not abs(d) < half:  # (a NaN step is corrected as numpy does: to NaN)
            dm = (d + half) % period - half
            if dm == -half and d > 0:
                dm = half
            corr = dm - d
        c += corr
        out[i + 1] = x[i + 1] + c
    return out


@jit
def _clamped_knots_ok(U, p, n):
    """Whether the knots ``U`` are clamped and pass every check of
    :func:`geomkit.validate.check_knots` for ``n`` control points of degree ``p``."""
    m = U.shape[0]
    if m != n + p + 1 or n < p + 1:
        return False
    for j in range(m):
        if not math.isfinite(U[j]):
            return False
    lo, hi = U[p], U[n]
    if not hi > lo or U[0] != U[p] or U[m - 1] != U[m - p - 1]:
        return False
    run = 0
    for j in range(m):
        if j and U[j] < U[j - 1]:
            return False
        run = run + 1 if j and U[j] == U[j - 1] else 1
        if run > p + 1 or (run > p and lo < U[j] < hi):
            return False
    return True


@jit
def plane_piece(Pw, p, U, reverse, O, X, Y):
    """An edge's own NURBS ``(p, U, Pw)`` mapped onto the plane ``O + a X + b Y``
    (affine: exact), in loop order: ``(U, Q, w, plain, ok)`` with ``w`` the weights
    (ones when all the edge's weights are equal: ``plain``), ``Q`` the mapped control
    points (``Q w / w`` when rational, as the Cartesian points are stored), ``ok``
    whether the knots are clamped and valid (:func:`_clamped_knots_ok`), ``Q`` finite
    and the weights (of a rational piece) positive: a trim curve as it stands."""
    n = Pw.shape[0]
    m = U.shape[0]
    U2 = np.empty(m)
    for j in range(m):
        U2[j] = (U[0] + U[m - 1]) - U[m - 1 - j] if reverse else U[j]
    Q = np.empty((n, 2))
    w = np.empty(n)
    plain = True
    for i in range(n):
        k = n - 1 - i if reverse else i
        wi = Pw[k, 3]
        w[i] = wi
        plain = plain and wi == Pw[0, 3]
        dx = Pw[k, 0] / wi - O[0]
        dy = Pw[k, 1] / wi - O[1]
        dz = Pw[k, 2] / wi - O[2]
        Q[i, 0] = dx * X[0] + dy * X[1] + dz * X[2]
        Q[i, 1] = dx * Y[0] + dy * Y[1] + dz * Y[2]
    good = True
    if plain:
        w[:] = 1.0
    else:
        for i in range(n):
            Q[i, 0] = Q[i, 0] * w[i] / w[i]
            Q[i, 1] = Q[i, 1] * w[i] / w[i]
            good = good and w[i] > 0.0
    for i in range(n):
        good = good and math.isfinite(Q[i, 0]) and math.isfinite(Q[i, 1])
    return U2, Q, w, plain, good and _clamped_knots_ok(U2, p, n)
