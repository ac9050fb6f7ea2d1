"""Result and body types of :mod:`geomkit.collision.collide` (slim, no algorithms).

:class:`Body` holds a triangle mesh and its flattened bounding-volume hierarchy;
construction hands off to :func:`geomkit.collision.collide.build_body`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Body", "Contact", "Contacts", "Distance"]


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
        from geomkit.collision.collide import build_body
        build_body(self, mesh, bv, face_tags, leaf_size, obb_center)

    def __setstate__(self, state):
        # a copy (pickle, copy.deepcopy) holds its packed buffer at another address:
        # the batch kernel's handle on it must follow, and the arrays stored in it
        # become views of it again
        self.__dict__.update(state)
        if state.get("_pf") is not None:
            from geomkit.collision.collide import _share_packed
            _share_packed(self)

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
