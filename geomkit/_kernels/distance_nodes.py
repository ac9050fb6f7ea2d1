"""Surface–surface distance kernels, part 1: sub-patch nodes (layout constants, growth
of the pools, patch evaluation / boxes / splitting, trim states) and the certified
pair lower bound.  See :mod:`geomkit._kernels.distance` for the data layout and the
certificate."""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.borrow import borrow_all, borrow_opt
from .numba_ext.policy import jit_plain as jit, jit_inline
from .trim import INSIDE, MAX_DEPTH, OUTSIDE, classify_point

NI = 10
NF = 16
# ni columns
I_OFF, I_P, I_Q, I_SURF, I_C0, I_C1, I_STATE, I_REPOK, I_SIDE, I_DIR = range(10)
# nf columns
F_U0, F_U1, F_V0, F_V1 = 0, 1, 2, 3
F_BOX = 4
F_REP = 10
F_REPUV = 13
F_SIZE = 15
# node trim states
ST_INSIDE = 1
ST_MIXED = 2
ST_OUTSIDE = 0



# --------------------------------------------------------------------------- growth
@jit_inline
def _grow2(a, need):
    n = a.shape[0]
    if need <= n:
        return a
    m = max(need, 2 * n)
    b = np.empty((m, a.shape[1]), dtype=a.dtype)
    for i in range(n):
        for j in range(a.shape[1]):
            b[i, j] = a[i, j]
    return b


@jit_inline
def _grow1(a, need):
    n = a.shape[0]
    if need <= n:
        return a
    m = max(need, 2 * n)
    b = np.empty(m, dtype=a.dtype)
    for i in range(n):
        b[i] = a[i]
    return b


@jit_inline
def _max_loops(trim_meta):
    """``max(1, trim_meta[:, 2].max())`` without numpy's max (slow to compile)."""
    m = 1
    for s in range(trim_meta.shape[0]):
        m = max(m, trim_meta[s, 2])
    return m


# --------------------------------------------------------------------------- patches
@jit
def _patch_eval(ctrl, off, p, q, s, t, tmp, out):
    """Point of the rational Bézier patch at local (s, t) in [0, 1]^2 (de Casteljau)."""
    # rows: for each i, de Casteljau in v
    for i in range(p + 1):
        base = off + i * (q + 1) * 4
        for j in range(q + 1):
            for c in range(4):
                tmp[j, c] = ctrl[base + j * 4 + c]
        for r in range(1, q + 1):
            for j in range(q + 1 - r):
                for c in range(4):
                    tmp[j, c] = (1.0 - t) * tmp[j, c] + t * tmp[j + 1, c]
        for c in range(4):
            tmp[q + 1 + i, c] = tmp[0, c]
    # column of row results at tmp[q+1 : q+2+p]
    b = q + 1
    for r in range(1, p + 1):
        for i in range(p + 1 - r):
            for c in range(4):
                tmp[b + i, c] = (1.0 - s) * tmp[b + i, c] + s * tmp[b + i + 1, c]
    w = tmp[b, 3]
    out[0] = tmp[b, 0] / w
    out[1] = tmp[b, 1] / w
    out[2] = tmp[b, 2] / w


@jit
def _node_box(ctrl, off, p, q, nf, k):
    lo0 = lo1 = lo2 = np.inf
    hi0 = hi1 = hi2 = -np.inf
    for i in range((p + 1) * (q + 1)):
        b = off + 4 * i
        w = ctrl[b + 3]
        x = ctrl[b] / w
        y = ctrl[b + 1] / w
        z = ctrl[b + 2] / w
        lo0 = min(lo0, x)
        lo1 = min(lo1, y)
        lo2 = min(lo2, z)
        hi0 = max(hi0, x)
        hi1 = max(hi1, y)
        hi2 = max(hi2, z)
    nf[k, F_BOX] = lo0
    nf[k, F_BOX + 1] = lo1
    nf[k, F_BOX + 2] = lo2
    nf[k, F_BOX + 3] = hi0
    nf[k, F_BOX + 4] = hi1
    nf[k, F_BOX + 5] = hi2
    nf[k, F_SIZE] = math.sqrt((hi0 - lo0) ** 2 + (hi1 - lo1) ** 2 + (hi2 - lo2) ** 2)


@jit
def _split_dir(ctrl, off, p, q):
    """0: split in u (the net is longer along u), 1: in v."""
    lu = 0.0
    lv = 0.0
    for i in range(p + 1):
        for j in range(q + 1):
            b = off + (i * (q + 1) + j) * 4
            wa = ctrl[b + 3]
            if i < p:
                b2 = b + (q + 1) * 4
                wb = ctrl[b2 + 3]
                d = 0.0
                for c in range(3):
                    e = ctrl[b2 + c] / wb - ctrl[b + c] / wa
                    d += e * e
                lu = max(lu, d)
            if j < q:
                b2 = b + 4
                wb = ctrl[b2 + 3]
                d = 0.0
                for c in range(3):
                    e = ctrl[b2 + c] / wb - ctrl[b + c] / wa
                    d += e * e
                lv = max(lv, d)
    lu *= p * p
    lv *= q * q
    return 0 if lu >= lv else 1


@jit
def _split_into(ctrl, off, p, q, d, offL, offR):
    """de Casteljau at 1/2 along u (d = 0) or v (d = 1) of the net at ``off``; the two
    halves are written at ``offL`` and ``offR``."""
    if d == 0:
        n = p
        ncurves = q + 1
        stride = (q + 1) * 4  # step between curve points
        cstep = 4             # step between curves
    else:
        n = q
        ncurves = p + 1
        stride = 4
        cstep = (q + 1) * 4
    for cv in range(ncurves):
        base = cv * cstep
        for c in range(4):
            # copy curve into right, then reduce
            for i in range(n + 1):
                ctrl[offR + base + i * stride + c] = ctrl[off + base + i * stride + c]
            ctrl[offL + base + c] = ctrl[off + base + c]
            for r in range(1, n + 1):
                for i in range(n - r + 1):
                    a = offR + base + i * stride + c
                    ctrl[a] = 0.5 * (ctrl[a] + ctrl[a + stride])
                ctrl[offL + base + r * stride + c] = ctrl[offR + base + c]


# --------------------------------------------------------------------------- trims
@jit
def _box_trim_state(seg_all, seg_deg, seg_loop, seg_box, trim_meta, s, u0, u1, v0, v1,
                    tol, winding, stack, depths, left, right):
    """INSIDE / OUTSIDE if the UV box is entirely inside / outside the trimmed face,
    MIXED if a trim segment's control box meets it (conservative)."""
    first = trim_meta[s, 0]
    cnt = trim_meta[s, 1]
    if cnt == 0:
        return ST_INSIDE
    for k in range(trim_meta[s, 3], trim_meta[s, 3] + trim_meta[s, 4]):
        if (seg_box[k, 0] <= u1 + tol and seg_box[k, 1] >= u0 - tol
                and seg_box[k, 2] <= v1 + tol and seg_box[k, 3] >= v0 - tol):
            return ST_MIXED
    c = classify_point(seg_all[first:first + cnt], seg_deg[first:first + cnt],
                       seg_loop[first:first + cnt], trim_meta[s, 2], 0.5 * (u0 + u1),
                       0.5 * (v0 + v1), tol, winding, stack, depths, left, right)
    if c == INSIDE:
        return ST_INSIDE
    if c == OUTSIDE:
        return ST_OUTSIDE
    return ST_MIXED


@jit_inline
def _uv_inside(seg_all, seg_deg, seg_loop, trim_meta, s, u, v, tol, winding, stack,
               depths, left, right):
    first = trim_meta[s, 0]
    cnt = trim_meta[s, 1]
    if cnt == 0:
        return True
    c = classify_point(seg_all[first:first + cnt], seg_deg[first:first + cnt],
                       seg_loop[first:first + cnt], trim_meta[s, 2], u, v, tol, winding,
                       stack, depths, left, right)
    return c == INSIDE


# --------------------------------------------------------------------------- bounds
@jit_inline
def _slab(ctrl, offa, na, offb, nb, d0, d1, d2):
    hi = -np.inf
    for i in range(na):
        b = offa + 4 * i
        w = ctrl[b + 3]
        x = (ctrl[b] * d0 + ctrl[b + 1] * d1 + ctrl[b + 2] * d2) / w
        hi = max(hi, x)
    lo = np.inf
    for i in range(nb):
        b = offb + 4 * i
        w = ctrl[b + 3]
        x = (ctrl[b] * d0 + ctrl[b + 1] * d1 + ctrl[b + 2] * d2) / w
        lo = min(lo, x)
    return lo - hi


@jit
def pair_lower_bound(ctrl, ni, nf, a, b):
    """Certified lower bound of the distance between nodes a and b (hull property)."""
    g = 0.0
    for c in range(3):
        e = max(nf[a, F_BOX + c] - nf[b, F_BOX + 3 + c], nf[b, F_BOX + c] - nf[a, F_BOX + 3 + c])
        if e > 0.0:
            g += e * e
    lb = math.sqrt(g)
    na = (ni[a, I_P] + 1) * (ni[a, I_Q] + 1)
    nb = (ni[b, I_P] + 1) * (ni[b, I_Q] + 1)
    for kind in range(2):
        if kind == 0:
            d0 = 0.5 * (nf[b, F_BOX] + nf[b, F_BOX + 3] - nf[a, F_BOX] - nf[a, F_BOX + 3])
            d1 = 0.5 * (nf[b, F_BOX + 1] + nf[b, F_BOX + 4] - nf[a, F_BOX + 1] - nf[a, F_BOX + 4])
            d2 = 0.5 * (nf[b, F_BOX + 2] + nf[b, F_BOX + 5] - nf[a, F_BOX + 2] - nf[a, F_BOX + 5])
        else:
            d0 = nf[b, F_REP] - nf[a, F_REP]
            d1 = nf[b, F_REP + 1] - nf[a, F_REP + 1]
            d2 = nf[b, F_REP + 2] - nf[a, F_REP + 2]
        L = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        if L <= 0.0 or not np.isfinite(L):
            continue
        s = _slab(ctrl, ni[a, I_OFF], na, ni[b, I_OFF], nb, d0 / L, d1 / L, d2 / L)
        if s > lb:
            lb = s
    return lb


@jit
def init_nodes(ctrl, ni, nf, n, seg_all, seg_deg, seg_loop, seg_box, trim_meta, uv_tol):
    """Fill boxes, trim states and representative points of the root nodes ``0..n-1``
    (offset, degrees, surface and UV box already set).  ``seg_all`` None: no face is
    trimmed (the trim classification is then not compiled)."""
    pmax1 = np.int64(1)
    if seg_all is not None:
        pmax1 = seg_all.shape[1]
    winding = np.zeros(_max_loops(trim_meta), dtype=np.int64)
    stack = np.empty((MAX_DEPTH + 2, pmax1, 3))
    depths = np.empty(MAX_DEPTH + 2, dtype=np.int64)
    tleft = np.empty((pmax1, 3))
    tright = np.empty((pmax1, 3))
    _init_nodes_loop(ctrl, ni, nf, n, seg_all, (seg_deg, seg_loop, seg_box, trim_meta), uv_tol,
                     (winding, stack, depths, tleft, tright))


@jit
def _init_nodes_loop(ctrl, ni, nf, n, seg_all, trims, uv_tol, tscr):
    """The loop of :func:`init_nodes` over borrowed views of its arrays and the
    caller's scratch (no atomic reference counting, :mod:`.numba_ext.borrow`; ``seg_all`` is
    read through ``segb``, see :func:`~geomkit._kernels.numba_ext.borrow.borrow_opt`)."""
    ctrl, ni, nf = borrow_all((ctrl, ni, nf))
    segb = borrow_opt(seg_all)
    seg_deg, seg_loop, seg_box, trim_meta = borrow_all(trims)
    winding, stack, depths, tleft, tright = borrow_all(tscr)
    for k in range(n):
        p = ni[k, I_P]
        q = ni[k, I_Q]
        tmp = np.empty((p + q + 3, 4))
        _node_box(ctrl, ni[k, I_OFF], p, q, nf, k)
        s = ni[k, I_SURF]
        u0 = nf[k, F_U0]
        u1 = nf[k, F_U1]
        v0 = nf[k, F_V0]
        v1 = nf[k, F_V1]
        st = ST_INSIDE
        if seg_all is not None:
            st = _box_trim_state(segb, seg_deg, seg_loop, seg_box, trim_meta, s, u0, u1,
                                 v0, v1, uv_tol, winding, stack, depths, tleft, tright)
        ni[k, I_STATE] = st
        ni[k, I_C0] = -1
        ni[k, I_C1] = -1
        _patch_eval(ctrl, ni[k, I_OFF], p, q, 0.5, 0.5, tmp, nf[k, F_REP:F_REP + 3])
        nf[k, F_REPUV] = 0.5 * (u0 + u1)
        nf[k, F_REPUV + 1] = 0.5 * (v0 + v1)
        ok = st == ST_INSIDE
        if seg_all is None:
            pass
        elif st == ST_MIXED:
            ok = _uv_inside(segb, seg_deg, seg_loop, trim_meta, s, nf[k, F_REPUV],
                            nf[k, F_REPUV + 1], uv_tol, winding, stack, depths, tleft, tright)
        ni[k, I_REPOK] = 1 if ok else 0
