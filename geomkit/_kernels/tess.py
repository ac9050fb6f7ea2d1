"""Tessellation kernels: cell error estimates and measured triangle deviation.

The deviation of a flat triangle from the surface is measured *parametrically*: for
a UV triangle with corners ``a, b, c`` and 3-D vertices ``S(a), S(b), S(c)``, the
sample at barycentric ``(l0, l1, l2)`` compares ``S(l0 a + l1 b + l2 c)`` with
``l0 S(a) + l1 S(b) + l2 S(c)``.  The parametric gap bounds both one-sided
distances (surface point to triangle, triangle point to surface) at that sample.
"""

from __future__ import annotations

import numpy as np

from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit, jit_inline, prun
from .basis import basis_funs, find_span
from .surface import (surface_point, surface_point_d1_inline as surface_point_d1,
                      surface_point_inline)
from .triangles import _dist3, point_triangle_distance

CELL_CHUNK = 32
"""Cells per parallel task range step (:func:`prun`).  A call of at most one chunk runs
in the calling thread: handing a few cells to the thread pool costs more than their
work (~0.1 ms per task on an idle machine, several ms when the cores are busy)."""
TRI_CHUNK = 128
"""Triangles (or chords) per parallel task range step."""
CELL_SERIAL = 256
TRI_SERIAL = 1024
"""Cells / triangles measured in the calling thread up to these counts: on the parts'
faces (tens to hundreds of triangles), handing half to the pool cost 7-20 % more CPU
time and gave no shorter wall time on an idle 2-core machine (same-run A/B)."""


def _run(worker, n, chunk, serial, *args):
    """:func:`prun`, or the worker directly for at most ``serial`` items or one chunk
    (skips the thread query and dispatch of ``prun``: a few tens of microseconds per
    call, which is the order of a whole small tessellation)."""
    if n <= chunk or n <= serial:
        worker(0, n, *args)
    else:
        prun(worker, n, chunk, *args)


@jit
def _grid_normals(G, Nrm):
    """Unit normals of a sampled grid G (m, m, 3) from finite differences."""
    m = G.shape[0]
    for i in range(m):
        i0 = max(i - 1, 0)
        i1 = min(i + 1, m - 1)
        for j in range(m):
            j0 = max(j - 1, 0)
            j1 = min(j + 1, m - 1)
            a0 = G[i1, j, 0] - G[i0, j, 0]
            a1 = G[i1, j, 1] - G[i0, j, 1]
            a2 = G[i1, j, 2] - G[i0, j, 2]
            b0 = G[i, j1, 0] - G[i, j0, 0]
            b1 = G[i, j1, 1] - G[i, j0, 1]
            b2 = G[i, j1, 2] - G[i, j0, 2]
            n0 = a1 * b2 - a2 * b1
            n1 = a2 * b0 - a0 * b2
            n2 = a0 * b1 - a1 * b0
            ln = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
            if ln > 0.0:
                Nrm[i, j, 0] = n0 / ln
                Nrm[i, j, 1] = n1 / ln
                Nrm[i, j, 2] = n2 / ln
            else:  # degenerate (pole): fall back to the full gap
                Nrm[i, j, 0] = np.nan


@jit_inline
def _normal_gap(Nrm, G, i, j, x0, x1, x2):
    """|n . (G[i,j] - x)|: distance of x to the tangent plane at the grid sample."""
    d0 = G[i, j, 0] - x0
    d1 = G[i, j, 1] - x1
    d2 = G[i, j, 2] - x2
    if np.isnan(Nrm[i, j, 0]):
        return np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    return abs(Nrm[i, j, 0] * d0 + Nrm[i, j, 1] * d1 + Nrm[i, j, 2] * d2)


@jit
def _cell_errors_range(i0, i1, Pw, p, q, U, V, cells, m, out):
    _cell_errors_box_range(i0, i1, Pw, p, q, U, V, cells, m, np.nan, np.nan, np.nan, np.nan,
                           out)


@jit
def _cell_errors_box_range(i0, i1, Pw, p, q, U, V, cells, m, bu0, bu1, bv0, bv1, out):
    mm = max(p, q) + 1
    Nu = np.empty(p + 1)
    Nv = np.empty(q + 1)
    left = np.empty(mm)
    right = np.empty(mm)
    tmp = np.empty(4)
    G = np.empty((m, m, 3))
    Nrm = np.empty((m, m, 3))
    Bu = np.empty((m, p + 1))
    Bv = np.empty((m, q + 1))
    H = np.empty((q + 1, 4))
    _cell_errors_loop(i0, i1, Pw, p, q, U, V, cells, m, bu0, bu1, bv0, bv1, out,
                      (Nu, Nv, left, right, tmp, G, Nrm, Bu, Bv, H))


@jit_inline
def _edge_sag(G, a0, b0, da, db, n):
    """Largest distance of the grid points ``G[a0 + i da, b0 + i db]`` (i = 1 .. n-2)
    from the segment between the first and the last."""
    a1 = a0 + (n - 1) * da
    b1 = b0 + (n - 1) * db
    d0 = G[a1, b1, 0] - G[a0, b0, 0]
    d1 = G[a1, b1, 1] - G[a0, b0, 1]
    d2 = G[a1, b1, 2] - G[a0, b0, 2]
    ll = d0 * d0 + d1 * d1 + d2 * d2
    worst = 0.0
    for i in range(1, n - 1):
        a = a0 + i * da
        b = b0 + i * db
        e0 = G[a, b, 0] - G[a0, b0, 0]
        e1 = G[a, b, 1] - G[a0, b0, 1]
        e2 = G[a, b, 2] - G[a0, b0, 2]
        s = 0.0  # the closest point of the chord segment
        if ll > 0.0:
            s = min(1.0, max(0.0, (e0 * d0 + e1 * d1 + e2 * d2) / ll))
        e0 -= s * d0
        e1 -= s * d1
        e2 -= s * d2
        worst = max(worst, np.sqrt(e0 * e0 + e1 * e1 + e2 * e2))
    return worst


@jit_inline
def _fold(e, sag):
    """``e`` raised to ``sag`` (a NaN estimate stays NaN)."""
    return e if (np.isnan(e) or e >= sag) else sag


@jit
def _cell_errors_loop(i0, i1, Pw, p, q, U, V, cells, m, bu0, bu1, bv0, bv1, out, scratch):
    """The loop of :func:`_cell_errors_box_range` over borrowed views of its arrays and
    the caller's scratch (no atomic reference counting, :mod:`.numba_ext.borrow`)."""
    Pw, U, V, cells, out, (Nu, Nv, left, right, tmp, G, Nrm, Bu, Bv, H) = borrow_all((
        Pw, U, V, cells, out, scratch))
    for c in range(i0, i1):
        _cell_grid(Pw, p, q, U, V, cells[c, 0], cells[c, 1], cells[c, 2], cells[c, 3], m - 1,
                   Nu, Nv, left, right, Bu, Bv, H, G)
        _grid_normals(G, Nrm)
        e_d0 = 0.0
        e_d1 = 0.0
        e_u = 0.0
        e_v = 0.0
        last = m - 1
        for i in range(m):
            s = i / last
            for j in range(m):
                t = j / last
                # diagonal (0,0)-(1,1): A=(0,0), B=(1,0), C=(1,1), D=(0,1)
                if s >= t:
                    for k in range(3):
                        tmp[k] = ((1.0 - s) * G[0, 0, k] + (s - t) * G[last, 0, k]
                                  + t * G[last, last, k])
                else:
                    for k in range(3):
                        tmp[k] = ((1.0 - t) * G[0, 0, k] + (t - s) * G[0, last, k]
                                  + s * G[last, last, k])
                e_d0 = max(e_d0, _normal_gap(Nrm, G, i, j, tmp[0], tmp[1], tmp[2]))
                # diagonal (1,0)-(0,1)
                if s + t <= 1.0:
                    for k in range(3):
                        tmp[k] = (G[0, 0, k] + s * (G[last, 0, k] - G[0, 0, k])
                                  + t * (G[0, last, k] - G[0, 0, k]))
                else:
                    for k in range(3):
                        tmp[k] = (G[last, last, k] + (1.0 - s) * (G[0, last, k] - G[last, last, k])
                                  + (1.0 - t) * (G[last, 0, k] - G[last, last, k]))
                e_d1 = max(e_d1, _normal_gap(Nrm, G, i, j, tmp[0], tmp[1], tmp[2]))
                for k in range(3):
                    tmp[k] = (1.0 - s) * G[0, j, k] + s * G[last, j, k]
                e_u = max(e_u, _normal_gap(Nrm, G, i, j, tmp[0], tmp[1], tmp[2]))
                for k in range(3):
                    tmp[k] = (1.0 - t) * G[i, 0, k] + t * G[i, last, k]
                e_v = max(e_v, _normal_gap(Nrm, G, i, j, tmp[0], tmp[1], tmp[2]))
        edge = 0.0
        edge = max(edge, _dist3(G[0, 0, 0], G[0, 0, 1], G[0, 0, 2], G[last, 0, 0], G[last, 0, 1], G[last, 0, 2]))
        edge = max(edge, _dist3(G[0, last, 0], G[0, last, 1], G[0, last, 2], G[last, last, 0], G[last, last, 1], G[last, last, 2]))
        edge = max(edge, _dist3(G[0, 0, 0], G[0, 0, 1], G[0, 0, 2], G[0, last, 0], G[0, last, 1], G[0, last, 2]))
        edge = max(edge, _dist3(G[last, 0, 0], G[last, 0, 1], G[last, 0, 2], G[last, last, 0], G[last, last, 1], G[last, last, 2]))
        # a cell edge on the box's edge lines: the boundary's sag from its chord (it
        # bends in the tangent plane, where the normal gap does not see it) raises the
        # chord error along it, which sets the children counts (``split_counts``)
        sag_u = 0.0
        sag_v = 0.0
        if cells[c, 2] == bv0 or cells[c, 2] == bv1:
            sag_u = max(sag_u, _edge_sag(G, 0, 0, 1, 0, m))
        if cells[c, 3] == bv0 or cells[c, 3] == bv1:
            sag_u = max(sag_u, _edge_sag(G, 0, last, 1, 0, m))
        if cells[c, 0] == bu0 or cells[c, 0] == bu1:
            sag_v = max(sag_v, _edge_sag(G, 0, 0, 0, 1, m))
        if cells[c, 1] == bu0 or cells[c, 1] == bu1:
            sag_v = max(sag_v, _edge_sag(G, last, 0, 0, 1, m))
        out[c, 0] = e_d0
        out[c, 1] = e_d1
        out[c, 2] = _fold(e_u, sag_u)
        out[c, 3] = _fold(e_v, sag_v)
        out[c, 4] = edge


def cell_errors(Pw, p, q, U, V, cells, m, out, box=None):
    """Error estimates for axis-aligned UV cells (parallel over cells).

    The surface is sampled on an m x m grid per cell; each error is the largest
    normal-direction gap ``|n . (S(uv) - X(uv))|`` (the first-order distance between
    the surface and the approximating point, free of parametric sliding).

    Parameters
    ----------
    cells : (N, 4) float, ``u0, u1, v0, v1`` per cell.
    m : samples per side (>= 3).
    out : (N, 5) float, filled with
        0: gap of the two triangles split along (u0,v0)-(u1,v1);
        1: the same for the other diagonal (u1,v0)-(u0,v1);
        2: gap of u-line chords (v fixed) across the cell (need to split u);
        3: gap of v-line chords (u fixed) across the cell (need to split v);
        4: largest 3-D edge length of the cell's corners (for ``max_edge``).
    """
    if box is None:
        _run(_cell_errors_range, cells.shape[0], CELL_CHUNK, CELL_SERIAL, Pw, p, q, U, V,
             cells, m, out)
    else:
        _run(_cell_errors_box_range, cells.shape[0], CELL_CHUNK, CELL_SERIAL, Pw, p, q, U, V,
             cells, m, *(float(b) for b in box), out)


FOOT_STEPS = 12
"""Largest number of Gauss-Newton steps toward the foot of a triangle point in
:func:`_foot_descent` (each halved up to :data:`FOOT_HALVINGS` times)."""
FOOT_HALVINGS = 8


@jit_inline
def foot_step(SKL, x, y, z):
    """``(ok, du, dv)``: the Gauss-Newton step from the surface point ``SKL[0, 0]``
    (with its first derivatives ``SKL[1, 0]``, ``SKL[0, 1]``) toward the foot of
    ``(x, y, z)``; not ``ok`` when the normal equations are singular."""
    r0 = x - SKL[0, 0, 0]
    r1 = y - SKL[0, 0, 1]
    r2 = z - SKL[0, 0, 2]
    a11 = SKL[1, 0, 0] ** 2 + SKL[1, 0, 1] ** 2 + SKL[1, 0, 2] ** 2
    a22 = SKL[0, 1, 0] ** 2 + SKL[0, 1, 1] ** 2 + SKL[0, 1, 2] ** 2
    a12 = (SKL[1, 0, 0] * SKL[0, 1, 0] + SKL[1, 0, 1] * SKL[0, 1, 1]
           + SKL[1, 0, 2] * SKL[0, 1, 2])
    b1 = SKL[1, 0, 0] * r0 + SKL[1, 0, 1] * r1 + SKL[1, 0, 2] * r2
    b2 = SKL[0, 1, 0] * r0 + SKL[0, 1, 1] * r1 + SKL[0, 1, 2] * r2
    det = a11 * a22 - a12 * a12
    if not det > 0.0:
        return False, 0.0, 0.0
    return True, (a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det


@jit_inline
def _foot_descent(Pw, p, q, U, V, x, y, z, uu, vv, d, d_stop, exact_above, umin, umax,
                  vmin, vmax, Nu, Nv, left, right, tmp, Q, SKL, Du, Dv):
    """An upper bound of the distance from X = (x, y, z) to the surface, from
    ``d = |X - S(uu, vv)|`` down: damped Gauss-Newton steps on ``|X - S(uv)|^2`` with
    the exact first derivatives (:func:`~geomkit._kernels.surface.surface_point_d1`
    into ``SKL`` (2, 2, 3), ``Du``, ``Dv`` its scratch).  Every value returned
    is ``|X - S(uv')|`` for a surface point, so it bounds the distance from above
    whatever the steering; a step that does not lower it is halved.  Stops at
    ``d <= d_stop`` or ``d <= exact_above`` (the caller's result cannot fall
    further) or after :data:`FOOT_STEPS` steps.  On a heavily weighted surface the
    foot of a sliver triangle's point can lie far from ``(uu, vv)`` along the sliver,
    and difference quotients over the sample spacing steer wrongly: hence exact
    derivatives and several steps."""
    for it in range(FOOT_STEPS):
        if d <= d_stop or d <= exact_above:
            break
        surface_point_d1(Pw, p, q, U, V, uu, vv, Du, Dv, left, right, SKL)
        ok, du, dv = foot_step(SKL, x, y, z)
        if not ok:
            break
        moved = False
        for _ in range(FOOT_HALVINGS + 1):
            nu_ = min(umax, max(umin, uu + du))
            nv_ = min(vmax, max(vmin, vv + dv))
            surface_point(Pw, p, q, U, V, nu_, nv_, Nu, Nv, left, right, tmp, Q)
            dn = _dist3(x, y, z, Q[0], Q[1], Q[2])
            if dn < d:
                moved = True
                break
            du *= 0.5
            dv *= 0.5
        if not moved:
            break
        d = dn
        uu = nu_
        vv = nv_
    return d


@jit
def _gap_pass(Pw, p, q, U, V, A, B, C, T, k, exact_above, Nu, Nv, left, right, tmp, P, G,
              gc, floor):
    """``(worst, over)``: the running maximum from ``floor`` of the parametric gaps at
    the samples of :func:`_tri_dev` (same order, same arithmetic), and whether a gap
    exceeds ``exact_above`` or is NaN (then :func:`_tri_dev` measures the samples
    again with the exact distances).  On its own, without the exact branch, this
    loop runs about twice as fast (same-run timing of the grouped measure)."""
    worst = floor
    over = False
    for i in range(k + 1):
        for j in range(k + 1 - i):
            if (i == 0 and j == 0) or i == k or j == k:
                continue  # the corners are exact
            l1 = i / k
            l2 = j / k
            l0 = 1.0 - l1 - l2
            if gc[0] >= 0:
                i0 = k - i - j
                gu = (i0 * gc[0] + i * gc[2] + j * gc[4]) // k
                gv = (i0 * gc[1] + i * gc[3] + j * gc[5]) // k
                P[0] = G[gu, gv, 0]
                P[1] = G[gu, gv, 1]
                P[2] = G[gu, gv, 2]
            else:
                u = l0 * A[0] + l1 * B[0] + l2 * C[0]
                v = l0 * A[1] + l1 * B[1] + l2 * C[1]
                surface_point(Pw, p, q, U, V, u, v, Nu, Nv, left, right, tmp, P)
            x = l0 * T[0, 0] + l1 * T[1, 0] + l2 * T[2, 0]
            y = l0 * T[0, 1] + l1 * T[1, 1] + l2 * T[2, 1]
            z = l0 * T[0, 2] + l1 * T[1, 2] + l2 * T[2, 2]
            gap = _dist3(x, y, z, P[0], P[1], P[2])
            if not gap <= exact_above:
                over = True
            worst = max(worst, gap)
    return worst, over


@jit
def _gap_pass_uv(Pw, p, q, U, V, A, B, C, T, k, exact_above, Nu, Nv, left, right, tmp, P):
    """:func:`_gap_pass` from 0 without a grid (the same samples, order and arithmetic):
    every sample's surface point evaluated, by :func:`.surface.surface_point` compiled
    into the loop (the grouped measure's; in :func:`_gap_pass`, whose uniform grids read
    their points from the grid, the inlined code made them slower)."""
    worst = 0.0
    over = False
    for i in range(k + 1):
        for j in range(k + 1 - i):
            if (i == 0 and j == 0) or i == k or j == k:
                continue  # the corners are exact
            l1 = i / k
            l2 = j / k
            l0 = 1.0 - l1 - l2
            u = l0 * A[0] + l1 * B[0] + l2 * C[0]
            v = l0 * A[1] + l1 * B[1] + l2 * C[1]
            surface_point_inline(Pw, p, q, U, V, u, v, Nu, Nv, left, right, tmp, P)
            gap = _dist3(l0 * T[0, 0] + l1 * T[1, 0] + l2 * T[2, 0],
                         l0 * T[0, 1] + l1 * T[1, 1] + l2 * T[2, 1],
                         l0 * T[0, 2] + l1 * T[1, 2] + l2 * T[2, 2], P[0], P[1], P[2])
            if not gap <= exact_above:
                over = True
            worst = max(worst, gap)
    return worst, over


@jit
def _tri_dev(Pw, p, q, U, V, A, B, C, T, k, umin, umax, vmin, vmax, exact_above,
             Nu, Nv, left, right, tmp, P, Q, SKL, G, gc, Du, Dv, floor, Tall, j0, j1):
    """Deviation of the flat triangle T (3, 3) over the UV triangle A, B, C (2,) each.

    See :func:`triangle_deviation` for the measure.  With ``gc[0] >= 0`` the surface
    points of the samples are read from the grid ``G`` (k+1, k+1, 3) of a cell
    (:func:`_cell_grid`) whose corners A, B, C are the grid nodes
    ``gc = (a_u, a_v, b_u, b_v, c_u, c_v)`` (each 0 or k) instead of evaluated.
    Returns ``max(floor, deviation)``: a sample whose gap is at most the running
    maximum cannot raise it (its value is at most its gap), so its exact one-sided
    distances are not measured.  ``Tall[j0:j1]`` (n, 3, 3) are other triangles of the
    mesh (the other half of the cell's split): the surface point's distance to the
    mesh is bounded by its distance to the nearest of them and T (a long cell of a cone or a revolved face slides its
    parametrisation across the diagonal: the surface point of a sample lies over the
    other half).  The other direction, the triangle point's distance to the surface,
    is measured from T's own points as before.

    The gaps are taken first on their own (:func:`_gap_pass`); only when one exceeds
    ``exact_above`` (or is NaN) are the samples measured again with the exact
    distances, so the result is the same either way.
    """
    worst, over = _gap_pass(Pw, p, q, U, V, A, B, C, T, k, exact_above, Nu, Nv, left,
                            right, tmp, P, G, gc, floor)
    if not over:
        return worst
    worst = floor
    for i in range(k + 1):
        for j in range(k + 1 - i):
            l1 = i / k
            l2 = j / k
            l0 = 1.0 - l1 - l2
            if (i == 0 and j == 0) or i == k or j == k:
                continue  # the corners are exact
            u = l0 * A[0] + l1 * B[0] + l2 * C[0]
            v = l0 * A[1] + l1 * B[1] + l2 * C[1]
            gu = 0
            gv = 0
            if gc[0] >= 0:
                i0 = k - i - j
                gu = (i0 * gc[0] + i * gc[2] + j * gc[4]) // k
                gv = (i0 * gc[1] + i * gc[3] + j * gc[5]) // k
                P[0] = G[gu, gv, 0]
                P[1] = G[gu, gv, 1]
                P[2] = G[gu, gv, 2]
            else:
                surface_point(Pw, p, q, U, V, u, v, Nu, Nv, left, right, tmp, P)
            x = l0 * T[0, 0] + l1 * T[1, 0] + l2 * T[2, 0]
            y = l0 * T[0, 1] + l1 * T[1, 1] + l2 * T[2, 1]
            z = l0 * T[0, 2] + l1 * T[1, 2] + l2 * T[2, 2]
            gap = _dist3(x, y, z, P[0], P[1], P[2])
            if gap > exact_above and gap > worst:
                d_st = point_triangle_distance(P[0], P[1], P[2], T)
                for j in range(j0, j1):
                    if d_st <= exact_above:
                        break
                    d_st = min(d_st, point_triangle_distance(P[0], P[1], P[2], Tall[j]))
                d_ts = _foot_descent(Pw, p, q, U, V, x, y, z, u, v, gap, d_st, exact_above,
                                     umin, umax, vmin, vmax, Nu, Nv, left, right, tmp, Q,
                                     SKL, Du, Dv)
                # never more than the gap, which bounds both distances (a near-degenerate
                # triangle at a pole can make the closest-point rounding exceed it)
                gap = min(gap, max(d_st, d_ts))
            worst = max(worst, gap)
    return worst


@jit_inline
def _dev_scratch(p, q):
    mm = max(p, q) + 1
    return (np.empty(p + 1), np.empty(q + 1), np.empty(mm), np.empty(mm), np.empty(4),
            np.empty(3), np.empty(3), np.empty((2, 2, 3)), np.empty((2, p + 1)),
            np.empty((2, q + 1)))


@jit
def _triangle_deviation_range(i0, i1, Pw, p, q, U, V, tri_uv, tri_xyz, k, umin, umax, vmin,
                              vmax, exact_above, out):
    G = np.empty((1, 1, 3))
    gc = np.full(6, -1, dtype=np.int64)   # no grid: evaluate every sample
    _triangle_deviation_loop(i0, i1, Pw, p, q, U, V, tri_uv, tri_xyz, k, umin, umax, vmin,
                             vmax, exact_above, out, G, gc, _dev_scratch(p, q))


@jit
def _triangle_deviation_loop(i0, i1, Pw, p, q, U, V, tri_uv, tri_xyz, k, umin, umax, vmin,
                             vmax, exact_above, out, G, gc, scratch):
    """The loop of :func:`_triangle_deviation_range` over borrowed views (no atomic
    reference counting, :mod:`.numba_ext.borrow`)."""
    (Pw, U, V, tri_uv, tri_xyz, out, G, gc,
     (Nu, Nv, left, right, tmp, P, Q, SKL, Du, Dv)) = borrow_all((
         Pw, U, V, tri_uv, tri_xyz, out, G, gc, scratch))
    for t in range(i0, i1):
        out[t] = _tri_dev(Pw, p, q, U, V, tri_uv[t, 0], tri_uv[t, 1], tri_uv[t, 2],
                          tri_xyz[t], k, umin, umax, vmin, vmax, exact_above,
                          Nu, Nv, left, right, tmp, P, Q, SKL, G, gc, Du, Dv, 0.0,
                          tri_xyz, 0, 0)


def triangle_deviation(Pw, p, q, U, V, tri_uv, tri_xyz, k, umin, umax, vmin, vmax,
                       exact_above, out):
    """Measured deviation of flat triangles from the surface (parallel over triangles).

    At each barycentric sample ``(i/k, j/k)`` (edges included, ``(k+1)(k+2)/2`` per
    triangle) with triangle point ``X`` and surface point ``P = S(uv)``:

    * the parametric gap ``|P - X|`` bounds the distance both ways;
    * where it exceeds ``exact_above``, the two one-sided distances are measured
      instead: ``dist(P, triangle)`` exactly, and ``dist(X, surface)`` from above by
      ``|X - S(uv')|`` after damped Gauss–Newton steps ``uv -> uv'`` toward the
      foot of ``X`` (:func:`_foot_descent`; the first Jacobian from grid differences
      in :func:`cell_deviation`, forward differences at one sample spacing otherwise;
      any surface point bounds the distance from above, so the Jacobian only
      steers), stopping once ``|X - S(uv')|`` is at most ``dist(P, triangle)`` or
      ``exact_above``; the sample's value is the larger of the two (and never more
      than the gap).

    ``tri_uv`` (M, 3, 2), ``tri_xyz`` (M, 3, 3); ``out[t]`` is the largest sample
    value of triangle t.
    """
    _run(_triangle_deviation_range, tri_uv.shape[0], TRI_CHUNK, TRI_SERIAL, Pw, p, q, U, V,
         tri_uv, tri_xyz, k, umin, umax, vmin, vmax, exact_above, out)


@jit
def _cell_grid(Pw, p, q, U, V, u0, u1, v0, v1, k, Nu, Nv, left, right, Bu, Bv, H, G):
    """``G[a, b] = S(u0 + a (u1 - u0) / k, v0 + b (v1 - v0) / k)`` for a, b in 0..k by
    one tensor product: a cell lies in one knot span (cells refine the spans), so the
    span's basis polynomials hold on the whole closed cell, ends included."""
    su = find_span(Pw.shape[0] - 1, p, 0.5 * (u0 + u1), U)
    sv = find_span(Pw.shape[1] - 1, q, 0.5 * (v0 + v1), V)
    for a in range(k + 1):
        u = u1 if a == k else u0 + (u1 - u0) * (a / k)
        basis_funs(su, u, p, U, Nu, left, right)
        for i in range(p + 1):
            Bu[a, i] = Nu[i]
        v = v1 if a == k else v0 + (v1 - v0) * (a / k)
        basis_funs(sv, v, q, V, Nv, left, right)
        for j in range(q + 1):
            Bv[a, j] = Nv[j]
    for a in range(k + 1):
        for j in range(q + 1):
            for c in range(4):
                H[j, c] = 0.0
            col = sv - q + j
            for i in range(p + 1):
                w = Bu[a, i]
                row = su - p + i
                for c in range(4):
                    H[j, c] += w * Pw[row, col, c]
        for b in range(k + 1):
            h0 = 0.0
            h1 = 0.0
            h2 = 0.0
            h3 = 0.0
            for j in range(q + 1):
                w = Bv[b, j]
                h0 += w * H[j, 0]
                h1 += w * H[j, 1]
                h2 += w * H[j, 2]
                h3 += w * H[j, 3]
            G[a, b, 0] = h0 / h3
            G[a, b, 1] = h1 / h3
            G[a, b, 2] = h2 / h3


# corners (0: (u0,v0), 1: (u1,v0), 2: (u1,v1), 3: (u0,v1)) of the two triangles of
# each diagonal: 0 (AC): ABC, ACD; 1 (BD): ABD, BCD
_HALF = np.array([[[0, 1, 2], [0, 2, 3]], [[0, 1, 3], [1, 2, 3]]], dtype=np.int64)


@jit
def _cell_deviation_range(i0, i1, Pw, p, q, U, V, cells, first, k, umin, umax, vmin, vmax,
                          exact_above, target, pair, out):
    Nu, Nv, left, right, tmp, P, Q, SKL, Du, Dv = _dev_scratch(p, q)
    G = np.empty((k + 1, k + 1, 3))
    Bu = np.empty((k + 1, p + 1))
    Bv = np.empty((k + 1, q + 1))
    H = np.empty((q + 1, 4))
    gc = np.empty(6, dtype=np.int64)
    UVc = np.empty((4, 2))
    X = np.empty((4, 3))
    T = np.empty((2, 3, 3))
    _cell_deviation_loop(i0, i1, Pw, p, q, U, V, cells, first, k, umin, umax, vmin, vmax,
                         exact_above, target, pair, out,
                         (Nu, Nv, left, right, tmp, P, Q, SKL, G, Bu, Bv, H, gc, UVc, X, T,
                          Du, Dv))


@jit
def _cell_deviation_loop(i0, i1, Pw, p, q, U, V, cells, first, k, umin, umax, vmin, vmax,
                         exact_above, target, pair, out, scratch):
    """The loop of :func:`_cell_deviation_range` over borrowed views (no atomic
    reference counting, :mod:`.numba_ext.borrow`)."""
    (Pw, U, V, cells, first, out,
     (Nu, Nv, left, right, tmp, P, Q, SKL, G, Bu, Bv, H, gc, UVc, X, T, Du,
      Dv)) = borrow_all((
         Pw, U, V, cells, first, out, scratch))
    for c in range(i0, i1):
        UVc[0, 0] = cells[c, 0]
        UVc[0, 1] = cells[c, 2]
        UVc[1, 0] = cells[c, 1]
        UVc[1, 1] = cells[c, 2]
        UVc[2, 0] = cells[c, 1]
        UVc[2, 1] = cells[c, 3]
        UVc[3, 0] = cells[c, 0]
        UVc[3, 1] = cells[c, 3]
        _cell_grid(Pw, p, q, U, V, cells[c, 0], cells[c, 1], cells[c, 2], cells[c, 3], k,
                   Nu, Nv, left, right, Bu, Bv, H, G)
        for r in range(4):
            gu = k if r == 1 or r == 2 else 0
            gv = k if r >= 2 else 0
            X[r, 0] = G[gu, gv, 0]
            X[r, 1] = G[gu, gv, 1]
            X[r, 2] = G[gu, gv, 2]
        out[c, 0] = np.inf
        out[c, 1] = np.inf
        for step in range(2):
            diag = first[c] if step == 0 else 1 - first[c]
            if step == 1 and out[c, first[c]] <= target:
                break
            for half in range(2):
                for r in range(3):
                    for h in range(3):
                        T[half, h, r] = X[_HALF[diag, half, h], r]
            worst = 0.0
            for half in range(2):
                j1 = 2 - half if pair else 1 - half  # the other half, or none
                a = _HALF[diag, half, 0]
                b = _HALF[diag, half, 1]
                cc = _HALF[diag, half, 2]
                gc[0] = k if a == 1 or a == 2 else 0
                gc[1] = k if a >= 2 else 0
                gc[2] = k if b == 1 or b == 2 else 0
                gc[3] = k if b >= 2 else 0
                gc[4] = k if cc == 1 or cc == 2 else 0
                gc[5] = k if cc >= 2 else 0
                worst = max(worst, _tri_dev(Pw, p, q, U, V, UVc[a], UVc[b], UVc[cc], T[half],
                                            k, umin, umax, vmin, vmax, exact_above, Nu, Nv,
                                            left, right, tmp, P, Q, SKL, G, gc, Du,
                                            Dv, worst, T, 1 - half, j1))
            out[c, diag] = worst


def cell_deviation(Pw, p, q, U, V, cells, first, k, umin, umax, vmin, vmax, exact_above,
                   target, out, pair=False):
    """Measured deviation of the two-triangle splits of UV cells (parallel).

    ``cells`` (N, 4) ``u0, u1, v0, v1``; ``out`` (N, 2): column 0 for the diagonal
    (u0,v0)-(u1,v1), column 1 for (u1,v0)-(u0,v1), each the larger of its two
    triangles' :func:`triangle_deviation`.  Diagonal ``first[c]`` is measured first;
    when it is within ``target`` the other is not measured (+inf).  With ``pair``, a
    sample's surface point is measured against the nearer triangle of its split (both
    must be in the mesh: the cell is emitted as that pair, no hanging node), which
    bounds its distance to the mesh; the triangle points are measured against the
    surface as always.  Only where the feet's box ``umin..vmax`` is the face (an
    untrimmed face, a rectangle face): the feet then bound the distance to the face,
    whereas a trimmed face's mesh point can lie off the trimmed region, which only
    the surface point of its own triangle's sample showed.
    """
    _run(_cell_deviation_range, cells.shape[0], CELL_CHUNK, CELL_SERIAL, Pw, p, q, U, V,
         cells, first, k, umin, umax, vmin, vmax, exact_above, target, bool(pair), out)
