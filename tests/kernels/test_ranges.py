"""Column ranges (``_kernels.ranges``) against numpy's reductions they replace, bit for
bit: random arrays of every width, NaN in a column, infinities, a single row, and the
refusal of no rows."""

import numpy as np
import pytest

from geomkit._kernels.ranges import col_range, spread


@pytest.mark.parametrize("seed", range(3))
def test_col_range_and_spread_are_numpys(seed):
    rng = np.random.default_rng(seed)
    for _ in range(300):
        n, k = int(rng.integers(1, 80)), int(rng.integers(1, 5))
        X = rng.normal(size=(n, k)) * 10.0 ** rng.integers(-6, 6, (1, k))
        if rng.random() < 0.2:
            X[rng.integers(n), rng.integers(k)] = rng.choice([np.nan, np.inf, -np.inf])
        lo, hi = col_range(X)
        np.testing.assert_array_equal(lo, X.min(axis=0))
        np.testing.assert_array_equal(hi, X.max(axis=0))
        with np.errstate(invalid="ignore"):
            ref = float(np.ptp(X, axis=0).max())
        got = spread(X)
        assert got == ref or (np.isnan(got) and np.isnan(ref))
    lo, hi = col_range(np.array([[3.0, -1.0]]))
    assert list(lo) == [3.0, -1.0] == list(hi)
    with pytest.raises(ValueError, match="no rows"):
        col_range(np.zeros((0, 3)))


@pytest.mark.parametrize("seed", range(3))
def test_hull_spread_is_the_loop_boxes_extent(seed):
    """The reader's sort key of a loop: the extent of the edges' control-point boxes
    (each ``col_range(Pw[:, :3] / Pw[:, 3:])``), as it was computed before, bit for bit
    (NaN and infinite coordinates, zero weights, one row)."""
    from geomkit._kernels.ranges import hull_spread

    rng = np.random.default_rng(seed)
    for _ in range(300):
        edges = []
        for _ in range(int(rng.integers(1, 6))):
            n = int(rng.integers(1, 12))
            Pw = np.column_stack([rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-6, 6),
                                  rng.uniform(0.2, 2.0, n)])
            if rng.random() < 0.1:
                Pw[rng.integers(n), rng.integers(4)] = rng.choice([np.nan, np.inf, 0.0])
            edges.append(Pw)
        with np.errstate(invalid="ignore", divide="ignore"):
            boxes = np.concatenate([np.array(col_range(Pw[:, :3] / Pw[:, 3:]))
                                    for Pw in edges])
            lo, hi = col_range(boxes)
            ref = float((hi - lo).max())
        got = hull_spread(np.concatenate(edges))
        assert got == ref or (np.isnan(got) and np.isnan(ref))
    with pytest.raises(ValueError, match="no rows"):
        hull_spread(np.zeros((0, 4)))


def test_nearest_rows_matches_kdtree():
    from scipy.spatial import cKDTree

    from geomkit._kernels.ranges import nearest_rows

    rng = np.random.default_rng(11)
    for trial in range(200):
        G = rng.normal(size=(int(rng.integers(1, 400)), 3)) * 10.0 ** rng.uniform(-3, 3)
        X = G[rng.integers(0, len(G), 30)] + rng.normal(size=(30, 3)) * 1e-2
        got = nearest_rows(G, X)
        d_got = ((X - G[got]) ** 2).sum(1)
        d_tree, _ = cKDTree(G).query(X)
        assert np.array_equal(np.sqrt(d_got), d_tree) or np.allclose(np.sqrt(d_got), d_tree,
                                                                     rtol=1e-15, atol=0)
        brute = ((X[:, None, :] - G[None]) ** 2).sum(-1).argmin(1)
        assert np.array_equal(got, brute)
    # equally near rows: the first wins
    G = np.array([[1.0, 0, 0], [-1.0, 0, 0], [0, 1.0, 0]])
    assert nearest_rows(G, np.zeros((1, 3)))[0] == 0
    assert nearest_rows(G, np.full((1, 3), np.nan))[0] == 0
