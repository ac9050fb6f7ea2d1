"""Exact rational NURBS constructions shared by the IGES and STEP readers.

Curves are ``(degree, knots, Pw)`` with homogeneous control points ``Pw`` of shape
``(n, 4)`` (``w x, w y, w z, w``).  Surfaces are returned as :class:`~geomkit.Surface`
arguments ``(p, q, U, V, P, W)`` so the caller adds trims and a name.

* Circular arcs: The NURBS Book, Algorithm A7.1 -- the sweep is split into equal arcs of
  at most 90 degrees, each a rational quadratic with middle weight ``cos(d / 2)``.  The
  knots are placed *at the arc's angles* (knot ``k`` = ``theta0 + k d``), so the NURBS
  parameter equals the angle at every knot and :func:`angle_to_param` /
  :func:`param_to_angle` convert between them in closed form in between: on a span,
  ``tan(psi / 2) = tan(d / 4) (2 r - 1)`` with ``psi`` the angle from the span's middle
  and ``r`` the span's local parameter in [0, 1].
* Surfaces of revolution: Algorithm A8.1 (each control point of the generatrix sweeps
  a circle about the axis; weights multiply).  ``u`` is the generatrix parameter, ``v``
  the NURBS angle parameter.  Cylinder, cone, sphere and torus are revolutions of a
  line or an arc, so they hold their closed forms to rounding.
* Extrusion (tabulated cylinder): the curve in ``u`` and a degree-1 ``v`` in [0, 1].
* Ruled surface between two curves of equal degree and knots (degree 1 in ``v``).
"""

from __future__ import annotations

import math

import numpy as np

from geomkit._kernels.arcs import arc_net, plane_net, revolve_net
from geomkit._kernels.bezier import curve_points
from geomkit._kernels.pcurve_map import unwrap_angles

__all__ = ["cross3", "unwrap", "arc_curve", "line_curve", "revolve", "extrude", "ruled", "plane_patch",
           "angle_to_param", "param_to_angle", "turn_into", "arc_knots", "transform_curve"]


def _spans(theta0: float, theta1: float):
    """Number of spans and span angle of the arc ``[theta0, theta1]``."""
    sweep = theta1 - theta0
    if not sweep > 0:
        raise ValueError(f"arc sweep must be > 0, got {sweep!r}")
    n = max(1, int(math.ceil(sweep / (0.5 * math.pi) - 1e-12)))
    return n, sweep / n


def arc_knots(theta0: float, theta1: float):
    """Number of spans, span angle and knot vector of the arc ``[theta0, theta1]``."""
    n, d = _spans(theta0, theta1)
    ks = theta0 + d * np.arange(n + 1)
    ks[-1] = theta1
    U = np.concatenate([[theta0] * 3, np.repeat(ks[1:-1], 2), [theta1] * 3])
    return n, d, U


def cross3(a, b) -> np.ndarray:
    """The cross product of two 3-vectors (``np.cross`` costs ~10x more on one pair)."""
    a0, a1, a2 = float(a[0]), float(a[1]), float(a[2])
    b0, b1, b2 = float(b[0]), float(b[1]), float(b[2])
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def norm3(v) -> float:
    """``np.linalg.norm`` of a 1-D float vector (its value: ``sqrt(v.dot(v))``, as
    numpy computes it) without its generic argument handling (~1 instead of ~5 us)."""
    return math.sqrt(v.dot(v))


def unwrap(x, period: float = 2 * math.pi) -> np.ndarray:
    """``np.unwrap(x, period=period)`` of a 1-D array (the same values, compiled: the
    readers unwrap thousands of short edges)."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    if x.ndim != 1:
        raise ValueError(f"unwrap takes a 1-D array, got shape {x.shape}")
    return unwrap_angles(x, float(period))


def turn_angle(y: float, x: float) -> float:
    """``atan2(y, x)`` in ``[0, 2 pi)``.  The float modulo takes a tiny negative angle to
    2 pi itself; that is 0 here, so an arc starting on its frame's x axis starts at 0
    whatever the last bits of ``y`` (the compiled circle frames,
    :func:`geomkit._kernels.arcs.circle_frames`, do the same)."""
    t = math.atan2(y, x) % (2 * math.pi)
    return 0.0 if t >= 2 * math.pi else t


def angle_to_param(theta, theta0: float, theta1: float) -> np.ndarray:
    """NURBS parameter of the arc built by :func:`arc_curve` at angle ``theta``."""
    n, d = _spans(theta0, theta1)
    th = np.asarray(theta, float)
    k = np.clip(np.floor((th - theta0) / d), 0, n - 1)
    mid = theta0 + (k + 0.5) * d
    r = 0.5 * (np.tan(0.5 * (th - mid)) / math.tan(d / 4) + 1.0)
    return np.clip(theta0 + (k + r) * d, theta0, theta1)


class AngleMap:
    """:func:`angle_to_param` of the arc ``[theta0, theta1]`` as a callable that names
    its arc (the readers' edge fits hand it to a kernel)."""

    __slots__ = ("theta0", "theta1")

    def __init__(self, theta0: float, theta1: float):
        self.theta0, self.theta1 = float(theta0), float(theta1)

    def __call__(self, theta) -> np.ndarray:
        th = np.asarray(theta, float)
        if th.ndim == 1 and th.size <= 4:  # a segment's ends: the formula per value
            # (numpy's per-call cost is most of it on so few)
            t0, t1 = self.theta0, self.theta1
            n, d = _spans(t0, t1)
            q = math.tan(d / 4)
            out = np.empty(th.size)
            for i, x in enumerate(th.tolist()):
                if not math.isfinite(x):
                    return angle_to_param(th, t0, t1)
                k = min(max(math.floor((x - t0) / d), 0), n - 1)
                mid = t0 + (k + 0.5) * d
                r = 0.5 * (math.tan(0.5 * (x - mid)) / q + 1.0)
                out[i] = min(max(t0 + (k + r) * d, t0), t1)
            return out
        return angle_to_param(th, self.theta0, self.theta1)


def turn_into(x, a0: float, a1: float) -> np.ndarray:
    """Angles outside ``[a0, a1]`` moved by whole turns into it where they fit (files
    may write ``[-pi/2, 0]`` for ``[3pi/2, 2pi]``)."""
    x = np.asarray(x, float)
    w = a0 + np.mod(x - a0 + 1e-9, 2 * math.pi) - 1e-9
    return np.where((x < a0 - 1e-9) | (x > a1 + 1e-9), w, x)


def param_to_angle(s, theta0: float, theta1: float) -> np.ndarray:
    """Inverse of :func:`angle_to_param`."""
    n, d = _spans(theta0, theta1)
    s = np.asarray(s, float)
    k = np.clip(np.floor((s - theta0) / d), 0, n - 1)
    r = (s - theta0) / d - k
    mid = theta0 + (k + 0.5) * d
    return mid + 2.0 * np.arctan(math.tan(d / 4) * (2 * r - 1))


def arc_curve(center, xaxis, yaxis, radius: float, theta0: float, theta1: float):
    """Exact rational quadratic arc ``center + radius (cos t X + sin t Y)``, ``t`` in
    ``[theta0, theta1]`` (X, Y orthonormal); knots at the angles (see module doc)."""
    if not (theta1 - theta0 > 0 and math.isfinite(theta1 - theta0)):
        raise ValueError(f"arc sweep must be finite and > 0, got {theta1 - theta0!r}")
    U, Pw = arc_net(*(np.ascontiguousarray(v, dtype=np.float64)
                      for v in (center, xaxis, yaxis)), float(radius), float(theta0),
                    float(theta1))
    return 2, U, Pw


def line_curve(p0, p1, t0: float = 0.0, t1: float = 1.0):
    """The segment ``p0 + (t - t0) / (t1 - t0) (p1 - p0)`` as a degree-1 curve."""
    Pw = np.ones((2, 4))
    Pw[0, :3] = p0
    Pw[1, :3] = p1
    return 1, np.array([t0, t0, t1, t1], float), Pw


def curve_derivs(curve, t, d: int) -> np.ndarray:
    """Points and derivatives up to order ``d`` of a ``(p, U, Pw)`` curve: (m, d+1, 3)."""
    p, U, Pw = curve
    out = np.empty((len(t), d + 1, 3))
    curve_points(np.ascontiguousarray(Pw, float), p, np.asarray(U, float),
                 np.ascontiguousarray(t, float), d, out)
    return out


def curve_eval(curve, t) -> np.ndarray:
    """Points (m, 3) of a ``(p, U, Pw)`` curve."""
    return curve_derivs(curve, t, 0)[:, 0, :]


def transform_curve(curve, M):
    """Apply a 4x4 affine matrix to a curve (exact: affine maps commute with NURBS)."""
    if M is None:
        return curve
    p, U, Pw = curve
    w = Pw[:, 3]
    P = Pw[:, :3] / w[:, None]
    Q = P @ M[:3, :3].T + M[:3, 3]
    return p, U, np.column_stack([Q * w[:, None], w])


def revolve(curve, axis_point, axis_dir, theta0: float, theta1: float):
    """Surface of revolution (A8.1): the curve (``u``) rotated about the axis by the
    angles ``[theta0, theta1]`` (``v``, right-handed about ``axis_dir``)."""
    p, U, Pw = curve
    S = np.asarray(axis_point, float)
    T = np.asarray(axis_dir, float)
    T = T / norm3(T)
    if not (theta1 - theta0 > 0 and math.isfinite(theta1 - theta0)):
        raise ValueError(f"arc sweep must be finite and > 0, got {theta1 - theta0!r}")
    # (one compiled call with this arithmetic: numpy's, its 3-element dots as OpenBLAS
    # fuses them)
    V, out, W = revolve_net(np.ascontiguousarray(Pw, dtype=np.float64),
                            np.ascontiguousarray(S), np.ascontiguousarray(T),
                            float(theta0), float(theta1))
    return p, 2, np.asarray(U, float), V, out, W


def extrude(curve, vector):
    """``C(u) + v * vector``, ``v`` in [0, 1] (IGES 122, STEP extrusion)."""
    p, U, Pw = curve
    w = Pw[:, 3]
    P = Pw[:, :3] / w[:, None]
    out = np.stack([P, P + np.asarray(vector, float)], axis=1)
    W = np.stack([w, w], axis=1)
    return p, 1, np.asarray(U, float), np.array([0.0, 0.0, 1.0, 1.0]), out, W


def ruled(c1, c2):
    """``(1 - v) C1(u) + v C2(u)`` for curves of equal degree and knot vector."""
    p1, U1, Pw1 = c1
    p2, U2, Pw2 = c2
    if p1 != p2 or len(U1) != len(U2) or not np.allclose(U1, U2, rtol=0, atol=1e-12):
        raise ValueError("ruled surface between curves of different degree or knots")
    Pw = np.stack([Pw1, Pw2], axis=1)
    W = Pw[..., 3]
    return p1, 1, np.asarray(U1, float), np.array([0.0, 0.0, 1.0, 1.0]), \
        Pw[..., :3] / W[..., None], W


def plane_patch(origin, xaxis, yaxis, u0: float, u1: float, v0: float, v1: float):
    """The bilinear patch ``origin + u X + v Y`` over ``[u0, u1] x [v0, v1]``."""
    O, X, Y = (np.ascontiguousarray(v, dtype=np.float64) for v in (origin, xaxis, yaxis))
    P = plane_net(O, X, Y, float(u0), float(u1), float(v0), float(v1))
    return 1, 1, np.array([u0, u0, u1, u1]), np.array([v0, v0, v1, v1]), P, np.ones((2, 2))
