"""Plane-section kernels: certified Bézier subdivision, edge roots, Newton projections.

The plane is ``plane = (A, B, C, D)`` with a unit normal; the plane function of a
surface point is ``f(u, v) = A x + B y + C z + D``.  On a rational Bézier patch with
homogeneous control points ``Qw[i, j] = (w x, w y, w z, w)`` the numerator
``N(u, v) = sum B_i(u) B_j(v) h_ij`` with ``h_ij = plane . Qw[i, j]`` has the same zero
set as ``f`` (the weights are positive), so the signs of ``h`` certify:

* all ``h > 0`` or all ``h < 0``: the patch misses the plane (convex hull);
* the ``h`` differences along u all ``>= 0`` (or all ``<= 0``): ``N`` is monotone in u,
  every v-line crosses the zero set at most once, no closed loop lies inside, and
  (with the edge polygons along v having at most one sign change) every edge holds
  at most one crossing.  Such a leaf is linked by sorting its edge crossings.

This extends Paper 2 (quad states a-g from corner signs, uniform 10x10 subdivision),
whose corner test cannot exclude a small loop inside a quad.

Curve points by Newton and densification are in :mod:`.section_project`, the trim
side of curve points in :mod:`.section_trims` and :mod:`.section_clip`, chord
refinement in :mod:`.section_refine`.
"""

from __future__ import annotations

import numpy as np

from .basis import basis_funs_inline, find_span_inline
from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit, jit_inline
from .surface import D2, _binomial_table, derivs_scratch, surface_derivs, surface_point

PRUNE = 0
MONO_U = 1
MONO_V = 2
UNRESOLVED = 3
SPLIT = 4


@jit
def _split(Q, axis, L, R):
    """de Casteljau split at the middle of a tensor net ``Q`` (m, n, k) along ``axis``."""
    m = Q.shape[0]
    n = Q.shape[1]
    k = Q.shape[2]
    if axis == 0:
        for j in range(n):
            for c in range(k):
                for i in range(m):
                    R[i, j, c] = Q[i, j, c]
                L[0, j, c] = Q[0, j, c]
                for r in range(1, m):
                    for i in range(m - r):
                        R[i, j, c] = 0.5 * (R[i, j, c] + R[i + 1, j, c])
                    L[r, j, c] = R[0, j, c]
    else:
        for i in range(m):
            for c in range(k):
                for j in range(n):
                    R[i, j, c] = Q[i, j, c]
                L[i, 0, c] = Q[i, 0, c]
                for r in range(1, n):
                    for j in range(n - r):
                        R[i, j, c] = 0.5 * (R[i, j, c] + R[i, j + 1, c])
                    L[i, r, c] = R[i, 0, c]


@jit_inline
def _variations(h, zsnap):
    """Sign changes of a control polygon, zeros (|h| <= zsnap) counted as positive."""
    count = 0
    prev = h[0] >= -zsnap
    for i in range(1, h.shape[0]):
        cur = h[i] >= -zsnap
        if cur != prev:
            count += 1
        prev = cur
    return count


@jit
def certify(Q, plane, zsnap):
    """State of a Bézier net ``Q`` (m, n, 4) against ``plane``: PRUNE, MONO_U, MONO_V
    or SPLIT (see the module docstring)."""
    m = Q.shape[0]
    n = Q.shape[1]
    h = np.empty((m, n))
    pos = True
    neg = True
    for i in range(m):
        for j in range(n):
            w = Q[i, j, 3]
            val = (plane[0] * Q[i, j, 0] + plane[1] * Q[i, j, 1] + plane[2] * Q[i, j, 2]
                   + plane[3] * w)
            if abs(val) <= zsnap * w:
                val = 0.0
            h[i, j] = val
            if val <= 0.0:
                pos = False
            if val >= 0.0:
                neg = False
    if pos or neg:
        return PRUNE
    # monotone in u: every difference along u of one sign (ties allowed)
    up = True
    down = True
    for i in range(m - 1):
        for j in range(n):
            d = h[i + 1, j] - h[i, j]
            if d < -zsnap:
                up = False
            if d > zsnap:
                down = False
    if up or down:
        if _variations(h[0, :], zsnap) <= 1 and _variations(h[m - 1, :], zsnap) <= 1:
            return MONO_U
    up = True
    down = True
    for i in range(m):
        for j in range(n - 1):
            d = h[i, j + 1] - h[i, j]
            if d < -zsnap:
                up = False
            if d > zsnap:
                down = False
    if up or down:
        if _variations(h[:, 0], zsnap) <= 1 and _variations(h[:, n - 1], zsnap) <= 1:
            return MONO_V
    return SPLIT


@jit
def _net_extent(Q):
    """(diameter of the Cartesian control net's box, mean polygon length along u, along v)."""
    m = Q.shape[0]
    n = Q.shape[1]
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    for i in range(m):
        for j in range(n):
            for c in range(3):
                x = Q[i, j, c] / Q[i, j, 3]
                lo[c] = min(lo[c], x)
                hi[c] = max(hi[c], x)
    diam = np.sqrt(np.sum((hi - lo) ** 2))
    lu = 0.0
    for i in range(m - 1):
        for j in range(n):
            s = 0.0
            for c in range(3):
                d = Q[i + 1, j, c] / Q[i + 1, j, 3] - Q[i, j, c] / Q[i, j, 3]
                s += d * d
            lu += np.sqrt(s)
    lv = 0.0
    for i in range(m):
        for j in range(n - 1):
            s = 0.0
            for c in range(3):
                d = Q[i, j + 1, c] / Q[i, j + 1, 3] - Q[i, j, c] / Q[i, j, 3]
                s += d * d
            lv += np.sqrt(s)
    return diam, lu / max(n, 1), lv / max(m, 1)


@jit
def subdivide(H, ub, vb, plane, zsnap, min_diam, max_depth):
    """Certified recursive subdivision of every Bézier patch of a surface.

    Parameters
    ----------
    H : (nsu, nsv, p+1, q+1, 4) homogeneous Bézier nets; ``ub`` (nsu+1,), ``vb``
        (nsv+1,) their parameter breaks.
    plane : (4,) unit-normal plane; ``zsnap`` absolute zero band of the plane function.
    min_diam : a sub-patch whose control net spans at most this (3-D box diagonal) is
        not split further (an UNRESOLVED leaf: tangency or singular crossing).
    max_depth : cap on the subdivision depth per patch.

    Returns
    -------
    leaves : (m, 5) float: u0, u1, v0, v1, state (MONO_U, MONO_V or UNRESOLVED).
    n_visited : int, sub-patches examined.
    """
    nsu = H.shape[0]
    nsv = H.shape[1]
    m = H.shape[2]
    n = H.shape[3]
    cap = 2 * max_depth + 8
    stack = np.empty((cap, m, n, 4))
    boxes = np.empty((cap, 4))
    depth = np.empty(cap, np.int64)
    out = np.empty((1024, 5))
    nout = 0
    visited = 0
    for a in range(nsu):
        for b in range(nsv):
            if ub[a + 1] <= ub[a] or vb[b + 1] <= vb[b]:
                continue
            top = 0
            for i in range(m):  # element loops, not slice copies: no shape-check raise
                for j in range(n):
                    for c in range(4):
                        stack[0, i, j, c] = H[a, b, i, j, c]
            boxes[0, 0] = ub[a]
            boxes[0, 1] = ub[a + 1]
            boxes[0, 2] = vb[b]
            boxes[0, 3] = vb[b + 1]
            depth[0] = 0
            top = 1
            while top > 0:
                top -= 1
                visited += 1
                Q = stack[top].copy()
                u0 = boxes[top, 0]
                u1 = boxes[top, 1]
                v0 = boxes[top, 2]
                v1 = boxes[top, 3]
                d = depth[top]
                state = certify(Q, plane, zsnap)
                if state == PRUNE:
                    continue
                diam, lu, lv = _net_extent(Q)
                if state == SPLIT and (diam <= min_diam or d >= max_depth):
                    state = UNRESOLVED
                if state != SPLIT:
                    if nout == out.shape[0]:
                        bigger = np.empty((2 * nout, 5))
                        for i in range(nout):
                            for c in range(5):
                                bigger[i, c] = out[i, c]
                        out = bigger
                    out[nout, 0] = u0
                    out[nout, 1] = u1
                    out[nout, 2] = v0
                    out[nout, 3] = v1
                    out[nout, 4] = state
                    nout += 1
                    continue
                axis = 0 if lu >= lv else 1
                L = stack[top]
                R = stack[top + 1]
                _split(Q, axis, L, R)
                if axis == 0:
                    um = 0.5 * (u0 + u1)
                    boxes[top, 0] = u0
                    boxes[top, 1] = um
                    boxes[top, 2] = v0
                    boxes[top, 3] = v1
                    boxes[top + 1, 0] = um
                    boxes[top + 1, 1] = u1
                    boxes[top + 1, 2] = v0
                    boxes[top + 1, 3] = v1
                else:
                    vm = 0.5 * (v0 + v1)
                    boxes[top, 0] = u0
                    boxes[top, 1] = u1
                    boxes[top, 2] = v0
                    boxes[top, 3] = vm
                    boxes[top + 1, 0] = u0
                    boxes[top + 1, 1] = u1
                    boxes[top + 1, 2] = vm
                    boxes[top + 1, 3] = v1
                depth[top] = d + 1
                depth[top + 1] = d + 1
                top += 2
    return out[:nout].copy(), visited


@jit
def _f_at(Pw, p, q, U, V, plane, u, v, Nu, Nv, left, right, tmp, X):
    surface_point(Pw, p, q, U, V, u, v, Nu, Nv, left, right, tmp, X)
    return plane[0] * X[0] + plane[1] * X[1] + plane[2] * X[2] + plane[3]


@jit
def plane_values(Pw, p, q, U, V, plane, uv, out):
    """``out[i] = f(uv[i])``, the plane function at ``uv`` (n, 2)."""
    mm = max(p, q) + 1
    Nu = np.empty(p + 1)
    Nv = np.empty(q + 1)
    left = np.empty(mm)
    right = np.empty(mm)
    tmp = np.empty(4)
    X = np.empty(3)
    _plane_values_loop(Pw, p, q, U, V, plane, uv, out, (Nu, Nv, left, right, tmp, X))


@jit
def _plane_values_loop(Pw, p, q, U, V, plane, uv, out, scratch):
    """The loop of :func:`plane_values` over borrowed views of its arrays and the
    caller's scratch (no atomic reference counting, :mod:`.numba_ext.borrow`)."""
    Pw, U, V, plane, uv, out, (Nu, Nv, left, right, tmp, X) = borrow_all((
        Pw, U, V, plane, uv, out, scratch))
    for i in range(uv.shape[0]):
        out[i] = _f_at(Pw, p, q, U, V, plane, uv[i, 0], uv[i, 1], Nu, Nv, left, right, tmp, X)


@jit
def edge_roots(Pw, p, q, U, V, plane, a, b, fa, fb, ttol, out):
    """Root of ``f`` on each segment ``a[i] -> b[i]`` (UV) with ``fa[i] * fb[i] < 0``.

    Illinois regula falsi with bisection safeguard until the bracket is shorter than
    ``ttol`` (in the segment parameter t in [0, 1]); ``out[i]`` = t.  The bracket is
    oriented from the negative end, so the result does not depend on the edge
    direction's sign convention.
    """
    mm = max(p, q) + 1
    Nu = np.empty(p + 1)
    Nv = np.empty(q + 1)
    left = np.empty(mm)
    right = np.empty(mm)
    tmp = np.empty(4)
    X = np.empty(3)
    _edge_roots_loop(Pw, p, q, U, V, plane, a, b, fa, fb, ttol, out,
                     (Nu, Nv, left, right, tmp, X))


@jit
def _edge_roots_loop(Pw, p, q, U, V, plane, a, b, fa, fb, ttol, out, scratch):
    """The loop of :func:`edge_roots` over borrowed views (:mod:`.numba_ext.borrow`)."""
    Pw, U, V, plane, a, b, fa, fb, out, (Nu, Nv, left, right, tmp, X) = borrow_all((
        Pw, U, V, plane, a, b, fa, fb, out, scratch))
    for i in range(a.shape[0]):
        out[i] = edge_root(Pw, p, q, U, V, plane, a[i, 0], a[i, 1], b[i, 0], b[i, 1], fa[i],
                           fb[i], ttol, Nu, Nv, left, right, tmp, X)


@jit
def edge_root(Pw, p, q, U, V, plane, au, av, bu, bv, fa, fb, ttol, Nu, Nv, left, right,
              tmp, X, rows=None, r0=0):
    """The root parameter t of :func:`edge_roots` on one segment ``(au, av) -> (bu, bv)``
    (``fa * fb < 0``); scratch as for :func:`surface_point`.

    With ``rows`` (the control-row sums at ``v = av = bv`` from control row ``r0`` on,
    :func:`.section_refine._u_rows`) the segment is a line of constant v and each
    iterate is evaluated by :func:`f_u_line` (the u basis and the outer sum alone, the
    same bits as ``_f_at`` where ``av + t * 0.0`` is ``av``, i.e. ``av`` not zero); the
    same loop, its other evaluator compiled away (``rows is None``)."""
    lo = 0.0
    hi = 1.0
    flo = fa
    fhi = fb
    side = 0
    t = 0.5
    for it in range(200):
        if hi - lo <= ttol:
            break
        if it % 3 == 2:
            t = 0.5 * (lo + hi)
        else:
            t = lo + (hi - lo) * flo / (flo - fhi)
            if not (t > lo and t < hi):
                t = 0.5 * (lo + hi)
        if rows is None:
            ft = _f_at(Pw, p, q, U, V, plane, au + t * (bu - au), av + t * (bv - av), Nu, Nv,
                       left, right, tmp, X)
        else:
            ft = f_u_line(Pw, p, U, plane, au + t * (bu - au), rows, r0, Nu, left, right)
        if ft == 0.0:
            lo = t
            hi = t
            break
        if (ft < 0.0) == (flo < 0.0):
            lo = t
            flo = ft
            if side == -1:
                fhi *= 0.5
            side = -1
        else:
            hi = t
            fhi = ft
            if side == 1:
                flo *= 0.5
            side = 1
    return 0.5 * (lo + hi)


@jit
def f_u_line(Pw, p, U, plane, u, rows, r0, Nu, left, right):
    """The plane function at ``(u, v)`` from the row sums of
    :func:`.section_refine._u_rows` at ``v``, as :func:`_f_at` computes it."""
    nu = Pw.shape[0]
    su = find_span_inline(nu - 1, p, u, U)
    basis_funs_inline(su, u, p, U, Nu, left, right)
    t0 = 0.0
    t1 = 0.0
    t2 = 0.0
    t3 = 0.0
    for k in range(p + 1):
        i = su - p + k - r0
        a = Nu[k]
        t0 += a * rows[i, 0]
        t1 += a * rows[i, 1]
        t2 += a * rows[i, 2]
        t3 += a * rows[i, 3]
    x = t0 / t3
    y = t1 / t3
    z = t2 / t3
    return plane[0] * x + plane[1] * y + plane[2] * z + plane[3]


@jit
def critical_points(Pw, p, q, U, V, plane, boxes, maxit, out_uv, out_f):
    """A critical point of ``f`` (``plane.S_u = plane.S_v = 0``) in each UV box.

    Damped Newton on the gradient with the Hessian ``plane.S_uu`` etc., started at the
    box centre and clamped to the box (rows of ``boxes``: u0, u1, v0, v1).  Writes the
    parameters and ``f`` there; the caller accepts the point as a contact when ``|f|``
    is within its contact tolerance.
    """
    bin_ = _binomial_table(D2)
    scr = derivs_scratch(p, q, D2)
    _critical_points_loop(Pw, p, q, U, V, plane, boxes, maxit, out_uv, out_f, bin_, scr,
                          np.empty((3, 3, 3)))


@jit
def _critical_points_loop(Pw, p, q, U, V, plane, boxes, maxit, out_uv, out_f, bin_, scr,
                          SKL):
    """The loop of :func:`critical_points` over borrowed views (:mod:`.numba_ext.borrow`)."""
    Pw, U, V, plane, boxes, out_uv, out_f, bin_, scr, SKL = borrow_all((
        Pw, U, V, plane, boxes, out_uv, out_f, bin_, scr, SKL))
    for i in range(boxes.shape[0]):
        u0 = boxes[i, 0]
        u1 = boxes[i, 1]
        v0 = boxes[i, 2]
        v1 = boxes[i, 3]
        u = 0.5 * (u0 + u1)
        v = 0.5 * (v0 + v1)
        best_u = u
        best_v = v
        best = np.inf
        for it in range(maxit):
            surface_derivs(Pw, p, q, U, V, u, v, D2, bin_, scr, SKL)
            f = (plane[0] * SKL[0, 0, 0] + plane[1] * SKL[0, 0, 1] + plane[2] * SKL[0, 0, 2]
                 + plane[3])
            if abs(f) < best:
                best = abs(f)
                best_u = u
                best_v = v
            gu = 0.0
            gv = 0.0
            huu = 0.0
            huv = 0.0
            hvv = 0.0
            for c in range(3):
                gu += plane[c] * SKL[1, 0, c]
                gv += plane[c] * SKL[0, 1, c]
                huu += plane[c] * SKL[2, 0, c]
                huv += plane[c] * SKL[1, 1, c]
                hvv += plane[c] * SKL[0, 2, c]
            lam = 1e-12 * (abs(huu) + abs(hvv) + 1e-300)
            a11 = huu + lam if huu >= 0 else huu - lam
            a22 = hvv + lam if hvv >= 0 else hvv - lam
            det = a11 * a22 - huv * huv
            if det == 0.0:
                break
            du = -(a22 * gu - huv * gv) / det
            dv = -(a11 * gv - huv * gu) / det
            un = min(max(u + du, u0), u1)
            vn = min(max(v + dv, v0), v1)
            if un == u and vn == v:
                break
            u = un
            v = vn
        out_uv[i, 0] = best_u
        out_uv[i, 1] = best_v
        out_f[i] = best if np.isfinite(best) else np.nan


@jit
def has_close_pair(uv, order, r):
    """Whether two of the points ``uv`` (n, 2) are within ``r`` of each other along
    both u and v (a superset of the pairs within Euclidean distance ``r``); ``order``
    sorts them by u, then v (``np.lexsort((uv[:, 1], uv[:, 0]))``).

    For each point the points after it in ``order`` with u at most ``r`` more are
    scanned; among those with its own u (sorted by v) the scan skips past the ones
    more than ``r`` above its v."""
    n = order.shape[0]
    # end of each run of equal u in the sorted order
    run_end = np.empty(n, np.int64)
    e = n
    for k in range(n - 1, -1, -1):
        if k < n - 1 and uv[order[k], 0] != uv[order[k + 1], 0]:
            e = k + 1
        run_end[k] = e
    for k in range(n):
        i = order[k]
        ui = uv[i, 0]
        vi = uv[i, 1]
        m = k + 1
        while m < n:
            j = order[m]
            if uv[j, 0] - ui > r:
                break
            if abs(uv[j, 1] - vi) <= r:
                return True
            if uv[j, 0] == ui and uv[j, 1] - vi > r:
                m = run_end[m]      # the rest of this u run is higher still
                continue
            m += 1
    return False
