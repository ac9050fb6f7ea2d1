"""Analytic.build's generator line of a cylinder or cone, computed in Python floats,
against the numpy expression it replaced, bit for bit."""

import math

import numpy as np

from geomkit.cad.analytic import line_curve, revolve
from geomkit.cad.brep import Analytic


def test_cylinder_and_cone_generator_is_the_numpy_formula():
    rng = np.random.default_rng(8)
    for _ in range(500):
        O = rng.normal(size=3) * 10.0 ** rng.integers(-2, 3)
        kind = "cone" if rng.random() < 0.5 else "cylinder"
        alpha = float(rng.uniform(0.05, 1.4)) if kind == "cone" else 0.0
        s = Analytic(kind, O, rng.normal(size=3), rng.normal(size=3),
                     R=float(rng.uniform(0.1, 50.0)), alpha=alpha)
        a0, a1 = np.sort(rng.normal(size=2) * 10.0)
        b0, b1 = 0.0, float(rng.uniform(0.5, 2 * math.pi))
        args, fu, fv = s.build((a0, a1), (b0, b1))
        ta = math.tan(s.alpha)
        gen = line_curve(s.O + (s.R + a0 * ta) * s.X + a0 * s.A,
                         s.O + (s.R + a1 * ta) * s.X + a1 * s.A, a0, a1)
        want = revolve(gen, s.O, s.A, b0, b1)
        for got, exp in zip(args, want):
            np.testing.assert_array_equal(np.asarray(got), np.asarray(exp))
        assert fu is None and fv.theta0 == b0 and fv.theta1 == b1
