"""Second-order certificate of a projection foot: candidates it settles without a
Newton run of their own.

Let uv* be a converged Newton foot of the point x on surface S (a KKT point of
f(u, v) = |S(u, v) - x|^2 / 2 over the domain box) at distance d*, with residual
r* = S(uv*) - x, Jacobian J* = [S_u S_v] and gradient g = J*^T r*, and let
B = [ua, ub] x [va, vb] be a parameter box inside the domain and inside one C0 piece
of the surface, containing uv*.  For uv = uv* + delta in B, Taylor's formula with
the integral remainder (the segment lies in B) gives
``S(uv) - x = r* + J* delta + R`` with
``|R| <= Q(delta) / 2``, ``Q(delta) = Muu du^2 + 2 Muv |du dv| + Mvv dv^2`` (Muu, Muv,
Mvv: true bounds of |S_uu|, |S_uv|, |S_vv| over B, from the sub-span bounds of
:mod:`geomkit.projection_cert`), and
``|r* + J* delta|^2 = d*^2 + 2 g.delta + |J* delta|^2``.

In parameters scaled by the tangent lengths (delta' = (|S_u*| du, |S_v*| dv)):
``|J* delta|^2 >= sigma^2 |delta'|^2`` with sigma^2 = 1 - |cos(S_u*, S_v*)|, and
``Q <= K |delta'|^2`` with K the largest eigenvalue of
[[Muu a^2, Muv a b], [Muv a b, Mvv b^2]] (a = 1 / |S_u*|, b = 1 / |S_v*|).  If

    mu = sigma^2 - (d* K + K^2 rho^2 / 4) > 0      (rho = max |delta'| over B)

then ``|r* + J* delta|^2 >= (d* + Q/2)^2 + mu |delta'|^2 + 2 g.delta
>= (d* + Q/2)^2 - e`` with ``e = |g'|^2 / mu`` (g' the scaled gradient; its components
along an active domain bound are dropped: there g.delta >= 0 for every delta into
B), hence over all of B ``|S(uv) - x| >= d* - e / d*`` (when e <= d*^2; else
``d* - sqrt(e)``).  A converged foot's gradient is tiny (|g'| ~ 1e-9 leaves
e / d* ~ 1e-18), and with that loss below ``LOSS_TOL`` times the Newton step
tolerance (rounding level) every candidate triangle whose parameter triangle lies in
B is *settled*: its Newton run would find no nearer point.  A candidate is only
settled when its whole surface piece lies in its parameter triangle: never a
triangle on a trim boundary (the face runs past it there).

Geometrically: the box may be as large as the surface's radius of curvature allows
(d* K ~ d* / R, K rho ~ box size / R), so the neighbours of the nearest triangle of a
scan point, whose first-order bounds ``d(x, t) - e_t`` always reach below d*, are
settled without Newton runs; near a centre of curvature (d* ~ R) it refuses.
"""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.policy import jit, jit_inline

CERT_MARGIN = 1e-9
"""Relative margin of the certificate's inequality (rounding of its evaluation)."""
LOSS_TOL = 1e-3
"""A settled candidate may hold a point at most this times the Newton step tolerance
(1e-12 of the model size by default) nearer than the foot: rounding level."""


@jit
def _cell(b, t):
    """Index of the sub-span of the borders ``b`` holding ``t`` (a border belongs to the
    sub-span on its right; clamped to the first / last)."""
    i = np.searchsorted(b, t, side="right") - 1
    return min(max(i, 0), b.shape[0] - 2)


@jit_inline
def box_bounds(cbrk, bnd, bo, brk_u, brk_v, ua, ub, va, vb):
    """``(ok, Mu, Mv, Muu, Muv, Mvv)``: bounds of ``|S_u|``, ``|S_v|``, ``|S_uu|``,
    ``|S_uv|``, ``|S_vv|`` over the parameter box [ua, ub] x [va, vb] (the largest of
    the sub-span bounds ``bnd`` of the cells it meets; ``bo`` the surface's row of
    ``bnd_off``, ``cbrk`` the cell borders); ok is False when a C0 piece border
    (``brk_u`` / ``brk_v``, domain ends included) lies in the closed box."""
    for j in range(1, brk_u.shape[0] - 1):
        if ua <= brk_u[j] <= ub:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0
    for j in range(1, brk_v.shape[0] - 1):
        if va <= brk_v[j] <= vb:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0
    bu = cbrk[bo[1]:bo[1] + bo[2]]
    bv = cbrk[bo[3]:bo[3] + bo[4]]
    ia = _cell(bu, ua)
    ib = _cell(bu, ub)
    ja = _cell(bv, va)
    jb = _cell(bv, vb)
    nv = bo[4] - 1
    Mu = 0.0
    Mv = 0.0
    Muu = 0.0
    Muv = 0.0
    Mvv = 0.0
    for iu in range(ia, ib + 1):
        row = bo[0] + iu * nv
        for iv in range(ja, jb + 1):
            Mu = max(Mu, bnd[row + iv, 0])
            Mv = max(Mv, bnd[row + iv, 1])
            Muu = max(Muu, bnd[row + iv, 2])
            Muv = max(Muv, bnd[row + iv, 3])
            Mvv = max(Mvv, bnd[row + iv, 4])
    return True, Mu, Mv, Muu, Muv, Mvv


@jit
def _cert_box(cbrk, bnd, bo, brk_u, brk_v, dm, u, v, d, SKL, x, step_tol, ua, ub, va,
              vb):
    """True when the certificate (module docstring) holds on the box
    [ua, ub] x [va, vb] around the foot (u, v)."""
    # one C0 piece: no interior crease in the closed box (a foot on a crease, where f
    # has a kink, is never certified)
    ok, _, _, Muu, Muv, Mvv = box_bounds(cbrk, bnd, bo, brk_u, brk_v, ua, ub, va, vb)
    if not ok:
        return False
    su0, su1, su2 = SKL[1, 0, 0], SKL[1, 0, 1], SKL[1, 0, 2]
    sv0, sv1, sv2 = SKL[0, 1, 0], SKL[0, 1, 1], SKL[0, 1, 2]
    la = math.sqrt(su0 * su0 + su1 * su1 + su2 * su2)
    lb = math.sqrt(sv0 * sv0 + sv1 * sv1 + sv2 * sv2)
    if not (la > 0.0 and lb > 0.0):
        return False  # a pole: no certificate
    sig2 = 1.0 - abs(su0 * sv0 + su1 * sv1 + su2 * sv2) / (la * lb) - 1e-12
    A = Muu / (la * la)
    B = Muv / (la * lb)
    C = Mvv / (lb * lb)
    K = 0.5 * (A + C) + math.sqrt(0.25 * (A - C) ** 2 + B * B)
    ru = max(u - ua, ub - u) * la
    rv = max(v - va, vb - v) * lb
    mu = sig2 - (d * K + 0.25 * K * K * (ru * ru + rv * rv)) * (1.0 + CERT_MARGIN)
    if not mu > 0.0:
        return False
    r0 = SKL[0, 0, 0] - x[0]
    r1 = SKL[0, 0, 1] - x[1]
    r2 = SKL[0, 0, 2] - x[2]
    gu = (r0 * su0 + r1 * su1 + r2 * su2) / la
    gv = (r0 * sv0 + r1 * sv1 + r2 * sv2) / lb
    # an active domain bound: every delta into the box has g.delta >= 0 there
    if (u <= dm[0] and gu >= 0.0) or (u >= dm[1] and gu <= 0.0):
        gu = 0.0
    if (v <= dm[2] and gv >= 0.0) or (v >= dm[3] and gv <= 0.0):
        gv = 0.0
    # the most a point of B can be nearer than d*: |g'|^2 / (mu d*) (second order in
    # the foot's residual gradient), or |g'| / sqrt(mu) when that is not smaller
    e = (gu * gu + gv * gv) / mu
    loss = e / d if e <= d * d else math.sqrt(e)
    return loss <= LOSS_TOL * step_tol


@jit
def _open(c, settled, ct, cd, fdev, face_surf, tbox, s, best):
    """Candidate ``c`` is still to settle: not settled yet, on surface ``s``, with a
    box of its surface piece (``tbox[t]`` not NaN) and could hold a point within
    ``best``."""
    t = ct[c]
    return (settled[c] == 0 and face_surf[t] == s and tbox[t, 0] == tbox[t, 0]
            and cd[c] - fdev[t] <= best)


@jit
def cert_settle(cbrk, bnd, bo, brk_u, brk_v, dm, u, v, d, SKL, x, step_tol, s, c0, k,
                best, ct, cd, fdev, face_surf, tbox, settled):
    """Mark (``settled[c] = 1``) the candidates ``c0 <= c < k`` of surface ``s`` that
    are not settled yet, could hold a point within ``best`` (lower bound
    ``cd[c] - fdev[t] <= best``) and have a box ``tbox[t]`` = (umin, umax, vmin,
    vmax) of their piece of the face (the parameter triangle, grown by the hull of
    the trim arc of a boundary edge: :func:`geomkit.projection_trim.cert_boxes`; NaN:
    never settled) when the certificate (module docstring) holds on the box of those
    and the foot (u, v) at distance ``d`` — all of them in one box, else each in its
    own; ``SKL`` holds the derivatives at the foot, ``x`` is the point, ``dm`` the
    domain (umin, umax, vmin, vmax), ``brk_u`` / ``brk_v`` the C0 piece borders
    (domain ends included) and ``bo`` the surface's row of ``bnd_off``
    (:func:`geomkit.projection_cert.pack_span_bounds`).
    Returns the number of candidates settled."""
    ua = u
    ub = u
    va = v
    vb = v
    m = 0
    for c in range(c0, k):
        if not _open(c, settled, ct, cd, fdev, face_surf, tbox, s, best):
            continue
        t = ct[c]
        ua = min(ua, tbox[t, 0])
        ub = max(ub, tbox[t, 1])
        va = min(va, tbox[t, 2])
        vb = max(vb, tbox[t, 3])
        m += 1
    if m == 0:
        return 0
    union = _cert_box(cbrk, bnd, bo, brk_u, brk_v, dm, u, v, d, SKL, x, step_tol, ua, ub,
                      va, vb)
    if not union and m == 1:
        return 0
    n = 0
    for c in range(c0, k):
        if not _open(c, settled, ct, cd, fdev, face_surf, tbox, s, best):
            continue
        t = ct[c]
        if not union:
            ua = min(u, tbox[t, 0])
            ub = max(u, tbox[t, 1])
            va = min(v, tbox[t, 2])
            vb = max(v, tbox[t, 3])
            if not _cert_box(cbrk, bnd, bo, brk_u, brk_v, dm, u, v, d, SKL, x, step_tol,
                             ua, ub, va, vb):
                continue
        settled[c] = 1
        n += 1
    return n
