"""Adaptive UV cells of one face: refined, graded, triangulated and measured until every
triangle is within ``tol`` (steps 1, 3 and 4 of :mod:`geomkit.mesh.tessellate`).

* :func:`adaptive_cells` -- the measure-and-split rounds on the lattice cells of
  :mod:`geomkit.mesh.quadtree`; which cells are in the face comes from a ``classify``
  function (0 outside, 1 inside, 2 cut by the trim), so the trim polylines'
  clipping (:meth:`geomkit.mesh.trim_polylines.TrimPolylines.classify`) and the fallback's
  staircase (:mod:`geomkit.mesh.fallback`) share the rounds.
* :func:`clip_triangulate` -- cut cells clipped to the trimmed region and triangulated
  by the constrained Delaunay rule (GEOS via shapely); :func:`clip_grid_cells` the
  same for a grid's rectangles, compiled (:mod:`geomkit._kernels.tess_clip`), GEOS
  taking the cells the kernel leaves.
* :func:`deviation` -- the measurement of step 4.
"""

from __future__ import annotations

import math
import time
import warnings

import numpy as np

from geomkit.mesh import quadtree as qt
from geomkit.mesh.weld import points, weld
from geomkit._kernels.tess import triangle_deviation
from geomkit._kernels.tess_clip import CLIP_DONE, clip_cells
from geomkit._kernels.tess_rings import prepared_rings
from geomkit._kernels.tess_grid import edge_gaps
from geomkit._kernels.tess_lattice import cell_triangles
from geomkit.errors import ToleranceNotMetWarning
from geomkit.nurbs.surface import Surface

CELL_TARGET = 0.9
"""Cells are refined until their measured two-triangle deviation is below
``CELL_TARGET * tol`` (the margin covers the fans of cells with hanging nodes)."""
EXACT_ABOVE = 1.0
"""Samples whose parametric gap exceeds ``EXACT_ABOVE * tol`` get the two one-sided
distances measured instead (see :func:`geomkit._kernels.tess.triangle_deviation`)."""
MAX_HANGING = 2
"""Grading: a cell edge carries at most this many hanging nodes (finer neighbours)."""
MAX_ROUNDS = 60
"""Rounds of measure-and-split; a mesh that still has a triangle above ``tol`` after
them warns (:class:`~geomkit.errors.ToleranceNotMetWarning`).  Typical: 1-5."""


EDGE_T = np.linspace(0.0, 1.0, 17)  # samples along each domain edge


def closed_directions(s: Surface, size: float) -> tuple[bool, bool]:
    """Whether ``s`` is closed in u and in v: its opposite domain edges coincide in 3-D
    within ``1e-10 * size`` at 17 samples each.  With clamped knots the domain's
    corners are the net's corners: when ``S(u0, v0)`` is further than that (plus the
    evaluation's rounding) from both ``S(u1, v0)`` and ``S(u0, v1)``, the first sample
    of each edge pair fails, so such a surface (open both ways) is answered without
    sampling (the same answer)."""
    eps = 1e-10 * size
    p, q = s.degree_u, s.degree_v
    ku, kv = s.knots_u, s.knots_v
    if ku[0] == ku[p] and ku[-1] == ku[-p - 1] and kv[0] == kv[q] and kv[-1] == kv[-q - 1]:
        P = s.control_points
        # S at (u0,v0), (u1,v0), (u0,v1), as floats (numpy calls on 3-vectors cost more)
        c00, c10, c01 = P[0, 0].tolist(), P[-1, 0].tolist(), P[0, -1].tolist()
        margin = 2.0 * eps + 1e-12 * float(np.maximum.reduce(np.abs(P), axis=None))
        if _max_gap(c00, c10) > margin and _max_gap(c00, c01) > margin:
            return False, False
    (u0, u1), (v0, v1) = s.domain
    # the u0, u1, v0, v1 edges' samples and their largest differences in one call
    cu, cv = edge_gaps(s.homogeneous, p, q, ku, kv, u0, u1, v0, v1, EDGE_T)
    return bool(cu <= eps), bool(cv <= eps)


def _max_gap(a, b) -> float:
    """``np.abs(a - b).max()`` of two 3-lists of floats (NaN when a difference is)."""
    d = [abs(a[0] - b[0]), abs(a[1] - b[1]), abs(a[2] - b[2])]
    return max(d) if d[0] == d[0] and d[1] == d[1] and d[2] == d[2] else math.nan


def breakpoints(knots: np.ndarray, p: int) -> np.ndarray:
    """The distinct knots of the domain ``knots[p : -p]`` (knot vectors are
    non-decreasing: ``np.unique`` without its sort)."""
    k = knots[p: len(knots) - p]
    keep = np.empty(len(k), dtype=bool)
    keep[0] = True
    np.not_equal(k[1:], k[:-1], out=keep[1:])
    return k[keep]


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
    coords, idx = clip_triangulate(ruv, ring_id, trim)
    return coords, cut[idx]


def clip_triangulate(ruv, ring_id, trim):
    """The cells whose UV rings are ``ruv`` (rows of cell ``ring_id``, counter-clockwise)
    clipped to the trimmed region and triangulated by the constrained Delaunay rule:
    UV triangles (n, 3, 2) counter-clockwise, and the cell of each."""
    import shapely

    polys = shapely.polygons(shapely.linearrings(ruv, indices=ring_id))
    return triangulate_pieces(shapely.intersection(polys, trim.region))


def clip_rectangles(c: np.ndarray, trim, inside_area: float):
    """The trimmed region's pieces in the axis-aligned cells ``c`` (n, 4) ``u0, u1, v0,
    v1`` (cells without hanging nodes).  GEOS's rectangle clipping (~8x faster than
    the overlay on the grid faces of real parts) is kept when its pieces are valid
    and, with the cells wholly inside (``inside_area``), add up to the region's area;
    it can return a wrong sliver where the region's edge runs along a cell edge
    within rounding, and then the overlay (:func:`shapely.intersection`) decides."""
    import shapely

    region = trim.region
    pieces = shapely.lib.clip_by_rect(region, c[:, 0], c[:, 2], c[:, 1], c[:, 3])
    cut_area = float(np.add.reduce((c[:, 1] - c[:, 0]) * (c[:, 3] - c[:, 2])))
    if np.logical_and.reduce(shapely.is_valid(pieces)) and abs(
            inside_area + float(np.add.reduce(shapely.area(pieces))) - region.area) \
            <= 1e-9 * cut_area:
        return pieces
    return shapely.intersection(shapely.box(c[:, 0], c[:, 2], c[:, 1], c[:, 3]), region)


LOOP_AREA_REL = 1e-12
"""Loops of a trim ring enclosing at most this fraction of the domain's area are cut off
before the compiled clip (where trim pieces overlap at their joins)."""


def region_rings(trim) -> tuple:
    """``(P, starts, tiny)``: the trimmed region's rings (:meth:`TrimPolylines.rings
    <geomkit.mesh.trim_polylines.TrimPolylines.rings>`) packed, ring ``i``
    ``P[starts[i]:starts[i+1]]``, and the area below which a loop of theirs is cut off
    (:data:`LOOP_AREA_REL` of the domain's): the arguments of
    :func:`geomkit._kernels.tess_rings.prepared_rings`."""
    rings = trim.rings()
    starts = np.zeros(len(rings) + 1, dtype=np.int64)
    np.add.accumulate(np.array([len(r) for r in rings], dtype=np.int64), out=starts[1:])
    (u0, u1), (v0, v1) = trim.surface.domain
    return (np.ascontiguousarray(np.concatenate(rings) if len(rings) > 1 else rings[0],
                                 dtype=np.float64), starts,
            LOOP_AREA_REL * (u1 - u0) * (v1 - v0))


def clip_grid_cells(c: np.ndarray, trim, inside_area: float):
    """The trimmed region in the axis-aligned cells ``c`` (n, 4) ``u0, u1, v0, v1``
    triangulated by the constrained Delaunay rule: UV triangles (t, 3, 2)
    counter-clockwise and the cell of each, in cell order.  The compiled clip
    (:func:`geomkit._kernels.tess_clip.clip_cells`) takes the cells it can; GEOS
    (:func:`clip_rectangles`) the others; the rings' spurs and loops of at most
    :data:`LOOP_AREA_REL` of the domain go first, as GEOS's valid form drops them
    (:func:`~geomkit._kernels.tess_rings.prepared_rings`).  Kept when the pieces, with
    the cells wholly inside (``inside_area``), add up to the even-odd area of the
    rings; else every cell goes through GEOS."""
    P, starts, dirs, region_area = prepared_rings(*region_rings(trim))
    tri, own, status, area = clip_cells(np.ascontiguousarray(c, dtype=np.float64), P,
                                        starts, dirs)
    cut_area = float(np.add.reduce((c[:, 1] - c[:, 0]) * (c[:, 3] - c[:, 2])))
    left = np.nonzero(status != CLIP_DONE)[0]
    total = inside_area + float(np.add.reduce(area))
    if len(left):
        import shapely

        pieces = shapely.lib.clip_by_rect(trim.region, c[left, 0], c[left, 2], c[left, 1],
                                          c[left, 3])
        if not np.logical_and.reduce(shapely.is_valid(pieces)):
            return triangulate_pieces(clip_rectangles(c, trim, inside_area))
        total += float(np.add.reduce(shapely.area(pieces)))
    if abs(total - region_area) > 1e-9 * cut_area:
        return triangulate_pieces(clip_rectangles(c, trim, inside_area))
    if len(left):
        gtri, gown = triangulate_pieces(pieces)
        tri = np.concatenate([tri, gtri])
        own = np.concatenate([own, left[gown]])
        order = np.argsort(own, kind="stable")
        tri, own = tri[order], own[order]
    return tri, own


def triangulate_pieces(pieces):
    """Pieces of the trimmed region (shapely polygons, one per cell) triangulated by
    the constrained Delaunay rule: UV triangles (n, 3, 2) counter-clockwise, and the
    piece of each."""
    import shapely

    try:
        tri = shapely.constrained_delaunay_triangles(pieces)
    except shapely.errors.GEOSException:
        tri = np.array([_triangulate_piece(g) for g in pieces], dtype=object)
    coords, idx = triangle_coordinates(tri)
    if not len(coords):
        return np.empty((0, 3, 2)), np.empty(0, dtype=np.int64)
    a = coords[:, 1] - coords[:, 0]
    b = coords[:, 2] - coords[:, 0]
    area2 = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    keep = area2 != 0
    coords = coords[keep]
    flip = area2[keep] < 0
    coords[flip] = coords[flip][:, ::-1]
    return coords, idx[keep]


def triangle_coordinates(collections):
    """``(coords (n, 3, 2), index (n,))``: the corners of the triangles (polygons of 4
    ring points, GEOS's triangulation output) in each geometry collection of the array,
    and the collection each came from.  Read with one ``get_coordinates`` call, no
    geometry object per triangle (``get_parts`` made one each: ~40 % of the cut cells'
    triangulation time); the per-triangle route when a part is not such a triangle."""
    import shapely

    xy, idx = shapely.get_coordinates(collections, return_index=True)
    if len(xy) % 4 == 0:
        ring = xy.reshape(-1, 4, 2)
        idx4 = idx.reshape(-1, 4)
        n = int(np.add.reduce(shapely.get_num_geometries(collections)))
        # one closed 4-point ring per part, all parts counted: nothing else in there
        if len(ring) == n and (ring[:, 0] == ring[:, 3]).all() and (idx4 == idx4[:, :1]).all():
            return ring[:, :3, :], idx4[:, 0]
    parts, pidx = shapely.get_parts(collections, return_index=True)
    if not len(parts):
        return np.empty((0, 3, 2)), np.empty(0, dtype=np.int64)
    ext = shapely.get_exterior_ring(parts)
    return shapely.get_coordinates(ext).reshape(-1, 4, 2)[:, :3, :], pidx


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



def deviation(s: Surface, tri_uv: np.ndarray, k: int, tol: float) -> np.ndarray:
    """(n,) measured deviation of UV triangles (n, 3, 2) from ``s`` (step 4)."""
    sub = np.ascontiguousarray(tri_uv)
    out = np.empty(len(sub))
    if len(sub):
        tri_xyz = points(s, sub.reshape(-1, 2)).reshape(-1, 3, 3)
        (u0, u1), (v0, v1) = s.domain
        triangle_deviation(s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                           sub, tri_xyz, k, u0, u1, v0, v1, EXACT_ABOVE * tol, out)
    return out



def adaptive_cells(s: Surface, tol: float, max_angle, max_edge, k: int, m: int, lat,
                   cells: np.ndarray, classify, trim, closed: tuple[bool, bool], size: float,
                   t0: float):
    """Steps 1, 3 and 4 of :mod:`geomkit.mesh.tessellate` on the lattice ``lat``, from
    ``cells``: refine and grade until every cell's better split is estimated within
    ``CELL_TARGET * tol``, triangulate, measure every triangle, split or fan the cells
    holding one above ``tol`` and repeat (at most :data:`MAX_ROUNDS` rounds; a mesh
    still above ``tol`` then warns and states the measured values).

    ``classify(lat, cells) -> (N,) int8`` says which cells are in the face (0 outside,
    1 inside, 2 cut: clipped by ``trim``'s region, :func:`clip_triangulate`); None for
    every cell inside.  Only cells it keeps are refined.
    Returns ``(V, F, UV, dev, tri_uv, stats)`` as the face's part of the mesh."""
    active = (lambda c: classify(lat, c) > 0) if classify is not None else None
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
        state = classify(lat, cells) if classify is not None else np.ones(len(cells), np.int8)
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
            out = deviation(s, sub, k, tol)
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
                      ToleranceNotMetWarning, stacklevel=4)
    V, F, UV, good = weld(s, tri_uv, size, near_uv=bool(np.any(state == 2)))
    stats = {"cells": int(len(cells)), "cut_cells": int(np.count_nonzero(state == 2)),
             "rounds": rounds, "collapsed_dropped": int(np.count_nonzero(~good)),
             "closed_u": closed[0], "closed_v": closed[1],
             "seconds": time.perf_counter() - t0}
    return V, F[good], UV, dev[good], tri_uv[good], stats
