"""Trim classification of a plane-section chain without densifying all of it.

Before a chain is clipped by the trims of its face, its curve is densified
(:func:`.section_project.densify`: exact curve points inserted by halving until consecutive
points are at most ``h`` apart in UV) and every point classified: a chain whose
points are all inside is kept whole, one whose points are all outside is dropped, and
only the others are cut.  Most chains of a part cross their face from edge to edge
and lie far from the trim curves but near their ends.  :func:`chain_side` decides the
two whole cases from a coarse densification (step ``H``; its points are points of the
fine one, the first levels of the same halving) and the fine points of only the coarse
segments that come near a trim curve or the domain's edge; for the others it gives
the fine points with their classes.  Points are classified by
:func:`.section_trims.outside_binned` (the trim segments of one bin over v).
"""

from __future__ import annotations

import numpy as np

from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit
from .section_project import _halve, point_scratch
from .section_trims import outside_binned, trim_bins
from .surface import D1, _binomial_table, derivs_scratch
from .trim import MAX_DEPTH as TRIM_MAX_DEPTH

INSIDE_ALL = 0
OUTSIDE_ALL = 1
MIXED = 2
NOT_FINITE = 3

FINE_MARGIN = 2.0
"""A coarse segment ``a -> b`` stands for the fine points between its ends, and they
lie in its box grown by ``FINE_MARGIN * |b - a|``: its fine halvings run with their
Newton iterates clamped to that box (met by the domain), as the domain alone clamps
them in :func:`.section_project.densify`.  The clamp is what bounds them: a fine point
is the projection of a midpoint moved at most the length of the segment it halves,
and those lengths need not shrink (a first halving stays within ``|b - a|`` of the
middle of ``a -> b``, a second within ``2 |b - a|`` of the segment, a third may
not).  Where no iterate reaches the box's edge (every chain of the 13 bench parts'
39 mid-planes) the fine points are densify's bit for bit; where one would, they stay
near their coarse segment instead of following Newton farther."""


@jit
def _in_domain(lu, hu, lv, hv, box, band):
    """The box ``[lu, hu] x [lv, hv]`` lies in the domain grown by ``band``."""
    return (lu >= box[0] - band and hu <= box[1] + band and lv >= box[2] - band
            and hv <= box[3] + band)


@jit
def _near_boxes(lu, hu, lv, hv, tlo, thi, idx, n, sep, out):
    """The trim boxes ``idx[:n]`` not separated from ``[lu, hu] x [lv, hv]`` by more
    than ``sep`` along u or v, written to ``out``; returns their count."""
    m = 0
    for r in range(n):
        k = idx[r]
        if not (lu - thi[k, 0] > sep or tlo[k, 0] - hu > sep or lv - thi[k, 1] > sep
                or tlo[k, 1] - hv > sep):
            out[m] = k
            m += 1
    return m


@jit
def chain_side(Pw, p, q, U, V, plane, uv, h, H, box, ftol, maxdepth, seg, seg_deg, seg_loop,
               nloops, tlo, thi, band):
    """The points of ``densify(uv, h)`` (:func:`.section_project.densify`) classified against
    the trimmed face: ``(side, points, inside)``.

    Parameters
    ----------
    Pw, p, q, U, V, plane : surface and plane as for :func:`.section_project.densify`;
        ``uv`` (n, 2) the chain, ``h`` its densification step, ``box`` the domain
        (u0, u1, v0, v1), ``ftol`` and ``maxdepth`` as for densify.
    H : the coarse step (> h).
    seg, seg_deg, seg_loop, nloops : the trim loops as packed by ``Surface.trim_segments``.
    tlo, thi : (S, 2) boxes holding the trim curves.
    band : the classification band (``classify_uv``'s ``tol``): a point is outside when
        it is outside the domain by more than ``band`` or ``classify_point`` says so.

    Returns
    -------
    side : ``INSIDE_ALL`` or ``OUTSIDE_ALL`` when every point is inside (outside),
        ``MIXED`` otherwise, ``NOT_FINITE`` when a point is not finite.
    points : (m, 2) the points of ``densify(uv, h)`` (their Newton iterates clamped
        near their coarse segment, see :data:`FINE_MARGIN`) and ``inside`` (m,) bool,
        ``classify_uv(points, band) != OUTSIDE``, when ``MIXED`` (else empty).

    A coarse segment whose box grown by :data:`FINE_MARGIN` times its length (which
    holds its fine points) lies more than ``2 * band`` from every trim box and inside
    the domain grown by ``band`` has one class for all the fine points it stands for
    (the parity of the loops around them, :func:`geomkit.classify_uv`): the class of
    one point, shared by consecutive such segments (their boxes overlap at the common
    end, no trim curve between).  The fine points of the other coarse segments are computed, and those
    of a fine segment whose own box is that far have the class of their stretch; the
    rest are classified one by one.
    """
    bin_ = _binomial_table(D1)
    scr = derivs_scratch(p, q, D1)
    SKL = np.empty((2, 2, 3))
    stack = np.empty((maxdepth + 2, 2))
    sdepth = np.empty(maxdepth + 2, np.int64)
    cls = _classifier(seg, seg_deg, seg_loop, nloops, tlo, thi, band, box)
    return _chain_side(Pw, p, q, U, V, plane, uv, h, H, box, ftol, maxdepth, cls,
                       (stack, sdepth, bin_, scr, SKL, point_scratch(p, q)))


@jit
def _chain_side(Pw, p, q, U, V, plane, uv, h, H, box, ftol, maxdepth, cls, scratch):
    """:func:`chain_side` over borrowed views of its arrays, the classifier ``cls``
    and the scratch (held by the caller: no atomic reference counting,
    :mod:`.numba_ext.borrow`)."""
    Pw, U, V, plane, uv, box, cls, scratch = borrow_all((Pw, U, V, plane, uv, box, cls,
                                                          scratch))
    stack, sdepth, bin_, scr, SKL, sp = scratch
    n = uv.shape[0]
    # the coarse points, each with the depth of the segment it ends
    cp = np.empty((max(2 * n, 16), 2))
    cdep = np.empty(cp.shape[0], np.int64)
    nc = 0
    if n > 0:
        cp[0, 0] = uv[0, 0]
        cp[0, 1] = uv[0, 1]
        cdep[0] = 0
        nc = 1
    for i in range(n - 1):
        nc, cp, cdep = _halve(Pw, p, q, U, V, plane, uv[i, 0], uv[i, 1], uv[i + 1, 0],
                              uv[i + 1, 1], 0, H, box, ftol, maxdepth, cp, cdep, nc, stack,
                              sdepth, bin_, scr, SKL, sp)
    for j in range(nc):
        if not (np.isfinite(cp[j, 0]) and np.isfinite(cp[j, 1])):
            return NOT_FINITE, np.empty((0, 2)), np.empty(0, np.bool_)
    # the fine points the first walk computes, kept for the second (same bits: each
    # coarse segment's fine points depend on its ends, depth and box only)
    memo = (np.empty((max(64, 4 * nc), 2)), np.full(max(nc, 1), -1, np.int64),
            np.zeros(max(nc, 1), np.int64))
    side, pts, ins, memo = _walk(Pw, p, q, U, V, plane, cp, cdep, nc, h, box, ftol, maxdepth,
                                 cls, False, memo, stack, sdepth, bin_, scr, SKL, sp)
    if side == MIXED:
        side, pts, ins, memo = _walk(Pw, p, q, U, V, plane, cp, cdep, nc, h, box, ftol,
                                     maxdepth, cls, True, memo, stack, sdepth, bin_, scr, SKL,
                                     sp)
    return side, pts, ins


@jit
def _classifier(seg, seg_deg, seg_loop, nloops, tlo, thi, band, box):
    """The trims, their boxes, their bins over v (:func:`.section_trims.trim_bins`) and
    the scratch of :func:`.section_trims.outside_binned`, bundled."""
    p1 = seg.shape[1]
    return (seg, seg_deg, seg_loop, nloops, tlo, thi, band, box,
            np.empty(max(nloops, 1), dtype=np.int64), np.empty((TRIM_MAX_DEPTH + 2, p1, 3)),
            np.empty(TRIM_MAX_DEPTH + 2, dtype=np.int64), np.empty((p1, 3)),
            np.empty((p1, 3)), np.empty(tlo.shape[0], np.int64),
            np.empty(tlo.shape[0], np.int64), np.arange(tlo.shape[0]),
            trim_bins(seg, seg_deg, band))


@jit
def _out(cls, u, v):
    """``classify_uv((u, v), band) == OUTSIDE`` (:func:`.section_trims.outside_binned`:
    the segments of one bin over v walked)."""
    (seg, seg_deg, seg_loop, nloops, _tlo, _thi, band, box, winding, cstack, depths, left,
     right, _near, _fnear, _all, bins) = cls
    return outside_binned(seg, seg_deg, seg_loop, nloops, u, v, box, band, bins, winding,
                          cstack, depths, left, right, None, None)


@jit
def _walk(Pw, p, q, U, V, plane, cp, cdep, nc, h, box, ftol, maxdepth, cls, record, memo,
          stack, sdepth, bin_, scr, SKL, sp):
    """The classes along the coarse points ``cp[:nc]`` (see :func:`chain_side`):
    without ``record``, stops at the first point of the other class and returns only
    the side; with it, returns every fine point and its class.  ``memo`` = (points,
    start per coarse segment or -1, count): without ``record`` the fine points
    computed are kept there, with it they are taken from there; returned (grown)."""
    mpts, moff, mcnt = memo
    nmemo = 0
    tlo = cls[4]
    thi = cls[5]
    band = cls[6]
    near = cls[13]
    fnear = cls[14]
    alltb = cls[15]
    ntb = tlo.shape[0]
    sep = 2.0 * band
    fine = np.empty((64, 2))
    fdep = np.empty(64, np.int64)
    fbox = np.empty(4)
    pts = np.empty((max(16, 16 * nc) if record else 0, 2))
    ins = np.empty(pts.shape[0], np.bool_)
    npts = 0
    n_in = 0
    n_out = 0
    if record and nc > 0:
        pts[0, 0] = cp[0, 0]
        pts[0, 1] = cp[0, 1]
        ins[0] = not _out(cls, cp[0, 0], cp[0, 1])
        npts = 1
        if ins[0]:
            n_in += 1
        else:
            n_out += 1
    if nc == 1:
        if _out(cls, cp[0, 0], cp[0, 1]):
            n_out = 1
        else:
            n_in = 1
    known = False       # the class of the current stretch of far segments is known
    kout = False
    for j in range(nc - 1):
        au = cp[j, 0]
        av = cp[j, 1]
        bu = cp[j + 1, 0]
        bv = cp[j + 1, 1]
        m = FINE_MARGIN * np.sqrt((bu - au) ** 2 + (bv - av) ** 2)
        lu = min(au, bu) - m
        hu = max(au, bu) + m
        lv = min(av, bv) - m
        hv = max(av, bv) + m
        nn = _near_boxes(lu, hu, lv, hv, tlo, thi, alltb, ntb, sep, near)
        far = nn == 0 and _in_domain(lu, hu, lv, hv, box, band)
        if far and not known:
            kout = _out(cls, au, av)
            known = True
            if kout:
                n_out += 1
            else:
                n_in += 1
        if far and not record:
            continue
        if not far:
            known = False
        # the fine points of this segment, its start excluded, their Newton iterates
        # clamped to its grown box met by the domain (FINE_MARGIN)
        fbox[0] = max(box[0], lu)
        fbox[1] = min(box[1], hu)
        fbox[2] = max(box[2], lv)
        fbox[3] = min(box[3], hv)
        fine[0, 0] = au
        fine[0, 1] = av
        if record and moff[j] >= 0:
            nf = mcnt[j] + 1
            if nf > fine.shape[0]:
                fine = np.empty((2 * nf, 2))
                fine[0, 0] = au
                fine[0, 1] = av
            for k in range(1, nf):
                fine[k, 0] = mpts[moff[j] + k - 1, 0]
                fine[k, 1] = mpts[moff[j] + k - 1, 1]
        else:
            nf, fine, fdep = _halve(Pw, p, q, U, V, plane, au, av, bu, bv, cdep[j + 1], h,
                                    fbox, ftol, maxdepth, fine, fdep, 1, stack, sdepth, bin_,
                                    scr, SKL, sp)
            if not record:
                if nmemo + nf > mpts.shape[0]:
                    bigger = np.empty((2 * (nmemo + nf), 2))
                    bigger[:nmemo] = mpts[:nmemo]
                    mpts = bigger
                moff[j] = nmemo
                mcnt[j] = nf - 1
                for k in range(1, nf):
                    mpts[nmemo, 0] = fine[k, 0]
                    mpts[nmemo, 1] = fine[k, 1]
                    nmemo += 1
        if record and npts + nf > pts.shape[0]:
            pts, ins = _grow(pts, ins, npts, 2 * (npts + nf))
        if far:       # every fine point in the stretch's class
            for k in range(1, nf):
                pts[npts, 0] = fine[k, 0]
                pts[npts, 1] = fine[k, 1]
                ins[npts] = not kout
                npts += 1
            continue
        fknown = False
        fout = False
        prev_out = False      # the class of fine[k] when classified one by one
        prev_done = record or j > 0   # fine[0] counted (recorded, or the last
        #                                 point of the segment before)
        if record:
            prev_out = not ins[npts - 1]
        for k in range(nf - 1):
            fu = fine[k, 0]
            fv = fine[k, 1]
            gu = fine[k + 1, 0]
            gv = fine[k + 1, 1]
            if not (np.isfinite(gu) and np.isfinite(gv)):
                return NOT_FINITE, pts[:0].copy(), ins[:0].copy(), (mpts, moff, mcnt)
            flu = min(fu, gu)
            fhu = max(fu, gu)
            flv = min(fv, gv)
            fhv = max(fv, gv)
            if flu >= lu and fhu <= hu and flv >= lv and fhv <= hv:
                ffar = _near_boxes(flu, fhu, flv, fhv, tlo, thi, near, nn, sep, fnear) == 0
            else:   # off the coarse box: every trim box
                ffar = _near_boxes(flu, fhu, flv, fhv, tlo, thi, alltb, ntb, sep, fnear) == 0
            ffar = ffar and _in_domain(flu, fhu, flv, fhv, box, band)
            if ffar:
                if not fknown:
                    if k == 0 and record:
                        fout = prev_out
                    else:
                        fout = _out(cls, fu, fv)
                        if fout:
                            n_out += 1
                        else:
                            n_in += 1
                    fknown = True
                gout = fout
            else:
                fknown = False
                if k == 0 and not prev_done:
                    if _out(cls, fu, fv):
                        n_out += 1
                    else:
                        n_in += 1
                gout = _out(cls, gu, gv)
                if gout:
                    n_out += 1
                else:
                    n_in += 1
            prev_done = True
            if record:
                pts[npts, 0] = gu
                pts[npts, 1] = gv
                ins[npts] = not gout
                npts += 1
            elif n_in > 0 and n_out > 0:
                return MIXED, pts, ins, (mpts, moff, mcnt)
        if not record and n_in > 0 and n_out > 0:
            return MIXED, pts, ins, (mpts, moff, mcnt)
    if n_in > 0 and n_out > 0:
        return MIXED, pts[:npts].copy(), ins[:npts].copy(), (mpts, moff, mcnt)
    return ((OUTSIDE_ALL if n_out > 0 else INSIDE_ALL), pts[:0].copy(), ins[:0].copy(),
            (mpts, moff, mcnt))


@jit
def _grow(pts, ins, n, size):
    """``pts`` (.., 2) and ``ins`` with room for ``size`` rows, the first ``n`` kept."""
    P = np.empty((size, 2))
    P[:n] = pts[:n]
    B = np.empty(size, np.bool_)
    B[:n] = ins[:n]
    return P, B
