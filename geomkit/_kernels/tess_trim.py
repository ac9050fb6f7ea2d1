"""Trim polylines for tessellation: adaptive midpoint subdivision in one kernel call.

A trim piece ``C(t)`` (a rational 2-D curve) on a surface ``S`` becomes the polyline
through ``C(t_i)``; a segment ``[ta, tb]`` is accepted when the points
``S(C(ta + f (tb - ta)))`` and ``S(C(ta) + f (C(tb) - C(ta)))`` for ``f`` in
``{1/4, 1/2, 3/4}`` (the exact boundary curve, and the image of the UV chord, which
the mesh boundary also follows where it crosses cell edges) all lie within
``chord_tol`` of the 3-D chord ``S(C(ta))``–``S(C(tb))``; otherwise it is split at its
parameter midpoint.  Curve points are clipped to the domain box (trim curves may stray
outside it by the validation tolerance).
"""

from __future__ import annotations

import numpy as np

from ._numba import jit
from .bezier import curve_derivs
from .surface import surface_point

MAX_DEPTH = 60
"""Halvings of one starting segment at most (the parameter step then reaches rounding)."""


@jit
def _curve_at(Pc, pc, Uc, t, lo0, lo1, hi0, hi1, dN, cd, zero):
    curve_derivs(Pc, pc, Uc, t, zero, dN, cd)
    return min(max(cd[0, 0], lo0), hi0), min(max(cd[0, 1], lo1), hi1)


@jit
def trim_polyline(Pc, pc, Uc, t0, lo0, lo1, hi0, hi1, Pw, p, q, U, V, chord_tol, out):
    """Polyline of one trim piece, starting from the parameters ``t0`` (sorted).

    Writes ``(t, u, v)`` rows into ``out`` (capacity, 3) in curve order, the last row
    at ``t0[-1]``; returns the row count, or -1 when ``out`` is too small (call again
    with a larger one)."""
    zero = 0
    dN = np.empty((1, pc + 1))
    cd = np.empty((1, 2))
    mm = max(p, q) + 1
    Nu = np.empty(p + 1)
    Nv = np.empty(q + 1)
    left = np.empty(mm)
    right = np.empty(mm)
    tmp = np.empty(4)
    Pa = np.empty(3)
    Pb = np.empty(3)
    X = np.empty(3)
    # the stack holds the right ends of pending segments: (t, u, v, x, y, z, depth)
    stack = np.empty((MAX_DEPTH + 2, 7))
    cap = out.shape[0]
    n = 0
    ta = t0[0]
    ua, va = _curve_at(Pc, pc, Uc, ta, lo0, lo1, hi0, hi1, dN, cd, zero)
    surface_point(Pw, p, q, U, V, ua, va, Nu, Nv, left, right, tmp, Pa)
    for i in range(1, t0.shape[0]):
        tb = t0[i]
        ub, vb = _curve_at(Pc, pc, Uc, tb, lo0, lo1, hi0, hi1, dN, cd, zero)
        surface_point(Pw, p, q, U, V, ub, vb, Nu, Nv, left, right, tmp, Pb)
        stack[0, 0] = tb
        stack[0, 1] = ub
        stack[0, 2] = vb
        stack[0, 3] = Pb[0]
        stack[0, 4] = Pb[1]
        stack[0, 5] = Pb[2]
        stack[0, 6] = 0
        top = 1
        while top > 0:
            tb = stack[top - 1, 0]
            ub = stack[top - 1, 1]
            vb = stack[top - 1, 2]
            depth = int(stack[top - 1, 6])
            d0 = stack[top - 1, 3] - Pa[0]
            d1 = stack[top - 1, 4] - Pa[1]
            d2 = stack[top - 1, 5] - Pa[2]
            ll = d0 * d0 + d1 * d1 + d2 * d2
            worst = 0.0
            for s in range(6):
                f = 0.25 * (s % 3 + 1)
                if s < 3:
                    su, sv = _curve_at(Pc, pc, Uc, ta + (tb - ta) * f, lo0, lo1, hi0, hi1,
                                       dN, cd, zero)
                else:
                    su = ua + (ub - ua) * f
                    sv = va + (vb - va) * f
                surface_point(Pw, p, q, U, V, su, sv, Nu, Nv, left, right, tmp, X)
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
                worst = max(worst, np.sqrt(g0 * g0 + g1 * g1 + g2 * g2))
            if worst > chord_tol and depth < MAX_DEPTH:
                # split: the midpoint becomes the right end of the left half (on top)
                tm = 0.5 * (ta + tb)
                um, vm = _curve_at(Pc, pc, Uc, tm, lo0, lo1, hi0, hi1, dN, cd, zero)
                surface_point(Pw, p, q, U, V, um, vm, Nu, Nv, left, right, tmp, X)
                stack[top - 1, 6] = depth + 1
                stack[top, 0] = tm
                stack[top, 1] = um
                stack[top, 2] = vm
                stack[top, 3] = X[0]
                stack[top, 4] = X[1]
                stack[top, 5] = X[2]
                stack[top, 6] = depth + 1
                top += 1
                continue
            # accepted: emit its start, its end becomes the next start
            if n >= cap:
                return -1
            out[n, 0] = ta
            out[n, 1] = ua
            out[n, 2] = va
            n += 1
            ta = tb
            ua = ub
            va = vb
            Pa[0] = stack[top - 1, 3]
            Pa[1] = stack[top - 1, 4]
            Pa[2] = stack[top - 1, 5]
            top -= 1
    if n >= cap:
        return -1
    out[n, 0] = ta
    out[n, 1] = ua
    out[n, 2] = va
    return n + 1
