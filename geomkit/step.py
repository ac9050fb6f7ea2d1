"""Reading STEP files through Open CASCADE (the optional ``cadquery-ocp`` extra).

Each face's surface is converted to a ``Geom_BSplineSurface`` (``GeomConvert``: exact
for B-spline, Bézier and the elementary surfaces, NURBS for the quadrics) and its
wires' parameter-space curves (pcurves, ``Geom2dConvert``) become the trim loops, outer
wire first.  Faces whose surface or pcurves cannot be converted are skipped and listed.
Face orientation is not carried (geomkit's normal is ``S_u x S_v`` of the surface).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .errors import FileFormatError, InvalidInputError, InvalidSurfaceError, \
    MissingDependencyError
from .iges import IgesResult
from .types import Surface, TrimCurve

__all__ = ["read_step"]

INSTALL_HINT = "reading STEP needs Open CASCADE: pip install 'geomkit[step]' (cadquery-ocp)"


def _flat_knots(knots, mults):
    return [float(k) for k, m in zip(knots, mults) for _ in range(m)]


def _bspline_surface(bs, name, trim):
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
        return _bspline_surface(bs, name, trim)
    ku = _flat_knots([bs.UKnot(i) for i in range(1, bs.NbUKnots() + 1)],
                     [bs.UMultiplicity(i) for i in range(1, bs.NbUKnots() + 1)])
    kv = _flat_knots([bs.VKnot(i) for i in range(1, bs.NbVKnots() + 1)],
                     [bs.VMultiplicity(i) for i in range(1, bs.NbVKnots() + 1)])
    w = W if bs.IsURational() or bs.IsVRational() else None
    return Surface(bs.UDegree(), bs.VDegree(), ku, kv, P, w, trim, name=name)


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


def read_step(path, skip_invalid: bool = False) -> IgesResult:
    """Read the faces of a STEP file as trimmed :class:`~geomkit.Surface` objects.

    Returns an :class:`~geomkit.iges.IgesResult` (``entities`` holds face indices).

    Raises
    ------
    MissingDependencyError
        cadquery-ocp is not installed (with the install hint).
    FileFormatError
        Missing or unreadable file, or no face.
    InvalidSurfaceError
        A face that fails validation (unless ``skip_invalid``).
    """
    p = Path(path)
    if not p.exists():
        raise FileFormatError(f"{p}: no such file")
    if p.is_dir():
        raise FileFormatError(f"{p}: is a directory, expected a STEP file")
    try:
        from OCP.BRep import BRep_Tool
        from OCP.BRepTools import BRepTools, BRepTools_WireExplorer
        from OCP.Geom2d import Geom2d_TrimmedCurve
        from OCP.Geom2dConvert import Geom2dConvert
        from OCP.GeomConvert import GeomConvert
        from OCP.IFSelect import IFSelect_RetDone
        from OCP.STEPControl import STEPControl_Reader
        from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED, TopAbs_WIRE
        from OCP.TopExp import TopExp_Explorer
    except ImportError:
        raise MissingDependencyError(INSTALL_HINT) from None
    from .oracles.occ import _cast
    rd = STEPControl_Reader()
    if rd.ReadFile(str(p)) != IFSelect_RetDone:
        raise FileFormatError(f"{p}: not a readable STEP file")
    rd.TransferRoots()
    shape = rd.OneShape()
    surfaces, entities, skipped = [], [], []
    ex = TopExp_Explorer(shape, TopAbs_FACE)
    k = -1
    while ex.More():
        k += 1
        face = _cast("Face", ex.Current())
        ex.Next()
        name = f"face{k}"
        try:
            bs = GeomConvert.SurfaceToBSplineSurface_s(BRep_Tool.Surface_s(face))
            outer = BRepTools.OuterWire_s(face)
            wires = [outer]
            wx = TopExp_Explorer(face, TopAbs_WIRE)
            while wx.More():
                w = _cast("Wire", wx.Current())
                if not w.IsSame(outer):
                    wires.append(w)
                wx.Next()
            loops = []
            for w in wires:
                pieces = []
                we = BRepTools_WireExplorer(w, face)
                while we.More():
                    e = we.Current()
                    f, l = BRep_Tool.Range_s(e, face)
                    c2 = BRep_Tool.CurveOnSurface_s(e, face, f, l)
                    if c2 is None:
                        raise ValueError(f"edge without a pcurve on {name}")
                    bc = Geom2dConvert.CurveToBSplineCurve_s(Geom2d_TrimmedCurve(c2, f, l))
                    if e.Orientation() == TopAbs_REVERSED:
                        bc.Reverse()
                    pieces.append(_bspline_curve2d(bc))
                    we.Next()
                if pieces:
                    loops.append(pieces)
            s = _bspline_surface(bs, name, loops or None)
        except InvalidInputError as exc:
            if not skip_invalid:
                raise InvalidSurfaceError(f"{p}: face {k}: {exc}") from None
            skipped.append(f"{name}: invalid: {exc}")
            continue
        except Exception as exc:  # OCC raises its own Standard_Failure kinds
            skipped.append(f"{name}: cannot convert ({type(exc).__name__}: {exc})")
            continue
        surfaces.append(s)
        entities.append(k)
    if not surfaces:
        raise FileFormatError(f"{p}: no readable face" + (f"; first skipped: {skipped[0]}"
                                                           if skipped else ""))
    return IgesResult(surfaces, entities, skipped, {"faces": k + 1})
