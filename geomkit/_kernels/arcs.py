"""Exact control nets the CAD readers build thousands of: rational quadratic arcs
(every circle edge), surfaces of revolution and plane patches, each in one call with
the arithmetic of the numpy formulas they replace (:func:`geomkit.cad.analytic.
arc_curve`, :func:`~geomkit.cad.analytic.revolve`, :func:`~geomkit.cad.analytic.
plane_patch`): the same operations in the same order, none contracted unless named
(:func:`~geomkit._kernels.numba_ext.fused.fma`), so the same values.

An arc ``[theta0, theta1]`` has ``n = ceil(sweep / (pi / 2))`` spans of angle ``d``;
its knots are the span ends, doubled inside; per span the control points are the span
start, the tangents' meeting point (weight ``cos(d / 2)``) and the span end.
"""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.fused import fma
from .numba_ext.policy import jit_exact as jit


@jit
def arc_coeffs(theta0, theta1):
    """``(a, b, w, U)``: per control point of the arc ``[theta0, theta1]`` (``theta1 >
    theta0``) the point ``O + r (a X + b Y)`` and its weight ``w``, and the knots."""
    sweep = theta1 - theta0
    n = max(1, int(math.ceil(sweep / (0.5 * math.pi) - 1e-12)))
    d = sweep / n
    U = np.empty(2 * n + 4)
    U[0] = U[1] = U[2] = theta0
    for k in range(1, n):
        U[2 * k + 1] = U[2 * k + 2] = theta0 + d * float(k)
    U[2 * n + 1] = U[2 * n + 2] = U[2 * n + 3] = theta1
    m = 2 * n + 1
    a = np.empty(m)
    b = np.empty(m)
    w = np.empty(m)
    wm = math.cos(d / 2)
    j = 0
    for k in range(n):
        t0 = theta0 + k * d
        tm = t0 + d / 2
        if k == 0:
            a[j], b[j], w[j] = math.cos(t0), math.sin(t0), 1.0
            j += 1
        a[j], b[j], w[j] = math.cos(tm) / wm, math.sin(tm) / wm, wm
        t1 = theta1 if k == n - 1 else t0 + d
        a[j + 1], b[j + 1], w[j + 1] = math.cos(t1), math.sin(t1), 1.0
        j += 2
    return a, b, w, U


@jit
def arc_net(C, X, Y, radius, theta0, theta1):
    """``(U, Pw)`` of the arc ``C + radius (cos t X + sin t Y)``, ``t`` in ``[theta0,
    theta1]``: knots and homogeneous control points."""
    a, b, w, U = arc_coeffs(theta0, theta1)
    m = a.shape[0]
    Pw = np.empty((m, 4))
    for j in range(m):
        for c in range(3):
            Pw[j, c] = (C[c] + radius * (a[j] * X[c] + b[j] * Y[c])) * w[j]
        Pw[j, 3] = w[j]
    return U, Pw



@jit
def circle_nets(C, x, y, r, t, same, use):
    """Every circle edge's curve as the STEP reader builds it one by one (the arc
    ``arc_net(C[k], r[k] x[k], r[k] y[k], 1, t[k, 0], t[k, 1])``, run backwards as
    :func:`geomkit.cad.stepgeom.reverse_curve` runs it where ``same[k]`` is False), for
    the edges ``use[k]``: ``(ok, U, Pw, uoff, poff)``, edge ``k``'s knots ``U[uoff[k]:
    uoff[k + 1]]`` and points ``Pw[poff[k]:poff[k + 1]]`` (none where not used); ``ok``
    False when a used edge's sweep is not finite and positive (nothing built: the
    caller's route names it)."""
    n = C.shape[0]
    uoff = np.zeros(n + 1, np.int64)
    poff = np.zeros(n + 1, np.int64)
    for k in range(n):
        nu = npw = 0
        if use[k]:
            sweep = t[k, 1] - t[k, 0]
            if not (sweep > 0 and math.isfinite(sweep)):
                return False, np.empty(0), np.empty((0, 4)), uoff, poff
            m = max(1, int(math.ceil(sweep / (0.5 * math.pi) - 1e-12)))
            nu, npw = 2 * m + 4, 2 * m + 1
        uoff[k + 1] = uoff[k] + nu
        poff[k + 1] = poff[k] + npw
    U = np.empty(uoff[n])
    Pw = np.empty((poff[n], 4))
    X = np.empty(3)
    Y = np.empty(3)
    for k in range(n):
        if not use[k]:
            continue
        for c in range(3):
            X[c] = r[k] * x[k, c]
            Y[c] = r[k] * y[k, c]
        Uk, Pk = arc_net(C[k], X, Y, 1.0, t[k, 0], t[k, 1])
        mu, mp = Uk.shape[0], Pk.shape[0]
        a, b = uoff[k], poff[k]
        for j in range(mu):
            U[a + j] = Uk[j] if same[k] else (Uk[0] + Uk[mu - 1]) - Uk[mu - 1 - j]
        for j in range(mp):
            src = j if same[k] else mp - 1 - j
            for c in range(4):
                Pw[b + j, c] = Pk[src, c]
    return True, U, Pw, uoff, poff


@jit
def _dot3(x0, x1, x2, y0, y1, y2):
    """The dot product as numpy's 1-D ``dot`` of two 3-vectors computes it (OpenBLAS's
    ``ddot``: the first product, then each next one fused into the sum)."""
    return fma(x2, y2, fma(x1, y1, x0 * y0))


@jit
def revolve_net(Pw, S, T, theta0, theta1):
    """``(V, P (n, m, 3), W (n, m))`` of the generatrix with homogeneous control
    points ``Pw`` (n, 4) turned about the axis through ``S`` along the unit vector
    ``T`` by ``[theta0, theta1]`` (:func:`geomkit.cad.analytic.revolve`, The NURBS
    Book A8.1, with its numpy arithmetic: each control point's foot on the axis, its
    radius and direction, then the arc's points ``O + r (a X + b Y)``); a control
    point on the axis stays there."""
    a, b, wa, V = arc_coeffs(theta0, theta1)
    n = Pw.shape[0]
    m = a.shape[0]
    out = np.empty((n, m, 3))
    W = np.empty((n, m))
    O = np.empty(3)
    X = np.empty(3)
    Y = np.empty(3)
    for j in range(n):
        w = Pw[j, 3]
        p0, p1, p2 = Pw[j, 0] / w, Pw[j, 1] / w, Pw[j, 2] / w
        h = _dot3(p0 - S[0], p1 - S[1], p2 - S[2], T[0], T[1], T[2])
        for c in range(3):
            O[c] = S[c] + h * T[c]
        X[0], X[1], X[2] = p0 - O[0], p1 - O[1], p2 - O[2]
        r = math.sqrt(_dot3(X[0], X[1], X[2], X[0], X[1], X[2]))
        big = abs(p0)
        for v in (abs(p1), abs(p2)):
            if v != v or v > big:  # (np.max: a NaN wins)
                big = v
        for k in range(m):
            W[j, k] = w * wa[k]
        if r <= 1e-15 * (big if big > 1.0 else 1.0):
            for k in range(m):
                for c in range(3):
                    out[j, k, c] = O[c]
            continue
        for c in range(3):
            X[c] = X[c] / r
        Y[0] = T[1] * X[2] - T[2] * X[1]
        Y[1] = T[2] * X[0] - T[0] * X[2]
        Y[2] = T[0] * X[1] - T[1] * X[0]
        for k in range(m):
            for c in range(3):
                out[j, k, c] = O[c] + r * (a[k] * X[c] + b[k] * Y[c])
    return V, out, W


@jit
def plane_net(O, X, Y, u0, u1, v0, v1):
    """The control points (2, 2, 3) of the bilinear patch ``O + u X + v Y`` over
    ``[u0, u1] x [v0, v1]`` (:func:`geomkit.cad.analytic.plane_patch`'s numpy
    arithmetic)."""
    P = np.empty((2, 2, 3))
    for i in range(2):
        u = u0 if i == 0 else u1
        for j in range(2):
            v = v0 if j == 0 else v1
            for c in range(3):
                P[i, j, c] = (O[c] + u * X[c]) + v * Y[c]
    return P


@jit
def line_edges(O, D, X1, X2, same):
    """Line edges ``O[k] + t D[k]`` between the vertices ``X1[k]``, ``X2[k]``, as the
    STEP reader builds them one by one (numpy's arithmetic, its dots OpenBLAS's):
    ``(ok, U (n, 4), Pw (n, 2, 4))``, each edge's segment over its vertices'
    parameters (swapped when ``same[k]`` is False, then the curve run backwards), ok
    False where the parameters are not increasing."""
    n = O.shape[0]
    ok = np.zeros(n, dtype=np.bool_)
    U = np.empty((n, 4))
    Pw = np.ones((n, 2, 4))
    for k in range(n):
        d0, d1, d2 = D[k, 0], D[k, 1], D[k, 2]
        dd = _dot3(d0, d1, d2, d0, d1, d2)
        t1 = _dot3(X1[k, 0] - O[k, 0], X1[k, 1] - O[k, 1], X1[k, 2] - O[k, 2],
                   d0, d1, d2) / dd
        t2 = _dot3(X2[k, 0] - O[k, 0], X2[k, 1] - O[k, 1], X2[k, 2] - O[k, 2],
                   d0, d1, d2) / dd
        if not same[k]:
            t1, t2 = t2, t1
        if not t2 > t1:
            continue
        ok[k] = True
        for c in range(3):
            Pw[k, 0, c] = O[k, c] + t1 * D[k, c]
            Pw[k, 1, c] = O[k, c] + t2 * D[k, c]
        U[k, 0] = U[k, 1] = t1
        U[k, 2] = U[k, 3] = t2
        if not same[k]:  # stepgeom.reverse_curve: (U[0] + U[-1]) - U[::-1], rows reversed
            s = t1 + t2
            U[k, 0] = U[k, 1] = s - t2
            U[k, 2] = U[k, 3] = s - t1
            for c in range(3):
                a = Pw[k, 0, c]
                Pw[k, 0, c] = Pw[k, 1, c]
                Pw[k, 1, c] = a
    return ok, U, Pw


@jit
def circle_frames(Z, Xd, C, r, X1, X2, same, closed):
    """Circle edges as the STEP reader builds them one by one (numpy's arithmetic, its
    dots OpenBLAS's): per edge ``(ok, x (n, 3), y (n, 3), t (n, 2))``, the circle's
    in-plane axes (``x`` made orthogonal to the unit normal ``Z[k]`` and unit, ``y =
    z x x``) and its vertices' angles, swapped when ``same[k]`` is False, the end a
    turn or less after the start (a whole turn when ``closed[k]`` or the two meet);
    ok False where ``x`` is (nearly) along ``z`` or an angle is NaN."""
    n = Z.shape[0]
    ok = np.zeros(n, dtype=np.bool_)
    x = np.empty((n, 3))
    y = np.empty((n, 3))
    t = np.empty((n, 2))
    two_pi = 2.0 * math.pi
    for k in range(n):
        z0, z1, z2 = Z[k, 0], Z[k, 1], Z[k, 2]
        xz = _dot3(Xd[k, 0], Xd[k, 1], Xd[k, 2], z0, z1, z2)
        if abs(xz) > 1 - 1e-12:
            continue
        ok[k] = True
        a0, a1, a2 = Xd[k, 0] - xz * z0, Xd[k, 1] - xz * z1, Xd[k, 2] - xz * z2
        m = math.sqrt(_dot3(a0, a1, a2, a0, a1, a2))
        a0, a1, a2 = a0 / m, a1 / m, a2 / m
        b0, b1, b2 = z1 * a2 - z2 * a1, z2 * a0 - z0 * a2, z0 * a1 - z1 * a0
        x[k, 0], x[k, 1], x[k, 2] = a0, a1, a2
        y[k, 0], y[k, 1], y[k, 2] = b0, b1, b2
        rk = r[k]
        for j in range(2):
            P = X1 if j == 0 else X2
            d0, d1, d2 = P[k, 0] - C[k, 0], P[k, 1] - C[k, 1], P[k, 2] - C[k, 2]
            tj = math.atan2(_dot3(d0, d1, d2, b0, b1, b2) / rk,
                            _dot3(d0, d1, d2, a0, a1, a2) / rk) % two_pi
            # a tiny negative angle wraps to 2 pi itself in floats: it is 0
            t[k, j] = 0.0 if tj >= two_pi else tj
        t1, t2 = t[k, 0], t[k, 1]
        if not same[k]:
            t1, t2 = t2, t1
        t2 = t1 + (t2 - t1) % two_pi
        if closed[k] or t2 - t1 <= 1e-12:
            t2 = t1 + two_pi
        t[k, 0], t[k, 1] = t1, t2
        ok[k] = t2 > t1  # (a NaN angle: no edge)
    return ok, x, y, t


@jit
def analytic_frame(O, A, X):
    """The frame of :class:`geomkit.cad.brep.Analytic` as its numpy code made it: ``A``
    over its norm, ``X - (X . A) A`` over its norm, ``Y = A x X`` (the dots
    OpenBLAS's, :func:`_dot3`; no contraction): ``(code, A, X, Y, frame)`` with
    ``frame`` ``O, X, Y, A`` (12,); ``code`` 1 / 2 when the norm of ``A`` / of the
    made ``X`` is not positive (nothing else made: the caller names it), else 0."""
    a0, a1, a2 = A[0], A[1], A[2]
    n = math.sqrt(_dot3(a0, a1, a2, a0, a1, a2))
    e = np.empty(0)
    if not n > 0:
        return 1, e, e, e, e
    a0, a1, a2 = a0 / n, a1 / n, a2 / n
    d = _dot3(X[0], X[1], X[2], a0, a1, a2)
    x0, x1, x2 = X[0] - d * a0, X[1] - d * a1, X[2] - d * a2
    m = math.sqrt(_dot3(x0, x1, x2, x0, x1, x2))
    if not m > 0:
        return 2, e, e, e, e
    x0, x1, x2 = x0 / m, x1 / m, x2 / m
    y0, y1, y2 = a1 * x2 - a2 * x1, a2 * x0 - a0 * x2, a0 * x1 - a1 * x0
    Av = np.empty(3)
    Xv = np.empty(3)
    Yv = np.empty(3)
    frame = np.empty(12)
    Av[0], Av[1], Av[2] = a0, a1, a2
    Xv[0], Xv[1], Xv[2] = x0, x1, x2
    Yv[0], Yv[1], Yv[2] = y0, y1, y2
    for c in range(3):
        frame[c] = O[c]
        frame[3 + c] = Xv[c]
        frame[6 + c] = Yv[c]
        frame[9 + c] = Av[c]
    return 0, Av, Xv, Yv, frame


@jit
def axis2_x(Z, X, E):
    """The unit reference direction of an axis placement as the STEP reader computed
    it with numpy (``StepGeometry.axis2``, ISO 10303-42 ``build_axes``): ``X`` (None:
    absent) replaced by ``E[0]`` (+x), or ``E[1]`` (+y) when ``|Z[0]| >= 0.9``, if absent
    or ``|X . Z| > 1 - 1e-12``; then ``X - (X . Z) Z`` divided by its norm.  The dots
    are OpenBLAS's (:func:`_dot3`); the defaults come in as data (``E``), not
    constants, so that no ``0 - y`` is folded to ``-y`` (signed zeros kept)."""
    z0, z1, z2 = Z[0], Z[1], Z[2]
    use = X is None
    if X is not None:
        x0, x1, x2 = X[0], X[1], X[2]
        use = abs(_dot3(x0, x1, x2, z0, z1, z2)) > 1 - 1e-12
    if use:
        e = 0 if abs(z0) < 0.9 else 1
        x0, x1, x2 = E[e, 0], E[e, 1], E[e, 2]
    d = _dot3(x0, x1, x2, z0, z1, z2)
    a0, a1, a2 = x0 - d * z0, x1 - d * z1, x2 - d * z2
    m = math.sqrt(_dot3(a0, a1, a2, a0, a1, a2))
    out = np.empty(3)
    out[0], out[1], out[2] = a0 / m, a1 / m, a2 / m
    return out


@jit
def axis2_zx(z, x, E):
    """``StepGeometry.axis2``'s ``(Z, X)`` from the DIRECTION records' numbers ``z``
    and ``x`` (None: no reference direction) at once, as a (2, 3) array: each divided
    by its norm (``StepGeometry.direction``), then :func:`axis2_x`'s arithmetic.  A
    (0, 3) array when a norm is not positive and finite (the caller reads the records
    the long way)."""
    n = math.sqrt(_dot3(z[0], z[1], z[2], z[0], z[1], z[2]))
    if not (n > 0 and math.isfinite(n)):
        return np.empty((0, 3))
    Z = np.empty(3)
    Z[0], Z[1], Z[2] = z[0] / n, z[1] / n, z[2] / n
    if x is None:
        X = axis2_x(Z, None, E)
    else:
        n = math.sqrt(_dot3(x[0], x[1], x[2], x[0], x[1], x[2]))
        if not (n > 0 and math.isfinite(n)):
            return np.empty((0, 3))
        Xu = np.empty(3)
        Xu[0], Xu[1], Xu[2] = x[0] / n, x[1] / n, x[2] / n
        X = axis2_x(Z, Xu, E)
    out = np.empty((2, 3))
    out[0] = Z
    out[1] = X
    return out
