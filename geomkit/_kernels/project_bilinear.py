"""Order-2 derivatives of a degree (1, 1) surface (planar faces, bilinear patches) for
the projection kernels, without the general basis recurrence.

:func:`geomkit._kernels.surface.surface_derivs2` costs ~0.4 µs whatever the degree
(span search, the A2.2 recurrence with its divisions, scratch arrays); on a bilinear
piece the basis is two linear functions per direction, so the six derivatives of
order <= 2 take a few dozen flops: the homogeneous ones are

    A = sum N_i(u) M_j(v) P_ij,  A_u = ((1 - b) (P_10 - P_00) + b (P_11 - P_01)) / du,
    A_uv = (P_11 - P_10 - P_01 + P_00) / (du dv),  A_uu = A_vv = 0

(a, b the local parameters in the span, du, dv its widths), then the quotient rule.
The span is :func:`geomkit._kernels.basis.find_span`'s (right-continuous at an
interior knot), so the values are those of ``surface_derivs2`` to rounding.
"""

from __future__ import annotations

from .numba_ext.policy import jit, jit_inline
from .basis import find_span
from .surface import surface_derivs2


@jit
def derivs2_bilinear(Pw, U, V, u, v, SKL):
    """``SKL[k, l, :]`` for k + l <= 2 of the degree (1, 1) surface (Pw, U, V) at (u, v)
    (the other entries are left as they are)."""
    i = find_span(Pw.shape[0] - 1, 1, u, U)
    j = find_span(Pw.shape[1] - 1, 1, v, V)
    du = U[i + 1] - U[i]
    dv = V[j + 1] - V[j]
    a = (u - U[i]) / du
    b = (v - V[j]) / dv
    ia = 1.0 / du
    ib = 1.0 / dv
    a0 = 1.0 - a
    b0 = 1.0 - b
    # the weight and its derivatives
    p00 = Pw[i - 1, j - 1, 3]
    p10 = Pw[i, j - 1, 3]
    p01 = Pw[i - 1, j, 3]
    p11 = Pw[i, j, 3]
    lo = b0 * p00 + b * p01  # along v at u = U[i]
    hi = b0 * p10 + b * p11
    w = a0 * lo + a * hi
    wu = (hi - lo) * ia
    wv = (a0 * (p01 - p00) + a * (p11 - p10)) * ib
    wuv = (p11 - p10 - p01 + p00) * (ia * ib)
    for c in range(3):
        p00 = Pw[i - 1, j - 1, c]
        p10 = Pw[i, j - 1, c]
        p01 = Pw[i - 1, j, c]
        p11 = Pw[i, j, c]
        lo = b0 * p00 + b * p01
        hi = b0 * p10 + b * p11
        SKL[0, 0, c] = a0 * lo + a * hi
        SKL[1, 0, c] = (hi - lo) * ia
        SKL[0, 1, c] = (a0 * (p01 - p00) + a * (p11 - p10)) * ib
        SKL[1, 1, c] = (p11 - p10 - p01 + p00) * (ia * ib)
    iw = 1.0 / w
    for c in range(3):
        s = SKL[0, 0, c] * iw
        su = (SKL[1, 0, c] - wu * s) * iw
        sv = (SKL[0, 1, c] - wv * s) * iw
        SKL[0, 0, c] = s
        SKL[1, 0, c] = su
        SKL[0, 1, c] = sv
        SKL[2, 0, c] = -2.0 * wu * su * iw
        SKL[1, 1, c] = (SKL[1, 1, c] - wu * sv - wv * su - wuv * s) * iw
        SKL[0, 2, c] = -2.0 * wv * sv * iw


@jit_inline
def derivs2(Pw, p, q, U, V, u, v, scr, SKL):
    """:func:`geomkit._kernels.surface.surface_derivs2`, by :func:`derivs2_bilinear`
    on a degree (1, 1) surface.  Inlined at the numba IR level: as a call of its own
    (with the ~10 array arguments exploded and reference-counted) it cost ~250 ns per
    evaluation on top of the ~30 ns bilinear one."""
    if p == 1 and q == 1:
        derivs2_bilinear(Pw, U, V, u, v, SKL)
    else:
        surface_derivs2(Pw, p, q, U, V, u, v, scr, SKL)
