"""Knot insertion, Bézier extraction and curve evaluation kernels.

Control points are homogeneous rows ``(w x_1, ..., w x_k, w)`` of any width, so one
kernel serves 2-D trim curves, 3-D curves and (row by row) surfaces.

Algorithms: curve knot insertion (The NURBS Book A5.1), decomposition into Bézier
segments (A5.6), de Casteljau subdivision, curve derivatives (A3.2 + A4.2).
"""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit_plain as jit, prun

from .basis import ders_basis_funs_inline, ders_scratch, find_span_inline

CURVE_CHUNK = 1024
"""Curve parameters per parallel task: a curve point costs ~0.1-0.2 us, so a smaller
task is cheaper than handing it to another thread (a reader evaluates thousands of
edges at 65-257 parameters each)."""


@jit
def count_segments(U, p):
    """Number of non-empty knot spans of a clamped vector (= Bézier segments)."""
    m = U.shape[0] - 1
    count = 0
    for i in range(p, m - p):
        if U[i + 1] > U[i]:
            count += 1
    return count


@jit
def decompose(Pw, p, U):
    """Split a clamped NURBS curve into Bézier segments (A5.6).

    Parameters
    ----------
    Pw : (n, dim) homogeneous control points.
    p : degree.
    U : (n + p + 1,) clamped knot vector.

    Returns
    -------
    Q : (nseg, p + 1, dim) homogeneous Bézier control points, one row per segment,
        consecutive segments sharing end points exactly.
    breaks : (nseg + 1,) parameter values of the segment ends.
    """
    n = Pw.shape[0]
    dim = Pw.shape[1]
    m = n + p  # index of the last knot
    nseg = count_segments(U, p)
    Q = np.zeros((nseg, p + 1, dim))
    breaks = np.empty(nseg + 1)
    alphas = np.empty(max(p, 1))
    a = p
    b = p + 1
    nb = 0
    breaks[0] = U[p]
    # element loops, not slice expressions: no shape-check raise path to compile
    for i in range(p + 1):
        for c in range(dim):
            Q[0, i, c] = Pw[i, c]
    while b < m:
        i = b
        while b < m and U[b + 1] == U[b]:
            b += 1
        mult = b - i + 1
        if mult < p:
            numer = U[b] - U[a]
            for j in range(p, mult, -1):
                alphas[j - mult - 1] = numer / (U[a + j] - U[a])
            r = p - mult
            for j in range(1, r + 1):
                save = r - j
                s = mult + j
                for k in range(p, s - 1, -1):
                    alpha = alphas[k - s]
                    for c in range(dim):
                        Q[nb, k, c] = alpha * Q[nb, k, c] + (1.0 - alpha) * Q[nb, k - 1, c]
                if b < m and nb + 1 < nseg:
                    for c in range(dim):
                        Q[nb + 1, save, c] = Q[nb, p, c]
        breaks[nb + 1] = U[b]
        nb += 1
        if b < m and nb < nseg:
            for k in range(p - mult, p + 1):
                for c in range(dim):
                    Q[nb, k, c] = Pw[b - p + k, c]
            a = b
            b += 1
    return Q, breaks


@jit
def insert_knot(Pw, p, U, u, r):
    """Insert ``u`` ``r`` times into a clamped curve (A5.1); returns (Qw, UQ).

    The caller guarantees ``r + s <= p`` where ``s`` is the existing multiplicity.
    """
    n = Pw.shape[0]
    dim = Pw.shape[1]
    # the span of u in the full vector (U[k] <= u < U[k+1]); unlike find_span this is
    # right for the ends of an unclamped vector too
    k = np.searchsorted(U, u, side="right") - 1
    s = 0
    for i in range(U.shape[0]):
        if U[i] == u:
            s += 1
    UQ = np.empty(U.shape[0] + r)
    for i in range(k + 1):
        UQ[i] = U[i]
    for i in range(1, r + 1):
        UQ[k + i] = u
    for i in range(k + 1, U.shape[0]):
        UQ[i + r] = U[i]
    # element loops, not row-slice assignments: no shape-check raise path to compile
    Qw = np.empty((n + r, dim))
    for i in range(k - p + 1):
        for c in range(dim):
            Qw[i, c] = Pw[i, c]
    for i in range(k - s, n):
        for c in range(dim):
            Qw[i + r, c] = Pw[i, c]
    Rw = np.empty((p + 1, dim))
    for i in range(p - s + 1):
        for c in range(dim):
            Rw[i, c] = Pw[k - p + i, c]
    L = k - p + 1
    for j in range(1, r + 1):
        L = k - p + j
        for i in range(p - j - s + 1):
            alpha = (u - U[L + i]) / (U[i + k + 1] - U[L + i])
            for c in range(dim):
                Rw[i, c] = alpha * Rw[i + 1, c] + (1.0 - alpha) * Rw[i, c]
        for c in range(dim):
            Qw[L, c] = Rw[0, c]
            Qw[k + r - j - s, c] = Rw[p - j - s, c]
    for i in range(L + 1, k - s):
        for c in range(dim):
            Qw[i, c] = Rw[i - L, c]
    return Qw, UQ


@jit
def _snap(U, t, eps):
    """``t``, or the first knot of ``U`` nearest it when within ``eps``."""
    k = 0
    best = abs(U[0] - t)
    for i in range(U.shape[0]):
        d = abs(U[i] - t)
        if d != d:  # (numpy's argmin stops at the first NaN)
            k, best = i, d
            break
        if d < best:
            k, best = i, d
    return U[k] if best <= eps else t


@jit
def _first_and_count(U, t):
    """Index of the first knot equal to ``t`` (-1: none) and how many are."""
    first, s = -1, 0
    for i in range(U.shape[0]):
        if U[i] == t:
            if first < 0:
                first = i
            s += 1
    return first, s


@jit
def restrict_curve(p, U, Pw, t0, t1, eps):
    """The curve ``(p, U, Pw)`` restricted to ``[t0, t1]`` (within its domain) by knot
    insertion (A5.1): ``(whole, U', Pw')``, ``whole`` when an end within ``eps`` of a
    knot is moved onto it and the range is then the whole domain (``U'``, ``Pw'``
    empty).  Each end is inserted to multiplicity ``p``; ``U'`` is clamped at the
    ends."""
    n = Pw.shape[0]
    t0 = _snap(U, t0, eps)
    t1 = _snap(U, t1, eps)
    if t0 <= U[p] and t1 >= U[n]:
        return True, U[:0].copy(), Pw[:0].copy()
    for t in (t0, t1):
        _, s = _first_and_count(U, t)
        if s < p:
            Pw, U = insert_knot(Pw, p, U, t, p - s)
    first_a, s_a = _first_and_count(U, t0)
    start = first_a + s_a - 1 - p
    first_b, _ = _first_and_count(U, t1)
    newU = U[start: first_b + p + 1].copy()
    newU[: p + 1] = t0
    newU[newU.shape[0] - p - 1:] = t1
    return False, newU, Pw[start: first_b].copy()


@jit
def de_casteljau_split(Q, t, left, right):
    """Split the Bézier segment ``Q`` (p+1, dim) at ``t`` into ``left`` and ``right``."""
    p = Q.shape[0] - 1
    dim = Q.shape[1]
    # element loops, not slice expressions: no temporaries and no shape-check raise
    # path (its string formatting alone costs seconds of compile)
    for i in range(p + 1):
        for c in range(dim):
            right[i, c] = Q[i, c]
    for c in range(dim):
        left[0, c] = Q[0, c]
    for r in range(1, p + 1):
        for i in range(p - r + 1):
            for c in range(dim):
                right[i, c] = (1.0 - t) * right[i, c] + t * right[i + 1, c]
        for c in range(dim):
            left[r, c] = right[0, c]


@jit
def curve_derivs(Pw, p, U, t, d, dN, out):
    """Point and derivatives up to order ``d`` of a NURBS curve (A3.2 + A4.2).

    ``Pw`` (n, k+1) homogeneous; fills ``out`` (d+1, k) with C, C', ..., C^(d).
    ``dN`` is scratch of shape (d+1, p+1).
    """
    n = Pw.shape[0]
    k = Pw.shape[1] - 1
    du = d if d < p else p
    span = find_span_inline(n - 1, p, t, U)
    ndu, left, right, a = ders_scratch(p)
    ders_basis_funs_inline(span, t, p, du, U, dN, ndu, left, right, a)
    Aw = np.zeros((d + 1, k + 1))
    for j in range(du + 1):  # element loops: no shape-check raise path to compile
        for r in range(p + 1):
            for c in range(k + 1):
                Aw[j, c] += dN[j, r] * Pw[span - p + r, c]
    for j in range(d + 1):
        for c in range(k):
            val = Aw[j, c]
            binom = 1.0
            for i in range(1, j + 1):
                binom = binom * (j - i + 1) / i
                val -= binom * Aw[i, k] * out[j - i, c]
            out[j, c] = val / Aw[0, k]


@jit
def _curve_points_range(i0, i1, Pw, p, U, t, d, out):
    for i in range(i0, i1):
        dN = np.empty((d + 1, p + 1))
        curve_derivs(Pw, p, U, t[i], d, dN, out[i])


def curve_points(Pw, p, U, t, d, out):
    """Batch curve points and derivatives: ``out`` (m, d+1, k), parallel over ``t``."""
    prun(_curve_points_range, t.shape[0], CURVE_CHUNK, Pw, p, U, t, d, out)


@jit
def curve_nearest_param(Pw, p, U, X, m):
    """The parameter of the point of a 3-D NURBS curve nearest to ``X`` (3,) from a
    start point: the nearest of ``m`` equally spaced parameters, then Newton on
    ``(C - X) . C'`` (clamped to the domain, at most 30 steps, stopped when a step
    is below 1e-15 of the domain or the second derivative term is not positive)."""
    n = Pw.shape[0]
    lo, hi = U[p], U[n]
    d = 2 if p >= 2 else p
    dN = np.empty((d + 1, p + 1))
    D = np.empty((d + 1, 3))
    best, t0 = np.inf, lo
    for i in range(m):
        t = lo + (hi - lo) * (i / (m - 1))
        curve_derivs(Pw, p, U, t, 0, dN, D)
        dd = (D[0, 0] - X[0]) ** 2 + (D[0, 1] - X[1]) ** 2 + (D[0, 2] - X[2]) ** 2
        if dd < best:
            best, t0 = dd, t
    for _ in range(30):
        curve_derivs(Pw, p, U, t0, d, dN, D)
        f = 0.0
        fp = 0.0
        for c in range(3):
            f += (D[0, c] - X[c]) * D[1, c]
            fp += D[1, c] * D[1, c]
            if d >= 2:
                fp += (D[0, c] - X[c]) * D[2, c]
        if not fp > 0:
            break
        t1 = min(hi, max(lo, t0 - f / fp))
        if abs(t1 - t0) <= 1e-15 * max(1.0, hi - lo):
            t0 = t1
            break
        t0 = t1
    return t0
