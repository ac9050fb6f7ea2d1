"""Chebyshev fits: minimum zone, minimum circumscribed, maximum inscribed.

All three are min-max problems ``min_p max_i v_i(p)`` over the local parameters of a
model (:mod:`geomkit.fitting.models`):

* minimum zone: v = (+r_i, -r_i), every parameter free (the size too), width 2 max;
* minimum circumscribed: v = d_i (distance to the centre / axis), size excluded;
* maximum inscribed: v = -d_i, size excluded.

They are solved by sequential linear programming with a trust region (HiGHS dual
simplex through :func:`scipy.optimize.linprog`): at the current parameters the
residuals are linearised on the points with the largest values, the LP gives the step,
the step is kept when the true maximum over all points decreases.  At a vertex
solution (k + 1 contacts for k parameters) the steps are Newton steps on the
contact equations and converge quadratically.  The answer is certified by the
first-order (KKT) condition of min-max: the origin lies in the convex hull of the
gradients of the contacts' values; the distance of the origin to that hull
(relative, from a non-negative least-squares fit of the multipliers) is reported,
with the decrease the linearised LP still finds in a small trust region.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linprog, nnls

from geomkit.fitting.models import Ball, Cylinder, param_scale

#: Points per sign block handed to each LP (the largest values).
LP_POINTS = 300
#: The iteration stops when the LP predicts a decrease below PRED_TOL * L.
PRED_TOL = 1e-15
#: Contacts: points within CONTACT_REL * f + CONTACT_ABS * L of the maximum.
CONTACT_REL, CONTACT_ABS = 1e-9, 1e-13
#: The KKT residual (relative) below which the optimality conditions are met.
KKT_TOL = 1e-8
#: Above this KKT residual the SLP answer is polished by SQP steps.
POLISH_KKT = 1e-11
#: An SQP step may raise the maximum by this much (x L): rounding on a flat optimum.
POLISH_BAND = 1e-13
_HIGHS = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}


class _Problem:
    """Values and Jacobian blocks of one min-max problem."""

    def __init__(self, model, mode):
        self.mode = mode
        k = len(model.ptype)
        self.cols = np.arange(k) if mode == "zone" else \
            np.array([j for j in range(k) if j != model.size])
        self.k = k

    def values(self, m, X):
        if self.mode == "zone":
            r = m.residuals(X)
            return np.stack([r, -r])
        d = m.radial(X)
        return (d if self.mode == "outer" else -d)[None, :]

    def jac(self, m, X, block):
        J = m.jacobian(X)[:, self.cols]
        if self.mode == "zone":
            return J if block == 0 else -J
        return J if self.mode == "outer" else -J

    def full_step(self, p):
        out = np.zeros(self.k)
        out[self.cols] = p
        return out


def _lp(prob, m, X, V, f, delta, m_points=LP_POINTS):
    """Solve the linearised min-max in the box |p_j| <= delta_j.  Returns (p, t)."""
    rows, rhs = [], []
    for b in range(V.shape[0]):
        v = V[b]
        idx = np.argpartition(-v, m_points)[:m_points] if v.shape[0] > m_points else \
            np.arange(v.shape[0])
        rows.append(prob.jac(m, X[idx], b) * delta)
        rhs.append(-v[idx])
    A = np.vstack(rows)
    fs = max(abs(f), 1e-300)
    A_ub = np.column_stack([A / fs, -np.ones(A.shape[0])])
    b_ub = np.concatenate(rhs) / fs
    k = A.shape[1]
    c = np.zeros(k + 1)
    c[-1] = 1.0
    res = linprog(c, A_ub=A_ub, b_ub=b_ub, bounds=[(-1.0, 1.0)] * k + [(None, None)],
                  method="highs-ds", options=_HIGHS)
    if res.status != 0 or res.x is None:
        return np.zeros(k), f
    return res.x[:-1] * delta, res.x[-1] * fs


def slp(model, X, mode, L, max_iter=300):
    """Minimise max_i v_i over the local parameters of ``model`` (see module doc).

    Returns (model, contacts, optimality dict).
    """
    prob = _Problem(model, mode)
    scale = param_scale(model, L)[prob.cols]
    V = prob.values(model, X)
    f = float(V.max())
    rho = float(np.clip(10.0 * abs(f) / L, 1e-9, 0.1))
    it, converged = 0, False
    while it < max_iter:
        it += 1
        delta = rho * scale
        p, t = _lp(prob, model, X, V, f, delta)
        pred = f - t
        if pred <= PRED_TOL * L:
            converged = True
            break
        new = model.step(prob.full_step(p))
        Vn = prob.values(new, X)
        fn = float(Vn.max())
        if fn < f:
            ratio = (f - fn) / pred
            at_edge = np.max(np.abs(p) / delta) > 0.99
            model, V, f = new, Vn, fn
            if ratio > 0.5 and at_edge:
                rho = min(2.0 * rho, 0.5)
            elif ratio < 0.25:
                rho *= 0.5
            if np.linalg.norm(p / scale) < 1e-15:
                converged = True
                break
        else:
            rho *= 0.25
            if rho < 1e-17:
                converged = True
                break
    contacts, info, act = certify(prob, model, X, V, f, L, scale)
    if info["kkt_residual"] > POLISH_KKT:
        model, polished = _polish(prob, model, X, L, scale, act)
        if polished:
            V = prob.values(model, X)
            f = float(V.max())
            contacts, info, act = certify(prob, model, X, V, f, L, scale)
        info["polish_iterations"] = polished
    info.update({"iterations": it, "converged": bool(converged),
                 "solver": "sequential LP (HiGHS)"})
    info["met"] = bool(converged and info["kkt_residual"] < KKT_TOL)
    return model, contacts, info


def certify(prob, model, X, V, f, L, scale):
    """Contacts and the first-order optimality measures at ``model``."""
    tol = CONTACT_REL * abs(f) + CONTACT_ABS * L
    blocks, idx = np.nonzero(V >= f - tol)
    g = np.vstack([prob.jac(model, X[idx[blocks == b]], b) for b in range(V.shape[0])])
    g = g * scale / L
    norm = max(float(np.abs(g).max()), 1e-300)
    w = 1e3 * norm
    A = np.vstack([g.T, w * np.ones(g.shape[0])])
    b = np.concatenate([np.zeros(g.shape[1]), [w]])
    lam, _ = nnls(A, b, maxiter=50 * A.shape[1] + 200)
    kkt = float(np.linalg.norm(g.T @ lam) / norm)
    _, t = _lp(prob, model, X, V, f, 1e-7 * scale)
    gap = max(0.0, f - t) / max(abs(f), 1e-300)
    contacts = np.unique(idx)
    return contacts, {"kkt_residual": kkt, "lp_gap": float(gap),
                      "n_contacts": int(contacts.shape[0]),
                      "multiplier_sum": float(lam.sum())}, (blocks, idx, lam)


def _polish(prob, model, X, L, scale, act, max_iter=12):
    """SQP (Newton) steps on the contact set for optima that are not vertices
    (fewer than k + 1 contacts, e.g. a circle circumscribed on a diameter), where
    the LP steps converge only linearly.  The Hessian of the Lagrangian sum
    lam_i v_i is taken by central differences in the local chart (it sets the rate,
    not the fixed point).  Returns (model, iterations made, 0 when none helped)."""
    blocks, idx, lam = act
    k = prob.cols.shape[0]
    Xa = X[idx]

    def vals(m):
        V = prob.values(m, Xa)
        return V[blocks, np.arange(idx.shape[0])]

    f0 = float(prob.values(model, X).max())
    done = 0
    for it in range(max_iter):
        e = 1e-4
        H = np.zeros((k, k))
        lv = lambda z: float(lam @ vals(model.step(prob.full_step(z * scale))))
        for i in range(k):
            for j in range(i, k):
                zi, zj = np.eye(k)[i] * e, np.eye(k)[j] * e
                H[i, j] = H[j, i] = (lv(zi + zj) - lv(zi - zj) - lv(zj - zi)
                                     + lv(-zi - zj)) / (4 * e * e)
        G = np.vstack([prob.jac(model, Xa[blocks == b], b) for b in range(2)
                       if np.any(blocks == b)]) * scale
        order = np.concatenate([np.nonzero(blocks == b)[0] for b in range(2)
                                if np.any(blocks == b)])
        v = vals(model)[order]
        m = v.shape[0]
        K = np.zeros((k + 1 + m, k + 1 + m))
        K[:k, :k] = H
        K[:k, k + 1:] = G.T
        K[k, k + 1:] = 1.0
        K[k + 1:, :k] = G
        K[k + 1:, k] = -1.0
        rhs = np.concatenate([np.zeros(k), [1.0], -v])
        sol = np.linalg.lstsq(K, rhs, rcond=None)[0]
        z = sol[:k]
        new = model.step(prob.full_step(z * scale))
        fn = float(prob.values(new, X).max())
        if not fn <= f0 + POLISH_BAND * L:
            break
        model, f0, done = new, fn, it + 1
        mu = np.empty(m)
        mu[order] = sol[k + 1:]
        lam = np.maximum(mu, 0.0)
        if np.linalg.norm(z) < 1e-15:
            break
        f0 = min(f0, fn)
    return model, done


def chebyshev_fit(kind, method, start, X, ctx, L):
    """Chebyshev fit of ``kind`` from the least-squares ``start`` model."""
    data = ctx[3] if kind == "circle" else X
    if kind == "line" or method == "mincircumscribed":
        mode = "outer"
    elif method == "maxinscribed":
        mode = "inner"
    else:
        mode = "zone"
    model, contacts, info = slp(start, data, mode, L)
    if mode != "zone":
        d = model.radial(data)
        r = float(d.max() if mode == "outer" else d.min())
        if isinstance(model, Ball):
            model = Ball(model.c, r)
        else:
            model = Cylinder(model.a, model.x0, r)
    info["mode"] = mode
    return model, contacts, info
