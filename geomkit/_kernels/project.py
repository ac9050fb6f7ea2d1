"""Point projection kernels: safeguarded Newton for the foot point on the exact surface.

Surfaces are passed packed (see :func:`geomkit.projection._pack`): ``Pw_all``
(sum nu*nv, 4) homogeneous control points, per surface ``meta[s] = (offset, nu, nv,
p, q, U offset, V offset)`` into ``Pw_all``, ``U_all``, ``V_all``, and the domain
``dom[s] = (umin, umax, vmin, vmax)``.

The Newton iteration minimises f(u, v) = |S(u, v) - x|^2 / 2 over the domain box:

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

from ._numba import jit, jit_inline, prun
from .surface import D2, _binomial_table, derivs_scratch, surface_derivs2
from .foot_class import _deep_cell, _foot_class
from .trim import BOUNDARY, INSIDE, MAX_DEPTH, OUTSIDE  # noqa: F401 (re-exported)
from .project_cert import cert_settle
from .project_bilinear import derivs2, derivs2_bilinear
from .project_outside import settled_outside
from ._borrow import borrow_all
from .voxel import (candidate_scratch, candidates_batch,  # noqa: F401 (the search alone)
                    search)

MAX_ITER = 100
FOOT_OK = 0
FOOT_NOT_CONVERGED = 1
PROJECT_CHUNK = 64
_ALONG_U = np.int64(1)  # non-literal: one compile of _slope for both directions
_ALONG_V = np.int64(0)


@jit_inline
def _surface(Pw_all, U_all, V_all, meta, s):
    o, nu, nv, p, q, uo, vo = (meta[s, 0], meta[s, 1], meta[s, 2], meta[s, 3], meta[s, 4],
                               meta[s, 5], meta[s, 6])
    Pw = Pw_all[o:o + nu * nv].reshape((nu, nv, 4))
    U = U_all[uo:uo + nu + p + 1]
    V = V_all[vo:vo + nv + q + 1]
    return Pw, p, q, U, V


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


@jit
def _project_chunk(i0, i1, P, V, F, fdev, face_surf, face_uv, dmax, origin, h, lvl_dims,
                   lvl_off, occ, start, tris, Pw_all, U_all, V_all, meta, dom, closed,
                   trimmed, brk_all, brk_off, tseg, tdeg, tloop, toff, ttol, tbox, gdeep, goff, cbrk, bnd,
                   bnd_off, certify, step_tol, max_dist, max_starts, skip, out_s, out_uv, out_d, out_st,
                   out_cls, out_nf, out_lb, out_rest, out_flags, out_work):
    """:func:`project_batch` for the points ``i0 .. i1 - 1``: its scratch arrays, then
    :func:`_project_range`."""
    pmax = np.int64(1)  # not a literal 1: one compile of derivs_scratch
    qmax = np.int64(1)
    for s in range(meta.shape[0]):
        pmax = max(pmax, meta[s, 3])
        qmax = max(qmax, meta[s, 4])
    p1 = tseg.shape[1]
    # trim classification scratch (as trim._classify_points_range)
    tscr = (np.empty(max(np.int64(1), np.max(toff[:, 2])), dtype=np.int64),
            np.empty((MAX_DEPTH + 2, p1, 3)), np.empty(MAX_DEPTH + 2, dtype=np.int64),
            np.empty((p1, 3)), np.empty((p1, 3)))
    _project_range(i0, i1, P, V, F, fdev, face_surf, face_uv, dmax, origin, h, lvl_dims,
                   lvl_off, occ, start, tris, Pw_all, U_all, V_all, meta, dom, closed,
                   trimmed, brk_all, brk_off, tseg, tdeg, tloop, toff, ttol, tbox, gdeep,
                   goff, cbrk, bnd, bnd_off, certify, step_tol, max_dist, max_starts, skip,
                   out_s, out_uv, out_d, out_st, out_cls, out_nf, out_lb, out_rest,
                   out_flags, out_work, candidate_scratch(F.shape[0], 64),
                   np.zeros(64, dtype=np.int8), np.empty((3, 3, 3)),
                   derivs_scratch(pmax, qmax, D2), _binomial_table(D2), np.empty(3), tscr)


@jit
def _project_range(i0, i1, P, V, F, fdev, face_surf, face_uv, dmax, origin, h, lvl_dims,
                   lvl_off, occ, start, tris, Pw_all, U_all, V_all, meta, dom, closed,
                   trimmed, brk_all, brk_off, tseg, tdeg, tloop, toff, ttol, tbox, gdeep,
                   goff, cbrk, bnd, bnd_off, certify, step_tol, max_dist, max_starts, skip,
                   out_s, out_uv, out_d, out_st, out_cls, out_nf, out_lb, out_rest,
                   out_flags, out_work, sc, settled, SKL, scr, bin_, x, tscr):
    """The loop of :func:`_project_chunk` over borrowed arrays
    (:mod:`geomkit._kernels._borrow`: no atomic reference counts in the loop; every
    array here is owned by the caller, which outlives this call)."""
    (P, V, F, fdev, face_surf, face_uv, origin, lvl_dims, lvl_off, occ, start, tris,
     Pw_all, U_all, V_all, meta, dom, closed, trimmed, brk_all, brk_off) = borrow_all((
        P, V, F, fdev, face_surf, face_uv, origin, lvl_dims, lvl_off, occ, start, tris,
        Pw_all, U_all, V_all, meta, dom, closed, trimmed, brk_all, brk_off))
    (tseg, tdeg, tloop, toff, ttol, tbox, gdeep, goff, cbrk, bnd, bnd_off, skip, out_s,
     out_uv, out_d, out_st, out_cls, out_nf, out_lb, out_rest, out_flags, out_work) = \
        borrow_all((tseg, tdeg, tloop, toff, ttol, tbox, gdeep, goff, cbrk, bnd, bnd_off,
                    skip, out_s, out_uv, out_d, out_st, out_cls, out_nf, out_lb, out_rest,
                    out_flags, out_work))
    sc, settled, SKL, scr, bin_, x, tscr = borrow_all((sc, settled, SKL, scr, bin_, x,
                                                      tscr))
    winding, stack, depths, left, right = tscr
    K = out_s.shape[1]
    for i in range(i0, i1):
        x[0] = P[i, 0]
        x[1] = P[i, 1]
        x[2] = P[i, 2]
        k, UB, LB, ovf, pops, tested, sc = search(
            x[0], x[1], x[2], V, F, fdev, dmax, origin, h, lvl_dims, lvl_off, occ,
            start, tris, sc, i, max_dist)
        ct, cd, cs, cw = sc[3], sc[4], sc[5], sc[6]
        out_lb[i] = LB
        out_work[i, 0] = pops
        out_work[i, 1] = tested
        out_work[i, 2] = k
        if settled.shape[0] < ct.shape[0]:
            settled = np.zeros(ct.shape[0], dtype=np.int8)
        settled[:k] = 0
        nset = 0
        flags = 1 if ovf else 0
        # feet of an earlier pass (its candidates before skip[i] were tried or pruned
        # there): continued, not repeated
        nf = out_nf[i]
        # the mesh upper bound holds for trimmed faces too (their triangles lie on
        # the face); a Newton foot on a trimmed surface may lie outside the face,
        # so only a foot classified inside its face is an upper bound (below)
        best = UB
        for j in range(nf):
            if out_cls[i, j] == INSIDE:
                best = min(best, out_d[i, j])
        if k == 0:
            flags |= 2
        rest = np.inf
        stop = k
        for c in range(skip[i], k):
            if settled[c] != 0:
                # proven no nearer than a foot found (second-order certificate)
                continue
            t = ct[c]
            lbc = cd[c] - fdev[t]
            if lbc > best:
                # candidates are sorted by triangle distance, not by lower bound (the
                # deviation bounds differ): a later one may still hold a nearer point.
                # Equality is tried: on a flat face (deviation 0) the nearest
                # triangle's lower bound equals the mesh upper bound
                continue
            s = face_surf[t]
            if (certify & 2) != 0 and trimmed[s] != 0 and settled_outside(
                    i, nf, s, out_s, out_uv, out_st, out_cls, Pw_all, U_all, V_all, meta,
                    dom, closed, brk_all, brk_off, cbrk, bnd, bnd_off, tbox[t], x, scr, SKL):
                # its piece's nearest point is on the face's trim curve (found by the
                # trim stage): project_outside
                nset += 1
                continue
            if nf >= K or nf >= max_starts:
                # over the start cap: this candidate is not tried, the answer is
                # proven only if it is no farther than ``rest``
                rest = min(rest, lbc)
                stop = min(stop, c)
                continue
            sw = cs[c]
            ww = cw[c]
            u0 = face_uv[t, 0, 0] + sw * (face_uv[t, 1, 0] - face_uv[t, 0, 0]) \
                + ww * (face_uv[t, 2, 0] - face_uv[t, 0, 0])
            v0 = face_uv[t, 0, 1] + sw * (face_uv[t, 1, 1] - face_uv[t, 0, 1]) \
                + ww * (face_uv[t, 2, 1] - face_uv[t, 0, 1])
            # every candidate whose lower bound is below the best bound so far is
            # tried: no start is skipped as "inside the basin of a foot already
            # found" (that heuristic lost the nearer of two close basins on
            # freeform_1, a Newton start from there costs a few iterations)
            Pw, p, q, U, Vk = _surface(Pw_all, U_all, V_all, meta, s)
            bu = brk_all[brk_off[s, 0]:brk_off[s, 0] + brk_off[s, 1]]
            bv = brk_all[brk_off[s, 2]:brk_off[s, 2] + brk_off[s, 3]]
            u, v, d, it, st = foot_c0(Pw, p, q, U, Vk, dom[s], bu, bv,
                                      closed[s, 0] != 0, closed[s, 1] != 0, x, u0, v0,
                                      step_tol, bin_, scr, SKL)
            cl = INSIDE
            # a foot in the box of a deep triangle is inside its face (beyond the
            # band: geomkit.projection_trim.cert_boxes), no classification needed
            if trimmed[s] != 0 and not (tbox[t, 4] != 0.0 and tbox[t, 0] <= u <= tbox[t, 1]
                                        and tbox[t, 2] <= v <= tbox[t, 3]) \
                    and not _deep_cell(gdeep, goff, dom, s, u, v):
                cl = _foot_class(tseg, tdeg, tloop, toff, ttol, dom, s, u, v, winding,
                                 stack, depths, left, right)
            # insert sorted by distance
            j = nf
            while j > 0 and out_d[i, j - 1] > d:
                out_s[i, j] = out_s[i, j - 1]
                out_uv[i, j, 0] = out_uv[i, j - 1, 0]
                out_uv[i, j, 1] = out_uv[i, j - 1, 1]
                out_d[i, j] = out_d[i, j - 1]
                out_st[i, j] = out_st[i, j - 1]
                out_cls[i, j] = out_cls[i, j - 1]
                j -= 1
            out_s[i, j] = s
            out_uv[i, j, 0] = u
            out_uv[i, j, 1] = v
            out_d[i, j] = d
            out_st[i, j] = st
            out_cls[i, j] = cl
            nf += 1
            # a foot inside its face (untrimmed surface, or strictly inside the trim
            # loops) is a point of the model: its distance prunes; a foot outside
            # or within the trim band of a trimmed face prunes nothing
            if cl == INSIDE:
                best = min(best, d)
                if (certify & 1) != 0 and st == FOOT_OK and d <= best:
                    # the candidates of this face around the foot, settled at once
                    # when f is provably convex over their parameter box
                    nset += cert_settle(cbrk, bnd, bnd_off[s], bu, bv, dom[s], u, v, d, SKL,
                                        x, step_tol, s, c + 1, k, best, ct, cd, fdev,
                                        face_surf, tbox, settled)
        out_work[i, 4] = nset
        out_nf[i] = nf
        out_work[i, 3] = stop
        out_rest[i] = rest
        out_flags[i] = flags


def project_batch(P, V, F, fdev, face_surf, face_uv, dmax, origin, h, lvl_dims, lvl_off,
                  occ, start, tris, Pw_all, U_all, V_all, meta, dom, closed, trimmed, brk_all,
                  brk_off, tseg, tdeg, tloop, toff, ttol, tbox, gdeep, goff, cbrk, bnd, bnd_off,
                  certify, step_tol, max_dist, max_starts, skip, out_s, out_uv, out_d, out_st, out_cls,
                  out_nf, out_lb, out_rest, out_flags, out_work):
    """Candidate feet of each point: up to ``max_starts`` Newton runs per point.

    For point i, ``out_nf[i]`` feet are written to ``out_s[i, j]`` (surface),
    ``out_uv[i, j]``, ``out_d[i, j]`` (distance), ``out_st[i, j]`` (Newton status) and
    ``out_cls[i, j]`` (the foot's INSIDE / OUTSIDE / BOUNDARY class on its trimmed face,
    INSIDE on an untrimmed one; trim segments of surface s are ``tseg[toff[s, 0]:][:toff[s,
    1]]`` with ``toff[s, 2]`` loops, band ``ttol[s]``), nearest first: every candidate whose lower bound is below the best bound so far
    is tried, up to ``max_starts``; ``out_rest[i]`` is the smallest lower bound of the
    candidates left untried by that cap (inf when none).  ``out_lb[i]`` is the mesh
    lower bound of the point's distance
    (certified up to the mesh deviation bounds ``fdev``).  ``trimmed[s]`` != 0 marks
    trimmed surfaces, whose Newton feet prune candidates only when inside the face (a
    foot in the box of a triangle with ``tbox[t, 4]`` != 0, or in a deep cell of its
    surface's grid ``gdeep`` / ``goff``, is inside without a classification).  ``out_flags[i]`` bit 0:
    more than 64 candidate triangles (the buffer grew: none is dropped); bit 1: beyond
    ``max_dist``.  ``out_work[i]`` = (cells opened, triangles tested, candidates, index
    of the first candidate left untried by the cap (candidates when none), candidates
    settled by the second-order certificate).

    Outside rule (``certify`` bit 1; :mod:`geomkit._kernels.project_outside`): a
    candidate of a trimmed face whose piece box ``tbox[t, :4]`` is proven to hold no
    local minimum of the distance over the face off its trim curves (f decreases
    towards a converged foot of the point on that surface classified OUTSIDE) is
    settled without a Newton run: the trim stage covers it.

    Certificate (``certify`` bit 0; :func:`geomkit._kernels.project_cert.cert_settle`):
    after each new nearest foot inside its face, the untried candidates of that face
    around it (whose piece of the face lies in the box ``tbox[t, :4]``, NaN: never)
    are settled without a Newton
    run when a second-order bound proves the distance no lower than the foot's over
    their parameter box (sub-span derivative bounds ``bnd`` over the borders ``cbrk``,
    surface s's from ``bnd_off[s]``).

    A later pass continues an earlier one: ``out_nf[i]`` (in/out) feet are already in
    the ``out_*`` rows (they count towards ``max_starts`` and their inside distances
    prune), and the candidates before ``skip[i]`` (the earlier pass's
    ``out_work[i, 3]``: each was tried or pruned there, against a bound no lower than
    the one here) are passed over; zeros for a first pass.
    Parallel over points (:func:`prun` of :func:`_project_chunk`).
    """
    prun(_project_chunk, P.shape[0], PROJECT_CHUNK, P, V, F, fdev, face_surf, face_uv, dmax,
         origin, h, lvl_dims, lvl_off, occ, start, tris, Pw_all, U_all, V_all, meta, dom,
         closed, trimmed, brk_all, brk_off, tseg, tdeg, tloop, toff, ttol, tbox, gdeep, goff, cbrk, bnd,
         bnd_off, certify, step_tol, max_dist, max_starts, skip, out_s, out_uv, out_d, out_st,
         out_cls, out_nf, out_lb, out_rest, out_flags, out_work)
