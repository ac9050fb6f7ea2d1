"""Trim boundaries for tessellation, and the direct path for trimmed planes.

* :class:`TrimPolylines` — each trim loop as a UV polyline whose 3-D chords are
  within ``chord_tol`` of the exact boundary curve ``S(C(t))`` (and of the image of
  the UV chord), the trimmed region as a shapely polygon, and the cells' classification
  against them (one compiled call).
* :func:`affine_map` — whether ``S`` is an affine map of its parameters (a B-spline
  net that is the affine image of its Greville abscissae, equal weights): then every
  UV triangle maps to a flat triangle that *is* part of the surface.
* :func:`planar_trimmed` — such a surface with trims is meshed without cells: the
  trimmed region's polygon (the trim polylines, clipped to the domain) is triangulated
  once by the constrained Delaunay rule, keeping every polyline edge.  The triangles
  lie on the surface (deviation 0); the boundary is the trim polylines, whose 3-D
  chord error is the one the cell path has.
"""

from __future__ import annotations

import numpy as np

from geomkit.tolerances import AFFINE_REL
from geomkit._kernels.tess_lattice import classify_cells
from geomkit._kernels.tess_loops import face_loops
from geomkit._kernels.tess_trim import (domain_rectangle_gap, line_rectangle_of, rectangle_of,
                                        speed_bound_of)
from geomkit.nurbs.surface import Surface
from geomkit.nurbs.trims import packed_loops, packed_trims, starts



def domain_loops(surface: Surface, chord_tol: float, gaps) -> list[bool]:
    """Whether each trim loop of ``surface`` is its domain rectangle, from the loops'
    ``(gap, area_gap)`` (:func:`geomkit._kernels.tess_trim.loop_rectangle_gap` of their
    polylines): within :func:`domain_eps` (UV) of the domain's edges and of its area
    (:func:`within`).  The bound of the surface's speed is computed only for a loop
    within ``1e-6`` of the domain's size (``eps`` is at most that)."""
    (u0, u1), (v0, v1) = surface.domain
    size_uv = max(u1 - u0, v1 - v0)
    perimeter = u1 - u0 + v1 - v0
    eps = None
    out = []
    for gap, area_gap in gaps:
        if not within(gap, area_gap, 1e-6 * size_uv, perimeter):
            out.append(False)
            continue
        if eps is None:  # the bound of the surface's speed, only when needed
            eps = domain_eps(size_uv, chord_tol, speed_bound(surface))
        out.append(within(gap, area_gap, eps, perimeter))
    return out


def domain_eps(size_uv, chord_tol: float, speed):
    """How far (UV) a loop may lie from the domain rectangle and be taken for it: the
    sliver between them is within ``eps * speed`` of the loop in 3-D, at most 1e-3 of the
    chord tolerance (files round their pcurves: OCC's closed torus face ends 2e-10
    short of 2 pi), ``eps`` between ``1e-12`` and ``1e-6`` of the domain's size
    ``size_uv`` (floats; ``speed``: :func:`speed_bound`)."""
    return max(min(1e-6 * size_uv, 1e-3 * chord_tol / max(speed, 1e-300)), 1e-12 * size_uv)


def within(gap, area_gap, eps, perimeter):
    """Whether loops of ``(gap, area_gap)`` lie within ``eps`` of the domain rectangle
    of ``perimeter`` (``u1 - u0 + v1 - v0``): every point within ``eps`` of an edge line
    and the area within ``eps * perimeter`` of the rectangle's.  Scalars or arrays."""
    return (gap <= eps) & (area_gap <= eps * perimeter)


class TrimPolylines:
    """Trim loops as UV polylines whose 3-D chords are within ``chord_tol`` (with
    ``pair_tol``: see :func:`loop_points`).

    ``packed``: :func:`packed_trims` of the surface, if the caller made it.
    ``loops``: the closed (k, 2) polylines (read only), the domain rectangle left out
    when a loop is just that rectangle (``domain_loop``); ``polylines``: this surface's
    :func:`loop_polylines`, if the caller made them.  ``region`` (the trimmed region, a
    shapely geometry inside the domain) is built on first use.
    """

    def __init__(self, surface: Surface, chord_tol: float, affine: bool = False,
                 packed=None, cross_knots: bool = False, polylines=None,
                 pair_tol: float | None = None):
        self.surface = surface
        self.cross_knots = cross_knots  # segments may run across smooth knots
        self.chord_tol = chord_tol
        self.affine = affine  # S maps UV chords to 3-D chords: sample the curve only
        self.loops = []
        self.domain_loop = False  # a loop was the domain rectangle (:func:`domain_loops`)
        if polylines is None:
            polylines = loop_polylines([surface], chord_tol, affine, cross_knots,
                                       None if packed is None else [packed],
                                       pair_tol=pair_tol)[0]
        loops, gaps = polylines
        for pts, is_domain in zip(loops, domain_loops(surface, chord_tol, gaps)):
            if is_domain:
                self.domain_loop = True
            else:
                self.loops.append(pts)
        self._region = None
        self._packed_rings = None

    @property
    def region(self):
        if self._region is None:
            import shapely

            region = _polygon(self.rings())
            # loops that cross or nest deeper than shell and holes: the even-odd
            # region of the loops, one at a time
            if not shapely.is_valid(region):
                (u0, u1), (v0, v1) = self.surface.domain
                box = shapely.box(u0, v0, u1, v1)
                region = box if self.domain_loop or not self.loops else None
                for pts in self.loops:
                    poly = shapely.make_valid(shapely.Polygon(pts))
                    region = poly if region is None else shapely.symmetric_difference(region,
                                                                                      poly)
            # the polylines are clipped to the domain: the region lies in the box (not
            # prepared: its users clip and overlay, which prepared geometry does not
            # speed up)
            self._region = region
        return self._region

    def rings(self) -> list[np.ndarray]:
        """The closed rings of the trimmed region when it is one polygon with holes:
        the domain rectangle first when a loop was that rectangle (or there are no
        loops), else the loop of the largest area, then the others (its holes).
        Whether they make a valid polygon is for GEOS to say."""
        loops = self.loops
        if self.domain_loop or not loops:
            (u0, u1), (v0, v1) = self.surface.domain
            return [np.array([[u0, v0], [u1, v0], [u1, v1], [u0, v1], [u0, v0]])] + loops
        if len(loops) == 1:
            return loops
        k = largest_loop(loops)
        return [loops[k]] + loops[:k] + loops[k + 1:]

    def rectangle(self):
        """``(a0, a1, b0, b1)`` when the trimmed region is one axis-aligned UV rectangle
        (one loop, every polyline point on the edge lines of its bounding box and its
        area the box's, both within the ``eps`` of the domain rectangle test: in 3-D
        within ``1e-3 chord_tol``); else None.  Such a face is the surface restricted to
        the box: its boundary is the box's edges (a revolved profile cut at two angles,
        a swept face)."""
        if len(self.loops) != 1 or self.domain_loop:
            return None
        return _rectangle_of(self.loops[0], self.chord_tol, self.surface)

    def classify(self, lat, cells: np.ndarray) -> np.ndarray:
        """(N,) int8 for lattice cells: 0 outside the trimmed region, 1 inside, 2 cut
        by the trim."""
        return self.classify_uv(lat.cells_uv(cells))

    def classify_rings(self) -> tuple:
        """``(P, starts, n_cut)``: the rings :meth:`classify_uv` tests, packed (ring
        ``i``: ``P[starts[i]:starts[i+1]]``; the loops first, ``n_cut`` of them, then
        the domain rectangle when :meth:`rings` has it)."""
        if self._packed_rings is None:
            rings = self.rings()
            # the loops' segments first (the cut test), then the domain rectangle's
            n_cut = len(self.loops)
            if len(rings) > n_cut:  # the domain rectangle leads rings(): move it last
                rings = rings[1:] + rings[:1]
            starts = np.zeros(len(rings) + 1, dtype=np.int64)
            np.add.accumulate(np.array([len(r) for r in rings], dtype=np.int64),
                              out=starts[1:])
            self._packed_rings = (np.ascontiguousarray(np.concatenate(rings)), starts, n_cut)
        return self._packed_rings

    def classify_uv(self, uv: np.ndarray) -> np.ndarray:
        """:meth:`classify` for cells given by their parameters (N, 4) ``u0, u1, v0,
        v1``: cut when a segment of a loop meets the closed cell, else in or out by
        its centre and the even-odd rule over the region's rings, in one compiled call
        (:func:`geomkit._kernels.tess_lattice.classify_cells`)."""
        P, starts, n_cut = self.classify_rings()
        state = np.empty(uv.shape[0], dtype=np.int8)
        if uv.shape[0]:
            classify_cells(P, starts, n_cut, np.ascontiguousarray(uv, dtype=np.float64),
                           state)
        return state


def largest_loop(loops) -> int:
    """The index of the loop of the largest shoelace area (the first of equal ones),
    each area ``|x[:-1] . y[1:] - x[1:] . y[:-1]|`` by numpy's dot products."""
    area = [abs(np.dot(p[:-1, 0], p[1:, 1]) - np.dot(p[1:, 0], p[:-1, 1])) for p in loops]
    return int(np.argmax(area))


def _polygon(rings):
    """``shapely.Polygon(rings[0], rings[1:])`` for closed rings, built by the
    vectorised constructors (the class's per-ring checks cost more than the GEOS
    work on a face's few rings); a ring of fewer than 4 points goes to the class
    (its error)."""
    import shapely

    if min(len(r) for r in rings) < 4:
        return shapely.Polygon(rings[0], rings[1:])
    if len(rings) == 1:
        return shapely.polygons(rings[0])
    geoms = shapely.linearrings(np.concatenate(rings), indices=np.repeat(
        np.arange(len(rings)), [len(r) for r in rings]))
    return shapely.polygons(geoms[0], holes=geoms[1:])


def domain_rectangle_only(surface: Surface, chord_tol: float, packed=None) -> bool:
    """Whether every trim loop of ``surface`` is the domain rectangle as
    :class:`TrimPolylines` judges it (within its ``eps`` of the domain's edges, the
    rectangle's area), decided from the control points without sampling: True only
    when each piece's control polygon runs along the domain's edges (a degree-1 piece:
    each of its segments on one edge line; a curved piece: all its control points on
    one edge line, so the curve, inside their convex hull, is on it too) and the
    loop's control points enclose the rectangle's area (along a line the shoelace sum
    depends only on the ends).  False when unsure: :class:`TrimPolylines` decides.
    The measuring is one kernel call (:func:`geomkit._kernels.tess_trim.
    domain_rectangle_gap`); ``packed``: :func:`packed_trims` of the surface, if made."""
    if not surface.trim:
        return False
    (u0, u1), (v0, v1) = surface.domain
    size_uv = max(u1 - u0, v1 - v0)
    lo, hi = 1e-12 * size_uv, 1e-6 * size_uv  # TrimPolylines' eps lies in [lo, hi]
    CP, _, _, deg, cp_off, _, loop_first = packed or packed_trims(surface)
    worst = domain_rectangle_gap(CP, deg, cp_off, loop_first, u0, u1, v0, v1, hi)
    if worst > hi:
        return False
    if worst <= lo:
        return True
    return worst <= domain_eps(size_uv, chord_tol, speed_bound(surface))


def loop_polylines(surfaces, chord_tol: float, affine: bool, cross_knots: bool,
                   packs=None, flat=None, pair_tol: float | None = None) -> list:
    """Per surface ``(loops, gaps)``: the closed (k, 2) UV polylines of its trim loops
    (read only) and each loop's :func:`geomkit._kernels.tess_trim.loop_rectangle_gap`
    (:func:`loop_points`, split by surface and loop)."""
    pts, start, gaps, face_loop = loop_points(surfaces, chord_tol, affine, cross_knots,
                                              packs, flat, pair_tol)
    bounds = start.tolist()
    loops = [pts[a:b] for a, b in zip(bounds[:-1], bounds[1:])]
    fl = face_loop.tolist()
    return [(loops[a:b], gaps[a:b].tolist()) for a, b in zip(fl[:-1], fl[1:])]


def loop_points(surfaces, chord_tol: float, affine: bool, cross_knots: bool, packs=None,
                flat=None, pair_tol: float | None = None) -> tuple:
    """``(pts (n, 2) read only, start (L+1,), gaps (L, 2), face_loop (len(surfaces)+1,))``:
    the closed UV polylines of the trim loops of ``surfaces`` (loop ``l``:
    ``pts[start[l]:start[l+1]]``, surface ``f``'s loops ``face_loop[f]:face_loop[f+1]``)
    and each loop's :func:`geomkit._kernels.tess_trim.loop_rectangle_gap`, every piece of
    every loop of every surface in one :func:`geomkit._kernels.tess_loops.face_loops` call
    (each piece from its knots, split until every 3-D chord is within ``chord_tol`` of
    the exact curve ``S(C(t))`` and of the image of its UV chord; with ``pair_tol``,
    until the chord is within ``chord_tol`` of the UV chord's image and within
    ``chord_tol`` of the curve too or the two distances add up to at most ``pair_tol``:
    the mesh boundary, which lies within the second of the chord, then lies within
    ``max(2 chord_tol, pair_tol)`` of the curve, and a plane's chords, whose UV chords
    map onto them, may lie ``pair_tol`` from the curve;
    ``affine``: the surfaces are affine maps of their parameters, whose UV chords map to
    3-D chords).  ``packs``: ``[packed_trims(s)]`` of a single surface, ``flat``:
    :func:`flat_surfaces`, if made."""
    if len(surfaces) == 1:
        CP, W, K, deg, cp_off, k_off, loop_first = packs[0] if packs else \
            packed_trims(surfaces[0])
        face_piece = np.array([0, len(deg)], dtype=np.int64)
        face_loop = np.array([0, len(loop_first) - 1], dtype=np.int64)
    else:  # every loop's kept pack, concatenated once
        CP, W, K, deg, cp_off, k_off, loop_first, face_loop = packed_loops(surfaces)
        face_piece = loop_first[face_loop]
    flat = flat_surfaces(surfaces) if flat is None else flat
    chord_tol = float(chord_tol)
    if pair_tol is None:  # each distance within chord_tol
        curve_tol, pair_tol = chord_tol, 2.0 * chord_tol
    else:
        curve_tol = pair_tol = float(pair_tol)
    pts, start, gaps = face_loops(CP, W, K, deg, cp_off, k_off, loop_first, face_piece,
                                  face_loop, *flat, SEED_SPANS, curve_tol, chord_tol,
                                  pair_tol, not affine, cross_knots)
    pts.flags.writeable = False
    return pts, start, gaps, face_loop


def _rectangle_of(pts, chord_tol: float, surface: Surface):
    """:meth:`TrimPolylines.rectangle` of the closed polyline ``pts``
    (:func:`geomkit._kernels.tess_trim.rectangle_of`)."""
    ok, a0, a1, b0, b1 = rectangle_of(pts, float(chord_tol), *_net(surface))
    return (a0, a1, b0, b1) if ok else None


def _net(surface: Surface) -> tuple:
    """The surface's ``(P, Pw, p, q, U, V)``, as :func:`speed_bound` takes them."""
    return (surface.control_points, surface.homogeneous, surface.degree_u,
            surface.degree_v, surface.knots_u, surface.knots_v)


def line_rectangle(surface: Surface, chord_tol: float, packed) -> tuple | None:
    """:meth:`TrimPolylines.rectangle` without the polylines, for a surface whose only
    loop is made of straight UV pieces (degree 1, unit weights, distinct knots): their
    polylines are the control points (clipped to the domain) with, at most, points added
    on the segments between them, which lie between their ends (within rounding), so
    the box, the points' distance from its edge lines and the enclosed area are the
    control polygon's.  None for other pieces, or a loop near the domain rectangle
    (which :class:`TrimPolylines` may drop as the domain's own edges): then the
    polylines decide.  One compiled call
    (:func:`geomkit._kernels.tess_trim.line_rectangle_of`)."""
    _, W, _, deg, _, _, loop_first = packed
    if len(loop_first) != 2 or not (deg == 1).all() or not (W == 1.0).all():
        return None  # (most curved faces: no kernel call)
    (u0, u1), (v0, v1) = surface.domain
    ok, a0, a1, b0, b1 = line_rectangle_of(*packed, u0, u1, v0, v1, float(chord_tol),
                                           *_net(surface))
    return (a0, a1, b0, b1) if ok else None


def flat_surfaces(surfaces) -> tuple:
    """The nets and knots of ``surfaces`` as flat arrays for the kernels that take many
    faces: ``(Pw (n, 4), pw_off, nets, U, u_off, V, v_off, domains)``, face ``f``'s
    homogeneous net the rows ``Pw[pw_off[f]:pw_off[f+1]]`` (row-major), ``nets[f] = (nu,
    nv, p, q)``, its knots ``U[u_off[f]:u_off[f+1]]`` and ``V[...]``, ``domains[f] = (u0,
    u1, v0, v1)`` (``U[p]``, ``U[-p-1]``, ``V[q]``, ``V[-q-1]``: ``Surface.domain``)."""
    H = [s.homogeneous for s in surfaces]
    nets = np.array([h.shape[:2] + (s.degree_u, s.degree_v) for h, s in zip(H, surfaces)],
                    dtype=np.int64)
    if len(surfaces) == 1:
        s = surfaces[0]
        Pw = H[0].reshape(-1, 4)
        U, V = s.knots_u, s.knots_v
        pw_off = np.array([0, len(Pw)], dtype=np.int64)
        u_off = np.array([0, len(U)], dtype=np.int64)
        v_off = np.array([0, len(V)], dtype=np.int64)
        (u0, u1), (v0, v1) = s.domain
        return Pw, pw_off, nets, U, u_off, V, v_off, np.array([[u0, u1, v0, v1]])
    Pw = np.concatenate(H, axis=None).reshape(-1, 4)
    Us = [s.knots_u for s in surfaces]
    Vs = [s.knots_v for s in surfaces]
    U = np.concatenate(Us)
    V = np.concatenate(Vs)
    pw_off = starts(nets[:, 0] * nets[:, 1])
    u_off = starts(np.fromiter(map(len, Us), dtype=np.int64, count=len(Us)))
    v_off = starts(np.fromiter(map(len, Vs), dtype=np.int64, count=len(Vs)))
    p, q = nets[:, 2], nets[:, 3]
    domains = np.stack([U[u_off[:-1] + p], U[u_off[1:] - p - 1], V[v_off[:-1] + q],
                        V[v_off[1:] - q - 1]], axis=1)
    return Pw, pw_off, nets, U, u_off, V, v_off, domains


def speed_bound(s: Surface) -> float:
    """An upper bound of ``|S_u| + |S_v|`` over the whole domain (so a UV step of
    length ``d`` moves ``S`` by at most ``d * speed_bound(s)``).

    At fixed ``v``, ``S`` is a rational B-spline curve in ``u`` whose control points
    lie in the convex hull of the net (diameter ``D``, bounded by its box diagonal) and
    whose weights lie in ``[w_min, w_max]``.  With ``R_i = N_i w_i / W``:
    ``S_u = sum R_i' (P_i - c)`` for any ``c`` (``sum R_i' = 0``), and
    ``sum |R_i'| <= sum |N_i'| w_max / W + |W'| / W <= 4 p (w_max / w_min) / h``,
    since ``sum |N_i'| <= 2 p / h`` (``h`` the shortest non-empty knot span).  So
    ``|S_u| <= 4 p (w_max / w_min) D / h_u``; the same in ``v``."""
    return float(speed_bound_of(s.control_points, s.homogeneous, s.degree_u, s.degree_v,
                                s.knots_u, s.knots_v))


SEED_SPANS = 16
"""A curved trim piece with at most this many spans has every polyline segment checked
on its knot span's 1/16 grid as well as at its quarter points (the sampling of the
route before, which started such pieces from 5 seeds a span: 1.2-1.6x the trim points
on real parts); one with more (a pcurve carried through a reparametrisation, fitted
span by span: its spans are already short) at its quarter points only."""


# ------------------------------------------------------------------ planes
def _greville(knots: np.ndarray, p: int, n: int) -> np.ndarray:
    """``mean(knots[i+1 : i+p+1])`` for i < n: below 8 terms numpy's mean is the
    left-to-right sum divided by p, the sums here in that order (the same bits)."""
    if p == 1:
        return np.asarray(knots[1:n + 1], dtype=np.float64)
    if p >= 8:
        return np.array([knots[i + 1: i + p + 1].mean() for i in range(n)])
    k = np.asarray(knots, dtype=np.float64)
    acc = k[1:n + 1] + k[2:n + 2]
    for j in range(3, p + 1):
        acc += k[j:n + j]
    return acc / p


def affine_map(s: Surface, size: float):
    """``(o, a, b)`` with ``S(u, v) = o + u a + v b`` exactly (to rounding), or None.

    A B-spline surface reproduces linear functions (the Greville identity): when its
    control points are ``o + g_u[i] a + g_v[j] b`` at the Greville abscissae and the
    weights are equal, ``S`` is that affine map.  Also requires ``a x b != 0`` (not
    degenerate)."""
    w = s.weights
    if w is not None and np.maximum.reduce(w, axis=None) != np.minimum.reduce(w, axis=None):
        return None  # (np.ptp(w) != 0, without its wrapper)
    P = s.control_points
    nu, nv = P.shape[:2]
    if nu == 2 and nv == 2:  # the bilinear patch (degree 1): the parallelogram test
        oab = _bilinear_affine(P.tolist(), s.knots_u.tolist(), s.knots_v.tolist(), size)
        return None if oab is None else _not_degenerate(*(np.array(x) for x in oab))
    gu = _greville(s.knots_u, s.degree_u, nu)
    gv = _greville(s.knots_v, s.degree_v, nv)
    du, dv = gu[-1] - gu[0], gv[-1] - gv[0]
    if du > 0 and dv > 0:
        # quick rejection (most curved nets): the affine map through three corners.
        # Had the least-squares map a residual <= eps at every point, this one would
        # differ from it by an affine function bounded by eps at those corners, so
        # by at most 3 eps on the Greville box: its residual would be <= 4 eps.
        R = P - P[0, 0] - np.multiply.outer(gu - gu[0], (P[-1, 0] - P[0, 0]) / du)[:, None] \
            - np.multiply.outer(gv - gv[0], (P[0, -1] - P[0, 0]) / dv)[None]
        if np.abs(R).max() > 4.5 * AFFINE_REL * size:
            return None
    G = np.stack([np.ones(nu * nv), np.repeat(gu, nv), np.tile(gv, nu)], axis=1)
    X = P.reshape(-1, 3)
    coef = np.linalg.lstsq(G, X, rcond=None)[0]
    if np.abs(G @ coef - X).max() > AFFINE_REL * size:
        return None
    o, a, b = coef
    return _not_degenerate(o, a, b)


def _not_degenerate(o, a, b):
    """``(o, a, b)`` unless ``a x b`` is 0 (a line or a point): then None."""
    n = (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
    if not n[0] ** 2 + n[1] ** 2 + n[2] ** 2 > 1e-24 * np.dot(a, a) * np.dot(b, b):
        return None  # degenerate (a line or a point)
    return o, a, b


def _bilinear_affine(P, ku, kv, size):
    """:func:`affine_map`'s ``(o, a, b)`` (lists of floats) of a 2 x 2 net ``P`` (nested
    lists of floats) of knots ``ku``, ``kv`` (lists; the Greville abscissae are
    ``ku[1], ku[2]`` / ``kv[1], kv[2]``) before the degeneracy test: ``a``, ``b`` the
    edges, ``o`` the origin; None when the twist (the net's departure from a
    parallelogram) exceeds ``AFFINE_REL * size``.  Float by float, the operations numpy
    did on the rows (the same values, without a numpy call per 3-vector)."""
    (p00, p01), (p10, p11) = P
    gu0, gu1, gv0, gv1 = ku[1], ku[2], kv[1], kv[2]
    du, dv = gu1 - gu0, gv1 - gv0
    a = [(p10[i] - p00[i]) / du for i in range(3)]
    b = [(p01[i] - p00[i]) / dv for i in range(3)]
    o = [p00[i] - gu0 * a[i] - gv0 * b[i] for i in range(3)]
    t = [abs(p11[i] - p10[i] - (p01[i] - p00[i])) for i in range(3)]
    lim = AFFINE_REL * size
    # numpy's max(t) > lim: NaN propagates through the max (and then fails the test)
    if t[0] == t[0] and t[1] == t[1] and t[2] == t[2] and max(t) > lim:
        return None
    return o, a, b


DEGENERATE_MARGIN = 1e-9
""":func:`affine_flags` decides :func:`_not_degenerate`'s test in floats of its own when
the two sides differ by more than this relative margin (rounding differences from
numpy's dot products are ~1e-16); closer, numpy's own test decides."""


def affine_flags(surfaces, sizes) -> list[bool]:
    """``[affine_map(s, size) is not None ...]`` for ``surfaces`` of ``sizes``, the same
    answers, with few numpy calls: unequal weights refused from a list of them, the
    2 x 2 nets tested together (:func:`_bilinear_affine`'s operations on arrays of their
    rows, elementwise: the same values; the degeneracy test too, unless its two sides
    lie within :data:`DEGENERATE_MARGIN` of each other: then numpy's, as
    :func:`affine_map` makes it).  Other nets: :func:`affine_map`."""
    out = [False] * len(surfaces)
    quad = []
    for i, s in enumerate(surfaces):
        w = s.weights
        if w is not None:  # finite and > 0 (the surface's invariant): min and max decide
            wl = w.ravel().tolist()
            if max(wl) != min(wl):
                continue
        shape = s.control_points.shape
        if shape[0] == 2 and shape[1] == 2:
            quad.append(i)
        else:
            out[i] = affine_map(s, sizes[i]) is not None
    if not quad:
        return out
    P = np.array([surfaces[i].control_points for i in quad])
    KU = np.array([surfaces[i].knots_u for i in quad])
    KV = np.array([surfaces[i].knots_v for i in quad])
    p00, p01, p10, p11 = P[:, 0, 0], P[:, 0, 1], P[:, 1, 0], P[:, 1, 1]
    a = (p10 - p00) / (KU[:, 2] - KU[:, 1])[:, None]
    b = (p01 - p00) / (KV[:, 2] - KV[:, 1])[:, None]
    t = np.abs(p11 - p10 - (p01 - p00))
    lim = AFFINE_REL * np.array([sizes[i] for i in quad])
    flat = ~(np.maximum.reduce(t, axis=1) > lim)  # NaN passes, as in _bilinear_affine
    (a0, a1, a2), (b0, b1, b2) = a.T, b.T
    n0, n1, n2 = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0
    lhs = n0 * n0 + n1 * n1 + n2 * n2
    rhs = 1e-24 * (a0 * a0 + a1 * a1 + a2 * a2) * (b0 * b0 + b1 * b1 + b2 * b2)
    sure = lhs > rhs * (1.0 + DEGENERATE_MARGIN)
    unsure = ~sure & ~(lhs < rhs * (1.0 - DEGENERATE_MARGIN))
    for k, i in enumerate(quad):
        if flat[k]:
            out[i] = bool(sure[k]) or bool(unsure[k]) and _not_degenerate(
                None, np.array(a[k].tolist()), np.array(b[k].tolist())) is not None
    return out


def planar_trimmed(trim: TrimPolylines):
    """``(uv (n, 2), faces (m, 3))``: a triangulation of the trimmed region of a
    surface that is an affine map of its parameters (:func:`affine_map`), faces
    counter-clockwise in UV, with every edge of the region's boundary (the trim
    polylines clipped to the domain, and the domain edges) as a triangle edge and no
    point added.  ``m == 0`` for an empty region.

    The Delaunay triangulation of the boundary vertices (GEOS, via shapely) is tried
    first: when it already holds every boundary edge, no triangle crosses the boundary
    and the triangles inside the region (centroid test) are the constrained Delaunay
    triangulation.  That is checked (every boundary edge present, the kept area equal
    to the region's, no triangle of zero area); otherwise the region is triangulated
    by GEOS's constrained Delaunay rule, which needs no check but grows quadratically
    with the vertex count (6-16x the unconstrained one's time on the 500-vertex plate
    region, measured on a loaded machine)."""
    import shapely

    region = trim.region
    if region.is_empty:
        return np.empty((0, 2)), np.empty((0, 3), dtype=np.int64)
    uv, F = _delaunay_inside(region)
    if F is None:
        xy = shapely.get_coordinates(shapely.constrained_delaunay_triangles(region))
        tri = xy.reshape(-1, 4, 2)[:, :3, :]
        uv, F = _indexed(tri)
    if not len(F):
        return uv, F
    a = uv[F[:, 1]] - uv[F[:, 0]]
    b = uv[F[:, 2]] - uv[F[:, 0]]
    area2 = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    F = F[area2 != 0]
    flip = area2[area2 != 0] < 0
    F[flip] = F[flip][:, ::-1]
    return uv, F


def _indexed(tri: np.ndarray):
    """Unique corners (sorted by u, then v) and the faces indexing them."""
    z = np.ascontiguousarray(tri).view(np.complex128).reshape(-1)
    uz, inv = np.unique(z, return_inverse=True)
    uv = np.ascontiguousarray(np.stack([uz.real, uz.imag], axis=1))
    return uv, inv.reshape(-1, 3).astype(np.int64)


def _delaunay_inside(region):
    """``(uv, faces)``: the triangles of the Delaunay triangulation of ``region``'s
    boundary vertices that lie inside it; faces None when that triangulation misses a
    boundary edge (or another check fails)."""
    import shapely

    # the collection's coordinates directly: 4 per triangle (closed ring), no
    # geometry object per triangle
    xy = shapely.get_coordinates(shapely.delaunay_triangles(region))
    if not len(xy) or len(xy) % 4:
        return None, None
    uv, T = _indexed(xy.reshape(-1, 4, 2)[:, :3, :])
    n = len(uv)
    e = np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]])
    have = np.sort(np.minimum(e[:, 0], e[:, 1]) * n + np.maximum(e[:, 0], e[:, 1]))
    # the boundary edges: consecutive vertices of each ring
    coords, ring_of = shapely.get_coordinates(shapely.get_rings(shapely.get_parts(region)),
                                              return_index=True)
    uz = uv.view(np.complex128).reshape(-1)
    rz = np.ascontiguousarray(coords).view(np.complex128).reshape(-1)
    ri = np.minimum(np.searchsorted(uz, rz), n - 1)
    if not np.array_equal(uz[ri], rz):  # a boundary vertex not in the triangulation
        return None, None
    same = ring_of[1:] == ring_of[:-1]
    a, b = ri[:-1][same], ri[1:][same]
    need = np.minimum(a, b) * n + np.maximum(a, b)
    at = np.minimum(np.searchsorted(have, need), len(have) - 1)
    if not np.array_equal(have[at], need):
        return None, None
    tri = uv[T]
    cen = (tri[:, 0] + tri[:, 1] + tri[:, 2]) / 3.0  # tri.mean(axis=1), the same sums
    inside = shapely.contains_xy(region, cen[:, 0], cen[:, 1])
    tri = tri[inside]
    v1 = tri[:, 1] - tri[:, 0]
    v2 = tri[:, 2] - tri[:, 0]
    area = 0.5 * np.abs(v1[:, 0] * v2[:, 1] - v1[:, 1] * v2[:, 0])
    if not len(tri) or not np.all(area > 0) \
            or abs(area.sum() - region.area) > 1e-9 * region.area:
        return None, None
    return uv, T[inside]
