"""Chord refinement of plane-section chains: exact midpoints inserted until every
segment's chord deviation is within the tolerance, all chains of a surface in one call.

A chain is a polyline of exact curve points in the parameter plane, each segment
inside one leaf of the certified subdivision (:func:`.section.subdivide`).  A segment
``a -> b`` is tested at its exact curve midpoint ``m`` (:func:`_midpoint`): the
distance of ``S(m)`` from the 3-D chord ``S(a) S(b)`` (the closest point on the
segment); a segment within half the tolerance is tested at its quarter points too (an
S-shaped arc has its midpoint on the chord).  A segment above half the tolerance is
split at ``m`` and both halves are tested again, down to ``max_rounds`` halvings of an
input segment.  Each segment depends on its own ends only, so the points are those of
halving all segments above the tolerance in rounds (``max_rounds`` rounds), as the
section did with one array operation per round.  On a leaf monotone in u the midpoint's
root is found on a line of constant v whose control-row sums are taken once
(:func:`_root_on_u_line`: ``edge_root``'s iterates and bits, at a fraction of the cost).
"""

from __future__ import annotations

import numpy as np

from .basis import basis_funs_inline, find_span_inline
from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit
from .section import MONO_U, MONO_V, _f_at, edge_root, f_u_line
from .section_project import _project_point
from .surface import D1, _binomial_table, derivs_scratch, surface_point

TINY = 1e-13
"""A segment at most this long in UV is accepted as it is (round-off length)."""


@jit
def refine_chains(Pw, p, q, U, V, plane, leaves, uv, segleaf, starts, tol, zsnap, ttol,
                  box, max_rounds):
    """Refined polylines of the chains ``uv[starts[c]:starts[c + 1]]``.

    Parameters
    ----------
    Pw, p, q, U, V : the surface (homogeneous control net, degrees, knots).
    plane : (4,) unit-normal plane.
    leaves : (L, 5) leaves of :func:`.section.subdivide` (u0, u1, v0, v1, state).
    uv : (n, 2) exact curve points of all chains, one after the other.
    segleaf : (n,) int, the leaf of the segment ``uv[i] -> uv[i + 1]`` (the entry of a
        chain's last point is not read).
    starts : (C + 1,) int, the first point of each chain and the end.
    tol : chord tolerance (a segment is split above ``0.5 * tol``).
    zsnap : zero band of the plane function; ``ttol``: bracket width of the roots in
        the line parameter; ``box`` (u0, u1, v0, v1): the domain.
    max_rounds : halvings of an input segment at most.

    Returns
    -------
    out : (m, 2) the refined chains, one after the other.
    out_starts : (C + 1,) int, their starts in ``out``.
    chord : (C,) the largest chord deviation measured at each chain's accepted
        segments (inf when a segment still above the tolerance reached
        ``max_rounds``).
    """
    mm = max(p, q) + 1
    sp = (np.empty(p + 1), np.empty(q + 1), np.empty(mm), np.empty(mm), np.empty(4),
          np.empty(3))
    nd = (_binomial_table(D1), derivs_scratch(p, q, D1), np.empty((2, 2, 3)),
          np.empty((Pw.shape[0], 4)))
    nch = starts.shape[0] - 1
    out = np.empty((max(2 * uv.shape[0], 16), 2))
    out_starts = np.zeros(nch + 1, np.int64)
    chord = np.zeros(nch)
    stack = np.empty((max_rounds + 2, 5))   # right ends: u, v, x, y, z
    sdepth = np.empty(max_rounds + 2, np.int64)
    out, nout = _refine_loop(Pw, p, q, U, V, plane, leaves, uv, segleaf, starts, tol, zsnap,
                             ttol, box, max_rounds, out, out_starts, chord,
                             (stack, sdepth, sp, nd))
    return out[:nout].copy(), out_starts, chord


@jit
def _refine_loop(Pw, p, q, U, V, plane, leaves, uv, segleaf, starts, tol, zsnap, ttol, box,
                 max_rounds, out, out_starts, chord, scratch):
    """The chains of :func:`refine_chains` over borrowed views of its inputs and the
    caller's scratch (no atomic reference counting, :mod:`.numba_ext.borrow`; ``out``,
    grown here, stays counted); returns (out, count)."""
    Pw, U, V, plane, leaves, uv, segleaf, starts, box, out_starts, chord, scratch = \
        borrow_all((Pw, U, V, plane, leaves, uv, segleaf, starts, box, out_starts, chord,
                    scratch))
    stack, sdepth, sp, nd = scratch
    nch = starts.shape[0] - 1
    nout = 0
    for c in range(nch):
        i0 = starts[c]
        i1 = starts[c + 1]
        out_starts[c] = nout
        nout, chord[c], out = _refine_chain(Pw, p, q, U, V, plane, leaves, uv, segleaf, i0,
                                            i1, tol, zsnap, ttol, box, max_rounds, out,
                                            nout, stack, sdepth, sp, nd)
    out_starts[nch] = nout
    return out, nout


@jit
def _refine_chain(Pw, p, q, U, V, plane, leaves, uv, segleaf, i0, i1, tol, zsnap, ttol, box,
                  max_rounds, out, nout, stack, sdepth, sp, nd):
    """One chain of :func:`refine_chains` appended to ``out`` (grown when full);
    returns (new count, chord deviation, out)."""
    Nu, Nv, left, right, tmp, X = sp
    chord = 0.0
    if i1 <= i0:
        return nout, chord, out
    A = np.empty(3)
    M = np.empty(3)
    Q = np.empty(3)
    au = uv[i0, 0]
    av = uv[i0, 1]
    surface_point(Pw, p, q, U, V, au, av, Nu, Nv, left, right, tmp, A)
    out = _append(out, nout, au, av)
    nout += 1
    for i in range(i0, i1 - 1):
        leaf = segleaf[i]
        stack[0, 0] = uv[i + 1, 0]
        stack[0, 1] = uv[i + 1, 1]
        surface_point(Pw, p, q, U, V, uv[i + 1, 0], uv[i + 1, 1], Nu, Nv, left, right, tmp, X)
        stack[0, 2] = X[0]
        stack[0, 3] = X[1]
        stack[0, 4] = X[2]
        sdepth[0] = 0
        top = 1
        while top > 0:
            bu = stack[top - 1, 0]
            bv = stack[top - 1, 1]
            d = sdepth[top - 1]
            split = False
            mu = 0.0
            mv = 0.0
            if d >= max_rounds:      # never tested: the rounds ran out
                chord = np.inf
            else:
                du = bu - au
                dv = bv - av
                seg = np.sqrt(du * du + dv * dv)
                mu, mv = _midpoint(Pw, p, q, U, V, plane, leaves, leaf, au, av, bu, bv, seg,
                                   zsnap, ttol, box, sp, nd)
                surface_point(Pw, p, q, U, V, mu, mv, Nu, Nv, left, right, tmp, M)
                d0 = stack[top - 1, 2] - A[0]
                d1 = stack[top - 1, 3] - A[1]
                d2 = stack[top - 1, 4] - A[2]
                ll = d0 * d0 + d1 * d1 + d2 * d2
                err = _chord_dist(A, d0, d1, d2, ll, M)
                tiny = seg <= TINY
                split = err > 0.5 * tol and not tiny
                if not split and not tiny:   # the quarter points (S-shaped arcs)
                    for h in range(2):
                        if h == 0:
                            qu, qv = _midpoint(Pw, p, q, U, V, plane, leaves, leaf, au, av,
                                               mu, mv, np.sqrt((mu - au) ** 2 + (mv - av) ** 2),
                                               zsnap, ttol, box, sp, nd)
                        else:
                            qu, qv = _midpoint(Pw, p, q, U, V, plane, leaves, leaf, mu, mv,
                                               bu, bv, np.sqrt((bu - mu) ** 2 + (bv - mv) ** 2),
                                               zsnap, ttol, box, sp, nd)
                        surface_point(Pw, p, q, U, V, qu, qv, Nu, Nv, left, right, tmp, Q)
                        err = max(err, _chord_dist(A, d0, d1, d2, ll, Q))
                    split = err > 0.5 * tol
                if not split:
                    chord = max(chord, err)
            if split:                # test (a, m), then (m, b)
                sdepth[top - 1] = d + 1
                stack[top, 0] = mu
                stack[top, 1] = mv
                stack[top, 2] = M[0]
                stack[top, 3] = M[1]
                stack[top, 4] = M[2]
                sdepth[top] = d + 1
                top += 1
                continue
            out = _append(out, nout, bu, bv)
            nout += 1
            au = bu
            av = bv
            A[0] = stack[top - 1, 2]
            A[1] = stack[top - 1, 3]
            A[2] = stack[top - 1, 4]
            top -= 1
    return nout, chord, out


@jit
def _append(out, n, u, v):
    """``out`` with row ``n`` set to (u, v), doubled first when full."""
    if n == out.shape[0]:
        bigger = np.empty((2 * n, 2))
        bigger[:n] = out
        out = bigger
    out[n, 0] = u
    out[n, 1] = v
    return out


@jit
def _chord_dist(A, d0, d1, d2, ll, M):
    """Distance of ``M`` from the segment ``A -> A + d`` (``ll = |d|^2``)."""
    e0 = M[0] - A[0]
    e1 = M[1] - A[1]
    e2 = M[2] - A[2]
    t = (e0 * d0 + e1 * d1 + e2 * d2) / (ll if ll > 0 else 1.0)
    t = min(max(t, 0.0), 1.0)
    r0 = A[0] + t * d0 - M[0]
    r1 = A[1] + t * d1 - M[1]
    r2 = A[2] + t * d2 - M[2]
    return np.sqrt(r0 * r0 + r1 * r1 + r2 * r2)


@jit
def _midpoint(Pw, p, q, U, V, plane, leaves, leaf, au, av, bu, bv, seg, zsnap, ttol, box,
              sp, nd):
    """The exact curve point between curve points ``a`` and ``b`` of one leaf.

    In a leaf monotone in u the curve is a graph over v: the root on the u-line
    through the middle v, bracketed by the leaf's sides (likewise for v); elsewhere (an
    unresolved leaf, no bracket) Newton along the gradient from the UV midpoint, the
    move limited to ``seg`` = ``|b - a|`` (:func:`.section_project.project`)."""
    Nu, Nv, left, right, tmp, X = sp
    mu = 0.5 * (au + bu)
    mv = 0.5 * (av + bv)
    state = leaves[leaf, 4]
    if state == MONO_U and mv != 0.0:   # a line of constant v: its row sums once
        lu = leaves[leaf, 0]
        hu = leaves[leaf, 1]
        t = _root_on_u_line(Pw, p, q, U, V, plane, lu, hu, mv, zsnap, ttol, sp, nd)
        if t >= 0.0:
            return lu + t * (hu - lu), mv + t * (mv - mv)
    elif state == MONO_U or state == MONO_V:
        lu = mu
        lv = mv
        hu = mu
        hv = mv
        if state == MONO_U:
            lu = leaves[leaf, 0]
            hu = leaves[leaf, 1]
        else:
            lv = leaves[leaf, 2]
            hv = leaves[leaf, 3]
        flo = _f_at(Pw, p, q, U, V, plane, lu, lv, Nu, Nv, left, right, tmp, X)
        fhi = _f_at(Pw, p, q, U, V, plane, hu, hv, Nu, Nv, left, right, tmp, X)
        if abs(flo) <= zsnap:
            flo = 0.0
        if abs(fhi) <= zsnap:
            fhi = 0.0
        if flo * fhi < 0:
            t = edge_root(Pw, p, q, U, V, plane, lu, lv, hu, hv, flo, fhi, ttol, Nu, Nv,
                          left, right, tmp, X)
            return lu + t * (hu - lu), lv + t * (hv - lv)
    bin_, scr, SKL, _rows = nd
    u, v, _f = _project_point(Pw, p, q, U, V, plane, mu, mv, seg, box, 0.25 * zsnap, 40,
                              bin_, scr, SKL, sp)
    return u, v


@jit
def _root_on_u_line(Pw, p, q, U, V, plane, lu, hu, v, zsnap, ttol, sp, nd):
    """The root parameter ``t`` of :func:`.section.edge_root` on the u-line
    ``(lu, v) -> (hu, v)`` (``v`` not zero), or -1 when the ends' plane values (snapped
    to zero within ``zsnap``) do not bracket a root.

    The same iterates and bits as ``edge_root`` with ``_f_at`` at the ends first, as
    :func:`_midpoint` had them: ``surface_point`` sums each control row over v first
    (``a_k = sum_l N_l(v) P_kl``) and then the rows over u, so on a line of constant v
    the row sums are computed once (:func:`_u_rows`) and each evaluation is the u basis
    and the outer sum alone (:func:`.section.f_u_line`, in ``edge_root``'s loop given
    the rows).  (``v + t * 0.0`` is ``v`` for ``v`` not zero, the reason zero is left
    to ``edge_root``'s own evaluator.)"""
    Nu, Nv, left, right, tmp, X = sp
    rows = nd[3]
    nu = Pw.shape[0]
    r0 = find_span_inline(nu - 1, p, lu, U) - p
    r1 = find_span_inline(nu - 1, p, hu, U)
    _u_rows(Pw, q, V, v, r0, r1, Nv, left, right, rows)
    flo = f_u_line(Pw, p, U, plane, lu, rows, r0, Nu, left, right)
    fhi = f_u_line(Pw, p, U, plane, hu, rows, r0, Nu, left, right)
    if abs(flo) <= zsnap:
        flo = 0.0
    if abs(fhi) <= zsnap:
        fhi = 0.0
    if not flo * fhi < 0:
        return -1.0
    return edge_root(Pw, p, q, U, V, plane, lu, v, hu, v, flo, fhi, ttol, Nu, Nv, left, right,
                     tmp, X, rows, r0)


@jit
def _u_rows(Pw, q, V, v, r0, r1, Nv, left, right, rows):
    """``rows[k - r0]`` = the row sums ``sum_l N_l(v) P_kl`` of ``surface_point`` at
    ``v``, for the control rows ``r0 <= k <= r1``."""
    nv = Pw.shape[1]
    sv = find_span_inline(nv - 1, q, v, V)
    basis_funs_inline(sv, v, q, V, Nv, left, right)
    for row in range(r0, r1 + 1):
        a0 = 0.0
        a1 = 0.0
        a2 = 0.0
        a3 = 0.0
        for l in range(q + 1):
            col = sv - q + l
            b = Nv[l]
            a0 += b * Pw[row, col, 0]
            a1 += b * Pw[row, col, 1]
            a2 += b * Pw[row, col, 2]
            a3 += b * Pw[row, col, 3]
        rows[row - r0, 0] = a0
        rows[row - r0, 1] = a1
        rows[row - r0, 2] = a2
        rows[row - r0, 3] = a3
