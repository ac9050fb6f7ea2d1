"""Vertices of a face's triangles: UV corners merged into shared vertices on the surface.

* :func:`points` -- ``S(uv)`` for parameters the tessellator made (no validation).
* :func:`weld` -- triangles given by their UV corners become vertices and faces: equal
  UVs merged (and, optionally, UVs within rounding of each other: trim crossings
  computed in two cells), then vertices on the domain boundary that coincide in 3-D
  (poles, closed seams); the triangles that collapse are dropped (compiled:
  :mod:`geomkit._kernels.tess_weld`).
* :func:`weld_grid` -- the same for a tensor grid of cells, from the grid's indices.
"""

from __future__ import annotations

import numpy as np

from geomkit.tolerances import WELD_REL
from geomkit._kernels.surface import surface_points_range, surface_points
from geomkit._kernels.tess_grid import grid_vertices
from geomkit._kernels.tess_weld import close_pairs, unique_uv, weld_merge
from geomkit.nurbs.surface import Surface

SERIAL_POINTS = 2048
"""Surface points evaluated in the calling thread up to this count (a thread-pool
dispatch costs ~0.1 ms on an idle machine, milliseconds on a busy one; 2,048 points
cost ~0.2 ms)."""


def points(s: Surface, uv: np.ndarray) -> np.ndarray:
    """S(uv) for (n, 2) parameters already in the domain (no validation: the callers
    make them; :func:`geomkit.nurbs.evaluation.evaluate` checks user input)."""
    uv = np.ascontiguousarray(uv, dtype=np.float64)
    out = np.empty((uv.shape[0], 3))
    if uv.shape[0] <= SERIAL_POINTS:  # in this thread: a dispatch costs more
        surface_points_range(0, uv.shape[0], s.homogeneous, s.degree_u, s.degree_v,
                              s.knots_u, s.knots_v, uv, out)
    else:
        surface_points(s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v, uv, out)
    return out



def weld(s: Surface, tri_uv: np.ndarray, size: float, near_uv: bool = True, corners=None):
    """Vertices, faces and per-vertex UV; merges equal UVs (and, with ``near_uv``,
    UVs within rounding of each other: trim crossings computed in two cells), then
    coincident boundary vertices in 3-D (poles, seams); drops the triangles that
    collapse.  The sort, the pairs and the merge are compiled
    (:func:`geomkit._kernels.tess_weld.unique_uv`, :func:`~geomkit._kernels.tess_weld.weld_merge`);
    the surface points come between them.  ``corners``: :func:`weld_corners` of ``tri_uv``
    (``near_uv``), if made."""
    (u0, u1), (v0, v1) = s.domain
    uniq, inv, pairs, P = corners if corners is not None else weld_corners(s, tri_uv, near_uv)
    dom = max(u1 - u0, v1 - v0)
    return weld_merge(P, uniq, inv, pairs, u0, u1, v0, v1, 1e-12 * dom, WELD_REL * size,
                      WELD_DIRECTION)


def weld_corners(s: Surface, tri_uv: np.ndarray, near_uv: bool = True):
    """``(uniq, inv, pairs, P)``: the distinct UV corners of the triangles ``tri_uv``
    (n, 3, 2) sorted by u then v, each corner's index among them, (``near_uv``) the
    pairs of distinct corners within rounding of each other, and their surface points
    (``P[inv]`` is ``S`` at every corner, bit for bit)."""
    (u0, u1), (v0, v1) = s.domain
    # crossing points computed in two neighbouring cells may differ by rounding
    dom = max(u1 - u0, v1 - v0)
    uniq, inv, pairs = unique_uv(np.ascontiguousarray(tri_uv.reshape(-1, 2), dtype=np.float64),
                                 near_uv, 1e-13 * dom, NEAR_DIRECTION)
    return uniq, inv, pairs, points(s, uniq)


NEAR_DIRECTION = np.array([0.6, 0.8])  # |w| = 1, oblique to the UV axes: UV pairs


def merge(P, uniq, inv, pairs):
    """Vertices ``P`` / ``uniq`` merged along ``pairs`` (k, 2) (each component keeps
    its first member), faces ``inv`` (3m,) renumbered and the mask of faces with three
    distinct corners."""
    n = len(uniq)
    if not len(pairs):  # nothing to merge
        F = inv.reshape(-1, 3)
        good = (F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])
        return P, F, uniq, good
    root = components(n, pairs)
    first = np.flatnonzero(root == np.arange(n))  # each component's first member
    label = np.searchsorted(first, root)
    F = label.ravel()[inv].reshape(-1, 3)
    good = (F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])
    return P[first], F, uniq[first], good


def components(n: int, pairs: np.ndarray) -> np.ndarray:
    """(n,) the smallest member of each node's connected component of the undirected
    graph with edges ``pairs`` (k, 2): minimum-label propagation with pointer jumping,
    a few numpy rounds for the short chains a weld has (scipy's sparse components cost
    ~0.2 ms a call in building the matrix alone)."""
    root = np.arange(n)
    a, b = pairs[:, 0], pairs[:, 1]
    while True:
        ra, rb = root[a], root[b]
        if np.array_equal(ra, rb):
            return root
        m = np.minimum(ra, rb)
        np.minimum.at(root, ra, m)  # the larger root points at the smaller
        np.minimum.at(root, rb, m)
        while True:  # pointer jumping: every node to its root
            nxt = root[root]
            if np.array_equal(nxt, root):
                break
            root = nxt


WELD_DIRECTION = np.array([0.35, 0.48, 0.8])  # |w| < 1, oblique to the axes and planes


def boundary_pairs(P, bnd, size):
    """Pairs of the vertices ``bnd`` (domain-boundary indices) closer than
    ``WELD_REL * size`` in 3-D."""
    if len(bnd) < 2:
        return np.empty((0, 2), np.int64)
    r = WELD_REL * size
    Q = np.ascontiguousarray(P[bnd], dtype=np.float64)
    # the points sorted by their projections on a unit-or-shorter direction: a pair
    # within r projects within r plus the projections' rounding (a dot product of 3
    # terms errs by at most ~5 ulp of max |Q| each, so 1e-14 max |Q| and a factor 2 on
    # r are ample) (:func:`geomkit._kernels.tess_weld.close_pairs`)
    return bnd[close_pairs(Q, WELD_DIRECTION, r,
                           2.0 * r + 1e-14 * np.maximum.reduce(np.abs(Q), axis=None))]


def weld_grid(s: Surface, u: np.ndarray, v: np.ndarray, diag: np.ndarray, size: float):
    """:func:`weld` (``near_uv=False``) of the triangles of a tensor grid
    (:func:`geomkit.mesh.quadtree.uniform_grid`: lines ``u`` x ``v``, two triangles per cell
    by ``diag``), from the grid's indices: its vertices, sorted by u then v, are the
    sorted unique corners.  The vertices, corners, domain-edge vertices and the
    boundary pairs' pre-test in one compiled call
    (:func:`geomkit._kernels.tess_grid.grid_vertices`).  None when the lines are not
    strictly increasing."""
    (u0, u1), (v0, v1) = s.domain
    eps = 1e-12 * max(u1 - u0, v1 - v0)
    ok, P, UV, inv, bnd, near = grid_vertices(
        s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v,
        np.ascontiguousarray(u, dtype=np.float64), np.ascontiguousarray(v, dtype=np.float64),
        np.ascontiguousarray(diag, dtype=np.int64), u0, u1, v0, v1, eps, WELD_REL * size)
    if not ok:
        return None
    pairs = boundary_pairs(P, bnd, size) if near else ()
    if not len(pairs):  # distinct grid corners: every face kept
        return P, inv.reshape(-1, 3), UV, np.ones(len(inv) // 3, dtype=bool)
    return merge(P, UV, inv, pairs)
