"""Feet on trim boundaries: the nearest point of a trimmed face's boundary curves,
by a safeguarded 1-D Newton on each exact rational trim segment mapped by S."""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit, jit_inline, prun
from .project_newton import MAX_ITER
from .project_bilinear import derivs2
from .surface import D2, _binomial_table, derivs_scratch

TRIM_FEET_CHUNK = 16


@jit
def _bernstein(n, t, out):
    """Bernstein polynomials of degree n >= 0 at t into out[:n+1] (triangle recursion)."""
    out[0] = 1.0
    for k in range(1, n + 1):
        saved = 0.0
        for j in range(k):
            tj = out[j]
            out[j] = saved + (1.0 - t) * tj
            saved = t * tj
        out[k] = saved


@jit
def _bernstein_d2(n, t, B, B1, B2):
    """Bernstein polynomials of degree n at t (B) and their first (B1) and second (B2)
    derivatives: B'_i = n (b_{i-1} - b_i) with b of degree n - 1, and
    B''_i = n (n - 1) (c_{i-2} - 2 c_{i-1} + c_i) with c of degree n - 2."""
    _bernstein(n, t, B)
    for i in range(n + 1):
        B1[i] = 0.0
        B2[i] = 0.0
    if n >= 1:
        _bernstein(n - 1, t, B1)  # b, degree n - 1, in B1[:n]
        prev = 0.0
        for i in range(n + 1):
            cur = B1[i] if i < n else 0.0
            B1[i] = n * (prev - cur)
            prev = cur
    if n >= 2:
        _bernstein(n - 2, t, B2)  # c, degree n - 2, in B2[:n-1]
        p2 = 0.0
        p1 = 0.0
        for i in range(n + 1):
            cur = B2[i] if i < n - 1 else 0.0
            B2[i] = n * (n - 1) * (p2 - 2.0 * p1 + cur)
            p2 = p1
            p1 = cur


@jit
def trim_curve_d2(Q, n, t, B, B1, B2, out):
    """Rational 2-D Bézier curve (homogeneous control points ``Q`` (n+1, 3)) at t:
    ``out[0]`` = C, ``out[1]`` = C', ``out[2]`` = C''."""
    _bernstein_d2(n, t, B, B1, B2)
    # homogeneous value and derivatives in registers (no array per call)
    a0 = a1 = aw = d0 = d1 = dw = e0 = e1 = ew = 0.0
    for i in range(n + 1):
        q0 = Q[i, 0]
        q1 = Q[i, 1]
        qw = Q[i, 2]
        a0 += B[i] * q0
        a1 += B[i] * q1
        aw += B[i] * qw
        d0 += B1[i] * q0
        d1 += B1[i] * q1
        dw += B1[i] * qw
        e0 += B2[i] * q0
        e1 += B2[i] * q1
        ew += B2[i] * qw
    C = a0 / aw
    C1 = (d0 - dw * C) / aw
    out[0, 0] = C
    out[1, 0] = C1
    out[2, 0] = (e0 - 2.0 * dw * C1 - ew * C) / aw
    C = a1 / aw
    C1 = (d1 - dw * C) / aw
    out[0, 1] = C
    out[1, 1] = C1
    out[2, 1] = (e1 - 2.0 * dw * C1 - ew * C) / aw


@jit_inline
def _trim_point(Pw, p, q, U, V, dom, Q, n, t, x, bin_, scr, SKL, B, B1, B2, Cd):
    """f, f', f'' of f(t) = |S(C(t)) - x|^2 / 2 and the 3-D speed |dS/dt|."""
    trim_curve_d2(Q, n, t, B, B1, B2, Cd)
    u = min(dom[1], max(dom[0], Cd[0, 0]))
    v = min(dom[3], max(dom[2], Cd[0, 1]))
    derivs2(Pw, p, q, U, V, u, v, scr, SKL)
    cu = Cd[1, 0]
    cv = Cd[1, 1]
    f = 0.0
    g = 0.0
    hh = 0.0
    sp = 0.0
    for c in range(3):
        r = SKL[0, 0, c] - x[c]
        St = SKL[1, 0, c] * cu + SKL[0, 1, c] * cv
        Stt = (SKL[2, 0, c] * cu * cu + 2.0 * SKL[1, 1, c] * cu * cv + SKL[0, 2, c] * cv * cv
               + SKL[1, 0, c] * Cd[2, 0] + SKL[0, 1, c] * Cd[2, 1])
        f += r * r
        g += r * St
        hh += St * St + r * Stt
        sp += St * St
    return 0.5 * f, g, hh, math.sqrt(sp), u, v


@jit
def segment_newton(Pw, p, q, U, V, dom, Q, nd, t, x, step_tol, bin_, scr, SKL, B, B1, B2, Cd):
    """Safeguarded 1-D Newton on |S(C(t)) - x|^2 / 2 over one trim segment ``Q`` (degree
    ``nd``), t in [0, 1], from ``t``: Newton step where the second derivative is
    positive, else a gradient step scaled by the speed; halving line search; stops on a
    step below ``step_tol`` (model units) or at an end it is pushed against.
    Returns ``(t, f)``."""
    f, g, hh, sp, u, v = _trim_point(Pw, p, q, U, V, dom, Q, nd, t, x, bin_, scr, SKL, B, B1,
                                     B2, Cd)
    for _ in range(MAX_ITER):
        dt = -g / hh if hh > 0.0 else -g / (sp * sp + 1e-300)
        if (t <= 0.0 and dt < 0.0) or (t >= 1.0 and dt > 0.0):
            break
        alpha = 1.0
        ok = False
        tn = t
        for _ls in range(60):
            tn = min(1.0, max(0.0, t + alpha * dt))
            fn, gn, hn, spn, un, vn = _trim_point(Pw, p, q, U, V, dom, Q, nd, tn, x, bin_,
                                                  scr, SKL, B, B1, B2, Cd)
            if fn <= f:
                ok = True
                break
            alpha *= 0.5
        if not ok:
            break
        step = abs(tn - t) * sp
        moved = tn != t
        t, f, g, hh, sp = tn, fn, gn, hn, spn
        if step <= step_tol or not moved:
            break
    return t, f


@jit
def _trim_feet_range(i0, i1, P, Pw, p, q, U, V, dom, seg, deg, near, samp_seg, samp_t,
                     step_tol, out_uv, out_d, out_seg, out_t):
    pmax = seg.shape[1] - 1
    _trim_feet_loop(i0, i1, P, Pw, p, q, U, V, dom, seg, deg, near, samp_seg, samp_t,
                    step_tol, out_uv, out_d, out_seg, out_t, _binomial_table(D2),
                    derivs_scratch(p, q, D2), np.empty((3, 3, 3)),
                    (np.empty(pmax + 1), np.empty(pmax + 1), np.empty(pmax + 1),
                     np.empty((3, 2))))


@jit
def _trim_feet_loop(i0, i1, P, Pw, p, q, U, V, dom, seg, deg, near, samp_seg, samp_t,
                    step_tol, out_uv, out_d, out_seg, out_t, bin_, scr, SKL, bern):
    """The loop of :func:`_trim_feet_range` over borrowed views (no atomic reference
    counting, :mod:`.numba_ext.borrow`)."""
    (P, Pw, U, V, dom, seg, deg, near, samp_seg, samp_t, out_uv, out_d, out_seg, out_t,
     bin_, scr, SKL, bern) = borrow_all((P, Pw, U, V, dom, seg, deg, near, samp_seg,
                                         samp_t, out_uv, out_d, out_seg, out_t, bin_, scr,
                                         SKL, bern))
    B, B1, B2, Cd = bern
    for i in range(i0, i1):
        x = P[i]
        out_d[i] = np.inf
        for r in range(near.shape[1]):
            k = near[i, r]
            if k < 0:
                continue
            sg = samp_seg[k]
            nd = deg[sg]
            Q = seg[sg]
            t = samp_t[k]
            t, f = segment_newton(Pw, p, q, U, V, dom, Q, nd, t, x, step_tol, bin_, scr,
                                  SKL, B, B1, B2, Cd)
            d = math.sqrt(2.0 * f)
            if d < out_d[i]:
                out_d[i] = d
                trim_curve_d2(Q, nd, t, B, B1, B2, Cd)
                out_uv[i, 0] = min(dom[1], max(dom[0], Cd[0, 0]))
                out_uv[i, 1] = min(dom[3], max(dom[2], Cd[0, 1]))
                out_seg[i] = sg
                out_t[i] = t


def trim_feet(P, Pw, p, q, U, V, dom, seg, deg, near, samp_seg, samp_t, step_tol,
              out_uv, out_d, out_seg, out_t):
    """Nearest point of each point on the trim boundary of one surface.

    Starts from the boundary samples ``near[i]`` (indices into ``samp_*``: points
    S(C(t)) on the segments, -1 for none; the caller finds the three nearest with a
    k-d tree), then a safeguarded 1-D Newton in each segment's parameter t in [0, 1].
    """
    prun(_trim_feet_range, P.shape[0], TRIM_FEET_CHUNK, P, Pw, p, q, U, V, dom, seg, deg,
         near, samp_seg, samp_t, step_tol, out_uv, out_d, out_seg, out_t)


@jit
def trim_samples(seg, deg, per_segment, out_uv, out_seg, out_t):
    """``per_segment`` parameter samples of every trim segment, t in [0, 1]."""
    pmax = seg.shape[1] - 1
    B = np.empty(pmax + 1)
    B1 = np.empty(pmax + 1)
    B2 = np.empty(pmax + 1)
    Cd = np.empty((3, 2))
    k = 0
    for s in range(seg.shape[0]):
        for j in range(per_segment):
            t = j / (per_segment - 1.0)
            trim_curve_d2(seg[s], deg[s], t, B, B1, B2, Cd)
            out_uv[k, 0] = Cd[0, 0]
            out_uv[k, 1] = Cd[0, 1]
            out_seg[k] = s
            out_t[k] = t
            k += 1
