"""The trimmed planes of a whole part in one constrained triangulation.

A trimmed surface that is an affine map of its parameters
(:func:`geomkit.mesh.trim_polylines.affine_map`) is meshed without cells: its trimmed
region's polygon is triangulated keeping every polyline edge, and the flat triangles
*are* the surface (deviation 0; step 5 of :mod:`geomkit.mesh.tessellate`).  Face by face
that costs a few shapely calls each (~0.4 ms a face); here all the planes of a call
are built as polygons in one ``shapely.polygons`` call (the largest loop the shell, the
others its holes; the domain rectangle the shell when a loop is that rectangle) and
triangulated in one ``shapely.constrained_delaunay_triangles`` call.

A polygon GEOS finds invalid (loops that cross, or nest deeper than shell and holes:
the even-odd region of the loops is then not that polygon) or that GEOS cannot
triangulate is left to the face-by-face path, which builds the even-odd region itself.
"""

from __future__ import annotations

import time

import numpy as np

from geomkit.mesh.cells import triangle_coordinates
from geomkit._kernels.tess_cdt import triangulate_polygons
from geomkit._kernels.tess_loops import (faces_points, loop_areas, plane_rings,
                                        polygon_meshes)
from geomkit._kernels.tess_trim import speed_bounds
from geomkit.mesh.trim_polylines import (TrimPolylines, affine_flags, domain_eps, flat_surfaces,
                                         largest_loop, loop_points, within)
from geomkit.nurbs.trims import starts

__all__ = ["planar_batch"]


CDT_SMALL = 64
"""Planar polygons of at most this many points are triangulated by the compiled
constrained Delaunay triangulation (:func:`geomkit._kernels.tess_cdt.triangulate_polygons`);
larger ones, and those it does not take, by GEOS."""


def _triangulate(polys: np.ndarray, coords, ring_size, ring_face, use):
    """Constrained Delaunay triangles of the polygons ``polys[use]`` (made of the rings
    ``coords``/``ring_size``, ring ``r`` in polygon ``ring_face[r]``, shell first):
    ``(coords (n, 3, 2), polygon of each (n,) ascending, failed (m,) bool)``.  The small
    ones compiled in one call, the others by GEOS in one call, one polygon at a time
    when GEOS refuses the batch (the polygons it still refuses are ``failed``)."""
    import shapely

    ring_size = np.asarray(ring_size, dtype=np.int64)
    rstart = np.zeros(len(ring_size) + 1, dtype=np.int64)
    np.add.accumulate(ring_size, out=rstart[1:])
    first = np.searchsorted(np.asarray(ring_face), np.arange(len(polys) + 1))
    ctri, cidx, taken = triangulate_polygons(
        np.ascontiguousarray(coords, dtype=np.float64), rstart, first[use], first[use + 1],
        CDT_SMALL)
    failed = np.zeros(len(use), dtype=bool)
    rest = np.nonzero(~taken)[0]
    if not len(rest):
        return ctri, cidx, failed
    todo = polys[use[rest]]
    try:
        tri = shapely.constrained_delaunay_triangles(todo)
    except shapely.errors.GEOSException:
        tri = np.empty(len(todo), dtype=object)
        for j, g in enumerate(todo):
            try:
                tri[j] = shapely.constrained_delaunay_triangles(g)
            except shapely.errors.GEOSException:
                tri[j] = shapely.GeometryCollection()
                failed[rest[j]] = True
    gtri, gidx = triangle_coordinates(tri)
    tri = np.concatenate([ctri, gtri])
    idx = np.concatenate([cidx, rest[gidx]])
    order = np.argsort(idx, kind="stable")
    return tri[order], idx[order], failed


def planar_batch(surfaces, chord_tol: float, sizes=None, cross_knots: bool = False,
                 pair_tol: float | None = None) -> dict:
    """``{index: (uv (n, 2), faces (m, 3), S(uv) (n, 3), seconds)}`` for the trimmed surfaces of
    ``surfaces`` that are affine maps of their parameters, their regions triangulated
    together (see the module docstring): faces counter-clockwise in UV, every
    boundary edge (trim polylines within ``chord_tol`` in 3-D, or ``pair_tol`` when given:
    :func:`~geomkit.mesh.trim_polylines.loop_points`; domain edges) kept, no
    point added, vertices sorted by u then v; ``{index: False}`` for a trimmed surface
    that is not such a map.  A surface not listed (untrimmed, an empty region, a
    polygon GEOS refuses, trim polylines that raise) is left to the face-by-face path.
    ``seconds``: its share of the batch's time; ``sizes``: each surface's ``size``, if
    known."""
    import shapely

    t0 = time.perf_counter()
    out = {}
    planes = []
    trimmed = [i for i, s in enumerate(surfaces) if s.trim]
    flags = affine_flags([surfaces[i] for i in trimmed],
                         [surfaces[i].size if sizes is None else sizes[i] for i in trimmed])
    for i, affine in zip(trimmed, flags):
        if affine:
            planes.append(i)
        else:
            out[i] = False  # not a plane: the face-by-face path need not ask again
    if not planes:
        return out
    P = [surfaces[i] for i in planes]
    flat = flat_surfaces(P)
    try:  # every plane's trim polylines and rings in one call each
        coords, ring_size, ring_face, kept = _rings(P, chord_tol, cross_knots, flat,
                                                    pair_tol)
        faces = [planes[f] for f in kept.tolist()]
    except Exception:  # noqa: BLE001 - face by face: the face path reports a failure
        faces, coords, ring_size, ring_face = _rings_one_by_one(surfaces, planes, chord_tol,
                                                                cross_knots, pair_tol)
    if not faces:
        return out
    ring_geoms = shapely.linearrings(coords, indices=np.repeat(np.arange(len(ring_size)),
                                                                ring_size))
    polys = shapely.polygons(ring_geoms, indices=ring_face)
    ok = shapely.is_valid(polys) & ~shapely.is_empty(polys)
    use = np.nonzero(ok)[0]
    if not len(use):
        return out
    tri, idx, failed = _triangulate(polys, coords, ring_size, ring_face, use)
    # counter-clockwise, no triangle of zero area (as planar_trimmed); each polygon's
    # vertices sorted by (u, v)
    n = len(use)
    uv_all, F_all, vstart, tstart = polygon_meshes(tri, idx, n)
    # the vertices S(uv), every face's in one call: uv_all holds the triangulated
    # planes' blocks in the order of `planes` (faces and use keep it), the others none
    rank = {i: r for r, i in enumerate(planes)}
    used = [faces[j] for j in use.tolist()]
    counts = np.zeros(len(planes), dtype=np.int64)
    counts[[rank[i] for i in used]] = np.diff(vstart)
    P_all = faces_points(*flat[:7], uv_all, starts(counts))
    share = (time.perf_counter() - t0) / len(faces)
    vs, ts, fail = vstart.tolist(), tstart.tolist(), failed.tolist()
    for j, i in enumerate(used):
        if fail[j] or ts[j] == ts[j + 1]:
            continue
        a, b = vs[j], vs[j + 1]
        out[i] = (uv_all[a:b], F_all[ts[j]:ts[j + 1]], P_all[a:b], share)
    return out


def _rings(P, chord_tol: float, cross_knots: bool, flat, pair_tol=None) -> tuple:
    """The rings of the planes ``P`` (surfaces with trims) for shapely's constructors,
    from every plane's trim polylines in one call (:func:`loop_points`):
    ``(coords, ring_size, ring_face, kept)`` of :func:`~geomkit._kernels.tess_loops.
    plane_rings`, each face's rings those of ``TrimPolylines(...).rings()``: the loops
    that are not the domain rectangle (:func:`domain_loops`' test on all loops at once,
    the speed bounds of the planes with a loop within its ``1e-6`` bound in one call),
    the rectangle first when a loop was it, else the
    loop of the largest area (:func:`loop_areas`, the areas' rounding bounded: when two
    are too close to tell, :func:`largest_loop` decides as ``rings()`` does)."""
    pts, start, gaps, face_loop = loop_points(P, chord_tol, True, cross_knots, flat=flat,
                                              pair_tol=pair_tol)
    d = flat[7]
    size_uv = np.maximum(d[:, 1] - d[:, 0], d[:, 3] - d[:, 2])
    perimeter = d[:, 1] - d[:, 0] + d[:, 3] - d[:, 2]
    nloops = np.diff(face_loop)
    of = np.repeat(np.arange(len(P)), nloops)  # each loop's face
    kept = np.ones(len(gaps), dtype=bool)
    near = within(gaps[:, 0], gaps[:, 1], (1e-6 * size_uv)[of], perimeter[of])
    if near.any():  # domain_loops' test, the speed bounds of those faces in one call
        ask = np.unique(of[near])
        Pw, pw_off, nets, U, u_off, V, v_off, _ = flat
        xyz = np.concatenate([s.control_points for s in P], axis=None).reshape(-1, 3)
        speed = speed_bounds(xyz, Pw, pw_off, nets, U, u_off, V, v_off, ask)
        eps = np.zeros(len(P))
        eps[ask] = [domain_eps(a, chord_tol, b) for a, b in zip(size_uv[ask].tolist(),
                                                                speed.tolist())]
        f = of[near]
        kept[near] = ~within(gaps[near, 0], gaps[near, 1], eps[f], perimeter[f])
    rect = np.add.reduceat(kept.astype(np.int64), face_loop[:-1]) < nloops
    shell = face_loop[:-1].copy()
    multi = np.nonzero(~rect & (nloops > 1))[0].tolist()
    fl = face_loop.tolist()
    if multi:
        area, err = loop_areas(pts, start)
        for f in multi:
            a, b = fl[f], fl[f + 1]
            k = int(np.argmax(area[a:b]))
            low = area[a + k] - err[a + k]
            others = np.delete(np.arange(a, b), k)
            if not (area[others] + err[others] < low).all():  # too close to tell
                bounds = start[a:b + 1].tolist()
                k = largest_loop([pts[x:y] for x, y in zip(bounds[:-1], bounds[1:])])
            shell[f] = a + k
    return plane_rings(pts, start, face_loop, kept, rect, shell, d)


def _rings_one_by_one(surfaces, planes, chord_tol: float, cross_knots: bool,
                      pair_tol=None) -> tuple:
    """:func:`_rings` face by face (``TrimPolylines(...).rings()``), a face whose
    polylines raise left out: ``(faces, coords, ring_size, ring_face)``."""
    faces, rings = [], []
    for i in planes:
        try:
            r = TrimPolylines(surfaces[i], chord_tol, affine=True, cross_knots=cross_knots,
                              pair_tol=pair_tol).rings()
        except Exception:  # noqa: BLE001 - the face-by-face path reports it
            continue
        if min(len(p) for p in r) < 4:  # not a ring: left to the face-by-face path
            continue
        faces.append(i)
        rings.append(r)
    if not faces:
        return faces, None, None, None
    ring_size = [len(p) for r in rings for p in r]
    return (faces, np.concatenate([p for r in rings for p in r]), ring_size,
            np.repeat(np.arange(len(faces)), [len(r) for r in rings]))
