"""``close_pairs`` (the weld's close points, sorted projections) against the route it
replaced, ``cKDTree(Q).query_pairs(r)``: the same pair sets on random points in 2-D
and 3-D with planted exact and near coincidences (inside, at and beyond ``r``),
points on grid lines, clusters, and coordinates far from the origin."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from geomkit._kernels.tess_weld import close_pairs


def _pairs(a):
    return {(int(i), int(j)) for i, j in a.tolist()}


def test_close_pairs_are_the_kd_tree_pairs():
    rng = np.random.default_rng(4)
    checked = 0
    for trial in range(300):
        d = 2 + trial % 2
        n = int(rng.integers(0, 300))
        w = np.array([0.6, 0.8]) if d == 2 else np.array([0.35, 0.48, 0.8])
        scale = float(rng.choice([1.0, 6.3, 1e3, 1e6]))
        Q = rng.random((n, d)) * scale + (1e6 if trial % 7 == 0 else 0.0)
        r = float(rng.choice([1e-13, 1e-10, 1e-3])) * scale
        if trial % 3 == 0 and n:  # grid lines: equal coordinates
            Q[: n // 2, 0] = Q[0, 0]
        if trial % 2 and n > 1:  # exact, near and just-too-far copies
            k = int(rng.integers(1, n // 2 + 1))
            i = rng.choice(n, size=k, replace=False)
            j = rng.choice(n, size=k, replace=False)
            Q[j] = Q[i] + rng.normal(size=(k, d)) * r * rng.choice([0.0, 0.3, 0.9, 3.0],
                                                                     size=(k, 1))
        got = close_pairs(Q, w, r, 2.0 * r + 1e-14 * (np.abs(Q).max() if n else 0.0))
        assert got.dtype == np.int64 and (got[:, 0] < got[:, 1]).all()
        assert len(got) == len(_pairs(got))
        want = _pairs(cKDTree(Q).query_pairs(r, output_type="ndarray")) if n else set()
        assert _pairs(got) == want, trial
        checked += len(want)
    assert checked > 200
