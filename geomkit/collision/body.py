"""Bodies and the result types of :mod:`geomkit.collision.collide`.

:class:`Body` holds a triangle mesh and its flattened bounding-volume hierarchy, built
once by :func:`build_body` (the tree kernels are in :mod:`geomkit._kernels.bvh`, the
packed record layout in :mod:`geomkit._kernels.bvh_boxes`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from geomkit._kernels import bvh as kb
from geomkit._kernels import bvh_boxes as kp
from geomkit._kernels import bvh_query as kq
from geomkit.validate import as_int, as_mesh_arrays
from geomkit.errors import InvalidInputError

__all__ = ["Body", "Contact", "Contacts", "Distance", "build_body", "BV_KINDS"]

BV_KINDS = {"obb": 0, "aabb": 1, "kdop14": 2}

_EK = np.empty((0, 14))
_EN = np.empty((0, 16))


class Body:
    """A rigid triangle mesh with a bounding-volume hierarchy built once.

    Parameters
    ----------
    mesh : :class:`geomkit.Mesh`, ``trimesh.Trimesh`` or ``(vertices, faces)``
        vertices (n, 3) float, faces (m, 3) int (m >= 1).
    bv : {"obb", "kdop14", "aabb"}
        Node volume: oriented boxes (Paper 3), 14-DOPs (Paper 5) or axis-aligned
        boxes in the body frame.
    face_tags : (m,) int, optional
        A tag per face (e.g. its CAD face); defaults to ``mesh.face_surface`` for a
        :class:`geomkit.Mesh`, else zeros.  Reported with contacts.
    leaf_size : int, 1 to 16
        Largest number of triangles in a leaf (default 4).
    obb_center : {"covariance", "regions"}
        Centre of the covariance that orients each OBB: the area centroid, or
        Paper 3's mean of 4 equal-area region centres.

    Poses are 4x4 rigid transforms (body frame -> world) given per query; the tree
    is never rebuilt for them (a 14-DOP tree is refitted, see
    :mod:`geomkit.collision.collide`).

    Attributes
    ----------
    vertices : (n, 3) float; faces : (m, 3) int64; face_tags : (m,) int64
    bv : str; leaf_size : int; depth : int, depth of the tree (root depth 0)
    n_nodes : int
    N : box trees' packed node records (n_nodes, 16) float64 read by the traversal
        (see :mod:`geomkit._kernels.bvh_boxes`)
    """

    def __init__(self, mesh, bv="obb", face_tags=None, leaf_size=4, obb_center="covariance"):
        build_body(self, mesh, bv, face_tags, leaf_size, obb_center)

    def __setstate__(self, state):
        # a copy (pickle, copy.deepcopy) holds its packed buffer at another address:
        # the batch kernel's handle on it must follow, and the arrays stored in it
        # become views of it again
        self.__dict__.update(state)
        if state.get("_pf") is not None:
            share_packed(self)

    def __repr__(self) -> str:
        return (f"<Body {self.faces.shape[0]} faces, bv={self.bv!r}, "
                f"{self.n_nodes} nodes, depth {self.depth}>")


@dataclass(frozen=True, eq=False)
class Contact:
    """Result of :func:`geomkit.collide`.

    Attributes
    ----------
    colliding : bool
    pairs : (k, 2) int64, intersecting (face of a, face of b), sorted; with
        ``all_pairs=False`` at most the first pair found.
    tags : (k, 2) int64, the ``face_tags`` of those faces.
    bv_tests : int, bounding-volume pair tests made by the traversal.
    """

    colliding: bool
    pairs: np.ndarray
    tags: np.ndarray
    bv_tests: int


def _contact(colliding, pairs, tags, bv_tests):
    """A :class:`Contact` without the frozen dataclass ``__init__`` (which costs
    ~2 µs, a tenth of a whole :func:`geomkit.collide` call); same object."""
    c = _new(Contact)
    d = c.__dict__
    d["colliding"] = colliding
    d["pairs"] = pairs
    d["tags"] = tags
    d["bv_tests"] = bv_tests
    return c


_new = object.__new__


@dataclass(frozen=True, eq=False)
class Contacts:
    """Result of :func:`geomkit.collide_many` (one row per pose pair).

    Attributes
    ----------
    colliding : (n,) bool
    n_pairs : (n,) int64, intersecting triangle pairs (1 for a hit when
        ``all_pairs=False``).
    bv_tests : (n,) int64
    """

    colliding: np.ndarray
    n_pairs: np.ndarray
    bv_tests: np.ndarray


@dataclass(frozen=True, eq=False)
class Distance:
    """Result of :func:`geomkit.min_distance`.

    Attributes
    ----------
    distance : float, exact minimum distance of the two triangle sets (0 when they
        intersect); with ``margin > 0`` see ``within_margin``.
    point_a, point_b : (3,) float, closest points in the world frame (on a, on b).
    triangle_a, triangle_b : int, their faces (-1 when no pair was examined).
    bv_tests : int, node-pair lower bounds computed.
    within_margin : bool, ``distance < margin`` (``margin > 0``: the search stops
        at the first such pair, so ``distance`` is then an upper bound below
        ``margin``, not the minimum; otherwise ``distance`` is ``inf``).
    """

    distance: float
    point_a: np.ndarray = field(repr=False)
    point_b: np.ndarray = field(repr=False)
    triangle_a: int
    triangle_b: int
    bv_tests: int
    within_margin: bool


# ------------------------------------------------------------------ building
def build_body(body, mesh, bv="obb", face_tags=None, leaf_size=4, obb_center="covariance"):
    """Fill a :class:`Body`: validate, build the tree, pack it (called by the constructor)."""
    if bv not in BV_KINDS:
        raise InvalidInputError(f"expected one of {sorted(BV_KINDS)}, got {bv!r}", "bv")
    if obb_center not in ("covariance", "regions"):
        raise InvalidInputError(f"expected 'covariance' or 'regions', got {obb_center!r}",
                                "obb_center")
    leaf_size = as_int(leaf_size, "leaf_size", minimum=1)
    if leaf_size > kq.LEAF_BUF:
        raise InvalidInputError(f"must be <= {kq.LEAF_BUF} (the leaf tests hold a leaf's "
                                f"triangles in a fixed buffer), got {leaf_size}", "leaf_size")
    V, F, tags = as_mesh_arrays(mesh)
    if F.shape[0] > kp.MAX_TRIANGLES:
        raise InvalidInputError(f"at most {kp.MAX_TRIANGLES} triangles, got {F.shape[0]}",
                                "mesh")
    if face_tags is not None:
        tags = face_tags
    if tags is None:
        tags = np.zeros(F.shape[0], dtype=np.int64)
    tags = np.asarray(tags)
    if tags.shape != (F.shape[0],) or not np.issubdtype(tags.dtype, np.integer):
        raise InvalidInputError(f"expected ({F.shape[0]},) integers, got shape {tags.shape} "
                                f"dtype {tags.dtype}", "face_tags")
    kind = BV_KINDS[bv]
    order, child, rng, C, R, E, K, depth = kb.build_tree(
        V, F, kind, leaf_size, 4 if obb_center == "regions" else 0)
    body.vertices, body.faces = V, F
    body.face_tags = np.ascontiguousarray(tags, dtype=np.int64)
    body.bv, body.kind, body.leaf_size, body.obb_center = bv, kind, leaf_size, obb_center
    body.order, body.child, body.rng = order, child, rng
    body.C, body.R, body.E = C, R, E
    body.K = K if kind == 2 else _EK
    body.T = kb.leaf_triangles(V, F, order)
    body._pf = body._addr = None
    if kind == 2:
        body.N = _EN
    else:   # one record per node for the traversal (kp.pack_boxes), in one buffer
        _pack(body, kp.pack_boxes(child, rng, C, R, E))
    body.depth, body.n_nodes = int(depth), int(child.shape[0])
    body._world_pose = None      # 14-DOP trees: pose of the cached world refit
    body._world_K = None


def _pack(body, N):
    """One buffer per box tree for the single-call kernel (layout in
    :mod:`geomkit._kernels.bvh_boxes`); the body's ``N``, ``T``, ``order`` and
    ``face_tags`` become views into it (nothing stored twice)."""
    n, m = N.shape[0], body.T.shape[0]
    h = kp.HEADER
    nf = h + 16 * n + 9 * m
    buf = np.zeros(kp.packed_size(n, m))
    bi = buf.view(np.int64)
    bi[:2] = n, m
    buf[h:h + 16 * n] = N.ravel()
    buf[h + 16 * n:nf] = body.T.ravel()
    bi[nf:nf + m] = body.order
    bi[nf + m:nf + 2 * m] = body.face_tags
    body._pf = buf
    share_packed(body)


def share_packed(body):
    """Make the packed buffer ``body._pf`` read-only (the traversal trusts its
    links) and the body's ``N``, ``T``, ``order``, ``face_tags`` read-only views into
    it; also after unpickling, which gives each array its own copy."""
    buf = body._pf
    buf.flags.writeable = False
    n, m = buf[:2].view(np.int64).tolist()
    h = kp.HEADER
    nf = h + 16 * n + 9 * m
    bi = buf.view(np.int64)
    body._addr = buf.ctypes.data     # the batch kernel's handle on it (the body keeps buf)
    body.N = buf[h:h + 16 * n].reshape(n, 16)
    body.T = buf[h + 16 * n:nf].reshape(m, 3, 3)
    body.order = bi[nf:nf + m]
    body.face_tags = bi[nf + m:nf + 2 * m]
