"""Reading STEP files through Open CASCADE (the optional ``cadquery-ocp`` extra).

Every face is converted with ``BRepBuilderAPI_NurbsConvert``: the face's *bounded*
patch becomes a ``Geom_BSplineSurface`` (exact for B-spline, Bezier, plane, cylinder,
cone, sphere, torus, revolution and extrusion surfaces; offset surfaces are
approximated by OCC) and its pcurves are re-expressed on it consistently.  Each wire's
pcurves (``Geom2dConvert``) become a trim loop, outer wire first.  Real files' pcurves
meet within the file's tolerance, not exactly: gaps between consecutive pieces are
bridged by straight UV segments (counted in ``gaps_closed``, largest in ``max_gap``),
as for IGES.  Faces that still cannot be converted are an error unless
``skip_unsupported=True`` (then listed in ``skipped``).

Coordinates stay in the file's length unit (``units``); ``resolution`` is the file's
``UNCERTAINTY_MEASURE_WITH_UNIT`` length value.  Face orientation is not carried
(geomkit's normal is ``S_u x S_v`` of the surface).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from geomkit.tolerances import GAP_TOL, PCURVE_CLIP_TOL
from geomkit.errors import (FileFormatError, InvalidInputError, InvalidSurfaceError,
                            MissingDependencyError)
import re

from geomkit.cad.loops import chain, clip_in_3d, clip_to_domain, same_point_3d, close_gaps
from geomkit.cad.iges.reader import IgesResult, Skipped
from geomkit.nurbs.surface import Surface, TrimCurve

__all__ = ["read_step"]

_UNITS = {"MILLIMETRE": ("mm", 1.0), "METRE": ("m", 1000.0), "INCH": ("in", 25.4),
          "FOOT": ("ft", 304.8), "CENTIMETRE": ("cm", 10.0), "MICROMETRE": ("um", 1e-3),
          "KILOMETRE": ("km", 1e6), "MIL": ("mil", 0.0254), "MICROINCH": ("uin", 2.54e-5)}
"""STEP length unit names to geomkit unit names and their size in millimetres."""
_UNCERTAINTY = re.compile(r"UNCERTAINTY_MEASURE_WITH_UNIT\s*\(\s*LENGTH_MEASURE\s*\(\s*"
                          r"([-+0-9.EeDd]+)\s*\)", re.I)


INSTALL_HINT = "reading STEP needs Open CASCADE: pip install 'geomkit[step]' (cadquery-ocp)"


def _flat_knots(knots, mults):
    return [float(k) for k, m in zip(knots, mults) for _ in range(m)]


def _bspline_surface(bs, name, trim, approx_error=0.0):
    nu, nv = bs.NbUPoles(), bs.NbVPoles()
    P = np.empty((nu, nv, 3))
    W = np.empty((nu, nv))
    for i in range(nu):
        for j in range(nv):
            p = bs.Pole(i + 1, j + 1)
            P[i, j] = p.X(), p.Y(), p.Z()
            W[i, j] = bs.Weight(i + 1, j + 1)
    if bs.IsUPeriodic() or bs.IsVPeriodic():
        bs = bs.Copy()
        bs.SetUNotPeriodic()
        bs.SetVNotPeriodic()
        return _bspline_surface(bs, name, trim, approx_error)
    ku = _flat_knots([bs.UKnot(i) for i in range(1, bs.NbUKnots() + 1)],
                     [bs.UMultiplicity(i) for i in range(1, bs.NbUKnots() + 1)])
    kv = _flat_knots([bs.VKnot(i) for i in range(1, bs.NbVKnots() + 1)],
                     [bs.VMultiplicity(i) for i in range(1, bs.NbVKnots() + 1)])
    w = W if bs.IsURational() or bs.IsVRational() else None
    return Surface(bs.UDegree(), bs.VDegree(), ku, kv, P, w, trim, name=name,
                   approx_error=approx_error)


def _bspline_curve2d(c):
    if c.IsPeriodic():
        c = c.Copy()
        c.SetNotPeriodic()
    n = c.NbPoles()
    P = np.array([[c.Pole(i).X(), c.Pole(i).Y()] for i in range(1, n + 1)])
    W = np.array([c.Weight(i) for i in range(1, n + 1)])
    k = _flat_knots([c.Knot(i) for i in range(1, c.NbKnots() + 1)],
                    [c.Multiplicity(i) for i in range(1, c.NbKnots() + 1)])
    return TrimCurve.create(c.Degree(), k, P, W if c.IsRational() else None)


def _wire_edges(w, face) -> list:
    """The edges of wire ``w`` in connection order (``BRepTools_WireExplorer``); when
    that walk stops early (it follows vertices within their tolerance, and a file read
    in another length unit can leave a seam vertex out of reach: a torus face of a
    part in inches lost 15 of its 17 edges), every edge of the wire, in file order —
    the caller chains them by their pcurves."""
    from OCP.BRepTools import BRepTools_WireExplorer
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer

    from geomkit.cad.occ import cast_shape

    walk, every = [], []
    we = BRepTools_WireExplorer(w, face)
    while we.More():
        walk.append(we.Current())
        we.Next()
    ex = TopExp_Explorer(w, TopAbs_EDGE)
    while ex.More():
        every.append(cast_shape("Edge", ex.Current()))
        ex.Next()
    return walk if len(walk) >= len(every) else every


def _file_units(rd):
    from OCP.OCP.collections import Sequence_TCollection_AsciiString as Seq

    a, b, c = Seq(), Seq(), Seq()
    try:
        rd.FileUnits(a, b, c)
    except Exception:  # noqa: BLE001 - OCC raises its own kinds; units stay unknown
        return None, None
    names = {a.Value(i + 1).ToCString().upper() for i in range(a.Length())}
    if len(names) != 1:
        return None, None
    return _UNITS.get(names.pop(), (None, None))


def _resolution(path: Path):
    m = _UNCERTAINTY.search(path.read_text(encoding="latin-1", errors="replace"))
    if not m:
        return None
    try:
        return float(m.group(1).replace("D", "E").replace("d", "e"))
    except ValueError:
        return None


def read_step(path, skip_invalid: bool = False,
              skip_unsupported: bool = False) -> IgesResult:
    """Read the faces of a STEP file as trimmed :class:`~geomkit.Surface` objects.

    Returns an :class:`~geomkit.cad.iges.reader.IgesResult` (``entities`` holds face indices in
    OCC's ``TopExp_Explorer`` order, so ``len(surfaces)`` equals OCC's face count when
    nothing is skipped).

    Raises
    ------
    MissingDependencyError
        cadquery-ocp is not installed (with the install hint).
    InvalidInputError
        An empty file.
    FileFormatError
        Missing or unreadable file, no face, or faces that cannot be converted (listed)
        without ``skip_unsupported``.
    InvalidSurfaceError
        A face that fails validation (unless ``skip_invalid``).
    """
    p = Path(path)
    if not p.exists():
        raise FileFormatError(f"{p}: no such file")
    if p.is_dir():
        raise FileFormatError(f"{p}: is a directory, expected a STEP file")
    if not p.read_bytes().strip():
        raise InvalidInputError(f"{p}: empty file, expected a STEP file")
    try:
        from OCP.BRep import BRep_Tool
        from OCP.BRepBuilderAPI import BRepBuilderAPI_NurbsConvert
        from OCP.BRepTools import BRepTools
        from OCP.Geom2d import Geom2d_TrimmedCurve
        from OCP.Geom2dConvert import Geom2dConvert
        from OCP.GeomConvert import GeomConvert
        from OCP.IFSelect import IFSelect_RetDone
        from OCP.STEPControl import STEPControl_Reader
        from OCP.TopAbs import (TopAbs_EDGE, TopAbs_FACE, TopAbs_REVERSED, TopAbs_VERTEX,
                                TopAbs_WIRE)
        from OCP.TopExp import TopExp_Explorer
    except ImportError:
        raise MissingDependencyError(INSTALL_HINT) from None
    from geomkit.cad.occ import cast_shape
    rd = STEPControl_Reader()
    if rd.ReadFile(str(p)) != IFSelect_RetDone:
        raise FileFormatError(f"{p}: not a readable STEP file")
    units, mm = _file_units(rd)
    if mm is not None:  # keep coordinates in the file's unit (OCC's default: mm)
        rd.SetSystemLengthUnit(mm)
    rd.TransferRoots()
    shape = rd.OneShape()
    resolution = _resolution(p) or 0.0

    def face_tolerance(face) -> float:
        # the file's own tolerance at this face: its edges' and vertices' (OCC keeps
        # what the file states or what the transfer needed), or the model resolution
        tol = resolution
        for kind in (TopAbs_EDGE, TopAbs_VERTEX):
            tx = TopExp_Explorer(face, kind)
            while tx.More():
                tol = max(tol, BRep_Tool.Tolerance_s(cast_shape(
                    "Edge" if kind == TopAbs_EDGE else "Vertex", tx.Current())))
                tx.Next()
        return tol

    surfaces, entities, skipped, gaps = [], [], [], []
    ex = TopExp_Explorer(shape, TopAbs_FACE)
    k = -1
    while ex.More():
        k += 1
        face0 = cast_shape("Face", ex.Current())
        ex.Next()
        name = f"face{k}"
        try:
            kind = BRep_Tool.Surface_s(face0).DynamicType().Name()
            if kind in ("Geom_BSplineSurface", "Geom_BezierSurface"):
                face = face0  # already bounded and exact; pcurves as in the file
            else:  # the face's bounded patch (elementary, swept, offset, trimmed)
                face = cast_shape("Face", BRepBuilderAPI_NurbsConvert(face0, True).Shape())
            bs = GeomConvert.SurfaceToBSplineSurface_s(BRep_Tool.Surface_s(face))
            u0, u1, v0, v1 = bs.Bounds()
            domain = ((u0, u1), (v0, v1))
            outer = BRepTools.OuterWire_s(face)
            wires = [outer]
            wx = TopExp_Explorer(face, TopAbs_WIRE)
            while wx.More():
                w = cast_shape("Wire", wx.Current())
                if not w.IsSame(outer):
                    wires.append(w)
                wx.Next()
            loops, repairs = [], []
            base = _bspline_surface(bs, name, None)
            ftol = face_tolerance(face0)
            periods = ((u1 - u0) * bs.IsUClosed(), (v1 - v0) * bs.IsVClosed())
            for w in wires:
                pieces = []
                for e in _wire_edges(w, face):
                    f, l = BRep_Tool.Range_s(e, face)
                    c2 = BRep_Tool.CurveOnSurface_s(e, face, f, l)
                    if c2 is None:
                        raise ValueError(f"edge without a pcurve on {name}")
                    bc = Geom2dConvert.CurveToBSplineCurve_s(Geom2d_TrimmedCurve(c2, f, l))
                    if e.Orientation() == TopAbs_REVERSED:
                        bc.Reverse()
                    pieces.append(_bspline_curve2d(bc))
                if pieces:
                    size = max(u1 - u0, v1 - v0)
                    if any(np.hypot(*(a.end - b.start)) > GAP_TOL * size
                           for a, b in zip(pieces, pieces[1:] + pieces[:1])):
                        pieces = chain(pieces, size, periods, domain)  # edge order, seam sides
                    pieces, moved = clip_to_domain(pieces, domain, PCURVE_CLIP_TOL, GAP_TOL)
                    gaps += moved
                    # what is left outside the domain or open: repaired when the
                    # file's own tolerance covers it, measured in 3-D
                    pieces, moved3 = clip_in_3d(pieces, base, ftol)
                    same = same_point_3d(base, ftol)
                    pieces, g = close_gaps(pieces, domain, f"{name} wire {len(loops)}", same)
                    gaps += g
                    repairs += moved3 + same.errors
                    loops.append(pieces)
            s = _bspline_surface(bs, name, loops or None, max(repairs, default=0.0))
        except InvalidInputError as exc:
            if not skip_invalid:
                raise InvalidSurfaceError(f"{p}: face {k}: {exc}") from None
            skipped.append(Skipped(name, f"invalid: {exc}"))
            continue
        except Exception as exc:  # noqa: BLE001 - OCC raises its own Standard_Failure kinds
            skipped.append(Skipped(name, f"cannot convert ({type(exc).__name__}: {exc})"))
            continue
        surfaces.append(s)
        entities.append(k)
    unsupported = [s for s in skipped if not s.reason.startswith("invalid:")]
    if unsupported and not skip_unsupported:
        lines = "; ".join(str(s) for s in unsupported[:5])
        raise FileFormatError(f"{p}: {len(unsupported)} face(s) cannot be read: {lines}; "
                              "pass skip_unsupported=True (--skip-unsupported) to go on "
                              "without them")
    if not surfaces:
        raise FileFormatError(f"{p}: no readable face" + (f"; first skipped: {skipped[0]}"
                                                           if skipped else ""))
    return IgesResult(surfaces, entities, skipped, {"faces": k + 1}, len(gaps),
                      max(gaps, default=0.0), units, _resolution(p))
