"""The trim polylines' evaluations inlined (``geomkit._kernels.tess_trim``: its curve
points through ``basis_funs_inline`` and its surface points through an inlined copy of
``surface.surface_point``) against the calls they replaced, bit for bit: the route
before is the same code compiled with the called ``basis.basis_funs`` /
``basis.find_span`` in place of the inlined ones (no copy of it here), on random
rational curves of degrees 1-5 and random rational surfaces of degrees 1-3, at random
parameters and at the knots."""

from __future__ import annotations

import types

import numba
import numpy as np

from geomkit._kernels import basis, surface, tess_trim
from geomkit._kernels.numba_ext.policy import FASTMATH


def _compiled(fn, **names):
    """``fn``'s code compiled with the global ``names`` replaced (not cached: the
    function is not the one its source defines)."""
    py = getattr(fn, "py_func", fn)
    return numba.njit(types.FunctionType(py.__code__, {**py.__globals__, **names}, py.__name__),
                      fastmath=FASTMATH, error_model="numpy")


def _curves(Pc, pc, Uc, ts, out):
    N = np.empty(pc + 1)
    left = np.empty(pc + 1)
    right = np.empty(pc + 1)
    for i in range(ts.shape[0]):
        span = find_span(Pc.shape[0] - 1, pc, ts[i], Uc)  # noqa: F821 - set by _compiled
        out[i, 0], out[i, 1] = curve_in_span(  # noqa: F821
            Pc, pc, Uc, span, ts[i], -0.5, -0.5, 0.5, 0.5, N, left, right)


def _surfaces(Pw, p, q, U, V, uv, out):
    Nu, Nv, left, right, tmp = surface.point_scratch(p, q)
    for i in range(uv.shape[0]):
        point(Pw, p, q, U, V, uv[i, 0], uv[i, 1], Nu, Nv, left, right, tmp,  # noqa: F821
              out[i])


CALLED_CURVE = _compiled(_curves, find_span=basis.find_span,
                         curve_in_span=_compiled(tess_trim._curve_in_span,
                                                 basis_funs_inline=basis.basis_funs))
INLINED_CURVE = _compiled(_curves, find_span=tess_trim.find_span,
                          curve_in_span=tess_trim._curve_in_span)
CALLED_SURFACE = _compiled(_surfaces, point=surface.surface_point)
INLINED_SURFACE = _compiled(_surfaces, point=tess_trim.surface_point)


def _knots(rng, n, p):
    inner = np.sort(rng.random(n - p - 1))
    if n - p - 1 > 1 and rng.random() < 0.5:  # a repeated knot
        inner[1] = inner[0]
    return np.concatenate([np.zeros(p + 1), inner, np.ones(p + 1)])


def _both(called, inlined, args, rows, cols):
    a = np.empty((rows, cols))
    b = np.empty((rows, cols))
    called(*args, a)
    inlined(*args, b)
    assert np.array_equal(a, b)


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
        ts = np.concatenate([rng.random(200), U])  # the knots themselves too
        _both(CALLED_CURVE, INLINED_CURVE, (Pc, p, U, ts), len(ts), 2)


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
        uv = np.concatenate([rng.random((150, 2)),
                             np.stack(np.meshgrid(U, V), -1).reshape(-1, 2)])
        _both(CALLED_SURFACE, INLINED_SURFACE, (Pw, p, q, U, V, uv), len(uv), 3)
