"""Nearest triangle of mesh B for each triangle of mesh A over a voxel grid (Paper 1,
step 4), with the exact stop rule; grid layout as in :mod:`geomkit._kernels.voxel`."""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit, prun
from .triangles import triangle_triangle_distance
from .voxel import (_decode, _heap_grow, _heap_pop, _push_children, _seed_heap,
                    _top_cells, _tri_aabb)

CHUNK = 64


@jit
def _load_tri(V, F, t, T):
    for r in range(3):
        for c in range(3):
            T[r, c] = V[F[t, r], c]


@jit
def _test_voxel(lin, start, tris, VB, FB, TA, TB, stamp, qid, best, bt, pa, pb, qa, qb):
    for e in range(start[lin], start[lin + 1]):
        t = tris[e]
        if stamp[t] == qid:
            continue
        stamp[t] = qid
        _load_tri(VB, FB, t, TB)
        d = triangle_triangle_distance(TA, TB, qa, qb)
        if d < best:
            best = d
            bt = t
            for c in range(3):
                pa[c] = qa[c]
                pb[c] = qb[c]
    return best, bt


@jit
def _best_first_range(ia, ib, VA, FA, VB, FB, origin, h, lvl_dims, lvl_off, occ, start,
                      tris, out_d, out_t, out_pa, out_pb, visits):
    if ia < ib:
        _best_first_loop(ia, ib, VA, FA, VB, FB, origin, h, lvl_dims, lvl_off, occ, start,
                         tris, out_d, out_t, out_pa, out_pb, visits,
                         np.full(FB.shape[0], -1, dtype=np.int64),
                         (np.empty(256), np.empty(256, dtype=np.int64)),
                         (np.empty((3, 3)), np.empty((3, 3)), np.empty(3), np.empty(3),
                          np.empty(3), np.empty(3), np.empty(3), np.empty(3)))


@jit
def _best_first_loop(ia, ib, VA, FA, VB, FB, origin, h, lvl_dims, lvl_off, occ, start,
                     tris, out_d, out_t, out_pa, out_pb, visits, stamp, heap, work):
    """The loop of :func:`_best_first_range` over borrowed views (no atomic reference
    counting, :mod:`.numba_ext.borrow`; the scratch is owned by the caller)."""
    (VA, FA, VB, FB, origin, lvl_dims, lvl_off, occ, start, tris, out_d, out_t, out_pa,
     out_pb, visits, stamp, heap, work) = borrow_all((
        VA, FA, VB, FB, origin, lvl_dims, lvl_off, occ, start, tris, out_d, out_t, out_pa,
        out_pb, visits, stamp, heap, work))
    hk, hv = heap
    TA, TB, qlo, qhi, pa, pb, qa, qb = work
    for i in range(ia, ib):
        _load_tri(VA, FA, i, TA)
        _tri_aabb(VA, FA, i, qlo, qhi)
        if hk.shape[0] < _top_cells(lvl_dims) + 8:
            hk, hv = _heap_grow(hk, hv, 0, _top_cells(lvl_dims) + 8)
        n = _seed_heap(lvl_dims, lvl_off, occ, origin, h, qlo[0], qlo[1], qlo[2], qhi[0],
                       qhi[1], qhi[2], hk, hv)
        best = np.inf
        bt = -1
        cnt = 0
        while n > 0:
            key = hk[0]
            val = hv[0]
            if key >= best * best:
                break
            n = _heap_pop(hk, hv, n)
            cnt += 1
            lev, a, b, c = _decode(val)
            if lev > 0:
                if n + 8 > hk.shape[0]:
                    hk, hv = _heap_grow(hk, hv, n, n + 8)
                n = _push_children(val, lvl_dims, lvl_off, occ, origin, h, qlo[0],
                                   qlo[1], qlo[2], qhi[0], qhi[1], qhi[2], hk, hv, n,
                                   best * best)
            else:
                lin = (a * lvl_dims[0, 1] + b) * lvl_dims[0, 2] + c
                best, bt = _test_voxel(lin, start, tris, VB, FB, TA, TB, stamp, i,
                                       best, bt, pa, pb, qa, qb)
        out_d[i] = best
        out_t[i] = bt
        visits[i] = cnt
        for c in range(3):
            out_pa[i, c] = pa[c]
            out_pb[i, c] = pb[c]


@jit
def _shell_bound(origin, h, dims, blo, bhi, qlo, qhi):
    """Lower bound of the distance from the box [qlo, qhi] to any triangle lying
    entirely outside the voxel block [blo, bhi] (inclusive indices); inf when the block
    covers the whole grid."""
    lb = np.inf
    for d in range(3):
        if blo[d] > 0:
            lb = min(lb, qlo[d] - (origin[d] + blo[d] * h))
        if bhi[d] < dims[d] - 1:
            lb = min(lb, origin[d] + (bhi[d] + 1) * h - qhi[d])
    return max(0.0, lb)


@jit
def _shells_range(ia, ib, VA, FA, VB, FB, origin, h, dims, start, tris, first_hit,
                  out_d, out_t, out_pa, out_pb, visits):
    ny = dims[1]
    nz = dims[2]
    if ia < ib:
        stamp = np.full(FB.shape[0], -1, dtype=np.int64)
        TA = np.empty((3, 3))
        TB = np.empty((3, 3))
        qlo = np.empty(3)
        qhi = np.empty(3)
        pa = np.empty(3)
        pb = np.empty(3)
        qa = np.empty(3)
        qb = np.empty(3)
        r0lo = np.empty(3, dtype=np.int64)
        r0hi = np.empty(3, dtype=np.int64)
        blo = np.empty(3, dtype=np.int64)
        bhi = np.empty(3, dtype=np.int64)
        for i in range(ia, ib):
            _load_tri(VA, FA, i, TA)
            _tri_aabb(VA, FA, i, qlo, qhi)
            for d in range(3):
                r0lo[d] = int(math.floor((qlo[d] - origin[d]) / h))
                r0hi[d] = int(math.floor((qhi[d] - origin[d]) / h))
            best = np.inf
            bt = -1
            cnt = 0
            k = 0
            while True:
                # shell k: block R0 grown by k, minus the block grown by k - 1
                for d in range(3):
                    blo[d] = r0lo[d] - k
                    bhi[d] = r0hi[d] + k
                i0 = max(0, blo[0])
                i1 = min(dims[0] - 1, bhi[0])
                j0 = max(0, blo[1])
                j1 = min(dims[1] - 1, bhi[1])
                k0 = max(0, blo[2])
                k1 = min(dims[2] - 1, bhi[2])
                for a in range(i0, i1 + 1):
                    ina = k > 0 and blo[0] < a < bhi[0]
                    for b in range(j0, j1 + 1):
                        inb = k > 0 and blo[1] < b < bhi[1]
                        if ina and inb:
                            # interior column: only the two end voxels are new
                            for c in (blo[2], bhi[2]):
                                if 0 <= c < dims[2]:
                                    cnt += 1
                                    best, bt = _test_voxel((a * ny + b) * nz + c, start,
                                                           tris, VB, FB, TA, TB, stamp, i,
                                                           best, bt, pa, pb, qa, qb)
                        else:
                            for c in range(k0, k1 + 1):
                                cnt += 1
                                best, bt = _test_voxel((a * ny + b) * nz + c, start, tris,
                                                       VB, FB, TA, TB, stamp, i, best, bt,
                                                       pa, pb, qa, qb)
                lb = _shell_bound(origin, h, dims, blo, bhi, qlo, qhi)
                if first_hit and bt >= 0:
                    break
                if lb >= best or lb == np.inf:
                    break
                k += 1
            out_d[i] = best
            out_t[i] = bt
            visits[i] = cnt
            for c in range(3):
                out_pa[i, c] = pa[c]
                out_pb[i, c] = pb[c]


def nearest_tris_best_first(VA, FA, VB, FB, origin, h, lvl_dims, lvl_off, occ, start, tris,
                            out_d, out_t, out_pa, out_pb, visits):
    """Best-first over the occupancy pyramid; a cell is opened only while the gap
    between its box and the query triangle's box is below the best distance.
    Parallel over the triangles of A (:func:`prun`: serial workers on threads, one
    compile instead of numba's parallel call tree)."""
    prun(_best_first_range, FA.shape[0], CHUNK, VA, FA, VB, FB, origin, h, lvl_dims,
         lvl_off, occ, start, tris, out_d, out_t, out_pa, out_pb, visits)


def nearest_tris_shells(VA, FA, VB, FB, origin, h, dims, start, tris, first_hit,
                        out_d, out_t, out_pa, out_pb, visits):
    """Paper 1's growing box: shell k is the block of voxels around the query
    triangle's box grown by k layers.  With ``first_hit`` the search stops at the first
    shell that holds a triangle (the paper's rule); otherwise it continues until the
    block's guaranteed lower bound reaches the best distance (exact).  Parallel as
    :func:`nearest_tris_best_first`."""
    prun(_shells_range, FA.shape[0], CHUNK, VA, FA, VB, FB, origin, h, dims, start, tris,
         bool(first_hit), out_d, out_t, out_pa, out_pb, visits)
