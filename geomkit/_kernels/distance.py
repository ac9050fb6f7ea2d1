"""Surface–surface minimum distance kernels: branch and bound over rational Bézier
sub-patch pairs with certified bounds, and a 4-unknown Newton on the exact surfaces.

Data layout (built by :mod:`geomkit.distance`):

* surfaces packed as in :func:`geomkit.projection._pack` (``Pw_all``, ``U_all``,
  ``V_all``, ``meta``, ``dom``), one index space for the surfaces of both scenes;
* trims: ``seg_all`` (S, pmax+1, 3) homogeneous Bézier trim segments of every
  surface, ``seg_deg``, ``seg_loop`` (loop index within its surface), ``seg_box``
  (P, 4) UV control-point boxes of sub-arcs of the segments, and per surface
  ``trim_meta[s] = (first segment, segment count, loop count, first box, box count)`` (count 0: untrimmed);
* sub-patch nodes: control nets in a flat pool ``ctrl`` (row-major (p+1, q+1, 4)
  homogeneous), integer fields ``ni[k] = (offset, p, q, surface, child0, child1,
  state, rep_ok, side, split_dir)`` and float fields ``nf[k] = (u0, u1, v0, v1,
  xmin, ymin, zmin, xmax, ymax, zmax, rep x, y, z, rep u, rep v, size)``.

Certificate.  With positive weights a rational Bézier patch lies in the convex hull of
its Cartesian control points, so for any unit direction d

    min_{x in A, y in B} |x - y|  >=  min_j (Q_j . d) - max_i (P_i . d),

and also >= the gap between the control points' axis boxes.  The lower bound of a
pair is the largest of these (d along the box centres and along the two
representative surface points), and the curved separators of
:mod:`geomkit._kernels.distance_sep` (distance to a point / line: ``|x - y| >=
phi(y) - phi(x)``) when the first Newton feet suggest one.  Upper bounds are distances between real surface
points (patch centres by de Casteljau, then Newton) that lie inside their trimmed
faces.  A pair whose lower bound is >= upper - tol cannot improve the answer by more
than tol and is discarded; the search stops when the smallest open lower bound is
>= upper - tol, so [lower, upper] contains the exact distance.
"""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.borrow import borrow_all, borrow_opt
from .numba_ext.policy import jit_plain as jit
from .surface import D2, _binomial_table, derivs_scratch
from .trim import MAX_DEPTH
from .voxel import _heap_pop, _heap_push
from .distance_nodes import (  # noqa: F401  (layout re-exported for geomkit.distance)
    NF, NI, F_BOX, F_REP, F_REPUV, F_SIZE, F_U0, F_U1, F_V0, F_V1, I_C0, I_C1, I_DIR, I_OFF,
    I_P, I_Q, I_REPOK, I_SIDE, I_STATE, I_SURF, ST_INSIDE, ST_MIXED, ST_OUTSIDE, _box_trim_state,
    _grow1, _grow2, _max_loops, _node_box, _patch_eval, _split_dir, _split_into, _uv_inside,
    init_nodes, pair_lower_bound)
from .distance_newton import alternate_feet, newton4
from .distance_sep import (NSEP, SEP_W, curvature_separators, keep_level_separators,
                           sep_bounds, sep_lower_bound, sphere_fit_separator)

# stop codes
STOP_CERTIFIED = 0
STOP_MAX_PAIRS = 1
STOP_EXHAUSTED = 2


# --------------------------------------------------------------------------- B&B
@jit
def branch_and_bound(ctrl, ni, nf, n_nodes, nodes_a, nodes_b, Pw_all, U_all, V_all, meta,
                     dom, seg_all, seg_deg, seg_loop, seg_box, trim_meta, uv_tol, tol,
                     min_size, max_pairs, max_newton, step_tol, out_f, out_i):
    """Best-first branch and bound over pairs (node of scene A, node of scene B).

    ``ctrl``, ``ni``, ``nf`` hold the ``n_nodes`` root nodes (the Bézier patches,
    boxes and representative points filled, children -1); the pools grow as needed.
    Results: ``out_f = (upper, lower, xa, ya, za, xb, yb, zb, ua, va, ub, vb)``,
    ``out_i = (surface a, surface b, pairs popped, pairs split, pairs pushed,
    nodes, newton runs, stop code, peak heap, pruned pairs)``.
    Returns the final pools (for inspection and memory accounting).
    ``seg_all`` None: no face is trimmed; numba prunes the ``seg_all is None`` branches
    of that specialisation, so the trim classification and the trim-edge search
    (``alternate_feet``) are not compiled for it.
    """
    pmax1 = np.int64(1)
    if seg_all is not None:
        pmax1 = seg_all.shape[1]
    winding = np.zeros(_max_loops(trim_meta), dtype=np.int64)
    stack = np.empty((MAX_DEPTH + 2, pmax1, 3))
    depths = np.empty(MAX_DEPTH + 2, dtype=np.int64)
    tleft = np.empty((pmax1, 3))
    tright = np.empty((pmax1, 3))
    maxdeg = np.int64(1)  # not a literal: one compile of derivs_scratch
    for s in range(meta.shape[0]):
        maxdeg = max(maxdeg, max(meta[s, 3], meta[s, 4]))
    tmp = np.empty((2 * maxdeg + 3, 4))
    bin_ = _binomial_table(2 * maxdeg + 2)
    scra = derivs_scratch(maxdeg, maxdeg, D2)
    scrb = derivs_scratch(maxdeg, maxdeg, D2)
    SA = np.zeros((3, 3, 3))
    SB = np.zeros((3, 3, 3))
    x4 = np.empty(4)
    alt = np.empty(10)

    cap = max(1024, 4 * nodes_a.shape[0] * nodes_b.shape[0])
    hlb = np.empty(cap)
    hab = np.empty(cap, dtype=np.int64)  # a pair (a, b) packed as a << 32 | b
    nh = 0
    upper = np.inf
    best_a = -1
    best_b = -1
    bx = np.zeros(12)
    pruned_min = np.inf
    pushed = 0
    newton_runs = 0
    pruned = 0

    # initial upper bound from representative points, then the root pairs
    for ia in range(nodes_a.shape[0]):
        a = nodes_a[ia]
        for ib in range(nodes_b.shape[0]):
            b = nodes_b[ib]
            if ni[a, I_REPOK] and ni[b, I_REPOK]:
                d = 0.0
                for c in range(3):
                    e = nf[a, F_REP + c] - nf[b, F_REP + c]
                    d += e * e
                d = math.sqrt(d)
                if d < upper:
                    upper = d
                    best_a = a
                    best_b = b
                    for c in range(3):
                        bx[2 + c] = nf[a, F_REP + c]
                        bx[5 + c] = nf[b, F_REP + c]
                    bx[8] = nf[a, F_REPUV]
                    bx[9] = nf[a, F_REPUV + 1]
                    bx[10] = nf[b, F_REPUV]
                    bx[11] = nf[b, F_REPUV + 1]
    bsa = ni[best_a, I_SURF] if best_a >= 0 else -1
    bsb = ni[best_b, I_SURF] if best_b >= 0 else -1
    # Newton from the best root pair
    if best_a >= 0:
        x4[0] = bx[8]
        x4[1] = bx[9]
        x4[2] = bx[10]
        x4[3] = bx[11]
        d = newton4(Pw_all, U_all, V_all, meta, dom, bsa, bsb, x4, step_tol, bin_, scra,
                    scrb, SA, SB)
        newton_runs += 1
        ok = d < upper
        if seg_all is not None:
            if ok:
                ok = _uv_inside(seg_all, seg_deg, seg_loop, trim_meta, bsa, x4[0], x4[1],
                                uv_tol, winding, stack, depths, tleft, tright) \
                    and _uv_inside(seg_all, seg_deg, seg_loop, trim_meta, bsb, x4[2], x4[3],
                                   uv_tol, winding, stack, depths, tleft, tright)
        if ok:
            upper = d
            for c in range(3):
                bx[2 + c] = SA[0, 0, c]
                bx[5 + c] = SB[0, 0, c]
            for c in range(4):
                bx[8 + c] = x4[c]
    # curved separators (points / lines) from the principal curvatures at the feet
    sep = np.zeros((NSEP, SEP_W))
    nsep = 0
    extent = 0.0
    if best_a >= 0:
        for k in range(n_nodes):
            extent = max(extent, nf[k, F_SIZE])
        nsep = sphere_fit_separator(ctrl, ni[best_a, I_OFF], ni[best_a, I_P],
                                    ni[best_a, I_Q], bin_, sep, nsep, extent)
        nsep = sphere_fit_separator(ctrl, ni[best_b, I_OFF], ni[best_b, I_P],
                                    ni[best_b, I_Q], bin_, sep, nsep, extent)
        nsep = curvature_separators(SA, sep, nsep, extent)
        nsep = curvature_separators(SB, sep, nsep, extent)
    ph = np.zeros((max(2, ni.shape[0]), 2 * NSEP + 1))
    Zs = np.empty(((maxdeg + 1) * (maxdeg + 1), 4))
    Rs = np.empty((2 * maxdeg + 1, 2 * maxdeg + 1))
    if nsep > 0:
        nsep = keep_level_separators(ctrl, ni[best_a, I_OFF], ni[best_a, I_P],
                                     ni[best_a, I_Q], ni[best_b, I_OFF], ni[best_b, I_P],
                                     ni[best_b, I_Q], sep, nsep, bin_, Zs, Rs, ph,
                                     extent)
    if nsep > 0:
        for k in range(n_nodes):
            sep_bounds(ctrl, ni[k, I_OFF], ni[k, I_P], ni[k, I_Q], sep, nsep, bin_, Zs, Rs,
                       ph, k)
    for ia in range(nodes_a.shape[0]):
        a = nodes_a[ia]
        for ib in range(nodes_b.shape[0]):
            b = nodes_b[ib]
            lb = max(pair_lower_bound(ctrl, ni, nf, a, b), sep_lower_bound(ph, nsep, a, b))
            if lb >= upper - tol:
                pruned += 1
                pruned_min = min(pruned_min, lb)
                continue
            hlb, hab, nh = _heap_push(hlb, hab, nh, lb, (a << 32) | b)
            pushed += 1
    ctrl_top = np.int64(0)  # not a literal: one compile of _split_into
    for k in range(n_nodes):
        ctrl_top = max(ctrl_top, ni[k, I_OFF] + (ni[k, I_P] + 1) * (ni[k, I_Q] + 1) * 4)
    mrow = np.int64(4)  # the largest control net (children keep their parent's degrees)
    for k in range(n_nodes):
        mrow = max(mrow, (ni[k, I_P] + 1) * (ni[k, I_Q] + 1) * 4)
    kids = np.empty(2, dtype=np.int64)
    # the search's state between its calls: it returns whenever a pool (nodes, control
    # points, heap) is too small for the next pair, and the pools grow here, so that
    # it reads every array through a borrowed view (its own allocations could not be)
    sti = np.zeros(12, dtype=np.int64)
    sti[0] = nh
    sti[1] = n_nodes
    sti[2] = ctrl_top
    sti[3] = bsa
    sti[4] = bsb
    sti[5] = pushed
    sti[6] = pruned
    sti[7] = newton_runs
    sti[8] = nh
    sti[11] = STOP_CERTIFIED
    stf = np.array([upper, pruned_min, np.inf])
    while not _search(ctrl, ni, nf, ph, hlb, hab, sti, stf, mrow, nsep,
                      (Pw_all, U_all, V_all, meta, dom), seg_all,
                      (seg_deg, seg_loop, seg_box, trim_meta),
                      (bin_, scra, scrb, SA, SB, x4, alt, bx, kids, tmp, sep, Zs, Rs),
                      (winding, stack, depths, tleft, tright), uv_tol, tol, min_size,
                      max_pairs, max_newton, step_tol, out_f, out_i):
        need = sti[1] + 2
        if need > ni.shape[0]:
            ni = _grow2(ni, need)
            nf = _grow2(nf, need)
            ph = _grow2(ph, ni.shape[0])
        need = sti[2] + 2 * mrow
        if need > ctrl.shape[0]:
            ctrl = _grow1(ctrl, need)
        need = sti[0] + 2
        if need > hlb.shape[0]:
            hlb = _grow1(hlb, need)
            hab = _grow1(hab, need)
    return ctrl, ni, nf


@jit
def _search(ctrl, ni, nf, ph, hlb, hab, sti, stf, mrow, nsep, surf, seg_all, trims, scr, tscr,
            uv_tol, tol, min_size, max_pairs, max_newton, step_tol, out_f, out_i):
    """The best-first loop of :func:`branch_and_bound` over borrowed views of every
    array (no atomic reference counting, :mod:`geomkit._kernels.numba_ext.borrow`): the
    arguments, the caller's scratch and the pools (``ctrl``, ``ni``, ``nf``, ``ph``,
    the heap ``hlb``, ``hab``), which never grow here: before each pair, when one could
    not take two more nodes (``mrow`` control-point values each) or two more heap
    entries, the state goes back into ``sti`` / ``stf`` and the search returns False
    for the caller to grow them and call again.  True when the search is over
    (``out_f``, ``out_i`` filled).  ``seg_all`` is read through ``segb``
    (:func:`~geomkit._kernels.numba_ext.borrow.borrow_opt`)."""
    Pw_all, U_all, V_all, meta, dom = borrow_all(surf)
    seg_deg, seg_loop, seg_box, trim_meta = borrow_all(trims)
    segb = borrow_opt(seg_all)
    bin_, scra, scrb, SA, SB, x4, alt, bx, kids, tmp, sep, Zs, Rs = borrow_all(scr)
    winding, stack, depths, tleft, tright = borrow_all(tscr)
    out_f, out_i = borrow_all((out_f, out_i))
    ctrl, ni, nf, ph, hlb, hab, sti, stf = borrow_all((ctrl, ni, nf, ph, hlb, hab, sti, stf))
    nh, n_nodes, ctrl_top, bsa, bsb = sti[0], sti[1], sti[2], sti[3], sti[4]
    pushed, pruned, newton_runs, peak, popped = sti[5], sti[6], sti[7], sti[8], sti[9]
    splits, stop = sti[10], sti[11]
    upper, pruned_min, final_min = stf[0], stf[1], stf[2]
    while nh > 0:
        if (n_nodes + 2 > ni.shape[0] or ctrl_top + 2 * mrow > ctrl.shape[0]
                or nh + 2 > hlb.shape[0]):
            sti[0], sti[1], sti[2], sti[3], sti[4] = nh, n_nodes, ctrl_top, bsa, bsb
            sti[5], sti[6], sti[7], sti[8], sti[9] = pushed, pruned, newton_runs, peak, popped
            sti[10], sti[11] = splits, stop
            stf[0], stf[1], stf[2] = upper, pruned_min, final_min
            return False
        lb = hlb[0]
        a = hab[0] >> 32
        b = hab[0] & 0xFFFFFFFF
        if lb >= upper - tol:
            break
        if popped >= max_pairs:
            stop = STOP_MAX_PAIRS
            break
        nh = _heap_pop(hlb, hab, nh)
        popped += 1
        # upper bound from the pair's representative points (+ Newton when it improves)
        if ni[a, I_REPOK] and ni[b, I_REPOK]:
            d = 0.0
            for c in range(3):
                e = nf[a, F_REP + c] - nf[b, F_REP + c]
                d += e * e
            d = math.sqrt(d)
            if d < upper:
                upper = d
                bsa = ni[a, I_SURF]
                bsb = ni[b, I_SURF]
                for c in range(3):
                    bx[2 + c] = nf[a, F_REP + c]
                    bx[5 + c] = nf[b, F_REP + c]
                bx[8] = nf[a, F_REPUV]
                bx[9] = nf[a, F_REPUV + 1]
                bx[10] = nf[b, F_REPUV]
                bx[11] = nf[b, F_REPUV + 1]
                if newton_runs < max_newton:
                    x4[0] = bx[8]
                    x4[1] = bx[9]
                    x4[2] = bx[10]
                    x4[3] = bx[11]
                    sa = ni[a, I_SURF]
                    sb = ni[b, I_SURF]
                    d = newton4(Pw_all, U_all, V_all, meta, dom, sa, sb, x4, step_tol, bin_,
                                scra, scrb, SA, SB)
                    newton_runs += 1
                    ok = d < upper
                    if seg_all is not None:
                        if ok:
                            ok = _uv_inside(segb, seg_deg, seg_loop, trim_meta, sa, x4[0],
                                            x4[1], uv_tol, winding, stack, depths, tleft,
                                            tright) \
                                and _uv_inside(segb, seg_deg, seg_loop, trim_meta, sb,
                                               x4[2], x4[3], uv_tol, winding, stack, depths,
                                               tleft, tright)
                    if ok:
                        upper = d
                        bsa = sa
                        bsb = sb
                        for c in range(3):
                            bx[2 + c] = SA[0, 0, c]
                            bx[5 + c] = SB[0, 0, c]
                        for c in range(4):
                            bx[8 + c] = x4[c]
                    elif seg_all is None:
                        pass  # untrimmed faces: no trim edge to follow
                    elif trim_meta[sa, 1] > 0 or trim_meta[sb, 1] > 0:
                        x4[0] = nf[a, F_REPUV]
                        x4[1] = nf[a, F_REPUV + 1]
                        x4[2] = nf[b, F_REPUV]
                        x4[3] = nf[b, F_REPUV + 1]
                        d = alternate_feet(Pw_all, U_all, V_all, meta, dom, segb, seg_deg,
                                           seg_loop, trim_meta, sa, sb, x4, uv_tol, step_tol,
                                           bin_, scra, SA, winding, stack, depths, tleft,
                                           tright, alt)
                        newton_runs += 1
                        if d < upper:
                            upper = d
                            bsa = sa
                            bsb = sb
                            for c in range(3):
                                bx[2 + c] = alt[2 + c]
                                bx[5 + c] = alt[7 + c]
                            bx[8] = alt[0]
                            bx[9] = alt[1]
                            bx[10] = alt[5]
                            bx[11] = alt[6]
            if lb >= upper - tol:
                pruned += 1
                pruned_min = min(pruned_min, lb)
                continue
        # split the larger node
        sz_a = nf[a, F_SIZE]
        sz_b = nf[b, F_SIZE]
        if sz_a <= min_size and sz_b <= min_size:
            final_min = min(final_min, lb)
            continue
        k = a if sz_a >= sz_b else b
        other = b if k == a else a
        if ni[k, I_C0] < 0:
            # create the two children of k
            p = ni[k, I_P]
            q = ni[k, I_Q]
            m = (p + 1) * (q + 1) * 4
            dirn = _split_dir(ctrl, ni[k, I_OFF], p, q)
            if nsep > 0 and ph[k, 2 * NSEP] >= 0.0:
                dirn = np.int64(ph[k, 2 * NSEP])  # the separators ask for this one
            _split_into(ctrl, ni[k, I_OFF], p, q, dirn, ctrl_top, ctrl_top + m)
            s = ni[k, I_SURF]
            for h in range(2):
                c = n_nodes + h
                kids[h] = c
                ni[c, I_OFF] = ctrl_top + h * m
                ni[c, I_P] = p
                ni[c, I_Q] = q
                ni[c, I_SURF] = s
                ni[c, I_C0] = -1
                ni[c, I_C1] = -1
                ni[c, I_SIDE] = ni[k, I_SIDE]
                ni[c, I_DIR] = 0
                u0 = nf[k, F_U0]
                u1 = nf[k, F_U1]
                v0 = nf[k, F_V0]
                v1 = nf[k, F_V1]
                if dirn == 0:
                    um = 0.5 * (u0 + u1)
                    if h == 0:
                        u1 = um
                    else:
                        u0 = um
                else:
                    vm = 0.5 * (v0 + v1)
                    if h == 0:
                        v1 = vm
                    else:
                        v0 = vm
                nf[c, F_U0] = u0
                nf[c, F_U1] = u1
                nf[c, F_V0] = v0
                nf[c, F_V1] = v1
                _node_box(ctrl, ni[c, I_OFF], p, q, nf, c)
                st = ni[k, I_STATE]
                if seg_all is None:
                    pass
                elif st == ST_MIXED:
                    st = _box_trim_state(segb, seg_deg, seg_loop, seg_box, trim_meta, s,
                                         u0, u1, v0, v1, uv_tol, winding, stack, depths,
                                         tleft, tright)
                ni[c, I_STATE] = st
                _patch_eval(ctrl, ni[c, I_OFF], p, q, 0.5, 0.5, tmp, nf[c, F_REP:F_REP + 3])
                nf[c, F_REPUV] = 0.5 * (u0 + u1)
                nf[c, F_REPUV + 1] = 0.5 * (v0 + v1)
                ok = st == ST_INSIDE
                if seg_all is None:
                    pass
                elif st == ST_MIXED:
                    ok = _uv_inside(segb, seg_deg, seg_loop, trim_meta, s,
                                    nf[c, F_REPUV], nf[c, F_REPUV + 1], uv_tol, winding,
                                    stack, depths, tleft, tright)
                ni[c, I_REPOK] = 1 if ok else 0
                if nsep > 0:
                    sep_bounds(ctrl, ni[c, I_OFF], p, q, sep, nsep, bin_, Zs, Rs, ph, c)
            ni[k, I_C0] = kids[0]
            ni[k, I_C1] = kids[1]
            ni[k, I_DIR] = dirn
            n_nodes += 2
            ctrl_top += 2 * m
        splits += 1
        for h in range(2):
            c = ni[k, I_C0 + h]
            if ni[c, I_STATE] == ST_OUTSIDE:
                continue
            ca = c if k == a else other
            cb = other if k == a else c
            lb2 = max(pair_lower_bound(ctrl, ni, nf, ca, cb),
                      sep_lower_bound(ph, nsep, ca, cb))
            if lb2 < lb:
                lb2 = lb  # the parent's bound holds for the child too
            if lb2 >= upper - tol:
                pruned += 1
                pruned_min = min(pruned_min, lb2)
                continue
            hlb, hab, nh = _heap_push(hlb, hab, nh, lb2, (ca << 32) | cb)
            pushed += 1
        peak = max(peak, nh)
    lower = upper
    if nh > 0:
        lower = min(lower, hlb[0])
    lower = min(lower, pruned_min, final_min)
    if lower < 0.0:
        lower = 0.0
    out_f[0] = upper
    out_f[1] = lower
    for c in range(2, 12):
        out_f[c] = bx[c]
    out_i[0] = bsa
    out_i[1] = bsb
    out_i[2] = popped
    out_i[3] = splits
    out_i[4] = pushed
    out_i[5] = n_nodes
    out_i[6] = newton_runs
    out_i[7] = stop
    out_i[8] = peak
    out_i[9] = pruned
    return True
