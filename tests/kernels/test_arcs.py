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
