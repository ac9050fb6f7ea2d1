"""Reading STEP files: geomkit's own reader first, Open CASCADE (the optional
``cadquery-ocp`` extra) for what it does not read.

:func:`read_step` reads the B-rep with :func:`geomkit.cad.stepbrep.read_native`
(geomkit's Part 21 parser and geometry; no Open CASCADE, no OCC crash in the process)
and falls back to :func:`read_step_occ` (in a child process) for faces the native
reader cannot convert.  Through Open CASCADE, OCC reads the file and builds the B-rep;
geomkit converts each face:

* B-spline and Bezier faces are taken as they are, with the file's pcurves;
* planes, cylinders, cones, spheres, tori and extrusions / revolutions of B-spline
  curves become geomkit's own exact patches (:mod:`geomkit.cad.elementary`), the
  file's pcurves carried onto them;
* anything else (offset surfaces, sweeps of other curves) goes through
  ``BRepBuilderAPI_NurbsConvert``, and the drift of OCC's re-approximated pcurves
  from the edges' 3-D curves is measured.

Each wire's pcurves become a trim loop, outer wire first.  Real files' pcurves meet
within the file's tolerance, not exactly: gaps between consecutive pieces are bridged
by straight UV segments (counted in ``gaps_closed``, largest in ``max_gap``), as for
IGES; loops that leave the domain or stay open by more are repaired when the repair,
measured in 3-D, is within the face's own tolerance.  Every conversion error, drift and
repair is stated as the face's ``approx_error``.  Faces that still cannot be converted
are an error unless ``skip_unsupported=True`` (then listed in ``skipped``).

Coordinates stay in the file's length unit (``units``); ``resolution`` is the file's
``UNCERTAINTY_MEASURE_WITH_UNIT`` length value.  Face orientation is not carried
(geomkit's normal is ``S_u x S_v`` of the surface).
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np

from geomkit.errors import (FileFormatError, FileRecoveredWarning, InvalidInputError,
                            InvalidSurfaceError, MissingDependencyError)

from geomkit.cad.elementary import carry_pcurve, elementary_patch
from geomkit.cad.loops import Unsupported, finish_loop
from geomkit.cad.occ import HAVE_OCP
from geomkit.cad.readcache import cached_read, gc_paused
from geomkit.cad.stepbrep import UnreadFaces, check_read, read_native
from geomkit.cad.iges.reader import IgesResult, Skipped
from geomkit.mesh.tessellate import closed_directions
from geomkit.nurbs.surface import Surface, TrimCurve

__all__ = ["read_step", "read_step_occ", "occ_shape", "edge_gaps", "READERS"]

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


def _drift(edge, pcurve, first: float, last: float, base, samples: int = 9) -> float:
    """Largest 3-D distance between ``base`` along an edge's (converted) pcurve and the
    edge's 3-D curve at the same parameters: OCC's re-approximated pcurve's error,
    plus the file's own edge tolerance."""
    from OCP.BRep import BRep_Tool

    from geomkit.cad.occ import xyz

    c3 = BRep_Tool.Curve_s(edge, 0.0, 0.0)
    if c3 is None or not np.allclose(BRep_Tool.Range_s(edge), (first, last), rtol=0,
                                     atol=1e-12 * max(1.0, abs(first), abs(last))):
        return BRep_Tool.Tolerance_s(edge)  # no 3-D curve on the same range
    t = np.linspace(first, last, samples)
    uv = np.array([[q.X(), q.Y()] for q in (pcurve.Value(x) for x in t)])
    (u0, u1), (v0, v1) = base.domain
    uv = np.column_stack([np.clip(uv[:, 0], u0, u1), np.clip(uv[:, 1], v0, v1)])
    X = np.array([xyz(c3.Value(x)) for x in t])
    return float(np.linalg.norm(base.evaluate(uv) - X, axis=1).max())


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


def edge_gaps(shape, approx_errors=None, samples: int = 9):
    """``(model gap, largest edge tolerance)`` of an OCC shape, from its topology:
    on every edge that two faces share, the largest distance between the two faces'
    own images of the edge (``S1(c1(t))`` and ``S2(c2(t))``, each face's surface at
    its pcurve, at ``samples`` parameters), plus the two faces' ``approx_error``
    (``approx_errors``: face name ``"face<k>"`` in ``TopExp_Explorer`` order -> error;
    a face missing from it was not read and its edges are not measured).  Edges with
    one face (free edges, seams) have no gap.  ``(0.0, 0.0)`` for a shape without
    shared edges.

    Pairing the images at the same edge parameter bounds their distance as point sets
    from above.  It may exceed the largest edge tolerance (NIST FTC-06: 4.56e-3 mm
    against 4.32e-3 mm): each face's image is within the edge's tolerance of its 3-D
    curve, so two images can be up to twice that apart."""
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
    from OCP.TopExp import TopExp, TopExp_Explorer
    from OCP.collections import (
        IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher as Map)

    from geomkit.cad.occ import cast_shape, xyz

    index, faces = {}, []
    ex = TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        f = cast_shape("Face", ex.Current())
        index.setdefault(hash(f), []).append((len(faces), f))
        faces.append(f)
        ex.Next()

    def number(f):
        for k, g in index.get(hash(f), ()):
            if g.IsSame(f):
                return k
        return None

    m = Map()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, m)
    gap = tol = 0.0
    for i in range(1, m.Extent() + 1):
        e = cast_shape("Edge", m.FindKey(i))
        tol = max(tol, BRep_Tool.Tolerance_s(e))
        owners = []
        for f in m.FindFromIndex(i):
            f = cast_shape("Face", f)
            if not any(f.IsSame(g) for g in owners):
                owners.append(f)
        if len(owners) != 2 or BRep_Tool.Degenerated_s(e):
            continue
        ks = [number(f) for f in owners]
        errs = [None if k is None else (approx_errors or {}).get(f"face{k}", 0.0)
                for k in ks] if approx_errors is not None else [0.0, 0.0]
        if None in errs:
            continue
        f0, l0 = BRep_Tool.Range_s(e)
        images = []
        for f in owners:
            c2 = BRep_Tool.CurveOnSurface_s(e, f, f0, l0)
            if c2 is None:
                break
            S = BRep_Tool.Surface_s(f)
            images.append(np.array([xyz(S.Value(q.X(), q.Y())) for q in
                                    (c2.Value(t) for t in np.linspace(f0, l0, samples))]))
        if len(images) != 2:
            continue
        d = float(np.linalg.norm(images[0] - images[1], axis=1).max())
        gap = max(gap, d + errs[0] + errs[1])
    return gap, tol


def _pcurves(face) -> list:
    """Per wire of ``face`` (outer first): ``(edge, pcurve, first, last, TrimCurve)``
    for its edges in connection order, each TrimCurve oriented along the wire."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepTools import BRepTools
    from OCP.Geom2d import Geom2d_TrimmedCurve
    from OCP.Geom2dConvert import Geom2dConvert
    from OCP.TopAbs import TopAbs_REVERSED, TopAbs_WIRE
    from OCP.TopExp import TopExp_Explorer

    from geomkit.cad.occ import cast_shape

    outer = BRepTools.OuterWire_s(face)
    wires = [outer]
    wx = TopExp_Explorer(face, TopAbs_WIRE)
    while wx.More():
        w = cast_shape("Wire", wx.Current())
        if not w.IsSame(outer):
            wires.append(w)
        wx.Next()
    out = []
    for w in wires:
        edges = []
        for e in _wire_edges(w, face):
            f, l = BRep_Tool.Range_s(e, face)
            c2 = BRep_Tool.CurveOnSurface_s(e, face, f, l)
            if c2 is None:
                raise ValueError("an edge without a pcurve")
            bc = Geom2dConvert.CurveToBSplineCurve_s(Geom2d_TrimmedCurve(c2, f, l))
            if e.Orientation() == TopAbs_REVERSED:
                bc.Reverse()
            edges.append((e, c2, f, l, _bspline_curve2d(bc)))
        if edges:
            out.append(edges)
    return out


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


def occ_shape(path):
    """``(shape, units)``: Open CASCADE's B-rep of a STEP file, in the file's own length
    unit (OCC's default would scale to mm), and that unit's name (None if unknown).
    Raises :class:`FileFormatError` for a file OCC cannot read."""
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.STEPControl import STEPControl_Reader

    rd = STEPControl_Reader()
    if rd.ReadFile(str(path)) != IFSelect_RetDone:
        raise FileFormatError(f"{path}: not a readable STEP file")
    units, mm = _file_units(rd)
    if mm is not None:
        rd.SetSystemLengthUnit(mm)
    rd.TransferRoots()
    return rd.OneShape(), units


READERS = ("auto", "geomkit", "occ")
"""``read_step``'s readers: geomkit's own (:mod:`geomkit.cad.stepbrep`), Open
CASCADE's, or geomkit's with Open CASCADE for what it does not read (faces it
cannot convert, placements other than item-defined transformations) when the extra
is installed."""


def read_step(path, skip_invalid: bool = False, skip_unsupported: bool = False,
              reader: str = "auto", cache: bool = True) -> IgesResult:
    """Read the faces of a STEP file as trimmed :class:`~geomkit.Surface` objects.

    ``reader="auto"`` reads the file's B-rep with geomkit's own reader
    (:func:`geomkit.cad.stepbrep.read_native`: no Open CASCADE needed), and hands
    the file to Open CASCADE (:func:`read_step_occ`) only for what it does not read
    (a face it cannot convert, a placement it does not read) when the extra is
    installed; ``"geomkit"`` / ``"occ"`` choose one.  A malformed file is an error
    from geomkit's reader, never handed on.

    Returns an :class:`~geomkit.cad.iges.reader.IgesResult` (``entities`` holds face indices in
    OCC's ``TopExp_Explorer`` order, so ``len(surfaces)`` equals OCC's face count when
    nothing is skipped).

    ``cache``: a file read before with the same bytes and options comes from the read
    cache (:mod:`geomkit.cad.readcache`; the first read's warnings given again); off
    with ``cache=False`` or ``GEOMKIT_NO_CACHE=1``.  A read that fails is never cached.

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
    data = p.read_bytes()
    if not data.strip():
        raise InvalidInputError(f"{p}: empty file, expected a STEP file")
    if reader not in READERS:
        raise InvalidInputError(f"expected one of {', '.join(READERS)}, got {reader!r}",
                                "reader")
    if not cache:
        return _read_step(p, skip_invalid, skip_unsupported, reader, data)
    return cached_read(data, ("step", str(p.resolve()), bool(skip_invalid),
                              bool(skip_unsupported), reader, HAVE_OCP),
                       lambda: _read_step(p, skip_invalid, skip_unsupported, reader, data))


def _read_step(p: Path, skip_invalid, skip_unsupported, reader, data=None) -> IgesResult:
    if reader == "occ":
        if not HAVE_OCP:
            raise MissingDependencyError(INSTALL_HINT)
        return _occ_isolated(p, skip_invalid, skip_unsupported, "")
    try:
        with gc_paused():
            return read_native(p, skip_invalid, skip_unsupported, data)
    except (Unsupported, UnreadFaces) as exc:
        if reader == "geomkit" or not HAVE_OCP:
            if isinstance(exc, UnreadFaces):
                raise
            raise FileFormatError(f"{p}: geomkit's STEP reader does not read {exc}"
                                  + ("" if HAVE_OCP else f"; {INSTALL_HINT}")) from None
        why = str(exc)
    return _occ_isolated(p, skip_invalid, skip_unsupported, why)


def _occ_isolated(p: Path, skip_invalid, skip_unsupported, why: str) -> IgesResult:
    """:func:`read_step_occ` in a child process (:mod:`geomkit.cad.occ_child`): a file
    geomkit's reader could not finish goes to Open CASCADE, which can crash on broken
    files (a segmentation fault in ``TransferRoots``); a crash there is a
    :class:`FileFormatError` here.  OCC's messages are captured, logged on the
    ``geomkit.occ`` logger (``geomkit --verbose`` shows them) and never printed on this
    process's stdout; a file OCC read only by skipping records with syntax errors gives
    a :class:`~geomkit.errors.FileRecoveredWarning`; the child's warnings are raised
    again here."""
    import os
    import pickle
    import subprocess
    import sys
    import tempfile

    fd, out = tempfile.mkstemp(prefix="geomkit-occ-", suffix=".pkl")
    os.close(fd)
    try:
        run = subprocess.run([sys.executable, "-m", "geomkit.cad.occ_child", str(p),
                              str(int(skip_invalid)), str(int(skip_unsupported)), out],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        messages = occ_messages(run.stdout)
        if run.returncode != 0 or not os.path.getsize(out):
            before = f"geomkit's STEP reader stopped ({why}) and " if why else ""
            raise FileFormatError(f"{p}: {before}Open CASCADE crashed reading the file "
                                  f"(exit {run.returncode}): it is malformed")
        with open(out, "rb") as fh:
            kind, res, found = pickle.load(fh)
    finally:
        os.unlink(out)
    for category, message in found:
        warnings.warn(message, category, stacklevel=3)
    fails = syntax_failures(messages)
    if kind == "error":
        raise res
    if fails:
        warnings.warn(f"{p}: Open CASCADE read the file only after skipping {fails} "
                      "record(s) with syntax errors; what they held may be missing",
                      FileRecoveredWarning, stacklevel=3)
    return res


_ANSI = re.compile(r"\x1b\[[0-9;]*m")


def occ_messages(raw: bytes) -> list[str]:
    """Open CASCADE's console output as lines (colour codes removed), each logged at
    INFO on the ``geomkit.occ`` logger."""
    import logging

    log = logging.getLogger("geomkit.occ")
    lines = [ln.strip() for ln in _ANSI.sub("", raw.decode("utf-8", "replace")).splitlines()]
    lines = [ln for ln in lines if ln]
    for ln in lines:
        log.info("%s", ln)
    return lines


def syntax_failures(lines) -> int:
    """The count of records OCC's STEP parser skipped as syntax errors (0 for none),
    from its ``ERR StepFile : Incorrect Syntax : Fails Count : N`` message."""
    n = 0
    for ln in lines:
        m = re.search(r"Incorrect Syntax\W*Fails Count\W*(\d+)", ln)
        if m:
            n += int(m.group(1))
    return n


def read_step_occ(path, skip_invalid: bool = False,
                  skip_unsupported: bool = False) -> IgesResult:
    """:func:`read_step` through Open CASCADE, in this process: OCC reads the file
    and builds the B-rep, geomkit converts each face (see the module).  OCC can crash
    on a malformed file and prints on stdout: ``read_step(path, reader="occ")`` runs
    this in a child process instead."""
    p = Path(path)
    try:
        from OCP.BRep import BRep_Tool
        from OCP.BRepBuilderAPI import BRepBuilderAPI_NurbsConvert
        from OCP.BRepTools import BRepTools
        from OCP.GeomConvert import GeomConvert
        from OCP.STEPControl import STEPControl_Reader  # noqa: F401 - the extra is there
        from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_VERTEX
        from OCP.TopExp import TopExp_Explorer
    except ImportError:
        raise MissingDependencyError(INSTALL_HINT) from None
    from geomkit.cad.occ import cast_shape
    shape, units = occ_shape(p)
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
            surf0 = BRep_Tool.Surface_s(face0)
            kind = surf0.DynamicType().Name()
            face, patch, converted = face0, None, False
            raw = _pcurves(face0)
            if kind not in ("Geom_BSplineSurface", "Geom_BezierSurface"):
                # plane, cylinder, cone, sphere, torus, extrusion and revolution of a
                # B-spline: geomkit's own exact patch over the face's pcurves, which
                # are carried onto it (measured)
                box = None
                if raw:
                    P = np.concatenate([c.control_points for w in raw for *_, c in w])
                    box = (*P.min(axis=0), *P.max(axis=0))
                patch = elementary_patch(surf0, BRepTools.UVBounds_s(face0), name, box)
            if patch is not None:
                base = patch[0]
            else:
                if kind not in ("Geom_BSplineSurface", "Geom_BezierSurface"):
                    # offset, other swept: OCC's bounded patch, its pcurves
                    # re-approximated by OCC (their drift is measured below)
                    face = cast_shape("Face",
                                      BRepBuilderAPI_NurbsConvert(face0, True).Shape())
                    converted = True
                    raw = _pcurves(face)
                bs = GeomConvert.SurfaceToBSplineSurface_s(BRep_Tool.Surface_s(face))
                base = _bspline_surface(bs, name, None)
            (u0, u1), (v0, v1) = base.domain
            loops, repairs = [], [] if patch is None else [patch[3]]
            ftol = face_tolerance(face0)
            if patch is None:
                closed = bs.IsUClosed(), bs.IsVClosed()
            else:  # a whole turn: the patch's opposite edges coincide
                closed = closed_directions(base, base.size)
            periods = ((u1 - u0) * closed[0], (v1 - v0) * closed[1])
            for wire in raw:
                pieces = []
                for e, c2, f, l, c in wire:
                    if patch is not None:
                        c, err = carry_pcurve(c, patch)
                        repairs.append(err)
                    elif converted:
                        repairs.append(_drift(e, c2, f, l, base))
                    pieces.append(c)
                if pieces:
                    pieces, g, r = finish_loop(pieces, base, periods, ftol,
                                               f"{name} wire {len(loops)}")
                    gaps += g
                    repairs += r
                    loops.append(pieces)
            s = Surface(base.degree_u, base.degree_v, base.knots_u, base.knots_v,
                        base.control_points, base.weights, loops or None, name=name,
                        approx_error=max(repairs, default=0.0))
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
    check_read(p, surfaces, skipped, skip_unsupported)
    errors = {f"face{k}": s.approx_error for k, s in zip(entities, surfaces)}
    gap, etol = edge_gaps(shape, errors)
    return IgesResult(surfaces, entities, skipped, {"faces": k + 1}, len(gaps),
                      max(gaps, default=0.0), units, _resolution(p), edge_gap=gap,
                      edge_tolerance=etol)
