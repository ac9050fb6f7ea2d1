"""Collision and minimum distance of rigid triangle meshes (Papers 3 and 5).

A :class:`Body` is a mesh with a bounding-volume hierarchy built once (OBB, 14-DOP
or AABB nodes; see :mod:`geomkit._kernels.bvh` for the tree layout).  Queries take
4x4 rigid poses (body -> world):

* :func:`collide` — every intersecting triangle pair (or the first);
* :func:`collide_many` — the same for many pose pairs in one call (threads);
* :func:`min_distance` — exact minimum distance with closest points and faces, or
  with ``margin`` a quick "closer than margin?".

Method
------
* Box trees (``"obb"``, ``"aabb"``): B's node boxes are carried into A's frame by
  the relative motion and tested with the 15-axis SAT of Paper 3 (robust epsilon
  for nearly parallel edges).  A pose costs nothing beyond the query.
* 14-DOP trees (``"kdop14"``): a k-DOP is not rotation invariant.  Each query
  refits the tree of every body whose pose changed since its last query in the
  world frame (leaf 14-DOPs from the moved triangle corners, inner nodes as unions;
  Paper 5's "rebuilt cheaply"): that is O(triangles) per moved body and query,
  ~1 ms for 50k triangles, which dominates the query; a body whose pose does not
  change (a static part) is refitted once.  The interval tests then run in the
  world frame in Paper 5's order.
* Leaves: the exact triangle kernels (:mod:`geomkit._kernels.triangles`).
* min_distance: branch and bound over node pairs with lower bounds from the SAT
  axes (boxes) or the 7 directions (14-DOPs), nearer pair first.

Examples
--------
>>> import numpy as np, trimesh, geomkit
>>> a = geomkit.Body(trimesh.creation.box((1, 1, 1)))
>>> b = geomkit.Body(trimesh.creation.icosphere(2, 0.5))
>>> far = np.eye(4); far[0, 3] = 2.0
>>> geomkit.collide(a, np.eye(4), b, far).colliding
False
>>> round(geomkit.min_distance(a, np.eye(4), b, far).distance, 6)
1.0
>>> near = np.eye(4); near[0, 3] = 0.9
>>> geomkit.collide(a, np.eye(4), b, near).colliding
True
"""

from __future__ import annotations

import threading

import numba
import numpy as np

from geomkit.tolerances import POSE_TOL
from geomkit.collision.body import Body, Contact, Contacts, Distance, _contact, _new
from geomkit._kernels import bvh as kb
from geomkit._kernels.numba_ext.policy import prun
from geomkit._kernels import bvh_boxes as kp
from geomkit._kernels import bvh_query as kq
from geomkit._kernels.numba_ext.pyobj import array_fields_ok, object_ref
from geomkit.validate import as_float_array
from geomkit.errors import InvalidInputError

__all__ = ["Body", "Contact", "Contacts", "Distance", "collide", "collide_many",
           "min_distance", "validate_pose"]


_E3 = np.empty((0, 3))
_E33 = np.empty((0, 3, 3))


def _body(x, field):
    if not isinstance(x, Body):
        raise InvalidInputError(f"expected a geomkit.Body, got {type(x).__name__}", field)
    return x


def _as_poses(value, field, single):
    if type(value) is np.ndarray and value.dtype == np.float64 and \
            value.flags.c_contiguous:
        P = value           # fast path: no copy, the kernel checks finiteness
        # (not for subclasses: np.matrix cannot be reshaped to (1, 4, 4))
    else:
        try:
            P = np.ascontiguousarray(value, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise InvalidInputError(f"expected numbers, could not convert ({exc})",
                                    field) from None
    if single:
        if P.shape != (4, 4):
            raise InvalidInputError(f"expected shape (4, 4), got {P.shape}", field)
        P3 = P.reshape(1, 4, 4)
    else:
        if P.shape == (4, 4):
            P = P.reshape(1, 4, 4)
        if P.ndim != 3 or P.shape[1:] != (4, 4):
            raise InvalidInputError(f"expected shape (n, 4, 4) or (4, 4), got {P.shape}",
                                    field)
        P3 = P
    k, code, val = kb.pose_status(P3, POSE_TOL)
    if k >= 0:
        f = field if single else f"{field}[{k}]"
        msg = {1: f"non-finite value {val!r}",
               2: f"last row must be (0, 0, 0, 1), got {P3[k, 3].tolist()}",
               3: f"rotation is not orthonormal (|R^T R - I| = {val:.3g} > {POSE_TOL:g})",
               4: "rotation has determinant -1 (a reflection)"}[code]
        raise InvalidInputError(msg, f)
    return P


def validate_pose(pose, field="pose") -> np.ndarray:
    """A (4, 4) float rigid transform, checked: finite, last row (0, 0, 0, 1),
    rotation orthonormal within :data:`POSE_TOL` with determinant +1."""
    return _as_poses(pose, field, True)


def _poses(poses, field):
    return _as_poses(poses, field, False)


def _same_kind(a, b):
    if (a.kind == 2) != (b.kind == 2):
        raise InvalidInputError(f"a 14-DOP body can only be tested against another one "
                                f"(a.bv={a.bv!r}, b.bv={b.bv!r})", "b.bv")


def _world_kdop(body, P):
    if body._world_pose is None or not np.array_equal(body._world_pose, P):
        K = np.empty_like(body.K)
        kb.refit_kdop(body.T, body.child, body.rng, np.ascontiguousarray(P[:3, :3]),
                      np.ascontiguousarray(P[:3, 3]), K)
        body._world_pose, body._world_K = P.copy(), K
    return body._world_K


def _frames(a, Pa, b, Pb):
    """Arguments of the traversal kernels for one pose pair, and the matrix that
    takes the common frame to the world."""
    if a.kind == 2:
        KA, KB = _world_kdop(a, Pa), _world_kdop(b, Pb)
        eye, zero = np.eye(3), np.zeros(3)
        mov = (eye, zero, np.ascontiguousarray(Pa[:3, :3]), np.ascontiguousarray(Pa[:3, 3]),
               np.ascontiguousarray(Pb[:3, :3]), np.ascontiguousarray(Pb[:3, 3]))
        to_world = np.eye(4)
    else:
        KA, KB = a.K, b.K
        Ra = Pa[:3, :3]
        Rr = np.ascontiguousarray(Ra.T @ Pb[:3, :3])
        tr = np.ascontiguousarray(Ra.T @ (Pb[:3, 3] - Pa[:3, 3]))
        mov = (Rr, tr, np.eye(3), np.zeros(3), Rr, tr)
        to_world = Pa
    A = (a.child, a.rng, a.C, a.R, a.E, KA, a.T, a.order)
    B = (b.child, b.rng, b.C, b.R, b.E, KB, b.T, b.order)
    return A, B, mov, to_world


# ------------------------------------------------------------------ queries
def collide(a, pose_a, b, pose_b, all_pairs=True) -> Contact:
    """Do two bodies intersect, and which triangle pairs do?

    Parameters
    ----------
    a, b : Body (both 14-DOP, or both box trees)
    pose_a, pose_b : (4, 4) float rigid transforms, body -> world.
    all_pairs : bool
        True: every intersecting pair; False: stop at the first one found.

    Returns
    -------
    Contact
        ``colliding`` is exact up to the orientation predicates of the triangle
        test (closed triangles: touching counts); ``pairs`` (k, 2) sorted.
    """
    if type(a) is Body and type(b) is Body and _BY_REF:
        # box trees: one kernel call (pose checks, relative motion, root test,
        # traversal, tags) given the bodies' buffers, the poses and the scratch as
        # the Python objects (geomkit._kernels.numba_ext.pyobj: nothing converted)
        try:
            W = _scratch.W
        except AttributeError:      # per-thread scratch, reused (results copied out)
            W = _single_scratch()
        first = not all_pairs
        r = _posed(a._pf, b._pf, pose_a, pose_b, first, W)
        if r == 2:                  # root boxes disjoint
            return _MISS1
        if r == -3:     # other types: checked, converted, written to the scratch
            P = _scratch.P
            P[0] = validate_pose(pose_a, "pose_a")
            P[1] = validate_pose(pose_b, "pose_b")
            r = _posed(a._pf, b._pf, None, None, first, W)
        if r >= 0:
            if not r & 1:
                c = _MISSES.get(r)
                if c is None:
                    c = _contact(False, _NO_PAIRS, _NO_PAIRS, r >> 1)
                    if r < 8192:
                        _MISSES[r] = c
                return c
            return _hits(r, a._pf, b._pf, first)
    a, b = _body(a, "a"), _body(b, "b")
    _same_kind(a, b)
    Pa, Pb = validate_pose(pose_a, "pose_a"), validate_pose(pose_b, "pose_b")
    A, B, mov, _ = _frames(a, Pa, b, Pb)
    cap = 64
    while True:
        buf = np.empty((cap, 2), dtype=np.int64)
        n, tests = kq.collide_trees(a.kind, *A, *B, *mov, kb.KDOP_ORDER, not all_pairs, buf)
        if n <= cap:
            break
        cap = n
    pairs = buf[:n]
    if n > 1:
        pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
    tags = np.column_stack([a.face_tags[pairs[:, 0]], b.face_tags[pairs[:, 1]]])
    return Contact(bool(n > 0), pairs, tags.reshape(-1, 2), int(tests))


def _hits(r, pfa, pfb, first_only):
    """The :class:`Contact` of a hit found by the single-call kernel (answer ``r``;
    pairs and tags copied out of this thread's scratch, sorted)."""
    sc = _scratch
    n = 1 if first_only else sc.W.item(kp.POSED_ANSWER)
    if n > sc.cap:              # more pairs than the buffer: once more, larger (the
        W = _posed_scratch(n)   # kernel left both poses in the scratch)
        W[kp.POSED_POSES:kp.POSED_POSES + 32] = sc.W[kp.POSED_POSES:kp.POSED_POSES + 32]
        _posed(pfa, pfb, None, None, first_only, W)
        o = kp.POSED_FIXED
        pairs = W[o:o + 2 * n].reshape(n, 2)
        tags = W[o + 2 * n:o + 4 * n].reshape(n, 2)
    elif n == 1:                # views made once per scratch: a copy each
        return _contact(True, sc.pairs1.copy(), sc.tags1.copy(), r >> 1)
    else:
        pairs, tags = sc.pairs[:n].copy(), sc.tags[:n].copy()
    if n > 1:
        k = np.lexsort((pairs[:, 1], pairs[:, 0]))
        pairs, tags = pairs[k], tags[k]
    return _contact(True, pairs, tags, r >> 1)


def _posed_scratch(cap):
    """A scratch ``W`` of the single-call kernel for ``cap`` pairs."""
    W = np.zeros(kp.posed_scratch_size(cap), dtype=np.int64)
    W[kp.POSED_LENGTH] = W.shape[0]
    W[kp.POSED_REFS:kp.POSED_REFS + 4] = id(np.ndarray), id(_F64), id(True), id(None)
    W[kp.POSED_TOL:kp.POSED_TOL + 1].view(np.float64)[0] = POSE_TOL
    return W


def _single_scratch():
    """This thread's scratch of the single-call kernel (``_scratch``: ``W``, ``P``
    the two poses' slots, ``pairs`` / ``tags`` views of ``cap`` rows, ``pairs1`` /
    ``tags1`` of one), made once per thread; loads the kernel's entry point on first
    use."""
    _posed_load()
    sc = _scratch
    sc.cap = _FAST_CAP
    W = _posed_scratch(_FAST_CAP)
    o = kp.POSED_FIXED
    sc.P = W[kp.POSED_POSES:kp.POSED_POSES + 32].view(np.float64).reshape(2, 4, 4)
    sc.pairs = W[o:o + 2 * _FAST_CAP].reshape(_FAST_CAP, 2)
    sc.tags = W[o + 2 * _FAST_CAP:o + 4 * _FAST_CAP].reshape(_FAST_CAP, 2)
    sc.pairs1, sc.tags1 = sc.pairs[:1], sc.tags[:1]
    sc.W = W
    return W


def _posed_load():
    """The compiled entry point of the single-call kernel for its one signature (six
    objects by reference), compiled or loaded from the cache once; calling it
    directly skips the dispatcher's type matching."""
    global _posed
    if _posed is None:
        _posed = kp.collide_packed.compile((object_ref,) * 6)
    return _posed


_BY_REF = array_fields_ok()
"""Can the single-call kernel read the arrays it is given (CPython, NumPy's layout)?
If not, :func:`collide` takes the generic path (same answers, slower)."""
_posed = None
_MISSES = {}
"""Non-colliding :class:`Contact` results by ``2 * bv_tests`` (immutable: shared)."""


_FAST_CAP = 64
_F64 = np.dtype(np.float64)
_MANY_CHUNK = 32
"""Pose pairs per task of :func:`collide_many` on threads (box trees; a batch of at
most one chunk runs in the calling thread).  A box-tree query costs ~1-30 µs, so a
task is ~0.1-1 ms of work.  Measured on 2 cores (sphere–torus, 1e-2 meshes, 100 /
200 poses, 15 calls each, µs per pose, median): with another engineer's job on the
machine (load ~2) chunks of 256 (one thread) 5.8 / 6.8, 64: 4.3 / 4.8, 32: 3.8 /
4.3; with six more busy processes (load ~8) 6.6 / 6.4 against 6.8 / 7.5 for 32 —
the threads help on a machine with a core to spare and cost little on a saturated
one (with tasks of 16 a saturated machine has shown 90 against 14 µs/query: a
pool thread that has not started is cancelled, :func:`geomkit._kernels.numba_ext.policy.prun`,
but one preempted inside its task is waited for)."""
_scratch = threading.local()
_NO_PAIRS = np.empty((0, 2), dtype=np.int64)
_NO_PAIRS.flags.writeable = False
_MISS1 = _MISSES[2] = _contact(False, _NO_PAIRS, _NO_PAIRS, 1)


def collide_many(a, b, poses_a, poses_b, all_pairs=False) -> Contacts:
    """:func:`collide` for n pose pairs in one call (serial kernel workers over pose
    ranges, on threads for batches longer than :data:`_MANY_CHUNK`; box trees reuse
    the previous pose's first hit, see :func:`geomkit._kernels.bvh_boxes.collide_boxes`).

    Parameters
    ----------
    a, b : Body
    poses_a, poses_b : (n, 4, 4) or (4, 4) float (a single pose is broadcast).
    all_pairs : bool
        False (default): each row stops at its first hit; True: count all pairs.

    Returns
    -------
    Contacts
        ``colliding`` (n,), ``n_pairs`` (n,), ``bv_tests`` (n,); row k equals
        ``collide(a, poses_a[k], b, poses_b[k], all_pairs)``.
    """
    a, b = _body(a, "a"), _body(b, "b")
    _same_kind(a, b)
    ra, poses_a = _unbroadcast(poses_a)
    rb, poses_b = _unbroadcast(poses_b)
    PA, PB = _poses(poses_a, "poses_a"), _poses(poses_b, "poses_b")
    na, nb = ra or PA.shape[0], rb or PB.shape[0]
    n = max(na, nb)
    if na not in (1, n) or nb not in (1, n):
        raise InvalidInputError(f"{na} poses for a but {nb} for b", "poses_b")
    PA, PB = np.ascontiguousarray(PA), np.ascontiguousarray(PB)
    col = np.empty(n, dtype=np.bool_)
    cnt = np.empty(n, dtype=np.int64)
    tests = np.empty(n, dtype=np.int64)
    first = not all_pairs
    if a.kind == 2:
        # a task refits its bodies at least once: few large tasks (refits cost the same
        # for every pose, so no balancing is lost)
        nt = numba.get_num_threads()
        prun(kq.collide_many_kdops, n, max(4, -(-n // nt)), a.child, a.rng, a.K, a.T, a.order,
             b.child, b.rng, b.K, b.T, b.order, PA, PB, kb.KDOP_ORDER, first, col, cnt, tests)
    else:
        prun(kp.collide_many_boxes, n, _MANY_CHUNK, a._addr, b._addr, PA, PB, first, col,
             cnt, tests)
    c = _new(Contacts)          # the frozen dataclass __init__ costs ~2 µs
    c.__dict__.update(colliding=col, n_pairs=cnt, bv_tests=tests)
    return c


def _unbroadcast(P):
    """``(rows, P)``: a stack of one pose repeated with stride 0 (``np.broadcast_to``)
    as that pose once (checked and passed once, broadcast by the kernel), else
    ``(None, P)``."""
    if isinstance(P, np.ndarray) and P.ndim == 3 and P.shape[0] > 1 and P.strides[0] == 0:
        return P.shape[0], P[:1]
    return None, P


def min_distance(a, pose_a, b, pose_b, margin=0.0) -> Distance:
    """Minimum distance between two posed bodies, with closest points and faces.

    Parameters
    ----------
    a, b : Body
    pose_a, pose_b : (4, 4) float rigid transforms.
    margin : float >= 0
        0: the exact minimum.  > 0: answer "closer than ``margin``?" quickly — the
        search prunes every node pair whose lower bound reaches ``margin`` and stops
        at the first triangle pair closer than it.

    Returns
    -------
    Distance
        ``distance`` is the exact minimum over all triangle pairs (0 iff
        :func:`collide` reports a collision) when ``margin == 0``; points in the
        world frame.
    """
    a, b = _body(a, "a"), _body(b, "b")
    _same_kind(a, b)
    Pa, Pb = validate_pose(pose_a, "pose_a"), validate_pose(pose_b, "pose_b")
    margin = float(as_float_array(margin, "margin", shape=()))
    if margin < 0:
        raise InvalidInputError(f"must be >= 0, got {margin!r}", "margin")
    A, B, mov, W = _frames(a, Pa, b, Pb)
    p = np.zeros(3)
    q = np.zeros(3)
    d, fa, fb, tests = kq.distance_trees(a.kind, *A, *B, *mov, kb.KDOP_ORDER, margin, p, q)
    p = W[:3, :3] @ p + W[:3, 3]
    q = W[:3, :3] @ q + W[:3, 3]
    within = bool(d < margin) if margin > 0 else bool(d == 0.0)
    if fa < 0:
        p = np.full(3, np.nan)
        q = np.full(3, np.nan)
    return Distance(float(d), p, q, int(fa), int(fb), int(tests), within)
