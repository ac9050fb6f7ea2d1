"""``_tess_trim.speed_bound`` is a true bound of ``|S_u| + |S_v|`` (it decides when a
trim loop within rounding of the domain's edges is the domain itself)."""

from __future__ import annotations

import numpy as np
import pytest

import geomkit
from geomkit.mesh.trim_polylines import speed_bound
from geomkit.nurbs.evaluation import derivatives
from geomkit.nurbs.surface import Surface


def _random_surface(rng, p, q, nu, nv, wspread):
    ku = np.r_[np.zeros(p), np.sort(rng.random(nu - p + 1)), np.ones(p)]
    kv = np.r_[np.zeros(q), np.sort(rng.random(nv - q + 1)), np.ones(q)]
    ku[p], ku[-p - 1], kv[q], kv[-q - 1] = 0.0, 1.0, 0.0, 1.0
    P = rng.normal(size=(nu, nv, 3))
    W = np.exp(rng.uniform(-wspread, wspread, (nu, nv))) if wspread else None
    return Surface(p, q, ku, kv, P, W)


def _max_speed(s, n=60):
    (u0, u1), (v0, v1) = s.domain
    uv = np.stack(np.meshgrid(np.linspace(u0, u1, n), np.linspace(v0, v1, n)), -1).reshape(-1, 2)
    D = derivatives(s, uv, 1)
    return float(np.max(np.linalg.norm(D[:, 1, 0], axis=1) + np.linalg.norm(D[:, 0, 1], axis=1)))


@pytest.mark.parametrize("name", ["sphere", "torus", "freeform_1", "heavy_weights", "crease"])
def test_bound_holds_on_the_shared_cases(name):
    for s in geomkit.samples.load(name):
        assert _max_speed(s) <= speed_bound(s)


@pytest.mark.parametrize("seed", range(6))
def test_bound_holds_on_random_rational_nets(seed):
    rng = np.random.default_rng(seed)
    s = _random_surface(rng, 1 + seed % 3, 1 + (seed + 1) % 3, 6, 7, [0, 1, 4][seed % 3])
    m = _max_speed(s)
    b = speed_bound(s)
    assert m <= b
    assert b < 1e6 * m       # a bound, not a placeholder
