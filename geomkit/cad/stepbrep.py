"""Reading a STEP file's B-rep faces without Open CASCADE: the file's own topology
and geometry (:mod:`geomkit.cad.p21`, :mod:`geomkit.cad.stepgeom`) to trimmed surfaces.

* **Which faces.** Every face of every shell of the shape representations that hold
  solids or surface models (``MANIFOLD_SOLID_BREP``, ``BREP_WITH_VOIDS``,
  ``SHELL_BASED_SURFACE_MODEL``, ``FACE_BASED_SURFACE_MODEL``), in file order of
  their shells; in an assembly, every occurrence of a part where its placements put
  it (:mod:`geomkit.cad.stepasm`), each part's faces converted once.
  (:class:`~geomkit.cad.loops.Unsupported`: the caller reads them through OCC).
* **Edges.** Each edge is its 3-D curve between its two vertices, an exact NURBS
  (:meth:`~geomkit.cad.stepgeom.Curve.nurbs`), run the way the loop runs it.  STEP
  files rarely carry pcurves (none of the 17 real parts of the test corpus does), so
  the UV boundary comes from the 3-D edges, as in the IGES B-rep reader:
  closed-form inversion on planes, cylinders, cones, spheres and tori
  (:func:`geomkit.cad.faceedges.analytic_pieces`: exact on iso-lines, within the pcurve
  tolerance elsewhere), projection onto B-spline surfaces
  (:func:`geomkit.cad.edgeproj.edge_uv`, within the model's tolerance, unwrapped
  across closed directions).
* **Loops** are then finished as the OCC path finishes the file's pcurves
  (:func:`geomkit.cad.step.finish_loop`): chained across seams, clipped to the
  domain, gaps within the face's tolerance bridged, every repair stated in
  ``approx_error``.
"""

from __future__ import annotations

import re

import numpy as np

from geomkit.cad.analytic import cross3, curve_eval, extrude, revolve
from geomkit.cad.faceedges import Edge, analytic_pieces
from geomkit.cad.edgeproj import edge_uv
from geomkit.cad.iges.reader import IgesResult, Skipped
from geomkit.cad.loose import duplicate_faces
from geomkit.cad.loops import Unsupported, finish_loop
from geomkit.cad.p21 import P21, Ref, read_p21
from geomkit.cad.stepasm import instances
from geomkit.cad.stepedges import fields_of, line_and_circle_edges
from geomkit.cad.stepgeom import StepGeometry, reverse_curve
from geomkit.cad.stepseam import cap_point, cut_at_seam, merge_winding, start_inside
from geomkit.errors import FileFormatError, InvalidInputError, InvalidSurfaceError
from geomkit.mesh.tessellate import closed_directions
from geomkit.nurbs.surface import Surface
from geomkit.tolerances import EDGE_TOL, PCURVE_TOL
from geomkit._kernels.pcurve_map import CYLINDER, local_points
from geomkit._kernels.ranges import hull_spread

__all__ = ["read_native", "file_units", "UnreadFaces"]

TWO_PI = 2.0 * np.pi

_LENGTH = {"MILLI": ("mm", 1.0), "CENTI": ("cm", 10.0), "MICRO": ("um", 1e-3),
           "KILO": ("km", 1e6), None: ("m", 1000.0)}
_NAMED = {"INCH": "in", "FOOT": "ft", "MIL": "mil", "MICROINCH": "uin", "MILLIMETRE": "mm",
          "METRE": "m", "CENTIMETRE": "cm"}
_REPS = ("ADVANCED_BREP_SHAPE_REPRESENTATION", "MANIFOLD_SURFACE_SHAPE_REPRESENTATION",
         "SHAPE_REPRESENTATION", "EDGE_BASED_WIREFRAME_SHAPE_REPRESENTATION")
_ITEMS = ("MANIFOLD_SOLID_BREP", "BREP_WITH_VOIDS", "SHELL_BASED_SURFACE_MODEL",
          "FACE_BASED_SURFACE_MODEL")


def _context_units(p: P21, ctx):
    """``(length unit name, angle in radians per unit, uncertainty)`` of a
    representation context (None where the file does not say)."""
    name, parts = p.get(ctx)
    if name is not None:
        return None, 1.0, None
    unit, angle, unc = None, 1.0, None
    for u in (parts.get("GLOBAL_UNIT_ASSIGNED_CONTEXT") or [[]])[0]:
        un, up = p.get(u)
        if un is not None:
            continue
        if "LENGTH_UNIT" in up:
            if "SI_UNIT" in up:
                prefix = up["SI_UNIT"][0]
                unit = _LENGTH.get(None if prefix is None else str(prefix), (None,))[0]
            elif "CONVERSION_BASED_UNIT" in up:
                unit = _NAMED.get(str(up["CONVERSION_BASED_UNIT"][0]).upper(),
                                  str(up["CONVERSION_BASED_UNIT"][0]).lower())
        elif "PLANE_ANGLE_UNIT" in up and "CONVERSION_BASED_UNIT" in up:
            m = up["CONVERSION_BASED_UNIT"][1]
            _, mp = p.get(m)
            v = mp[0].value if hasattr(mp[0], "value") else mp[0]
            angle = float(v)
            # the factor's own unit is the radian (or a degree given as 0.01745...)
    for u in (parts.get("GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT") or [[]])[0]:
        un, up = p.get(u)
        if un == "UNCERTAINTY_MEASURE_WITH_UNIT":
            v = up[0].value if hasattr(up[0], "value") else up[0]
            try:
                unc = max(unc or 0.0, float(v))
            except (TypeError, ValueError):
                pass
    return unit, angle, unc


def file_units(p: P21):
    """The length unit, angle factor and uncertainty of the first shape
    representation that holds B-rep items."""
    for i in p.of_type(*_REPS):
        _, a = p.get(i)
        if len(a) > 2 and isinstance(a[2], Ref):
            u = _context_units(p, a[2])
            if u[0] is not None:
                return u
    return None, 1.0, None


def _rep_items(p: P21) -> dict:
    """Shape representation id -> its item ids."""
    out = {}
    for i in p.of_type(*_REPS):
        _, a = p.get(i)
        out[i] = [int(x) for x in a[1]] if len(a) > 1 and isinstance(a[1], list) else []
    return out


def _shells(p: P21, reps=None):
    """Shell ids of the B-rep items of the representations ``reps`` (default: every
    shape representation), in file order, each once."""
    out = []
    for i in (p.of_type(*_REPS) if reps is None else reps):
        _, a = p.get(i)
        for it in a[1] if len(a) > 1 and isinstance(a[1], list) else []:
            if not isinstance(it, Ref) or p.names.get(int(it)) not in _ITEMS:
                continue
            name, b = p.get(it)
            if name == "MANIFOLD_SOLID_BREP":
                out.append(b[1])
            elif name == "BREP_WITH_VOIDS":
                out += [b[1], *b[2]]
            else:
                out += list(b[1])
    seen, uniq = set(), []
    for s in out:
        if int(s) not in seen:
            seen.add(int(s))
            uniq.append(int(s))
    return uniq


def _holds_brep(p: P21, rep) -> bool:
    name, a = p.get(rep)
    items = a[1] if name is not None and len(a) > 1 and isinstance(a[1], list) else []
    return any(isinstance(it, Ref) and p.names.get(int(it)) in _ITEMS for it in items)


def _placed(p: P21, geom: StepGeometry) -> bool:
    """The file places B-rep representations by transformations other than the
    identity (an assembly), through representation relationships or mapped items."""
    for i in p.complex_ids("REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION"):
        _, parts = p.get(i)
        t = parts.get("REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION", [None])[0]
        if t is None or p.names.get(int(t)) != "ITEM_DEFINED_TRANSFORMATION":
            return True
        _, ta = p.get(t)
        if not _same_place(geom, ta[2], ta[3]):
            return True
    for i in p.of_type("MAPPED_ITEM"):
        _, a = p.get(i)
        _, m = p.get(a[1])
        if _holds_brep(p, m[1]) and not _same_place(geom, m[0], a[2]):
            return True
    return False


def _same_place(geom, a, b) -> bool:
    if _name(geom, a) != "AXIS2_PLACEMENT_3D" or _name(geom, b) != "AXIS2_PLACEMENT_3D":
        return False
    A, B = geom.axis2(a), geom.axis2(b)
    return all(np.abs(x - y).max() <= 1e-12 * max(1.0, np.abs(x).max())
               for x, y in zip(A, B))


def _name(geom, i):
    return geom.p.names.get(int(i)) if isinstance(i, Ref) else None


def check_read(source, surfaces, skipped, skip_unsupported, error=FileFormatError):
    """Raise ``error`` listing the faces that could not be converted (unless
    ``skip_unsupported``), or :class:`~geomkit.errors.FileFormatError` when no face
    was read; shared by both STEP readers."""
    unsupported = [s for s in skipped if not s.reason.startswith("invalid:")]
    if unsupported and not skip_unsupported:
        lines = "; ".join(str(s) for s in unsupported[:5])
        raise error(f"{source}: {len(unsupported)} face(s) cannot be read: {lines}; "
                    "pass skip_unsupported=True (--skip-unsupported) to go on without "
                    "them")
    if not surfaces:
        raise FileFormatError(f"{source}: no readable face" + (
            f"; first skipped: {skipped[0]}" if skipped else ""))


class UnreadFaces(FileFormatError):
    """Faces of a sound file that the reader does not convert (listed with why)."""


_IDS = r"\(\s*(#\d+(?:\s*,\s*#\d+)*)\s*\)"
_PLAIN = {
    "face": re.compile(r"(ADVANCED_FACE|FACE_SURFACE)\s*\(\s*'[^']*'\s*,\s*" + _IDS
                       + r"\s*,\s*#(\d+)\s*,\s*\.([TF])\.\s*\)"),
    "bound": re.compile(r"(FACE_OUTER_BOUND|FACE_BOUND)\s*\(\s*'[^']*'\s*,\s*#(\d+)"
                        r"\s*,\s*\.([TF])\.\s*\)"),
    "loop": re.compile(r"EDGE_LOOP\s*\(\s*'[^']*'\s*,\s*" + _IDS + r"\s*\)"),
}
"""The writers' plain form of a face, its bounds and their edge loops (a label,
references, a sense), read at once; any other form goes through the parser."""
_ID = re.compile(r"#(\d+)")


class _Faces:
    def __init__(self, p: P21, geom: StepGeometry):
        self.p, self.g = p, geom
        found: dict = {}  # the plain edge and vertex records' fields, read on the way
        self._edges: dict = line_and_circle_edges(p, found)  # id -> its curve (see edge)
        self._edge_fields, self._vertex_fields = found["EDGE_CURVE"], found["VERTEX_POINT"]
        self._samples: dict = {}  # (id(edge curve), n) -> its points
        self._face_recs: dict = {}  # face id -> (bounds, surface, same sense)
        ids = p.of_type("ORIENTED_EDGE")  # id -> (edge id, same sense), plain ones
        self._oriented = dict(zip(ids, fields_of(p, ids, "ORIENTED_EDGE")))

    def edge(self, i):
        """The edge curve (exact NURBS) run from its start vertex to its end vertex."""
        i = int(i)
        e = self._edges.get(i)
        if e is not None:
            return e
        f = self._edge_fields.get(i)  # (ids and the sense of a plain record)
        if f is None:
            _, a = self.g.rec(i, "EDGE_CURVE")
            f = a[1], a[2], a[3], a[4]
        v1, v2, cid, same = f
        X1, X2 = self.vertex(v1), self.vertex(v2)
        c = self.g.curve(cid)
        closed = int(v1) == int(v2)
        bounds = c.bounds
        if closed and c.period is None and bounds is not None:
            t1, t2 = bounds  # (a closed bounded curve: its whole range, whatever
            # its vertex's parameters, which are not sought)
        else:
            t1, t2 = c.param(X1), c.param(X2)
            if same is False:
                t1, t2 = t2, t1
            if c.period is not None:
                t2 = t1 + (t2 - t1) % c.period
                if closed or t2 - t1 <= 1e-12:
                    t2 = t1 + c.period
            elif bounds is not None and abs(t2 - t1) <= 1e-12 * (bounds[1] - bounds[0]):
                t1, t2 = bounds
        if not t2 > t1:
            raise Unsupported(f"edge #{i}: its vertices are in reverse order on its curve")
        curve = c.nurbs(t1, t2)
        if same is False:
            curve = reverse_curve(curve)
        e = self._edges[i] = curve
        return e

    def vertex(self, i):
        f = self._vertex_fields.get(int(i))  # (its point's id, of a plain record)
        if f is not None:
            return self.g.point(f[0])
        _, a = self.g.rec(i, "VERTEX_POINT")
        return self.g.point(a[1])

    def face(self, face):
        """``(bounds, surface, same_sense)`` of face record ``face`` (read once: the
        face's loops and its surface both ask)."""
        got = self._face_recs.get(int(face))
        if got is None:
            m = _PLAIN["face"].fullmatch(self.p.body(face))
            if m is None:
                _, a = self.g.rec(face, "ADVANCED_FACE", "FACE_SURFACE")
                got = a[1], a[2], a[3]
            else:
                got = [int(x) for x in _ID.findall(m[2])], int(m[3]), m[4] == "T"
            self._face_recs[int(face)] = got
        return got

    def _bound(self, b):
        """``(name, loop name, loop params, orientation)`` of bound record ``b`` (an
        edge loop's params: ``[label, [oriented edges]]``)."""
        m = _PLAIN["bound"].fullmatch(self.p.body(b))
        if m is None:
            bname, ba = self.g.rec(b, "FACE_OUTER_BOUND", "FACE_BOUND")
            loop, sense = ba[1], ba[2]
        else:
            bname, loop, sense = m[1], int(m[2]), m[3] == "T"
        m = _PLAIN["loop"].fullmatch(self.p.body(loop))
        if m is None:
            lname, la = self.g.rec(loop, "EDGE_LOOP", "VERTEX_LOOP", "POLY_LOOP")
        else:
            lname, la = "EDGE_LOOP", [None, [int(x) for x in _ID.findall(m[1])]]
        return bname, lname, la, sense

    def loops(self, face):
        """The face's bounds as lists of oriented :class:`~geomkit.cad.faceedges.Edge`,
        outer bound first, and the points of its vertex loops (a pole, an apex)."""
        outer, inner, vertices = [], [], []
        for b in self.face(face)[0]:
            bname, lname, la, sense = self._bound(b)
            if lname != "EDGE_LOOP":
                if lname == "POLY_LOOP":
                    raise Unsupported(f"face #{int(face)}: a POLY_LOOP bound")
                vertices.append(self.vertex(la[1]))
                continue
            edges = []
            for oe in la[1]:
                f = self._oriented.get(int(oe))
                if f is None:
                    _, oa = self.g.rec(oe, "ORIENTED_EDGE")
                    key, rev = int(oa[3]), oa[4] is False
                else:
                    key, rev = f[0], not f[1]
                edges.append(Edge(self.edge(key), key, rev, self._samples))
            if sense is False:
                edges = [Edge(e.curve, e.key, not e.reverse, self._samples)
                         for e in edges[::-1]]
            (outer if bname == "FACE_OUTER_BOUND" else inner).append(edges)
        if not outer and len(inner) > 1:  # no outer bound named: the widest loop
            inner.sort(key=_extent_down)
        return outer + inner, np.array(vertices).reshape(-1, 3)


def _extent_down(loop):
    """Minus the largest extent along x, y or z of a loop's control points (a sort
    key: the widest loop first), in one compiled call."""
    return -hull_spread(np.concatenate([e.curve[2] for e in loop]))


def _bspline_base(args, name):
    p, q, U, V, P, W = args
    return Surface.of_arrays(p, q, U, V, P, W, name=name)


class _Axis:
    """Angles about a surface of revolution's axis (for :func:`_cut_at_seam`)."""

    kind = "revolution"

    def __init__(self, O, A):
        self.O, self.A = O, A
        X = np.eye(3)[int(np.argmin(np.abs(A)))]
        self.X = X - (X @ A) * A
        self.X /= np.linalg.norm(self.X)
        self.Y = cross3(A, self.X)
        self.frame = np.concatenate([O, self.X, self.Y, A])
        self.inverse = (CYLINDER, self.frame, 0.0, 0.0, 0.0)

    def local(self, P):
        """Height along and angle about the axis of points (n, 3), and their distance
        from it."""
        return local_points(np.ascontiguousarray(P, dtype=np.float64), *self.inverse)


def _swept_base(kind, srf, loops):
    """``(p, q, U, V, P, W)`` of an extrusion or a revolution over a range that holds
    the face: the swept curve's range (bounded curves only), the extrusion's length
    over the edges' extent along it, the revolution's whole turn starting at an angle
    off the face (or crossed once by each loop around the axis; those loops are cut
    there in place, as on a cylinder)."""
    c = srf[0]
    if c.bounds is None:
        raise Unsupported(f"a swept {c.kind}: only B-spline and polyline curves are read")
    curve = c.nurbs(*c.bounds)
    if kind == "extrusion":
        X = np.concatenate([e.points(33) for lp in loops for e in lp])
        V = srf[1]
        vv = float(V @ V)
        C = curve_eval(curve, np.linspace(*c.bounds, 257))
        lo = (float((X @ V).min()) - float((C @ V).max())) / vv
        hi = (float((X @ V).max()) - float((C @ V).min())) / vv
        pad = 1e-6 * (hi - lo) + 1e-12
        p, U, Pw = curve
        w = Pw[:, 3:]
        P0 = Pw[:, :3] / w + (lo - pad) * V
        return extrude((p, U, np.column_stack([P0 * w, w])), (hi - lo + 2 * pad) * V)
    ax = _Axis(srf[1], srf[2])
    loops[:], _, theta = cut_at_seam(ax, list(loops), sweep=True)
    p, q, U, V, P, W = revolve(curve, ax.O, ax.A, 0.0, TWO_PI)
    # turned so that the patch's seam (the curve) lies at theta about the axis
    ref = curve_eval(curve, np.array([c.bounds[0]]))[0] - ax.O
    t = theta - float(np.arctan2(ref @ ax.Y, ref @ ax.X))
    A = ax.A
    K = np.array([[0, -A[2], A[1]], [A[2], 0, -A[0]], [-A[1], A[0], 0]])
    R = np.eye(3) + np.sin(t) * K + (1 - np.cos(t)) * (K @ K)
    P = (P - ax.O) @ R.T + ax.O
    return p, q, U, V, P, W


def _face(F, geom, face, name, unc):
    """``(Surface, UV gaps bridged, edge fit error)`` of one face (see the module)."""
    loops, apex = F.loops(face)
    _, surface, same_sense = F.face(face)
    kind, srf = geom.surface(surface)
    repairs, gaps, fit_error = [], [], 0.0
    if kind in ("extrusion", "revolution"):
        srf = _swept_base(kind, srf, loops)
    if kind == "analytic":
        loops, turns = cut_at_seam(srf, loops)
        if not len(apex) and sum(1 for t in turns if t) == 1:
            apex = cap_point(srf, sum(turns), same_sense)
        args, uv_loops, _ = analytic_pieces(srf, loops, PCURVE_TOL, name, apex,
                                            bridge=False)
        base = _bspline_base(args, name)
    else:
        base = _bspline_base(srf, name)
    (u0, u1), (v0, v1) = base.domain
    # a plane patch is never closed (it spans more than 1e-9 of its range both ways:
    # analytic_pieces)
    plane = kind == "analytic" and srf.kind == "plane"
    closed = (False, False) if plane else closed_directions(base, base.size)
    periods = ((u1 - u0) * closed[0], (v1 - v0) * closed[1])
    ftol = max(unc or 0.0, EDGE_TOL * base.size)
    if kind != "analytic":
        uv_loops = []
        for j, lp in enumerate(loops):
            pieces, err = edge_uv(base, lp, ftol, f"{name} loop {j}", periods)
            fit_error = max(fit_error, err)
            repairs.append(err)
            uv_loops.append(start_inside(pieces, base))
    uv_loops = merge_winding(uv_loops, base, periods, name)
    trim = []
    for j, pieces in enumerate(uv_loops):
        pieces, g, r = finish_loop(pieces, base, periods, ftol, f"{name} wire {j}")
        gaps += g
        repairs += r
        trim.append(pieces)
    s = base.with_trim(trim or None, approx_error=max(repairs, default=0.0))
    # how far the face's surface lies from its edges (closed form on analytic faces,
    # the projection's on the others): the model's gap at an edge is at most the
    # two faces' distances plus their approximation errors
    if kind == "analytic":
        X = np.concatenate([e.points(9) for lp in loops for e in lp]) if loops \
            else np.empty((0, 3))
        off = srf.worst_residual(X) if len(X) else 0.0
    else:
        off = fit_error
    keys = {e.key for lp in loops for e in lp}
    return s, gaps, fit_error, off + s.approx_error, keys


_MALFORMED = (IndexError, TypeError, KeyError, AttributeError)
"""What reading a record with missing or mistyped parameters raises (a list where a
reference should be, too few parameters)."""


def _malformed(source, where, exc) -> FileFormatError:
    return FileFormatError(f"{source}: {where}: a record with missing or mistyped "
                           f"parameters ({type(exc).__name__}: {exc})")


def read_native(path, skip_invalid: bool = False, skip_unsupported: bool = False,
                data: bytes | None = None):
    """Every face of a STEP file's B-rep as a trimmed :class:`~geomkit.Surface`, read
    by geomkit alone (see the module); an :class:`~geomkit.cad.iges.reader.IgesResult`
    as :func:`geomkit.cad.step.read_step` returns.  Raises
    :class:`~geomkit.cad.loops.Unsupported` for a file it does not read (an
    assembly), :class:`UnreadFaces` for faces it cannot convert (unless
    ``skip_unsupported``), :class:`~geomkit.errors.FileFormatError` for a malformed
    file.  ``data``: the file's bytes when already read."""
    p = read_p21(path, data)
    try:
        unit, angle, unc = file_units(p)
        geom = StepGeometry(p, angle)
        if _placed(p, geom):  # an assembly: each part's shells where they sit
            items = _rep_items(p)
            placed = [(_shells(p, [r]), M) for r, M in
                      instances(p, geom, items, lambda r: _holds_brep(p, r))]
        else:
            placed = [(_shells(p), None)]
    except _MALFORMED as exc:
        raise _malformed(p.source, "its product structure", exc) from None
    if not any(sh for sh, _ in placed):
        raise FileFormatError(f"{p.source}: no solid or surface model (no shell)")
    F = _Faces(p, geom)
    surfaces, entities, skipped, gaps = [], [], [], []
    fit_error = 0.0
    loose, closed_faces = [], 0   # positions of faces outside the solids
    at_edge: dict = {}  # (occurrence, edge id) -> each face's distance from it
    done: dict = {}  # face id -> its conversion (a part placed twice is read once)
    k = -1
    for occ, (shells, M) in enumerate(placed):
        for sh in shells:
            kind, sa = geom.rec(sh, "CLOSED_SHELL", "OPEN_SHELL", "CONNECTED_FACE_SET",
                                "ORIENTED_CLOSED_SHELL")
            is_open = kind in ("OPEN_SHELL", "CONNECTED_FACE_SET")
            closed_faces += 0 if is_open else len(sa[1])
            for face in sa[1]:
                k += 1
                name = f"face{k}"
                try:
                    if int(face) not in done:
                        done[int(face)] = _face(F, geom, face, name, unc)
                    s, g, err, dev, keys = done[int(face)]
                    s = _placed_surface(s, M, name)
                    gaps += g
                    fit_error = max(fit_error, err)
                    for key in keys:
                        at_edge.setdefault((occ, key), []).append(dev)
                except InvalidInputError as exc:
                    if not skip_invalid:
                        raise InvalidSurfaceError(f"{p.source}: face {k}: {exc}") from None
                    skipped.append(Skipped(name, f"invalid: {exc}"))
                    continue
                except (FileFormatError,) + _MALFORMED as exc:
                    # a malformed record: the file is broken, not merely beyond this
                    # reader (never handed on to another reader)
                    err = exc if isinstance(exc, FileFormatError) else \
                        _malformed(p.source, f"face {k}", exc)
                    if not skip_unsupported:
                        raise FileFormatError(f"face {k}: {err}") from None
                    skipped.append(Skipped(name, f"malformed ({err})"))
                    continue
                except (Unsupported, ValueError) as exc:
                    skipped.append(Skipped(name, f"cannot convert ({exc})"))
                    continue
                if is_open:
                    loose.append(len(surfaces))
                surfaces.append(s)
                entities.append(k)
    check_read(p.source, surfaces, skipped, skip_unsupported, UnreadFaces)
    shared = [sorted(d)[-2:] for d in at_edge.values() if len(d) > 1]
    edge_gap = max((sum(d) for d in shared), default=None)
    if not closed_faces:
        loose = []                 # a surface model alone: nothing is loose
    dup = {}
    if loose:
        size = max(s.size for s in surfaces)
        dup = duplicate_faces(surfaces, loose, max(unc or 0.0, edge_gap or 0.0,
                                                   1e-9 * size))
    return IgesResult(surfaces, entities, skipped, {"faces": k + 1}, len(gaps),
                      max(gaps, default=0.0), unit, unc, edge_fit_error=fit_error,
                      edge_gap=edge_gap, loose=loose, duplicates=dup)


def _placed_surface(s, M, name):
    """``s`` carried by the 4 x 4 matrix ``M`` (exact: affine maps commute with
    NURBS), named ``name``."""
    if M is None and s.name == name:
        return s
    return s.placed(M, name)
