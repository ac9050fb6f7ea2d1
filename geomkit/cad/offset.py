"""IGES 140 (offset surface) as a NURBS approximation with a measured error.

An offset ``S(u, v) + d N(u, v)`` of a NURBS surface is not a NURBS surface, so it is
approximated: a bicubic B-spline interpolating the offset points on a grid uniform in
the base surface's parameters (so the base's pcurves trim it unchanged), the grid
doubled until the largest distance between the approximation and the true offset,
measured at the grid's cell centres and edge midpoints (a dense sample off the
interpolation nodes), is within ``tol`` (default :data:`OFFSET_TOL` x the base's size).
The achieved error is recorded as :attr:`geomkit.Surface.approx_error`, which every
result computed on the face carries into its bound.
"""

from __future__ import annotations

import numpy as np

from .loops import Unsupported

__all__ = ["offset_args", "OFFSET_TOL"]

OFFSET_TOL = 1e-6
"""Default approximation error of an offset surface, relative to its base's size."""
_MAX_GRID = 257


def _offset_points(base, d, uu, vv):
    from ..evaluation import evaluate, normals

    uv = np.stack(np.meshgrid(uu, vv, indexing="ij"), -1).reshape(-1, 2)
    N, status = normals(base, uv, return_status=True)
    if np.any(status != 0):
        raise Unsupported("offset of a surface with degenerate normals (a pole) is not "
                          "approximated")
    return (evaluate(base, uv) + d * N).reshape(len(uu), len(vv), 3)


def offset_args(base, d: float, tol: float | None = None):
    """``((3, 3, U, V, P, None), error)``: the offset by ``d`` along the base's unit
    normal, interpolated as above; ``error`` is the measured largest distance."""
    from scipy.interpolate import RectBivariateSpline

    (u0, u1), (v0, v1) = base.domain
    P = base.control_points.reshape(-1, 3)
    size = float(np.linalg.norm(np.ptp(P, axis=0)))
    tol = OFFSET_TOL * size if tol is None else tol
    n = 9
    while True:
        uu, vv = np.linspace(u0, u1, n), np.linspace(v0, v1, n)
        X = _offset_points(base, d, uu, vv)
        fits = [RectBivariateSpline(uu, vv, X[..., k], kx=3, ky=3, s=0) for k in range(3)]
        um = np.sort(np.concatenate([uu, 0.5 * (uu[1:] + uu[:-1])]))
        vm = np.sort(np.concatenate([vv, 0.5 * (vv[1:] + vv[:-1])]))
        T = _offset_points(base, d, um, vm)
        F = np.stack([f(um, vm) for f in fits], -1)
        err = float(np.linalg.norm(F - T, axis=-1).max())
        if err <= tol or n >= _MAX_GRID:
            break
        n = 2 * n - 1
    if err > tol:
        raise Unsupported(f"offset surface not approximated within {tol:.3g} "
                          f"(reached {err:.3g} on a {n} x {n} grid)")
    tx, ty, _ = fits[0].tck[0], fits[0].tck[1], None
    m, k = len(tx) - 4, len(ty) - 4
    C = np.stack([f.tck[2].reshape(m, k) for f in fits], -1)
    return (3, 3, np.asarray(tx, float), np.asarray(ty, float), C, None), err
