"""Open CASCADE surfaces and trimmed faces from plain arrays (the oracle's
construction half; conventions in :mod:`geomkit.bench.oracles.occ`)."""

from __future__ import annotations

import numpy as np

from geomkit.cad.occ import (array1_double, array1_int, cast_shape, knots_to_occ,
                             ocp_array, require_ocp, xyz)

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
    require_ocp("make_surface")
    Array2_double, Array2_gp_Pnt = ocp_array("Array2_double"), ocp_array("Array2_gp_Pnt")
    from OCP.Geom import Geom_BSplineSurface
    from OCP.gp import gp_Pnt

    p, q = int(degree_u), int(degree_v)
    cp = np.asarray(control_points, dtype=np.float64)
    if cp.ndim != 3 or cp.shape[2] != 3:
        raise ValueError(f"control_points must have shape (nu, nv, 3), got {cp.shape}")
    if not np.all(np.isfinite(cp)):
        raise ValueError("control_points must be finite")
    nu, nv = cp.shape[:2]
    uk, um = knots_to_occ(knots_u, p, nu, "knots_u")
    vk, vm = knots_to_occ(knots_v, q, nv, "knots_v")

    poles = Array2_gp_Pnt(1, nu, 1, nv)
    for i in range(nu):
        for j in range(nv):
            x, y, z = cp[i, j]
            poles.SetValue(i + 1, j + 1, gp_Pnt(float(x), float(y), float(z)))
    args = (array1_double(uk), array1_double(vk), array1_int(um), array1_int(vm), p, q)
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
    Array1_gp_Pnt2d = ocp_array("Array1_gp_Pnt2d")
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
    knots, mults = knots_to_occ(piece["knots"], deg, k, "trim piece knots")
    poles = Array1_gp_Pnt2d(1, k)
    for i in range(k):
        poles.SetValue(i + 1, gp_Pnt2d(float(cp[i, 0]), float(cp[i, 1])))
    w = piece.get("weights")
    if w is None:
        curve = Geom2d_BSplineCurve(poles, array1_double(knots), array1_int(mults), deg, False)
    else:
        w = np.asarray(w, dtype=np.float64).ravel()
        if w.shape != (k,):
            raise ValueError(f"trim piece weights must be ({k},), got {w.shape}")
        if np.any(w <= 0):
            raise ValueError("trim piece weights must be > 0")
        curve = Geom2d_BSplineCurve(
            poles, array1_double(w), array1_double(knots), array1_int(mults), deg, False
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
        return xyz(surf.Value(uv.X(), uv.Y()))

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
    require_ocp("is_valid")
    from OCP.BRepCheck import BRepCheck_Analyzer

    return bool(BRepCheck_Analyzer(shape).IsValid())


def _fix_face(face, tol: float):
    from OCP.ShapeFix import ShapeFix_Face

    sff = ShapeFix_Face(face)
    sff.SetPrecision(tol)
    sff.SetMaxTolerance(max(1e3 * tol, 1e-4))
    sff.Perform()
    return cast_shape("Face", sff.Face())


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
    require_ocp("face_from_surface")
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
                w = cast_shape("Wire", w.Reversed())  # Reversed() returns a TopoDS_Shape
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
    require_ocp("face_surface")
    from OCP.BRep import BRep_Tool

    return BRep_Tool.Surface_s(cast_shape("Face", face))


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
    require_ocp("area")
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props, float(eps))
    return float(props.Mass())
