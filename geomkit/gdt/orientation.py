"""Orientation tolerances of a planar feature or an axis to one datum of a frame
(ISO 1101:2017 clauses 18.9-18.11 as understood; ASME Y14.5-2018 section 9):
parallelism, perpendicularity, angularity.

The zone has the required orientation to the datum direction ``d`` (outward
normal of a datum plane, direction of a datum axis) and is otherwise free: it may
move, and, when one datum leaves a rotation about ``d`` free, rotate about ``d``
(ISO 1101: orientation constrained only by the datums given).

* Planar feature: two parallel planes of normal ``u`` at the required angle to
  ``d``; ``measured`` = max u.p - min u.p, minimised over the free rotation (exact
  for 90 degrees from the convex hull of the projected points; a bounded 1-D search
  otherwise), or at the rotation fixed by ``direction``.
* Axis (``feature="axis"``): the axis of a cylinder fitted to the points,
  limited to the feature's length (its end points e1, e2 are the extreme
  projections of the points on it).  Cylindrical zone (``diameter=True``, the
  default when the axis must be parallel to ``d``): ``measured`` = the distance of
  e2 - e1 perpendicular to the zone's axis; two-plane zone: |m . (e2 - e1)|, m the
  zone normal.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize_scalar

from geomkit.errors import InvalidInputError
from geomkit.fitting import fit
from geomkit.gdt._common import (Characteristic, check_choice, check_direction,
                                 check_points, check_tol, extremes, min_width_2d,
                                 orient, perp_basis, reject, size_of)
from geomkit.gdt.datums import DatumFrame

__all__ = ["parallelism", "perpendicularity", "angularity", "axis_endpoints"]


def _datum_direction(frame, datum):
    if not isinstance(frame, DatumFrame):
        raise InvalidInputError(f"expected a DatumFrame, got {type(frame).__name__}",
                                "frame")
    if not frame.datums:
        raise InvalidInputError("the frame holds no datums", "frame")
    label = frame.labels[0] if datum is None else datum
    df = frame.datum(label)
    if df.direction is None:
        raise InvalidInputError(f"datum {label} is a point; it has no direction to "
                                "orient a zone", "datum")
    return label, df


def axis_endpoints(P, method="lsq"):
    """The derived axis of a cylindrical feature over its length.

    Parameters
    ----------
    P : (n, 3) float
        Points on the cylinder (n >= 5).
    method : str
        Cylinder fit (:func:`geomkit.fitting.fit`).

    Returns
    -------
    e1, e2 : (3,) float
        Axis points at the smallest and largest projection of the points.
    fit : FitResult
    ends : (2,) int
        Indices of the points of smallest and largest projection.
    """
    r = fit(P, "cylinder", method)
    s = (P - r.point) @ r.axis
    i, j = int(np.argmin(s)), int(np.argmax(s))
    return r.point + s[i] * r.axis, r.point + s[j] * r.axis, r, np.array([i, j])


def _cone_dir(d, w, beta):
    return math.cos(beta) * d + math.sin(beta) * w


def _plane_zone(P, d, beta, w_fix, w_fit):
    """Zone normal u at angle beta to d of least width; returns (u, width, search)."""
    if beta < 1e-12:
        return d, float(np.ptp(P @ d)), "fixed by the datum"
    if w_fix is not None:
        u = _cone_dir(d, w_fix, beta)
        return u, float(np.ptp(P @ u)), "fixed by direction"
    e1, e2 = w_fit, np.cross(d, w_fit)
    if abs(beta - math.pi / 2) < 1e-12:
        Q = np.column_stack([P @ e1, P @ e2])
        u2, w = min_width_2d(Q, np.array([1.0, 0.0]))
        u = u2[0] * e1 + u2[1] * e2
        return u / np.linalg.norm(u), float(np.ptp(P @ u)), "exact (hull edges)"
    Pc = P - P.mean(axis=0)
    a, b, c = Pc @ d, Pc @ e1, Pc @ e2

    def width(phi):
        v = math.cos(beta) * a + math.sin(beta) * (math.cos(phi) * b + math.sin(phi) * c)
        return float(v.max() - v.min())

    grid = np.linspace(-math.pi / 3, math.pi / 3, 721)
    vals = [width(g) for g in grid]
    k = int(np.argmin(vals))
    h = grid[1] - grid[0]
    res = minimize_scalar(width, bounds=(grid[k] - h, grid[k] + h), method="bounded",
                          options={"xatol": 1e-13})
    phi = float(res.x) if res.fun <= vals[k] else float(grid[k])
    u = _cone_dir(d, math.cos(phi) * e1 + math.sin(phi) * e2, beta)
    return u, float(np.ptp(P @ u)), "1-D bounded search over the free rotation"


def _orientation(type_, points, tol, frame, datum, alpha, feature, method, direction,
                 diameter):
    check_choice(feature, ("plane", "axis"), "feature")
    P = check_points(points, 3 if feature == "plane" else 5, f"{type_} of a {feature}")
    t = check_tol(tol)
    label, df = _datum_direction(frame, datum)
    d = df.direction
    same = (feature == "plane") == (df.element == "plane")
    beta = alpha if same else math.pi / 2 - alpha          # angle between u / axis and d
    beta = min(max(beta, 0.0), math.pi / 2)
    w_fix = None
    if direction is not None:
        v = check_direction(direction, "direction")
        w_fix = reject(v, d)
        if float(np.linalg.norm(w_fix)) < 1e-9:
            if beta > 1e-12:
                raise InvalidInputError("direction is parallel to the datum direction; "
                                        "it cannot fix the zone's rotation", "direction")
            w_fix = None
        else:
            w_fix = w_fix / np.linalg.norm(w_fix)
    L = size_of(P)
    tolerance = {"zone": t, "angle_deg": math.degrees(alpha)}
    if feature == "plane":
        if method not in (None, "lsq", "minzone"):
            check_choice(method, ("lsq", "minzone"), "method")
        r = fit(P, "plane", method or "lsq")
        # undirected: d is turned toward the feature (given or fitted) normal
        d = orient(d, r.normal if direction is None else check_direction(direction,
                                                                          "direction"))
        w_fit = reject(r.normal, d)
        nw = float(np.linalg.norm(w_fit))
        w_fit = w_fit / nw if nw > 1e-12 else perp_basis(d)[0]
        u, w, how = _plane_zone(P, d, beta, w_fix, w_fit)
        s = P @ u
        det = {"zone_normal": u, "zone_offsets": (float(s.min()), float(s.max())),
               "datum_direction": d, "search": how, "fit": r}
        return Characteristic(type_, w, tolerance, (label,), w <= t, P.shape[0],
                              extremes(s, L, w), det)
    e1, e2, r, ends = axis_endpoints(P, method or "lsq")
    d = orient(d, r.axis if direction is None else check_direction(direction,
                                                                    "direction"))
    D = e2 - e1
    if diameter is None:
        diameter = beta < 1e-12
    w = w_fix
    if w is None:
        w = reject(r.axis, d)
        nw = float(np.linalg.norm(w))
        w = w / nw if nw > 1e-12 else None
    if w is None and (beta > 1e-12 or not diameter):
        raise InvalidInputError("the zone's rotation about the datum direction is "
                                "undefined (the fitted axis is parallel to it); give "
                                "direction=", "direction")
    v = d if beta < 1e-12 else _cone_dir(d, w, beta)      # the zone's nominal axis
    if diameter:
        value = float(np.linalg.norm(reject(D, v)))
        zone = {"shape": "cylinder", "axis": v}
    else:
        m = -math.sin(beta) * d + math.cos(beta) * w
        value = abs(float(m @ D))
        zone = {"shape": "two planes", "normal": m, "axis": v}
    tolerance["diameter"] = bool(diameter)
    det = {"zone": zone, "axis_ends": (e1, e2), "datum_direction": d, "fit": r,
           "length": float(np.linalg.norm(D))}
    deciding = np.unique(np.concatenate([ends, r.contacts]))
    return Characteristic(type_, value, tolerance, (label,), value <= t, P.shape[0],
                          deciding, det)


def parallelism(points, tol, frame, datum=None, feature="plane", method=None,
                direction=None, diameter=None) -> Characteristic:
    """Parallelism to a datum (ISO 1101:2017 18.9, as understood; ASME Y14.5-2018
    section 9).

    Parameters
    ----------
    points : (n, 3) float
        Points on the toleranced feature, part coordinates of ``frame``.
    tol : float > 0
    frame : DatumFrame
    datum : str, optional
        Label of the datum (default the primary).  A datum plane orients by its
        normal, a datum axis by its direction.
    feature : {"plane", "axis"}
        A planar surface, or the axis of a cylindrical feature (its points).
    method : str, optional
        Fit of the feature: plane ``"lsq"`` (default, only used for the start of
        the free rotation), axis: the cylinder fit (default ``"lsq"``).
    direction : (3,) float, optional
        Nominal normal / axis of the feature fixing the zone's rotation about the
        datum direction (as a secondary datum would).
    diameter : bool, optional
        Axis zone: cylindrical (the tolerance a diameter) or two planes; default
        cylindrical when the axis is parallel to the datum direction.

    Returns
    -------
    Characteristic
        ``details``: ``zone_normal`` / ``zone``, ``fit``, ``axis_ends``.
    """
    return _orientation("parallelism", points, tol, frame, datum, 0.0, feature, method,
                        direction, diameter)


def perpendicularity(points, tol, frame, datum=None, feature="plane", method=None,
                     direction=None, diameter=None) -> Characteristic:
    """Perpendicularity to a datum (ISO 1101:2017 18.10, as understood; ASME
    Y14.5-2018 section 9).  Parameters as :func:`parallelism`.  A plane perpendicular to
    a datum plane with one datum: the zone rotates freely about the datum normal and
    the minimum width is taken (exact)."""
    return _orientation("perpendicularity", points, tol, frame, datum, math.pi / 2,
                        feature, method, direction, diameter)


def angularity(points, tol, frame, angle, datum=None, feature="plane", method=None,
               direction=None, diameter=None, degrees=True) -> Characteristic:
    """Angularity to a datum (ISO 1101:2017 18.11, as understood; ASME Y14.5-2018
    section 9).

    ``angle`` is the basic angle between the feature (plane or axis) and the datum
    (plane or axis) as drawn, in [0, 90] degrees (``degrees=False``: radians).
    Other parameters as :func:`parallelism`.
    """
    try:
        a = float(angle)
    except (TypeError, ValueError):
        raise InvalidInputError(f"expected a number, got {angle!r}", "angle") from None
    a = math.radians(a) if degrees else a
    if not (math.isfinite(a) and 0.0 <= a <= math.pi / 2 + 1e-15):
        raise InvalidInputError(f"must be in [0, 90] degrees, got {angle!r}", "angle")
    return _orientation("angularity", points, tol, frame, datum, a, feature, method,
                        direction, diameter)
