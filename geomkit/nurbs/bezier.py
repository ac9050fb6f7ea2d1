"""Bézier extraction of NURBS surfaces (knot insertion, The NURBS Book A5.6).

The patches carry exact homogeneous control nets; with positive weights each patch
lies in the convex hull of its control points, which gives the conservative bounds
that later subdivision and distance certification use.
"""

from __future__ import annotations

import numpy as np

from geomkit._kernels.bezier import decompose
from geomkit.nurbs.surface import BezierPatches, Surface

__all__ = ["bezier_patches"]


def _net(a):
    """Control rows for ``decompose``: C-contiguous and writable (a copy of a read-only
    surface net), as :func:`geomkit.nurbs.trimming._segments` passes its curves'; knots go
    read-only (:func:`_knots`).  numba compiles a read-only and a writable array
    argument separately: one argument kind per parameter, one compiled ``decompose``."""
    a = np.ascontiguousarray(a)
    return a if a.flags.writeable else a.copy()


def _knots(a):
    a = np.ascontiguousarray(a)
    if a.flags.writeable:
        a = a.view()
        a.setflags(write=False)
    return a


def bezier_patches(surface: Surface) -> BezierPatches:
    """Split ``surface`` into rational Bézier patches, one per non-empty knot cell.

    Returns
    -------
    BezierPatches
        ``homogeneous`` (nsu, nsv, p+1, q+1, 4); patch (i, j) covers
        ``[u_breaks[i], u_breaks[i+1]] x [v_breaks[j], v_breaks[j+1]]`` and evaluates
        exactly like the surface there.  Trims are ignored (patches cover the domain).
    """
    p, q = surface.degree_u, surface.degree_v
    Pw = surface.homogeneous
    nu, nv = Pw.shape[:2]
    # u direction: each row index i is a control point of a curve in R^(nv*4)
    Qu, ub = decompose(_net(Pw.reshape(nu, nv * 4)), p, _knots(surface.knots_u))
    nsu = Qu.shape[0]
    rows = Qu.reshape(nsu * (p + 1), nv, 4)
    # v direction: columns become control points of curves in R^(nsu*(p+1)*4)
    cols = np.ascontiguousarray(rows.transpose(1, 0, 2)).reshape(nv, -1)
    Qv, vb = decompose(_net(cols), q, _knots(surface.knots_v))
    nsv = Qv.shape[0]
    H = Qv.reshape(nsv, q + 1, nsu, p + 1, 4).transpose(2, 0, 3, 1, 4)
    H = np.ascontiguousarray(H)
    for a in (H, ub, vb):
        a.setflags(write=False)
    return BezierPatches(H, ub, vb)
