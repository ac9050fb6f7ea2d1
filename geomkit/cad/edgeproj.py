"""Trim curves of a face whose edges are given only in model space (a 510 over a
B-spline surface whose 508 loop carries no pcurves): each 3-D edge curve is projected
onto the face's surface with :func:`geomkit.project_points` and becomes a UV polyline,
refined until the surface point of every segment's UV midpoint lies within ``tol`` of
the edge curve's midpoint (``tol``: the larger of the model's resolution and
:data:`EDGE_TOL` x the surface size; writers state resolutions, 1e-7, finer than their
edges lie on their faces).  On a surface closed in u or v (``periods``), the UV
points are unwrapped across the seam (the polyline may then leave the domain by up
to a period, for the loop's chaining to place).  An edge that is not on the surface
(farther than ``tol``), or whose projection jumps, is refused with the reason.
"""

from __future__ import annotations

import numpy as np

from geomkit.tolerances import EDGE_TOL
from geomkit.nurbs.surface import TrimCurve
from geomkit.cad.loops import Unsupported
from geomkit.cad.analytic import curve_eval
from geomkit.nurbs.evaluation import evaluate
from geomkit.query.projection_part import project_points

__all__ = ["edge_uv", "EDGE_TOL"]

_MAX_POINTS = 4097


def edge_uv(base, edges, tol: float, what: str, periods=(0.0, 0.0)):
    """``(pieces, err)``: one UV polyline :class:`~geomkit.TrimCurve` per oriented edge
    (:class:`geomkit.cad.brep._Edge`) on the untrimmed ``base``, and the largest
    model-space distance measured between a segment's UV midpoint and the edge.
    ``periods``: the UV period of each closed direction of ``base`` (0: open)."""
    (u0, u1), (v0, v1) = base.domain
    lo = np.array([u0, v0])
    per = np.asarray(periods, float)
    wrapped = per > 0

    def inside(uv):  # unwrapped parameters back into the domain
        if not wrapped.any():
            return uv
        out = uv.copy()
        for c in np.flatnonzero(wrapped):
            out[:, c] = lo[c] + np.mod(uv[:, c] - lo[c], per[c])
        return out

    pieces, worst = [], 0.0
    for k, e in enumerate(edges):
        s = np.linspace(0.0, 1.0, 17)
        while True:
            X = curve_eval(e.curve, e.ts(s))
            pr = project_points([base], X)
            off = float(np.nanmax(pr.distance)) if np.all(np.isfinite(pr.distance)) \
                else np.inf
            if off > tol:
                raise Unsupported(f"{what}: edge {k} is not on the surface (a point is "
                                  f"{off:.3g} from it, tolerance {tol:.3g})")
            uv = pr.uv
            for c in np.flatnonzero(wrapped):
                uv[:, c] = np.unwrap(uv[:, c], period=per[c])
            sm = 0.5 * (s[1:] + s[:-1])
            Xm = curve_eval(e.curve, e.ts(sm))
            dev = np.linalg.norm(evaluate(base, inside(0.5 * (uv[1:] + uv[:-1]))) - Xm,
                                 axis=1)
            bad = dev > tol
            if not bad.any():
                worst = max(worst, float(dev.max()), off)
                break
            if len(s) + int(bad.sum()) > _MAX_POINTS:
                raise Unsupported(f"{what}: edge {k} has no UV polyline within {tol:.3g} "
                                  f"of {_MAX_POINTS} points (its projection jumps: a "
                                  "seam?)")
            s = np.sort(np.concatenate([s, sm[bad]]))
        pieces.append(TrimCurve.polyline(uv, f"{what}.edge{k}"))
    return pieces, worst
