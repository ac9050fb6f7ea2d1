"""Incremental deviation statistics: fed chunk by chunk, equal to the one-pass values.

* counts (points, valid, edge, beyond, failed, within / over / under the tolerance),
  min, max, max |d| and its row: exact;
* mean and RMS: the sums of d and d² are carried as double-double values (two floats
  updated with :func:`math.fsum`, an exactly rounded sum), so the result does not
  depend on how the points were chunked and is the exactly rounded mean of the
  values (to ~1e-32 relative), the same in a streamed, a Dask and an in-memory run;
* std: chunk-wise (count, mean, M2) merged with Chan et al.'s pairwise update
  (accurate to rounding; its last bits may depend on the chunking);
* percentiles: a mergeable logarithmic-bucket sketch (DDSketch, Masson et al. 2019):
  bucket k of |d| holds (γ^(k-1), γ^k] with γ = (1 + α) / (1 - α), one store per
  sign; the estimate of the q-quantile (the sorted value of rank ⌊q (n - 1)⌋) is
  within ``α |d_q|`` of it, α = :data:`PERCENTILE_REL_ERROR`, plus ``zero_tol`` for
  values below it (counted as 0).
"""

from __future__ import annotations

import math

import numpy as np

from geomkit.tolerances import PERCENTILE_REL_ERROR
from geomkit.query import results as R
from geomkit.errors import InvalidInputError

__all__ = ["DeviationStats", "PERCENTILE_REL_ERROR", "PERCENTILES"]

PERCENTILES = (1, 5, 25, 50, 75, 95, 99)


class _DD:
    """A double-double accumulator of float sums (exactly rounded chunk sums)."""

    __slots__ = ("hi", "lo")

    def __init__(self):
        self.hi = 0.0
        self.lo = 0.0

    def add(self, values: np.ndarray):
        v = values.tolist()
        s = math.fsum(v)
        e = math.fsum(v + [-s])            # what s left out (exactly rounded)
        t = math.fsum((self.hi, self.lo, s, e))
        self.lo = math.fsum((self.hi, self.lo, s, e, -t))
        self.hi = t

    @property
    def value(self) -> float:
        return self.hi


class _Sketch:
    """Logarithmic buckets of |x| per sign; dense counts grown on demand."""

    def __init__(self, alpha: float, zero_tol: float):
        self.alpha = alpha
        self.gamma = (1 + alpha) / (1 - alpha)
        self.lg = math.log(self.gamma)
        self.zero_tol = zero_tol
        self.zero = 0
        self.stores = {1: [0, np.zeros(0, np.int64)], -1: [0, np.zeros(0, np.int64)]}

    def _add(self, sign, x):
        k = np.ceil(np.log(x) / self.lg).astype(np.int64)
        lo, hi = int(k.min()), int(k.max())
        off, c = self.stores[sign]
        if c.size == 0:
            off, c = lo, np.zeros(hi - lo + 1, np.int64)
        elif lo < off or hi >= off + c.size:
            nlo, nhi = min(lo, off), max(hi, off + c.size - 1)
            n = np.zeros(nhi - nlo + 1, np.int64)
            n[off - nlo:off - nlo + c.size] = c
            off, c = nlo, n
        c += np.bincount(k - off, minlength=c.size)
        self.stores[sign] = [off, c]

    def add(self, v: np.ndarray):
        a = np.abs(v)
        z = a < self.zero_tol
        self.zero += int(np.count_nonzero(z))
        pos, neg = v[~z & (v > 0)], v[~z & (v < 0)]
        if pos.size:
            self._add(1, pos)
        if neg.size:
            self._add(-1, -neg)

    def quantile(self, q: float, n: int) -> float:
        rank = int(math.floor(q * (n - 1)))
        off, c = self.stores[-1]
        nneg = int(c.sum())
        g = self.gamma
        if rank < nneg:  # negatives, from the most negative (largest key) down
            cum = np.cumsum(c[::-1])
            j = int(np.searchsorted(cum, rank + 1))
            k = off + c.size - 1 - j
            return -2 * g ** k / (g + 1)
        rank -= nneg
        if rank < self.zero:
            return 0.0
        rank -= self.zero
        off, c = self.stores[1]
        j = int(np.searchsorted(np.cumsum(c), rank + 1))
        return 2 * g ** (off + j) / (g + 1)


class DeviationStats:
    """Statistics of deviations fed in row order, chunk by chunk.

    Parameters
    ----------
    tolerance : (lower, upper) or None
    zero_tol : float
        Deviations below this in magnitude count as 0 in the percentile sketch.
    """

    def __init__(self, tolerance=None, zero_tol: float = 1e-12):
        self.tolerance = tolerance
        self.n = self.valid = self.edge = self.beyond = self.failed = 0
        self.within = self.over = self.under = 0
        self.min = math.inf
        self.max = -math.inf
        self.max_abs = -1.0
        self.argmax_abs = -1
        self.s1, self.s2 = _DD(), _DD()
        self._mean = 0.0
        self._m2 = 0.0
        self.sketch = _Sketch(PERCENTILE_REL_ERROR, zero_tol)

    def update(self, deviation, status, edge):
        """Add the next rows (in row order): deviation (NaN = no value), status
        codes and edge flags."""
        d = np.asarray(deviation, dtype=np.float64)
        ok = np.isfinite(d)
        v = d[ok]
        base = self.n
        self.n += int(d.size)
        self.edge += int(np.count_nonzero(edge))
        self.beyond += int(np.count_nonzero(status == R.BEYOND))
        self.failed += int(np.count_nonzero(status == R.FAILED))
        if not v.size:
            return
        self.min = min(self.min, float(v.min()))
        self.max = max(self.max, float(v.max()))
        a = np.abs(v)
        j = int(np.argmax(a))
        if a[j] > self.max_abs:  # strict: the first row of the maximum wins
            self.max_abs = float(a[j])
            self.argmax_abs = base + int(np.nonzero(ok)[0][j])
        self.s1.add(v)
        self.s2.add(v * v)
        m, nb = float(v.mean()), int(v.size)
        m2 = float(np.sum((v - m) ** 2))
        na = self.valid
        delta = m - self._mean
        tot = na + nb
        self._mean += delta * nb / tot
        self._m2 += m2 + delta * delta * na * nb / tot
        self.valid = tot
        if self.tolerance:
            lo, hi = self.tolerance
            self.within += int(np.count_nonzero((v >= lo) & (v <= hi)))
            self.over += int(np.count_nonzero(v > hi))
            self.under += int(np.count_nonzero(v < lo))
        self.sketch.add(v)

    def percentile(self, p: float) -> float:
        """The p-th percentile (0..100) within α |value| + zero_tol (module doc)."""
        if not self.valid:
            return float("nan")
        return self.sketch.quantile(p / 100.0, self.valid)

    def result(self, require_valid: bool = False) -> dict:
        """JSON-ready statistics (the keys of :meth:`DeviationReport.summary`).

        Raises
        ------
        InvalidInputError
            ``require_valid`` and no point has a deviation.
        """
        st = {"points": self.n, "valid": self.valid, "edge": self.edge,
              "beyond": self.beyond, "failed": self.failed}
        if self.valid:
            n = self.valid
            st.update(min=self.min, max=self.max, mean=self.s1.value / n,
                      rms=math.sqrt(self.s2.value / n), std=math.sqrt(self._m2 / n),
                      max_abs=self.max_abs, argmax_abs=self.argmax_abs,
                      percentiles={f"p{p}": self.percentile(p) for p in PERCENTILES},
                      percentile_error={"relative": PERCENTILE_REL_ERROR,
                                        "absolute": self.sketch.zero_tol})
        else:
            if require_valid:
                raise InvalidInputError(
                    f"no valid point: all {self.n} points are beyond the max distance or "
                    f"failed ({self.beyond} beyond, {self.failed} failed); no statistics",
                    "points")
            nan = float("nan")
            st.update(min=nan, max=nan, mean=nan, rms=nan, std=nan, max_abs=nan,
                      argmax_abs=-1, percentiles=None, percentile_error=None)
        if self.tolerance:
            n = self.valid
            pct = (lambda k: 100.0 * k / n) if n else (lambda k: float("nan"))
            st.update(within=self.within, over=self.over, under=self.under,
                      pct_within=pct(self.within), pct_over=pct(self.over),
                      pct_under=pct(self.under))
        return st
