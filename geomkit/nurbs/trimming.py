"""Trim curves: evaluation and inside/outside classification of UV points.

Classification is exact away from the trim curves: the winding number of a UV point
around each loop is computed against the exact rational curves by adaptive
subdivision near the point (see :mod:`geomkit._kernels.trim`).  Only points proven to
lie within ``tol`` of a trim curve are reported as ``ON_BOUNDARY``; the default
``tol`` is ``TRIM_TOL`` (1e-9) times the larger side of the parameter domain.
"""

from __future__ import annotations

import numpy as np

from geomkit import tolerances as tols
from geomkit._kernels.bezier import curve_points, decompose
from geomkit._kernels.trim import BOUNDARY, INSIDE, OUTSIDE, classify_points
from geomkit.validate import as_float_array, as_points
from geomkit.errors import InvalidInputError
from geomkit.nurbs.surface import Surface, TrimCurve

__all__ = ["classify_uv", "evaluate_trim_curve", "OUTSIDE", "INSIDE", "ON_BOUNDARY"]

ON_BOUNDARY = BOUNDARY


def _segments(surface: Surface):
    """Pack all trim loops as homogeneous rational Bézier segments (cached).

    Returns ``seg`` (S, pmax+1, 3), ``deg`` (S,), ``loop`` (S,) and the loop count.
    Gaps between consecutive pieces (within the closure tolerance) are bridged by
    straight segments so that every loop is exactly closed.
    """
    cached = surface._cache.get("trim_segments")
    if cached is not None:
        return cached
    pieces = []  # (deg, Q (p+1, 3), loop)
    for k, loop in enumerate(surface.trim):
        n = len(loop.pieces)
        for i, c in enumerate(loop.pieces):
            Q, _ = decompose(c.homogeneous, c.degree, c.knots)
            for s in range(Q.shape[0]):
                pieces.append((c.degree, Q[s], k))
            nxt = loop.pieces[(i + 1) % n]
            if np.any(c.end != nxt.start):
                bridge = np.array([[*c.end, 1.0], [*nxt.start, 1.0]])
                pieces.append((1, bridge, k))
    pmax = max((d for d, _, _ in pieces), default=1)
    seg = np.ones((len(pieces), pmax + 1, 3))
    deg = np.empty(len(pieces), dtype=np.int64)
    lp = np.empty(len(pieces), dtype=np.int64)
    for s, (d, Q, k) in enumerate(pieces):
        seg[s, : d + 1] = Q
        deg[s] = d
        lp[s] = k
    result = (seg, deg, lp, len(surface.trim))
    surface._cache["trim_segments"] = result
    return result


def classify_uv(surface: Surface, uv, tol: float | None = None) -> np.ndarray:
    """Classify parameter points against the trimmed face.

    Parameters
    ----------
    surface : Surface
    uv : (..., 2) float
        Parameter points (may lie outside the domain).
    tol : float, optional
        Boundary band width in UV units; default ``TRIM_TOL * max(domain sides)``.

    Returns
    -------
    (...,) int8
        ``INSIDE`` (1), ``OUTSIDE`` (0) or ``ON_BOUNDARY`` (2).  ``ON_BOUNDARY`` means
        proven within ``tol`` of a trim curve or of the domain edge; ``INSIDE`` and
        ``OUTSIDE`` are exact for every other point.  An untrimmed surface is its whole
        domain.
    """
    if not isinstance(surface, Surface):
        raise InvalidInputError(f"expected a geomkit.Surface, got {type(surface).__name__}",
                                "surface")
    arr, lead = as_points(uv, 2, "uv")
    (u0, u1), (v0, v1) = surface.domain
    if tol is None:
        tol = tols.TRIM_TOL * max(u1 - u0, v1 - v0)
    tol = float(tol)
    if not np.isfinite(tol) or tol < 0:
        raise InvalidInputError(f"must be a finite number >= 0, got {tol!r}", "tol")
    out = np.empty(arr.shape[0], dtype=np.int8)
    # the domain rectangle
    du = np.minimum(arr[:, 0] - u0, u1 - arr[:, 0])
    dv = np.minimum(arr[:, 1] - v0, v1 - arr[:, 1])
    d = np.minimum(du, dv)
    out[:] = np.where(d < -tol, OUTSIDE, np.where(d <= tol, BOUNDARY, INSIDE))
    if surface.trim and arr.shape[0]:
        seg, deg, lp, nloops = _segments(surface)
        res = np.empty(arr.shape[0], dtype=np.int8)
        classify_points(seg, deg, lp, nloops, arr, tol, res)
        # outside the trim wins; on a trim curve wins over inside
        out = np.where((out == OUTSIDE) | (res == OUTSIDE), OUTSIDE,
                       np.where((res == BOUNDARY) | (out == BOUNDARY), BOUNDARY, INSIDE))
        out = out.astype(np.int8)
    return out.reshape(lead)


def evaluate_trim_curve(curve: TrimCurve, t, order: int = 0) -> np.ndarray:
    """Points (and derivatives) of a 2-D trim curve.

    Parameters
    ----------
    curve : TrimCurve
    t : (m,) float in ``[knots[p], knots[-p-1]]``
    order : int, number of derivatives

    Returns
    -------
    (m, order+1, 2) float: C(t), C'(t), ... (The NURBS Book A3.2 + A4.2).
    """
    t = as_float_array(t, "t", shape=(None,))
    a, b = curve.knots[curve.degree], curve.knots[-curve.degree - 1]
    if t.size and (t.min() < a or t.max() > b):
        raise InvalidInputError(f"parameters must lie in [{a}, {b}]", "t")
    out = np.empty((t.shape[0], order + 1, 2))
    if t.shape[0]:
        curve_points(curve.homogeneous, curve.degree, curve.knots, t, order, out)
    return out
