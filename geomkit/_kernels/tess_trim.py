"""Trim polylines for tessellation: adaptive subdivision in one kernel call.

A trim piece ``C(t)`` (a rational 2-D curve) on a surface ``S`` becomes the polyline
through ``C(t_i)``; a segment ``[ta, tb]`` is accepted when the points
``S(C(ta + f (tb - ta)))`` and ``S(C(ta) + f (C(tb) - C(ta)))`` for ``f`` in
``{1/4, 1/2, 3/4}`` (the exact boundary curve, and the image of the UV chord, which
the mesh boundary also follows where it crosses cell edges) all lie within
``chord_tol`` of the 3-D chord ``S(C(ta))``–``S(C(tb))``; otherwise it is split into
``k`` equal parameter parts, ``k`` predicted from the measured error (chord errors
fall with the square of the step), each part tested again.  Curve points are clipped
to the domain box (trim curves may stray outside it by the validation tolerance).
"""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit
from .basis import basis_funs, find_span
from .surface import surface_point

MAX_DEPTH = 60
"""Splits of one starting segment at most (the parameter step then reaches rounding)."""
MAX_PARTS = 64
"""A failing segment is split into at most this many equal parameter parts."""
SPLIT_AIM = 0.8
"""Parts are sized for a predicted chord error of ``SPLIT_AIM * chord_tol``."""


@jit
def _curve_at(Pc, pc, Uc, t, lo0, lo1, hi0, hi1, N, left, right):
    """``C(t)`` of a rational 2-D curve (homogeneous ``Pc`` (n, 3)), clipped to the
    box; no allocation (A2.1, A2.2, then the weighted sum)."""
    span = find_span(Pc.shape[0] - 1, pc, t, Uc)
    basis_funs(span, t, pc, Uc, N, left, right)
    x = 0.0
    y = 0.0
    w = 0.0
    for r in range(pc + 1):
        b = N[r]
        x += b * Pc[span - pc + r, 0]
        y += b * Pc[span - pc + r, 1]
        w += b * Pc[span - pc + r, 2]
    return min(max(x / w, lo0), hi0), min(max(y / w, lo1), hi1)


@jit
def trim_polyline(Pc, pc, Uc, t0, lo0, lo1, hi0, hi1, Pw, p, q, U, V, chord_tol, uv_chords,
                  out):
    """Polyline of one trim piece, starting from the parameters ``t0`` (sorted).

    ``uv_chords`` False skips the samples of the UV chord (for a surface that is an
    affine map of its parameters they lie on the 3-D chord).  Writes ``(t, u, v)`` rows
    into ``out`` (capacity, 3) in curve order, the last row
    at ``t0[-1]``; returns the row count, or -1 when ``out`` is too small (call again
    with a larger one)."""
    Nc = np.empty(pc + 1)
    lc = np.empty(pc + 1)
    rc = np.empty(pc + 1)
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
    stack = np.empty(((MAX_DEPTH + 2) * MAX_PARTS, 7))
    cap = out.shape[0]
    n = 0
    ta = t0[0]
    ua, va = _curve_at(Pc, pc, Uc, ta, lo0, lo1, hi0, hi1, Nc, lc, rc)
    surface_point(Pw, p, q, U, V, ua, va, Nu, Nv, left, right, tmp, Pa)
    for i in range(1, t0.shape[0]):
        tb = t0[i]
        ub, vb = _curve_at(Pc, pc, Uc, tb, lo0, lo1, hi0, hi1, Nc, lc, rc)
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
            for s in range(6 if uv_chords else 3):
                f = 0.25 * (s % 3 + 1)
                if s < 3:
                    su, sv = _curve_at(Pc, pc, Uc, ta + (tb - ta) * f, lo0, lo1, hi0, hi1,
                                       Nc, lc, rc)
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
                # split into k equal parameter parts, k from the measured excess (a
                # chord's error falls with the square of its length; parts that
                # still fail are split again): their inner ends go on the stack,
                # the leftmost on top
                k = int(np.ceil(np.sqrt(worst / (SPLIT_AIM * chord_tol))))
                k = min(max(k, 2), MAX_PARTS)
                stack[top - 1, 6] = depth + 1
                for j in range(k - 1, 0, -1):
                    tm = ta + (tb - ta) * (j / k)
                    um, vm = _curve_at(Pc, pc, Uc, tm, lo0, lo1, hi0, hi1, Nc, lc, rc)
                    surface_point(Pw, p, q, U, V, um, vm, Nu, Nv, left, right, tmp, X)
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
