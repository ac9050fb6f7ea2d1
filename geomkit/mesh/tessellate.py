"""Tessellation of trimmed NURBS surfaces to a chord tolerance that holds (Paper 1).

Method (Paper 1 step 1, then beyond it):

1. **Cells.**  The UV domain starts as one cell per knot span (creases stay on cell
   edges) and is refined adaptively — in u, in v or both, as the cell's chord
   errors say — until each cell's best two-triangle split is estimated within
   ``0.8 tol`` (:mod:`geomkit.mesh.quadtree`), and within ``max_edge`` / ``max_angle``
   when given.  Flat regions stay coarse.
2. **Trim boundary.**  Each trim curve becomes a polyline whose 3-D chords
   ``S(C(t_i))``–``S(C(t_i+1))`` deviate at most ``tol / 2`` from the image under ``S``
   of the UV chord (the mesh boundary runs through UV-chord points where it crosses
   cell edges), and at most ``tol / 2``, or ``0.9 tol`` minus that deviation, from the
   exact boundary curve ``S(C(t))``, so that the mesh boundary lies within ``tol`` of
   the curve (on a plane, whose UV chords map onto the 3-D chords, the chords lie
   within ``0.9 tol`` of the curve) — checked at interior samples; a segment whose curve
   bends away from it by more than 0.3 times its length is split too, so a loop small
   against ``tol`` keeps three edges or more; a failing segment is split into as many
   equal parameter parts
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
   boundary is the trim polylines of step 2.  The trimmed planes of one call are
   triangulated together, in one GEOS call (:mod:`geomkit.mesh.planes`).
6. **Grids first.**  A surface untrimmed, or trimmed only by its domain rectangle
   (a STEP face bounded by its surface's own edges: most cylinders and cones of real
   parts; :func:`geomkit.mesh.trim_polylines.domain_rectangle_only`), is tried as one
   uniform grid of cells (:func:`geomkit.mesh.quadtree.uniform_grid`, every cell's
   two triangles measured).  A trimmed curved surface is tried on the grid of the
   estimates (:func:`geomkit.mesh.quadtree.planned_grid`): cells inside the region keep
   two triangles, cells the trim crosses are clipped as in step 3, and only the kept
   triangles are measured (feet inside the face); a failing grid is made again for a
   target scaled by the excess.  The first such grid of a face of at most
   :data:`FIRST_CELLS` cells is planned, clipped, measured and welded in one compiled
   call (:func:`geomkit._kernels.tess_face.trimmed_first`, the same mesh as the steps
   make).  A grid that is refused or has
   a triangle above ``tol`` leaves the surface to the adaptive cells of steps 1-4.
7. **Clean-up.**  Vertices on the domain boundary that coincide in 3-D (poles,
   closed seams) are merged and the triangles they collapse dropped, so a sphere is
   watertight and no triangle has zero area; faces are counter-clockwise in UV, i.e.
   oriented with ``S_u x S_v``.
8. **Fallback.**  A face whose route above raises (GEOS refusing a clip or a
   constrained triangulation, a numeric failure) is meshed again by the fallback route
   (:mod:`geomkit.mesh.fallback`: the untrimmed surface's cells kept inside the trim
   loops, every triangle measured as in step 4), with a
   :class:`~geomkit.errors.FaceFailedWarning` and ``stats["fallback"]`` naming the cause;
   only a face that fails there too is left out (``stats["failed"]``), or, for a single
   surface, raises :class:`~geomkit.errors.MeshingError`.

Steps 1, 3 and 4 live in :mod:`geomkit.mesh.cells`, the vertex merging of step 7 in
:mod:`geomkit.mesh.weld`.
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from geomkit.mesh import quadtree as qt
from geomkit.mesh.cells import (CELL_TARGET, EDGE_T, EXACT_ABOVE, adaptive_cells, breakpoints,
                                clip_grid_cells, closed_directions, deviation, region_rings)
from geomkit.mesh.fallback import fallback_face
from geomkit.mesh.planes import planar_batch
from geomkit.mesh.weld import (NEAR_DIRECTION, WELD_DIRECTION, boundary_pairs, merge, points,
                               weld, weld_corners, weld_grid)
from geomkit._kernels.tess_face import (FACE_EMPTY, FACE_FAILED, FACE_OK, FACE_REFUSED,
                                       trimmed_first)
from geomkit._kernels.tess_grid import GRID_OK, whole_grid
from geomkit._kernels.tess_lattice import group_deviation
from geomkit.mesh.trim_polylines import (TrimPolylines, affine_map, domain_rectangle_only,
                                         line_rectangle, packed_trims, planar_trimmed)
from geomkit.tolerances import WELD_REL
from geomkit.validate import as_int
from geomkit.errors import FaceFailedWarning, InvalidInputError, MeshingError
from geomkit.mesh.mesh import Mesh
from geomkit.nurbs.surface import Surface, as_surfaces

__all__ = ["tessellate", "SAMPLES_PER_EDGE", "CELL_TARGET", "TRIM_TARGET", "TRIM_PAIR"]

SAMPLES_PER_EDGE = 6
"""``k``: barycentric samples per triangle edge in the deviation measurement."""
TRIM_TARGET = 0.5
"""Trim polylines are refined until their 3-D chords are within ``TRIM_TARGET * tol`` of
the images of their UV chords (and, for the projector's mesh, of the curve)."""
TRIM_PAIR = 0.9
"""... and until a chord lies within ``TRIM_TARGET * tol`` of the curve, or its
distances from the curve and from its UV chord's image add up to at most
``TRIM_PAIR * tol`` (:func:`geomkit.mesh.trim_polylines.loop_points`; the mesh boundary
within ``tol`` of the curve at the samples; on a plane, where the second is 0, the rest
of ``tol`` covers the curve between them: a plane's hole at 1.0 came 1.004 tol from
its chords)."""
PLANNED_TRIES = 3
"""Grids of the estimates tried for a trimmed surface before the measured grid
(:func:`_trimmed_grid`)."""
FIRST_CELLS = 256
"""A trimmed face's first grid of the estimates is clipped, measured and welded in one
call (:func:`geomkit._kernels.tess_face.trimmed_first`, in this thread) up to this many
cells; a larger one by the steps of :func:`_trimmed_grid` (its measure threaded)."""
GRID_CELLS = 4096
"""Untrimmed surfaces whose first estimate asks for at most this many cells are tried
as one uniform grid first (:func:`geomkit.mesh.quadtree.uniform_grid`): small meshes then
cost a few kernel calls instead of the adaptive rounds' per-call overhead."""



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
    return points(s, UV), F, UV, np.zeros(2), UV[F]


def _planar_trimmed(s: Surface, tol: float, size: float, t0: float,
                    trim_target: float = TRIM_TARGET, cross_knots: bool = False,
                    pair_tol: float | None = None):
    """A trimmed surface that is an affine map of its domain, meshed without cells
    (:func:`geomkit.mesh.trim_polylines.planar_trimmed`); None for any other surface (or when
    the trimmed region is empty: the general path reports that)."""
    if affine_map(s, size) is None:
        return None
    uv, F = planar_trimmed(TrimPolylines(s, trim_target * tol, affine=True,
                                         cross_knots=cross_knots, pair_tol=pair_tol))
    if not len(F):
        return None
    used = np.zeros(len(uv), dtype=bool)  # corners of triangles inside the region only
    used[F.ravel()] = True
    if not used.all():
        index = np.cumsum(used) - 1
        uv, F = uv[used], index[F]
    return points(s, uv), F, uv, np.zeros(len(F)), uv[F], \
        _planar_stats(time.perf_counter() - t0)


def _planar_stats(seconds: float) -> dict:
    return {"cells": 0, "cut_cells": 0, "rounds": 0, "collapsed_dropped": 0,
            "closed_u": False, "closed_v": False, "planar_trimmed": True,
            "seconds": seconds}


def _trimmed_grid(s: Surface, trim: TrimPolylines, ub, vb, m: int, k: int, tol: float,
                  size: float, t0: float):
    """A trimmed surface on one uniform grid: cells inside the region keep their two
    triangles, cells the trim crosses are clipped and triangulated (step 3).  First the
    grid of the estimates (:func:`geomkit.mesh.quadtree.planned_grid`; inside cells split
    along the diagonal of the smaller estimate), every kept triangle measured within
    its cell's group (:func:`_grouped_deviation`: feet inside the face), the target
    scaled down by the excess and the grid made again while a triangle fails (at most
    :data:`PLANNED_TRIES` grids); then the grid whose cells are measured alone
    (:func:`geomkit.mesh.quadtree.uniform_grid`), its clipped triangles measured alone.
    None when the grid is refused or a triangle measures above ``tol``: the adaptive
    cells take over."""
    target = CELL_TARGET * tol
    grouped = True
    closed = closed_directions(s, size)
    # the first grid in one call (the same mesh as the steps below make of it)
    first = _trimmed_first(s, trim, ub, vb, m, target, k, tol, size, closed)
    status, worst = first[0], first[-1]
    if status == FACE_OK:
        _, V, F, UV, good, dev, tri_uv, n_cells, n_cut, _ = first
        return V, F[good], UV, dev[good], tri_uv[good], _trimmed_stats(
            n_cells, n_cut, good, closed, True, t0)
    if status in (FACE_REFUSED, FACE_EMPTY):
        return None
    tries = PLANNED_TRIES
    if status == FACE_FAILED:  # the steps below go on from the second grid
        target *= max(0.25, target / worst) if np.isfinite(worst) else 0.25
        tries -= 1
    for _ in range(tries):
        plan = qt.planned_grid(s, ub, vb, m, target, GRID_CELLS, closed)
        if plan is None:
            return None
        cells, diag = plan
        tri_uv, _ = qt._grid_triangles(cells, np.zeros(len(cells)), diag)
        cut, tri_uv, _, cuv, cown = _clip_grid(trim, cells, tri_uv, None)
        tri_uv, dev, worst, corners = _grouped(s, tri_uv, cuv, cown, k, tol, bool(len(cut)))
        if tri_uv is not None:
            break
        # errors fall with the square of the cell size: aim the next grid below target
        target *= max(0.25, target / worst) if np.isfinite(worst) else 0.25
    else:
        grouped = False
        corners = None
        grid = qt.uniform_grid(s, ub, vb, m, k, tol, CELL_TARGET * tol, EXACT_ABOVE * tol,
                               GRID_CELLS, closed=closed)
        if grid is None:
            return None
        tri_uv, dev, cells, _ = grid
        cut, tri_uv, dev, cuv, cown = _clip_grid(trim, cells, tri_uv, dev)
        if cuv is not None:
            cdev = deviation(s, cuv, k, tol)
            if not (cdev <= tol).all():
                return None
            tri_uv = np.concatenate([tri_uv, cuv])
            dev = np.concatenate([dev, cdev])
    if not len(tri_uv):
        return None
    V, F, UV, good = weld(s, tri_uv, size, near_uv=bool(len(cut)), corners=corners)
    return V, F[good], UV, dev[good], tri_uv[good], _trimmed_stats(
        len(cells), len(cut), good, closed, grouped, t0)


def _trimmed_stats(n_cells, n_cut, good, closed, grouped: bool, t0: float) -> dict:
    """A trimmed grid face's ``stats``: its cells, cut cells, the faces the weld
    dropped (not ``good``), whether it is closed in u and v and was measured in
    groups, and its time since ``t0``."""
    return {"cells": int(n_cells), "cut_cells": int(n_cut), "rounds": 1,
            "collapsed_dropped": int(np.count_nonzero(~good)),
            "closed_u": closed[0], "closed_v": closed[1], "trimmed_grid": True,
            "grouped": grouped, "seconds": time.perf_counter() - t0}


def _trimmed_first(s: Surface, trim: TrimPolylines, ub, vb, m: int, target: float, k: int,
                   tol: float, size: float, closed):
    """:func:`geomkit._kernels.tess_face.trimmed_first` of the face: its first grid of
    the estimates clipped, measured and welded in one call, as the steps of
    :func:`_trimmed_grid` make it."""
    (u0, u1), (v0, v1) = s.domain
    dom = max(u1 - u0, v1 - v0)
    CP, cstarts, n_cut = trim.classify_rings()
    return trimmed_first(s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v, ub,
                         vb, m, float(target), GRID_CELLS, FIRST_CELLS,
                         qt.fold_lines(s, None, closed), CP, cstarts, n_cut,
                         *region_rings(trim), k, float(tol), EXACT_ABOVE * tol,
                         1e-13 * dom, NEAR_DIRECTION, u0, u1, v0, v1, 1e-12 * dom,
                         WELD_REL * size, WELD_DIRECTION)


def _clip_grid(trim: TrimPolylines, cells, tri_uv, dev):
    """A grid's cells (N, 4) against the trimmed region: ``(cut, tri_uv, dev, cuv,
    cown)``, the indices of the cut cells, the two triangles (and deviations, if
    given) of each cell inside, the cut cells' pieces triangulated and the piece of each
    (None when no cell is cut)."""
    state = trim.classify_uv(cells)
    cut = np.nonzero(state == 2)[0]
    keep = (state == 1).repeat(2)  # two triangles per cell, in cell order
    tri_uv = tri_uv[keep]
    if dev is not None:
        dev = dev[keep]
    cuv = cown = None
    if len(cut):
        inside = cells[state == 1]
        cuv, cown = clip_grid_cells(cells[cut], trim, float(np.add.reduce(
            (inside[:, 1] - inside[:, 0]) * (inside[:, 3] - inside[:, 2]))))
    return cut, tri_uv, dev, cuv, cown


def _grouped(s: Surface, tri_uv, cuv, cown, k: int, tol: float, near_uv: bool):
    """The inside cells' triangle pairs ``tri_uv`` and the cut cells' clipped triangles
    ``cuv`` (of piece ``cown``) together, measured by :func:`_grouped_deviation`:
    ``(tri_uv, dev, worst, corners)``, or ``(None, None, worst, None)`` when a triangle
    is above ``tol`` (``worst``: the largest deviation, NaN if one is); ``corners``:
    their :func:`geomkit.mesh.weld.weld_corners` (``near_uv``), whose points the
    measure takes and the weld then reuses."""
    n = len(tri_uv) // 2
    group = np.arange(n).repeat(2)
    if cuv is not None and len(cuv):
        if not (cown[1:] >= cown[:-1]).all():  # GEOS lists pieces in order: rarely
            order = np.argsort(cown, kind="stable")
            cuv, cown = cuv[order], cown[order]
        cg = np.zeros(len(cown), dtype=np.int64)  # each piece's rank among the pieces
        np.add.accumulate(cown[1:] != cown[:-1], dtype=np.int64, out=cg[1:])
        tri_uv = np.concatenate([tri_uv, cuv])
        group = np.concatenate([group, n + cg])
    corners = weld_corners(s, tri_uv, near_uv) if len(tri_uv) else None
    dev = _grouped_deviation(s, tri_uv, group, k, tol,
                             None if corners is None else corners[3][corners[1]])
    if not (dev <= tol).all():
        return None, None, float(np.max(dev)) if len(dev) else np.nan, None
    return tri_uv, dev, float(np.max(dev)) if len(dev) else 0.0, corners


def _grouped_deviation(s: Surface, tri_uv, group, k: int, tol: float, xyz=None):
    """(n,) measured deviation of UV triangles in consecutive groups ``group`` (n,),
    each group one cell's part of the face
    (:func:`geomkit._kernels.tess_lattice.group_deviation`); ``xyz`` (3n, 3): the
    corners' surface points, if made."""
    out = np.empty(len(tri_uv))
    if not len(tri_uv):
        return out
    sub = np.ascontiguousarray(tri_uv)
    xyz = points(s, sub.reshape(-1, 2)) if xyz is None else xyz
    xyz = xyz.reshape(-1, 3, 3)
    starts = np.searchsorted(group, np.arange(int(group[-1]) + 2)).astype(np.int64)
    group_deviation(s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v, sub, xyz,
                    np.ascontiguousarray(group, dtype=np.int64), starts, k,
                    EXACT_ABOVE * tol, out)
    return out


def _box_grid(s: Surface, box, ub, vb, m: int, k: int, tol: float, size: float,
              t0: float):
    """A face that is its surface restricted to a UV rectangle ``box``
    (:meth:`geomkit.mesh.trim_polylines.TrimPolylines.rectangle`) as one uniform grid
    over the box (:func:`geomkit.mesh.quadtree.uniform_grid`, feet measured inside the
    box): no clipping, the box's edges are the mesh boundary.  None when the grid is
    refused."""
    a0, a1, b0, b1 = box
    ub = np.concatenate([[a0], ub[(ub > a0) & (ub < a1)], [a1]])
    vb = np.concatenate([[b0], vb[(vb > b0) & (vb < b1)], [b1]])
    closed = closed_directions(s, size)
    grid = qt.uniform_grid(s, ub, vb, m, k, tol, CELL_TARGET * tol, EXACT_ABOVE * tol,
                           GRID_CELLS, box=box, pair=True, closed=closed)
    if grid is None:
        return None
    tri_uv, dev, cells, (u, v, diag) = grid
    welded = weld_grid(s, u, v, diag, size)
    V, F, UV, good = welded if welded is not None else weld(s, tri_uv, size, near_uv=False)
    (u0, u1), (v0, v1) = s.domain
    stats = {"cells": int(len(cells)), "cut_cells": 0, "rounds": 1,
             "collapsed_dropped": int(np.count_nonzero(~good)),
             "closed_u": closed[0] and (a0, a1) == (u0, u1),
             "closed_v": closed[1] and (b0, b1) == (v0, v1), "box_grid": True,
             "seconds": time.perf_counter() - t0}
    return V, F[good], UV, dev[good], tri_uv[good], stats


def _whole_grid(s: Surface, k: int, tol: float, size: float, t0: float):
    """A face that is its whole surface as the first uniform grid of
    :func:`geomkit.mesh.quadtree.uniform_grid` (``pair``), welded as
    :func:`geomkit.mesh.weld.weld_grid` does, in one compiled call
    (:func:`geomkit._kernels.tess_grid.whole_grid`): ``(face, None)``, or ``(None,
    (closed, first))`` when that grid is not kept (uniform_grid goes on from it)."""
    (status, tri_uv, dev, cells, welded, P, UV, inv, bnd, near, closed_u, closed_v,
     first) = whole_grid(s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v, k,
                         float(tol), CELL_TARGET * tol, EXACT_ABOVE * tol, GRID_CELLS,
                         qt.SMALL_GRID, True, WELD_REL * size, 1e-10 * size, EDGE_T)
    if status != GRID_OK:
        return None, ((bool(closed_u), bool(closed_v)), first)
    if not welded:
        V, F, UV, good = weld(s, tri_uv, size, near_uv=False)
    else:
        pairs = boundary_pairs(P, bnd, size) if near else ()
        if len(pairs):
            V, F, UV, good = merge(P, UV, inv, pairs)
        else:  # distinct grid corners: every face kept
            V, F, good = P, inv.reshape(-1, 3), None
    return _grid_face(V, F, UV, dev, tri_uv, good, cells,
                      (bool(closed_u), bool(closed_v)), t0), None


def _grid_face(V, F, UV, dev, tri_uv, good, cells, closed, t0: float):
    """A whole face's uniform grid as the face's part of the mesh: the faces ``good``
    (None: all) kept, and its stats."""
    dropped = 0 if good is None else len(good) - int(np.count_nonzero(good))
    stats = {"cells": int(len(cells)), "cut_cells": 0, "rounds": 1,
             "collapsed_dropped": dropped, "closed_u": closed[0], "closed_v": closed[1],
             "uniform_grid": True, "seconds": time.perf_counter() - t0}
    if not dropped:  # every face kept: no copies
        return V, F, UV, dev, tri_uv, stats
    return V, F[good], UV, dev[good], tri_uv[good], stats


def _tessellate_one(s: Surface, tol: float, max_angle, max_edge, k: int,
                    trim_target: float = TRIM_TARGET, fallback: str | None = None,
                    planar=None, size: float | None = None, cross_knots: bool = False,
                    trim_pair: float | None = None):
    """One face's part of the mesh, ``(V, F, UV, dev, tri_uv, stats)``: the fast paths
    (planes, grids), then the adaptive cells.  With ``fallback`` (why this route failed
    for the face) the fallback route instead (:func:`geomkit.mesh.fallback.fallback_face`);
    with ``planar``, the face's triangles from :func:`geomkit.mesh.planes.planar_batch`
    (False: it found the surface is not a plane); ``size``: ``s.size`` if known;
    ``trim_pair``: the trim polylines' :data:`TRIM_PAIR` (None: each of their chord
    errors within ``trim_target * tol``)."""
    pair_tol = None if trim_pair is None else trim_pair * tol
    if fallback is not None:
        return fallback_face(s, tol, max_angle, max_edge, k, trim_target, fallback, pair_tol,
                             cross_knots)
    if planar:
        uv, F, P, seconds = planar
        return P, F, uv, np.zeros(len(F)), uv[F], _planar_stats(seconds)
    t0 = time.perf_counter()
    size = s.size if size is None else size
    if not s.trim and max_angle is None and max_edge is None:
        flat = _affine_plane(s, size)
        if flat is not None:
            return flat + ({"cells": 1, "cut_cells": 0, "rounds": 0, "collapsed_dropped": 0,
                            "closed_u": False, "closed_v": False, "affine_plane": True,
                            "seconds": time.perf_counter() - t0},)
    # a plane's normals agree: max_angle holds (planar False: the batch found no plane)
    if s.trim and max_edge is None and planar is None:
        planar = _planar_trimmed(s, tol, size, t0, trim_target, cross_knots, pair_tol)
        if planar is not None:
            return planar
    # trims that are only the domain rectangle (a STEP face bounded by its surface's
    # own edges: most cylinders and cones of real parts) leave the whole domain; the
    # cell path drops that loop too, so the untrimmed paths give the same guarantee
    packed = packed_trims(s) if s.trim else None
    whole = not s.trim or domain_rectangle_only(s, trim_target * tol, packed)
    ub = breakpoints(s.knots_u, s.degree_u)
    vb = breakpoints(s.knots_v, s.degree_v)
    m = max(5, 2 * max(s.degree_u, s.degree_v) + 1)
    if not whole and max_angle is None and max_edge is None:
        # a loop of straight UV pieces around a rectangle: the box grid without polylines
        box = line_rectangle(s, trim_target * tol, packed)
        if box is not None:
            gridded = _box_grid(s, box, ub, vb, m, k, tol, size, t0)
            if gridded is not None:
                return gridded
    trim = None if whole else TrimPolylines(s, trim_target * tol, packed=packed,
                                            cross_knots=cross_knots, pair_tol=pair_tol)
    if trim is not None and not trim.loops:
        whole, trim = True, None
    if whole:
        trim = None
    if whole and max_angle is None and max_edge is None:
        face, again = _whole_grid(s, k, tol, size, t0)
        if face is not None:
            return face
        closed, first = again
        # the first grid failed or is big: the Python steps go on from it
        grid = qt.uniform_grid(s, ub, vb, m, k, tol, CELL_TARGET * tol, EXACT_ABOVE * tol,
                               GRID_CELLS, pair=True, closed=closed, first=first)
        if grid is not None:
            tri_uv, dev, cells, (u, v, diag) = grid
            welded = weld_grid(s, u, v, diag, size)
            V, F, UV, good = welded if welded is not None else \
                weld(s, tri_uv, size, near_uv=False)
            return _grid_face(V, F, UV, dev, tri_uv, good, cells, closed, t0)
    if trim is not None and max_angle is None and max_edge is None:
        box = trim.rectangle()
        if box is not None:
            gridded = _box_grid(s, box, ub, vb, m, k, tol, size, t0)
            if gridded is not None:
                return gridded
        gridded = _trimmed_grid(s, trim, ub, vb, m, k, tol, size, t0)
        if gridded is not None:
            return gridded
    lat = qt.Lattice(ub, vb)
    cells = lat.roots()
    return adaptive_cells(s, tol, max_angle, max_edge, k, m, lat, cells,
                          trim.classify if trim is not None else None, trim,
                          closed_directions(s, size), size, t0)


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
        ``stats["surfaces"][i]`` describes face i's route; a face meshed by the
        fallback route has ``"fallback"`` (why the primary route failed) and
        ``"fallback_overhang"``, a face left out ``"failed"`` (both with a
        :class:`~geomkit.errors.FaceFailedWarning`).

    Raises
    ------
    MeshingError
        A single surface that neither route can mesh, or no surface meshed.
    """
    return tessellate_with_target(surfaces, tol, max_angle, max_edge, samples_per_edge,
                                  TRIM_TARGET, cross_knots=True, trim_pair=TRIM_PAIR)


def _mesh_face(i: int, s: Surface, args: tuple, planar=None, size=None,
               cross_knots: bool = False, trim_pair: float | None = None):
    """Face ``i``'s part of the mesh by the primary route, else by the fallback route
    (a :class:`~geomkit.errors.FaceFailedWarning` says which face and why): ``(part,
    None)``, or ``(None, why)`` when both routes fail."""
    try:
        return _tessellate_one(s, *args, planar=planar, size=size,
                               cross_knots=cross_knots, trim_pair=trim_pair), None
    except Exception as exc:  # noqa: BLE001 - GEOS and numeric failures: the fallback
        why = f"{type(exc).__name__}: {exc}"
    name = f"surface {i}" + (f" ({s.name})" if s.name else "")
    try:
        part = _tessellate_one(s, *args, fallback=why, trim_pair=trim_pair,
                               cross_knots=cross_knots)
    except Exception as exc:  # noqa: BLE001 - reported by the caller
        return None, f"{why}; the fallback failed too ({type(exc).__name__}: {exc})"
    warnings.warn(f"{name} meshed by the fallback route (untrimmed cells kept inside its "
                  f"trim loops, overhang {part[5]['fallback_overhang']:.3g}; deviation "
                  f"measured as always): {why}", FaceFailedWarning, stacklevel=4)
    return part, None


def tessellate_with_target(surfaces, tol, max_angle, max_edge, samples_per_edge,
                           trim_target, cross_knots: bool = False,
                           trim_pair: float | None = None) -> Mesh:
    """:func:`tessellate` with the trim polylines' chord error target (a fraction of
    ``tol``) chosen: the projector's candidate mesh asks for finer ones (its bounds
    carry this error).  ``cross_knots``: trim polyline edges may run across a trim
    piece's smooth knots (:class:`~geomkit.mesh.trim_polylines.TrimPolylines`;
    :func:`tessellate` does); without, each edge lies on one knot span of its piece
    (the projector's certificate boxes locate an edge on one trim segment).
    ``trim_pair``: the trim polylines' :data:`TRIM_PAIR` (:func:`tessellate`'s); None:
    each chord within ``trim_target * tol`` of the curve and of its UV chord's image."""
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
    args = (tol, max_angle, max_edge, k, trim_target)
    if len(surfaces) == 1:  # one surface: its arrays as they are, no concatenation
        part, why = _mesh_face(0, surfaces[0], args, cross_knots=cross_knots,
                               trim_pair=trim_pair)
        if part is None:
            raise MeshingError(f"the surface could not be triangulated ({why})")
        V, F, UV, dev, tuv, st = part
        return Mesh(V, F.astype(np.int64, copy=False), UV, np.zeros(len(V), dtype=np.int32),
                    np.zeros(len(F), dtype=np.int32), dev, tol, {"surfaces": [st]},
                    np.ascontiguousarray(tuv))
    # the trimmed planes together: one constrained triangulation
    sizes = [s.size for s in surfaces]  # once a face (the batch and the face path)
    planes = (planar_batch(surfaces, trim_target * tol, sizes, cross_knots,
                           None if trim_pair is None else trim_pair * tol)
              if max_edge is None else {})
    Vs, Fs, UVs, ds, fuv, stats = [], [], [], [], [], []
    kept, nv, nf = [], [], []  # the faces meshed, their vertex and triangle counts
    offset = 0
    for i, s in enumerate(surfaces):
        part, why = _mesh_face(i, s, args, planes.get(i), sizes[i], cross_knots, trim_pair)
        if part is None:  # one face never sinks the model: named in the stats
            name = f"surface {i}" + (f" ({s.name})" if s.name else "")
            warnings.warn(f"{name} left out of the mesh: {why}", FaceFailedWarning,
                          stacklevel=3)
            stats.append({"failed": why})
            continue
        V, F, UV, dev, tuv, st = part
        fuv.append(tuv)
        Vs.append(V)
        Fs.append(F + offset)
        UVs.append(UV)
        kept.append(i)
        nv.append(len(V))
        nf.append(len(F))
        ds.append(dev)
        stats.append(st)
        offset += len(V)
    if not Vs:
        raise MeshingError("no surface could be triangulated: "
                           + "; ".join(st["failed"] for st in stats[:3]))
    kept = np.array(kept, dtype=np.int32)
    return Mesh(np.concatenate(Vs), np.concatenate(Fs).astype(np.int64), np.concatenate(UVs),
                np.repeat(kept, nv), np.repeat(kept, nf), np.concatenate(ds), tol,
                {"surfaces": stats}, np.ascontiguousarray(np.concatenate(fuv)))
