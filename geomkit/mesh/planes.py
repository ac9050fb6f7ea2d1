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
from geomkit._kernels.tess_loops import faces_points
from geomkit.mesh.trim_polylines import (TrimPolylines, _starts, affine_map, flat_surfaces,
                                         loop_polylines)

__all__ = ["planar_batch"]


def _triangulate(polys: np.ndarray):
    """Constrained Delaunay triangles of each polygon: ``(coords (n, 3, 2), polygon of
    each (n,), failed (m,) bool)``; all in one call, one polygon at a time when GEOS
    refuses the batch (the polygons it still refuses are ``failed``)."""
    import shapely

    failed = np.zeros(len(polys), dtype=bool)
    try:
        tri = shapely.constrained_delaunay_triangles(polys)
    except shapely.errors.GEOSException:
        tri = np.empty(len(polys), dtype=object)
        for j, g in enumerate(polys):
            try:
                tri[j] = shapely.constrained_delaunay_triangles(g)
            except shapely.errors.GEOSException:
                tri[j] = shapely.GeometryCollection()
                failed[j] = True
    coords, idx = triangle_coordinates(tri)
    return coords, idx, failed


def planar_batch(surfaces, chord_tol: float, sizes=None, cross_knots: bool = False) -> dict:
    """``{index: (uv (n, 2), faces (m, 3), S(uv) (n, 3), seconds)}`` for the trimmed surfaces of
    ``surfaces`` that are affine maps of their parameters, their regions triangulated
    together (see the module docstring): faces counter-clockwise in UV, every
    boundary edge (trim polylines within ``chord_tol`` in 3-D, domain edges) kept, no
    point added, vertices sorted by u then v; ``{index: False}`` for a trimmed surface
    that is not such a map.  A surface not listed (untrimmed, an empty region, a
    polygon GEOS refuses, trim polylines that raise) is left to the face-by-face path.
    ``seconds``: its share of the batch's time; ``sizes``: each surface's ``size``, if
    known."""
    import shapely

    t0 = time.perf_counter()
    faces, rings = [], []
    out = {}
    planes = []
    for i, s in enumerate(surfaces):
        if not s.trim:
            continue
        if affine_map(s, s.size if sizes is None else sizes[i]) is None:
            out[i] = False  # not a plane: the face-by-face path need not ask again
            continue
        planes.append(i)
    if not planes:
        return out
    flat = flat_surfaces([surfaces[i] for i in planes])
    try:  # every plane's trim polylines in one call
        lines = loop_polylines([surfaces[i] for i in planes], chord_tol, True, cross_knots,
                               flat=flat)
    except Exception:  # noqa: BLE001 - face by face below: the face path reports it
        lines = [None] * len(planes)
    for i, polylines in zip(planes, lines):
        try:
            trim = TrimPolylines(surfaces[i], chord_tol, affine=True, cross_knots=cross_knots,
                                 polylines=polylines)
        except Exception:  # noqa: BLE001 - the face-by-face path reports it
            continue
        r = trim.rings()
        if min(len(p) for p in r) < 4:  # not a ring: left to the face-by-face path
            continue
        faces.append(i)
        rings.append(r)
    if not faces:
        return out
    ring_sizes = [len(p) for r in rings for p in r]
    coords = np.concatenate([p for r in rings for p in r])
    ring_geoms = shapely.linearrings(coords, indices=np.repeat(np.arange(len(ring_sizes)),
                                                                ring_sizes))
    owner = np.repeat(np.arange(len(faces)), [len(r) for r in rings])
    polys = shapely.polygons(ring_geoms, indices=owner)
    ok = shapely.is_valid(polys) & ~shapely.is_empty(polys)
    use = np.nonzero(ok)[0]
    if not len(use):
        return out
    tri, idx, failed = _triangulate(polys[use])
    # counter-clockwise, no triangle of zero area (as planar_trimmed)
    a = tri[:, 1] - tri[:, 0]
    b = tri[:, 2] - tri[:, 0]
    area2 = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    keep = area2 != 0
    tri, idx, area2 = tri[keep], idx[keep], area2[keep]
    flip = area2 < 0
    tri[flip] = tri[flip][:, ::-1]
    # unique corners per polygon, sorted by (polygon, u, v)
    corners = tri.reshape(-1, 2)
    cown = np.repeat(idx, 3)
    order = np.lexsort((corners[:, 1], corners[:, 0], cown))
    c, o = corners[order], cown[order]
    new = np.ones(len(c), dtype=bool)
    new[1:] = (o[1:] != o[:-1]) | (c[1:, 0] != c[:-1, 0]) | (c[1:, 1] != c[:-1, 1])
    inv = np.empty(len(c), dtype=np.int64)
    inv[order] = np.cumsum(new) - 1
    uv_all, uv_own = c[new], o[new]
    n = len(use)
    vstart = np.searchsorted(uv_own, np.arange(n + 1))
    tstart = np.searchsorted(idx, np.arange(n + 1))
    F_all = inv.reshape(-1, 3) - vstart[idx][:, None]
    # the vertices S(uv), every face's in one call: uv_all holds the triangulated
    # planes' blocks in the order of `planes` (faces and use keep it), the others none
    rank = {i: r for r, i in enumerate(planes)}
    counts = np.zeros(len(planes), dtype=np.int64)
    counts[[rank[faces[use[j]]] for j in range(n)]] = np.diff(vstart)
    P_all = faces_points(*flat[:7], np.ascontiguousarray(uv_all), _starts(counts))
    share = (time.perf_counter() - t0) / len(faces)
    for j in range(n):
        if failed[j] or tstart[j] == tstart[j + 1]:
            continue
        a, b = vstart[j], vstart[j + 1]
        out[faces[use[j]]] = (np.ascontiguousarray(uv_all[a:b]), F_all[tstart[j]:tstart[j + 1]],
                              P_all[a:b], share)
    return out
