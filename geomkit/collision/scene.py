"""Scenes of many bodies: sweep-and-prune broad phase, assembly groups, declared
fits (Papers 4 and 5).

A :class:`Scene` holds bodies with poses, an assembly group and a static flag.
Each :meth:`Scene.update` moves the world AABBs (the body's local box carried by
the pose: Paper 4's cheap update) and re-sorts the interval endpoints of the
three axes by insertion from the previous frame's order (frame coherence:
O(n + swaps)).  Candidate pairs overlap on all three axes, belong to different
groups and are not both static (Paper 4: the moving assembly against the rest).
The narrow phase is :func:`geomkit.collide` / :func:`geomkit.min_distance`.

False interference (Paper 4): a shaft and its hole of the same nominal size
interfere once both are faceted.  :meth:`Scene.declare_fit` names the fitted faces
(face tags of the two bodies, e.g. the CAD surfaces the triangles came from) and
their adjacent faces; intersecting triangle pairs between a fitted face and the
other body's fitted or adjacent faces are then dropped, while every other pair —
a real interference next to the fit — is still reported.

Examples
--------
>>> import numpy as np, trimesh
>>> from geomkit.collision.collide import Body
>>> from geomkit.collision.scene import Scene
>>> s = Scene()
>>> box = Body(trimesh.creation.box((1, 1, 1)))
>>> i = s.add(box); j = s.add(box, pose=np.eye(4), static=True)
>>> s.pairs().tolist()
[[0, 1]]
>>> s.collisions().pairs.tolist()
[[0, 1]]
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from geomkit.collision.body import Body, Contact
from geomkit._kernels import bvh as kb
from geomkit._kernels import motion as km
from geomkit._kernels import sap as ks
from geomkit.validate import as_float_array, as_int
from geomkit.collision.collide import (_body, _frames, _poses, _same_kind, collide, min_distance,
                                       validate_pose)
from geomkit.errors import InvalidInputError

__all__ = ["CoherentPair", "Scene", "SceneCollisions", "SceneDistances", "SweepAndPrune",
           "fit_exclusions"]


@dataclass(frozen=True, eq=False)
class SceneCollisions:
    """Result of :meth:`Scene.collisions`.

    Attributes
    ----------
    pairs : (k, 2) int64, colliding body pairs (i < j), sorted.
    contacts : list of :class:`geomkit.Contact`, one per pair (triangle pairs of
        i and j; with declared fits, the excluded triangle pairs removed).
    candidates : int, pairs the broad phase passed to the narrow phase.
    excluded : int, triangle pairs dropped by declared fits.
    """

    pairs: np.ndarray
    contacts: list = field(repr=False)
    candidates: int
    excluded: int


@dataclass(frozen=True, eq=False)
class SceneDistances:
    """Result of :meth:`Scene.min_distances`.

    Attributes
    ----------
    pairs : (k, 2) int64, body pairs closer than ``margin`` (i < j), sorted.
    distance : (k,) float, their exact minimum distances.
    point_a, point_b : (k, 3) float, closest points (world) on i and on j.
    candidates : int, pairs whose grown boxes overlapped.
    """

    pairs: np.ndarray
    distance: np.ndarray
    point_a: np.ndarray = field(repr=False)
    point_b: np.ndarray = field(repr=False)
    candidates: int


class SweepAndPrune:
    """Sweep and prune over n axis-aligned boxes with incremental re-sorting.

    Parameters
    ----------
    lo, hi : (n, 3) float, box corners (``lo <= hi``).
    group : (n,) int, optional; boxes of one group are never paired (default: all
        different).
    static : (n,) bool, optional; two static boxes are never paired.

    Attributes
    ----------
    swaps : int, endpoint swaps of the last re-sort (the work coherence saves).
    """

    def __init__(self, lo, hi, group=None, static=None):
        lo, hi = self._boxes(lo, hi)
        n = lo.shape[0]
        self.group = np.arange(n, dtype=np.int64) if group is None else \
            np.ascontiguousarray(group, dtype=np.int64)
        self.static = np.zeros(n, dtype=np.bool_) if static is None else \
            np.ascontiguousarray(static, dtype=np.bool_)
        if self.group.shape != (n,):
            raise InvalidInputError(f"expected ({n},) integers, got {self.group.shape}",
                                    "group")
        if self.static.shape != (n,):
            raise InvalidInputError(f"expected ({n},) booleans, got {self.static.shape}",
                                    "static")
        self.lo, self.hi = lo, hi
        self.ep_id = np.empty((3, 2 * n), dtype=np.int64)
        self.ep_val = np.empty((3, 2 * n))
        self.swaps = int(ks.init_endpoints(lo, hi, self.ep_id, self.ep_val)) if n else 0
        self._cap = max(64, 4 * n)

    @staticmethod
    def _boxes(lo, hi):
        lo = as_float_array(lo, "lo", shape=(None, 3))
        hi = as_float_array(hi, "hi", shape=(lo.shape[0], 3))
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            raise InvalidInputError("expected finite numbers", "lo")
        if np.any(lo > hi):
            raise InvalidInputError("expected lo <= hi on every axis", "hi")
        return np.ascontiguousarray(lo), np.ascontiguousarray(hi)

    def update(self, lo, hi) -> int:
        """New box corners (same n); re-sorts from the previous order; returns the
        number of endpoint swaps."""
        lo, hi = self._boxes(lo, hi)
        if lo.shape != self.lo.shape:
            raise InvalidInputError(f"expected {self.lo.shape}, got {lo.shape}", "lo")
        self.lo, self.hi = lo, hi
        self.swaps = int(ks.resort(lo, hi, self.ep_id, self.ep_val))
        return self.swaps

    def pairs(self, margin=0.0) -> np.ndarray:
        """Candidate pairs (k, 2), i < j, sorted: boxes grown by ``margin`` overlap
        (closed intervals) on all three axes, different groups, not both static."""
        n = self.lo.shape[0]
        if n < 2:
            return np.empty((0, 2), dtype=np.int64)
        c = 0.5 * (self.lo + self.hi)
        axis = int(np.argmax(c.var(0)))
        while True:
            out = np.empty((self._cap, 2), dtype=np.int64)
            k = ks.sweep_pairs(self.lo, self.hi, self.ep_id, axis, self.group, self.static,
                               float(margin), out)
            if k <= self._cap:
                break
            self._cap = 2 * k
        out = out[:k]
        return out[np.lexsort((out[:, 1], out[:, 0]))]


def _parents(child):
    par = np.full(child.shape[0], -1, dtype=np.int64)
    inner = child[:, 0] >= 0
    idx = np.nonzero(inner)[0]
    par[child[idx, 0]] = idx
    par[child[idx, 1]] = idx
    return par


class CoherentPair:
    """Collision queries of one body pair over a sequence of frames, restarting
    each traversal from the previous frame's front (Paper 4).

    The front is the set of node pairs where the last traversal stopped
    (separated pairs and leaf pairs).  Each frame tests the front: an entry that
    now overlaps is descended, one that still separates stays; two separated
    sibling entries move up to their parent pair.  The answer equals
    :func:`geomkit.collide` with ``all_pairs=True``.

    Attributes
    ----------
    front_size : int, node pairs in the current front.
    """

    def __init__(self, a, b):
        self.a, self.b = _body(a, "a"), _body(b, "b")
        _same_kind(self.a, self.b)
        self.parentA = _parents(self.a.child)
        self.parentB = _parents(self.b.child)
        self.front = np.zeros((1, 2), dtype=np.int64)
        self._cap = 256

    @property
    def front_size(self) -> int:
        return int(self.front.shape[0])

    def reset(self):
        """Forget the front (the next query starts at the root pair)."""
        self.front = np.zeros((1, 2), dtype=np.int64)

    def collide(self, pose_a, pose_b) -> Contact:
        """Every intersecting triangle pair at these poses (as :func:`geomkit.collide`)."""
        a, b = self.a, self.b
        Pa, Pb = validate_pose(pose_a, "pose_a"), validate_pose(pose_b, "pose_b")
        A, B, mov, _ = _frames(a, Pa, b, Pb)
        capp = 64
        while True:
            cap = max(self._cap, 2 * self.front.shape[0])
            out_f = np.empty((cap, 2), dtype=np.int64)
            out_s = np.empty(cap, dtype=np.bool_)
            pairs = np.empty((capp, 2), dtype=np.int64)
            n, nf, tests = km.collide_front(a.kind, *A, *B, *mov, kb.KDOP_ORDER, self.front,
                                            self.front.shape[0], out_f, out_s, pairs)
            if nf <= cap and n <= capp:
                break
            self._cap = max(self._cap, 2 * nf)
            capp = max(capp, n)
        new = np.empty((nf, 2), dtype=np.int64)
        K_A, K_B = A[5], B[5]
        m = km.collapse_front(a.kind, a.child, self.parentA, a.E, K_A, b.child,
                              self.parentB, b.E, K_B, out_f[:nf], out_s[:nf], nf, new)
        self.front = new[:m]
        pairs = pairs[:n]
        if n > 1:
            pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
        tags = np.column_stack([a.face_tags[pairs[:, 0]], b.face_tags[pairs[:, 1]]])
        return Contact(bool(n > 0), pairs, tags.reshape(-1, 2), int(tests))


def fit_exclusions(shaft_faces, hole_faces, shaft_adjacent=(), hole_adjacent=()):
    """Tag pairs to skip for a declared shaft/hole fit (Paper 4).

    Parameters
    ----------
    shaft_faces, hole_faces : int or sequence of int, face tags of the fitted
        surfaces on the shaft body and on the hole body.
    shaft_adjacent, hole_adjacent : sequence of int, tags of their adjacent faces
        (chamfers, shoulders, the face the hole opens into) whose triangles may
        graze the other body's fitted face because of faceting.

    Returns
    -------
    (k, 2) int64, (shaft-body tag, hole-body tag) pairs: fitted x fitted,
    fitted shaft x adjacent hole faces, adjacent shaft faces x fitted hole.
    """
    sf = np.atleast_1d(np.asarray(shaft_faces, dtype=np.int64))
    hf = np.atleast_1d(np.asarray(hole_faces, dtype=np.int64))
    sa = np.atleast_1d(np.asarray(shaft_adjacent, dtype=np.int64))
    ha = np.atleast_1d(np.asarray(hole_adjacent, dtype=np.int64))
    rows = [(a, b) for a in sf for b in np.concatenate([hf, ha])]
    rows += [(a, b) for a in sa for b in hf]
    return np.unique(np.array(rows, dtype=np.int64).reshape(-1, 2), axis=0)


class Scene:
    """Bodies with poses, assembly groups and declared fits; broad phase by sweep
    and prune on world AABBs, narrow phase by the collision core.

    Parameters
    ----------
    coherent : bool
        Keep a :class:`CoherentPair` (cached traversal front) per candidate pair
        and restart each frame's narrow phase from it; :meth:`collisions` then
        searches every triangle pair (the front needs the full traversal).

    Methods: :meth:`add`, :meth:`update`, :meth:`pairs`, :meth:`collisions`,
    :meth:`min_distances`, :meth:`declare_fit`.
    """

    def __init__(self, coherent=False):
        self.coherent = bool(coherent)
        self._fronts: dict = {}
        self.bodies: list[Body] = []
        self._poses: list[np.ndarray] = []
        self._group: list[int] = []
        self._static: list[bool] = []
        self._C = np.empty((0, 3))
        self._H = np.empty((0, 3))
        self._sap = None
        self._fits: dict = {}

    def __len__(self):
        return len(self.bodies)

    def add(self, body, pose=None, group=None, static=False) -> int:
        """Add a body; returns its index.

        Parameters
        ----------
        body : Body
        pose : (4, 4) float, default identity.
        group : int >= 0, assembly id (bodies of one group are never tested
            against each other); default: a group of its own.
        static : bool, static bodies are never tested against each other.
        """
        if not isinstance(body, Body):
            raise InvalidInputError(f"expected a geomkit.Body, got {type(body).__name__}",
                                    "body")
        P = np.eye(4) if pose is None else validate_pose(pose, "pose").copy()
        if group is None:
            g = -1 - len(self.bodies)
        else:
            g = as_int(group, "group", minimum=0)
        V = body.vertices
        lo, hi = V.min(0), V.max(0)
        self.bodies.append(body)
        self._poses.append(P)
        self._group.append(g)
        self._static.append(bool(static))
        self._C = np.vstack([self._C, 0.5 * (lo + hi)])
        self._H = np.vstack([self._H, 0.5 * (hi - lo)])
        self._sap = None
        return len(self.bodies) - 1

    @property
    def poses(self) -> np.ndarray:
        """(n, 4, 4) current poses."""
        return np.array(self._poses).reshape(-1, 4, 4)

    def _world_boxes(self):
        P = self.poses
        lo = np.empty((len(self), 3))
        hi = np.empty((len(self), 3))
        ks.world_aabbs(self._C, self._H, np.ascontiguousarray(P[:, :3, :3]),
                       np.ascontiguousarray(P[:, :3, 3]), lo, hi)
        return lo, hi

    def _broad(self):
        if self._sap is None:
            lo, hi = self._world_boxes()
            self._sap = SweepAndPrune(lo, hi, np.array(self._group, dtype=np.int64),
                                      np.array(self._static, dtype=np.bool_))
        return self._sap

    def update(self, poses) -> int:
        """Move bodies: ``poses`` (n, 4, 4) for all bodies, or a dict
        ``{index: (4, 4) pose}``.  Returns the endpoint swaps of the re-sort."""
        n = len(self)
        if isinstance(poses, dict):
            for k, P in poses.items():
                k = as_int(k, "poses", minimum=0)
                if k >= n:
                    raise InvalidInputError(f"body index {k} out of range [0, {n})",
                                            "poses")
                self._poses[k] = validate_pose(P, f"poses[{k}]").copy()
        else:
            P = _poses(poses, "poses")
            if P.shape[0] != n:
                raise InvalidInputError(f"expected ({n}, 4, 4), got {P.shape}", "poses")
            self._poses = [p.copy() for p in P]
        sap = self._broad()
        lo, hi = self._world_boxes()
        return sap.update(lo, hi)

    def pairs(self, margin=0.0) -> np.ndarray:
        """Broad-phase candidate body pairs (k, 2), i < j (boxes grown by margin)."""
        margin = float(as_float_array(margin, "margin", shape=()))
        if not (np.isfinite(margin) and margin >= 0):
            raise InvalidInputError(f"expected a finite number >= 0, got {margin!r}",
                                    "margin")
        return self._broad().pairs(margin)

    def declare_fit(self, shaft, hole, shaft_faces, hole_faces, shaft_adjacent=(),
                    hole_adjacent=()):
        """Declare a shaft/hole fit between bodies ``shaft`` and ``hole`` (indices):
        intersecting triangle pairs between the fitted faces and the adjacent faces
        (see :func:`fit_exclusions`) are no longer reported by :meth:`collisions`."""
        n = len(self)
        i = as_int(shaft, "shaft", minimum=0)
        j = as_int(hole, "hole", minimum=0)
        if i >= n or j >= n or i == j:
            raise InvalidInputError(f"expected two different body indices < {n}, got "
                                    f"{i}, {j}", "hole")
        ex = fit_exclusions(shaft_faces, hole_faces, shaft_adjacent, hole_adjacent)
        key = (min(i, j), max(i, j))
        if i > j:
            ex = ex[:, ::-1]
        old = self._fits.get(key)
        self._fits[key] = ex if old is None else np.unique(np.vstack([old, ex]), axis=0)

    def collisions(self, all_pairs=False) -> SceneCollisions:
        """Colliding body pairs.  ``all_pairs``: report every intersecting triangle
        pair of each body pair (else the first found; a pair with a declared fit
        is always searched in full, so that a real interference is not hidden
        behind an excluded one)."""
        cand = self.pairs()
        out, contacts = [], []
        excluded = 0
        P = self._poses
        for i, j in cand:
            i, j = int(i), int(j)
            ex = self._fits.get((i, j))
            if self.coherent:
                cp = self._fronts.get((i, j))
                if cp is None:
                    cp = self._fronts[(i, j)] = CoherentPair(self.bodies[i], self.bodies[j])
                c = cp.collide(P[i], P[j])
            else:
                c = collide(self.bodies[i], P[i], self.bodies[j], P[j],
                            all_pairs=all_pairs or ex is not None)
            if ex is not None and c.colliding:
                keep = ~_rows_in(c.tags, ex)
                excluded += int((~keep).sum())
                c = Contact(bool(keep.any()), c.pairs[keep], c.tags[keep], c.bv_tests)
            if c.colliding:
                out.append((i, j))
                contacts.append(c)
        pairs = np.array(out, dtype=np.int64).reshape(-1, 2)
        return SceneCollisions(pairs, contacts, int(cand.shape[0]), excluded)

    def min_distances(self, margin) -> SceneDistances:
        """Body pairs closer than ``margin`` (> 0) with exact distances."""
        margin = float(as_float_array(margin, "margin", shape=()))
        if not (np.isfinite(margin) and margin > 0):
            raise InvalidInputError(f"expected a finite number > 0, got {margin!r}",
                                    "margin")
        cand = self.pairs(0.5 * margin)     # both boxes grow: gap < margin
        P = self._poses
        rows, d, pa, pb = [], [], [], []
        for i, j in cand:
            i, j = int(i), int(j)
            r = min_distance(self.bodies[i], P[i], self.bodies[j], P[j])
            if r.distance < margin:
                rows.append((i, j))
                d.append(r.distance)
                pa.append(r.point_a)
                pb.append(r.point_b)
        return SceneDistances(np.array(rows, dtype=np.int64).reshape(-1, 2),
                              np.array(d, dtype=np.float64),
                              np.array(pa, dtype=np.float64).reshape(-1, 3),
                              np.array(pb, dtype=np.float64).reshape(-1, 3),
                              int(cand.shape[0]))


def _rows_in(rows, table):
    """Which rows (k, 2) appear in table (m, 2)."""
    if rows.shape[0] == 0 or table.shape[0] == 0:
        return np.zeros(rows.shape[0], dtype=bool)
    return (rows[:, None, :] == table[None, :, :]).all(-1).any(1)
