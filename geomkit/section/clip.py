"""Trim clipping of plane-section chains: which parts of a chain lie in its trimmed face.

Private helper of :mod:`geomkit.section.plane`: each chain of a trimmed surface
(:func:`geomkit.section.trace.trace_surface`) is densified and classified against the
trims (:func:`geomkit._kernels.section_clip.chain_side`), kept whole, dropped, or cut at
the exact trim crossings (:func:`_boundaries`), with stretches along an approximate
trim kept (:func:`_along_trim`).
"""

from __future__ import annotations

import numpy as np

from geomkit.section.joins import near_boundary
from geomkit.section.trace import _Eval
from geomkit.tolerances import TRIM_TOL
from geomkit._kernels.section_clip import INSIDE_ALL, MIXED, OUTSIDE_ALL, chain_side
from geomkit.validate import as_float_array
from geomkit.nurbs.trimming import OUTSIDE


TRIM_STEP = 1.0 / 1024
"""On trimmed surfaces, curve points are at most ``TRIM_STEP * domain size`` apart in
UV before they are classified (a trim loop smaller than that can be missed)."""


def clip_trims(s, plane, chains, zsnap, reach=0.0):
    """Keep the parts of each chain inside the trimmed face; the ends on the trim
    curve are found by bisection along the exact curve (classify_uv), all the face's
    crossings at once.  A stretch outside between two inside ones that stays within
    ``reach`` (3-D) of the face's boundary is kept (:func:`_along_trim`)."""
    if not s.is_trimmed:
        return chains
    ev = _Eval(s, plane)
    h = TRIM_STEP * max(ev.box[1] - ev.box[0], ev.box[3] - ev.box[2])
    out, pending, req_in, req_out = [], [], [], []
    for c in chains:
        uv = c["uv"]
        if c["closed"]:
            uv = np.concatenate([uv, uv[:1]])
        side, dense, inside = _chain_side(s, ev, uv, h, zsnap)
        if side == INSIDE_ALL:
            out.append(c)
            continue
        if side == OUTSIDE_ALL:
            continue
        if side == MIXED:
            uv = dense
        else:   # a point is not finite: densified again, the face fails, named
            uv = _densify(ev, uv, h, zsnap)
            inside = _not_outside(s, uv)
        if not inside.all() and reach > 0:
            inside = _along_trim(s, ev, uv, inside, c["closed"], reach)
        if inside.all():
            out.append(c)
            continue
        if c["closed"] and inside.any():  # start the walk at an outside point
            r = int(np.argmin(inside))
            uv = np.concatenate([uv[r:-1], uv[:r + 1]])
            inside = inside[np.r_[r:len(inside) - 1, :r + 1]]
        # runs of inside points [i0, i1); a boundary point before i0 > 0 and after
        # i1 < len(uv) (requests into req_in / req_out, solved below)
        d = np.diff(np.r_[0, inside.astype(np.int8), 0])
        for i0, i1 in zip(np.nonzero(d == 1)[0], np.nonzero(d == -1)[0]):
            head = tail = None
            if i0 > 0:
                head = len(req_in)
                req_in.append(uv[i0])
                req_out.append(uv[i0 - 1])
            if i1 < len(uv):
                tail = len(req_in)
                req_in.append(uv[i1 - 1])
                req_out.append(uv[i1])
            if (head is not None) + (i1 - i0) + (tail is not None) >= 2:
                pending.append((uv[i0:i1], head, tail, c["chord"]))
    if pending:
        q = _boundaries(s, ev, np.array(req_in), np.array(req_out), zsnap)
        for run, head, tail, chord in pending:
            parts = ([q[head:head + 1]] if head is not None else []) + [run] + (
                [q[tail:tail + 1]] if tail is not None else [])
            out.append({"uv": np.concatenate(parts), "closed": False, "chord": chord})
    return out


def _along_trim(s, ev, uv, inside, closed, reach):
    """``inside`` (k,) bool with the outside runs that lie between inside points and
    within ``reach`` (3-D) of the face's boundary set True.

    Where the plane contains a face's edge, the section runs along the trim curve, and
    a trim that only approximates the edge (a fitted pcurve: CTC-01 read through Open
    CASCADE has one within 2.6e-6 in of the plane, beyond the classification band)
    winds around it: classified alone, the section would fall into pieces with gaps
    between them.  A curve leaving the face and coming back within ``reach`` of its
    boundary all the way is on the boundary at that tolerance (a notch or hole of the
    trim shallower than ``reach`` is crossed, as it is below the section's resolution).
    """
    ins = inside.copy()
    d = np.diff(np.r_[ins[-1] if closed else 1, ins.astype(np.int8)].astype(np.int8))
    starts = np.flatnonzero(d == -1)   # first outside point of a run
    if not len(starts):
        return ins
    runs = []
    for i0 in starts:
        j = np.flatnonzero(ins[i0:])
        if len(j):
            runs.append(np.arange(i0, i0 + j[0]))
        elif closed and ins.any():   # the run wraps round to the start
            runs.append(np.r_[i0:len(ins), 0:int(np.argmax(ins))])
    if closed:
        runs = [r for r in runs if len(r) < len(ins)]
    else:
        runs = [r for r in runs if r[0] > 0 and r[-1] < len(ins) - 1]
    if not runs:
        return ins
    # the middle point of each run first: a run crossing a hole is out at once
    mid = np.array([r[len(r) // 2] for r in runs])
    near = near_boundary(s, ev.points(uv[mid]), reach)
    runs = [r for r, o in zip(runs, near) if o]
    if not runs:
        return ins
    idx = np.concatenate(runs)
    near = near_boundary(s, ev.points(uv[idx]), reach)
    ok = np.split(near, np.cumsum([len(r) for r in runs])[:-1])
    for r, o in zip(runs, ok):
        if o.all():
            ins[r] = True
    return ins


COARSE = 16
""":func:`_chain_side` densifies a chain first with ``COARSE`` times the step."""


def _chain_side(s, ev, uv, h, zsnap):
    """``(side, points, inside)``: ``INSIDE_ALL`` when every point of
    ``_densify(ev, uv, h, zsnap)`` is inside the trimmed face (``_not_outside``),
    ``OUTSIDE_ALL`` when none is; else ``MIXED`` with those points and their classes
    (:func:`geomkit._kernels.section_clip.chain_side`: the coarse densification with
    ``COARSE * h``, fine points where it comes near a trim curve or is cut)."""
    seg, deg, lp, nloops = s.trim_segments()
    tlo, thi = _trim_boxes(s)
    (u0, u1), (v0, v1) = s.domain
    return chain_side(*ev.args, np.ascontiguousarray(uv, dtype=np.float64), float(h),
                      float(COARSE * h), ev.box, float(0.25 * zsnap), 40, seg, deg, lp,
                      nloops, tlo, thi, float(TRIM_TOL * max(u1 - u0, v1 - v0)))


def _densify(ev, uv, h, zsnap):
    """Insert exact curve points until consecutive UV points are at most ``h`` apart
    (so that a trim loop crossing the curve is seen by point classification): each
    segment longer than ``h`` halved at the curve point projected from its middle, up
    to 40 times (:func:`geomkit._kernels.section_project.densify`)."""
    return _finite(ev.densify(uv, h, 0.25 * zsnap, 40))


def _boundaries(s, ev, a_in, b_out, zsnap, iters=60):
    """The curve points on the trim boundary between inside points ``a_in`` (n, 2) and
    outside points ``b_out`` (n, 2): bisection along the exact curve, all at once
    (:func:`geomkit._kernels.section_trims.trim_crossings`).

    A point is inside when ``classify_uv`` does not call it OUTSIDE within a round-off
    band (``1e-14`` of the domain): the ends land on the exact trim.  Where ``a_in`` is
    outside by that test, it was kept only for lying within the classification band
    (``TRIM_TOL``) of a trim curve: the curve runs along the trim (a face's edge lying
    in the plane, its trim a hair off the curve, e.g. v = 4e-10 against v = 0).  There
    every midpoint would be outside too and the end would stay at the first inside
    sample, up to ``TRIM_STEP`` of the domain short of the trim corner where that edge
    ends; such ends are bisected with the band ``a_in`` was classified with, and
    reach the corner within it.  (Both tests in the kernel, as ``classify_uv`` makes
    them: :func:`geomkit._kernels.section_trims.outside_binned`.)"""
    dom = max(ev.box[1] - ev.box[0], ev.box[3] - ev.box[2])
    band = 1e-14 * dom
    a = np.array(a_in, dtype=np.float64, order="C")
    b = np.array(b_out, dtype=np.float64, order="C")
    ev.trim_crossings(a, b, 0.25 * zsnap, band, TRIM_TOL * dom, iters, 1e-13)
    return _finite(a)


CLASSIFY_RUN = 16
"""Points classified together by :func:`_not_outside` (a run of consecutive curve
points whose box is far from every trim curve gets the class of its first)."""


def _not_outside(s, uv):
    """(n,) bool: ``s.classify_uv(uv) != OUTSIDE`` for the points of a curve ``uv``
    (n, 2), classifying one point per run of :data:`CLASSIFY_RUN` consecutive points
    whose UV box lies more than twice the classification band from the box of every
    trim segment's control points (which holds the segment).

    The classification of a point farther than the band from every trim curve is the
    exact parity of the loops around it (:func:`geomkit.classify_uv`), the same for
    every point of such a box (convex, meeting no trim curve); the domain rectangle is
    checked point by point.  The runs near a trim are classified point by point."""
    n = len(uv)
    if n <= 2 * CLASSIFY_RUN or not s.is_trimmed:
        return s.classify_uv(uv) != OUTSIDE
    (u0, u1), (v0, v1) = s.domain
    tol = TRIM_TOL * max(u1 - u0, v1 - v0)
    lo_s, hi_s = _trim_boxes(s)
    starts = np.arange(0, n, CLASSIFY_RUN)
    lo = np.minimum.reduceat(uv, starts, axis=0)
    hi = np.maximum.reduceat(uv, starts, axis=0)
    sep = 2 * tol
    far = ((lo[:, None, :] - hi_s[None] > sep) | (lo_s[None] - hi[:, None, :] > sep)).any(
        axis=2).all(axis=1)
    # the domain rectangle as classify_uv tests it, point by point
    d = np.minimum(np.minimum(uv[:, 0] - u0, u1 - uv[:, 0]),
                   np.minimum(uv[:, 1] - v0, v1 - uv[:, 1]))
    rect_out = d < -tol
    far &= ~np.logical_or.reduceat(rect_out, starts)
    run = np.repeat(np.arange(len(starts)), np.diff(np.r_[starts, n]))
    one = far[run]
    one[starts[far]] = False            # the first point of a far run is classified
    idx = np.flatnonzero(~one)
    out = np.empty(n, bool)
    out[idx] = s.classify_uv(uv[idx]) != OUTSIDE
    out[one] = out[starts[run[one]]]
    return out


TRIM_BOX_SPLITS = 3
""":func:`_trim_boxes` halves each trim segment this many times (8 boxes each)."""


def _trim_boxes(s):
    """(S, 2) lower and upper corners of boxes whose union holds the trim curves:
    those of the control points of the pieces of ``s.trim_segments()`` halved
    :data:`TRIM_BOX_SPLITS` times (de Casteljau; each piece lies in its control
    points' box: convex hull, weights > 0); kept on the surface."""
    boxes = s._cache.get("section_trim_boxes")
    if boxes is None:
        seg, deg, _lp, _n = s.trim_segments()
        lo, hi = [], []
        for Q, d in zip(seg, deg):
            pieces = [Q[:d + 1]]
            for _ in range(TRIM_BOX_SPLITS):
                pieces = [h for q in pieces for h in _halves(q)]
            for q in pieces:
                X = q[:, :2] / q[:, 2:3]
                lo.append(X.min(axis=0))
                hi.append(X.max(axis=0))
        boxes = s._cache["section_trim_boxes"] = (np.reshape(lo, (-1, 2)),
                                                  np.reshape(hi, (-1, 2)))
    return boxes


def _halves(Q):
    """The two halves of a homogeneous Bézier control polygon ``Q`` (d+1, 3) split at
    its middle (de Casteljau)."""
    left, right, P = [Q[0]], [Q[-1]], Q
    for _ in range(len(Q) - 1):
        P = 0.5 * (P[:-1] + P[1:])
        left.append(P[0])
        right.append(P[-1])
    return np.array(left), np.array(right[::-1])


def _finite(uv):
    """``uv`` checked finite, as ``classify_uv`` checks its input (a face whose curve
    points are not finite fails, named, instead of giving NaN points)."""
    return as_float_array(uv, "uv")
