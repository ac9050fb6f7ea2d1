"""One collision query of two packed box trees straight from their (4, 4) poses.

A single :func:`geomkit.collide` call on box trees is a few microseconds of work
when the root boxes are already disjoint, so the call itself must cost little:
numba unboxes every array argument (~0.1 µs each), so each body is packed into one
buffer (the body's ``N``, ``T``, ``I``, ``order`` and ``face_tags`` are views into
it, nothing is stored twice), the kernel takes 6 arguments, allocates nothing,
answers a pose whose root boxes are disjoint without the traversal's call, and
returns one integer.

Body buffer ``B`` float64 (built by :func:`geomkit.collision.build_body`), with
``Bi = B.view(int64)``: ``N`` (n, 16) node records at ``B[0:16 n]``, ``T`` (m, 3, 3)
triangle corners in tree order at ``B[16 n:16 n + 9 m]`` (see
:mod:`geomkit._kernels.bvh_query`), then as int64 ``I`` (n, 4), ``order`` (m,),
``face_tags`` (m,), and ``Bi[-2] = n``, ``Bi[-1] = m``.  ``N`` starts the buffer,
so its 128-byte records keep their cache-line alignment.

Scratch ``W`` int64 (1-D), one per thread (:func:`posed_scratch_size`): the node
stack (``2 STACK``), the answer ``(n_pairs, bv_tests)``, the seed pair, the float
scratch (``POSED_FLOAT`` (3, 3) slabs, viewed as float64; the last slab holds the
relative translation in row 0 and the pose tolerance at ``[2, 2]``, set by the
caller), then ``cap`` pairs and ``cap`` tag pairs.
"""

from __future__ import annotations

import numpy as np

from ._numba import jit
from .bvh import rigid_code
from .bvh_query import LEAF_BUF, STACK, _boxes_disjoint, _relative, collide_boxes

POSED_FLOAT = 4 + LEAF_BUF + 2
"""(3, 3) slabs of float scratch: 4 of SAT scratch, ``LEAF_BUF`` moved leaf
triangles, the relative rotation, the relative translation and tolerance."""
POSED_ANSWER = 2 * STACK
"""Index in ``W`` of ``n_pairs`` (``bv_tests`` follows)."""
POSED_FLOATS = 2 * STACK + 4
"""Index in ``W`` of the float scratch."""
POSED_FIXED = POSED_FLOATS + 9 * POSED_FLOAT
"""Index in ``W`` of the pairs (``cap`` rows of 2, then ``cap`` tag rows of 2)."""


def posed_scratch_size(cap):
    """Length of the scratch ``W`` for up to ``cap`` pairs."""
    return POSED_FIXED + 4 * cap


@jit
def collide_packed(BA, BB, Pa, Pb, first_only, W):
    """:func:`geomkit._kernels.bvh_query.collide_boxes` for two packed bodies (see
    the module docstring) under the poses ``Pa``, ``Pb``, first checked to be rigid
    (4, 4) transforms within the tolerance in ``W`` (the caller sets it).

    Returns ``2 * bv_tests + (n_pairs > 0)``, or -1 / -2 for the first pose that is
    not a rigid (4, 4) transform (nothing traversed).  The pairs (original face
    indices, ``(cap, 2)`` from ``W[POSED_FIXED]``), their face tags (the next ``2
    cap``) and ``(n_pairs, bv_tests)`` (``W[POSED_ANSWER]``) are written to ``W``;
    ``n_pairs > cap`` means the buffer was too small (call again with a larger
    one)."""
    S = W[POSED_FLOATS:POSED_FIXED].view(np.float64).reshape((POSED_FLOAT, 3, 3))
    tol = S[POSED_FLOAT - 1, 2, 2]
    if Pa.shape[0] != 4 or Pa.shape[1] != 4 or rigid_code(Pa, tol)[0] != 0:
        return -1
    if Pb.shape[0] != 4 or Pb.shape[1] != 4 or rigid_code(Pb, tol)[0] != 0:
        return -2
    JA = BA.view(np.int64)
    JB = BB.view(np.int64)
    na = JA[JA.shape[0] - 2]
    ma = JA[JA.shape[0] - 1]
    nb = JB[JB.shape[0] - 2]
    mb = JB[JB.shape[0] - 1]
    NA = BA[:na * 16].reshape((na, 16))
    NB = BB[:nb * 16].reshape((nb, 16))
    Rr = S[POSED_FLOAT - 2]
    tr = S[POSED_FLOAT - 1, 0]
    _relative(Pa, Pb, Rr, tr)
    if _boxes_disjoint(NA, 0, NB, 0, Rr, tr, S[0], S[3, 0], S[1], S[2]):
        W[POSED_ANSWER] = 0     # root boxes disjoint (most poses of a sparse scene):
        W[POSED_ANSWER + 1] = 1     # answered without the traversal's call
        return 2
    fa = na * 16 + ma * 9
    fb = nb * 16 + mb * 9
    TA = BA[na * 16:fa].reshape((ma, 3, 3))
    TB = BB[nb * 16:fb].reshape((mb, 3, 3))
    IA = JA[fa:fa + 4 * na].reshape((na, 4))
    IB = JB[fb:fb + 4 * nb].reshape((nb, 4))
    orderA = JA[fa + 4 * na:fa + 4 * na + ma]
    orderB = JB[fb + 4 * nb:fb + 4 * nb + mb]
    tagsA = JA[fa + 4 * na + ma:fa + 4 * na + 2 * ma]
    tagsB = JB[fb + 4 * nb + mb:fb + 4 * nb + 2 * mb]
    cap = (W.shape[0] - POSED_FIXED) // 4
    pairs = W[POSED_FIXED:POSED_FIXED + 2 * cap].reshape((cap, 2))
    tags = W[POSED_FIXED + 2 * cap:POSED_FIXED + 4 * cap].reshape((cap, 2))
    seed = W[POSED_ANSWER + 2:POSED_ANSWER + 4]
    seed[0] = -1
    seed[1] = -1
    n, tests = collide_boxes(IA, NA, TA, orderA, IB, NB, TB, orderB, Rr, tr, first_only,
                             pairs, W[:2 * STACK].reshape((STACK, 2)), S[:4],
                             S[4:4 + LEAF_BUF], seed)
    for k in range(min(n, cap)):
        tags[k, 0] = tagsA[pairs[k, 0]]
        tags[k, 1] = tagsB[pairs[k, 1]]
    W[POSED_ANSWER] = n
    W[POSED_ANSWER + 1] = tests
    return 2 * tests + (1 if n > 0 else 0)
