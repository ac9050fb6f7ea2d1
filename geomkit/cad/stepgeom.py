"""STEP geometry (ISO 10303-42) from the records of :mod:`geomkit.cad.p21`: points,
placements, curves as exact NURBS between two vertices, surfaces as closed forms
(:class:`~geomkit.cad.brep.Analytic`) or B-spline nets.

Coordinates stay in the file's length unit; angles given as parameters (a cone's
semi-angle) are converted from the file's plane-angle unit (``angle``, radians per
unit).  Curve parameters follow ISO 10303-42: a line's is the distance along its
vector over the vector's magnitude, a circle's and an ellipse's the angle (radians
here), a B-spline's its knots.
"""

from __future__ import annotations

import math
import re

import numpy as np

from geomkit.cad.analytic import (arc_curve, cross3, curve_derivs, line_curve, norm3,
                                  turn_angle)
from geomkit.cad.brep import Analytic
from geomkit.cad.iges.entities import restrict
from geomkit.cad.loops import Unsupported
from geomkit.cad.p21 import P21, Ref
from geomkit.errors import FileFormatError
from geomkit._kernels.arcs import axis2_x, axis2_zx
from geomkit._kernels.bezier import curve_nearest_param

__all__ = ["StepGeometry", "Curve", "reverse_curve"]

TWO_PI = 2.0 * math.pi

_AXES_XY = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])  # axis2's default X: +x, +y
_AXES_XY.flags.writeable = False
_Z_UP = np.array([0.0, 0.0, 1.0])  # axis2's default Z (read only)
_Z_UP.flags.writeable = False
_NUM = r"[-+]?(?:\d+\.\d*|\d*\.\d+|\d+)(?:[Ee][-+]?\d+)?"
_ENUM = r"\s*,\s*\.[A-Za-z_]+\."
_BSPLINE_CURVE = re.compile(
    r"B_SPLINE_CURVE_WITH_KNOTS\s*\(\s*'[^']*'\s*,\s*(\d+)\s*,"
    r"\s*\(\s*(#\d+(?:\s*,\s*#\d+)*)\s*\)" + _ENUM * 3 + r"\s*,"
    r"\s*\(\s*(\d+(?:\s*,\s*\d+)*)\s*\)\s*,"
    r"\s*\(\s*(" + _NUM + r"(?:\s*,\s*" + _NUM + r")*)\s*\)" + _ENUM + r"\s*\)")
"""A writer's plain B-spline curve record: a label, the degree, the control points'
references, three enumerations, the multiplicities and the knots, an enumeration."""


def reverse_curve(curve):
    """The NURBS ``(p, U, Pw)`` run the other way over the same parameter range."""
    p, U, Pw = curve
    U = np.asarray(U, float)
    return p, (U[0] + U[-1]) - U[::-1], np.ascontiguousarray(Pw[::-1])


def _knots(mults, knots):
    return np.repeat(np.asarray(knots, float), np.asarray(mults, int))


def _clamped_ends(p, U, Pw) -> list:
    """``[(parameter, end point, step to the next control point, whether that step
    is not zero)]`` of a B-spline's clamped ends (start, end), Cartesian."""
    E = Pw[[0, -1, 1, -2]]
    E = E[:, :3] / E[:, 3:]
    S = E[2:] - E[:2]
    moves = S.any(axis=1).tolist()
    lo, hi = float(U[p]), float(U[-p - 1])
    out = []
    if all(u == lo for u in U[:p + 1].tolist()):
        out.append((lo, E[0], S[0], moves[0]))
    if all(u == hi for u in U[-p - 1:].tolist()):
        out.append((hi, E[1], S[1], moves[1]))
    return out


class Curve:
    """A 3-D curve: ``kind`` (line, circle, ellipse, bspline, polyline), its closed
    form, :meth:`param` (the parameter of the nearest point) and :meth:`nurbs` (the
    exact piece between two parameters, in the curve's direction)."""

    def __init__(self, kind, **kw):
        self.kind = kind
        self.__dict__.update(kw)
        self.period = TWO_PI if kind in ("circle", "ellipse") else None
        self._ends = None  # a B-spline's clamped ends (_clamped_ends)
        self._extent = None  # (_near)

    def param(self, X) -> float:
        X = np.asarray(X, float)
        if self.kind == "line":
            return float((X - self.O) @ self.D / (self.D @ self.D))
        if self.kind in ("circle", "ellipse"):
            d = X - self.C
            return turn_angle((d @ self.Y) / self.b, (d @ self.X) / self.a)
        return self._locate(X)

    def _locate(self, X):
        """Nearest parameter of a B-spline / polyline: the nearest of dense samples,
        then Newton on ``(C - X) . C'``."""
        p, U, Pw = self.spline
        # a vertex is most often at a clamped end (its control point): that end's
        # parameter when the vertex is that point, or lies within 1e-6 of the curve's
        # extent of it on the outer side of the end's tangent (the end is then the
        # local minimum Newton would reach, clamped)
        # (the nearer end of a closed curve)
        if self._ends is None:  # (kept: each of an edge's two vertices asks)
            self._ends = _clamped_ends(p, U, Pw)
        near = []
        for t, E, step, moves in self._ends:
            d = E - X
            dd = float(d @ d)
            if dd == 0.0:
                return t
            if moves:
                near.append((dd, t, d, step))
        best = None
        for dd, t, d, step in near:  # (the nearer end of a closed curve)
            if (best is None or dd < best[0]) and float(d @ step) >= 0.0 \
                    and dd <= self._near():
                best = (dd, t)
        if best is not None:
            return best[1]
        return float(curve_nearest_param(np.ascontiguousarray(Pw, float), int(p),
                                         np.asarray(U, float), np.ascontiguousarray(X, float),
                                         max(65, 8 * (len(U) - p))))

    def _near(self) -> float:
        """The square of 1e-6 x the curve's extent (the largest range of its control
        points' coordinates), computed once."""
        if self._extent is None:
            Pw = self.spline[2]
            near = 1e-6 * float(np.ptp(Pw[:, :3] / Pw[:, 3:], axis=0).max())
            self._extent = near * near
        return self._extent

    @property
    def bounds(self):
        """The parameter range of a bounded curve (B-spline, polyline), else None."""
        if self.kind in ("bspline", "polyline"):
            p, U, _ = self.spline
            return float(U[p]), float(U[-p - 1])
        return None

    def point(self, t):
        t = np.atleast_1d(np.asarray(t, float))
        if self.kind == "line":
            return self.O + t[:, None] * self.D
        if self.kind in ("circle", "ellipse"):
            return (self.C + self.a * np.cos(t)[:, None] * self.X
                    + self.b * np.sin(t)[:, None] * self.Y)
        return curve_derivs(self.spline, t, 0)[:, 0, :]

    def nurbs(self, t0: float, t1: float):
        """``(p, U, Pw)`` of the curve over ``[t0, t1]`` (``t0 < t1``), exact."""
        if self.kind == "line":
            return line_curve(self.O + t0 * self.D, self.O + t1 * self.D, t0, t1)
        if self.kind in ("circle", "ellipse"):
            return arc_curve(self.C, self.a * self.X, self.b * self.Y, 1.0, t0, t1)
        p, U, Pw = self.spline
        U2, Pw2 = restrict(p, U, Pw, t0, t1)
        return p, U2, Pw2


class StepGeometry:
    """Geometry records of one :class:`~geomkit.cad.p21.P21` file, converted once and
    kept (see the module)."""

    def __init__(self, p21: P21, angle: float = 1.0):
        self.p = p21
        self.angle = float(angle)
        self._curves: dict = {}
        self._surfaces: dict = {}

    # ---------------------------------------------------------------- records
    def rec(self, i, *names):
        """``(name, params)`` of record ``i``, which must be one of ``names`` (a complex
        record gives its parts' dict as params and the first of ``names`` it holds)."""
        name, params = self.p.get(i)
        if name is None:
            for n in names:
                if n in params:
                    return n, params
            raise Unsupported(f"#{int(i)} is a complex entity of "
                              f"{', '.join(params)}, expected {' or '.join(names)}")
        if names and name not in names:
            raise Unsupported(f"#{int(i)} is {name}, expected {' or '.join(names)}")
        return name, params

    def _bad(self, i, what):
        return FileFormatError(f"{self.p.source} #{int(i)}: {what}")

    def numbers(self, i, vals, n=None):
        try:
            out = np.array([float(v) for v in vals])
        except (TypeError, ValueError):
            raise self._bad(i, f"expected numbers, found {vals!r}") from None
        if n is not None and out.size != n or not np.isfinite(out).all():
            raise self._bad(i, f"expected {n or ''} finite numbers, found {vals!r}")
        return out

    def point(self, i):
        x = self.p.xyz(i, "CARTESIAN_POINT")
        if x is not None:
            return x
        _, a = self.rec(i, "CARTESIAN_POINT")
        if len(a) < 2 or not isinstance(a[1], list):
            raise self._bad(i, "CARTESIAN_POINT without coordinates")
        x = self.numbers(i, a[1])
        if x.size == 2:
            x = np.append(x, 0.0)
        if x.size != 3:
            raise self._bad(i, f"a point of {x.size} coordinates")
        return x

    def points(self, ids) -> np.ndarray:
        """:meth:`point` of many records: (n, 3)."""
        X = self.p.coordinates(ids, "CARTESIAN_POINT", 3)
        if X is not None and np.isfinite(X).all():
            return X
        return np.array([self.point(k) for k in ids]).reshape(-1, 3)

    def direction(self, i):
        v = self.p.xyz(i, "DIRECTION")
        if v is not None:
            n = norm3(v)
            if n > 0 and math.isfinite(n):
                return v / n
        _, a = self.rec(i, "DIRECTION")
        x = self.numbers(i, a[1] if len(a) > 1 and isinstance(a[1], list) else [])
        if x.size == 2:
            x = np.append(x, 0.0)
        n = norm3(x) if x.size == 3 else 0.0
        if not n > 0:
            raise self._bad(i, "a zero or malformed DIRECTION")
        return x / n

    def vector(self, i):
        _, a = self.rec(i, "VECTOR")
        return self.direction(a[1]) * float(self.numbers(i, [a[2]], 1)[0])

    def axis2(self, i):
        """``(O, Z, X)`` of an AXIS2_PLACEMENT_3D (defaults: Z = +z, X = +x made
        orthogonal to Z, as ISO 10303-42 ``build_axes``)."""
        name, a = self.rec(i, "AXIS2_PLACEMENT_3D", "AXIS2_PLACEMENT_2D")
        O = self.point(a[1])
        if name == "AXIS2_PLACEMENT_3D":  # plain DIRECTION records: in one kernel call
            zr, xr = a[2], (a[3] if len(a) > 3 else None)
            z = self.p.xyz(zr, "DIRECTION") if isinstance(zr, Ref) else _Z_UP
            x = self.p.xyz(xr, "DIRECTION") if isinstance(xr, Ref) else None
            if z is not None and (x is not None or not isinstance(xr, Ref)):
                ZX = axis2_zx(z, x, _AXES_XY)
                if len(ZX):
                    return O, ZX[0], ZX[1]
        if name == "AXIS2_PLACEMENT_2D":
            Z = np.array([0.0, 0.0, 1.0])
            ref = a[2] if len(a) > 2 else None
        else:
            Z = self.direction(a[2]) if isinstance(a[2], Ref) else np.array([0.0, 0, 1])
            ref = a[3] if len(a) > 3 else None
        X = self.direction(ref) if isinstance(ref, Ref) else None
        return O, Z, axis2_x(Z, X, _AXES_XY)  # numpy's arithmetic, compiled

    # ---------------------------------------------------------------- curves
    def curve(self, i) -> Curve:
        i = int(i)
        c = self._curves.get(i)
        if c is None:
            c = self._curves[i] = self._curve(i)
        return c

    def _curve(self, i) -> Curve:
        if self.p.names.get(i) == "B_SPLINE_CURVE_WITH_KNOTS":  # read at once when plain
            m = _BSPLINE_CURVE.fullmatch(self.p.body(i))
            if m is not None:
                a = ["", int(m[1]), [int(x.strip()[1:]) for x in m[2].split(",")], None,
                     None, None, [int(x) for x in m[3].split(",")],
                     [float(x) for x in m[4].split(",")]]
                return Curve("bspline", spline=self._bspline_curve(
                    i, "B_SPLINE_CURVE_WITH_KNOTS", a))
        name, a = self.rec(i, "LINE", "CIRCLE", "ELLIPSE", "B_SPLINE_CURVE_WITH_KNOTS",
                           "B_SPLINE_CURVE", "BEZIER_CURVE", "SURFACE_CURVE",
                           "SEAM_CURVE", "INTERSECTION_CURVE", "TRIMMED_CURVE",
                           "POLYLINE")
        if name == "LINE":
            D = self.vector(a[2])
            if not D.any():
                raise self._bad(i, "a LINE whose VECTOR has zero magnitude")
            return Curve("line", O=self.point(a[1]), D=D)
        if name in ("CIRCLE", "ELLIPSE"):
            C, Z, X = self.axis2(a[1])
            r1 = float(self.numbers(i, [a[2]], 1)[0])
            r2 = float(self.numbers(i, [a[3]], 1)[0]) if name == "ELLIPSE" else r1
            if not (r1 > 0 and r2 > 0):
                raise self._bad(i, f"{name} of radius {r1}, {r2}")
            return Curve(name.lower(), C=C, X=X, Y=cross3(Z, X), a=r1, b=r2)
        if name in ("SURFACE_CURVE", "SEAM_CURVE", "INTERSECTION_CURVE"):
            return self.curve(a[1])
        if name == "TRIMMED_CURVE":  # the edge's vertices bound it
            return self.curve(a[1])
        if name == "POLYLINE":
            P = np.array([self.point(k) for k in a[1]])
            if len(P) < 2:
                raise self._bad(i, "a POLYLINE of fewer than 2 points")
            t = np.arange(len(P), dtype=float)
            U = np.concatenate([[0.0], t, [t[-1]]])
            return Curve("polyline", spline=(1, U, np.column_stack([P, np.ones(len(P))])))
        return Curve("bspline", spline=self._bspline_curve(i, name, a))

    def _bspline_curve(self, i, name, a):
        if isinstance(a, dict):  # complex: B_SPLINE_CURVE(...) and its subtypes
            base = a.get("B_SPLINE_CURVE")
            if base is None:
                raise Unsupported(f"#{i}: a complex curve without B_SPLINE_CURVE")
            p, pts = int(base[0]), base[1]
            kn = a.get("B_SPLINE_CURVE_WITH_KNOTS")
            w = a.get("RATIONAL_B_SPLINE_CURVE")
            weights = None if w is None else self.numbers(i, w[0])
            sub = "BEZIER_CURVE" if "BEZIER_CURVE" in a else \
                "UNIFORM_CURVE" if "UNIFORM_CURVE" in a else \
                "QUASI_UNIFORM_CURVE" if "QUASI_UNIFORM_CURVE" in a else None
        else:
            p, pts = int(a[1]), a[2]
            kn = a[6:8] if name == "B_SPLINE_CURVE_WITH_KNOTS" else None
            weights, sub = None, (None if kn is not None else name)
        if not isinstance(pts, list):
            raise self._bad(i, "B-spline curve control points are not a list")
        P = self.points(pts)
        n = len(P)
        if n < 2:
            raise self._bad(i, f"a B-spline curve of {n} control point(s)")
        if kn is not None:
            U = _knots(kn[0], kn[1])
        else:
            U = _implied_knots(sub, p, n)
        if p < 1 or U.size != n + p + 1 or (U[1:] < U[:-1]).any():
            raise self._bad(i, f"a B-spline curve of degree {p} with {n} control points "
                               f"and {U.size} knots")
        if weights is None:  # (P * 1, 1)
            Pw = np.empty((n, 4))
            Pw[:, :3] = P
            Pw[:, 3] = 1.0
            return p, U, Pw
        W = weights
        if W.size != n or not (W > 0).all():
            raise self._bad(i, "B-spline curve weights: wrong count or not positive")
        return p, U, np.column_stack([P * W[:, None], W])

    # ---------------------------------------------------------------- surfaces
    def surface(self, i):
        """``("analytic", Analytic)``, ``("nurbs", (p, q, U, V, P, W))``,
        ``("extrusion", (Curve, vector))`` or ``("revolution", (Curve, point,
        axis))``."""
        i = int(i)
        s = self._surfaces.get(i)
        if s is None:
            s = self._surfaces[i] = self._surface(i)
        return s

    def _surface(self, i):
        name, a = self.rec(i, "PLANE", "CYLINDRICAL_SURFACE", "CONICAL_SURFACE",
                           "SPHERICAL_SURFACE", "TOROIDAL_SURFACE",
                           "DEGENERATE_TOROIDAL_SURFACE", "B_SPLINE_SURFACE_WITH_KNOTS",
                           "B_SPLINE_SURFACE", "BEZIER_SURFACE", "OFFSET_SURFACE",
                           "SURFACE_OF_LINEAR_EXTRUSION", "SURFACE_OF_REVOLUTION")
        if name == "SURFACE_OF_LINEAR_EXTRUSION":
            return "extrusion", (self.curve(a[1]), self.vector(a[2]))
        if name == "SURFACE_OF_REVOLUTION":
            _, ax = self.rec(a[2], "AXIS1_PLACEMENT")
            A = self.direction(ax[2]) if isinstance(ax[2], Ref) else np.array([0.0, 0, 1])
            return "revolution", (self.curve(a[1]), self.point(ax[1]), A)
        if name == "OFFSET_SURFACE":
            kind, base = self.surface(a[1])
            if kind != "analytic":
                raise Unsupported(f"#{i}: OFFSET_SURFACE of a B-spline surface")
            return "analytic", base.offset(float(self.numbers(i, [a[2]], 1)[0]))
        if isinstance(a, dict) or name.startswith("B_SPLINE") or name == "BEZIER_SURFACE":
            return "nurbs", self._bspline_surface(i, name, a)
        O, Z, X = self.axis2(a[1])
        if name == "PLANE":
            return "analytic", Analytic("plane", O, Z, X)
        r = self.numbers(i, a[2:4] if name in ("CONICAL_SURFACE", "TOROIDAL_SURFACE",
                                               "DEGENERATE_TOROIDAL_SURFACE") else a[2:3])
        if name == "CYLINDRICAL_SURFACE":
            return "analytic", Analytic("cylinder", O, Z, X, R=float(r[0]))
        if name == "CONICAL_SURFACE":
            alpha = float(r[1]) * self.angle
            if not 0 < abs(alpha) < math.pi / 2:
                raise self._bad(i, f"a cone of semi-angle {r[1]}")
            return "analytic", Analytic("cone", O, Z, X, R=float(r[0]), alpha=alpha)
        if name == "SPHERICAL_SURFACE":
            return "analytic", Analytic("sphere", O, Z, X, R=float(r[0]))
        return "analytic", Analytic("torus", O, Z, X, R=float(r[0]), r=float(r[1]))

    def _bspline_surface(self, i, name, a):
        if isinstance(a, dict):
            base = a.get("B_SPLINE_SURFACE")
            if base is None:
                raise Unsupported(f"#{i}: a complex surface without B_SPLINE_SURFACE")
            p, q, net = int(base[0]), int(base[1]), base[2]
            kn = a.get("B_SPLINE_SURFACE_WITH_KNOTS")
            w = a.get("RATIONAL_B_SPLINE_SURFACE")
            W = None if w is None else np.array([self.numbers(i, row) for row in w[0]])
            sub = "BEZIER_SURFACE" if "BEZIER_SURFACE" in a else \
                "UNIFORM_SURFACE" if "UNIFORM_SURFACE" in a else \
                "QUASI_UNIFORM_SURFACE" if "QUASI_UNIFORM_SURFACE" in a else None
        else:
            p, q, net = int(a[1]), int(a[2]), a[3]
            kn = a[8:12] if name == "B_SPLINE_SURFACE_WITH_KNOTS" else None
            W, sub = None, (None if kn is not None else name)
        rows = [len(row) if isinstance(row, list) else -1 for row in net] \
            if isinstance(net, list) else [-1]
        if min(rows, default=-1) < 2 or len(set(rows)) != 1:
            raise self._bad(i, "a B-spline surface whose control net is not rectangular")
        P = self.points([k for row in net for k in row]).reshape(len(rows), rows[0], 3)
        if P.ndim != 3 or P.shape[0] < 2 or P.shape[1] < 2:
            raise self._bad(i, "a B-spline surface whose control net is not rectangular")
        nu, nv = P.shape[:2]
        if kn is not None:
            U, V = _knots(kn[0], kn[2]), _knots(kn[1], kn[3])
        else:
            U, V = _implied_knots(sub, p, nu), _implied_knots(sub, q, nv)
        if (p < 1 or q < 1 or U.size != nu + p + 1 or V.size != nv + q + 1
                or np.any(np.diff(U) < 0) or np.any(np.diff(V) < 0)):
            raise self._bad(i, f"a B-spline surface of degrees {p}, {q} with {nu} x {nv} "
                               f"control points and {U.size}, {V.size} knots")
        if W is not None and (W.shape != (nu, nv) or not (W > 0).all()):
            raise self._bad(i, "B-spline surface weights: wrong shape or not positive")
        return p, q, U, V, P, W


def _implied_knots(sub, p, n):
    """Knots of BEZIER / UNIFORM / QUASI_UNIFORM curves and surfaces (ISO 10303-42)."""
    if sub in ("BEZIER_CURVE", "BEZIER_SURFACE"):
        k = (n - 1) // p
        inner = np.repeat(np.arange(1, k, dtype=float), p)
        return np.concatenate([np.zeros(p + 1), inner, np.full(p + 1, float(k))])
    if sub in ("QUASI_UNIFORM_CURVE", "QUASI_UNIFORM_SURFACE"):
        m = n - p
        return np.concatenate([np.zeros(p), np.arange(m + 1, dtype=float), np.full(p, float(m))])
    raise Unsupported(f"B-spline without clamped knots ({sub})")
