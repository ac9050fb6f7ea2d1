"""Open CASCADE adapter: geomkit's test oracle and benchmark reference.

Every function here takes and returns plain data (numpy arrays, floats, lists
and dicts of arrays) plus opaque Open CASCADE handles (``Geom_BSplineSurface``,
``TopoDS_Face``, ``TopoDS_Shape``) that are only ever passed back into this
module. No geomkit type is imported, so the oracle stays independent of the
code it checks.

Construction (surfaces, trimmed faces) lives in :mod:`geomkit.bench.oracles.occ_faces`, the
shared conversion helpers in :mod:`geomkit.bench.oracles.occ_common`; this module re-exports
them, so ``occ.make_face`` etc. keep working.

Open CASCADE comes from the optional ``cadquery-ocp`` wheel (``import OCP``).
It is imported lazily inside each function through :func:`require_ocp`, so
importing this module never fails; use :data:`HAVE_OCP` to skip tests.

Conventions
-----------
* Knot vectors are FULL clamped vectors of length ``n + p + 1`` (the geomdl /
  NURBS Book form). They are converted to Open CASCADE's distinct-knot +
  multiplicity form here. Open CASCADE arrays are 1-based.
* Control points are Cartesian ``(nu, nv, 3)``; weights ``(nu, nv)`` are kept
  separately (not premultiplied).
* A trim is a list of loops in the surface's UV space, outer loop first. A loop
  is a list of pieces; a piece is a 2-D NURBS curve given as a dict
  ``{"degree", "knots", "control_points" (k, 2), "weights" (k,) or None}``
  (a polyline is a degree-1 piece). geomkit's convention is outer loop
  counter-clockwise, holes clockwise; :func:`make_face` enforces it.
* Timings (``seconds``) use :func:`time.perf_counter` around the Open CASCADE
  call only, never around the conversion to numpy.
"""

from __future__ import annotations

import time

import numpy as np

from geomkit.cad.occ import (HAVE_OCP, array1_double, array1_int, cast_shape,
                             gp_pnt, knots_to_occ, ocp_array, require_ocp,
                             xyz)
from geomkit.bench.oracles.occ_faces import (area, face_from_surface, face_surface, is_valid,
                                             make_face, make_surface)

__all__ = [
    "HAVE_OCP",
    "make_surface",
    "make_face",
    "face_from_surface",
    "face_surface",
    "is_valid",
    "evaluate",
    "derivatives1",
    "mesh",
    "project_point",
    "distance_shapes",
    "section",
    "area",
]

# ---------------------------------------------------------------------------
# 3. evaluation
# ---------------------------------------------------------------------------


def _as_uv(uv) -> np.ndarray:
    uv = np.asarray(uv, dtype=np.float64)
    if uv.ndim == 1:
        uv = uv.reshape(1, -1)
    if uv.ndim != 2 or uv.shape[1] != 2:
        raise ValueError(f"uv must have shape (n, 2) or (2,), got {np.shape(uv)}")
    return uv


def evaluate(surf, uv) -> np.ndarray:
    """Evaluate surface points ``S(u, v)`` with Open CASCADE.

    Parameters
    ----------
    surf : OCP.Geom.Geom_Surface
    uv : (n, 2) or (2,) array_like of float
        Parameters inside the surface's domain.

    Returns
    -------
    (n, 3) ndarray of float
    """
    require_ocp("evaluate")
    uv = _as_uv(uv)
    out = np.empty((uv.shape[0], 3))
    for i, (u, v) in enumerate(uv):
        p = surf.Value(float(u), float(v))
        out[i] = p.X(), p.Y(), p.Z()
    return out


def derivatives1(surf, uv) -> np.ndarray:
    """Point and first partial derivatives via ``Geom_Surface.D1``.

    Parameters
    ----------
    surf : OCP.Geom.Geom_Surface
    uv : (n, 2) or (2,) array_like of float

    Returns
    -------
    (n, 3, 3) ndarray of float
        ``out[i, 0] = S``, ``out[i, 1] = dS/du``, ``out[i, 2] = dS/dv``.
    """
    require_ocp("derivatives1")
    from OCP.gp import gp_Pnt, gp_Vec

    uv = _as_uv(uv)
    out = np.empty((uv.shape[0], 3, 3))
    p, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
    for i, (u, v) in enumerate(uv):
        surf.D1(float(u), float(v), p, du, dv)  # outputs filled in place
        out[i, 0] = p.X(), p.Y(), p.Z()
        out[i, 1] = du.X(), du.Y(), du.Z()
        out[i, 2] = dv.X(), dv.Y(), dv.Z()
    return out


# ---------------------------------------------------------------------------
# 4. meshing
# ---------------------------------------------------------------------------


def _faces_of(shape):
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer

    exp = TopExp_Explorer(shape, TopAbs_FACE)
    while exp.More():
        yield cast_shape("Face", exp.Current())
        exp.Next()


def mesh(
    face,
    deflection: float,
    angle: float = 0.5,
    relative: bool = False,
    parallel: bool = False,
):
    """Triangulate a face (or any shape) with ``BRepMesh_IncrementalMesh``.

    Parameters
    ----------
    face : OCP.TopoDS.TopoDS_Face or OCP.TopoDS.TopoDS_Shape
        All faces of the shape are meshed and concatenated. Any existing
        triangulation is removed first (``BRepTools.Clean_s``) so the call
        always does the full work.
    deflection : float
        Linear deflection (model units, or a fraction of the edge size when
        ``relative``).
    angle : float
        Angular deflection in radians.
    relative : bool
        Interpret ``deflection`` relative to edge sizes.
    parallel : bool
        Let Open CASCADE mesh faces in parallel.

    Returns
    -------
    vertices : (n, 3) ndarray of float
        Node positions with the face location applied.
    faces : (m, 3) ndarray of int64
        0-based vertex indices, wound so that the normal follows the face
        orientation (swapped for REVERSED faces). Returned as Open CASCADE
        made them: at a collapsed pole there can be zero-area triangles (two
        nodes with different uv at the same 3-D point); nodes are not shared
        between faces.
    uv : (n, 2) ndarray of float
        Surface parameters of each node (NaN if Open CASCADE stored none).
    seconds : float
        Wall time of the ``BRepMesh_IncrementalMesh`` call only.
    """
    require_ocp("mesh")
    from OCP.BRep import BRep_Tool
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.BRepTools import BRepTools
    from OCP.TopAbs import TopAbs_REVERSED
    from OCP.TopLoc import TopLoc_Location

    if not deflection > 0:
        raise ValueError(f"deflection must be > 0, got {deflection}")
    BRepTools.Clean_s(face)
    t0 = time.perf_counter()
    mesher = BRepMesh_IncrementalMesh(
        face, float(deflection), bool(relative), float(angle), bool(parallel)
    )
    seconds = time.perf_counter() - t0
    if not mesher.IsDone():
        raise RuntimeError("BRepMesh_IncrementalMesh failed")

    all_v, all_f, all_uv = [], [], []
    offset = 0
    for f in _faces_of(face):
        loc = TopLoc_Location()
        tri = BRep_Tool.Triangulation_s(f, loc)  # loc is filled in place
        if tri is None or tri.NbTriangles() == 0:
            continue
        nn, nt = tri.NbNodes(), tri.NbTriangles()
        trsf = None if loc.IsIdentity() else loc.Transformation()
        verts = np.empty((nn, 3))
        for i in range(1, nn + 1):  # Poly arrays are 1-based
            p = tri.Node(i)
            if trsf is not None:
                p = p.Transformed(trsf)
            verts[i - 1] = p.X(), p.Y(), p.Z()
        uv = np.full((nn, 2), np.nan)
        if tri.HasUVNodes():
            for i in range(1, nn + 1):
                q = tri.UVNode(i)
                uv[i - 1] = q.X(), q.Y()
        tris = np.empty((nt, 3), dtype=np.int64)
        for i in range(1, nt + 1):
            tris[i - 1] = tri.Triangle(i).Get()
        tris -= 1
        if f.Orientation() == TopAbs_REVERSED:
            tris = tris[:, [0, 2, 1]]
        all_v.append(verts)
        all_uv.append(uv)
        all_f.append(tris + offset)
        offset += nn
    if not all_v:
        return np.empty((0, 3)), np.empty((0, 3), dtype=np.int64), np.empty((0, 2)), seconds
    return np.vstack(all_v), np.vstack(all_f), np.vstack(all_uv), seconds


# ---------------------------------------------------------------------------
# 5. distances
# ---------------------------------------------------------------------------


def _is_geom_surface(obj) -> bool:
    from OCP.Geom import Geom_Surface

    return isinstance(obj, Geom_Surface)


def _project_one(target, point, include_boundary: bool, tol: float, cache: dict):
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape, BRepExtrema_SupportType
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
    from OCP.ShapeAnalysis import ShapeAnalysis_Surface

    P = gp_pnt(point)
    best = (np.inf, np.full(3, np.nan), (np.nan, np.nan))
    if _is_geom_surface(target):
        u0, u1, v0, v1 = target.Bounds()
        proj = GeomAPI_ProjectPointOnSurf(P, target, u0, u1, v0, v1)
        if proj.IsDone() and proj.NbPoints() > 0:
            best = (float(proj.LowerDistance()), xyz(proj.NearestPoint()),
                    tuple(map(float, proj.LowerDistanceParameters())))
        if not include_boundary and np.isfinite(best[0]):
            return best
        if "face" not in cache:  # natural face, built once per call
            cache["face"] = face_from_surface(target, tol=tol, check=False)
        face = cache["face"]
        surf = target
    else:
        face = target
        if "surf" not in cache:
            cache["surf"] = face_surface(face)
        surf = cache["surf"]
    # BRepExtrema covers face interior, edges and vertices (the boundary).
    v = BRepBuilderAPI_MakeVertex(P).Vertex()
    dss = BRepExtrema_DistShapeShape(v, face)
    if not dss.IsDone() or dss.NbSolution() == 0:
        if np.isfinite(best[0]):
            return best
        raise RuntimeError("BRepExtrema_DistShapeShape found no solution")
    d = float(dss.Value())
    if d < best[0]:
        foot = dss.PointOnShape2(1)
        if dss.SupportTypeShape2(1) == BRepExtrema_SupportType.BRepExtrema_IsInFace:
            uv = tuple(map(float, dss.ParOnFaceS2(1)))
        else:
            q = ShapeAnalysis_Surface(surf).ValueOfUV(foot, tol)
            uv = (q.X(), q.Y())
        best = (d, xyz(foot), uv)
    return best


def project_point(surf_or_face, point, include_boundary: bool = True, tol: float = 1e-7):
    """Nearest point on a surface or face.

    Parameters
    ----------
    surf_or_face : OCP.Geom.Geom_Surface or OCP.TopoDS.TopoDS_Face
        For a ``Geom_Surface`` the orthogonal projections come from
        ``GeomAPI_ProjectPointOnSurf`` over the surface's bounds. Because an
        orthogonal foot may not exist (or may be only a local minimum) when the
        nearest point lies on the boundary, the natural face is also checked
        with ``BRepExtrema_DistShapeShape`` unless ``include_boundary`` is
        False. For a face (trims respected) ``BRepExtrema_DistShapeShape``
        is used directly.
    point : (3,) or (n, 3) array_like of float
    include_boundary : bool
        See above (``Geom_Surface`` input only).
    tol : float
        Tolerance for the UV inversion of boundary feet.

    Returns
    -------
    distance : float or (n,) ndarray
    foot : (3,) or (n, 3) ndarray
        Nearest point on the surface / face.
    uv : tuple (u, v) or (n, 2) ndarray
        Parameters of ``foot``.
    """
    require_ocp("project_point")
    pts = np.asarray(point, dtype=np.float64)
    single = pts.ndim == 1
    pts = pts.reshape(-1, 3) if pts.size % 3 == 0 else None
    if pts is None:
        raise ValueError(f"point must have shape (3,) or (n, 3), got {np.shape(point)}")
    cache: dict = {}
    res = [_project_one(surf_or_face, p, include_boundary, tol, cache) for p in pts]
    if single:
        return res[0]
    return (
        np.array([r[0] for r in res]),
        np.array([r[1] for r in res]),
        np.array([r[2] for r in res]),
    )


def distance_shapes(shape_a, shape_b, deflection: float | None = None):
    """Minimum distance between two shapes (``BRepExtrema_DistShapeShape``).

    Parameters
    ----------
    shape_a, shape_b : OCP.TopoDS.TopoDS_Shape
        Faces, shells, compounds...
    deflection : float, optional
        Open CASCADE's precision for the solution; default is its own
        (``Precision::Confusion``).

    Returns
    -------
    distance : float
    point_a : (3,) ndarray
        Closest point on ``shape_a`` (first solution).
    point_b : (3,) ndarray
        Closest point on ``shape_b``.
    seconds : float
        Wall time of ``Perform`` only.
    """
    require_ocp("distance_shapes")
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape

    dss = BRepExtrema_DistShapeShape()
    if deflection is not None:
        dss.SetDeflection(float(deflection))
    dss.LoadS1(shape_a)
    dss.LoadS2(shape_b)
    t0 = time.perf_counter()
    dss.Perform()
    seconds = time.perf_counter() - t0
    if not dss.IsDone() or dss.NbSolution() == 0:
        raise RuntimeError("BRepExtrema_DistShapeShape failed")
    return float(dss.Value()), xyz(dss.PointOnShape1(1)), xyz(dss.PointOnShape2(1)), seconds


# ---------------------------------------------------------------------------
# 6. plane section
# ---------------------------------------------------------------------------


def _chain(pieces, tol: float):
    """Join (k, 3) point runs whose end points coincide within ``tol``."""
    pieces = [p for p in pieces if len(p) >= 2]
    used = [False] * len(pieces)
    out = []
    for s in range(len(pieces)):
        if used[s]:
            continue
        used[s] = True
        chain = [pieces[s]]
        for end in ("tail", "head"):
            grown = True
            while grown:
                grown = False
                tip = chain[-1][-1] if end == "tail" else chain[0][0]
                if np.linalg.norm(chain[0][0] - chain[-1][-1]) <= tol and (
                    len(chain) > 1 or len(chain[0]) > 2
                ):
                    break  # already closed
                for k in range(len(pieces)):
                    if used[k]:
                        continue
                    a, b = pieces[k][0], pieces[k][-1]
                    if end == "tail":
                        if np.linalg.norm(a - tip) <= tol:
                            chain.append(pieces[k])
                        elif np.linalg.norm(b - tip) <= tol:
                            chain.append(pieces[k][::-1])
                        else:
                            continue
                    else:
                        if np.linalg.norm(b - tip) <= tol:
                            chain.insert(0, pieces[k])
                        elif np.linalg.norm(a - tip) <= tol:
                            chain.insert(0, pieces[k][::-1])
                        else:
                            continue
                    used[k] = True
                    grown = True
                    break
        poly = np.vstack([chain[0]] + [c[1:] for c in chain[1:]])
        if len(poly) > 2 and np.linalg.norm(poly[0] - poly[-1]) <= tol:
            poly[-1] = poly[0]  # closed loop: first == last exactly
        out.append(poly)
    return out


def section(shape, plane_abcd, deflection: float = 1e-3, approximation: bool = True):
    """Intersect a shape with the plane ``A x + B y + C z + D = 0``.

    Uses ``BRepAlgoAPI_Section`` with ``gp_Pln(A, B, C, D)``; every result edge
    is discretised with ``GCPnts_QuasiUniformDeflection`` and the pieces are
    chained end to end.

    Parameters
    ----------
    shape : OCP.TopoDS.TopoDS_Shape
    plane_abcd : (4,) array_like of float
        Plane coefficients; ``(A, B, C)`` need not be unit length.
    deflection : float
        Maximum chordal deviation of the polylines from the section edges.
    approximation : bool
        Ask Open CASCADE to approximate the intersection curves by B-splines
        (more accurate edges).

    Returns
    -------
    polylines : list of (k, 3) ndarray
        One per connected section curve; a closed curve has ``first == last``.
        Empty list if the plane misses the shape.
    seconds : float
        Wall time of the section ``Build`` only.
    """
    require_ocp("section")
    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Curve
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Section
    from OCP.GCPnts import GCPnts_QuasiUniformDeflection
    from OCP.gp import gp_Pln
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_REVERSED, TopAbs_VERTEX
    from OCP.TopExp import TopExp_Explorer

    abcd = np.asarray(plane_abcd, dtype=np.float64).ravel()
    if abcd.shape != (4,) or not np.linalg.norm(abcd[:3]) > 0:
        raise ValueError(f"plane_abcd must be (A, B, C, D) with (A, B, C) != 0, got {plane_abcd}")
    if not deflection > 0:
        raise ValueError(f"deflection must be > 0, got {deflection}")
    pln = gp_Pln(*map(float, abcd))
    sec = BRepAlgoAPI_Section(shape, pln, False)
    sec.Approximation(bool(approximation))
    t0 = time.perf_counter()
    sec.Build()
    seconds = time.perf_counter() - t0
    if not sec.IsDone():
        raise RuntimeError("BRepAlgoAPI_Section failed")
    result = sec.Shape()

    pieces = []
    exp = TopExp_Explorer(result, TopAbs_EDGE)
    while exp.More():
        edge = cast_shape("Edge", exp.Current())
        exp.Next()
        if BRep_Tool.Degenerated_s(edge):
            continue
        ad = BRepAdaptor_Curve(edge)
        disc = GCPnts_QuasiUniformDeflection(ad, float(deflection))
        if not disc.IsDone() or disc.NbPoints() < 2:
            continue
        pts = np.array([xyz(disc.Value(i)) for i in range(1, disc.NbPoints() + 1)])
        if edge.Orientation() == TopAbs_REVERSED:
            pts = pts[::-1]
        pieces.append(pts)
    if not pieces:
        return [], seconds
    # join tolerance: the largest vertex tolerance, with a tiny absolute floor
    vtol = 1e-7
    vexp = TopExp_Explorer(result, TopAbs_VERTEX)
    while vexp.More():
        vtol = max(vtol, BRep_Tool.Tolerance_s(cast_shape("Vertex", vexp.Current())))
        vexp.Next()
    return _chain(pieces, 2.0 * vtol + 1e-9), seconds
