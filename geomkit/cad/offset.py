"""IGES 140 (offset surface) as a NURBS approximation with a measured error.

An offset ``S(u, v) + d N(u, v)`` of a NURBS surface is not a NURBS surface, so it is
approximated: a bicubic B-spline interpolating the offset points on a tensor grid in
the base surface's parameters (so the base's pcurves trim it unchanged) that holds the
base's knots and is refined interval by interval until the largest distance between
the approximation and the true offset, measured at the grid's cell centres and edge
midpoints (a sample off the interpolation nodes), is within ``tol /`` :data:`SAFETY`;
the error stated is :data:`SAFETY` x that sample's largest (the largest on a dense
301 x 301 sample of a freeform offset was 1.06 x the midpoint sample's), so within
``tol`` (default :data:`OFFSET_TOL` x the base's size).
The achieved error is recorded as :attr:`geomkit.Surface.approx_error`, which every
result computed on the face carries into its bound.
"""

from __future__ import annotations

import numpy as np

from geomkit.tolerances import OFFSET_TOL
from geomkit.cad.loops import Unsupported
from geomkit.nurbs.evaluation import evaluate, normals

__all__ = ["offset_args", "OFFSET_TOL", "SAFETY"]

_MAX_GRID = 513
SAFETY = 2.0
"""The fit aims at ``tol / SAFETY`` on its check sample and states ``SAFETY`` x the
sampled error: the true largest error between samples is above the sampled one."""


def _offset_points(base, d, uu, vv):

    uv = np.stack(np.meshgrid(uu, vv, indexing="ij"), -1).reshape(-1, 2)
    N, status = normals(base, uv, return_status=True)
    if np.any(status != 0):
        raise Unsupported("offset of a surface with degenerate normals (a pole) is not "
                          "approximated")
    return (evaluate(base, uv) + d * N).reshape(len(uu), len(vv), 3)


def _nodes(base, k: int, lo: float, hi: float) -> np.ndarray:
    """The base's distinct knots in ``[lo, hi]`` with 3 nodes inside each span."""
    U = np.asarray(base.knots_u if k == 0 else base.knots_v, float)
    br = np.unique(np.concatenate([[lo, hi], U[(U > lo) & (U < hi)]]))
    return np.unique(np.concatenate([np.linspace(a, b, 5) for a, b in zip(br[:-1],
                                                                         br[1:])]))


def _refine(nodes, e, aim):
    """``nodes`` with every interval whose error ``e`` exceeds ``aim`` split into
    ``ceil(1.2 (e / aim)^(1/4))`` (at most 8) equal parts: a cubic interpolant's error
    falls as the 4th power of the spacing."""
    k = np.clip(np.ceil(1.2 * (np.maximum(e, 0) / aim) ** 0.25), 1, 8).astype(int)
    k[e <= aim] = 1
    a, b = nodes[:-1], nodes[1:]
    extra = [a[i] + (b[i] - a[i]) * np.arange(1, k[i]) / k[i] for i in np.nonzero(k > 1)[0]]
    return np.sort(np.concatenate([nodes, *extra]))


def offset_args(base, d: float, tol: float | None = None):
    """``((3, 3, U, V, P, None), error)``: the offset by ``d`` along the base's unit
    normal, interpolated as in the module doc; ``error`` is the measured largest
    distance.

    The interpolation nodes start at the base's knots with 3 nodes inside each knot
    span, and are refined where the error is: an interval in ``u`` is split
    (:func:`_refine`) where the error at its midpoints (any ``v``) exceeds the aim,
    likewise in ``v``.  Flat regions keep few nodes; the fit never smooths across a
    base knot without a node on it.
    """
    from scipy.interpolate import RectBivariateSpline

    (u0, u1), (v0, v1) = base.domain
    P = base.control_points.reshape(-1, 3)
    size = float(np.linalg.norm(np.ptp(P, axis=0)))
    tol = OFFSET_TOL * size if tol is None else tol
    aim = tol / SAFETY
    uu, vv = _nodes(base, 0, u0, u1), _nodes(base, 1, v0, v1)
    while True:
        X = _offset_points(base, d, uu, vv)
        fits = [RectBivariateSpline(uu, vv, X[..., k], kx=3, ky=3, s=0) for k in range(3)]
        um = np.sort(np.concatenate([uu, 0.5 * (uu[1:] + uu[:-1])]))
        vm = np.sort(np.concatenate([vv, 0.5 * (vv[1:] + vv[:-1])]))
        T = _offset_points(base, d, um, vm)
        F = np.stack([f(um, vm) for f in fits], -1)
        E = np.linalg.norm(F - T, axis=-1)  # nodes at even, midpoints at odd indices
        err = float(E.max())
        if max(len(uu), len(vv)) >= _MAX_GRID:
            break
        if err <= aim:
            break
        eu = E[1::2, :].max(axis=1)  # error between u nodes (any v)
        ev = E[:, 1::2].max(axis=0)
        uu, vv = _refine(uu, eu, aim), _refine(vv, ev, aim)
    if err > aim:
        raise Unsupported(f"offset surface not approximated within {tol:.3g} "
                          f"(reached {SAFETY * err:.3g} on a {len(uu)} x {len(vv)} grid)")
    err *= SAFETY
    tx, ty = fits[0].tck[0], fits[0].tck[1]
    m, k = len(tx) - 4, len(ty) - 4
    C = np.stack([f.tck[2].reshape(m, k) for f in fits], -1)
    return (3, 3, np.asarray(tx, float), np.asarray(ty, float), C, None), err
