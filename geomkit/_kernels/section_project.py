"""Plane-section kernels: curve points by Newton along the plane function's gradient.

The plane function ``f(u, v) = plane . S(u, v) + D`` of a surface (see
:mod:`.section`).  :func:`project` moves UV points onto ``f = 0``; :func:`densify`
inserts such points into a polyline by halving its segments (:func:`_halve`), the
densification :mod:`.section_clip` classifies against the trims.
"""

from __future__ import annotations

import numpy as np

from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit
from .surface import D1, _binomial_table, derivs_scratch, surface_derivs, surface_point



@jit
def point_scratch(p, q):
    """Scratch of :func:`.surface.surface_point` for degrees ``p``, ``q``: (Nu, Nv,
    left, right, tmp, X)."""
    m = max(p, q) + 1
    return (np.empty(p + 1), np.empty(q + 1), np.empty(m), np.empty(m), np.empty(4),
            np.empty(3))


@jit
def project(Pw, p, q, U, V, plane, uv, maxstep, box, ftol, maxit, out_uv, out_f):
    """Newton along the UV gradient of ``f`` onto ``f = 0`` from each ``uv[i]``.

    ``x <- x - f g / |g|^2`` with ``g = (plane.S_u, plane.S_v)``, the total move from
    the start limited to ``maxstep[i]`` and the iterate clamped to ``box`` (u0, u1,
    v0, v1).  Stops when ``|f| <= ftol``.  Writes the final parameters and ``f``.
    """
    bin_ = _binomial_table(D1)
    scr = derivs_scratch(p, q, D1)
    _project_loop(Pw, p, q, U, V, plane, uv, maxstep, box, ftol, maxit, out_uv, out_f,
                  bin_, scr, np.empty((2, 2, 3)), point_scratch(p, q))


@jit
def _project_loop(Pw, p, q, U, V, plane, uv, maxstep, box, ftol, maxit, out_uv, out_f,
                  bin_, scr, SKL, sp):
    """The loop of :func:`project` over borrowed views (:mod:`.numba_ext.borrow`)."""
    Pw, U, V, plane, uv, maxstep, box, out_uv, out_f, bin_, scr, SKL, sp = borrow_all((
        Pw, U, V, plane, uv, maxstep, box, out_uv, out_f, bin_, scr, SKL, sp))
    for i in range(uv.shape[0]):
        u, v, f = _project_point(Pw, p, q, U, V, plane, uv[i, 0], uv[i, 1], maxstep[i], box,
                                 ftol, maxit, bin_, scr, SKL, sp)
        out_uv[i, 0] = u
        out_uv[i, 1] = v
        out_f[i] = f


@jit
def _project_point(Pw, p, q, U, V, plane, u0, v0, maxstep, box, ftol, maxit, bin_, scr,
                   SKL, sp):
    """One start point of :func:`project`: returns (u, v, f).

    The start is evaluated alone first (:func:`.surface.surface_point` with the
    scratch ``sp`` of :func:`point_scratch`): a start already within ``ftol``
    (midpoints of straight chains on planes and cylinders) costs no derivatives.  Its
    ``f`` is the one the derivatives' evaluation gives (``surface_derivs`` sums the
    same products in the same order, its basis functions' row 0 computed as
    ``basis_funs`` does; it skips the zero basis values, which changes at most the
    sign of a zero), so the result is that of Newton from the derivatives alone."""
    u = u0
    v = v0
    Nu, Nv, left, right, tmp, X = sp
    surface_point(Pw, p, q, U, V, u, v, Nu, Nv, left, right, tmp, X)
    f = plane[0] * X[0] + plane[1] * X[1] + plane[2] * X[2] + plane[3]
    if abs(f) <= ftol or maxit == 0:
        return u, v, f
    for it in range(maxit + 1):
        surface_derivs(Pw, p, q, U, V, u, v, D1, bin_, scr, SKL)
        f = (plane[0] * SKL[0, 0, 0] + plane[1] * SKL[0, 0, 1] + plane[2] * SKL[0, 0, 2]
             + plane[3])
        if abs(f) <= ftol or it == maxit:
            break
        gu = plane[0] * SKL[1, 0, 0] + plane[1] * SKL[1, 0, 1] + plane[2] * SKL[1, 0, 2]
        gv = plane[0] * SKL[0, 1, 0] + plane[1] * SKL[0, 1, 1] + plane[2] * SKL[0, 1, 2]
        g2 = gu * gu + gv * gv
        if not g2 > 0.0:
            break
        un = u - f * gu / g2
        vn = v - f * gv / g2
        du = un - u0
        dv = vn - v0
        dist = np.sqrt(du * du + dv * dv)
        if dist > maxstep:
            un = u0 + du * maxstep / dist
            vn = v0 + dv * maxstep / dist
        un = min(max(un, box[0]), box[1])
        vn = min(max(vn, box[2]), box[3])
        if un == u and vn == v:
            break
        u = un
        v = vn
    return u, v, f


@jit
def _halve(Pw, p, q, U, V, plane, au, av, bu, bv, d, h, box, ftol, maxdepth, out, dep, nout,
           stack, sdepth, bin_, scr, SKL, sp):
    """The points of :func:`densify` on the segment ``a -> b`` at depth ``d``
    (its halvings so far), ``a`` excluded, ``b`` included, appended to ``out`` with the
    depth of the segment each point ends; returns (count, out, dep)."""
    stack[0, 0] = bu
    stack[0, 1] = bv
    sdepth[0] = d
    top = 1
    while top > 0:
        bu = stack[top - 1, 0]
        bv = stack[top - 1, 1]
        dd = sdepth[top - 1]
        du = bu - au
        dv = bv - av
        seg = np.sqrt(du * du + dv * dv)
        if seg > h and dd < maxdepth:
            mu, mv, _f = _project_point(Pw, p, q, U, V, plane, 0.5 * (au + bu),
                                        0.5 * (av + bv), seg, box, ftol, 40, bin_, scr, SKL,
                                        sp)
            sdepth[top - 1] = dd + 1
            stack[top, 0] = mu
            stack[top, 1] = mv
            sdepth[top] = dd + 1
            top += 1
            continue
        if nout == out.shape[0]:
            bigger = np.empty((2 * nout, 2))
            bigger[:nout] = out
            out = bigger
            bdep = np.empty(2 * nout, np.int64)
            bdep[:nout] = dep
            dep = bdep
        out[nout, 0] = bu
        out[nout, 1] = bv
        dep[nout] = dd
        nout += 1
        au = bu
        av = bv
        top -= 1
    return nout, out, dep


@jit
def densify(Pw, p, q, U, V, plane, uv, h, box, ftol, maxdepth):
    """Exact curve points inserted into the polyline ``uv`` (n, 2) until consecutive
    points are at most ``h`` apart in UV; returns the (m, 2) polyline.

    A segment ``a -> b`` longer than ``h`` is halved at :func:`project` of its midpoint
    (the move limited to its length ``|b - a|``, stopping at ``|f| <= ftol``, clamped to
    ``box``), and both halves are examined again, down to ``maxdepth`` halvings of an
    input segment (each segment depends on its own ends only: the points are those of
    halving all long segments in rounds, ``maxdepth`` rounds).
    """
    bin_ = _binomial_table(D1)
    scr = derivs_scratch(p, q, D1)
    SKL = np.empty((2, 2, 3))
    n = uv.shape[0]
    out = np.empty((max(2 * n, 16), 2))
    dep = np.empty(out.shape[0], np.int64)
    stack = np.empty((maxdepth + 2, 2))   # right ends of the pending halves
    sdepth = np.empty(maxdepth + 2, np.int64)
    nout = 0
    if n > 0:
        out[0, 0] = uv[0, 0]
        out[0, 1] = uv[0, 1]
        nout = 1
    for i in range(n - 1):
        nout, out, dep = _halve(Pw, p, q, U, V, plane, uv[i, 0], uv[i, 1], uv[i + 1, 0],
                                uv[i + 1, 1], 0, h, box, ftol, maxdepth, out, dep, nout,
                                stack, sdepth, bin_, scr, SKL, point_scratch(p, q))
    return out[:nout].copy()
