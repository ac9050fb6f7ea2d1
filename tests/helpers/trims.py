"""Trim loops in closed form for the trimming and validation tests: the exact circle
as one rational quadratic NURBS (or four arcs) and the unit plate to trim.

:func:`circle_dict` runs clockwise (a hole's orientation);
:func:`helpers.tesshelp.circle_dict` is the counter-clockwise one."""

from __future__ import annotations

import numpy as np

from geomkit import Surface

S2 = 2 ** -0.5


def unit_plate(trim=None):
    """The bilinear plate [0, 1]^2 x {0} with UV = XY, trimmed by ``trim``."""
    P = np.array([[[0, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0]]], float)
    return Surface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], P, trim=trim)


def circle_dict(c=(0.5, 0.5), r=0.2):
    """The exact circle of centre ``c`` and radius ``r`` in UV, clockwise, as one
    rational quadratic trim-curve dict (4 quarters)."""
    unit = np.array([[1, 0], [1, -1], [0, -1], [-1, -1], [-1, 0], [-1, 1], [0, 1], [1, 1],
                     [1, 0]], float)
    return {"degree": 2, "knots": [0, 0, 0, .25, .25, .5, .5, .75, .75, 1, 1, 1],
            "control_points": (np.asarray(c) + r * unit).tolist(),
            "weights": [1, S2, 1, S2, 1, S2, 1, S2, 1]}


def circle_quarters(c=(0.5, 0.5), r=0.2):
    """The circle of :func:`circle_dict` as four rational quadratic arcs, one dict per
    arc."""
    d = circle_dict(c, r)
    cp, w = d["control_points"], d["weights"]
    return [{"degree": 2, "knots": [0, 0, 0, 1, 1, 1], "control_points": cp[2 * k: 2 * k + 3],
             "weights": w[2 * k: 2 * k + 3]} for k in range(4)]
