"""The compiled arc (``_kernels.arcs``, as ``arc_curve`` builds every circle edge)
against the numpy formulas it replaced, bit for bit: knots, control points and
weights of random arcs of every span count (a quarter turn and less up to more than a
turn), and the refusal of an empty, reversed or non-finite sweep."""

import math

import numpy as np
import pytest

from geomkit.cad.analytic import arc_curve


def _numpy_arc(C, X, Y, radius, theta0, theta1):
    sweep = theta1 - theta0
    n = max(1, int(math.ceil(sweep / (0.5 * math.pi) - 1e-12)))
    d = sweep / n
    ks = theta0 + d * np.arange(n + 1)
    ks[-1] = theta1
    U = np.concatenate([[theta0] * 3, np.repeat(ks[1:-1], 2), [theta1] * 3])
    wm = math.cos(d / 2)
    a, b, w = [], [], []
    for k in range(n):
        t0 = theta0 + k * d
        tm = t0 + d / 2
        if k == 0:
            a.append(math.cos(t0)); b.append(math.sin(t0)); w.append(1.0)
        a.append(math.cos(tm) / wm); b.append(math.sin(tm) / wm); w.append(wm)
        t1 = theta1 if k == n - 1 else t0 + d
        a.append(math.cos(t1)); b.append(math.sin(t1)); w.append(1.0)
    a, b, w = np.array(a), np.array(b), np.array(w)
    P = C + radius * (a[:, None] * X + b[:, None] * Y)
    Pw = np.empty((len(w), 4))
    Pw[:, :3] = P * w[:, None]
    Pw[:, 3] = w
    return U, Pw


@pytest.mark.parametrize("seed", range(3))
def test_arc_is_the_numpy_formula_bit_for_bit(seed):
    rng = np.random.default_rng(seed)
    spans = set()
    for _ in range(3000):
        C, X, Y = rng.normal(0, 50, 3), rng.normal(size=3), rng.normal(size=3)
        r = float(rng.uniform(1e-3, 1e3))
        t0 = float(rng.uniform(-10, 10))
        t1 = t0 + float(rng.choice([rng.uniform(1e-6, 8.0), np.pi / 2, np.pi, 2 * np.pi]))
        p, U, Pw = arc_curve(C, X, Y, r, t0, t1)
        U0, Pw0 = _numpy_arc(C, X, Y, r, t0, t1)
        assert p == 2 and np.array_equal(U, U0) and np.array_equal(Pw, Pw0)
        spans.add((len(U) - 4) // 2)
    assert spans >= {1, 2, 3, 4, 5}


@pytest.mark.parametrize("t1", [0.0, -1.0, np.nan, np.inf])
def test_empty_reversed_or_infinite_sweep_is_refused(t1):
    with pytest.raises(ValueError, match="sweep"):
        arc_curve(np.zeros(3), np.eye(3)[0], np.eye(3)[1], 1.0, 0.0, t1)


def test_fma_rounds_once():
    """numba_ext.fused.fma: a * b + c correctly rounded (exact rational arithmetic as
    the oracle), also where the unfused sum loses every digit."""
    from fractions import Fraction

    import numba

    from geomkit._kernels.numba_ext.fused import fma

    f = numba.njit(lambda a, b, c: fma(a, b, c))
    rng = np.random.default_rng(4)
    for a, b, c in rng.normal(size=(2000, 3)) * 10.0 ** rng.integers(-8, 8, (2000, 3)):
        assert f(a, b, c) == float(Fraction(a) * Fraction(b) + Fraction(c))
    a = 1.0 + 2.0 ** -30
    assert f(a, a, -(a * a)) == float(Fraction(a) ** 2 - Fraction(a * a)) != 0.0


def _numpy_revolve(curve, S, T, theta0, theta1):
    """The numpy formulas the kernel replaced (A8.1, a control point at a time)."""
    from geomkit.cad.analytic import cross3, norm3
    from geomkit._kernels.arcs import arc_coeffs

    p, U, Pw = curve
    T = T / norm3(T)
    a, b, wa, V = arc_coeffs(float(theta0), float(theta1))
    wc = Pw[:, 3]
    P = Pw[:, :3] / wc[:, None]
    out = np.empty((P.shape[0], a.size, 3))
    for j in range(P.shape[0]):
        O = S + np.dot(P[j] - S, T) * T
        X = P[j] - O
        r = norm3(X)
        if r <= 1e-15 * max(1.0, float(np.abs(P[j]).max())):
            out[j] = O
            continue
        X /= r
        Y = cross3(T, X)
        out[j] = O + r * (a[:, None] * X + b[:, None] * Y)
    return V, out, wc[:, None] * wa[None, :]


@pytest.mark.parametrize("seed", range(3))
def test_revolve_is_the_numpy_formula(seed):
    """revolve (one revolve_net call) against the numpy route on random rational
    generatrices, a control point on the axis among them, every span count: the same
    knots and weights, the points within a few ulps of the model's size (numpy's
    3-element dot is OpenBLAS's, whose fused order the kernel follows; OpenBLAS picks
    its dot kernel by CPU, and on a Zen 5 one point came out 3 ulps away), the control
    point on the axis one point for every angle."""
    from geomkit.cad.analytic import revolve

    rng = np.random.default_rng(seed)
    for _ in range(100):
        n = int(rng.integers(2, 7))
        P = rng.normal(size=(n, 3)) * 5
        S, T = rng.normal(size=3), rng.normal(size=3)
        P[0] = S + 2.5 * T  # on the axis
        w = rng.uniform(0.3, 2.0, n)
        curve = (2, np.array([0.0] * 3 + sorted(rng.uniform(0, 1, n - 3)) + [1.0] * 3)
                 if n >= 3 else np.array([0.0, 0.0, 1.0, 1.0]),
                 np.column_stack([P * w[:, None], w]))
        curve = (min(2, n - 1), curve[1], curve[2])
        t0 = float(rng.uniform(-4, 4))
        t1 = t0 + float(rng.uniform(0.1, 7.0))
        p, q, U, V, Q, W = revolve(curve, S, T, t0, t1)
        V2, Q2, W2 = _numpy_revolve(curve, S, T, t0, t1)
        assert (p, q) == (curve[0], 2)
        np.testing.assert_array_equal(V, V2)
        np.testing.assert_array_equal(W, W2)
        np.testing.assert_allclose(Q, Q2, rtol=0, atol=2e-15 * np.abs(Q2).max())
        assert (Q[0] == Q[0][0]).all()


def test_plane_patch_is_the_numpy_formula_bit_for_bit():
    from geomkit.cad.analytic import plane_patch

    rng = np.random.default_rng(12)
    for _ in range(200):
        O, X, Y = rng.normal(size=(3, 3)) * 10.0 ** rng.integers(-4, 4, (3, 1))
        u0, u1, v0, v1 = rng.normal(size=4) * 50
        p, q, U, V, P, W = plane_patch(O, X, Y, u0, u1, v0, v1)
        ref = np.array([[O + u * X + v * Y for v in (v0, v1)] for u in (u0, u1)])
        np.testing.assert_array_equal(P, ref)
        assert (p, q) == (1, 1) and (W == 1).all()
        np.testing.assert_array_equal(U, [u0, u0, u1, u1])
        np.testing.assert_array_equal(V, [v0, v0, v1, v1])


@pytest.mark.parametrize("seed", range(3))
def test_circle_nets_are_the_edge_by_edge_arcs(seed):
    """The STEP reader's circles in one call (``circle_nets``) against the route it
    replaced, edge by edge: ``arc_curve(C, r x, r y, 1, t0, t1)``, reversed by
    ``reverse_curve`` where the edge runs against its circle; knots and points bit for
    bit, unused edges empty, a sweep that is not finite and positive refused."""
    from geomkit.cad.stepgeom import reverse_curve
    from geomkit._kernels.arcs import circle_nets

    rng = np.random.default_rng(seed)
    n = 60
    C = rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-3, 4, (n, 1))
    x = rng.normal(size=(n, 3))
    y = rng.normal(size=(n, 3))
    r = rng.uniform(0.01, 100.0, n)
    t0 = rng.uniform(0.0, 2 * math.pi, n)
    t = np.column_stack([t0, t0 + rng.choice([rng.uniform(1e-3, 2 * math.pi),
                                              2 * math.pi, 0.5 * math.pi], n)])
    same = rng.random(n) < 0.5
    use = rng.random(n) < 0.8
    ok, U, Pw, uo, po = circle_nets(C, x, y, r, t, same, use)
    assert ok
    for k in range(n):
        Uk, Pk = U[uo[k]:uo[k + 1]], Pw[po[k]:po[k + 1]]
        if not use[k]:
            assert Uk.size == 0 and Pk.shape[0] == 0
            continue
        rk = float(r[k])
        c = arc_curve(C[k], rk * x[k], rk * y[k], 1.0, float(t[k, 0]), float(t[k, 1]))
        p, Ur, Pr = c if same[k] else reverse_curve(c)
        np.testing.assert_array_equal(Uk, Ur)
        np.testing.assert_array_equal(Pk, Pr)
    bad = t.copy()
    bad[3, 1] = bad[3, 0]
    assert not circle_nets(C, x, y, r, bad, same, np.ones(n, dtype=bool))[0]


def test_analytic_frame_is_the_numpy_route():
    """Analytic's frame in one call (``analytic_frame``) against the numpy code it
    replaced (A and X - (X . A) A over their norms, Y = cross3(A, X), the frame
    concatenated) on random and near-degenerate directions: the origin bit for bit,
    A within a few ulps, X and Y within a few ulps of |X| / |X - (X . A) A| (numpy's dot is OpenBLAS's,
    whose kernel, and so its rounding, depends on the CPU; the subtraction cancels
    that much of it); and the refusal of a zero A or an X along A."""
    from geomkit.cad.analytic import cross3, norm3
    from geomkit.cad.brep import Analytic
    from geomkit.cad.loops import Unsupported
    from geomkit._kernels.arcs import analytic_frame

    rng = np.random.default_rng(4)
    for _ in range(3000):
        O = rng.normal(size=3) * 10.0 ** rng.integers(-3, 4)
        A = rng.normal(size=3) * 10.0 ** rng.integers(-8, 8)
        X = rng.normal(size=3) if rng.random() < 0.7 else A * 3.0 + rng.normal(size=3) * 1e-9
        if rng.random() < 0.2:
            A[rng.integers(3)] = 0.0
        a = A / norm3(A)
        x = X - np.dot(X, a) * a
        code, A2, X2, Y2, F = analytic_frame(O, A, X)
        if not norm3(x) > 0:  # (X along A to rounding: refused both ways)
            assert code == 2
            continue
        slack = 8 * np.finfo(float).eps * (1.0 + norm3(X) / norm3(x))
        x = x / norm3(x)
        y = cross3(a, x)
        assert code == 0
        np.testing.assert_array_equal(F[:3], O)
        for got in (A2, F[9:]):
            np.testing.assert_allclose(got, a, rtol=0, atol=4 * np.finfo(float).eps)
        for got, want in ((X2, x), (Y2, y), (F[3:6], x), (F[6:9], y)):
            np.testing.assert_allclose(got, want, rtol=0, atol=slack)
        s = Analytic("cylinder", O, A, X, R=1.0)
        np.testing.assert_array_equal(s.frame, F)
    assert analytic_frame(np.zeros(3), np.zeros(3), np.ones(3))[0] == 1
    assert analytic_frame(np.zeros(3), np.array([0.0, 0, 2]), np.array([0.0, 0, 1]))[0] == 2
    with pytest.raises(Unsupported, match="zero direction"):
        Analytic("plane", np.zeros(3), np.zeros(3), np.ones(3))
