"""Packed box trees (OBB / AABB): one record per node, the collision traversal
(single calls and batches) and the single-call kernel (Paper 3).

Node record ``N`` (n, 16) float64: centre (0:3), axes row-major (3:12,
``R[r, c] = N[3 + 3 r + c]``, axes as columns), half extents (12:15) and the link
(15): for an inner node its first child ``c`` (children ``c`` and ``c + 1``, as
:func:`geomkit._kernels.bvh.build_tree` numbers them), for a leaf ``-1 - (lo +
hi * LEAF_CODE)`` with its triangles ``lo:hi`` in tree order.  A node test thus
reads one 128-byte record (two cache lines) per node and nothing else: the node
tests of a query jump across trees of several MB, so memory latency, not
arithmetic, is most of their cost.  Built by :func:`pack_boxes`.

Single call (:func:`collide_packed`): numba unboxes every array argument (~0.1 µs
each: it allocates a meminfo per array) and a query whose root boxes are disjoint
is ~1 µs of kernel work, so each body is one buffer (``B`` float64 with ``Bi =
B.view(int64)``: a 16-slot header record with ``Bi[0] = n``, ``Bi[1] = m``, then
``N`` at ``B[16:16 + 16 n]``, ``T`` (m, 3, 3) triangle corners in tree order, then as
int64 ``order`` (m,) and ``face_tags`` (m,); the body's ``N``, ``T``, ``order``,
``face_tags`` are views into it; the header is one record long so that the node
records keep their offsets modulo 128 bytes, and it sits next to the root record:
a root-only query reads the start of each buffer and nothing else).  The kernel
takes its six arguments as the caller's Python objects, unconverted
(:mod:`geomkit._kernels.numba_ext.pyobj`: numba's conversion of two arrays and four
addresses was most of a root-only call): the two bodies' buffers (read-only
float64 arrays, their length checked against their header), the two poses (an exact
float64 2-D ``ndarray`` of any layout is read through NumPy's array struct by
:func:`_pose_from_object`; any other object is left to the caller, which converts
it and writes it into ``W``), ``first_only`` and the thread's scratch; allocates nothing,
answers a pose whose root boxes are disjoint without the traversal's call, and
returns one integer.  Its scratch ``W`` int64 (one per thread,
:func:`posed_scratch_size`): the answer ``(n_pairs, bv_tests)``, the seed pair,
``W``'s own length, the addresses of ``numpy.ndarray`` and of the float64 dtype,
six (3, 3) float slabs (relative motion, pose tolerance set by the caller, SAT
scratch), the two poses (4, 4), the moved leaf triangles, the node stack, then
``cap`` pairs and ``cap`` tag pairs (``POSED_*`` below: what a root-only query
touches comes first).  Its compiled entry keeps the GIL for the pose checks, the
root test and the first ``GIL_AFTER`` node tests, and the traversal releases it for
the rest (:func:`_release_gil`).

The batch worker (:func:`collide_many_boxes`) reads the same buffers by address, and
both kernels view every array they traverse through addresses: a view of an array
without a meminfo costs no reference counting in the loops.
"""

from __future__ import annotations

import numpy as np

from llvmlite import ir
from numba import carray
from numba.core import cgutils, types
from numba.extending import intrinsic

from .numba_ext.policy import jit, jit_holding_gil, jit_inline
from .numba_ext.pyobj import (DATA, DIMS, NPY_DOUBLE, OB_TYPE, address, array_data, f64_load, f64_ptr,
                     i64_ptr)
from .bvh import rigid_code
from .bvh_query import LEAF_BUF, SAT_EPS, STACK
from .triangles import _intersect_point

LEAF_CODE = 1 << 26
"""Leaf links: ``lo + hi * LEAF_CODE`` (exact in float64 up to 2**26 triangles)."""
MAX_TRIANGLES = LEAF_CODE - 1
POSED_ANSWER = 0
"""Index in the single-call scratch ``W`` of ``n_pairs`` (``bv_tests`` follows, then
the seed pair and the length of ``W``).  ``W`` is laid out so that a query whose root
boxes are disjoint reads and writes only its first ~100 slots."""
POSED_LENGTH = POSED_ANSWER + 4
POSED_REFS = POSED_ANSWER + 5
"""Index in ``W`` of the addresses of ``numpy.ndarray``, of the float64 dtype, of
``True`` and of ``None`` (set by the caller; :func:`collide_packed`)."""
POSED_FLOATS = 10
"""Index in ``W`` of six (3, 3) float64 slabs: the relative rotation, the relative
translation (row 0) with the pose tolerance at ``[2, 2]`` (set by the caller), and
four of SAT scratch."""
POSED_TOL = POSED_FLOATS + 17
POSED_POSES = POSED_FLOATS + 54
"""Index in ``W`` of the two poses (4, 4) float64 the kernel works on (copied from
the callers' arrays, or written there by the caller)."""
POSED_LEAF = POSED_POSES + 32
"""Index in ``W`` of ``LEAF_BUF`` (3, 3) float64 slabs: a leaf's moved triangles."""
POSED_STACK = POSED_LEAF + 9 * LEAF_BUF
"""Index in ``W`` of the node stack (``STACK`` rows of 2)."""
POSED_FIXED = POSED_STACK + 2 * STACK
"""Index in ``W`` of the pairs (``cap`` rows of 2, then ``cap`` tag rows of 2)."""


GIL_AFTER = 64
"""Node tests a single call makes holding the GIL before it releases it (~2-4 µs;
releasing and taking it back costs ~0.1 µs, a tenth of a short query)."""

HEADER = 16
"""Slots (float64) of a packed body buffer before its node records."""


def packed_size(n, m):
    """Length (float64) of the packed buffer of a box tree of ``n`` nodes and ``m``
    triangles."""
    return HEADER + 16 * n + 11 * m


def posed_scratch_size(cap):
    """Length of the scratch ``W`` of :func:`collide_packed` for ``cap`` pairs."""
    return POSED_FIXED + 4 * cap


@jit
def pack_boxes(child, rng, C, R, E):
    """The node records ``N`` (n, 16) of a box tree (see the module docstring)."""
    n = child.shape[0]
    N = np.empty((n, 16))
    for i in range(n):
        for k in range(3):
            N[i, k] = C[i, k]
            N[i, 12 + k] = E[i, k]
            for c in range(3):
                N[i, 3 + 3 * k + c] = R[i, k, c]
        if child[i, 0] >= 0:
            N[i, 15] = child[i, 0]
        else:
            N[i, 15] = -1.0 - (rng[i, 0] + rng[i, 1] * LEAF_CODE)
    return N


@jit_inline
def _leaf_range(N, i):
    """Triangle range ``(lo, hi)`` of leaf ``i``."""
    k = np.int64(-N[i, 15]) - 1
    return k % LEAF_CODE, k // LEAF_CODE


@jit_inline
def _extent(N, i):
    return max(N[i, 12], N[i, 13], N[i, 14])


@jit_inline
def _boxes_disjoint(NA, i, NB, j, Rr, tr, Rab, T, M, Ab):
    """``box_separation(...) > 0`` with ``early`` for packed nodes (same arithmetic as
    ``_rel_box`` + ``box_separation`` of :mod:`geomkit._kernels.bvh_query`): B-node ``j`` carried
    into A-node ``i``'s axes by the relative motion ``(Rr, tr)``."""
    for r in range(3):
        for c in range(3):
            M[r, c] = Rr[r, 0] * NB[j, 3 + c] + Rr[r, 1] * NB[j, 6 + c] + \
                Rr[r, 2] * NB[j, 9 + c]
    d0 = Rr[0, 0] * NB[j, 0] + Rr[0, 1] * NB[j, 1] + Rr[0, 2] * NB[j, 2] + tr[0] - NA[i, 0]
    d1 = Rr[1, 0] * NB[j, 0] + Rr[1, 1] * NB[j, 1] + Rr[1, 2] * NB[j, 2] + tr[1] - NA[i, 1]
    d2 = Rr[2, 0] * NB[j, 0] + Rr[2, 1] * NB[j, 1] + Rr[2, 2] * NB[j, 2] + tr[2] - NA[i, 2]
    for r in range(3):
        T[r] = NA[i, 3 + r] * d0 + NA[i, 6 + r] * d1 + NA[i, 9 + r] * d2
        for c in range(3):
            Rab[r, c] = NA[i, 3 + r] * M[0, c] + NA[i, 6 + r] * M[1, c] + \
                NA[i, 9 + r] * M[2, c]
            Ab[r, c] = abs(Rab[r, c]) + SAT_EPS
    a0 = NA[i, 12]
    a1 = NA[i, 13]
    a2 = NA[i, 14]
    b0 = NB[j, 12]
    b1 = NB[j, 13]
    b2 = NB[j, 14]
    for k in range(3):   # A's face normals
        ak = a0 if k == 0 else (a1 if k == 1 else a2)
        if abs(T[k]) - ak - (b0 * Ab[k, 0] + b1 * Ab[k, 1] + b2 * Ab[k, 2]) > 0.0:
            return True
    for k in range(3):   # B's face normals
        bk = b0 if k == 0 else (b1 if k == 1 else b2)
        if abs(T[0] * Rab[0, k] + T[1] * Rab[1, k] + T[2] * Rab[2, k]) - bk - \
                (a0 * Ab[0, k] + a1 * Ab[1, k] + a2 * Ab[2, k]) > 0.0:
            return True
    for p in range(3):   # A_p x B_q
        p1 = (p + 1) % 3
        p2 = (p + 2) % 3
        for q in range(3):
            q1 = (q + 1) % 3
            q2 = (q + 2) % 3
            ra = NA[i, 12 + p1] * Ab[p2, q] + NA[i, 12 + p2] * Ab[p1, q]
            rb = NB[j, 12 + q1] * Ab[p, q2] + NB[j, 12 + q2] * Ab[p, q1]
            if abs(T[p2] * Rab[p1, q] - T[p1] * Rab[p2, q]) - ra - rb > 0.0:
                return True
    return False


@jit_inline
def _leaf_pair(NA, TA, orderA, NB, TB, orderB, i, j, Rr, tr, first_only, out_pairs,
               npairs, tbs, M, hit):
    """Triangle tests of the leaf pair ``(i, j)`` (B's triangles moved by ``(Rr,
    tr)``, at most ``LEAF_BUF`` of them: ``leaf_size`` is checked); returns the new
    pair count (one more than ``npairs`` at most with ``first_only``)."""
    cap = out_pairs.shape[0]
    ra0, ra1 = _leaf_range(NA, i)
    rb0, rb1 = _leaf_range(NB, j)
    for rb in range(rb1 - rb0):   # B's leaf triangles moved once per leaf pair
        for v in range(3):
            x, y, z = TB[rb0 + rb, v, 0], TB[rb0 + rb, v, 1], TB[rb0 + rb, v, 2]
            for k in range(3):
                tbs[rb, v, k] = Rr[k, 0] * x + Rr[k, 1] * y + Rr[k, 2] * z + tr[k]
    for ra in range(ra0, ra1):
        # scalars and indices, no array views (a view of an array with a meminfo
        # costs reference counting) until the exact test's call
        x0 = min(TA[ra, 0, 0], TA[ra, 1, 0], TA[ra, 2, 0])
        x1 = max(TA[ra, 0, 0], TA[ra, 1, 0], TA[ra, 2, 0])
        y0 = min(TA[ra, 0, 1], TA[ra, 1, 1], TA[ra, 2, 1])
        y1 = max(TA[ra, 0, 1], TA[ra, 1, 1], TA[ra, 2, 1])
        z0 = min(TA[ra, 0, 2], TA[ra, 1, 2], TA[ra, 2, 2])
        z1 = max(TA[ra, 0, 2], TA[ra, 1, 2], TA[ra, 2, 2])
        for rb in range(rb0, rb1):
            q = rb - rb0
            # the two triangles' bounding boxes (same coordinates as the exact test:
            # boxes apart means triangles apart, touching boxes go on)
            if min(tbs[q, 0, 0], tbs[q, 1, 0], tbs[q, 2, 0]) > x1 \
                    or max(tbs[q, 0, 0], tbs[q, 1, 0], tbs[q, 2, 0]) < x0 \
                    or min(tbs[q, 0, 1], tbs[q, 1, 1], tbs[q, 2, 1]) > y1 \
                    or max(tbs[q, 0, 1], tbs[q, 1, 1], tbs[q, 2, 1]) < y0 \
                    or min(tbs[q, 0, 2], tbs[q, 1, 2], tbs[q, 2, 2]) > z1 \
                    or max(tbs[q, 0, 2], tbs[q, 1, 2], tbs[q, 2, 2]) < z0:
                continue
            if _intersect_point(TA[ra], tbs[q], hit):
                if npairs < cap:
                    out_pairs[npairs, 0] = orderA[ra]
                    out_pairs[npairs, 1] = orderB[rb]
                npairs += 1
                if first_only:
                    return npairs
    return npairs


@jit
def collide_boxes(NA, TA, orderA, NB, TB, orderB, Rr, tr, first_only, out_pairs,
                  st, scr, tbs, seed, root_overlaps=False, gil_after=-1):
    """:func:`geomkit._kernels.bvh_query.collide_trees` for packed box trees in A's
    frame, B moved by ``(Rr, tr)``; scratch passed in (``st`` (STACK, 2) int64,
    ``scr`` (4, 3, 3), ``tbs`` (LEAF_BUF, 3, 3)) so that a batch allocates it once.
    Descends the node with the larger extent; with ``first_only`` the child whose
    centre is nearer the other node's centre first (fewer node tests before the
    first hit: 62-128 mean, 41-44 median on the bench's pairs, against 93-134 /
    64-107 in index order).

    ``seed`` (2,) int64, temporal coherence for ``first_only``: a leaf pair tested
    before the traversal (the pair that held the previous pose's first hit;
    ``seed[0] < 0`` for none); a hit there ends the query, else the traversal runs
    as without it (the seed pair's tests are counted in ``bv_tests``).  On return
    ``seed`` holds the leaf pair of the first hit found (unchanged if none).
    ``root_overlaps``: the caller has tested the root pair and found it overlapping
    (not tested again; still counted in ``bv_tests``).  ``gil_after`` >= 0: release
    the GIL, if this thread holds it, once that many node tests are made, and take it
    back before returning (a short traversal, the common case of a single call, does
    not pay the release; a long one does not block other Python threads).
    Returns ``(n_pairs, bv_tests)`` as ``collide_trees``.
    """
    Rab = scr[0]
    M = scr[1]
    Ab = scr[2]
    T = scr[3, 0]
    hit = scr[3, 1]
    npairs = 0
    tests = 0
    st[0, 0] = 0
    st[0, 1] = 0
    top = 1
    if first_only and seed[0] >= 0:   # the seed on top of the root: popped first
        st[1, 0] = seed[0]
        st[1, 1] = seed[1]
        top = 2
    gil = 0
    while top > 0:
        top -= 1
        i = st[top, 0]
        j = st[top, 1]
        if tests == gil_after:
            gil = _release_gil()
        tests += 1
        if not (root_overlaps and i == 0 and j == 0) and \
                _boxes_disjoint(NA, i, NB, j, Rr, tr, Rab, T, M, Ab):
            continue
        la = NA[i, 15] < 0.0
        lb = NB[j, 15] < 0.0
        if la and lb:
            n0 = npairs
            npairs = _leaf_pair(NA, TA, orderA, NB, TB, orderB, i, j, Rr, tr, first_only,
                                out_pairs, npairs, tbs, M, hit)
            if npairs > n0:
                if n0 == 0:
                    seed[0] = i
                    seed[1] = j
                if first_only:
                    break
            continue
        if lb or (not la and _extent(NA, i) >= _extent(NB, j)):
            c0 = np.int64(NA[i, 15])
            c1 = c0 + 1
            if first_only:
                if _dist2_moved(NB, j, Rr, tr, NA, c1) < _dist2_moved(NB, j, Rr, tr, NA, c0):
                    c0, c1 = c1, c0
            st[top, 0] = c1
            st[top, 1] = j
            st[top + 1, 0] = c0
            st[top + 1, 1] = j
        else:
            c0 = np.int64(NB[j, 15])
            c1 = c0 + 1
            if first_only:
                if _dist2_moved(NB, c1, Rr, tr, NA, i) < _dist2_moved(NB, c0, Rr, tr, NA, i):
                    c0, c1 = c1, c0
            st[top, 0] = i
            st[top, 1] = c1
            st[top + 1, 0] = i
            st[top + 1, 1] = c0
        top += 2
    _restore_gil(gil)
    return npairs, tests


@jit_inline
def _dist2_moved(NB, j, Rr, tr, NA, i):
    """Squared distance of B-node ``j``'s centre moved by ``(Rr, tr)`` to A-node
    ``i``'s centre."""
    s = 0.0
    for r in range(3):
        x = Rr[r, 0] * NB[j, 0] + Rr[r, 1] * NB[j, 1] + Rr[r, 2] * NB[j, 2] + tr[r] - NA[i, r]
        s += x * x
    return s


@jit_inline
def _relative(Pa, Pb, Rr, tr):
    """Relative motion ``Ra^T [Rb | tb - ta]`` of two (4, 4) poses (B into A's frame)."""
    for r in range(3):
        tr[r] = Pa[0, r] * (Pb[0, 3] - Pa[0, 3]) + Pa[1, r] * (Pb[1, 3] - Pa[1, 3]) + \
            Pa[2, r] * (Pb[2, 3] - Pa[2, 3])
        for c in range(3):
            Rr[r, c] = Pa[0, r] * Pb[0, c] + Pa[1, r] * Pb[1, c] + Pa[2, r] * Pb[2, c]


@jit
def collide_many_boxes(i0, i1, ba, bb, PA, PB, first_only, colliding, npairs, tests):
    """Serial worker (run by :func:`geomkit._kernels.numba_ext.policy.prun`): the packed bodies
    at the addresses ``ba``, ``bb`` (as :func:`collide_packed`; the caller keeps them
    alive) under the pose pairs ``k`` in ``[i0, i1)`` of ``PA``, ``PB`` ((n, 4, 4) or
    (1, 4, 4) float64 C-contiguous, broadcast; checked rigid by the caller): flags,
    pair counts, node tests.  The relative motion carries B into A's frame (no tree is
    touched per pose); with ``first_only`` the previous pose's hit is tried first
    (temporal coherence, :func:`collide_boxes`).

    Every array the traversal touches (trees, poses, scratch) is a view made from an
    address (``carray``, :func:`_views`): it has no meminfo, so the views the traversal takes of
    it (``TA[ra]``, ``scr[0]``, ...) cost no atomic reference counting.  With the
    body's own arrays (unboxed with a meminfo) and ``np.empty`` scratch a pose cost
    ~1.6x as much (sphere–torus, 1e-1 meshes: 5.1-5.4 against 3.2 µs)."""
    NA, TA, orderA = _views(ba)
    NB, TB, orderB = _views(bb)
    ma = PA.shape[0] > 1
    mb = PB.shape[0] > 1
    PAv = carray(f64_ptr(PA.ctypes.data), (PA.shape[0], 4, 4))
    PBv = carray(f64_ptr(PB.ctypes.data), (PB.shape[0], 4, 4))
    fs = np.empty(9 * (4 + LEAF_BUF + 1) + 3)      # scratch, kept alive to the end
    ist = np.empty(2 * STACK + 2, dtype=np.int64)
    S = carray(f64_ptr(fs.ctypes.data), 9 * (4 + LEAF_BUF + 1) + 3)
    scr = S[:36].reshape((4, 3, 3))
    tbs = S[36:36 + 9 * LEAF_BUF].reshape((LEAF_BUF, 3, 3))
    Rr = S[36 + 9 * LEAF_BUF:45 + 9 * LEAF_BUF].reshape((3, 3))
    tr = S[45 + 9 * LEAF_BUF:]
    I = carray(i64_ptr(ist.ctypes.data), 2 * STACK + 2)
    st = I[:2 * STACK].reshape((STACK, 2))
    seed = I[2 * STACK:]
    seed[0] = -1
    seed[1] = -1
    buf = I[:0].reshape((0, 2))
    for k in range(i0, i1):
        _relative(PAv[k if ma else 0], PBv[k if mb else 0], Rr, tr)
        c, t = collide_boxes(NA, TA, orderA, NB, TB, orderB, Rr, tr, first_only, buf, st,
                             scr, tbs, seed)
        colliding[k] = c > 0
        npairs[k] = c
        tests[k] = t
    return fs[0] + ist[0]       # the owners of S and I live until here


@intrinsic
def _release_gil(typingctx):
    """Release the GIL if this thread holds it (``PyEval_SaveThread``); returns the
    thread state for :func:`_restore_gil` (0: the GIL was not held, e.g. a call
    from another kernel)."""
    sig = types.int64()

    def codegen(context, builder, signature, args):
        i64 = ir.IntType(64)
        mod = builder.module
        check = cgutils.get_or_insert_function(mod, ir.FunctionType(ir.IntType(32), []),
                                               "PyGILState_Check")
        save = cgutils.get_or_insert_function(mod, ir.FunctionType(cgutils.voidptr_t, []),
                                              "PyEval_SaveThread")
        out = cgutils.alloca_once_value(builder, ir.Constant(i64, 0))
        held = builder.icmp_signed("!=", builder.call(check, []), ir.Constant(ir.IntType(32), 0))
        with builder.if_then(held):
            builder.store(builder.ptrtoint(builder.call(save, []), i64), out)
        return builder.load(out)
    return sig, codegen


@intrinsic
def _restore_gil(typingctx, state):
    """Take the GIL back (``PyEval_RestoreThread``) if :func:`_release_gil` released
    it (``state != 0``)."""
    sig = types.none(types.int64)

    def codegen(context, builder, signature, args):
        mod = builder.module
        restore = cgutils.get_or_insert_function(
            mod, ir.FunctionType(ir.VoidType(), [cgutils.voidptr_t]), "PyEval_RestoreThread")
        with builder.if_then(builder.icmp_signed("!=", args[0], ir.Constant(ir.IntType(64), 0))):
            builder.call(restore, [builder.inttoptr(args[0], cgutils.voidptr_t)])
        return context.get_dummy_value()
    return sig, codegen


@jit_inline
def _views(ba):
    """``N``, ``T``, ``order`` of the packed body at the address ``ba`` (views
    without a meminfo)."""
    h = carray(i64_ptr(ba), 2)
    n = h[0]
    m = h[1]
    f = HEADER + 16 * n
    N = carray(f64_ptr(ba + 8 * HEADER), (n, 16))
    T = carray(f64_ptr(ba + 8 * f), (m, 3, 3))
    order = carray(i64_ptr(ba + 8 * (f + 9 * m)), m)
    return N, T, order


@jit_inline
def _pose_from_object(obj, ndarray, float64, P):
    """Copy the pose object at the address ``obj`` into ``P`` (4, 4) if it is exactly
    a float64 2-D ``numpy.ndarray`` (any strides): 0; 1 if it is one of another
    shape; 2 if it is any other object."""
    data, dims, strides = array_data(obj, ndarray, float64, NPY_DOUBLE, 2)
    if data == 0:
        return 2
    d = carray(i64_ptr(dims), 2)
    if d[0] != 4 or d[1] != 4:
        return 1
    st = carray(i64_ptr(strides), 2)
    for r in range(4):
        for c in range(4):
            P[r, c] = f64_load(data + r * st[0] + c * st[1])
    return 0


@jit_inline
def _packed_body(obj, ndarray, float64):
    """Data address of the packed body buffer at the object address ``obj`` (a
    contiguous float64 1-D ndarray whose length matches its header's node and
    triangle counts), else 0."""
    data, dims, strides = array_data(obj, ndarray, float64, NPY_DOUBLE, 1)
    if data == 0 or i64_ptr(strides)[0] != 8:
        return 0
    h = carray(i64_ptr(data), 2)
    if h[0] < 1 or h[1] < 1 or i64_ptr(dims)[0] != HEADER + 16 * h[0] + 11 * h[1]:
        return 0
    return data


@jit_holding_gil
def collide_packed(body_a, body_b, pose_a, pose_b, first_only, scratch):
    """:func:`collide_boxes` for two packed bodies under two poses; every argument is
    the caller's Python object, passed by address (:data:`geomkit._kernels.numba_ext.pyobj.object_ref`):
    ``body_a``, ``body_b`` the bodies' packed buffers (float64 1-D ndarrays, see the
    module docstring), ``pose_a``, ``pose_b`` float64 2-D ndarrays of any layout
    (copied to ``W``) or ``None`` (the caller wrote that pose to ``W``),
    ``first_only`` ``True`` or ``False``, ``scratch`` the thread's scratch ``W``
    (int64 1-D ndarray; the addresses of ``numpy.ndarray``, the float64 dtype,
    ``True`` and ``None`` at ``W[POSED_REFS]``, set by the caller with the pose
    tolerance).  The poses are first checked to be rigid (4, 4) transforms.

    Returns ``2 * bv_tests + (n_pairs > 0)``; -1 / -2 for the first pose that is not
    a rigid (4, 4) transform, -3 when a pose is not a float64 2-D ndarray, -4 when a
    body buffer is not a float64 ndarray, -5 when the scratch is not an ndarray as
    long as its recorded length (nothing traversed in these cases).  The
    pairs (original face indices, ``(cap, 2)`` from ``W[POSED_FIXED]``), their face
    tags (the next ``2 cap``) and ``(n_pairs, bv_tests)`` (``W[POSED_ANSWER]``) are
    written to ``W``; ``n_pairs > cap`` means the buffer was too small (call again
    with a larger one)."""
    sa = address(scratch)
    # the scratch's own length bounds every view made of it below (its fixed part
    # first: W[POSED_LENGTH] is read from the buffer)
    length = i64_ptr(i64_ptr(sa + DIMS)[0])[0]
    if length < POSED_FIXED:
        return -5
    w = i64_ptr(sa + DATA)[0]
    W = carray(i64_ptr(w), POSED_FIXED)
    nd = W[POSED_REFS]
    if i64_ptr(sa + OB_TYPE)[0] != nd or W[POSED_LENGTH] > length:
        return -5
    f8 = W[POSED_REFS + 1]
    ba = _packed_body(address(body_a), nd, f8)
    bb = _packed_body(address(body_b), nd, f8)
    if ba == 0 or bb == 0:
        return -4
    S = carray(f64_ptr(w + 8 * POSED_FLOATS), (6, 3, 3))
    Pa = carray(f64_ptr(w + 8 * POSED_POSES), (4, 4))
    Pb = carray(f64_ptr(w + 8 * (POSED_POSES + 16)), (4, 4))
    none = W[POSED_REFS + 3]
    ida = address(pose_a)
    idb = address(pose_b)
    ka = _pose_from_object(ida, nd, f8, Pa) if ida != none else 0
    kb = _pose_from_object(idb, nd, f8, Pb) if idb != none else 0
    if ka == 2 or kb == 2:
        return -3
    tol = S[1, 2, 2]
    if ka != 0 or rigid_code(Pa, tol)[0] != 0:
        return -1
    if kb != 0 or rigid_code(Pb, tol)[0] != 0:
        return -2
    first = address(first_only) == W[POSED_REFS + 2]
    hA = carray(i64_ptr(ba), 2)
    hB = carray(i64_ptr(bb), 2)
    na = hA[0]
    ma = hA[1]
    nb = hB[0]
    mb = hB[1]
    NA = carray(f64_ptr(ba + 8 * HEADER), (na, 16))
    NB = carray(f64_ptr(bb + 8 * HEADER), (nb, 16))
    Rr = S[0]
    tr = S[1, 0]
    _relative(Pa, Pb, Rr, tr)
    if _boxes_disjoint(NA, 0, NB, 0, Rr, tr, S[2], S[5, 0], S[3], S[4]):
        W[POSED_ANSWER] = 0     # root boxes disjoint (most poses of a sparse scene):
        W[POSED_ANSWER + 1] = 1     # answered without the traversal's call
        return 2
    fa = HEADER + na * 16
    fb = HEADER + nb * 16
    TA = carray(f64_ptr(ba + 8 * fa), (ma, 3, 3))
    TB = carray(f64_ptr(bb + 8 * fb), (mb, 3, 3))
    fa += 9 * ma
    fb += 9 * mb
    orderA = carray(i64_ptr(ba + 8 * fa), ma)
    orderB = carray(i64_ptr(bb + 8 * fb), mb)
    tagsA = carray(i64_ptr(ba + 8 * (fa + ma)), ma)
    tagsB = carray(i64_ptr(bb + 8 * (fb + mb)), mb)
    cap = (W[POSED_LENGTH] - POSED_FIXED) // 4
    # views made from addresses (a slice's .reshape calls numba's reshape helper)
    pairs = carray(i64_ptr(w + 8 * POSED_FIXED), (cap, 2))
    tags = carray(i64_ptr(w + 8 * (POSED_FIXED + 2 * cap)), (cap, 2))
    seed = W[POSED_ANSWER + 2:POSED_ANSWER + 4]
    seed[0] = -1
    seed[1] = -1
    n, tests = collide_boxes(NA, TA, orderA, NB, TB, orderB, Rr, tr, first, pairs,
                             carray(i64_ptr(w + 8 * POSED_STACK), (STACK, 2)), S[2:],
                             carray(f64_ptr(w + 8 * POSED_LEAF), (LEAF_BUF, 3, 3)), seed,
                             True, GIL_AFTER)
    for k in range(min(n, cap)):
        tags[k, 0] = tagsA[pairs[k, 0]]
        tags[k, 1] = tagsB[pairs[k, 1]]
    W[POSED_ANSWER] = n
    W[POSED_ANSWER + 1] = tests
    return 2 * tests + (1 if n > 0 else 0)
