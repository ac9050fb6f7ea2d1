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
from scipy.spatial import cKDTree

from geomkit._kernels.pcurve_map import curve_at
from geomkit._kernels.ranges import nearest_rows
from geomkit._kernels.surface import invert_points, surface_points
from geomkit.tolerances import EDGE_TOL
from geomkit.nurbs.surface import TrimCurve
from geomkit.cad.loops import Unsupported
from geomkit.cad.analytic import curve_eval, unwrap
from geomkit.nurbs.evaluation import evaluate
from geomkit.query.projection_part import project_points

__all__ = ["edge_uv", "EDGE_TOL", "SurfaceInverse"]

_MAX_POINTS = 4097
_BRUTE = 200_000
"""Up to this many grid-point x query-point pairs the seeds are found by brute force
(:func:`~geomkit._kernels.ranges.nearest_rows`), beyond by a k-d tree built once."""


class SurfaceInverse:
    """Parameters of points on (within ``tol`` of) a surface: Gauss-Newton from the
    nearest of a grid of its points (several per knot span); a point it does not bring
    within ``tol`` is projected exactly (:func:`geomkit.project_points`)."""

    def __init__(self, base):
        self.base = base
        (u0, u1), (v0, v1) = self.dom = base.domain
        # 4 points per knot span (the knots are sorted: a span ends where they step)
        Ku, Kv = base.knots_u, base.knots_v
        gu = int(min(128, max(16, 4 * np.count_nonzero(Ku[1:] != Ku[:-1]))))
        gv = int(min(128, max(16, 4 * np.count_nonzero(Kv[1:] != Kv[:-1]))))
        us, vs = np.linspace(u0, u1, gu), np.linspace(v0, v1, gv)
        self.grid = np.column_stack([np.repeat(us, gv), np.tile(vs, gu)])
        # base.evaluate's points: the grid lies in the domain (linspace's ends are its
        # ends), which evaluate's check would clamp to, unchanged
        self.points = np.empty((self.grid.shape[0], 3))
        surface_points(base.homogeneous, base.degree_u, base.degree_v, base.knots_u,
                       base.knots_v, self.grid, self.points)
        self._tree = None

    def nearest(self, X):
        """Index of the grid point nearest each point of ``X``."""
        if self.points.shape[0] * X.shape[0] <= _BRUTE:
            return nearest_rows(self.points, np.ascontiguousarray(X, float))
        if self._tree is None:
            self._tree = cKDTree(self.points)
        return self._tree.query(X)[1]

    def newton(self, X):
        """``(uv, dist)``: the Gauss-Newton parameters of the points ``X`` and their
        distances from the surface points there (a local minimum: an upper bound of
        the distance to the surface)."""
        (u0, u1), (v0, v1) = self.dom
        uv = np.ascontiguousarray(self.grid[self.nearest(X)])
        b = self.base
        dist = np.empty(len(X))
        if len(X):
            invert_points(b.homogeneous, b.degree_u, b.degree_v, b.knots_u, b.knots_v,
                          np.ascontiguousarray(X, float), uv, u0, u1, v0, v1,
                          1e-14 * max(u1 - u0, v1 - v0), dist)
        return uv, dist

    def __call__(self, X, tol):
        uv, dist = self.newton(X)
        far = ~(dist <= tol)
        if far.any():
            pr = project_points([self.base], X[far])
            uv[far] = pr.uv
            dist[far] = pr.distance
        return uv, dist


def _curve_at(e, s):
    """The points of edge ``e`` at its loop parameters ``s``: ``curve_eval(e.curve,
    e.ts(s))``, bit for bit, in one compiled call."""
    p, U, Pw = e.curve
    return curve_at(np.ascontiguousarray(Pw, dtype=np.float64), int(p),
                    np.asarray(U, dtype=np.float64), e.ts(s))


def edge_uv(base, edges, tol: float, what: str, periods=(0.0, 0.0)):
    """``(pieces, err)``: one UV polyline :class:`~geomkit.TrimCurve` per oriented edge
    (:class:`geomkit.cad.faceedges.Edge`) on the untrimmed ``base``, and the largest
    model-space distance measured between a segment's UV midpoint and the edge.
    ``periods``: the UV period of each closed direction of ``base`` (0: open)."""
    (u0, u1), (v0, v1) = base.domain
    lo = np.array([u0, v0])
    per = np.asarray(periods, float)
    wrapped = np.flatnonzero(per > 0).tolist()

    def inside(uv):  # unwrapped parameters back into the domain
        if not wrapped:
            return uv
        out = uv.copy()
        for c in wrapped:
            out[:, c] = lo[c] + np.mod(uv[:, c] - lo[c], per[c])
        return out

    # the edges of the loop are refined together: each round projects the new points
    # of every edge in one call (the per-call cost of the inversion dominates) and
    # measures every edge's midpoints in a few array operations
    inverse = SurfaceInverse(base)
    n0 = 17
    s0 = np.linspace(0.0, 1.0, n0)
    sm0 = 0.5 * (s0[1:] + s0[:-1])
    S = [s0] * len(edges)  # (replaced, never written to)
    raw0, dist0 = inverse(np.concatenate([e.points(n0) for e in edges]), tol)
    RAW = [raw0[k * n0:(k + 1) * n0] for k in range(len(edges))]
    DIST = [dist0[k * n0:(k + 1) * n0] for k in range(len(edges))]
    # the first round's largest distance of each edge (np.nanmax when all are finite)
    D0 = dist0.reshape(len(edges), n0)
    fin0 = np.isfinite(D0).all(axis=1).tolist()
    max0 = D0.max(axis=1).tolist()
    UV = [None] * len(edges)
    worst = 0.0
    active = list(range(len(edges)))
    first = True
    while active:
        rounds = []
        for k in active:
            if first:
                off = max0[k] if fin0[k] else np.inf
            else:
                dist = DIST[k]
                off = float(np.nanmax(dist)) if np.all(np.isfinite(dist)) else np.inf
            if off > tol:
                raise Unsupported(f"{what}: edge {k} is not on the surface (a point is "
                                  f"{off:.3g} from it, tolerance {tol:.3g})")
            uv = RAW[k].copy()
            for c in wrapped:
                uv[:, c] = unwrap(uv[:, c], per[c])
            sm = sm0 if S[k] is s0 else 0.5 * (S[k][1:] + S[k][:-1])
            rounds.append((k, off, uv, sm))
        first = False
        mid = evaluate(base, inside(np.concatenate([0.5 * (uv[1:] + uv[:-1])
                                                    for _, _, uv, _ in rounds])))
        # every edge's curve at its midpoints (curve_eval's points) and their
        # distances (np.linalg.norm's: the square root of each row's sum of squares)
        C = np.concatenate([_curve_at(edges[k], sm) for k, _, _, sm in rounds])
        d = mid - C
        dev_all = np.sqrt(np.add.reduce(d * d, axis=1))
        starts = np.cumsum([0] + [sm.size for _, _, _, sm in rounds[:-1]])
        any_bad = np.logical_or.reduceat(dev_all > tol, starts).tolist()
        dev_max = np.maximum.reduceat(dev_all, starts).tolist()
        todo, new_X, o = [], [], 0
        for j, (k, off, uv, sm) in enumerate(rounds):
            e = edges[k]
            dev = dev_all[o:o + sm.size]
            o += sm.size
            if not any_bad[j]:
                worst = max(worst, dev_max[j], off)
                UV[k] = uv
                continue
            bad = dev > tol
            if len(S[k]) + int(bad.sum()) > _MAX_POINTS:
                raise Unsupported(f"{what}: edge {k} has no UV polyline within {tol:.3g} "
                                  f"of {_MAX_POINTS} points (its projection jumps: a "
                                  "seam?)")
            new = sm[bad]
            todo.append((k, new))
            new_X.append(curve_eval(e.curve, e.ts(new)))
        if todo:  # only the new points are projected
            nuv_all, nd_all = inverse(np.concatenate(new_X), tol)
            o = 0
            for k, new in todo:
                nuv, nd = nuv_all[o:o + new.size], nd_all[o:o + new.size]
                o += new.size
                order = np.argsort(np.concatenate([S[k], new]), kind="stable")
                S[k] = np.concatenate([S[k], new])[order]
                RAW[k] = np.concatenate([RAW[k], nuv])[order]
                DIST[k] = np.concatenate([DIST[k], nd])[order]
        active = [k for k, _ in todo]
    pieces = [TrimCurve.polyline(uv, f"{what}.edge{k}") for k, uv in enumerate(UV)]
    return pieces, worst
