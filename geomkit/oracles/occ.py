"""Open CASCADE adapter: geomkit's test oracle and benchmark reference.

Every function here takes and returns plain data (numpy arrays, floats, lists
and dicts of arrays) plus opaque Open CASCADE handles (``Geom_BSplineSurface``,
``TopoDS_Face``, ``TopoDS_Shape``) that are only ever passed back into this
module. No geomkit type is imported, so the oracle stays independent of the
code it checks.

Open CASCADE comes from the optional ``cadquery-ocp`` wheel (``import OCP``).
It is imported lazily inside each function through :func:`_require_ocp`, so
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

import importlib.util
import time

import numpy as np

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

#: True when the ``OCP`` package (cadquery-ocp) can be imported. Computed with
#: :func:`importlib.util.find_spec`, so it does not load Open CASCADE.
def _find_ocp() -> bool:
    try:
        return importlib.util.find_spec("OCP") is not None
    except (ImportError, ValueError):  # e.g. sys.modules["OCP"] without a spec
        return False


HAVE_OCP: bool = _find_ocp()

# Knots closer than this fraction of the knot span are treated as one knot
# (Open CASCADE rejects distinct knots closer than Epsilon(|k|)).
_KNOT_MERGE_RTOL = 1e-12


def _require_ocp(feature: str = "geomkit.oracles.occ"):
    """Import and return the ``OCP`` package, or raise a helpful ImportError.

    Parameters
    ----------
    feature : str
        What needs Open CASCADE; quoted in the error message.

    Returns
    -------
    module
        The ``OCP`` package.

    Raises
    ------
    ImportError
        If cadquery-ocp is not installed.
    """
    try:
        import OCP  # noqa: F401  (lazy: heavy shared libraries)
    except ImportError as exc:  # pragma: no cover - depends on environment
        raise ImportError(
            f"Open CASCADE (cadquery-ocp) is required for {feature}; "
            "pip install 'geomkit[test]'"
        ) from exc
    return OCP


# ---------------------------------------------------------------------------
# plain array -> Open CASCADE conversion helpers
# ---------------------------------------------------------------------------


# cadquery-ocp 8.x (OCCT 8) exposes NCollection arrays as
# ``OCP.collections.Array1_double`` etc. and the TopoDS casts as ``TopoDS.Face``;
# 7.x wheels used ``TColStd_Array1OfReal`` ... and ``TopoDS.Face_s``. These two
# helpers hide the difference (only the 8.x path is exercised in CI here).
_OLD_ARRAY_NAMES = {
    "Array1_double": ("OCP.TColStd", "TColStd_Array1OfReal"),
    "Array1_int": ("OCP.TColStd", "TColStd_Array1OfInteger"),
    "Array2_double": ("OCP.TColStd", "TColStd_Array2OfReal"),
    "Array2_gp_Pnt": ("OCP.TColgp", "TColgp_Array2OfPnt"),
    "Array1_gp_Pnt2d": ("OCP.TColgp", "TColgp_Array1OfPnt2d"),
}


def _ocp_array(name: str):
    """Open CASCADE array class by its OCP 8.x name (falls back to the TCol* name)."""
    try:
        import OCP.collections as coll

        return getattr(coll, name)
    except (ImportError, AttributeError):  # pragma: no cover - older OCP
        mod, old = _OLD_ARRAY_NAMES[name]
        return getattr(importlib.import_module(mod), old)


def _cast(kind: str, shape):
    """Down-cast a TopoDS_Shape: ``kind`` in {"Face", "Wire", "Edge", "Vertex"}."""
    from OCP.TopoDS import TopoDS

    fn = getattr(TopoDS, kind, None) or getattr(TopoDS, kind + "_s")
    return fn(shape)


def _knots_to_occ(knots, degree: int, n_ctrl: int, name: str):
    """Convert a full clamped knot vector to (distinct knots, multiplicities).

    Parameters
    ----------
    knots : (n_ctrl + degree + 1,) array_like of float
        Full, non-decreasing, clamped knot vector.
    degree : int
        Degree ``p >= 1``.
    n_ctrl : int
        Number of control points along this direction.
    name : str
        Used in error messages (e.g. ``"knots_u"``).

    Returns
    -------
    distinct : (m,) ndarray of float
    mults : (m,) ndarray of int
        ``mults[0] == mults[-1] == degree + 1``; interior ``<= degree``.
    """
    k = np.asarray(knots, dtype=np.float64).ravel()
    if degree < 1:
        raise ValueError(f"{name}: degree must be >= 1, got {degree}")
    if k.size != n_ctrl + degree + 1:
        raise ValueError(
            f"{name}: expected n + p + 1 = {n_ctrl} + {degree} + 1 = "
            f"{n_ctrl + degree + 1} knots, got {k.size}"
        )
    if not np.all(np.isfinite(k)):
        raise ValueError(f"{name}: knots must be finite")
    if np.any(np.diff(k) < 0):
        raise ValueError(f"{name}: knots must be non-decreasing")
    span = k[-1] - k[0]
    if not span > 0:
        raise ValueError(f"{name}: knot vector has zero span")
    tol = _KNOT_MERGE_RTOL * span
    distinct = [k[0]]
    mults = [1]
    for x in k[1:]:
        if x - distinct[-1] <= tol:
            mults[-1] += 1
        else:
            distinct.append(x)
            mults.append(1)
    # the last distinct knot must be exactly the last knot (clamped end value)
    distinct[-1] = k[-1]
    if mults[0] != degree + 1 or mults[-1] != degree + 1:
        raise ValueError(
            f"{name}: knot vector must be clamped (first and last knot repeated "
            f"degree + 1 = {degree + 1} times); got end multiplicities "
            f"{mults[0]} and {mults[-1]}"
        )
    if len(mults) > 2 and max(mults[1:-1]) > degree:
        raise ValueError(
            f"{name}: interior knot multiplicity exceeds degree {degree} "
            "(discontinuous spline)"
        )
    return np.asarray(distinct), np.asarray(mults, dtype=np.int64)


def _array1_double(values):
    Array1_double = _ocp_array("Array1_double")
    values = np.asarray(values, dtype=np.float64).ravel()
    arr = Array1_double(1, int(values.size))
    for i, v in enumerate(values, start=1):
        arr.SetValue(i, float(v))
    return arr


def _array1_int(values):
    Array1_int = _ocp_array("Array1_int")
    values = np.asarray(values).ravel()
    arr = Array1_int(1, int(values.size))
    for i, v in enumerate(values, start=1):
        arr.SetValue(i, int(v))
    return arr


def _gp_pnt(p):
    from OCP.gp import gp_Pnt

    p = np.asarray(p, dtype=np.float64).ravel()
    if p.size != 3:
        raise ValueError(f"expected a 3-D point, got shape {np.shape(p)}")
    return gp_Pnt(float(p[0]), float(p[1]), float(p[2]))


def _xyz(p) -> np.ndarray:
    return np.array([p.X(), p.Y(), p.Z()])


# ---------------------------------------------------------------------------
# 1. surfaces
# ---------------------------------------------------------------------------


def make_surface(degree_u, degree_v, knots_u, knots_v, control_points, weights=None):
    """Build an Open CASCADE ``Geom_BSplineSurface`` from plain arrays.

    Parameters
    ----------
    degree_u, degree_v : int
        Degrees ``p, q >= 1``.
    knots_u : (nu + p + 1,) array_like of float
        Full clamped knot vector in u (interior knots may repeat up to ``p``).
    knots_v : (nv + q + 1,) array_like of float
        Full clamped knot vector in v.
    control_points : (nu, nv, 3) array_like of float
        Cartesian control net, first index along u.
    weights : (nu, nv) array_like of float, optional
        Positive weights; ``None`` gives a polynomial (non-rational) surface.

    Returns
    -------
    OCP.Geom.Geom_BSplineSurface
        Non-periodic surface over ``[knots_u[0], knots_u[-1]] x
        [knots_v[0], knots_v[-1]]``, identical to the input NURBS (the knot
        vector is stored as distinct knots + multiplicities).

    Raises
    ------
    ValueError
        On shape, knot or weight inconsistencies.
    ImportError
        If cadquery-ocp is not installed.
    """
    _require_ocp("make_surface")
    Array2_double, Array2_gp_Pnt = _ocp_array("Array2_double"), _ocp_array("Array2_gp_Pnt")
    from OCP.Geom import Geom_BSplineSurface
    from OCP.gp import gp_Pnt

    p, q = int(degree_u), int(degree_v)
    cp = np.asarray(control_points, dtype=np.float64)
    if cp.ndim != 3 or cp.shape[2] != 3:
        raise ValueError(f"control_points must have shape (nu, nv, 3), got {cp.shape}")
    if not np.all(np.isfinite(cp)):
        raise ValueError("control_points must be finite")
    nu, nv = cp.shape[:2]
    uk, um = _knots_to_occ(knots_u, p, nu, "knots_u")
    vk, vm = _knots_to_occ(knots_v, q, nv, "knots_v")

    poles = Array2_gp_Pnt(1, nu, 1, nv)
    for i in range(nu):
        for j in range(nv):
            x, y, z = cp[i, j]
            poles.SetValue(i + 1, j + 1, gp_Pnt(float(x), float(y), float(z)))
    args = (_array1_double(uk), _array1_double(vk), _array1_int(um), _array1_int(vm), p, q)
    if weights is None:
        return Geom_BSplineSurface(poles, *args, False, False)
    w = np.asarray(weights, dtype=np.float64)
    if w.shape != (nu, nv):
        raise ValueError(f"weights must have shape {(nu, nv)}, got {w.shape}")
    if not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise ValueError("weights must be finite and > 0")
    warr = Array2_double(1, nu, 1, nv)
    for i in range(nu):
        for j in range(nv):
            warr.SetValue(i + 1, j + 1, float(w[i, j]))
    return Geom_BSplineSurface(poles, warr, *args, False, False)


def _make_pcurve(piece):
    """2-D NURBS piece dict -> (Geom2d_BSplineCurve, C0 break parameters)."""
    Array1_gp_Pnt2d = _ocp_array("Array1_gp_Pnt2d")
    from OCP.Geom2d import Geom2d_BSplineCurve
    from OCP.gp import gp_Pnt2d

    if not isinstance(piece, dict):
        raise TypeError(
            "a trim piece must be a dict {degree, knots, control_points, weights}, "
            f"got {type(piece).__name__}"
        )
    deg = int(piece["degree"])
    cp = np.asarray(piece["control_points"], dtype=np.float64)
    if cp.ndim != 2 or cp.shape[1] != 2:
        raise ValueError(f"trim piece control_points must be (k, 2), got {cp.shape}")
    k = cp.shape[0]
    knots, mults = _knots_to_occ(piece["knots"], deg, k, "trim piece knots")
    poles = Array1_gp_Pnt2d(1, k)
    for i in range(k):
        poles.SetValue(i + 1, gp_Pnt2d(float(cp[i, 0]), float(cp[i, 1])))
    w = piece.get("weights")
    if w is None:
        curve = Geom2d_BSplineCurve(poles, _array1_double(knots), _array1_int(mults), deg, False)
    else:
        w = np.asarray(w, dtype=np.float64).ravel()
        if w.shape != (k,):
            raise ValueError(f"trim piece weights must be ({k},), got {w.shape}")
        if np.any(w <= 0):
            raise ValueError("trim piece weights must be > 0")
        curve = Geom2d_BSplineCurve(
            poles, _array1_double(w), _array1_double(knots), _array1_int(mults), deg, False
        )
    # split at C0 knots (multiplicity == degree) so every edge is at least C1:
    # polylines become one edge per segment, which BuildCurves3d handles exactly.
    breaks = [knots[0]] + [t for t, m in zip(knots[1:-1], mults[1:-1]) if m >= deg] + [knots[-1]]
    return curve, np.asarray(breaks)


def _loop_signed_area_uv(curves, samples_per_span: int = 32) -> float:
    """Signed shoelace area of a trim loop sampled in UV (CCW > 0)."""
    pts = []
    for curve, breaks in curves:
        for a, b in zip(breaks[:-1], breaks[1:]):
            for t in np.linspace(a, b, samples_per_span, endpoint=False):
                p = curve.Value(float(t))
                pts.append((p.X(), p.Y()))
    xy = np.asarray(pts)
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _make_wire(surf, curves, tol: float):
    """Edges on ``surf`` from pcurves, sharing explicit vertices, into a wire."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeWire
    from OCP.gp import gp_Pnt
    from OCP.TopoDS import TopoDS_Vertex

    segs = []  # (curve, t0, t1)
    for curve, breaks in curves:
        for a, b in zip(breaks[:-1], breaks[1:]):
            segs.append((curve, float(a), float(b)))
    n = len(segs)

    def on_surf(curve, t):
        uv = curve.Value(t)
        return _xyz(surf.Value(uv.X(), uv.Y()))

    # vertex j joins the end of segment j-1 and the start of segment j
    builder = BRep_Builder()
    verts = []
    for j in range(n):
        c0, _, t_end = segs[j - 1]
        c1, t_start, _ = segs[j]
        pa, pb = on_surf(c0, t_end), on_surf(c1, t_start)
        gap = float(np.linalg.norm(pa - pb))
        mid = 0.5 * (pa + pb)
        v = TopoDS_Vertex()
        builder.MakeVertex(v, gp_Pnt(*map(float, mid)), max(tol, 0.6 * gap + tol))
        verts.append(v)

    mw = BRepBuilderAPI_MakeWire()
    for j, (curve, a, b) in enumerate(segs):
        me = BRepBuilderAPI_MakeEdge(curve, surf, verts[j], verts[(j + 1) % n], a, b)
        if not me.IsDone():
            raise RuntimeError(
                f"BRepBuilderAPI_MakeEdge failed on trim segment {j} "
                f"(error {me.Error()}); check that the loop is closed"
            )
        mw.Add(me.Edge())
        if not mw.IsDone():
            raise RuntimeError(
                f"BRepBuilderAPI_MakeWire failed at segment {j} (error {mw.Error()})"
            )
    return mw.Wire()


def is_valid(shape) -> bool:
    """Return True if ``BRepCheck_Analyzer`` finds ``shape`` valid.

    Parameters
    ----------
    shape : OCP.TopoDS.TopoDS_Shape

    Returns
    -------
    bool
    """
    _require_ocp("is_valid")
    from OCP.BRepCheck import BRepCheck_Analyzer

    return bool(BRepCheck_Analyzer(shape).IsValid())


def _fix_face(face, tol: float):
    from OCP.ShapeFix import ShapeFix_Face

    sff = ShapeFix_Face(face)
    sff.SetPrecision(tol)
    sff.SetMaxTolerance(max(1e3 * tol, 1e-4))
    sff.Perform()
    return _cast("Face", sff.Face())


def face_from_surface(surf, trim=None, tol: float = 1e-7, check: bool = True):
    """Build a (trimmed) ``TopoDS_Face`` on an existing Open CASCADE surface.

    Parameters
    ----------
    surf : OCP.Geom.Geom_Surface
        Typically the result of :func:`make_surface`.
    trim : list of loops, optional
        Loops in the surface's UV space, outer loop first, then holes. A loop is
        a list of pieces (a single piece dict is also accepted); a piece is a
        dict ``{"degree": int, "knots": (k + degree + 1,), "control_points":
        (k, 2), "weights": (k,) or None}`` with a full clamped knot vector.
        Consecutive pieces must join and the loop must close (gaps are absorbed
        into vertex tolerances). ``None``: the natural face over the full
        parameter domain (seams and degenerate pole edges added by Open
        CASCADE).
    tol : float
        Modelling tolerance: degenerate-edge tolerance for the natural face,
        minimum vertex tolerance, 3-D curve approximation tolerance.
    check : bool
        Raise if the final face is not valid for ``BRepCheck_Analyzer``.

    Returns
    -------
    OCP.TopoDS.TopoDS_Face
        A FORWARD face with 3-D edge curves built (``BRepLib.BuildCurves3d_s``).
        Loop orientation is normalised from the loops' signed UV area: the
        outer loop is made counter-clockwise and holes clockwise (Open
        CASCADE's material-on-the-left rule), whatever the input direction.

    Raises
    ------
    RuntimeError
        If Open CASCADE cannot build a valid face.
    """
    _require_ocp("face_from_surface")
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.BRepLib import BRepLib
    from OCP.GeomAbs import GeomAbs_C1

    if trim is None or len(trim) == 0:
        mf = BRepBuilderAPI_MakeFace(surf, float(tol))
        if not mf.IsDone():
            raise RuntimeError(f"BRepBuilderAPI_MakeFace failed (error {mf.Error()})")
        face = mf.Face()
        if not is_valid(face):
            face = _fix_face(face, tol)
        if check and not is_valid(face):
            raise RuntimeError("natural face is not valid (BRepCheck_Analyzer)")
        return face

    loops = []
    for li, loop in enumerate(trim):
        pieces = [loop] if isinstance(loop, dict) else list(loop)
        if not pieces:
            raise ValueError(f"trim loop {li} is empty")
        curves = [_make_pcurve(pc) for pc in pieces]
        loops.append((curves, _loop_signed_area_uv(curves)))

    def build(flip_holes: bool):
        wires = []
        for li, (curves, signed) in enumerate(loops):
            w = _make_wire(surf, curves, tol)
            want_ccw = True if li == 0 else flip_holes  # holes: CW unless flipped
            if (signed > 0) != want_ccw:
                w = _cast("Wire", w.Reversed())  # Reversed() returns a TopoDS_Shape
            wires.append(w)
        mf = BRepBuilderAPI_MakeFace(surf, wires[0], True)
        if not mf.IsDone():
            raise RuntimeError(f"BRepBuilderAPI_MakeFace failed (error {mf.Error()})")
        for w in wires[1:]:
            mf.Add(w)
        face = mf.Face()
        BRepLib.BuildCurves3d_s(face, max(tol, 1e-9), GeomAbs_C1, 14, 0)
        if not is_valid(face):
            face = _fix_face(face, tol)
        return face

    face = build(flip_holes=False)
    if not is_valid(face) or area(face) <= 0:
        # be robust to unusual surfaces/pcurves: try the opposite hole sense
        alt = build(flip_holes=True)
        if is_valid(alt) and area(alt) > 0:
            face = alt
    if check and not is_valid(face):
        raise RuntimeError("trimmed face is not valid (BRepCheck_Analyzer)")
    return face


def make_face(
    degree_u,
    degree_v,
    knots_u,
    knots_v,
    control_points,
    weights=None,
    trim=None,
    tol: float = 1e-7,
):
    """Build a (trimmed) NURBS ``TopoDS_Face`` from plain arrays.

    Parameters
    ----------
    degree_u, degree_v, knots_u, knots_v, control_points, weights
        As in :func:`make_surface` (``control_points`` ``(nu, nv, 3)``,
        ``weights`` ``(nu, nv)`` or None).
    trim : list of loops, optional
        UV trim loops, outer first; see :func:`face_from_surface`.
    tol : float
        Modelling tolerance; see :func:`face_from_surface`.

    Returns
    -------
    OCP.TopoDS.TopoDS_Face
        Valid face (``BRepCheck_Analyzer``) on the surface of
        :func:`make_surface`.
    """
    surf = make_surface(degree_u, degree_v, knots_u, knots_v, control_points, weights)
    return face_from_surface(surf, trim=trim, tol=tol)


def face_surface(face):
    """Return the ``Geom_Surface`` underlying a face (``BRep_Tool.Surface_s``).

    Parameters
    ----------
    face : OCP.TopoDS.TopoDS_Face

    Returns
    -------
    OCP.Geom.Geom_Surface
    """
    _require_ocp("face_surface")
    from OCP.BRep import BRep_Tool

    return BRep_Tool.Surface_s(_cast("Face", face))


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
    _require_ocp("evaluate")
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
    _require_ocp("derivatives1")
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
        yield _cast("Face", exp.Current())
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
    _require_ocp("mesh")
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

    P = _gp_pnt(point)
    best = (np.inf, np.full(3, np.nan), (np.nan, np.nan))
    if _is_geom_surface(target):
        u0, u1, v0, v1 = target.Bounds()
        proj = GeomAPI_ProjectPointOnSurf(P, target, u0, u1, v0, v1)
        if proj.IsDone() and proj.NbPoints() > 0:
            best = (float(proj.LowerDistance()), _xyz(proj.NearestPoint()),
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
        best = (d, _xyz(foot), uv)
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
    _require_ocp("project_point")
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
    _require_ocp("distance_shapes")
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
    return float(dss.Value()), _xyz(dss.PointOnShape1(1)), _xyz(dss.PointOnShape2(1)), seconds


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
    _require_ocp("section")
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
        edge = _cast("Edge", exp.Current())
        exp.Next()
        if BRep_Tool.Degenerated_s(edge):
            continue
        ad = BRepAdaptor_Curve(edge)
        disc = GCPnts_QuasiUniformDeflection(ad, float(deflection))
        if not disc.IsDone() or disc.NbPoints() < 2:
            continue
        pts = np.array([_xyz(disc.Value(i)) for i in range(1, disc.NbPoints() + 1)])
        if edge.Orientation() == TopAbs_REVERSED:
            pts = pts[::-1]
        pieces.append(pts)
    if not pieces:
        return [], seconds
    # join tolerance: the largest vertex tolerance, with a tiny absolute floor
    vtol = 1e-7
    vexp = TopExp_Explorer(result, TopAbs_VERTEX)
    while vexp.More():
        vtol = max(vtol, BRep_Tool.Tolerance_s(_cast("Vertex", vexp.Current())))
        vexp.Next()
    return _chain(pieces, 2.0 * vtol + 1e-9), seconds


# ---------------------------------------------------------------------------
# 7. area
# ---------------------------------------------------------------------------


def area(face, eps: float = 1e-10) -> float:
    """Surface area via ``BRepGProp.SurfaceProperties_s`` (trims respected).

    Parameters
    ----------
    face : OCP.TopoDS.TopoDS_Shape
        A face, or any shape (areas of all faces are summed).
    eps : float
        Relative error target of Open CASCADE's adaptive Gauss integration.

    Returns
    -------
    float
        Area in model units squared (negative if a face's loops are wound
        against its orientation).
    """
    _require_ocp("area")
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props, float(eps))
    return float(props.Mass())
