"""Trim curves (pcurves) carried through a reparametrisation of their surface.

A file's surface of revolution is parametrised by the rotation angle; its exact NURBS
form (:mod:`geomkit.cad.analytic`) by a rational parameter that equals the angle at the
knots only.  A pcurve ``c(t) = (u(t), v(t))`` becomes ``(fu(u(t)), fv(v(t)))`` with
monotone maps ``fu``/``fv`` (``None``: unchanged).

* Exact where the mapped curve is the same point set: a straight segment along which
  only one mapped coordinate varies (iso-parametric lines -- most face boundaries), or
  any curve whose varying coordinates are not remapped.  Its vertices are mapped.
* Otherwise the mapped curve is interpolated by C0 piecewise cubics at 4 equally
  spaced parameters per span, spans halved until 7 check points per span are within
  ``tol`` of the mapped curve (the error of a cubic interpolant falls as ``h^4``); the
  largest check error is returned.
"""

from __future__ import annotations

import numpy as np

from geomkit.nurbs.trimming import evaluate_trim_curve
from geomkit.nurbs.surface import TrimCurve

__all__ = ["map_pcurve"]

_R = np.array([0.0, 1 / 3, 2 / 3, 1.0])
# Bernstein basis at _R: B[i, j] = B_j(r_i); Bezier points = inv(B) @ samples
_B = np.array([[(1 - r) ** 3, 3 * r * (1 - r) ** 2, 3 * r * r * (1 - r), r ** 3] for r in _R])
_BINV = np.linalg.inv(_B)
_CHECK = np.array([0.08, 0.17, 0.28, 0.5, 0.61, 0.75, 0.92])
_MAX_SPANS = 20000
_CB = np.array([[(1 - r) ** 3, 3 * r * (1 - r) ** 2, 3 * r * r * (1 - r), r ** 3] for r in _CHECK])


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
        k = a.size
        bez = np.einsum("ij,kjd->kid", _BINV, X[:4 * k].reshape(k, 4, 2))
        chk = X[4 * k:].reshape(k, 7, 2)
        e = np.abs(np.einsum("ij,kjd->kid", _CB, bez) - chk).max(axis=(1, 2))
        split = (e > tol) & (h > hmin)
        if sum(len(x) for x in done_a) + 2 * int(split.sum()) > _MAX_SPANS:
            split[:] = False  # give up refining: the error found is returned
        keep = ~split
        done_a.append(a[keep])
        done_bez.append(bez[keep])
        errs.append(float(e[keep].max(initial=0.0)))
        m = a[split] + h[split] / 2
        a, b = np.concatenate([a[split], m]), np.concatenate([m, b[split]])
    A = np.concatenate(done_a)
    order = np.argsort(A, kind="stable")
    bez = np.concatenate(done_bez)[order]
    B = np.concatenate([A[order][1:], brk[-1:]])
    pts = np.concatenate([bez[:1, 0], bez[:, 1:].reshape(-1, 2)])
    knots = np.concatenate([[A[order][0]] * 4, np.repeat(B[:-1], 3), [B[-1]] * 4])
    return TrimCurve.create(3, knots, pts), max(errs)
