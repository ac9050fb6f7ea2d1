"""Tessellation of trimmed NURBS surfaces to a chord tolerance that holds (Paper 1).

Method (Paper 1 step 1, then beyond it):

1. **Cells.**  The UV domain starts as one cell per knot span (creases stay on cell
   edges) and is refined adaptively — in u, in v or both, as the cell's chord
   errors say — until each cell's best two-triangle split is estimated within
   ``0.8 tol`` (:mod:`geomkit.mesh.quadtree`), and within ``max_edge`` / ``max_angle``
   when given.  Flat regions stay coarse.
2. **Trim boundary.**  Each trim curve becomes a polyline whose 3-D chords
   ``S(C(t_i))``–``S(C(t_i+1))`` deviate at most ``tol / 2`` from the exact boundary
   curve ``S(C(t))``, and from the image under ``S`` of the UV chord (the mesh
   boundary runs through UV-chord points where it crosses cell edges) — checked at
   interior samples; a failing segment is split into as many equal parameter parts
   as its measured error predicts (:mod:`geomkit._kernels.tess_trim`, one kernel
   call per trim piece).
3. **Triangles.**  A cell untouched by the trim becomes two triangles (the diagonal
   with the smaller deviation), or, when finer neighbours put hanging nodes on its
   edges, a fan around its centre — so there are no cracks between levels.  A cell
   the trim crosses is clipped against the trimmed region (its inside corners, its
   edge crossings and the trim points inside it) and triangulated by the
   constrained Delaunay rule, keeping the trim edges (GEOS via shapely).
4. **Measured guarantee.**  Every triangle is sampled against the exact surface at
   ``(k+1)(k+2)/2`` barycentric points (``k = 6`` by default); cells holding a
   triangle above ``tol`` are split and the mesh rebuilt, until every triangle passes.  The
   reported ``face_deviation`` / ``max_deviation`` are these measurements: the
   parametric gap ``|S(uv) - T(uv)|``, an upper bound of the distance both ways at
   each sample.
5. **Planes.**  A surface that is an affine map of its parameters (the net is the
   affine image of its Greville abscissae, equal weights) is exact on any UV
   triangle: untrimmed it is its two corner triangles; trimmed, the region's
   polygon (the trim polylines) is triangulated once, without cells, by the
   constrained Delaunay rule (:mod:`geomkit.mesh.trim_polylines`).  Deviation 0; the
   boundary is the trim polylines of step 2.
6. **Grids first.**  A surface untrimmed, or trimmed only by its domain rectangle
   (a STEP face bounded by its surface's own edges: most cylinders and cones of real
   parts; :func:`geomkit.mesh.trim_polylines.domain_rectangle_only`), is tried as one
   uniform grid of cells (:func:`geomkit.mesh.quadtree.uniform_grid`, every cell's
   two triangles measured).  A trimmed curved surface is tried on such a grid too:
   cells inside the region keep their measured triangles, cells the trim crosses are
   clipped as in step 3 and their triangles measured.  A grid that is refused or has
   a triangle above ``tol`` leaves the surface to the adaptive cells of steps 1-4.
7. **Clean-up.**  Vertices on the domain boundary that coincide in 3-D (poles,
   closed seams) are merged and the triangles they collapse dropped, so a sphere is
   watertight and no triangle has zero area; faces are counter-clockwise in UV, i.e.
   oriented with ``S_u x S_v``.
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from geomkit.tolerances import WELD_REL
from geomkit.mesh import quadtree as qt
from geomkit._kernels.surface import surface_points_range, surface_points
from geomkit._kernels.tess import triangle_deviation
from geomkit._kernels.tess_lattice import cell_triangles
from geomkit.mesh.trim_polylines import (TrimPolylines, affine_map, domain_rectangle_only,
                                         planar_trimmed)
from geomkit.validate import as_int
from geomkit.errors import (FaceFailedWarning, GeomkitError, InvalidInputError, MeshingError,
                            ToleranceNotMetWarning)
from geomkit.mesh.mesh import Mesh
from geomkit.nurbs.surface import Surface, as_surfaces

__all__ = ["tessellate", "SAMPLES_PER_EDGE", "CELL_TARGET", "TRIM_TARGET"]

SAMPLES_PER_EDGE = 6
"""``k``: barycentric samples per triangle edge in the deviation measurement."""
CELL_TARGET = 0.9
"""Cells are refined until their measured two-triangle deviation is below
``CELL_TARGET * tol`` (the margin covers the fans of cells with hanging nodes)."""
TRIM_TARGET = 0.5
"""Trim polylines are refined until their 3-D chord error is below ``TRIM_TARGET * tol``."""
EXACT_ABOVE = 1.0
"""Samples whose parametric gap exceeds ``EXACT_ABOVE * tol`` get the two one-sided
distances measured instead (see :func:`geomkit._kernels.tess.triangle_deviation`)."""
MAX_HANGING = 2
"""Grading: a cell edge carries at most this many hanging nodes (finer neighbours)."""
GRID_CELLS = 4096
"""Untrimmed surfaces whose first estimate asks for at most this many cells are tried
as one uniform grid first (:func:`geomkit.mesh.quadtree.uniform_grid`): small meshes then
cost a few kernel calls instead of the adaptive rounds' per-call overhead."""
SERIAL_POINTS = 2048
"""Surface points evaluated in the calling thread up to this count (a thread-pool
dispatch costs ~0.1 ms on an idle machine, milliseconds on a busy one; 2,048 points
cost ~0.2 ms)."""
MAX_ROUNDS = 60
"""Rounds of measure-and-split; a mesh that still has a triangle above ``tol`` after
them warns (:class:`~geomkit.errors.ToleranceNotMetWarning`).  Typical: 1-5."""


# ------------------------------------------------------------------ triangles
_EDGE_T = np.linspace(0.0, 1.0, 17)  # samples along each domain edge


def closed_directions(s: Surface, size: float) -> tuple[bool, bool]:
    (u0, u1), (v0, v1) = s.domain
    eps = 1e-10 * size
    v = v0 + (v1 - v0) * _EDGE_T
    u = u0 + (u1 - u0) * _EDGE_T
    uv = np.empty((4, 17, 2))  # the u0, u1, v0, v1 edges, in one evaluation
    uv[0, :, 0], uv[1, :, 0], uv[:2, :, 1] = u0, u1, v
    uv[2, :, 1], uv[3, :, 1], uv[2:, :, 0] = v0, v1, u
    P = _points(s, uv.reshape(-1, 2)).reshape(4, 17, 3)
    cu = np.abs(P[0] - P[1]).max()
    cv = np.abs(P[2] - P[3]).max()
    return bool(cu <= eps), bool(cv <= eps)


def _breakpoints(knots: np.ndarray, p: int) -> np.ndarray:
    """The distinct knots of the domain ``knots[p : -p]`` (knot vectors are
    non-decreasing: ``np.unique`` without its sort)."""
    k = knots[p: len(knots) - p]
    keep = np.empty(len(k), dtype=bool)
    keep[0] = True
    np.not_equal(k[1:], k[:-1], out=keep[1:])
    return k[keep]


def _points(s: Surface, uv: np.ndarray) -> np.ndarray:
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


def _triangulate(s, lat, cells, M, state, trim, closed, centre):
    """UV triangles (M, 3, 2) and the index of the cell each came from."""
    pts = qt.lattice_points(cells[state > 0])
    cu, cv = closed
    if cu or cv:  # mirror seam points so both sides of a closed seam get the same vertices
        if cu:
            on = pts[(pts[:, 0] == 0) | (pts[:, 0] == lat.gu_max)]
            pts = np.concatenate([pts, np.c_[lat.gu_max - on[:, 0], on[:, 1]]])
        if cv:
            on = pts[(pts[:, 1] == 0) | (pts[:, 1] == lat.gv_max)]
            pts = np.concatenate([pts, np.c_[on[:, 0], lat.gv_max - on[:, 1]]])
        keys = qt.unique_ints(pts[:, 1] * qt.KEY + pts[:, 0])
        pts = np.stack([keys % qt.KEY, keys // qt.KEY], axis=1)
    index = qt.EdgeIndex(pts, sorted_rows=True)
    inside = np.nonzero(state == 1)[0]
    c = cells[inside]
    counts = index.counts(c)
    # the measured better diagonal; a cell whose pieces failed: centre fan
    diag = (M[inside, 1] < M[inside, 0]).astype(np.int64)
    diag = np.where(centre[inside], 2, diag)
    sizes = np.where(diag == 2, 4 + counts.sum(axis=1), 2 + counts.sum(axis=1))
    starts = np.zeros(len(c) + 1, dtype=np.int64)
    np.cumsum(sizes, out=starts[1:])
    lat_tris = np.empty((starts[-1], 3, 2), dtype=np.int64)
    kind = np.empty(starts[-1], dtype=np.int8)
    if len(c):
        cell_triangles(index.h, index.v, qt.KEY, np.ascontiguousarray(c), counts, diag,
                       starts, lat_tris, kind)
    owners = np.repeat(inside, sizes)
    uv = np.stack([lat.u(lat_tris[..., 0]), lat.v(lat_tris[..., 1])], axis=-1)
    uv = uv.reshape(-1, 3, 2)
    # a plain half of a cell was measured during refinement
    known = np.where(kind == 0, M[owners, np.minimum(np.repeat(diag, sizes), 1)], np.nan)
    # cut cells: clip against the trimmed region, constrained Delaunay
    cut = np.nonzero(state == 2)[0]
    if len(cut):
        cuv, cown = _triangulate_cut(lat, cells, cut, index, trim)
        uv = np.concatenate([uv, cuv])
        owners = np.concatenate([owners, cown])
        known = np.concatenate([known, np.full(len(cown), np.nan)])
    return uv, owners, known


def _triangulate_cut(lat, cells, cut, index, trim):
    starts, ring = index.rings(cells[cut])
    ruv = np.c_[lat.u(ring[:, 0]), lat.v(ring[:, 1])]
    ring_id = np.repeat(np.arange(len(cut)), np.diff(starts))
    coords, idx = _clip_triangulate(ruv, ring_id, trim)
    return coords, cut[idx]


def _clip_triangulate(ruv, ring_id, trim):
    """The cells whose UV rings are ``ruv`` (rows of cell ``ring_id``, counter-clockwise)
    clipped to the trimmed region and triangulated by the constrained Delaunay rule:
    UV triangles (n, 3, 2) counter-clockwise, and the cell of each."""
    import shapely

    polys = shapely.polygons(shapely.linearrings(ruv, indices=ring_id))
    pieces = shapely.intersection(polys, trim.region)
    try:
        tri = shapely.constrained_delaunay_triangles(pieces)
    except shapely.errors.GEOSException:
        tri = np.array([_triangulate_piece(g) for g in pieces], dtype=object)
    parts, idx = shapely.get_parts(tri, return_index=True)
    if not len(parts):
        return np.empty((0, 3, 2)), np.empty(0, dtype=np.int64)
    ext = shapely.get_exterior_ring(parts)
    coords = shapely.get_coordinates(ext).reshape(-1, 4, 2)[:, :3, :]
    a = coords[:, 1] - coords[:, 0]
    b = coords[:, 2] - coords[:, 0]
    area2 = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    keep = area2 != 0
    coords = coords[keep]
    flip = area2[keep] < 0
    coords[flip] = coords[flip][:, ::-1]
    return coords, idx[keep]


def _triangulate_piece(piece):
    """One cut cell's piece of the trimmed region as triangles, when GEOS's constrained
    triangulation of the batch fails on one of them ("Unable to find a convex corner"
    on nearly collinear trim points): the piece alone, then its valid form, then an
    unconstrained triangulation of its vertices keeping the triangles whose centre is
    inside.  Every triangle is measured afterwards like any other, so the deviation
    bound holds; only the last resort may leave slivers of the piece uncovered."""
    import shapely

    for g in (piece, shapely.make_valid(piece)):
        try:
            return shapely.constrained_delaunay_triangles(g)
        except shapely.errors.GEOSException:
            continue
    tris = shapely.get_parts(shapely.delaunay_triangles(piece))
    keep = [g for g in tris if shapely.contains(piece, shapely.centroid(g))]
    return shapely.GeometryCollection(keep)


class _Measured:
    """Deviations of UV triangles measured in earlier rounds, found again by their
    corner coordinates (the same UV corners are the same flat triangle): a hash of
    the corners' bits, sorted, then an exact comparison of the 6 coordinates."""

    _MIX = np.array([0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9,
                     0xD6E8FEB86659FD93, 0xFF51AFD7ED558CCD, 0xC4CEB9FE1A85EC53],
                    dtype=np.uint64)

    def __init__(self):
        self.h = np.empty(0, dtype=np.uint64)
        self.bits = np.empty((0, 6), dtype=np.int64)
        self.dev = np.empty(0)

    @classmethod
    def _keys(cls, tri_uv):
        bits = np.ascontiguousarray(tri_uv, dtype=np.float64).reshape(-1, 6).view(np.int64)
        u = bits.view(np.uint64) * cls._MIX
        h = u[:, 0] ^ (u[:, 1] >> np.uint64(7)) ^ u[:, 2] ^ (u[:, 3] >> np.uint64(13)) \
            ^ u[:, 4] ^ (u[:, 5] >> np.uint64(29))
        return h, bits

    def get(self, tri_uv) -> np.ndarray:
        """(n,) earlier deviation of each triangle, NaN if not measured before."""
        out = np.full(len(tri_uv), np.nan)
        if not len(self.h) or not len(tri_uv):
            return out
        h, bits = self._keys(tri_uv)
        i = np.minimum(np.searchsorted(self.h, h), len(self.h) - 1)
        hit = (self.h[i] == h) & np.all(self.bits[i] == bits, axis=1)
        out[hit] = self.dev[i[hit]]
        return out

    def add(self, tri_uv, dev) -> None:
        h, bits = self._keys(tri_uv)
        h = np.concatenate([self.h, h])
        order = np.argsort(h, kind="stable")
        self.h = h[order]
        self.bits = np.concatenate([self.bits, bits])[order]
        self.dev = np.concatenate([self.dev, dev])[order]


# ------------------------------------------------------------------ assembly
def _weld(s: Surface, tri_uv: np.ndarray, size: float, near_uv: bool = True):
    """Vertices, faces and per-vertex UV; merges equal UVs (and, with ``near_uv``,
    UVs within rounding of each other: trim crossings computed in two cells), then
    coincident boundary vertices in 3-D (poles, seams); drops the triangles that
    collapse."""
    flat = tri_uv.reshape(-1, 2)
    (u0, u1), (v0, v1) = s.domain
    # crossing points computed in two neighbouring cells may differ by rounding
    dom = max(u1 - u0, v1 - v0)
    z = np.ascontiguousarray(flat).view(np.complex128).ravel()  # (u, v) as u + iv
    uz, inv = np.unique(z, return_inverse=True)  # complex sorts by u, then v
    uniq = np.ascontiguousarray(np.stack([uz.real, uz.imag], axis=1))
    inv = inv.ravel()
    pairs = [_near_pairs(uniq, 1e-13 * dom)] if near_uv else []
    P = _points(s, uniq)
    eps = 1e-12 * dom
    bnd = np.nonzero((uniq[:, 0] <= u0 + eps) | (uniq[:, 0] >= u1 - eps)
                     | (uniq[:, 1] <= v0 + eps) | (uniq[:, 1] >= v1 - eps))[0]
    if len(bnd):
        pairs.append(_boundary_pairs(P, bnd, size))
    pairs = np.concatenate(pairs).reshape(-1, 2) if pairs else np.empty((0, 2), np.int64)
    return _merge(P, uniq, inv, pairs)


def _near_pairs(Q, r):
    """Pairs of the rows of ``Q`` (n, 2) closer than ``r``; the KD-tree only when the
    points' projections on an oblique unit direction, sorted, have a gap below ``2 r``
    plus rounding (a pair within ``r`` projects within ``r``: see
    :func:`_boundary_pairs`)."""
    if len(Q) < 2:
        return np.empty((0, 2), np.int64)
    gaps = np.diff(np.sort(Q @ _NEAR_DIRECTION))
    if (gaps > 2.0 * r + 1e-14 * np.abs(Q).max()).all():
        return np.empty((0, 2), np.int64)
    from scipy.spatial import cKDTree

    return cKDTree(Q).query_pairs(r, output_type="ndarray")


_NEAR_DIRECTION = np.array([0.6, 0.8])  # |w| = 1, oblique to the UV axes


def _merge(P, uniq, inv, pairs):
    """Vertices ``P`` / ``uniq`` merged along ``pairs`` (k, 2) (each component keeps
    its first member), faces ``inv`` (3m,) renumbered and the mask of faces with three
    distinct corners."""
    n = len(uniq)
    if not len(pairs):  # nothing to merge
        F = inv.reshape(-1, 3)
        good = (F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])
        return P, F, uniq, good
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    # representative of each component: its first member
    first = np.full(label.max() + 1, n, dtype=np.int64)
    np.minimum.at(first, label, np.arange(n))
    F = label.ravel()[inv].reshape(-1, 3)
    good = (F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])
    return P[first], F, uniq[first], good


_WELD_DIRECTION = np.array([0.35, 0.48, 0.8])  # |w| < 1, oblique to the axes and planes


def _boundary_pairs(P, bnd, size):
    """Pairs of the vertices ``bnd`` (domain-boundary indices) closer than
    ``WELD_REL * size`` in 3-D."""
    if len(bnd) < 2:
        return np.empty((0, 2), np.int64)
    r = WELD_REL * size
    Q = P[bnd]
    # no pair when the points' projections on a unit-or-shorter direction, sorted, are
    # all further apart than r plus the projections' rounding (a pair within r projects
    # within r; a dot product of 3 terms errs by at most ~5 ulp of max |Q| each, so
    # 1e-14 max |Q| and a factor 2 on r are ample): an open surface skips the tree
    gaps = np.diff(np.sort(Q @ _WELD_DIRECTION))
    if (gaps > 2.0 * r + 1e-14 * np.abs(Q).max()).all():
        return np.empty((0, 2), np.int64)
    from scipy.spatial import cKDTree

    return bnd[cKDTree(Q).query_pairs(r, output_type="ndarray")]


def _weld_grid(s: Surface, u: np.ndarray, v: np.ndarray, diag: np.ndarray, size: float):
    """:func:`_weld` (``near_uv=False``) of the triangles of a tensor grid
    (:func:`geomkit.mesh.quadtree.uniform_grid`: lines ``u`` x ``v``, two triangles per cell
    by ``diag``), from the grid's indices: its vertices, sorted by u then v, are the
    sorted unique corners.  None when the lines are not strictly increasing."""
    if not (np.all(u[1:] > u[:-1]) and np.all(v[1:] > v[:-1])):
        return None
    nu1, nv1 = len(u), len(v)
    UV = np.empty((nu1, nv1, 2))
    UV[..., 0] = u[:, None]
    UV[..., 1] = v
    UV = UV.reshape(-1, 2)
    P = _points(s, UV)
    (u0, u1), (v0, v1) = s.domain
    eps = 1e-12 * max(u1 - u0, v1 - v0)
    on = ((u <= u0 + eps) | (u >= u1 - eps))[:, None] | ((v <= v0 + eps) | (v >= v1 - eps))
    base = (np.arange(nu1 - 1)[:, None] * nv1 + np.arange(nv1 - 1)).ravel()
    off = np.array([[0, nv1, nv1 + 1, 0, nv1 + 1, 1], [0, nv1, 1, nv1, nv1 + 1, 1]])
    inv = (base[:, None] + off[diag]).ravel()
    pairs = _boundary_pairs(P, np.nonzero(on.ravel())[0], size)
    if not len(pairs):  # distinct grid corners: every face kept
        return P, inv.reshape(-1, 3), UV, np.ones(len(inv) // 3, dtype=bool)
    return _merge(P, UV, inv, pairs)


def _affine_plane(s: Surface, size: float):
    """Two triangles for a surface that is an affine map of its domain
    (:func:`geomkit.mesh.trim_polylines.affine_map`: e.g. a parallelogram control net with equal
    weights): the flat triangles *are* the surface, so their deviation is 0.  None for
    any other surface."""
    if affine_map(s, size) is None:
        return None
    (u0, u1), (v0, v1) = s.domain
    UV = np.array([[u0, v0], [u1, v0], [u1, v1], [u0, v1]])
    F = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64)
    return _points(s, UV), F, UV, np.zeros(2), UV[F]


def _planar_trimmed(s: Surface, tol: float, size: float, t0: float,
                    trim_target: float = TRIM_TARGET):
    """A trimmed surface that is an affine map of its domain, meshed without cells
    (:func:`geomkit.mesh.trim_polylines.planar_trimmed`); None for any other surface (or when
    the trimmed region is empty: the general path reports that)."""
    if affine_map(s, size) is None:
        return None
    uv, F = planar_trimmed(TrimPolylines(s, trim_target * tol, affine=True))
    if not len(F):
        return None
    used = np.zeros(len(uv), dtype=bool)  # corners of triangles inside the region only
    used[F.ravel()] = True
    if not used.all():
        index = np.cumsum(used) - 1
        uv, F = uv[used], index[F]
    stats = {"cells": 0, "cut_cells": 0, "rounds": 0, "collapsed_dropped": 0,
             "closed_u": False, "closed_v": False, "planar_trimmed": True,
             "seconds": time.perf_counter() - t0}
    return _points(s, uv), F, uv, np.zeros(len(F)), uv[F], stats


def _deviation(s: Surface, tri_uv: np.ndarray, k: int, tol: float) -> np.ndarray:
    """(n,) measured deviation of UV triangles (n, 3, 2) from ``s`` (step 4)."""
    sub = np.ascontiguousarray(tri_uv)
    out = np.empty(len(sub))
    if len(sub):
        tri_xyz = _points(s, sub.reshape(-1, 2)).reshape(-1, 3, 3)
        (u0, u1), (v0, v1) = s.domain
        triangle_deviation(s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                           sub, tri_xyz, k, u0, u1, v0, v1, EXACT_ABOVE * tol, out)
    return out


def _trimmed_grid(s: Surface, trim: TrimPolylines, ub, vb, m: int, k: int, tol: float,
                  size: float, t0: float):
    """A trimmed surface on one uniform grid (:func:`geomkit.mesh.quadtree.uniform_grid`,
    every cell's better two-triangle split measured within ``tol``): cells inside the
    region keep their two triangles, cells the trim crosses are clipped and
    triangulated (step 3) and their triangles measured.  None when the grid is refused
    or a clipped triangle measures above ``tol``: the adaptive cells take over."""
    grid = qt.uniform_grid(s, ub, vb, m, k, tol, CELL_TARGET * tol, EXACT_ABOVE * tol,
                           GRID_CELLS)
    if grid is None:
        return None
    tri_uv, dev, cells, _ = grid
    state = trim.classify_uv(cells)
    cut = np.nonzero(state == 2)[0]
    keep = np.repeat(state == 1, 2)  # two triangles per cell, in cell order
    tri_uv, dev = tri_uv[keep], dev[keep]
    if len(cut):
        c = cells[cut]
        ruv = np.stack([c[:, [0, 2]], c[:, [1, 2]], c[:, [1, 3]], c[:, [0, 3]]], axis=1)
        cuv, _ = _clip_triangulate(ruv.reshape(-1, 2), np.repeat(np.arange(len(cut)), 4),
                                   trim)
        cdev = _deviation(s, cuv, k, tol)
        if not (cdev <= tol).all():
            return None
        tri_uv = np.concatenate([tri_uv, cuv])
        dev = np.concatenate([dev, cdev])
    if not len(tri_uv):
        return None
    V, F, UV, good = _weld(s, tri_uv, size, near_uv=bool(len(cut)))
    closed = closed_directions(s, size)
    stats = {"cells": int(len(cells)), "cut_cells": int(len(cut)), "rounds": 1,
             "collapsed_dropped": int(np.count_nonzero(~good)),
             "closed_u": closed[0], "closed_v": closed[1], "trimmed_grid": True,
             "seconds": time.perf_counter() - t0}
    return V, F[good], UV, dev[good], tri_uv[good], stats


def _tessellate_one(s: Surface, tol: float, max_angle, max_edge, k: int,
                    trim_target: float = TRIM_TARGET):
    t0 = time.perf_counter()
    size = s.size
    if not s.trim and max_angle is None and max_edge is None:
        flat = _affine_plane(s, size)
        if flat is not None:
            return flat + ({"cells": 1, "cut_cells": 0, "rounds": 0, "collapsed_dropped": 0,
                            "closed_u": False, "closed_v": False, "affine_plane": True,
                            "seconds": time.perf_counter() - t0},)
    if s.trim and max_edge is None:  # a plane's normals agree: max_angle holds
        planar = _planar_trimmed(s, tol, size, t0, trim_target)
        if planar is not None:
            return planar
    # trims that are only the domain rectangle (a STEP face bounded by its surface's
    # own edges: most cylinders and cones of real parts) leave the whole domain; the
    # cell path drops that loop too, so the untrimmed paths give the same guarantee
    whole = not s.trim or domain_rectangle_only(s, trim_target * tol)
    trim = None if whole else TrimPolylines(s, trim_target * tol)
    if trim is not None and not trim.loops:
        whole, trim = True, None
    if whole:
        trim = None
    ub = _breakpoints(s.knots_u, s.degree_u)
    vb = _breakpoints(s.knots_v, s.degree_v)
    m = max(5, 2 * max(s.degree_u, s.degree_v) + 1)
    if whole and max_angle is None and max_edge is None:
        grid = qt.uniform_grid(s, ub, vb, m, k, tol, CELL_TARGET * tol, EXACT_ABOVE * tol,
                               GRID_CELLS)
        if grid is not None:
            tri_uv, dev, cells, (u, v, diag) = grid
            welded = _weld_grid(s, u, v, diag, size)
            V, F, UV, good = welded if welded is not None else \
                _weld(s, tri_uv, size, near_uv=False)
            closed = closed_directions(s, size)
            dropped = len(good) - int(np.count_nonzero(good))
            stats = {"cells": int(len(cells)), "cut_cells": 0, "rounds": 1,
                     "collapsed_dropped": dropped,
                     "closed_u": closed[0], "closed_v": closed[1], "uniform_grid": True,
                     "seconds": time.perf_counter() - t0}
            if not dropped:  # every face kept: no copies
                return V, F, UV, dev, tri_uv, stats
            return V, F[good], UV, dev[good], tri_uv[good], stats
    if trim is not None and max_angle is None and max_edge is None:
        gridded = _trimmed_grid(s, trim, ub, vb, m, k, tol, size, t0)
        if gridded is not None:
            return gridded
    lat = qt.Lattice(ub, vb)
    cells = lat.roots()
    active = (lambda c: trim.classify(lat, c) > 0) if trim is not None else None
    closed = closed_directions(s, size)
    force = None
    known = None
    fanned = set()  # cells whose split failed the measurement: centre fan instead
    fan_ll = np.empty(0, dtype=np.int64)  # their lower-left corners (a quick pre-test)
    measured = _Measured()
    rounds = 0
    bad = np.zeros(0, dtype=bool)
    for rounds in range(1, MAX_ROUNDS + 1):
        cells, E, M = qt.refine(s, lat, cells, CELL_TARGET * tol, m, k,
                                CELL_TARGET * EXACT_ABOVE * tol, max_edge, max_angle, active,
                                force, known)
        cells, E, M = qt.balance(s, lat, cells, E, M, m, k, CELL_TARGET * EXACT_ABOVE * tol,
                                 CELL_TARGET * tol, MAX_HANGING)
        known = (E, M)
        state = trim.classify(lat, cells) if trim is not None else np.ones(len(cells), np.int8)
        centre = np.zeros(len(cells), dtype=bool)
        if fanned:
            cand = np.nonzero(np.isin(cells[:, 0] * qt.KEY + cells[:, 2], fan_ll))[0]
            for i in cand.tolist():
                centre[i] = tuple(cells[i].tolist()) in fanned
        tri_uv, owner, dev = _triangulate(s, lat, cells, M, state, trim, closed, centre)
        todo = np.nonzero(np.isnan(dev))[0]
        if len(todo):
            # triangles measured in an earlier round (same UV corners: same triangle)
            old = measured.get(tri_uv[todo])
            hit = ~np.isnan(old)
            dev[todo[hit]] = old[hit]
            todo = todo[~hit]
        if len(todo):
            sub = np.ascontiguousarray(tri_uv[todo])
            tri_xyz = _points(s, sub.reshape(-1, 2)).reshape(-1, 3, 3)
            out = np.empty(len(todo))
            (u0, u1), (v0, v1) = s.domain
            triangle_deviation(s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                               sub, tri_xyz, k, u0, u1, v0, v1, EXACT_ABOVE * tol, out)
            dev[todo] = out
            measured.add(sub, out)
        bad = dev > tol
        if not bad.any():
            break
        # a failing split or fan first becomes a centre fan (better shaped pieces);
        # a failing centre fan or trimmed cell is split
        force = np.zeros(len(cells), dtype=bool)
        for ci in qt.unique_ints(owner[bad]).tolist():
            key = tuple(cells[ci].tolist())
            if state[ci] == 1 and key not in fanned:
                fanned.add(key)
            else:
                force[ci] = True
        fan_ll = np.array([a * qt.KEY + c for a, _, c, _ in fanned], dtype=np.int64)
    if bad.any():  # never silently: the mesh states the measured values
        warnings.warn(f"tessellate: {int(np.count_nonzero(bad))} triangle(s) still above "
                      f"tol = {tol:.4g} after {rounds} rounds (largest "
                      f"{float(dev.max()):.4g}); face_deviation states them",
                      ToleranceNotMetWarning, stacklevel=3)
    V, F, UV, good = _weld(s, tri_uv, size, near_uv=bool(np.any(state == 2)))
    stats = {"cells": int(len(cells)), "cut_cells": int(np.count_nonzero(state == 2)),
             "rounds": rounds, "collapsed_dropped": int(np.count_nonzero(~good)),
             "closed_u": closed[0], "closed_v": closed[1],
             "seconds": time.perf_counter() - t0}
    return V, F[good], UV, dev[good], tri_uv[good], stats


def tessellate(surfaces, tol: float, max_angle: float | None = None,
               max_edge: float | None = None, samples_per_edge: int = SAMPLES_PER_EDGE) -> Mesh:
    """Triangulate surfaces so that every triangle is within ``tol`` of its surface.

    Parameters
    ----------
    surfaces : Surface or sequence of Surface
    tol : float > 0
        Absolute chord tolerance (model units).
    max_angle : float, optional
        Largest angle in radians between the normals at the corners of a cell.
    max_edge : float, optional
        Largest 3-D edge length of a cell (model units).
    samples_per_edge : int
        ``k`` of the deviation measurement (``(k+1)(k+2)/2`` samples per triangle).

    Returns
    -------
    Mesh
        ``face_deviation[i]`` is the measured largest parametric gap between face i
        and the exact surface (at the samples; the gap bounds the distance either way
        there) and is ``<= tol`` for every face; ``max_deviation`` is their maximum.
        Faces keep the trim edges and are oriented with ``S_u x S_v``; vertices are
        shared across seams and poles of one surface, not between surfaces.
    """
    return tessellate_with_target(surfaces, tol, max_angle, max_edge, samples_per_edge,
                                  TRIM_TARGET)


def tessellate_with_target(surfaces, tol, max_angle, max_edge, samples_per_edge,
                           trim_target) -> Mesh:
    """:func:`tessellate` with the trim polylines' chord error target (a fraction of
    ``tol``) chosen: the projector's candidate mesh asks for finer ones (its bounds
    carry this error)."""
    surfaces = as_surfaces(surfaces)
    try:
        tol = float(tol)
    except (TypeError, ValueError):
        raise InvalidInputError(f"must be a positive number, got {tol!r}", "tol") from None
    if not np.isfinite(tol) or tol <= 0:
        raise InvalidInputError(f"must be a positive finite number, got {tol!r}", "tol")
    checked = {}
    for name, val in (("max_angle", max_angle), ("max_edge", max_edge)):
        if val is not None:
            try:
                val = float(val)
            except (TypeError, ValueError):
                raise InvalidInputError(f"must be a positive number, got {val!r}",
                                        name) from None
            if not np.isfinite(val) or val <= 0:
                raise InvalidInputError(f"must be a positive finite number, got {val!r}", name)
        checked[name] = val
    max_angle, max_edge = checked["max_angle"], checked["max_edge"]
    if max_angle is not None and max_angle >= np.pi:
        raise InvalidInputError(f"must be < pi radians, got {max_angle!r}", "max_angle")
    k = as_int(samples_per_edge, "samples_per_edge", minimum=2)
    trim_target = float(trim_target)
    if len(surfaces) == 1:  # one surface: its arrays as they are, no concatenation
        try:
            V, F, UV, dev, tuv, st = _tessellate_one(surfaces[0], tol, max_angle, max_edge,
                                                     k, trim_target)
        except GeomkitError:
            raise
        except Exception as exc:  # noqa: BLE001 - GEOS and numeric failures, named
            raise MeshingError(f"the surface could not be triangulated "
                               f"({type(exc).__name__}: {exc})") from exc
        return Mesh(V, F.astype(np.int64, copy=False), UV, np.zeros(len(V), dtype=np.int32),
                    np.zeros(len(F), dtype=np.int32), dev, tol, {"surfaces": [st]},
                    np.ascontiguousarray(tuv))
    Vs, Fs, UVs, vs, fs, ds, fuv, stats = [], [], [], [], [], [], [], []
    offset = 0
    for i, s in enumerate(surfaces):
        try:
            V, F, UV, dev, tuv, st = _tessellate_one(s, tol, max_angle, max_edge, k,
                                                     trim_target)
        except Exception as exc:  # noqa: BLE001 - reported: a warning and the stats
            # one face never sinks the model: left out, named in the stats and a warning
            why = f"{type(exc).__name__}: {exc}"
            name = f"surface {i}" + (f" ({s.name})" if s.name else "")
            warnings.warn(f"{name} left out of the mesh: {why}", FaceFailedWarning,
                          stacklevel=3)
            stats.append({"failed": why})
            continue
        fuv.append(tuv)
        Vs.append(V)
        Fs.append(F + offset)
        UVs.append(UV)
        vs.append(np.full(len(V), i, dtype=np.int32))
        fs.append(np.full(len(F), i, dtype=np.int32))
        ds.append(dev)
        stats.append(st)
        offset += len(V)
    if not Vs:
        raise MeshingError("no surface could be triangulated: "
                           + "; ".join(st["failed"] for st in stats[:3]))
    return Mesh(np.concatenate(Vs), np.concatenate(Fs).astype(np.int64), np.concatenate(UVs),
                np.concatenate(vs), np.concatenate(fs), np.concatenate(ds), tol,
                {"surfaces": stats}, np.ascontiguousarray(np.concatenate(fuv)))
