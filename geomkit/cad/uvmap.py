"""Trim curves (pcurves) carried through a reparametrisation of their surface.

A file's surface of revolution is parametrised by the rotation angle; its exact NURBS
form (:mod:`geomkit.cad.analytic`) by a rational parameter that equals the angle at the
knots only.  A pcurve ``c(t) = (u(t), v(t))`` becomes ``(fu(u(t)), fv(v(t)))`` with
monotone maps ``fu``/``fv`` (``None``: unchanged).

* Exact where the mapped curve is the same point set: a straight segment along which
  only one mapped coordinate varies (iso-parametric lines -- most face boundaries), or
  any curve whose varying coordinates are not remapped.  Its vertices are mapped.
* Otherwise the mapped curve is interpolated by C0 piecewise quintics at 6 equally
  spaced parameters per span, spans split until 9 check points per span are within
  ``tol`` of the mapped curve; the error of a quintic interpolant falls as ``h^6``, so a
  span with error ``e`` is cut into ``(e / tol)^(1/6)`` pieces (with a margin).  The
  largest check error is returned.
"""

from __future__ import annotations

import numpy as np

from geomkit._kernels.pcurve_map import fit_edge_pcurve, spans_net
from geomkit.nurbs.trimming import evaluate_trim_curve
from geomkit.nurbs.surface import TrimCurve

__all__ = ["map_pcurve", "map_edge", "spans_curve"]

DEGREE = 5
"""Degree of the interpolating Bézier spans: the error falls as ``h^6``, so a curve
carried to 1e-10 of its range needs few spans (cubic spans needed ~7x more, and every
span join is a vertex of the mesh's trim polyline)."""


def _bernstein(r):
    from math import comb

    r = np.asarray(r, float)[:, None]
    k = np.arange(DEGREE + 1)
    return np.array([comb(DEGREE, j) for j in k]) * r ** k * (1 - r) ** (DEGREE - k)


_R = np.linspace(0.0, 1.0, DEGREE + 1)
_BINV = np.linalg.inv(_bernstein(_R))  # Bezier points = _BINV @ samples at _R
_CHECK = np.array([0.05, 0.13, 0.27, 0.41, 0.5, 0.59, 0.73, 0.87, 0.95])
_CB = _bernstein(_CHECK)
_MAX_SPANS = 20000
_MAX_SPLIT = 16


def _apply(uv, fu, fv):
    out = np.array(uv, float)
    if fu is not None:
        out[..., 0] = fu(out[..., 0])
    if fv is not None:
        out[..., 1] = fv(out[..., 1])
    return out


def map_pcurve(c: TrimCurve, fu, fv, tol: float):
    """``(mapped TrimCurve, error)`` -- see the module docstring."""
    P = c.control_points
    varies = np.ptp(P, axis=0) > 0
    mapped_vary = [bool(varies[0] and fu is not None), bool(varies[1] and fv is not None)]
    if not any(mapped_vary):
        return TrimCurve.create(c.degree, c.knots, _apply(P, fu, fv), c.weights), 0.0
    if c.is_polyline and P.shape[0] == 2 and not all(varies):
        return TrimCurve.polyline(_apply(P, fu, fv)), 0.0
    p = c.degree
    brk = np.unique(c.knots[p: c.knots.size - p])

    def f(t):
        t = np.clip(t, brk[0], brk[-1])
        return _apply(evaluate_trim_curve(c, t)[:, 0, :], fu, fv)

    # all spans of one halving level are fitted and checked in one evaluation
    a, b = brk[:-1].copy(), brk[1:].copy()
    done_a, done_bez, errs = [], [], [0.0]
    hmin = 1e-9 * (brk[-1] - brk[0])
    while a.size:
        h = b - a
        T = np.concatenate([(a[:, None] + h[:, None] * _R).ravel(),
                            (a[:, None] + h[:, None] * _CHECK).ravel()])
        X = f(T)
        k, n = a.size, DEGREE + 1
        bez = np.einsum("ij,kjd->kid", _BINV, X[:n * k].reshape(k, n, 2))
        chk = X[n * k:].reshape(k, _CHECK.size, 2)
        e = np.abs(np.einsum("ij,kjd->kid", _CB, bez) - chk).max(axis=(1, 2))
        split = (e > tol) & (h > hmin)
        # pieces per failing span from the error's h^6 decay (a margin of 1.25 on
        # the length), 2 to _MAX_SPLIT: one or two rounds instead of one per halving
        m = np.clip(np.ceil(1.25 * (e[split] / tol) ** (1.0 / 6.0)), 2, _MAX_SPLIT)
        m = m.astype(np.int64)
        if sum(len(x) for x in done_a) + int(m.sum()) > _MAX_SPANS:
            split[:] = False  # give up refining: the error found is returned
            m = m[:0]
        keep = ~split
        done_a.append(a[keep])
        done_bez.append(bez[keep])
        errs.append(float(e[keep].max(initial=0.0)))
        lo, step = np.repeat(a[split], m), np.repeat(h[split] / m, m)
        j = np.arange(int(m.sum())) - np.repeat(np.cumsum(m) - m, m)
        a = lo + j * step
        b = np.where(j + 1 == np.repeat(m, m), np.repeat(b[split], m), lo + (j + 1) * step)
    return spans_curve(np.concatenate(done_a), np.concatenate(done_bez), brk[-1]), max(errs)


def map_edge(edge, rev: bool, kind: int, frame, radii, periodic, ref, maps,
             diag: TrimCurve, tol: float):
    """``(TrimCurve, error)``: :func:`map_pcurve` of the pcurve ``diag`` (a polyline
    ``(s, s)`` over the loop parameter ``s`` in [0, 1], its vertices the starting
    spans) mapped by the local coordinates of the edge's point at ``s`` on a surface
    of revolution, in one kernel call (:func:`geomkit._kernels.pcurve_map.fit_edge_pcurve`
    documents the arguments).  ``edge`` is the ``(p, U, Pw)`` curve, run backwards when
    ``rev``; ``radii`` is ``(R, r, tan(alpha))``; ``periodic[c]`` whether coordinate
    ``c`` is an angle kept on the branch of the reference samples ``ref``;
    ``maps[c]`` the arc ``(theta0, theta1)`` the coordinate is mapped by, or None."""
    p, U, Pw = edge
    U = np.asarray(U, float)
    M = np.zeros((2, 3))
    for c, m in enumerate(maps):
        if m is not None:
            M[c] = 1.0, m[0], m[1]
    T = np.ascontiguousarray(diag.knots[1:-1])
    S = np.ascontiguousarray(diag.control_points[:, 0])
    starts, bez, err = fit_edge_pcurve(
        np.ascontiguousarray(Pw, float), int(p), U, float(U[p]), float(U[-p - 1]),
        bool(rev), int(kind), np.ascontiguousarray(frame, float), float(radii[0]),
        float(radii[1]), float(radii[2]), np.ascontiguousarray(ref, float),
        np.asarray(periodic, np.int64), M, T, S, float(tol), _BINV, _CHECK, _CB,
        _MAX_SPANS, _MAX_SPLIT)
    return spans_curve(starts, bez, float(T[-1])), float(err)


def spans_curve(starts: np.ndarray, bez: np.ndarray, end: float) -> TrimCurve:
    """The C0 chain of quintic Bézier spans (k, 6, 2) that start at the parameters
    ``starts`` (any order) and end, the last one, at ``end``."""
    ok, knots, pts = spans_net(starts, bez, float(end))
    if not ok:
        return TrimCurve.create(DEGREE, knots, pts)  # the error that names the fault
    # clamped, interior knots of multiplicity DEGREE: what create() would check
    w = np.ones(len(pts))
    for a in (knots, pts, w):
        a.setflags(write=False)
    return TrimCurve(DEGREE, knots, pts, w)
