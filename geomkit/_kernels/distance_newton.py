"""Surface–surface distance kernels, part 2: the 4-unknown Newton on
|S_a(u, v) - S_b(s, t)|^2 (exact Hessian, Levenberg damping, active set on the domain
boxes) and the alternating trim-edge feet used when a minimum lies on a trim curve."""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.policy import jit_plain as jit
from .distance_nodes import _uv_inside
from .project import _surface
from .project_newton import foot_newton
from .trim_feet import _trim_point, segment_newton
from .surface import D2, surface_derivs

NEWTON_MAX_ITER = 60


# --------------------------------------------------------------------------- Newton
@jit
def _chol_solve(H, g, free, n, x):
    """Solve H x = -g on the free variables by Cholesky; False if not PD."""
    L = np.zeros((4, 4))
    idx = np.empty(4, dtype=np.int64)
    m = 0
    for i in range(n):
        if free[i]:
            idx[m] = i
            m += 1
    for i in range(m):
        for j in range(i + 1):
            s = H[idx[i], idx[j]]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            if i == j:
                if s <= 0.0:
                    return False
                L[i, i] = math.sqrt(s)
            else:
                L[i, j] = s / L[j, j]
    y = np.zeros(4)
    for i in range(m):
        s = -g[idx[i]]
        for k in range(i):
            s -= L[i, k] * y[k]
        y[i] = s / L[i, i]
    for i in range(n):
        x[i] = 0.0
    z = np.zeros(4)
    for i in range(m - 1, -1, -1):
        s = y[i]
        for k in range(i + 1, m):
            s -= L[k, i] * z[k]
        z[i] = s / L[i, i]
        x[idx[i]] = z[i]
    return True


@jit
def _eval2(Pw_all, U_all, V_all, meta, s, u, v, bin_, scr, SKL):
    Pw, p, q, U, V = _surface(Pw_all, U_all, V_all, meta, s)
    surface_derivs(Pw, p, q, U, V, u, v, D2, bin_, scr, SKL)


@jit
def newton4(Pw_all, U_all, V_all, meta, dom, sa, sb, x, step_tol, bin_, scra, scrb,
            SA, SB):
    """Local minimiser of |S_a(u, v) - S_b(s, t)|^2 / 2 over the two domain boxes.

    ``x`` (4,) = (u, v, s, t) is updated in place.  Exact Hessian with Levenberg
    damping when it is not positive definite, active set on the box bounds (the
    edge–surface, edge–edge and corner cases), monotone backtracking.  Returns the
    distance at ``x``.
    """
    lo = np.empty(4)
    hi = np.empty(4)
    lo[0] = dom[sa, 0]
    hi[0] = dom[sa, 1]
    lo[1] = dom[sa, 2]
    hi[1] = dom[sa, 3]
    lo[2] = dom[sb, 0]
    hi[2] = dom[sb, 1]
    lo[3] = dom[sb, 2]
    hi[3] = dom[sb, 3]
    for i in range(4):
        x[i] = min(hi[i], max(lo[i], x[i]))
    _eval2(Pw_all, U_all, V_all, meta, sa, x[0], x[1], bin_, scra, SA)
    _eval2(Pw_all, U_all, V_all, meta, sb, x[2], x[3], bin_, scrb, SB)
    D = np.empty(3)
    J = np.empty((4, 3))
    H = np.empty((4, 4))
    Hd = np.empty((4, 4))
    g = np.empty(4)
    dx = np.empty(4)
    xn = np.empty(4)
    free = np.empty(4, dtype=np.bool_)
    f = 0.0
    for c in range(3):
        D[c] = SA[0, 0, c] - SB[0, 0, c]
        f += D[c] * D[c]
    mu = 0.0
    for it in range(NEWTON_MAX_ITER):
        for c in range(3):
            J[0, c] = SA[1, 0, c]
            J[1, c] = SA[0, 1, c]
            J[2, c] = -SB[1, 0, c]
            J[3, c] = -SB[0, 1, c]
        for i in range(4):
            s = 0.0
            for c in range(3):
                s += J[i, c] * D[c]
            g[i] = s
            for j in range(4):
                s = 0.0
                for c in range(3):
                    s += J[i, c] * J[j, c]
                H[i, j] = s
        for c in range(3):
            H[0, 0] += SA[2, 0, c] * D[c]
            H[0, 1] += SA[1, 1, c] * D[c]
            H[1, 1] += SA[0, 2, c] * D[c]
            H[2, 2] -= SB[2, 0, c] * D[c]
            H[2, 3] -= SB[1, 1, c] * D[c]
            H[3, 3] -= SB[0, 2, c] * D[c]
        H[1, 0] = H[0, 1]
        H[3, 2] = H[2, 3]
        nfree = 0
        scale = 0.0
        for i in range(4):
            fix = (x[i] <= lo[i] and g[i] > 0.0) or (x[i] >= hi[i] and g[i] < 0.0)
            free[i] = not fix
            if free[i]:
                nfree += 1
                scale = max(scale, abs(H[i, i]))
        if nfree == 0 or f == 0.0:
            break
        if scale == 0.0:
            scale = 1.0
        accepted = False
        fn = f
        for tries in range(40):
            for i in range(4):
                for j in range(4):
                    Hd[i, j] = H[i, j]
                Hd[i, i] += mu * scale + 1e-15 * scale
            if not _chol_solve(Hd, g, free, 4, dx):
                mu = max(4.0 * mu, 1e-8)
                continue
            for i in range(4):
                xn[i] = min(hi[i], max(lo[i], x[i] + dx[i]))
            _eval2(Pw_all, U_all, V_all, meta, sa, xn[0], xn[1], bin_, scra, SA)
            _eval2(Pw_all, U_all, V_all, meta, sb, xn[2], xn[3], bin_, scrb, SB)
            fn = 0.0
            for c in range(3):
                e = SA[0, 0, c] - SB[0, 0, c]
                fn += e * e
            if fn <= f:
                accepted = True
                break
            mu = max(4.0 * mu, 1e-8)
        if not accepted:
            # restore derivatives at x
            _eval2(Pw_all, U_all, V_all, meta, sa, x[0], x[1], bin_, scra, SA)
            _eval2(Pw_all, U_all, V_all, meta, sb, x[2], x[3], bin_, scrb, SB)
            break
        # 3-D size of the step
        st = 0.0
        for c in range(3):
            e = J[0, c] * (xn[0] - x[0]) + J[1, c] * (xn[1] - x[1])
            e2 = J[2, c] * (xn[2] - x[2]) + J[3, c] * (xn[3] - x[3])
            st += e * e + e2 * e2
        for i in range(4):
            x[i] = xn[i]
        for c in range(3):
            D[c] = SA[0, 0, c] - SB[0, 0, c]
        f_old = f
        f = fn
        mu = mu * 0.25 if mu > 1e-12 else 0.0
        if math.sqrt(st) <= step_tol or f_old - f <= 1e-30 * (1.0 + f_old):
            break
    return math.sqrt(f)


# --------------------------------------------------------------------------- trim edges
TRIM_STARTS = 5
ALT_MAX_ITER = 200


@jit
def _trim_foot(Pw, p, q, U, V, dom_s, seg, deg, x, step_tol, bin_, scr, SKL, B, B1, B2, Cd,
               out):
    """Nearest point to ``x`` on the trim boundary of one surface (1-D Newton on every
    segment from TRIM_STARTS starts).  ``out = (u, v, X, Y, Z)``; returns the distance."""
    best = np.inf
    for k in range(seg.shape[0]):
        nd = deg[k]
        Q = seg[k]
        for r in range(TRIM_STARTS):
            t = r / (TRIM_STARTS - 1.0)
            t, f = segment_newton(Pw, p, q, U, V, dom_s, Q, nd, t, x, step_tol, bin_, scr,
                                  SKL, B, B1, B2, Cd)
            d = math.sqrt(2.0 * f)
            if d < best:
                best = d
                _trim_point(Pw, p, q, U, V, dom_s, Q, nd, t, x, bin_, scr, SKL, B, B1, B2, Cd)
                out[0] = min(dom_s[1], max(dom_s[0], Cd[0, 0]))
                out[1] = min(dom_s[3], max(dom_s[2], Cd[0, 1]))
                out[2] = SKL[0, 0, 0]
                out[3] = SKL[0, 0, 1]
                out[4] = SKL[0, 0, 2]
    return best


@jit
def _face_foot(Pw_all, U_all, V_all, meta, dom, seg_all, seg_deg, seg_loop, trim_meta, s, x,
               u, v, uv_tol, step_tol, bin_, scr, SKL, B, B1, B2, Cd, winding, stack, depths,
               tleft, tright, out):
    """Nearest point of the trimmed face ``s`` to ``x`` near (u, v): the surface foot if
    it is inside the face, else the nearest trim-boundary point."""
    Pw, p, q, U, V = _surface(Pw_all, U_all, V_all, meta, s)
    # "not closed" as a runtime bool and explicit border allowances: literal arguments
    # would compile a second foot_newton (~5 s on a fresh install) beside projection's
    no_seam = s < 0
    u, v, d, it, st = foot_newton(Pw, p, q, U, V, dom[s, 0], dom[s, 1], dom[s, 2], dom[s, 3],
                                  no_seam, no_seam, x, u, v, step_tol, bin_, scr, SKL, 0.0, 0.0)
    if _uv_inside(seg_all, seg_deg, seg_loop, trim_meta, s, u, v, uv_tol, winding, stack,
                  depths, tleft, tright):
        out[0] = u
        out[1] = v
        out[2] = SKL[0, 0, 0]
        out[3] = SKL[0, 0, 1]
        out[4] = SKL[0, 0, 2]
        return d
    first = trim_meta[s, 0]
    cnt = trim_meta[s, 1]
    return _trim_foot(Pw, p, q, U, V, dom[s], seg_all[first:first + cnt],
                      seg_deg[first:first + cnt], x, step_tol, bin_, scr, SKL, B, B1, B2, Cd,
                      out)


@jit
def alternate_feet(Pw_all, U_all, V_all, meta, dom, seg_all, seg_deg, seg_loop, trim_meta,
                   sa, sb, x4, uv_tol, step_tol, bin_, scr, SKL, winding, stack, depths, tleft,
                   tright, res):
    """Alternating projections between two trimmed faces (the trim-edge cases:
    trim edge–surface, trim edge–trim edge), from parameters ``x4``.  Converges
    linearly; ``res = (ua, va, XA, YA, ZA, ub, vb, XB, YB, ZB)``.  Returns the distance
    of the final pair (a pair of face points: an upper bound)."""
    pmax1 = seg_all.shape[1]
    B = np.empty(pmax1)
    B1 = np.empty(pmax1)
    B2 = np.empty(pmax1)
    Cd = np.empty((3, 2))
    fa = np.empty(5)
    fb = np.empty(5)
    xa = np.empty(3)
    xb = np.empty(3)
    # start: the point of b at its parameters
    Pw, p, q, U, V = _surface(Pw_all, U_all, V_all, meta, sb)
    surface_derivs(Pw, p, q, U, V, min(dom[sb, 1], max(dom[sb, 0], x4[2])),
                   min(dom[sb, 3], max(dom[sb, 2], x4[3])), D2, bin_, scr, SKL)
    for c in range(3):
        xb[c] = SKL[0, 0, c]
    fb[0] = x4[2]
    fb[1] = x4[3]
    fa[0] = x4[0]
    fa[1] = x4[1]
    d = np.inf
    for it in range(ALT_MAX_ITER):
        _face_foot(Pw_all, U_all, V_all, meta, dom, seg_all, seg_deg, seg_loop, trim_meta, sa,
                   xb, fa[0], fa[1], uv_tol, step_tol, bin_, scr, SKL, B, B1, B2, Cd, winding,
                   stack, depths, tleft, tright, fa)
        for c in range(3):
            xa[c] = fa[2 + c]
        dn = _face_foot(Pw_all, U_all, V_all, meta, dom, seg_all, seg_deg, seg_loop, trim_meta,
                        sb, xa, fb[0], fb[1], uv_tol, step_tol, bin_, scr, SKL, B, B1, B2, Cd,
                        winding, stack, depths, tleft, tright, fb)
        moved = 0.0
        for c in range(3):
            moved += (fb[2 + c] - xb[c]) ** 2
            xb[c] = fb[2 + c]
        if dn < d:
            d = dn
            for c in range(5):
                res[c] = fa[c]
                res[5 + c] = fb[c]
        if math.sqrt(moved) <= step_tol:
            break
    return d
