"""The result type of every characteristic, input checks and small geometric helpers
shared by the GD&T modules (private to :mod:`geomkit.gdt`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import ConvexHull
from scipy.spatial import QhullError

from geomkit.errors import InvalidInputError
from geomkit.fitting import orthonormal_frame
from geomkit.validate import as_float_array

#: Points within CONTACT_REL * value + CONTACT_ABS * size of an extreme are "deciding".
CONTACT_REL, CONTACT_ABS = 1e-9, 1e-12


def jsonable(x):
    """Lists, floats, ints, bools, str and dicts of them (recursively)."""
    if hasattr(x, "to_dict") and callable(x.to_dict):
        try:
            return x.to_dict(residuals=False)
        except TypeError:
            return x.to_dict()
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, (np.floating, np.integer, np.bool_)):
        return x.item()
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    return x


@dataclass(frozen=True)
class Characteristic:
    """One evaluated GD&T characteristic.

    Attributes
    ----------
    type : str
        ``"flatness"``, ``"position"``, ... (the function's name).
    measured : float or tuple of float
        The value compared with the tolerance (a zone width or diameter, model
        units); a pair for a rectangular position zone.
    tolerance : dict
        ``zone`` (the tolerance value) and the modifiers in force (``diameter``,
        ``material`` and ``bonus``, ``unequal``, ``method``, ...).
    datums : tuple of str
        Datum labels the zone refers to, in order (empty for form).
    passed : bool
        ``measured`` within the tolerance (plus bonus, if any).
    n_points : int
    deciding : (k,) int
        Indices of the points that decide ``measured``.
    details : dict
        The fit, the zone geometry and the other values behind ``measured``.
    """

    type: str
    measured: float | tuple
    tolerance: dict
    datums: tuple
    passed: bool
    n_points: int
    deciding: np.ndarray
    details: dict = field(default_factory=dict, repr=False)

    def to_dict(self) -> dict:
        """JSON-safe dict (fits without their residuals)."""
        return {"type": self.type, "measured": jsonable(self.measured),
                "tolerance": jsonable(self.tolerance), "datums": list(self.datums),
                "passed": bool(self.passed), "n_points": int(self.n_points),
                "deciding": jsonable(self.deciding), "details": jsonable(self.details)}


def check_points(points, need, what, field="points") -> np.ndarray:
    """(n, 3) finite float64 points, at least ``need`` of them for ``what``."""
    P = as_float_array(points, field, shape=(None, 3))
    if P.shape[0] < need:
        raise InvalidInputError(f"{what} needs at least {need} points, got {P.shape[0]}",
                                field)
    return P


def check_tol(tol, field="tol") -> float:
    """A finite tolerance > 0."""
    if isinstance(tol, bool):
        raise InvalidInputError(f"expected a number, got {tol!r}", field)
    try:
        t = float(tol)
    except (TypeError, ValueError):
        raise InvalidInputError(f"expected a number, got {tol!r}", field) from None
    if not math.isfinite(t) or t <= 0.0:
        raise InvalidInputError(f"a tolerance must be finite and > 0, got {t!r}", field)
    return t


def check_direction(v, field) -> np.ndarray:
    """A unit (3,) vector from a finite non-zero (3,) vector."""
    d = as_float_array(v, field, shape=(3,))
    n = float(np.linalg.norm(d))
    if not n > 0.0:
        raise InvalidInputError("a direction must be non-zero", field)
    return d / n


def check_choice(value, choices, field):
    if not isinstance(value, str) or value not in choices:
        raise InvalidInputError(f"expected one of {', '.join(map(repr, choices))}, got "
                                f"{value!r}", field)
    return value


def size_of(P) -> float:
    """A length scale of the points (bounding-box diagonal, 1 when all coincide)."""
    d = float(np.linalg.norm(P.max(axis=0) - P.min(axis=0)))
    return d if d > 0.0 else 1.0


def extremes(v, L, value=None):
    """Indices of the entries of ``v`` within tolerance of its max and of its min."""
    value = float(v.max() - v.min()) if value is None else value
    tol = CONTACT_REL * abs(value) + CONTACT_ABS * L
    return np.unique(np.concatenate([np.nonzero(v >= v.max() - tol)[0],
                                     np.nonzero(v <= v.min() + tol)[0]]))


def perp_basis(z):
    """Unit (e1, e2) with (e1, e2, z) right-handed orthonormal (deterministic):
    :func:`geomkit.fitting.orthonormal_frame`'s pair, turned by a half turn."""
    u, v = orthonormal_frame(np.asarray(z, dtype=np.float64))
    return -u, -v


def reject(v, a):
    """Component of vectors ``v`` (..., 3) perpendicular to unit ``a``."""
    return v - (v @ a)[..., None] * a


def orient(v, ref):
    """``v`` or ``-v``, whichever points along ``ref`` (``v`` unchanged if ref None)."""
    if ref is None:
        return v
    return -v if float(v @ ref) < 0.0 else v


def width_along(P, u):
    s = P @ u
    return float(s.max() - s.min())


def min_width_2d(Q, u0, max_angle=math.radians(60.0)):
    """Minimum width of 2-D points over directions within ``max_angle`` of ``u0``.

    The width w(u) = max u.q - min u.q is, between the angles where the extreme
    points change, |a| cos(theta - phi): concave, so its minima over an interval are
    at those angles (the normals of the convex hull's edges) or at the interval's
    ends.  Every such candidate is evaluated exactly.

    Parameters
    ----------
    Q : (n, 2) float
    u0 : (2,) float
        Unit nominal direction (the result is oriented along it).

    Returns
    -------
    u : (2,) unit direction, width : float
    """
    X = Q - Q.mean(axis=0)
    cands = []
    try:
        V = X[ConvexHull(X).vertices]
        E = np.roll(V, -1, axis=0) - V
        N = np.column_stack([E[:, 1], -E[:, 0]])
        nn = np.linalg.norm(N, axis=1)
        cands.append(N[nn > 0] / nn[nn > 0, None])
    except (QhullError, ValueError):
        # (nearly) collinear points: the normal of their principal line
        _, _, Vt = np.linalg.svd(X, full_matrices=True)
        cands.append(Vt[-1][None, :])
    c, s = math.cos(max_angle), math.sin(max_angle)
    rot = np.array([[c, -s], [s, c]])
    cands.append(np.vstack([rot @ u0, rot.T @ u0]))
    C = np.vstack(cands)
    C = np.where((C @ u0)[:, None] < 0.0, -C, C)
    C = C[C @ u0 >= c - 1e-12]
    S = X @ C.T
    w = S.max(axis=0) - S.min(axis=0)
    k = int(np.argmin(w))
    return C[k], float(w[k])
