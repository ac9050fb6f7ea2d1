"""Exact NURBS patches of Open CASCADE's analytic and swept surfaces, built by geomkit.

For planes, cylinders, cones, spheres and tori (bare or inside a
``Geom_RectangularTrimmedSurface``), and for extrusions and revolutions of a B-spline or
Bezier curve, the STEP reader builds the patch itself from the closed form
(:func:`~geomkit.cad.analytic.revolve` of the meridian line or arc, knots at the angles;
the swept curve keeps its own parameter) and carries each of the file's pcurves through
the angle-to-parameter map (:func:`~geomkit.cad.uvmap.map_pcurve`, exact on iso-lines
and on unmapped coordinates).  Open CASCADE's ``BRepBuilderAPI_NurbsConvert`` does the
same job less well on real files:

* it re-approximates pcurves that are not iso-lines, and on a CATIA V5 extrusion face
  the result strays 1.1e-2 mm from the file's pcurve (edge tolerance 5.3e-4 mm);
* it converts the edges too, and fails on an Inventor cylinder whose circle edges start
  at ``2 pi - 3.5e-9`` ("Knots interval values too close").

The patch spans the face's UV bounds widened to its pcurves' control points (a rational
arc's middle control point lies beyond the arc), within the surface's own limits: an
angle spans at most one turn, a sphere stops at its poles, a cone at its apex.  It is
checked against OCC's surface on a 9 x 9 grid; the largest distance (rounding, ~1e-14
of the size) is the patch's stated error.
"""

from __future__ import annotations

import numpy as np

from geomkit.cad.analytic import angle_to_param, arc_curve, line_curve, plane_patch, revolve
from geomkit.cad.occ import xyz
from geomkit.cad.uvmap import map_pcurve
from geomkit.nurbs.trimming import evaluate_trim_curve
from geomkit.nurbs.surface import Surface

__all__ = ["ELEMENTARY", "SWEPT", "elementary_patch", "carry_pcurve"]

ELEMENTARY = ("Geom_Plane", "Geom_CylindricalSurface", "Geom_ConicalSurface",
              "Geom_SphericalSurface", "Geom_ToroidalSurface")
"""OCC surface types :func:`elementary_patch` builds."""
SWEPT = ("Geom_SurfaceOfLinearExtrusion", "Geom_SurfaceOfRevolution")
"""Swept surfaces it builds when their curve is a B-spline or Bezier curve."""


def _basis(surface):
    while surface.DynamicType().Name() == "Geom_RectangularTrimmedSurface":
        surface = surface.BasisSurface()
    return surface


def _range(lo, hi, box_lo, box_hi, periodic, limits):
    """The patch's range in one parameter: the pcurves' control-point box (a pcurve
    lies in the hull of its control points, and a rational arc's middle point lies
    beyond the arc), kept within the surface's own ``limits``; for an angle, at most one
    turn (beyond that, the face's own bounds)."""
    a, b = min(lo, box_lo), max(hi, box_hi)
    if limits is not None:
        a, b = max(a, limits[0]), min(b, limits[1])
    if periodic and b - a > 2 * np.pi:
        return lo, hi
    return a, b


def _curve_segment(c, lo: float, hi: float):
    """``(degree, knots, Pw)`` of a B-spline / Bezier curve ``c`` cut to ``[lo, hi]``
    (clamped to its range) with its own parametrisation, or ``None`` for other
    curves (their B-spline form is parametrised differently)."""
    from OCP.GeomConvert import GeomConvert

    while c.DynamicType().Name() == "Geom_TrimmedCurve":
        c = c.BasisCurve()
    if c.DynamicType().Name() not in ("Geom_BSplineCurve", "Geom_BezierCurve"):
        return None
    b = GeomConvert.CurveToBSplineCurve_s(c)  # a Bezier curve keeps its parameter
    if b.IsPeriodic():
        b.SetNotPeriodic()
    lo, hi = max(lo, b.FirstParameter()), min(hi, b.LastParameter())
    if not hi > lo:
        return None
    b.Segment(lo, hi)
    n = b.NbPoles()
    P = np.array([xyz(b.Pole(i)) for i in range(1, n + 1)])
    w = np.array([b.Weight(i) for i in range(1, n + 1)])
    U = [b.Knot(i) for i in range(1, b.NbKnots() + 1) for _ in range(b.Multiplicity(i))]
    return b.Degree(), np.array(U), np.column_stack([P * w[:, None], w])


def _swept(g, kind: str, bounds, name: str, box):
    """Extrusion ``C(u) + v D`` and revolution (``C(v)`` turned by ``u`` about the
    axis) of a B-spline curve: the curve keeps its parameter, so only the angle is
    mapped."""
    u0, u1, v0, v1 = (float(b) for b in bounds)
    if box is not None:
        u0, u1 = min(u0, box[0]), max(u1, box[2])
        v0, v1 = min(v0, box[1]), max(v1, box[3])
    if kind == "Geom_SurfaceOfLinearExtrusion":
        cur = _curve_segment(g.BasisCurve(), u0, u1)
        if cur is None:
            return None
        p, U, Pw = cur
        w = Pw[:, 3]
        C = Pw[:, :3] / w[:, None]
        D = xyz(g.Direction())
        P = np.stack([C + v0 * D, C + v1 * D], axis=1)
        s = Surface(p, 1, U, [v0, v0, v1, v1], P, np.stack([w, w], axis=1), name=name)
        fu = fv = None
    else:
        if box is not None and u1 - u0 > 2 * np.pi:
            u0, u1 = (float(b) for b in bounds[:2])
        cur = _curve_segment(g.BasisCurve(), v0, v1)
        if cur is None:
            return None
        ax = g.Axis()
        p, q, U, V, P, W = revolve(cur, xyz(ax.Location()), xyz(ax.Direction()), u0, u1)
        s = Surface(q, p, V, U, P.transpose(1, 0, 2), W.T, name=name)
        fu = lambda u: angle_to_param(u, u0, u1)  # noqa: E731
        fv = None
    return s, fu, fv, _patch_error(g, s, fu, fv)


def _patch_error(g, s, fu, fv) -> float:
    """Largest distance between the patch and OCC's surface ``g`` on a 9 x 9 grid of
    OCC's parameters over the patch's range."""
    (a0, a1), (b0, b1) = s.domain
    uu, vv = np.meshgrid(np.linspace(a0, a1, 9), np.linspace(b0, b1, 9), indexing="ij")
    uu, vv = uu.ravel(), vv.ravel()
    ref = np.array([xyz(g.Value(a, b)) for a, b in zip(uu, vv)])
    mine = s.evaluate(np.column_stack([uu if fu is None else fu(uu),
                                       vv if fv is None else fv(vv)]))
    return float(np.linalg.norm(mine - ref, axis=1).max())


def elementary_patch(surface, bounds, name: str, box=None):
    """``(Surface, fu, fv, error)`` for OCC ``surface`` over ``bounds`` = ``(u0, u1,
    v0, v1)`` (the face's ``BRepTools.UVBounds``) widened to ``box`` (the same four
    numbers for the pcurves' control points), or ``None`` if its type is not one of
    :data:`ELEMENTARY`.  ``fu`` / ``fv`` map OCC's ``u`` / ``v`` to the patch's
    parameters (``None``: unchanged); ``error`` is the largest distance found between
    the patch and OCC's surface on a 9 x 9 grid (both are closed forms: the distance
    is rounding)."""
    g = _basis(surface)
    kind = g.DynamicType().Name()
    if kind in SWEPT:
        return _swept(g, kind, bounds, name, box)
    if kind not in ELEMENTARY:
        return None
    u0, u1, v0, v1 = (float(b) for b in bounds)
    if box is not None:
        vlim = None
        if kind == "Geom_SphericalSurface":
            vlim = (-np.pi / 2, np.pi / 2)
        elif kind == "Geom_ConicalSurface":  # never across the apex
            apex = -g.RefRadius() / np.sin(g.SemiAngle())
            vlim = (apex, np.inf) if v0 + v1 >= 2 * apex else (-np.inf, apex)
        u0, u1 = _range(u0, u1, box[0], box[2], kind != "Geom_Plane", None)
        v0, v1 = _range(v0, v1, box[1], box[3], kind == "Geom_ToroidalSurface", vlim)
    pos = g.Position()
    O, X, Y = xyz(pos.Location()), xyz(pos.XDirection()), xyz(pos.YDirection())
    Z = xyz(pos.Direction())  # the axis; -(X x Y) in an indirect frame
    turn = np.cross(X, Y)  # OCC's u turns from X towards Y, direct frame or not
    fv = None
    if kind == "Geom_Plane":  # linear in both parameters: pcurves unchanged
        p, q, U, V, P, W = plane_patch(O, X, Y, u0, u1, v0, v1)
        return Surface(p, q, U, V, P, None, name=name), None, None, 0.0
    if kind == "Geom_CylindricalSurface":
        R = g.Radius()
        meridian = line_curve(O + R * X + v0 * Z, O + R * X + v1 * Z, v0, v1)
    elif kind == "Geom_ConicalSurface":
        R, a = g.RefRadius(), g.SemiAngle()
        meridian = line_curve(*(O + (R + v * np.sin(a)) * X + v * np.cos(a) * Z
                                for v in (v0, v1)), v0, v1)
    elif kind == "Geom_SphericalSurface":
        meridian = arc_curve(O, X, Z, g.Radius(), v0, v1)
        fv = lambda v: angle_to_param(v, v0, v1)  # noqa: E731
    else:  # torus
        meridian = arc_curve(O + g.MajorRadius() * X, X, Z, g.MinorRadius(), v0, v1)
        fv = lambda v: angle_to_param(v, v0, v1)  # noqa: E731
    p, q, U, V, P, W = revolve(meridian, O, turn, u0, u1)
    # revolve's u is the meridian, its v the angle: transpose to OCC's order
    s = Surface(q, p, V, U, P.transpose(1, 0, 2), W.T, name=name)
    fu = lambda u: angle_to_param(u, u0, u1)  # noqa: E731
    return s, fu, fv, _patch_error(g, s, fu, fv)


def carry_pcurve(c, patch, samples: int = 17):
    """``(pcurve on the patch, error)``: the pcurve ``c`` (in OCC's parameters) carried
    through ``patch``'s maps (:func:`~geomkit.cad.uvmap.map_pcurve`, UV tolerance 1e-10
    of the range).  The 3-D error bound is the patch's own (measured against OCC's
    surface) plus the carried curve's UV error times the patch's largest speed along
    it (0 where the map is exact: iso-parametric lines, unmapped coordinates)."""
    s, fu, fv, patch_err = patch
    if fu is None and fv is None:
        return c, patch_err
    (u0, u1), (v0, v1) = s.domain
    m, uv_err = map_pcurve(c, fu, fv, 1e-10 * max(u1 - u0, v1 - v0))
    if uv_err == 0.0:
        return m, patch_err
    t = np.linspace(m.knots[m.degree], m.knots[-m.degree - 1], samples)
    Y = evaluate_trim_curve(m, t)[:, 0, :]
    Y = np.column_stack([np.clip(Y[:, 0], u0, u1), np.clip(Y[:, 1], v0, v1)])
    D = s.derivatives(Y, 1)
    speed = float((np.linalg.norm(D[:, 1, 0], axis=1) + np.linalg.norm(D[:, 0, 1], axis=1)).max())
    return m, patch_err + uv_err * speed
