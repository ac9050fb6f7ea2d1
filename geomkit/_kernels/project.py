"""Point projection kernels: the batch driver (candidate search, Newton feet, foot
classes, certificates) over packed surfaces; the Newton itself is in
:mod:`geomkit._kernels.project_newton`.

Surfaces are passed packed (see :func:`geomkit.projection._pack`): ``Pw_all``
(sum nu*nv, 4) homogeneous control points, per surface ``meta[s] = (offset, nu, nv,
p, q, U offset, V offset)`` into ``Pw_all``, ``U_all``, ``V_all``, and the domain
``dom[s] = (umin, umax, vmin, vmax)``.
"""

from __future__ import annotations

import numpy as np

from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit, jit_inline, prun
from .foot_class import _deep_cell, _foot_class
from .project_cert import cert_settle
from .project_newton import (FOOT_NOT_CONVERGED, FOOT_OK, MAX_ITER,  # noqa: F401 (re-exported)
                             foot_c0, foot_newton)
from .project_outside import settled_outside
from .surface import D2, _binomial_table, derivs_scratch
from .trim import BOUNDARY, INSIDE, MAX_DEPTH, OUTSIDE  # noqa: F401 (re-exported)
from .voxel import (candidate_scratch, candidates_batch,  # noqa: F401 (the search alone)
                    search)

PROJECT_CHUNK = 64


@jit_inline
def _surface(Pw_all, U_all, V_all, meta, s):
    o, nu, nv, p, q, uo, vo = (meta[s, 0], meta[s, 1], meta[s, 2], meta[s, 3], meta[s, 4],
                               meta[s, 5], meta[s, 6])
    Pw = Pw_all[o:o + nu * nv].reshape((nu, nv, 4))
    U = U_all[uo:uo + nu + p + 1]
    V = V_all[vo:vo + nv + q + 1]
    return Pw, p, q, U, V


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
    (:mod:`geomkit._kernels.numba_ext.borrow`: no atomic reference counts in the loop; every
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
            start, tris, sc, i, max_dist[i])
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
    ``max_dist[i]`` (the point's own search radius).  ``out_work[i]`` = (cells opened, triangles tested, candidates, index
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
