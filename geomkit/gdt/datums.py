"""Datum reference frames from measured datum features (ASME Y14.5-2018 section 7,
ISO 5459:2011), as understood.

Each datum feature is reduced to a *datum element*: a plane (point, outward
normal), an axis (point, direction) or a point.  The primary is associated on its
own; the secondary is associated constrained by the primary (a plane at 90 degrees
to it, an axis parallel to its normal, ...); the tertiary by both.  Default
associations (ISO 5459 default; ASME "datum feature simulator" as understood):

* plane: the tangent plane outside the material minimising the largest distance
  of the points (constrained L-infinity: all points on the material side);
* cylinder / sphere: the maximum inscribed feature for an internal feature (bore),
  the minimum circumscribed for an external one (shaft, ball);
* line: the minimum-zone line;
* point: the given point.

``method="lsq"`` takes least squares instead (a plane through the points' mean).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from geomkit.errors import InvalidInputError
from geomkit.fitting import FitResult, fit
from geomkit.gdt._common import (check_choice, check_direction, check_points, extremes,
                                 jsonable, min_width_2d, orient, perp_basis, reject,
                                 size_of)
from geomkit.validate import as_float_array

__all__ = ["Datum", "DatumFeature", "DatumFrame", "datum_frame", "frame_from_axes",
           "align_to_cad"]

KINDS = ("plane", "cylinder", "line", "sphere", "point")
DOFS = ("tx", "ty", "tz", "rx", "ry", "rz")
#: A secondary / tertiary plane's nominal normal must be within this of 90 degrees
#: to the primary direction (only perpendicular datum planes are supported).
PERP_LIMIT_DEG = 30.0


@dataclass(frozen=True)
class Datum:
    """A datum feature as measured.

    Parameters
    ----------
    label : str
        The datum letter, e.g. ``"A"``.
    kind : {"plane", "cylinder", "line", "sphere", "point"}
    points : (n, 3) float
        Points on the datum feature, part (machine) coordinates; one point for
        ``"point"``.
    method : {None, "lsq", "tangent", "minzone", "maxinscribed", "mincircumscribed"}
        None: the default association of the kind (module doc).
    feature : {None, "internal", "external"}
        Bore / shaft (cylinder, sphere); required unless ``method="lsq"``.
    normal : (3,) float, optional
        Nominal outward normal of a planar feature (pointing away from the
        material).  Required for the tangent plane (it says which side the material
        is on); with ``lsq`` it only orients the normal.
    axis : (3,) float, optional
        Nominal direction of a cylinder / line datum (orients its axis).
    """

    label: str
    kind: str
    points: object = field(repr=False)
    method: str | None = None
    feature: str | None = None
    normal: object = None
    axis: object = None


@dataclass(frozen=True)
class DatumFeature:
    """A datum feature after association (the datum element).

    Attributes
    ----------
    label, kind, role : str
        ``role`` is ``"primary"``, ``"secondary"`` or ``"tertiary"``.
    method : str
        The association used (``tangent``, ``lsq``, ``maxinscribed``, ...).
    element : {"plane", "axis", "point"}
    point : (3,) float
        A point of the element (part coordinates).
    direction : (3,) float or None
        Outward plane normal or axis direction (unit); None for a point.
    constrains : tuple of str
        Degrees of freedom of the frame this datum fixes (``tx`` ... ``rz``, in the
        frame's axes).
    size : float or None
        Diameter of a cylinder / sphere datum.
    fit : FitResult or None
        The feature fit behind the element (None for constrained plane fits).
    contacts : (k,) int
        Points deciding the element (tangent contacts, fit contacts).
    max_distance : float
        Largest distance of the feature's points from the element (planes) or its
        form error (others).
    """

    label: str
    kind: str
    role: str
    method: str
    element: str
    point: np.ndarray
    direction: np.ndarray | None
    constrains: tuple
    size: float | None = None
    fit: FitResult | None = field(default=None, repr=False)
    contacts: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    max_distance: float = 0.0

    def to_dict(self) -> dict:
        out = {k: jsonable(getattr(self, k)) for k in
               ("label", "kind", "role", "method", "element", "point", "direction",
                "constrains", "size", "contacts", "max_distance")}
        out["fit"] = None if self.fit is None else self.fit.to_dict(residuals=False)
        return out


@dataclass(frozen=True)
class DatumFrame:
    """A datum reference frame.

    Attributes
    ----------
    origin : (3,) float
        Origin in part coordinates.
    axes : (3, 3) float
        Rows x, y, z: unit axes in part coordinates, right-handed.  z is the primary
        direction (outward normal of a primary plane, axis of a primary cylinder),
        x the secondary's (outward normal of a secondary plane) or the tertiary's
        clocking direction; see the guide.
    transform : (4, 4) float
        Homogeneous map part -> datum coordinates: q = axes @ (p - origin).
    datums : dict of str -> DatumFeature
        In order primary, secondary, tertiary.
    dof : dict of str -> tuple of str
        The degrees of freedom each datum fixes; ``free`` those left free.
    free : tuple of str
    """

    origin: np.ndarray
    axes: np.ndarray
    transform: np.ndarray
    datums: dict = field(repr=False)
    dof: dict
    free: tuple

    @property
    def labels(self) -> tuple:
        return tuple(self.datums)

    def datum(self, label) -> DatumFeature:
        """The associated datum ``label``; InvalidInputError if it is not in the frame."""
        if not isinstance(label, str) or label not in self.datums:
            raise InvalidInputError(f"datum {label!r} is referenced but not defined in "
                                    f"this frame (datums {', '.join(self.datums)})",
                                    "datum")
        return self.datums[label]

    def to_datum(self, points) -> np.ndarray:
        """Part -> datum coordinates of (n, 3) points."""
        P = as_float_array(points, "points", shape=(None, 3))
        return (P - self.origin) @ self.axes.T

    def to_part(self, points) -> np.ndarray:
        """Datum -> part coordinates of (n, 3) points."""
        Q = as_float_array(points, "points", shape=(None, 3))
        return Q @ self.axes + self.origin

    def to_dict(self) -> dict:
        return {"origin": self.origin.tolist(), "axes": self.axes.tolist(),
                "transform": self.transform.tolist(),
                "datums": {k: v.to_dict() for k, v in self.datums.items()},
                "dof": {k: list(v) for k, v in self.dof.items()},
                "free": list(self.free)}


def _make_frame(origin, z, x, datums, dof, free) -> DatumFrame:
    y = np.cross(z, x)
    axes = np.array([x, y, z])
    T = np.eye(4)
    T[:3, :3] = axes
    T[:3, 3] = -axes @ origin
    return DatumFrame(origin=np.asarray(origin, float), axes=axes, transform=T,
                      datums=datums, dof=dof, free=free)


def frame_from_axes(origin, z, x) -> DatumFrame:
    """A nominal frame (e.g. the CAD's datum frame) from its origin and z, x axes
    (part / CAD coordinates; x is made orthogonal to z).  Holds no datums."""
    o = as_float_array(origin, "origin", shape=(3,))
    z = check_direction(z, "z")
    x = reject(check_direction(x, "x"), z)
    if float(np.linalg.norm(x)) < 1e-9:
        raise InvalidInputError("x is parallel to z", "x")
    x = x / np.linalg.norm(x)
    return _make_frame(o, z, x, {}, {}, ())


def align_to_cad(points, frame: DatumFrame, nominal: DatumFrame | None = None):
    """Move measured points into CAD coordinates by their datum frame.

    ``p_cad = nominal.to_part(frame.to_datum(p))``: the measured datum frame is
    placed on the nominal one (the CAD's datum frame, e.g. from
    :func:`frame_from_axes`); with ``nominal=None`` the datum coordinates are the
    CAD coordinates.

    Parameters
    ----------
    points : (n, 3) float
        Measured points (part / machine coordinates of ``frame``).
    frame, nominal : DatumFrame
    """
    Q = frame.to_datum(points)
    return Q if nominal is None else nominal.to_part(Q)


# ---------------------------------------------------------------------- association

def _default_method(d: Datum) -> str:
    if d.kind == "plane":
        return "tangent"
    if d.kind == "line":
        return "minzone"
    if d.kind == "point":
        return "point"
    if d.feature not in ("internal", "external"):
        raise InvalidInputError(f"datum {d.label}: a {d.kind} datum needs "
                                "feature='internal' (bore) or 'external' (shaft), or "
                                "method='lsq'", "feature")
    return "maxinscribed" if d.feature == "internal" else "mincircumscribed"


_METHODS = {"plane": ("tangent", "lsq"), "line": ("minzone", "lsq"),
            "cylinder": ("maxinscribed", "mincircumscribed", "lsq"),
            "sphere": ("maxinscribed", "mincircumscribed", "lsq"), "point": ("point",)}
_NEED = {"plane": 3, "line": 2, "cylinder": 5, "sphere": 4, "point": 1}


def _check(d, role) -> tuple:
    if not isinstance(d, Datum):
        raise InvalidInputError(f"expected a Datum, got {type(d).__name__}", role)
    if not isinstance(d.label, str) or not d.label:
        raise InvalidInputError(f"a datum label must be a non-empty string, got "
                                f"{d.label!r}", f"{role}.label")
    check_choice(d.kind, KINDS, f"datum {d.label}.kind")
    if d.feature is not None:
        check_choice(d.feature, ("internal", "external"), f"datum {d.label}.feature")
    method = _default_method(d) if d.method is None else d.method
    check_choice(method, _METHODS[d.kind], f"datum {d.label}.method")
    P = as_float_array(d.points, f"datum {d.label}.points")
    if d.kind == "point" and P.shape == (3,):
        P = P[None, :]
    if d.kind == "point" and P.shape != (1, 3):
        raise InvalidInputError(f"a point datum takes one point (3,), got shape {P.shape}",
                                f"datum {d.label}.points")
    P = check_points(P, _NEED[d.kind], f"a {d.kind} datum", f"datum {d.label}.points")
    nrm = None if d.normal is None else check_direction(d.normal, f"datum {d.label}.normal")
    ax = None if d.axis is None else check_direction(d.axis, f"datum {d.label}.axis")
    if d.kind == "plane" and method == "tangent" and nrm is None:
        raise InvalidInputError(f"datum {d.label}: the tangent plane needs the outward "
                                "normal (normal=..., pointing away from the material), "
                                "or method='lsq'", f"datum {d.label}.normal")
    return P, method, nrm, ax


def _plane_free(d, role, P, method, nrm):
    """Unconstrained plane datum: the tangent (minimax, outside the material) plane,
    whose normal is the minimum-zone normal, or the least-squares plane."""
    r = fit(P, "plane", "minzone" if method == "tangent" else "lsq")
    n = orient(r.normal, nrm)
    s = P @ n
    if method == "tangent":
        c = float(s.max())
        contacts = r.contacts
    else:
        c = float(s.mean())
        contacts = r.contacts
    foot = r.point + (c - float(r.point @ n)) * n
    return n, foot, r, contacts, float(np.max(np.abs(s - c)))


def _plane_in_family(d, P, method, nrm, z):
    """Plane datum whose normal is perpendicular to unit ``z`` (one rotation free):
    the minimum width of the points projected on the plane normal to ``z`` near the
    nominal normal (tangent), or their 2-D principal direction (lsq)."""
    e1, e2 = perp_basis(z)
    Q = np.column_stack([P @ e1, P @ e2])
    Qc = Q - Q.mean(axis=0)
    _, sv, Vt = np.linalg.svd(Qc, full_matrices=False)
    u_lsq = Vt[-1]
    if nrm is not None:
        nn = np.array([nrm @ e1, nrm @ e2])
        if float(np.linalg.norm(nn)) < math.cos(math.radians(PERP_LIMIT_DEG)):
            ang = math.degrees(math.acos(min(1.0, abs(float(nrm @ z)))))
            raise InvalidInputError(
                f"datum {d.label}: its nominal normal is at {ang:.3g} deg to the "
                f"primary direction; a constrained datum plane must be "
                "perpendicular to it (parallel planes cannot be secondary / tertiary)",
                f"datum {d.label}.normal")
        nn /= np.linalg.norm(nn)
        u_lsq = orient(u_lsq, nn)
    else:
        nn = u_lsq
    if sv[0] <= 0:
        raise InvalidInputError(f"datum {d.label}: the points project onto one point "
                                "along the primary direction; the plane is parallel to "
                                "it", f"datum {d.label}.points")
    if method == "tangent":
        u, _ = min_width_2d(Q, nn)
    else:
        u = u_lsq
    n = u[0] * e1 + u[1] * e2
    n /= np.linalg.norm(n)
    s = P @ n
    c = float(s.max()) if method == "tangent" else float(s.mean())
    contacts = extremes(s, size_of(P))
    foot = P.mean(axis=0) + (c - float(P.mean(axis=0) @ n)) * n
    return n, foot, contacts, float(np.max(np.abs(s - c)))


def _plane_fixed(d, P, method, nrm, n):
    """Plane datum whose normal is fixed (+-n): only its offset is free."""
    n = orient(n, nrm)
    s = P @ n
    c = float(s.max()) if method == "tangent" else float(s.mean())
    foot = P.mean(axis=0) + (c - float(P.mean(axis=0) @ n)) * n
    return n, foot, extremes(s, size_of(P)), float(np.max(np.abs(s - c)))


def _round(d, P, method, ax):
    """Cylinder / line / sphere datum, unconstrained: (point, direction, size, fit)."""
    kind = "line" if d.kind == "line" else d.kind
    r = fit(P, kind, method)
    if kind == "sphere":
        return r.center, None, 2.0 * r.radius, r
    a = orient(r.direction if kind == "line" else r.axis, ax)
    size = None if kind == "line" else 2.0 * r.radius
    return r.point, a, size, r


def _centre_along(d, P, method, z):
    """Centre of a cylinder datum constrained parallel to unit ``z`` (a circle fit of
    the points projected on the plane normal to z), of a sphere, or the point."""
    if d.kind == "point":
        return P[0], None, None
    if d.kind == "sphere":
        r = fit(P, "sphere", method)
        return r.center, 2.0 * r.radius, r
    if d.kind == "cylinder":
        X = reject(P, z)
        r = fit(X, "circle", method)
        return r.center, 2.0 * r.radius, r
    raise InvalidInputError(f"datum {d.label}: a {d.kind} datum is not supported in this "
                            "position of the frame", f"datum {d.label}.kind")


def _x_default(z):
    for e in (np.array([1.0, 0, 0]), np.array([0, 1.0, 0])):
        x = reject(e, z)
        if np.linalg.norm(x) > 0.5:
            return x / np.linalg.norm(x)
    return perp_basis(z)[0]  # pragma: no cover


def datum_frame(primary: Datum, secondary: Datum | None = None,
                tertiary: Datum | None = None) -> DatumFrame:
    """Build a datum reference frame from up to three datum features.

    Supported orders (ASME Y14.5-2018 section 7 / ISO 5459:2011, as understood):

    ======================  =====================================================
    primary | secondary     constrains
    ======================  =====================================================
    plane                   tz rx ry (z = outward normal); tx ty rz free
    plane | plane           + tx rz (secondary plane perpendicular to the primary)
    plane | cylinder/sphere + tx ty (cylinder axis parallel to z; centre)
    /point
    cylinder (or line)      tx ty rx ry (z = axis); tz rz free
    cylinder | plane        + tz (plane normal to the axis)
    sphere / point          tx ty tz; rotations free
    ======================  =====================================================

    The tertiary fixes the last DOF: after plane | plane a plane perpendicular to
    both, or a cylinder / sphere / point (its y coordinate); after plane | cylinder
    or cylinder | plane (only rz left) a plane whose normal is perpendicular to z
    (x = its outward normal) or a cylinder / sphere / point (x points from the
    origin to its centre).

    Parameters
    ----------
    primary, secondary, tertiary : Datum

    Returns
    -------
    DatumFrame

    Raises
    ------
    InvalidInputError
        Bad datum input, a repeated label, a plane datum not perpendicular to the
        primary where it must be, an unsupported combination.
    DegenerateGeometryError
        From the fits (collinear points on a plane datum, ...).
    """
    given = [(d, r) for d, r in ((primary, "primary"), (secondary, "secondary"),
                                 (tertiary, "tertiary")) if d is not None]
    if secondary is None and tertiary is not None:
        raise InvalidInputError("a tertiary datum needs a secondary", "tertiary")
    labels = [d.label for d, _ in given if isinstance(d, Datum)]
    if len(set(labels)) != len(labels):
        raise InvalidInputError(f"datum labels must differ, got {labels}", "label")
    checked = [(d, r) + _check(d, r) for d, r in given]
    feats, dof = {}, {}
    rows, rhs = [], []          # linear constraints on the origin: rows @ o = rhs
    allP = np.vstack([c[2] for c in checked])
    z = x = None
    state = None                # what is fixed so far

    def add(d, role, method, element, point, direction, cons, size=None, r=None,
            contacts=None, maxd=0.0):
        feats[d.label] = DatumFeature(
            d.label, d.kind, role, method, element, np.asarray(point, float),
            None if direction is None else np.asarray(direction, float), tuple(cons),
            size, r, np.zeros(0, np.int64) if contacts is None else np.asarray(contacts),
            float(maxd))
        dof[d.label] = tuple(cons)

    # ---- primary
    d, role, P, method, nrm, ax = checked[0]
    if d.kind == "plane":
        z, foot, r, cont, maxd = _plane_free(d, role, P, method, nrm)
        rows.append(z), rhs.append(float(z @ foot))
        add(d, role, method, "plane", foot, z, ("tz", "rx", "ry"), None, r, cont, maxd)
        state = "plane"
    elif d.kind in ("cylinder", "line"):
        pt, z, size, r = _round(d, P, method, ax)
        e1, e2 = perp_basis(z)
        rows += [e1, e2]
        rhs += [float(e1 @ pt), float(e2 @ pt)]
        add(d, role, method, "axis", pt, z, ("tx", "ty", "rx", "ry"), size, r, r.contacts,
            r.form_error)
        state = "axis"
    else:
        if d.kind == "sphere":
            c, _, size, r = _round(d, P, method, ax)
        else:
            c, size, r = P[0], None, None
        rows += list(np.eye(3))
        rhs += list(c)
        add(d, role, method, "point", c, None, ("tx", "ty", "tz"), size, r,
            None if r is None else r.contacts, 0.0 if r is None else r.form_error)
        state = "point"

    # ---- secondary
    if len(checked) > 1:
        d, role, P, method, nrm, ax = checked[1]
        if state == "plane" and d.kind == "plane":
            x, foot, cont, maxd = _plane_in_family(d, P, method, nrm, z)
            rows.append(x), rhs.append(float(x @ foot))
            add(d, role, method, "plane", foot, x, ("tx", "rz"), None, None, cont, maxd)
            state = "plane-plane"
        elif state == "plane" and d.kind in ("cylinder", "sphere", "point"):
            if d.kind == "cylinder" and ax is not None and abs(float(ax @ z)) < \
                    math.cos(math.radians(PERP_LIMIT_DEG)):
                raise InvalidInputError(f"datum {d.label}: its nominal axis is not "
                                        "perpendicular to the primary plane",
                                        f"datum {d.label}.axis")
            c, size, r = _centre_along(d, P, method, z)
            e1, e2 = perp_basis(z)
            rows += [e1, e2]
            rhs += [float(e1 @ c), float(e2 @ c)]
            add(d, role, method, "axis" if d.kind == "cylinder" else "point", c,
                z if d.kind == "cylinder" else None, ("tx", "ty"), size, r,
                None if r is None else r.contacts, 0.0 if r is None else r.form_error)
            state = "located"
        elif state == "axis" and d.kind == "plane":
            n, foot, cont, maxd = _plane_fixed(d, P, method, nrm, z)
            rows.append(n), rhs.append(float(n @ foot))
            add(d, role, method, "plane", foot, n, ("tz",), None, None, cont, maxd)
            state = "located"
        elif state == "axis" and d.kind in ("sphere", "point"):
            c, size, r = _centre_along(d, P, method, z)
            rows.append(z), rhs.append(float(z @ c))
            add(d, role, method, "point", c, None, ("tz",), size, r)
            state = "located"
        else:
            prim = checked[0][0]
            raise InvalidInputError(f"unsupported datum combination: primary {prim.kind} "
                                    f"{prim.label} with secondary {d.kind} {d.label}",
                                    "secondary")

    # ---- tertiary
    if len(checked) > 2:
        d, role, P, method, nrm, ax = checked[2]
        if state == "plane-plane" and d.kind == "plane":
            y = np.cross(z, x)
            n, foot, cont, maxd = _plane_fixed(d, P, method, nrm, y)
            if nrm is not None and abs(float(nrm @ y)) < \
                    math.cos(math.radians(PERP_LIMIT_DEG)):
                raise InvalidInputError(f"datum {d.label}: a tertiary plane must be "
                                        "perpendicular to both the primary and the "
                                        "secondary", f"datum {d.label}.normal")
            rows.append(n), rhs.append(float(n @ foot))
            add(d, role, method, "plane", foot, n, ("ty",), None, None, cont, maxd)
        elif state == "plane-plane" and d.kind in ("cylinder", "sphere", "point"):
            c, size, r = _centre_along(d, P, method, z)
            y = np.cross(z, x)
            rows.append(y), rhs.append(float(y @ c))
            add(d, role, method, "axis" if d.kind == "cylinder" else "point", c,
                z if d.kind == "cylinder" else None, ("ty",), size, r)
        elif state == "located" and d.kind == "plane":
            x, foot, cont, maxd = _plane_in_family(d, P, method, nrm, z)
            add(d, role, method, "plane", foot, x, ("rz",), None, None, cont, maxd)
        elif state == "located" and d.kind in ("cylinder", "sphere", "point"):
            c, size, r = _centre_along(d, P, method, z)
            o = _solve_origin(rows, rhs, allP.mean(axis=0))
            v = reject(c - o, z)
            if float(np.linalg.norm(v)) <= 1e-9 * size_of(allP):
                raise InvalidInputError(f"datum {d.label}: its centre lies on the frame's "
                                        "z axis; it cannot orient the frame",
                                        f"datum {d.label}.points")
            x = v / np.linalg.norm(v)
            add(d, role, method, "axis" if d.kind == "cylinder" else "point", c,
                z if d.kind == "cylinder" else None, ("rz",), size, r)
        else:
            raise InvalidInputError(f"unsupported datum combination: tertiary {d.kind} "
                                    f"{d.label} after {', '.join(labels[:2])}",
                                    "tertiary")

    if z is None:               # point / sphere primary alone: part axes
        z, x = np.array([0.0, 0, 1]), np.array([1.0, 0, 0])
    elif x is None:
        x = _x_default(z)
    origin = _solve_origin(rows, rhs, allP.mean(axis=0))
    fixed = {f for v in dof.values() for f in v}
    free = tuple(f for f in DOFS if f not in fixed)
    return _make_frame(origin, z, x, feats, dof, free)


def _solve_origin(rows, rhs, start):
    """The point nearest ``start`` satisfying rows @ o = rhs (least-norm change)."""
    A = np.array(rows, dtype=np.float64).reshape(-1, 3)
    b = np.array(rhs, dtype=np.float64) - A @ start
    return start + np.linalg.lstsq(A, b, rcond=None)[0]
