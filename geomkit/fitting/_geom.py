"""Frames, sign conventions, input checks and starting values of the feature fits.

Everything here works on points already centred on their centroid (the fits shift
the data once, so that a feature 1e3 from the origin loses no digits).
"""

from __future__ import annotations

import numpy as np

from geomkit.errors import DegenerateGeometryError, InvalidInputError
from geomkit.validate import as_float_array

#: Kinds, the fewest points each needs, and the methods defined for each.
MIN_POINTS = {"plane": 3, "line": 2, "circle": 3, "sphere": 4, "cylinder": 5, "cone": 6}
METHODS = {
    "plane": ("lsq", "minzone"),
    "line": ("lsq", "minzone"),
    "circle": ("lsq", "minzone", "mincircumscribed", "maxinscribed"),
    "sphere": ("lsq", "minzone", "mincircumscribed", "maxinscribed"),
    "cylinder": ("lsq", "minzone", "mincircumscribed", "maxinscribed"),
    "cone": ("lsq", "minzone"),
}
#: Relative singular value below which points count as collinear / coplanar.
DEGENERATE_REL = 1e-10


def check_request(points, kind, method):
    """Validate ``kind``, ``method`` and ``points``; return the (n, 3) float64 array."""
    if not isinstance(kind, str) or kind not in MIN_POINTS:
        raise InvalidInputError(f"unknown kind {kind!r}; expected one of "
                                f"{', '.join(MIN_POINTS)}", "kind")
    allowed = METHODS[kind]
    known = ("lsq", "minzone", "mincircumscribed", "maxinscribed")
    if not isinstance(method, str) or method not in known:
        raise InvalidInputError(f"unknown method {method!r}; expected one of "
                                f"{', '.join(known)}", "method")
    if method not in allowed:
        raise InvalidInputError(f"method {method!r} is not defined for kind {kind!r}; "
                                f"use one of {', '.join(allowed)}", "method")
    P = as_float_array(points, "points", shape=(None, 3))
    need = MIN_POINTS[kind]
    if P.shape[0] < need:
        raise InvalidInputError(f"a {kind} fit needs at least {need} points, got "
                                f"{P.shape[0]}", "points")
    return P


def centre(P):
    """Return (centroid, centred points, singular values of the centred points)."""
    c = P.mean(axis=0)
    X = P - c
    c = c + X.mean(axis=0)          # one refinement step: exact to rounding
    X = P - c
    s, Vt = principal_axes(X)
    return c, X, s, Vt


def principal_axes(X):
    """Singular values and right singular vectors of (n, 3) ``X`` (QR first: fast
    and backward stable for n up to 1e7)."""
    R = np.linalg.qr(X, mode="r") if X.shape[0] > 3 else X
    _, s, Vt = np.linalg.svd(R, full_matrices=True)
    return np.concatenate([s, np.zeros(3 - s.shape[0])]), Vt


def check_degenerate(kind, s):
    """Raise DegenerateGeometryError when the spread ``s`` (singular values) cannot
    define the feature."""
    if not s[0] > 0.0:
        raise DegenerateGeometryError("all points coincide", "points")
    tol = DEGENERATE_REL * s[0]
    if kind in ("plane", "circle") and s[1] <= tol:
        raise DegenerateGeometryError(f"points are collinear; a {kind} is undefined",
                                      "points")
    if kind in ("cylinder", "cone") and s[1] <= tol:
        raise DegenerateGeometryError(f"points lie on a line; a {kind} is undefined",
                                      "points")
    if kind == "sphere" and s[2] <= tol:
        raise DegenerateGeometryError("points are coplanar; a sphere is undefined",
                                      "points")


def canonical(v):
    """Unit ``v`` with the sign rule of every undirected direction: its component of
    largest magnitude is positive (ties: the first such component)."""
    v = np.asarray(v, dtype=np.float64)
    v = v / np.linalg.norm(v)
    i = int(np.argmax(np.abs(v)))
    return v if v[i] > 0 else -v


def frame(a):
    """Two unit vectors (u, v) with (u, v, a) a right-handed orthonormal frame."""
    a = np.asarray(a, dtype=np.float64)
    e = np.zeros(3)
    e[int(np.argmin(np.abs(a)))] = 1.0
    u = np.cross(a, e)
    u /= np.linalg.norm(u)
    return u, np.cross(a, u)


def fibonacci_hemisphere(m):
    """``m`` nearly uniform unit vectors with z >= 0."""
    k = np.arange(m) + 0.5
    z = 1.0 - k / m
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    t = np.pi * (3.0 - np.sqrt(5.0)) * k
    return np.column_stack([r * np.cos(t), r * np.sin(t), z])


def subsample(X, m):
    """At most ``m`` rows of ``X``, evenly strided (deterministic)."""
    n = X.shape[0]
    return X if n <= m else X[np.linspace(0, n - 1, m).astype(np.int64)]


def circle_start(Y):
    """Algebraic (Kasa) circle / sphere through (n, d) centred points: (centre, r)."""
    A = np.column_stack([2.0 * Y, np.ones(Y.shape[0])])
    b = np.einsum("ij,ij->i", Y, Y)
    sol = np.linalg.lstsq(A, b, rcond=None)[0]
    c = sol[:-1]
    return c, float(np.sqrt(max(sol[-1] + c @ c, 1e-300)))


def axis_candidates(X, Vt, m=200):
    """Candidate axis directions: the principal axes and a hemisphere grid."""
    return np.vstack([Vt, fibonacci_hemisphere(m)])


def cylinder_scores(Y, dirs):
    """For each direction, an algebraic circle of the projected points and the RMS of
    its radial residuals.  Returns (scores, centres (k, 3) on the plane through the
    origin, radii)."""
    out = []
    for a in dirs:
        u, v = frame(a)
        xy = np.column_stack([Y @ u, Y @ v])
        c, r = circle_start(xy)
        rr = np.hypot(xy[:, 0] - c[0], xy[:, 1] - c[1]) - r
        out.append((float(np.sqrt(np.mean(rr * rr))), c[0] * u + c[1] * v, r))
    s = np.array([o[0] for o in out])
    return s, np.array([o[1] for o in out]), np.array([o[2] for o in out])


def cone_scores(Y, dirs):
    """For each direction a, the linear fit x^2 + y^2 = A x + B y + C h^2 + D h + E
    (a cone about a, or a cylinder when C = 0) and the RMS of its approximate
    orthogonal residuals.  Returns a list of (score, x0 (3,), r0, tan_phi, a)."""
    out = []
    for a in dirs:
        u, v = frame(a)
        x, y, h = Y @ u, Y @ v, Y @ a
        M = np.column_stack([x, y, h * h, h, np.ones_like(x)])
        sol = np.linalg.lstsq(M, x * x + y * y, rcond=None)[0]
        cx, cy = 0.5 * sol[0], 0.5 * sol[1]
        k = np.sqrt(max(sol[2], 0.0))
        if k > 1e-12 and sol[3] < 0:
            k = -k
        r0sq = sol[4] + cx * cx + cy * cy
        r0 = np.sqrt(r0sq) if r0sq > 0 else (0.5 * sol[3] / k if k != 0 else 0.0)
        rho = np.hypot(x - cx, y - cy)
        d = (rho - (r0 + k * h)) / np.sqrt(1.0 + k * k)
        score = float(np.sqrt(np.mean(d * d)))
        if not np.isfinite(score):
            score = np.inf
        out.append((score, cx * u + cy * v, float(r0), float(k), np.asarray(a, float)))
    return out
