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
