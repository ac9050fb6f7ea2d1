"""Safeguarded Newton for the foot point of a point on the exact surface (the
projection's local solver, :func:`foot_newton`, and over C0 pieces :func:`foot_c0`).

The iteration minimises f(u, v) = |S(u, v) - x|^2 / 2 over the domain box:

* Newton step on the exact Hessian when it is positive definite, otherwise the
  Gauss–Newton matrix (J^T J, always positive semi-definite) with a small
  Levenberg damping — so every step is a descent direction, also at poles where
  S_u vanishes;
* bounds by an active set: a parameter at its bound whose gradient pushes outward is
  frozen (the foot slides along the domain edge, or stops at a corner);
* backtracking halves the step until f does not increase (monotone, hence bounded);
* stop when the 3-D step is below ``step_tol`` or no decrease is possible.
"""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.policy import jit, jit_inline
from .project_bilinear import derivs2, derivs2_bilinear
from .surface import surface_derivs2

MAX_ITER = 100
FOOT_OK = 0
FOOT_NOT_CONVERGED = 1
_ALONG_U = np.int64(1)  # non-literal: one compile of _slope for both directions
_ALONG_V = np.int64(0)


@jit
def _f(SKL, x):
    r0 = SKL[0, 0, 0] - x[0]
    r1 = SKL[0, 0, 1] - x[1]
    r2 = SKL[0, 0, 2] - x[2]
    return r0 * r0 + r1 * r1 + r2 * r2


@jit
def _wrap(u, lo, hi, closed):
    """Clamp to [lo, hi], or wrap around when the surface is closed that way."""
    if not math.isfinite(u):
        return 0.5 * (lo + hi)
    if closed and (u < lo or u > hi):
        per = hi - lo
        u = lo + (u - lo) % per
        return min(hi, max(lo, u))
    return min(hi, max(lo, u))


@jit_inline
def _ev(Pw, p, q, U, V, u, v, umax, vmax, left_u, left_v, bin_, scr, SKL):
    """Derivatives at (u, v); on an upper piece bound that is an interior C0 knot the
    left-sided ones (evaluated ``left_u`` before the knot: the knot itself gives the
    right-sided derivatives).  Inlined at the numba IR level (a call of its own, with
    its array arguments exploded and reference-counted, cost ~0.2 us per evaluation:
    a Newton run 10-15 % faster without it)."""
    if left_u > 0.0 and u >= umax:
        u = umax - left_u
    if left_v > 0.0 and v >= vmax:
        v = vmax - left_v
    # biquadratic (spheres, tori, cylinders: conics) as a compile-time constant (literal
    # arguments): LLVM unrolls the small loops, 0.5-0.65x the evaluation time; bicubic
    # gained 0.92x for another ~3 s of first-run compilation, so it stays generic
    if p == 2 and q == 2:
        surface_derivs2(Pw, 2, 2, U, V, u, v, scr, SKL)
    elif p == 1 and q == 1:
        # planar faces, bilinear patches: no basis recurrence (project_bilinear)
        derivs2_bilinear(Pw, U, V, u, v, SKL)
    else:
        surface_derivs2(Pw, p, q, U, V, u, v, scr, SKL)


@jit_inline
def _save(SKL):
    """The order <= 2 derivatives of ``SKL`` (what :func:`foot_newton` leaves there)."""
    return (SKL[0, 0, 0], SKL[0, 0, 1], SKL[0, 0, 2], SKL[1, 0, 0], SKL[1, 0, 1],
            SKL[1, 0, 2], SKL[0, 1, 0], SKL[0, 1, 1], SKL[0, 1, 2], SKL[2, 0, 0],
            SKL[2, 0, 1], SKL[2, 0, 2], SKL[1, 1, 0], SKL[1, 1, 1], SKL[1, 1, 2],
            SKL[0, 2, 0], SKL[0, 2, 1], SKL[0, 2, 2])


@jit_inline
def _restore(SKL, t):
    """Put back what :func:`_save` took: the same values a new evaluation at the same
    parameters would give (evaluation is deterministic), without its cost."""
    SKL[0, 0, 0], SKL[0, 0, 1], SKL[0, 0, 2] = t[0], t[1], t[2]
    SKL[1, 0, 0], SKL[1, 0, 1], SKL[1, 0, 2] = t[3], t[4], t[5]
    SKL[0, 1, 0], SKL[0, 1, 1], SKL[0, 1, 2] = t[6], t[7], t[8]
    SKL[2, 0, 0], SKL[2, 0, 1], SKL[2, 0, 2] = t[9], t[10], t[11]
    SKL[1, 1, 0], SKL[1, 1, 1], SKL[1, 1, 2] = t[12], t[13], t[14]
    SKL[0, 2, 0], SKL[0, 2, 1], SKL[0, 2, 2] = t[15], t[16], t[17]


@jit
def foot_newton(Pw, p, q, U, V, umin, umax, vmin, vmax, closed_u, closed_v, x, u, v,
                step_tol, bin_, scr, SKL, left_u=0.0, left_v=0.0):
    """Local minimiser of |S(u, v) - x| over the domain box, started at (u, v).

    On a surface closed in u (or v) the iteration crosses the seam instead of
    stopping on it.

    Returns ``(u, v, distance, iterations, status)``; ``SKL`` holds the derivatives
    up to order 2 at the returned parameters.
    """
    u = min(umax, max(umin, u))
    v = min(vmax, max(vmin, v))
    _ev(Pw, p, q, U, V, u, v, umax, vmax, left_u, left_v, bin_, scr, SKL)
    f = _f(SKL, x)
    it = 0
    escapes = 0
    status = FOOT_NOT_CONVERGED
    while it < MAX_ITER:
        it += 1
        r0 = SKL[0, 0, 0] - x[0]
        r1 = SKL[0, 0, 1] - x[1]
        r2 = SKL[0, 0, 2] - x[2]
        su0, su1, su2 = SKL[1, 0, 0], SKL[1, 0, 1], SKL[1, 0, 2]
        sv0, sv1, sv2 = SKL[0, 1, 0], SKL[0, 1, 1], SKL[0, 1, 2]
        gu = r0 * su0 + r1 * su1 + r2 * su2
        gv = r0 * sv0 + r1 * sv1 + r2 * sv2
        ga = su0 * su0 + su1 * su1 + su2 * su2
        gb = su0 * sv0 + su1 * sv1 + su2 * sv2
        gc = sv0 * sv0 + sv1 * sv1 + sv2 * sv2
        a = ga + r0 * SKL[2, 0, 0] + r1 * SKL[2, 0, 1] + r2 * SKL[2, 0, 2]
        b = gb + r0 * SKL[1, 1, 0] + r1 * SKL[1, 1, 1] + r2 * SKL[1, 1, 2]
        c = gc + r0 * SKL[0, 2, 0] + r1 * SKL[0, 2, 1] + r2 * SKL[0, 2, 2]
        fixu = not closed_u and ((u <= umin and gu > 0.0) or (u >= umax and gu < 0.0))
        fixv = not closed_v and ((v <= vmin and gv > 0.0) or (v >= vmax and gv < 0.0))
        lam = 1e-14 * (ga + gc) + 1e-300
        du = 0.0
        dv = 0.0
        if fixu and fixv:
            status = FOOT_OK
            break
        elif fixu:
            hv = c if c > 0.0 else gc + lam
            dv = -gv / hv
        elif fixv:
            hu = a if a > 0.0 else ga + lam
            du = -gu / hu
        else:
            det = a * c - b * b
            if a > 0.0 and det > 1e-14 * a * c:
                du = -(c * gu - b * gv) / det
                dv = -(a * gv - b * gu) / det
            else:
                ga2 = ga + lam
                gc2 = gc + lam
                det = ga2 * gc2 - gb * gb
                if not det > 0.0:
                    det = ga2 * gc2
                    gb = 0.0
                du = -(gc2 * gu - gb * gv) / det
                dv = -(ga2 * gv - gb * gu) / det
        if not (math.isfinite(du) and math.isfinite(dv)):
            break
        # the full Newton step in 3-D (clamped to the box): the convergence measure
        ddu = min(umax, max(umin, u + du)) - u if not closed_u else du
        ddv = min(vmax, max(vmin, v + dv)) - v if not closed_v else dv
        s0 = su0 * ddu + sv0 * ddv
        s1 = su1 * ddu + sv1 * ddv
        s2 = su2 * ddu + sv2 * ddv
        full_step = math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
        if full_step <= 1e4 * step_tol and escapes < 4:
            # stationary: a minimum only if the Hessian of the free parameters is
            # positive definite; from a saddle or a maximum, step along the direction
            # of negative curvature (both ways) and go on
            eu = 0.0
            ev = 0.0
            if fixv:
                if not a > 0.0:
                    eu = 1.0
            elif fixu:
                if not c > 0.0:
                    ev = 1.0
            elif not (a > 0.0 and a * c - b * b > 1e-14 * a * c):
                lmin = 0.5 * (a + c) - math.sqrt(0.25 * (a - c) ** 2 + b * b)
                if abs(b) > abs(lmin - a):
                    eu = b
                    ev = lmin - a
                else:
                    eu = lmin - c
                    ev = b
                if eu == 0.0 and ev == 0.0:
                    eu = 1.0
            if eu != 0.0 or ev != 0.0:
                s0 = su0 * eu + sv0 * ev
                s1 = su1 * eu + sv1 * ev
                s2 = su2 * eu + sv2 * ev
                ln = math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
                if ln > 0.0:
                    # a short 3-D step, at most a tenth of the domain in parameters
                    L = max(1e-3 * math.sqrt(f), 1e6 * step_tol) / ln
                    L = min(L, 0.1 * max(umax - umin, vmax - vmin)
                            / max(abs(eu), abs(ev)))
                    bu = u
                    bvv = v
                    bf = f
                    for sgn in (-1.0, 1.0):
                        ut = _wrap(u + sgn * L * eu, umin, umax, closed_u)
                        vt = _wrap(v + sgn * L * ev, vmin, vmax, closed_v)
                        _ev(Pw, p, q, U, V, ut, vt, umax, vmax, left_u, left_v, bin_, scr, SKL)
                        ft = _f(SKL, x)
                        if ft < bf:
                            bu = ut
                            bvv = vt
                            bf = ft
                    escapes += 1
                    _ev(Pw, p, q, U, V, bu, bvv, umax, vmax, left_u, left_v, bin_, scr, SKL)
                    if bf < f:
                        u = bu
                        v = bvv
                        f = bf
                        continue
        if full_step <= step_tol:
            # converged: the last step is taken (for a point on the surface the distance
            # error is first order in the foot's error, so skipping it costs accuracy:
            # up to 7.6e-12 instead of rounding level on a cone of radius 4)
            un = _wrap(u + du, umin, umax, closed_u)
            vn = _wrap(v + dv, vmin, vmax, closed_v)
            here = _save(SKL)
            _ev(Pw, p, q, U, V, un, vn, umax, vmax, left_u, left_v, bin_, scr, SKL)
            fn = _f(SKL, x)
            if fn <= f:
                u = un
                v = vn
                f = fn
            else:
                _restore(SKL, here)
            status = FOOT_OK
            break
        alpha = 1.0
        accepted = False
        un = u
        vn = v
        # near convergence a failing decrease is rounding: give up after 2 halvings
        tries = 30 if full_step > 1e4 * step_tol else 2
        full_newton = False
        here = _save(SKL)
        for _ in range(tries):
            un = _wrap(u + alpha * du, umin, umax, closed_u)
            vn = _wrap(v + alpha * dv, vmin, vmax, closed_v)
            _ev(Pw, p, q, U, V, un, vn, umax, vmax, left_u, left_v, bin_, scr, SKL)
            fn = _f(SKL, x)
            if fn < f:
                accepted = True
                full_newton = alpha == 1.0
                break
            alpha *= 0.5
        if (not accepted or alpha < 1.0 / 64.0) and du != 0.0 and dv != 0.0 \
                and full_step > 1e4 * step_tol:
            # a kink (a C0 knot line, a crease) or a bound cuts the joint step short:
            # try moving one parameter at a time, keep the best
            full_newton = accepted and alpha == 1.0
            fbest = fn if accepted else f
            for axis in range(2):
                if axis == 0:
                    su_ = 0.0
                    sv_ = -gv / (c if c > 0.0 else gc + lam)
                else:
                    su_ = -gu / (a if a > 0.0 else ga + lam)
                    sv_ = 0.0
                beta = 1.0
                for _ in range(30):
                    ut = _wrap(u + beta * su_, umin, umax, closed_u)
                    vt = _wrap(v + beta * sv_, vmin, vmax, closed_v)
                    _ev(Pw, p, q, U, V, ut, vt, umax, vmax, left_u, left_v, bin_, scr, SKL)
                    ft = _f(SKL, x)
                    if ft < fbest:
                        fbest = ft
                        un = ut
                        vn = vt
                        fn = ft
                        accepted = True
                        break
                    beta *= 0.5
            _ev(Pw, p, q, U, V, un, vn, umax, vmax, left_u, left_v, bin_, scr, SKL)
        if not accepted:
            # no decrease along a descent direction: stationary within rounding (the
            # derivatives at (u, v) saved before the trials, not evaluated again)
            _restore(SKL, here)
            status = FOOT_OK
            break
        moved = un != u or vn != v
        # a stall only in the smooth regime (the full Newton step was taken): at a
        # kink the distance error is first order in the step, so keep going there
        stalled = f - fn <= 1e-13 * f and full_step <= 1e4 * step_tol and full_newton
        u = un
        v = vn
        f = fn
        if not moved or stalled:
            # rounding noise in the gradient keeps a tiny step alive: the distance is
            # exact to second order in that step (|step| <= 1e4 step_tol)
            status = FOOT_OK
            break
    return u, v, math.sqrt(f), it, status


@jit
def _slope(Pw, p, q, U, V, u, v, x, along_u, bin_, scr, SKL):
    """d/du (along_u = 1) or d/dv of |S - x|^2 / 2 at (u, v)."""
    derivs2(Pw, p, q, U, V, u, v, scr, SKL)
    k = 1 if along_u else 0
    g = 0.0
    for c in range(3):
        g += (SKL[0, 0, c] - x[c]) * SKL[k, 1 - k, c]
    return g


@jit
def foot_c0(Pw, p, q, U, V, dom, brk_u, brk_v, closed_u, closed_v, x, u, v, step_tol,
            bin_, scr, SKL):
    """:func:`foot_newton` over the C0 pieces of the surface.

    Interior knots of multiplicity >= degree (creases) split the domain into pieces
    whose borders are bounds of the Newton box, so a foot on a crease is found exactly
    as a constrained minimum (one-sided derivatives on each side) instead of by
    backtracking across the kink.  A foot stopped on a piece border moves on to the
    neighbouring piece when that one descends further.  ``brk_u``/``brk_v``: the
    piece borders including the domain ends (a closed direction keeps one piece).
    """
    npu = brk_u.shape[0] - 1
    npv = brk_v.shape[0] - 1
    if closed_u:
        npu = 1
    if closed_v:
        npv = 1
    iu = 0
    while iu < npu - 1 and brk_u[iu + 1] <= u:
        iu += 1
    iv = 0
    while iv < npv - 1 and brk_v[iv + 1] <= v:
        iv += 1
    d = np.inf
    it_all = 0
    st = FOOT_NOT_CONVERGED
    for _hop in range(16):
        ua = brk_u[iu] if npu > 1 else dom[0]
        ub = brk_u[iu + 1] if npu > 1 else dom[1]
        va = brk_v[iv] if npv > 1 else dom[2]
        vb = brk_v[iv + 1] if npv > 1 else dom[3]
        lu = 1e-14 * (dom[1] - dom[0]) if iu < npu - 1 else 0.0
        lv = 1e-14 * (dom[3] - dom[2]) if iv < npv - 1 else 0.0
        u, v, d, it, st = foot_newton(Pw, p, q, U, V, ua, ub, va, vb,
                                      closed_u and npu == 1, closed_v and npv == 1, x, u, v,
                                      step_tol, bin_, scr, SKL, lu, lv)
        it_all += it
        moved = False
        # on an interior border: does the neighbouring piece descend further?  (the
        # slope there is one-sided: at the knot from the right, just before it from the
        # left)
        vc = min(vb, max(va, v))
        uc = min(ub, max(ua, u))
        eu = 1e-14 * (dom[1] - dom[0])
        ev = 1e-14 * (dom[3] - dom[2])
        if iu < npu - 1 and u >= ub and _slope(Pw, p, q, U, V, ub, vc, x, _ALONG_U,
                                              bin_, scr, SKL) < 0.0:
            iu += 1
            u = ub
            moved = True
        elif iu > 0 and u <= ua and _slope(Pw, p, q, U, V, ua - eu, vc, x, _ALONG_U,
                                           bin_, scr, SKL) > 0.0:
            iu -= 1
            u = ua
            moved = True
        elif iv < npv - 1 and v >= vb and _slope(Pw, p, q, U, V, uc, vb, x, _ALONG_V,
                                                bin_, scr, SKL) < 0.0:
            iv += 1
            v = vb
            moved = True
        elif iv > 0 and v <= va and _slope(Pw, p, q, U, V, uc, va - ev, x, _ALONG_V,
                                           bin_, scr, SKL) > 0.0:
            iv -= 1
            v = va
            moved = True
        if not moved:
            break
    return u, v, d, it_all, st
