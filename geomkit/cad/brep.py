"""IGES B-rep faces (186 / 514 / 510 / 508 / 504 / 502) and analytic surfaces
(108, 190 plane, 192 cylinder, 194 cone, 196 sphere, 198 torus) as exact NURBS.

The analytic surfaces are unbounded; each face's surface is built over the range of
its own boundary (:func:`face_surface`).  Boundaries are read from the *model-space*
edge curves (504 edges, 142 ``CPTR``), not from the file's pcurves (their
parametrisation conventions differ between writers: OCC writes angles in degrees):

* Each edge point is inverted in closed form to local coordinates ``(a, b)``: plane
  ``(x, y)`` in the plane's frame; cylinder / cone ``(height, angle)``; sphere
  ``(latitude, longitude)``; torus ``(minor angle, major angle)``.  Angles are unwrapped
  along each edge and chained from edge to edge; the second use of a seam edge in a
  loop is shifted by a full turn.
* On a plane the map is affine, so the pcurve is the edge's own NURBS with mapped
  control points (exact).  On the others an edge that is an iso-line (a circle or a
  generator line: all of OCC's primitives and fillets) is a straight UV segment,
  carried exactly through the angle reparametrisation; any other edge is a
  piecewise-quintic interpolant within ``PCURVE_TOL`` (:func:`geomkit.cad.uvmap.map_edge`:
  one compiled call per edge).
* Consecutive pieces that do not meet in UV (a pole, a degenerate edge) are joined by
  a straight UV segment, which maps to one point there.
* The surfaces are revolutions (:func:`geomkit.cad.analytic.revolve`) of a line or an
  arc, so they hold their closed forms to rounding.
"""

from __future__ import annotations

import math

import numpy as np

from geomkit.cad.analytic import (AngleMap, arc_curve, cross3, line_curve, norm3,
                                  plane_patch, revolve)
from geomkit.cad.iges.entities import curve3d
from geomkit.cad.iges.file import integer as i_
from geomkit.cad.iges.file import real as f_
from geomkit.cad.loops import Unsupported
from geomkit.cad.faceedges import KIND_CODE, Edge, analytic_pieces, edge_points
from geomkit._kernels.arcs import analytic_frame
from geomkit._kernels.pcurve_map import PLANE, local_points, residuals

__all__ = ["Analytic", "analytic", "edge_loop_508", "curve_loop_141", "curve_loop_142",
           "face_surface"]

ANALYTIC = {108: "plane", 190: "plane surface", 192: "right circular cylindrical surface",
            194: "right circular conical surface", 196: "spherical surface",
            198: "toroidal surface"}
_LOCAL_CODE = {"plane": PLANE, **KIND_CODE}
"""The code of each kind for :func:`~geomkit._kernels.pcurve_map.local_points`."""


def _unit(v):
    v = np.asarray(v, float)
    n = norm3(v)
    if not n > 0:
        raise Unsupported("zero direction vector")
    return v / n


def _vec3(v):
    """A float64 3-vector as a contiguous array (itself when it is one), else None."""
    if isinstance(v, np.ndarray) and v.dtype == np.float64 and v.shape == (3,):
        return np.ascontiguousarray(v)
    return None


class Analytic:
    """An analytic surface: frame ``O, X, Y, A`` and its kind's parameters."""

    def __init__(self, kind, O, A, X, R=0.0, r=0.0, alpha=0.0):
        self.kind, self.O = kind, np.asarray(O, float)
        O3, A3, X3 = (_vec3(v) for v in (self.O, A, X))
        if O3 is not None and A3 is not None and X3 is not None:
            # A and X made unit, X orthogonal to A, Y = A x X in one call (the
            # values of the numpy route below)
            code, self.A, self.X, self.Y, self.frame = analytic_frame(O3, A3, X3)
            if code:
                raise Unsupported("zero direction vector")
        else:
            self.A = _unit(A)
            X = np.asarray(X, float) - np.dot(X, self.A) * self.A
            self.X = _unit(X)
            self.Y = cross3(self.A, self.X)
            self.frame = np.concatenate([self.O, self.X, self.Y, self.A])
        self.R, self.r, self.alpha = R, r, alpha
        self.inverse = (_LOCAL_CODE[kind], self.frame, float(R), float(r),
                        math.tan(alpha))
        """The arguments of the compiled inverse (:func:`local_points`)."""
        self.periodic = {"plane": (False, False), "cylinder": (False, True),
                         "cone": (False, True), "sphere": (False, True),
                         "torus": (True, True)}[kind]

    def local(self, P):
        """Closed-form inverse: model points (n, 3) to local ``(a, b)`` (n, 2) and the
        distance of each point from the axis (1 for planes); one compiled call
        (:func:`~geomkit._kernels.pcurve_map.local_points`, as the pcurve kernels
        invert)."""
        return local_points(np.ascontiguousarray(P, dtype=np.float64), *self.inverse)

    def worst_residual(self, P) -> float:
        """The largest distance of the points ``P`` (n >= 1, 3) from the surface (its
        closed form: a cone's two nappes, a spindle torus's inner part), NaN when one
        is: one compiled call (:func:`~geomkit._kernels.pcurve_map.residuals`)."""
        return float(residuals(np.ascontiguousarray(P, dtype=np.float64),
                               _LOCAL_CODE[self.kind], self.frame, float(self.R),
                               float(self.r), float(self.alpha)))

    def offset(self, d):
        """The surface offset by ``d`` along the radial / normal direction (exact: the
        offset of these surfaces is one of the same kind)."""
        if self.kind == "plane":
            return Analytic("plane", self.O + d * self.A, self.A, self.X)
        if self.kind == "torus":
            return Analytic("torus", self.O, self.A, self.X, self.R, self.r + d)
        R = self.R + (d / math.cos(self.alpha) if self.kind == "cone" else d)
        return Analytic(self.kind, self.O, self.A, self.X, R, self.r, self.alpha)

    def build(self, ra, rb):
        """Surface arguments over local ranges ``ra x rb`` and the maps ``fu, fv`` from
        local coordinates to the NURBS parameters."""
        (a0, a1), (b0, b1) = ra, rb
        O, X, A = self.O, self.X, self.A
        if self.kind == "plane":
            return plane_patch(O, X, self.Y, a0, a1, b0, b1), None, None
        fv = AngleMap(b0, b1)
        if self.kind in ("cylinder", "cone"):
            ta = math.tan(self.alpha)
            o, x, ax = O.tolist(), X.tolist(), A.tolist()
            # O + (R + a ta) X + a A at both ends, in floats (numpy's values)
            ends = [[o[c] + (self.R + a * ta) * x[c] + a * ax[c] for c in range(3)]
                    for a in (float(a0), float(a1))]
            gen = line_curve(ends[0], ends[1], a0, a1)
            fu = None
        elif self.kind == "sphere":
            gen = arc_curve(O, X, A, self.R, a0, a1)
            fu = AngleMap(a0, a1)
        else:
            gen = arc_curve(O + self.R * X, X, A, self.r, a0, a1)
            fu = AngleMap(a0, a1)
        return revolve(gen, O, A, b0, b1), fu, fv


def analytic(rd, de: int) -> Analytic:
    """Entity 108 / 190-198 as an :class:`Analytic` (its 124 transform applied)."""
    t = rd.type_of(de)
    r = rd.rec(de)

    def pt(k):
        return np.array([f_(x) for x in rd.rec(k)[1:4]])

    if t == 108:
        a, b, c, d = (f_(x) for x in r[1:5])
        n = np.array([a, b, c])
        nn = float(np.dot(n, n))
        if not nn > 0:
            raise Unsupported(f"plane 108 at DE {de} has a zero normal")
        O = n * d / nn
        ref = np.eye(3)[int(np.argmin(np.abs(n)))]
        s = Analytic("plane", O, n, ref)
    elif t == 190:
        O, N = pt(i_(r[1])), pt(i_(r[2]))
        ref = pt(i_(r[3])) if len(r) > 3 and i_(r[3]) else np.eye(3)[int(np.argmin(np.abs(N)))]
        s = Analytic("plane", O, N, ref)
    elif t in (192, 194, 196, 198):
        O = pt(i_(r[1]))
        A = pt(i_(r[2])) if t != 196 else None
        if t == 192:
            R, ref = f_(r[3]), i_(r[4]) if len(r) > 4 else 0
            kw = dict(R=R)
        elif t == 194:
            R, ang, ref = f_(r[3]), f_(r[4]), i_(r[5]) if len(r) > 5 else 0
            kw = dict(R=R, alpha=math.radians(ang))
        elif t == 196:  # 196: centre, radius, axis, refdir
            R = f_(r[2])
            A = pt(i_(r[3])) if len(r) > 3 and i_(r[3]) else np.array([0.0, 0.0, 1.0])
            ref = i_(r[4]) if len(r) > 4 else 0
            kw = dict(R=R)
        else:
            R, rr, ref = f_(r[3]), f_(r[4]), i_(r[5]) if len(r) > 5 else 0
            kw = dict(R=R, r=rr)
        refv = pt(ref) if ref else np.eye(3)[int(np.argmin(np.abs(A)))]
        kind = {192: "cylinder", 194: "cone", 196: "sphere", 198: "torus"}[t]
        s = Analytic(kind, O, A, refv, **kw)
    else:
        raise Unsupported(f"surface DE {de} is entity {t}, not an analytic surface")
    M = rd.transform(de)
    if M is not None:
        s = Analytic(s.kind, M[:3, :3] @ s.O + M[:3, 3], M[:3, :3] @ s.A,
                     M[:3, :3] @ s.X, s.R, s.r, s.alpha)
    return s




def edge_loop_508(rd, de: int):
    """The oriented model-space edges of a 508 loop (vertex entries are dropped)."""

    r = rd.rec(de)
    n = i_(r[1])
    a, out = 2, []
    for _ in range(n):
        typ, lst, ndx, of, k = (i_(x) for x in r[a: a + 5])
        a += 5 + 2 * k
        if typ == 1:
            continue
        e = rd.rec(lst)
        cde = i_(e[2 + 5 * (ndx - 1)])
        curve, _, _ = curve3d(rd, cde)
        out.append(Edge(curve, (lst, ndx), of == 0))
    if not out:
        raise Unsupported(f"loop 508 at DE {de} has no edges")
    return out


def curve_loop_142(rd, de: int):
    """The model-space curve ``CPTR`` of a 142 as oriented edges (102 composites
    split)."""

    def walk(c):
        if rd.type_of(c) == 102:
            r = rd.rec(c)
            return [x for k in range(i_(r[1])) for x in walk(i_(r[2 + k]))]
        curve, _, _ = curve3d(rd, c)
        return [Edge(curve, ("c", c), False)]

    cptr = i_(rd.rec(de)[4])
    if not cptr:
        raise Unsupported(f"boundary 142 at DE {de} has neither a parameter-space nor a "
                          "model-space curve")
    return walk(cptr)


def curve_loop_141(rd, de: int):
    """The model-space curves of a 141 boundary as oriented edges (``SENSE = 2``:
    reversed)."""

    if rd.type_of(de) != 141:
        raise Unsupported(f"boundary DE {de} is entity {rd.type_of(de)}, expected 141")
    r = rd.rec(de)
    n, a, out = i_(r[4]), 5, []
    for _ in range(n):
        crv, sense, k = i_(r[a]), i_(r[a + 1]), i_(r[a + 2])
        a += 3 + k
        parts = []

        def walk(c):
            if rd.type_of(c) == 102:
                rc = rd.rec(c)
                for j in range(i_(rc[1])):
                    walk(i_(rc[2 + j]))
            else:
                parts.append(Edge(curve3d(rd, c)[0], ("c", c), False))

        walk(crv)
        if sense == 2:
            parts = [Edge(e.curve, e.key, True) for e in parts[::-1]]
        out += parts
    if not out:
        raise Unsupported(f"boundary 141 at DE {de} has no curves")
    return out


def face_surface(rd, srf_de: int, loops, tol_rel: float):
    """``(surface args, [loops of TrimCurve pieces], domain)`` of one face: the
    analytic surface ``srf_de`` over the range of its boundary ``loops`` (lists of
    :class:`Edge`, outer first)."""
    if rd.type_of(srf_de) == 140:  # offset of an analytic surface: exact, the side
        # that holds the face's edges
        r = rd.rec(srf_de)
        if rd.transform(srf_de) is not None:
            raise Unsupported(f"offset surface DE {srf_de} with its own transformation")
        base = analytic(rd, i_(r[5]))
        P = edge_points(loops)
        cands = [base.offset(f_(r[4])), base.offset(-f_(r[4]))]
        srf = min(cands, key=lambda c: c.worst_residual(P))
    else:
        srf = analytic(rd, srf_de)
    return analytic_pieces(srf, loops, tol_rel, f"surface DE {srf_de}")
