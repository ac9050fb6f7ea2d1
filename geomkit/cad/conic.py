"""IGES 104 (conic arc) as an exact rational quadratic NURBS.

The arc lies in the plane ``z = ZT`` of its definition space, on the conic
``A x^2 + B x y + C y^2 + D x + E y + F = 0``, from ``(X1, Y1)`` to ``(X2, Y2)``.
The conic is brought to its canonical frame (centre / vertex ``c``, right-handed unit
axes ``X, Y``, the frame nearest the definition axes), where

* ellipse (form 1): ``c + a cos t X + b sin t Y``, run counter-clockwise from start to
  end (start = end: the whole ellipse).  Built as the affine image of the circular arc
  of :func:`geomkit.cad.analytic.arc_curve` (The NURBS Book A7.1), so the entity
  parameter ``t`` maps to the NURBS parameter by
  :func:`~geomkit.cad.analytic.angle_to_param`;
* hyperbola (form 2): ``c + a sec t X + b tan t Y``, ``|t| < pi / 2`` on the branch of
  the end points; with ``s = tan(t / 2)`` this is the rational quadratic
  ``(a (1 + s^2) X + 2 b s Y) / (1 - s^2)``, one Bezier segment in ``s``;
* parabola (form 3): ``c + (k t^2) X + t Y``, one polynomial Bezier segment in ``t``.

These are the closed forms of the IGES 5.3 standard position (conic centred / with its
vertex at the origin, axes along ``XT, YT``), extended to any position.  Hyperbolas and
parabolas run from start to end; where that is against ``t`` the curve is reversed and
the parameter map says so.  The result holds ``A x^2 + ... + F = 0`` to rounding.

A record whose coefficients do not make the conic its form number names, whose conic
is degenerate or empty, or whose end points are off the conic (more than
:data:`ON_CONIC_TOL` x its size) raises :class:`~geomkit.errors.FileFormatError` naming
the entity and its DE number.
"""

from __future__ import annotations

import math

import numpy as np

from geomkit.tolerances import ON_CONIC_TOL
from geomkit.errors import FileFormatError
from geomkit.cad.analytic import angle_to_param, arc_curve, turn_angle
from geomkit.cad.analytic import turn_into as _turn

__all__ = ["conic_arc", "ON_CONIC_TOL", "FORMS"]

FORMS = {1: "ellipse", 2: "hyperbola", 3: "parabola"}
_PARABOLA_TOL = 1e-9  # |B^2 - 4AC| / (A^2 + B^2 + C^2) below this: a parabola


def _frame(vecs):
    """Of the four right-handed frames with axes along ``vecs`` (2x2, columns), the
    one nearest the identity."""
    X = vecs[:, 0]
    best = None
    for k in range(4):
        Y = np.array([-X[1], X[0]])
        score = X[0] + Y[1]
        if best is None or score > best[0] + 1e-12:
            best = (score, X.copy(), Y)
        X = Y
    return best[1], best[2]


def _bezier2(c0, c1, c2, s0, s1):
    """Bezier control points on ``[s0, s1]`` of the quadratic ``c0 + c1 s + c2 s^2``
    (rows: homogeneous coordinates)."""
    h = s1 - s0
    b0 = c0 + c1 * s0 + c2 * s0 * s0
    d1 = (c1 + 2 * c2 * s0) * h
    d2 = c2 * h * h
    return np.array([b0, b0 + d1 / 2, b0 + d1 + d2])


def conic_arc(coef, zt: float, start, end, form: int, what: str):
    """``(curve, fmap, (t0, t1))`` of a conic arc in its definition space (see the
    module doc): ``curve = (2, U, Pw)`` with ``Pw`` (n, 4) homogeneous, ``fmap`` the map
    from the entity parameter ``t`` to the NURBS parameter (``None``: the same) and
    ``(t0, t1)`` the entity parameters of start and end.  ``what`` names the entity in
    errors (``"<file>: entity 104 at DE <n>"``)."""
    A, B, C, D, E, F = (float(x) for x in coef)
    p0, p1 = np.asarray(start, float), np.asarray(end, float)
    if not all(math.isfinite(x) for x in (A, B, C, D, E, F, zt, *p0, *p1)):
        raise FileFormatError(f"{what}: non-finite coefficient or point")
    nq = A * A + B * B + C * C
    if not nq > 0:
        raise FileFormatError(f"{what}: A = B = C = 0, not a conic (a line)")
    disc = (B * B - 4 * A * C) / nq
    kind = 3 if abs(disc) <= _PARABOLA_TOL else (1 if disc < 0 else 2)
    if form in FORMS and form != kind:
        raise FileFormatError(f"{what}: form {form} ({FORMS[form]}) but the coefficients "
                              f"describe a {FORMS[kind]} "
                              f"(B^2 - 4AC = {B * B - 4 * A * C:.6g})")
    if form not in FORMS and form != 0:
        raise FileFormatError(f"{what}: form number {form} (expected 1 ellipse, "
                              "2 hyperbola or 3 parabola)")
    Q = np.array([[A, B / 2], [B / 2, C]])
    lam, vecs = np.linalg.eigh(Q)
    scale = max(1.0, float(np.abs(p0).max()), float(np.abs(p1).max()))
    if kind == 3:
        return _parabola(Q, lam, vecs, D, E, F, zt, p0, p1, what, scale)
    c = np.linalg.solve(2 * Q, [-D, -E])
    Fc = F + 0.5 * (D * c[0] + E * c[1])
    X, Y = _frame(vecs)
    lx, ly = float(X @ Q @ X), float(Y @ Q @ Y)
    if kind == 2 and lx * -Fc <= 0:  # transverse axis along X
        X, Y = Y, -X
        lx, ly = ly, lx
    if Fc == 0 or lx * -Fc <= 0 or (kind == 1 and ly * -Fc <= 0):
        raise FileFormatError(f"{what}: degenerate or empty {FORMS[kind]} (its "
                              "coefficients give no curve or a pair of lines)")
    a, b = math.sqrt(-Fc / lx), math.sqrt(abs(Fc / ly))
    size = max(a, b, scale)
    loc = [((q - c) @ X, (q - c) @ Y) for q in (p0, p1)]
    if kind == 1:
        for (x, y), q in zip(loc, (p0, p1)):
            _on(x / a, y / b, lambda x, y: math.hypot(x, y) - 1.0, q, a, b, size, what)
        t0, t1 = (turn_angle(y / b, x / a) for x, y in loc)
        if t1 <= t0 + 1e-12 * (1 + t0):
            t1 += 2 * math.pi
        cz = np.array([*c, zt])
        curve = arc_curve(cz, [*(a * X), 0.0], [*(b * Y), 0.0], 1.0, t0, t1)
        return curve, (lambda x, t0=t0, t1=t1: angle_to_param(_turn(x, t0, t1), t0, t1)), \
            (t0, t1)
    # hyperbola: the branch of the start point is x > 0
    if loc[0][0] < 0:
        X, Y = -X, -Y
        loc = [(-x, -y) for x, y in loc]
    if loc[1][0] <= 0:
        raise FileFormatError(f"{what}: start and end points on different branches of "
                              "the hyperbola")
    for (x, y), q in zip(loc, (p0, p1)):
        _on(x / a, y / b, lambda x, y: x * x - y * y - 1.0, q, a, b, size, what)
    ts = [math.atan(y / b) for _, y in loc]
    s = [math.tan(t / 2) for t in ts]
    lo, hi = min(s), max(s)
    if not hi > lo:
        raise FileFormatError(f"{what}: start and end points coincide")
    # homogeneous (x, y, z, w) = a (1 + s^2) X + 2 b s Y + (1 - s^2) (c, zt)
    cz = np.array([*c, zt])
    Xh, Yh = np.array([*(a * X), 0.0, 0.0]), np.array([*(b * Y), 0.0, 0.0])
    ch = np.array([*cz, 1.0])
    Pw = _bezier2(Xh + ch, 2 * Yh, Xh - ch, lo, hi)
    return _directed(Pw, lo, hi, s[0] > s[1], lambda t: np.tan(np.asarray(t) / 2),
                     ts)


def _parabola(Q, lam, vecs, D, E, F, zt, p0, p1, what, scale):
    """Form 3: ``x' = k t^2, y' = t`` about the vertex (module doc)."""
    i = int(np.argmax(np.abs(lam)))
    lb = float(lam[i])
    X = vecs[:, 1 - i]  # along the axis (the zero eigenvalue)
    Y = np.array([-X[1], X[0]])
    Dx, Ey = D * X[0] + E * X[1], D * Y[0] + E * Y[1]
    if abs(Dx) <= 1e-12 * (abs(D) + abs(E) + abs(lb) * scale):
        raise FileFormatError(f"{what}: degenerate parabola (its coefficients give a "
                              "pair of parallel lines or none)")
    if -lb / Dx < 0:  # open towards +X
        X, Y = -X, -Y
        Dx, Ey = -Dx, -Ey
    # lb y^2 + Dx x + Ey y + F = 0 (coordinates about the origin):
    # x = -(lb y^2 + Ey y + F) / Dx; vertex at y = -Ey / (2 lb)
    yv = -Ey / (2 * lb)
    xv = -(lb * yv * yv + Ey * yv + F) / Dx
    c = xv * X + yv * Y
    k = -lb / Dx
    loc = [((q - c) @ X, (q - c) @ Y) for q in (p0, p1)]
    size = max(scale, abs(1 / k))
    for (x, y), q in zip(loc, (p0, p1)):
        if abs(x - k * y * y) > ON_CONIC_TOL * size * math.hypot(1.0, 2 * k * y):
            raise FileFormatError(f"{what}: point {q.tolist()} is not on the parabola "
                                  f"(off by {abs(x - k * y * y):.3g})")
    ts = [y for _, y in loc]
    lo, hi = min(ts), max(ts)
    if not hi > lo:
        raise FileFormatError(f"{what}: start and end points coincide")
    cz = np.array([*c, zt, 1.0])
    Xh, Yh = np.array([*X, 0.0, 0.0]), np.array([*Y, 0.0, 0.0])
    Pw = _bezier2(cz, Yh, k * Xh, lo, hi)
    return _directed(Pw, lo, hi, ts[0] > ts[1], None, ts)


def _directed(Pw, lo, hi, reverse, g, ts):
    """One Bezier segment on ``[lo, hi]`` as a curve run from start to end; ``g`` maps
    the entity parameter to the Bezier parameter (``None``: the same)."""
    U = np.array([lo] * 3 + [hi] * 3)
    if not reverse:
        return (2, U, Pw), g, (ts[0], ts[1])
    f = (lambda t: lo + hi - np.asarray(t, float)) if g is None else \
        (lambda t: lo + hi - g(t))
    return (2, U, Pw[::-1].copy()), f, (ts[0], ts[1])


def _on(x, y, fn, q, a, b, size, what):
    """Raise when the normalised point ``(x, y)`` is off the unit conic ``fn``."""
    off = abs(fn(x, y)) * min(a, b)
    if off > ON_CONIC_TOL * size:
        raise FileFormatError(f"{what}: point {q.tolist()} is not on the conic (off by "
                              f"~{off:.3g})")
