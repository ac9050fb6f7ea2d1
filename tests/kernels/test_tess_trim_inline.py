"""The trim polylines' evaluations inlined (``geomkit._kernels.tess_trim``: its curve
points through ``basis_funs_inline`` and its surface points through an inlined copy of
``surface.surface_point``) against the calls they replaced (``basis.basis_funs`` and
``surface.surface_point``, compiled as separate functions), bit for bit: random
rational curves of degrees 1-5 and random rational surfaces of degrees 1-3, at random
parameters, knots and spans included."""

from __future__ import annotations

import numpy as np

from geomkit._kernels.basis import basis_funs, find_span
from geomkit._kernels.numba_ext.policy import jit
from geomkit._kernels.surface import surface_point as called_surface_point
from geomkit._kernels.tess_trim import _curve_at, surface_point


@jit
def _curve_called(Pc, pc, Uc, ts, out):
    """The route before: ``basis_funs`` called, then the weighted sum and the clip."""
    N = np.empty(pc + 1)
    left = np.empty(pc + 1)
    right = np.empty(pc + 1)
    for i in range(ts.shape[0]):
        t = ts[i]
        span = find_span(Pc.shape[0] - 1, pc, t, Uc)
        basis_funs(span, t, pc, Uc, N, left, right)
        x = 0.0
        y = 0.0
        w = 0.0
        for r in range(pc + 1):
            b = N[r]
            x += b * Pc[span - pc + r, 0]
            y += b * Pc[span - pc + r, 1]
            w += b * Pc[span - pc + r, 2]
        out[i, 0] = min(max(x / w, -0.5), 0.5)
        out[i, 1] = min(max(y / w, -0.5), 0.5)


@jit
def _curve_inlined(Pc, pc, Uc, ts, out):
    N = np.empty(pc + 1)
    left = np.empty(pc + 1)
    right = np.empty(pc + 1)
    for i in range(ts.shape[0]):
        out[i, 0], out[i, 1] = _curve_at(Pc, pc, Uc, ts[i], -0.5, -0.5, 0.5, 0.5, N, left,
                                         right)


@jit
def _surface(Pw, p, q, U, V, uv, out, inlined):
    m = max(p, q) + 1
    Nu = np.empty(p + 1)
    Nv = np.empty(q + 1)
    left = np.empty(m)
    right = np.empty(m)
    tmp = np.empty(4)
    for i in range(uv.shape[0]):
        if inlined:
            surface_point(Pw, p, q, U, V, uv[i, 0], uv[i, 1], Nu, Nv, left, right, tmp,
                          out[i])
        else:
            called_surface_point(Pw, p, q, U, V, uv[i, 0], uv[i, 1], Nu, Nv, left, right,
                                 tmp, out[i])


def _knots(rng, n, p):
    inner = np.sort(rng.random(n - p - 1))
    if n - p - 1 > 1 and rng.random() < 0.5:  # a repeated knot
        inner[1] = inner[0]
    return np.concatenate([np.zeros(p + 1), inner, np.ones(p + 1)])


def _params(rng, U, k):
    t = rng.random(k)
    return np.concatenate([t, U, [0.0, 1.0]])  # the knots themselves too


def test_inlined_curve_points_match_the_called_route():
    rng = np.random.default_rng(17)
    for _ in range(300):
        p = int(rng.integers(1, 6))
        n = p + 1 + int(rng.integers(0, 6))
        U = _knots(rng, n, p)
        w = rng.uniform(0.2, 3.0, n) if rng.random() < 0.7 else np.ones(n)
        Pc = np.empty((n, 3))
        Pc[:, :2] = (rng.random((n, 2)) - 0.5) * w[:, None]
        Pc[:, 2] = w
        ts = _params(rng, U, 200)
        a = np.empty((len(ts), 2))
        b = np.empty((len(ts), 2))
        _curve_called(Pc, p, U, ts, a)
        _curve_inlined(Pc, p, U, ts, b)
        assert np.array_equal(a, b)


def test_inlined_surface_points_match_the_called_route():
    rng = np.random.default_rng(19)
    for _ in range(200):
        p, q = (int(x) for x in rng.integers(1, 4, 2))
        nu = p + 1 + int(rng.integers(0, 4))
        nv = q + 1 + int(rng.integers(0, 4))
        U, V = _knots(rng, nu, p), _knots(rng, nv, q)
        w = rng.uniform(0.2, 3.0, (nu, nv)) if rng.random() < 0.7 else np.ones((nu, nv))
        Pw = np.empty((nu, nv, 4))
        Pw[..., :3] = rng.standard_normal((nu, nv, 3)) * w[..., None]
        Pw[..., 3] = w
        uv = np.stack([_params(rng, U, 150)[:150], _params(rng, V, 150)[:150]], axis=1)
        uv = np.concatenate([uv, np.stack(np.meshgrid(U, V), -1).reshape(-1, 2)])
        a = np.empty((len(uv), 3))
        b = np.empty((len(uv), 3))
        _surface(Pw, p, q, U, V, uv, a, False)
        _surface(Pw, p, q, U, V, uv, b, True)
        assert np.array_equal(a, b)
