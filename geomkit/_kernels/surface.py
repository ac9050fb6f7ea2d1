"""NURBS surface evaluation kernels.

Control nets are stored homogeneous: ``Pw[i, j] = (w x, w y, w z, w)``, shape
(nu, nv, 4); a plain B-spline has ``w = 1``.  Knot vectors are clamped.

Algorithms: surface point (The NURBS Book A3.5 / A4.3), B-spline surface derivatives
(A3.6) applied to ``Pw`` and the rational quotient rule (A4.4).
"""

from __future__ import annotations

import numpy as np

from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit, jit_inline, prun
from .basis import (basis_d1_inline, basis_funs_inline, ders_basis_funs_inline,
                    ders_scratch, find_span_inline)

CHUNK = 256  # points per parallel work item (scratch arrays allocated once per chunk)
POLE_RATIO = 1e-7
"""A point where ``min(|Su|, |Sv|) <= POLE_RATIO * max(|Su|, |Sv|)`` is treated as next
to a collapsed row: its normal comes from the mixed derivative (error O(h) instead of
the cross product's O(eps / h))."""
D1 = np.int64(1)
D2 = np.int64(2)
"""Derivative orders passed to :func:`surface_derivs` / :func:`derivs_scratch` as
non-literal int64: a literal ``2`` or ``1`` makes numba compile a separate
specialisation of the whole evaluation chain per value (measured: 3 compiles of
surface_derivs in one demo run)."""


@jit
def surface_point(Pw, p, q, U, V, u, v, Nu, Nv, left, right, tmp, out):
    """Write S(u, v) into ``out[0:3]`` (A4.3).  Scratch arrays are caller-provided."""
    nu = Pw.shape[0]
    nv = Pw.shape[1]
    su = find_span_inline(nu - 1, p, u, U)
    basis_funs_inline(su, u, p, U, Nu, left, right)
    sv = find_span_inline(nv - 1, q, v, V)
    basis_funs_inline(sv, v, q, V, Nv, left, right)
    for c in range(4):
        tmp[c] = 0.0
    for k in range(p + 1):
        row = su - p + k
        a0 = 0.0
        a1 = 0.0
        a2 = 0.0
        a3 = 0.0
        for l in range(q + 1):
            col = sv - q + l
            b = Nv[l]
            a0 += b * Pw[row, col, 0]
            a1 += b * Pw[row, col, 1]
            a2 += b * Pw[row, col, 2]
            a3 += b * Pw[row, col, 3]
        a = Nu[k]
        tmp[0] += a * a0
        tmp[1] += a * a1
        tmp[2] += a * a2
        tmp[3] += a * a3
    out[0] = tmp[0] / tmp[3]
    out[1] = tmp[1] / tmp[3]
    out[2] = tmp[2] / tmp[3]


@jit
def surface_point_d1(Pw, p, q, U, V, u, v, Du, Dv, left, right, SKL):
    """``S``, ``S_u``, ``S_v`` at ``(u, v)`` into ``SKL[0, 0]``, ``SKL[1, 0]``,
    ``SKL[0, 1]`` (``SKL[1, 1]`` untouched): :func:`surface_derivs` of order 1 without
    the mixed derivative, from :func:`.basis.basis_d1` (the cost of about two surface
    points).  ``Du`` (2, p+1), ``Dv`` (2, q+1), ``left``, ``right`` (max(p, q)+1):
    scratch."""
    su = find_span_inline(Pw.shape[0] - 1, p, u, U)
    basis_d1_inline(su, u, p, U, Du, left, right)
    sv = find_span_inline(Pw.shape[1] - 1, q, v, V)
    basis_d1_inline(sv, v, q, V, Dv, left, right)
    a0 = a1 = a2 = a3 = 0.0   # S w
    b0 = b1 = b2 = b3 = 0.0   # d/du
    c0 = c1 = c2 = c3 = 0.0   # d/dv
    for k in range(p + 1):
        row = su - p + k
        e0 = e1 = e2 = e3 = 0.0
        f0 = f1 = f2 = f3 = 0.0
        for l in range(q + 1):
            col = sv - q + l
            n = Dv[0, l]
            d = Dv[1, l]
            x0 = Pw[row, col, 0]
            x1 = Pw[row, col, 1]
            x2 = Pw[row, col, 2]
            x3 = Pw[row, col, 3]
            e0 += n * x0
            e1 += n * x1
            e2 += n * x2
            e3 += n * x3
            f0 += d * x0
            f1 += d * x1
            f2 += d * x2
            f3 += d * x3
        n = Du[0, k]
        d = Du[1, k]
        a0 += n * e0
        a1 += n * e1
        a2 += n * e2
        a3 += n * e3
        b0 += d * e0
        b1 += d * e1
        b2 += d * e2
        b3 += d * e3
        c0 += n * f0
        c1 += n * f1
        c2 += n * f2
        c3 += n * f3
    s0 = a0 / a3
    s1 = a1 / a3
    s2 = a2 / a3
    SKL[0, 0, 0] = s0
    SKL[0, 0, 1] = s1
    SKL[0, 0, 2] = s2
    SKL[1, 0, 0] = (b0 - b3 * s0) / a3
    SKL[1, 0, 1] = (b1 - b3 * s1) / a3
    SKL[1, 0, 2] = (b2 - b3 * s2) / a3
    SKL[0, 1, 0] = (c0 - c3 * s0) / a3
    SKL[0, 1, 1] = (c1 - c3 * s1) / a3
    SKL[0, 1, 2] = (c2 - c3 * s2) / a3


surface_point_d1_inline = jit_inline(surface_point_d1.py_func)
surface_point_inline = jit_inline(surface_point.py_func)
"""The same code compiled into its callers' loops (the same values): the calls' thirteen
arguments cost about a third of a point."""


@jit
def point_scratch(p, q):
    """Scratch for :func:`surface_point`: ``(Nu, Nv, left, right, tmp)``."""
    m = max(p, q) + 1
    return np.empty(p + 1), np.empty(q + 1), np.empty(m), np.empty(m), np.empty(4)


@jit
def surface_points_range(i0, i1, Pw, p, q, U, V, uv, out):
    _surface_points_loop(i0, i1, Pw, p, q, U, V, uv, out, point_scratch(p, q))


@jit
def _surface_points_loop(i0, i1, Pw, p, q, U, V, uv, out, scratch):
    """The loop of :func:`surface_points_range` over borrowed views (no atomic
    reference counting, :mod:`.numba_ext.borrow`)."""
    Pw, U, V, uv, out, (Nu, Nv, left, right, tmp) = borrow_all((Pw, U, V, uv, out, scratch))
    for i in range(i0, i1):
        surface_point(Pw, p, q, U, V, uv[i, 0], uv[i, 1], Nu, Nv, left, right, tmp, out[i])


def surface_points(Pw, p, q, U, V, uv, out):
    """Batch S(u, v) for ``uv`` (n, 2) into ``out`` (n, 3), parallel over points."""
    prun(surface_points_range, uv.shape[0], CHUNK, Pw, p, q, U, V, uv, out)


@jit
def _binomial_table(n):
    b = np.zeros((n + 1, n + 1))
    for i in range(n + 1):
        b[i, 0] = 1.0
        for j in range(1, i + 1):
            b[i, j] = b[i - 1, j - 1] + b[i - 1, j]
    return b


@jit
def derivs_scratch(p, q, d):
    """Scratch for :func:`surface_derivs`: (dNu, dNv, Aw, su_scratch, sv_scratch)."""
    return (np.empty((d + 1, p + 1)), np.empty((d + 1, q + 1)), np.empty((d + 1, d + 1, 4)),
            ders_scratch(p), ders_scratch(q))


@jit
def surface_derivs(Pw, p, q, U, V, u, v, d, bin_, scr, SKL):
    """All partial derivatives up to order ``d`` in each direction (A3.6 + A4.4).

    Fills ``SKL[k, l, :]`` = d^(k+l) S / du^k dv^l for ``0 <= k, l <= d`` (the full
    tensor; derivatives beyond the degree are exactly zero for the polynomial part).
    ``scr`` is scratch from :func:`derivs_scratch` with at least order ``d``; ``bin_``
    a binomial table of size at least (d+1, d+1).
    """
    dNu, dNv, Aw, sa, sb = scr
    nu = Pw.shape[0]
    nv = Pw.shape[1]
    du = d if d < p else p
    dv = d if d < q else q
    su = find_span_inline(nu - 1, p, u, U)
    ders_basis_funs_inline(su, u, p, du, U, dNu, sa[0], sa[1], sa[2], sa[3])
    sv = find_span_inline(nv - 1, q, v, V)
    ders_basis_funs_inline(sv, v, q, dv, V, dNv, sb[0], sb[1], sb[2], sb[3])
    for k in range(d + 1):
        for l in range(d + 1):
            for c in range(4):
                Aw[k, l, c] = 0.0
    for k in range(du + 1):
        for r in range(p + 1):
            a = dNu[k, r]
            if a == 0.0:
                continue
            row = su - p + r
            for l in range(dv + 1):
                t0 = 0.0
                t1 = 0.0
                t2 = 0.0
                t3 = 0.0
                for s in range(q + 1):
                    b = dNv[l, s]
                    col = sv - q + s
                    t0 += b * Pw[row, col, 0]
                    t1 += b * Pw[row, col, 1]
                    t2 += b * Pw[row, col, 2]
                    t3 += b * Pw[row, col, 3]
                Aw[k, l, 0] += a * t0
                Aw[k, l, 1] += a * t1
                Aw[k, l, 2] += a * t2
                Aw[k, l, 3] += a * t3
    w0 = Aw[0, 0, 3]
    for k in range(d + 1):
        for l in range(d + 1):
            for c in range(3):
                val = Aw[k, l, c]
                for j in range(1, l + 1):
                    val -= bin_[l, j] * Aw[0, j, 3] * SKL[k, l - j, c]
                for i in range(1, k + 1):
                    val -= bin_[k, i] * Aw[i, 0, 3] * SKL[k - i, l, c]
                    v2 = 0.0
                    for j in range(1, l + 1):
                        v2 += bin_[l, j] * Aw[i, j, 3] * SKL[k - i, l - j, c]
                    val -= bin_[k, i] * v2
                SKL[k, l, c] = val / w0


@jit
def _surface_derivatives_range(i0, i1, Pw, p, q, U, V, uv, d, out):
    bin_ = _binomial_table(d)
    scr = derivs_scratch(p, q, d)
    for i in range(i0, i1):
        surface_derivs(Pw, p, q, U, V, uv[i, 0], uv[i, 1], d, bin_, scr, out[i])


def surface_derivatives(Pw, p, q, U, V, uv, d, out):
    """Batch derivatives: ``out`` (n, d+1, d+1, 3), parallel over points."""
    prun(_surface_derivatives_range, uv.shape[0], CHUNK, Pw, p, q, U, V, uv, d, out)


@jit
def _invert_range(i0, i1, Pw, p, q, U, V, X, uv, u0, u1, v0, v1, stop, dist):
    bin_ = _binomial_table(D1)
    scr = derivs_scratch(p, q, D1)
    SKL = np.empty((2, 2, 3))
    for i in range(i0, i1):
        u = uv[i, 0]
        v = uv[i, 1]
        for _ in range(12):
            surface_derivs(Pw, p, q, U, V, u, v, D1, bin_, scr, SKL)
            a = b = c = g1 = g2 = 0.0
            for k in range(3):
                r = X[i, k] - SKL[0, 0, k]
                su = SKL[1, 0, k]
                sv = SKL[0, 1, k]
                a += su * su
                b += su * sv
                c += sv * sv
                g1 += su * r
                g2 += sv * r
            det = a * c - b * b
            du = dv = 0.0
            if det > 1e-300:
                du = (c * g1 - b * g2) / det
                dv = (a * g2 - b * g1) / det
            u = min(max(u + du, u0), u1)
            v = min(max(v + dv, v0), v1)
            if max(abs(du), abs(dv)) <= stop:
                break
        uv[i, 0] = u
        uv[i, 1] = v
        surface_derivs(Pw, p, q, U, V, u, v, D1, bin_, scr, SKL)
        dd = 0.0
        for k in range(3):
            dd += (SKL[0, 0, k] - X[i, k]) ** 2
        dist[i] = np.sqrt(dd)


def invert_points(Pw, p, q, U, V, X, uv, u0, u1, v0, v1, stop, dist):
    """Gauss-Newton from the parameters ``uv`` (n, 2), updated in place, towards the
    points ``X`` (n, 3) near the surface: at most 12 steps per point, each clamped to
    the domain, stopped when a step is at most ``stop`` in both parameters; ``dist``
    (n,) gets the distance from each point to the surface point reached."""
    prun(_invert_range, X.shape[0], CHUNK, Pw, p, q, U, V, X, uv, u0, u1, v0, v1, stop,
         dist)


@jit_inline
def _cross_into(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@jit_inline
def _norm3(a):
    return np.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


@jit
def surface_normal(Pw, p, q, U, V, u, v, umin, umax, vmin, vmax, degen_rel,
                   bin_, scr, SKL, out):
    """Unit normal ``Su x Sv / |Su x Sv|`` at (u, v), written to ``out[0:3]``.

    Where the surface is degenerate (a pole: a collapsed control row makes ``Su`` or
    ``Sv`` vanish), the normal is the limit taken from inside the domain:
    ``Su ~ h Suv`` as the parameter distance ``h`` to the collapsed row goes to 0, so
    ``N ~ sign(h) Suv x Sv`` (and symmetrically for ``Sv``).  If that is degenerate too,
    the normal is taken at parameters nudged toward the domain centre.  Returns 0 for a
    regular point, 1 for a limit normal, 2 for a nudged normal, 3 if no normal exists.
    """
    surface_derivs(Pw, p, q, U, V, u, v, D1, bin_, scr, SKL)
    su = SKL[1, 0]
    sv = SKL[0, 1]
    _cross_into(su, sv, out)
    lu = _norm3(su)
    lv = _norm3(sv)
    ln = _norm3(out)
    scale = max(lu, lv)
    regular = ln > degen_rel * scale * scale and ln > 0.0
    if regular and min(lu, lv) > POLE_RATIO * scale:
        for c in range(3):
            out[c] /= ln
        return 0
    # at or next to a degenerate point (pole): the limit normal from the mixed
    # derivative is accurate to O(h), where the cross product has lost digits
    r0 = out[0]
    r1 = out[1]
    r2 = out[2]
    surface_derivs(Pw, p, q, U, V, u, v, D2, bin_, scr, SKL)
    su = SKL[1, 0]
    sv = SKL[0, 1]
    if lu <= lv:
        # Su vanishes along v = const: N ~ sign(v - v0) * (Suv x Sv)
        sgn = 1.0 if v <= 0.5 * (vmin + vmax) else -1.0
        _cross_into(SKL[1, 1], sv, out)
    else:
        sgn = 1.0 if u <= 0.5 * (umin + umax) else -1.0
        _cross_into(su, SKL[1, 1], out)
    lm = _norm3(out)
    if lm > degen_rel * max(scale, _norm3(SKL[1, 1])) ** 2 and lm > 0.0:
        if regular:  # near (not at) the pole: the side is the regular normal's
            sgn = 1.0 if out[0] * r0 + out[1] * r1 + out[2] * r2 >= 0.0 else -1.0
        for c in range(3):
            out[c] *= sgn / lm
        return 1
    if regular:
        out[0] = r0 / ln
        out[1] = r1 / ln
        out[2] = r2 / ln
        return 0
    # nudge toward the centre of the domain
    cu = 0.5 * (umin + umax)
    cv = 0.5 * (vmin + vmax)
    h = 1e-9
    for _ in range(10):  # h up to 1: never leave the domain
        uu = u + h * (cu - u)
        vv = v + h * (cv - v)
        surface_derivs(Pw, p, q, U, V, uu, vv, D1, bin_, scr, SKL)
        _cross_into(SKL[1, 0], SKL[0, 1], out)
        ln = _norm3(out)
        scale = max(_norm3(SKL[1, 0]), _norm3(SKL[0, 1]))
        if ln > degen_rel * scale * scale and ln > 0.0:
            for c in range(3):
                out[c] /= ln
            return 2
        h *= 10.0
    for c in range(3):
        out[c] = 0.0
    return 3


@jit
def _surface_normals_range(i0, i1, Pw, p, q, U, V, uv, umin, umax, vmin, vmax, degen_rel,
                           out, status):
    bin_ = _binomial_table(D2)
    scr = derivs_scratch(p, q, D2)
    SKL = np.empty((3, 3, 3))
    for i in range(i0, i1):
        status[i] = surface_normal(Pw, p, q, U, V, uv[i, 0], uv[i, 1], umin, umax,
                                   vmin, vmax, degen_rel, bin_, scr, SKL, out[i])


def surface_normals(Pw, p, q, U, V, uv, umin, umax, vmin, vmax, degen_rel, out, status):
    """Batch unit normals ``out`` (n, 3) with per-point ``status`` (n,) int8."""
    prun(_surface_normals_range, uv.shape[0], CHUNK, Pw, p, q, U, V, uv, umin, umax, vmin,
         vmax, degen_rel, out, status)


# ------------------------------------------------ order-2 derivatives, fixed size
@jit_inline
def _basis_d2(i, u, p, U, D, W, left, right, A):
    """Basis functions and their first and second derivatives at ``u`` in span ``i``:
    ``D[0..2, 0..p]`` (rows: N, N', N'').

    The degree p-2 and p-1 functions are by-products of the triangular recurrence
    (A2.2: kept in rows 2 and 1 of ``W``); the derivatives follow from them by the
    derivative formula (The NURBS Book eq. 2.7) applied once and twice, with one
    division per knot difference.  ``W`` (>= 3 x (p+1) for p >= 2, else (p+1) x
    (p+1)), ``left``/``right`` (p+1) and ``A`` (>= 1 x (p+1)) are scratch: the arrays
    of :func:`derivs_scratch`.  Every knot difference used is the support of a basis
    function that is non-zero on the (non-empty) span, so none is zero.
    """
    D[0, 0] = 1.0
    if p == 1:
        W[1, 0] = 1.0
    elif p == 2:
        W[2, 0] = 1.0
    for j in range(1, p + 1):
        left[j] = u - U[i + 1 - j]
        right[j] = U[i + j] - u
        saved = 0.0
        for r in range(j):
            temp = D[0, r] / (right[r + 1] + left[j - r])
            D[0, r] = saved + right[r + 1] * temp
            saved = left[j - r] * temp
        D[0, j] = saved
        if j == p - 1:
            for r in range(j + 1):
                W[1, r] = D[0, r]
        elif j == p - 2:
            for r in range(j + 1):
                W[2, r] = D[0, r]
    if p == 0:
        D[1, 0] = 0.0
        D[2, 0] = 0.0
        return
    # right[r] = 1 / (U[i + r] - U[i + r - p]), r = 1..p (supports of degree p-1)
    for r in range(1, p + 1):
        right[r] = 1.0 / (U[i + r] - U[i + r - p])
    for r in range(p + 1):
        t = 0.0
        if r >= 1:
            t += W[1, r - 1] * right[r]
        if r <= p - 1:
            t -= W[1, r] * right[r + 1]
        D[1, r] = p * t
    if p == 1:
        D[2, 0] = 0.0
        D[2, 1] = 0.0
        return
    # left[r] = 1 / (U[i + r] - U[i + r + 1 - p]), r = 1..p-1 (supports of degree p-2);
    # A[0, r] = N'_{i-p+1+r, p-1}, r = 0..p-1
    for r in range(1, p):
        left[r] = 1.0 / (U[i + r] - U[i + r + 1 - p])
    for r in range(p):
        t = 0.0
        if r >= 1:
            t += W[2, r - 1] * left[r]
        if r <= p - 2:
            t -= W[2, r] * left[r + 1]
        A[0, r] = (p - 1) * t
    for r in range(p + 1):
        t = 0.0
        if r >= 1:
            t += A[0, r - 1] * right[r]
        if r <= p - 1:
            t -= A[0, r] * right[r + 1]
        D[2, r] = p * t


@jit
def surface_derivs2(Pw, p, q, U, V, u, v, scr, SKL):
    """The derivatives of order k + l <= 2: ``SKL[k, l, :]`` for (0,0), (1,0), (0,1),
    (2,0), (1,1), (0,2) — what a Newton step on |S - x|^2 needs (the other entries of
    ``SKL`` are left as they are).

    Same values as :func:`surface_derivs` with ``d = 2`` (to rounding), at about a
    third of its cost: basis derivatives from the recurrence's by-products
    (:func:`_basis_d2`), one pass over the (p+1)(q+1) control points accumulating the
    six homogeneous derivatives in registers, and the rational quotient rule (A4.4)
    written out for these six.  ``scr`` is :func:`derivs_scratch` of at least the
    surface's degrees (any order >= 2 ... the arrays are only used as scratch).
    """
    dNu, dNv, Aw, sa, sb = scr
    su = find_span_inline(Pw.shape[0] - 1, p, u, U)
    _basis_d2(su, u, p, U, dNu, sa[0], sa[1], sa[2], sa[3])
    sv = find_span_inline(Pw.shape[1] - 1, q, v, V)
    _basis_d2(sv, v, q, V, dNv, sb[0], sb[1], sb[2], sb[3])
    a00x = a00y = a00z = a00w = 0.0
    a10x = a10y = a10z = a10w = 0.0
    a01x = a01y = a01z = a01w = 0.0
    a20x = a20y = a20z = a20w = 0.0
    a11x = a11y = a11z = a11w = 0.0
    a02x = a02y = a02z = a02w = 0.0
    for r in range(p + 1):
        row = su - p + r
        t0x = t0y = t0z = t0w = 0.0
        t1x = t1y = t1z = t1w = 0.0
        t2x = t2y = t2z = t2w = 0.0
        for s in range(q + 1):
            col = sv - q + s
            px = Pw[row, col, 0]
            py = Pw[row, col, 1]
            pz = Pw[row, col, 2]
            pw = Pw[row, col, 3]
            b = dNv[0, s]
            t0x += b * px
            t0y += b * py
            t0z += b * pz
            t0w += b * pw
            b = dNv[1, s]
            t1x += b * px
            t1y += b * py
            t1z += b * pz
            t1w += b * pw
            b = dNv[2, s]
            t2x += b * px
            t2y += b * py
            t2z += b * pz
            t2w += b * pw
        a = dNu[0, r]
        a00x += a * t0x
        a00y += a * t0y
        a00z += a * t0z
        a00w += a * t0w
        a01x += a * t1x
        a01y += a * t1y
        a01z += a * t1z
        a01w += a * t1w
        a02x += a * t2x
        a02y += a * t2y
        a02z += a * t2z
        a02w += a * t2w
        a = dNu[1, r]
        a10x += a * t0x
        a10y += a * t0y
        a10z += a * t0z
        a10w += a * t0w
        a11x += a * t1x
        a11y += a * t1y
        a11z += a * t1z
        a11w += a * t1w
        a = dNu[2, r]
        a20x += a * t0x
        a20y += a * t0y
        a20z += a * t0z
        a20w += a * t0w
    # quotient rule (A4.4) for k + l <= 2
    iw = 1.0 / a00w
    s00x = a00x * iw
    s00y = a00y * iw
    s00z = a00z * iw
    s10x = (a10x - a10w * s00x) * iw
    s10y = (a10y - a10w * s00y) * iw
    s10z = (a10z - a10w * s00z) * iw
    s01x = (a01x - a01w * s00x) * iw
    s01y = (a01y - a01w * s00y) * iw
    s01z = (a01z - a01w * s00z) * iw
    SKL[0, 0, 0] = s00x
    SKL[0, 0, 1] = s00y
    SKL[0, 0, 2] = s00z
    SKL[1, 0, 0] = s10x
    SKL[1, 0, 1] = s10y
    SKL[1, 0, 2] = s10z
    SKL[0, 1, 0] = s01x
    SKL[0, 1, 1] = s01y
    SKL[0, 1, 2] = s01z
    SKL[2, 0, 0] = (a20x - 2.0 * a10w * s10x - a20w * s00x) * iw
    SKL[2, 0, 1] = (a20y - 2.0 * a10w * s10y - a20w * s00y) * iw
    SKL[2, 0, 2] = (a20z - 2.0 * a10w * s10z - a20w * s00z) * iw
    SKL[1, 1, 0] = (a11x - a10w * s01x - a01w * s10x - a11w * s00x) * iw
    SKL[1, 1, 1] = (a11y - a10w * s01y - a01w * s10y - a11w * s00y) * iw
    SKL[1, 1, 2] = (a11z - a10w * s01z - a01w * s10z - a11w * s00z) * iw
    SKL[0, 2, 0] = (a02x - 2.0 * a01w * s01x - a02w * s00x) * iw
    SKL[0, 2, 1] = (a02y - 2.0 * a01w * s01y - a02w * s00y) * iw
    SKL[0, 2, 2] = (a02z - 2.0 * a01w * s01z - a02w * s00z) * iw


@jit
def homogeneous_net(P, W, rational):
    """``(Pw, ok, unit)`` of a control net ``P`` (nu, nv, 3) and its weights ``W``
    (nu, nv; read only when ``rational``): the homogeneous points ``(w x, w y, w z,
    w)``, whether they are finite and the weights positive, and whether every weight
    is 1 (numpy's ``P * W[..., None]``: the same products)."""
    nu, nv = P.shape[0], P.shape[1]
    Pw = np.empty((nu, nv, 4))
    ok = True
    unit = True
    for i in range(nu):
        for j in range(nv):
            w = W[i, j] if rational else 1.0
            for c in range(3):
                x = P[i, j, c] * w
                Pw[i, j, c] = x
                ok = ok and x - x == 0.0
            Pw[i, j, 3] = w
            ok = ok and w - w == 0.0 and w > 0.0
            unit = unit and w == 1.0
    return Pw, ok, unit
