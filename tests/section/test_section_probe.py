"""Shortcuts of the section that must not change its answers.

* :func:`geomkit._kernels.section_project._project_point` evaluates a Newton start
  with :func:`geomkit._kernels.surface.surface_point` and stops there when it is within
  the tolerance; the iteration itself uses ``surface_derivs``.  The start's ``f`` must
  be the one ``surface_derivs`` gives (the same products summed in the same order), or
  a start at the tolerance could stop where Newton would move.
* :func:`geomkit.section.joins.near_boundary` settles a point as soon as an upper
  bound of its distance is within the reach: the same answers as
  ``boundary_distance(...) <= reach``.
"""

from __future__ import annotations

import numpy as np
import pytest

from geomkit import samples
from geomkit._kernels.section_project import point_scratch
from geomkit._kernels.surface import D1, _binomial_table, derivs_scratch, surface_derivs, \
    surface_point
from geomkit.section.joins import boundary_distance, near_boundary
from geomkit.section.trace import _Eval


@pytest.mark.parametrize("name", ["plate_with_hole", "cylinder_quarter", "sphere", "torus",
                                  "heavy_weights", "freeform_1", "saddle", "wave_seed003"])
def test_point_alone_is_the_derivatives_point(name):
    """Random points, the knots and the domain's corners: the same coordinates."""
    rng = np.random.default_rng(7)
    for s in samples.load(name):
        (u0, u1), (v0, v1) = s.domain
        uu = np.r_[rng.uniform(u0, u1, 300), np.clip(s.knots_u, u0, u1)]
        vv = np.r_[rng.uniform(v0, v1, 300), np.clip(s.knots_v, v0, v1)]
        uv = np.column_stack([rng.choice(uu, 400), rng.choice(vv, 400)])
        Pw, p, q, U, V = s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v
        Nu, Nv, left, right, tmp, X = point_scratch(p, q)
        bin_, scr, SKL = _binomial_table(D1), derivs_scratch(p, q, D1), np.empty((2, 2, 3))
        for u, v in uv:
            surface_point(Pw, p, q, U, V, u, v, Nu, Nv, left, right, tmp, X)
            surface_derivs(Pw, p, q, U, V, u, v, D1, bin_, scr, SKL)
            assert np.array_equal(X, SKL[0, 0]), (name, u, v)


@pytest.mark.parametrize("reach", [0.05, 0.5, 3.0, 12.0])
def test_near_boundary_is_the_distance_within_reach(reach):
    """Points of the plate with a hole on, near and far from its boundary (the outer
    square and the hole)."""
    s = samples.load("plate_with_hole")[0]
    rng = np.random.default_rng(3)
    (u0, u1), (v0, v1) = s.domain
    uv = np.column_stack([rng.uniform(u0, u1, 3000), rng.uniform(v0, v1, 3000)])
    P = _Eval(s, np.array([0.0, 0.0, 1.0, 0.0])).points(uv)
    P += rng.normal(size=P.shape) * reach * 0.1
    want = boundary_distance(s, P, reach) <= reach
    assert want.any() and not want.all()
    assert np.array_equal(near_boundary(s, P, reach), want)
