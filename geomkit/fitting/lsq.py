"""Gaussian (least-squares) fits of orthogonal distances.

Plane and line are exact (SVD of the centred points).  Circle (in the least-squares
plane), sphere, cylinder and cone start from algebraic fits (Kasa; for the axes a
search over the principal axes and a hemisphere grid of directions) and finish with
Levenberg-Marquardt on the geometric residuals (:mod:`geomkit.fitting.models`), iterated
until the relative step is below 1e-14 or the sum of squares stops decreasing.
"""

from __future__ import annotations

import numpy as np

from geomkit.fitting import _geom as G
from geomkit.fitting.models import Ball, Cone, Cylinder, Plane, cylinder_geometry, param_scale
from geomkit.fitting.result import FitResult

#: Relative step (lengths / L, angles in rad) that ends the iteration.
STEP_TOL = 1e-14
#: Below this relative step a sum of squares that no longer decreases is rounding.
ROUNDING_STEP = 1e-9
#: Points used for the starting values and the warm-up iterations.
START_POINTS, WARM_POINTS = 400, 20000


def levenberg_marquardt(model, X, L, max_iter=200):
    """Minimise the sum of squared residuals of ``model`` over ``X``.

    Returns (model, info) with info the gradient measure |J^T r| / (|J| |r|), the
    iterations, the last relative step and whether the stopping rule was met.
    """
    scale = param_scale(model, L)
    k = scale.shape[0]
    r = model.residuals(X)
    S = float(r @ r)
    lam, it, step, converged = 0.0, 0, np.inf, False
    while it < max_iter and not converged:
        it += 1
        J = model.jacobian(X) * scale
        A, g = J.T @ J, J.T @ r
        d = np.sqrt(np.diag(A))
        d[d == 0] = 1.0
        As, gs = A / np.outer(d, d), g / d
        while True:
            try:
                z = -np.linalg.solve(As + lam * np.eye(k), gs)
            except np.linalg.LinAlgError:
                z = -np.linalg.lstsq(As + lam * np.eye(k), gs, rcond=None)[0]
            p = z / d
            step = float(np.linalg.norm(p))
            new = model.step(p * scale)
            rn = new.residuals(X)
            Sn = float(rn @ rn)
            if Sn <= S:
                small_gain = Sn >= S * (1.0 - 1e-13)
                model, r, S = new, rn, Sn
                lam = 0.0 if lam <= 1e-3 else lam / 10.0
                converged = step < STEP_TOL or (small_gain and step < ROUNDING_STEP)
                break
            if step < ROUNDING_STEP or lam > 1e12:
                converged = step < ROUNDING_STEP
                it = max_iter if not converged else it
                break
            lam = max(lam * 10.0, 1e-4)
    J = model.jacobian(X) * scale
    gnorm = float(np.linalg.norm(J.T @ r) / max(np.linalg.norm(J) * np.linalg.norm(r), 1e-300))
    return model, {"gradient": gnorm, "iterations": it, "last_step": step,
                   "converged": bool(converged)}


def _warm(model, X, L):
    """A few iterations on a subsample first when ``X`` is large."""
    if X.shape[0] > 2 * WARM_POINTS:
        model, _ = levenberg_marquardt(model, G.subsample(X, WARM_POINTS), L, max_iter=50)
    return levenberg_marquardt(model, X, L)


def _best_of(models, X, L):
    """Refine each candidate on a subsample; keep the smallest sum of squares."""
    Y = G.subsample(X, 3000)
    best = None
    for m in models:
        m, _ = levenberg_marquardt(m, Y, L, max_iter=40)
        r = m.residuals(Y)
        S = float(r @ r)
        if np.isfinite(S) and (best is None or S < best[0]):
            best = (S, m)
    return best[1]


def plane_model(X, Vt):
    return Plane(Vt[2], 0.0)


def circle_frame(X, Vt):
    """LSQ plane of the circle: (normal, u, v, 2-D coordinates)."""
    n = G.canonical(Vt[2])
    u, v = G.frame(n)
    return n, u, v, np.column_stack([X @ u, X @ v])


def sphere_like(Y, L):
    c, r = G.circle_start(G.subsample(Y, WARM_POINTS))
    return _warm(Ball(c, r), Y, L)


def cylinder_lsq(X, Vt, L):
    Y = G.subsample(X, START_POINTS)
    dirs = G.axis_candidates(X, Vt)
    scores, cs, rs = G.cylinder_scores(Y, dirs)
    best = np.argsort(scores)[:4]
    m = _best_of([Cylinder(dirs[i], cs[i], rs[i]) for i in best], X, L)
    return _warm(m, X, L)


def cone_lsq(X, Vt, L):
    Y = G.subsample(X, START_POINTS)
    cands = sorted(G.cone_scores(Y, G.axis_candidates(X, Vt)), key=lambda t: t[0])[:4]
    m = _best_of([Cone(a, x0, r0, np.arctan(k)) for _, x0, r0, k, a in cands], X, L)
    return _warm(m, X, L)


def make_result(kind, method, P, c0, X, model, ctx, contacts, optimality):
    """Assemble the FitResult of a fitted ``model`` (centred coordinates)."""
    geo = {}
    if kind == "plane":
        geo, sgn = model.geometry(c0)
        res = sgn * model.residuals(X)
    elif kind == "line":
        res = model.radial(X)
        foot = c0 + model.x0
        geo = {"point": foot, "direction": G.canonical(model.a)}
    elif kind == "circle":
        n, u, v, Y = ctx
        res = model.residuals(Y)
        geo = {"center": c0 + model.c[0] * u + model.c[1] * v, "normal": n,
               "radius": model.r}
    elif kind == "sphere":
        res = model.residuals(X)
        geo = {"center": c0 + model.c, "radius": model.r}
    elif kind == "cylinder":
        res = model.residuals(X)
        geo = cylinder_geometry(model, c0)
    else:
        res = model.oriented().residuals(X)
        geo = model.geometry(c0)
    if kind == "line":
        form = 2.0 * float(res.max())
    else:
        form = float(res.max() - res.min())
    if contacts is None:
        contacts = [int(np.argmax(res))] if kind == "line" else \
            [int(np.argmax(res)), int(np.argmin(res))]
    return FitResult(kind=kind, method=method, form_error=form, residuals=res,
                     contacts=np.asarray(contacts, dtype=np.int64),
                     optimality=optimality, **geo)


def lsq_model(kind, X, s, Vt, L):
    """Least-squares model of ``kind`` on centred ``X``: (model, ctx, info)."""
    ctx = None
    if kind == "plane":
        return Plane(Vt[2], 0.0), None, {"exact": True, "solver": "svd",
                                         "singular_values": s.tolist()}
    if kind == "line":
        return Cylinder(Vt[0], np.zeros(3), 0.0), None, {
            "exact": True, "solver": "svd", "singular_values": s.tolist()}
    if kind == "circle":
        ctx = circle_frame(X, Vt)
        m, info = sphere_like(ctx[3], L)
    elif kind == "sphere":
        m, info = sphere_like(X, L)
    elif kind == "cylinder":
        m, info = cylinder_lsq(X, Vt, L)
    else:
        m, info = cone_lsq(X, Vt, L)
    info["solver"] = "levenberg-marquardt"
    return m, ctx, info
