"""The numbers of a STEP file's plain point and direction records, read for all the
records of an entity name at once from their bytes
(:func:`geomkit._kernels.p21_scan.read_coordinates`), for
:meth:`geomkit.cad.p21.P21.numbers` and :meth:`~geomkit.cad.p21.P21.coordinates`.

A plain record is ``NAME('label', (x, y[, z]))``.  The kernel reads a number only
when its value is exact by construction (Clinger's fast path: a significand of at
most 2**53 (trailing zeros aside) times or over an exact power of ten, one
correctly rounded operation:
``float``'s value, bit for bit); a record with any other number (more digits, a
larger exponent, a number ``float`` may reject) or more than three is read by the
record-by-record route, which gives ``float``'s values or None.
"""

from __future__ import annotations

import numpy as np

from geomkit._kernels.p21_scan import read_coordinates

__all__ = ["CoordinateTable"]

PLAIN, OTHER, BY_FLOAT = 0, 1, 2
"""A record's status: read here, not of the plain form, left to ``float``."""


class CoordinateTable:
    """The numbers of the records ``ids`` (one entity name's) with bodies ``bodies``
    (Latin-1 text), or at ``spans`` ``(bytes, starts, ends)`` of the file (then
    ``bodies`` is not read); ``each(id)`` reads a record the kernel leaves to
    ``float`` (its numbers or None), once here.

    Attributes
    ----------
    row : dict, record id -> its row.
    values : (n, 3) float, a row's numbers (``count`` of them) when its status is
        PLAIN (BY_FLOAT: a record of more than three numbers).
    count, status : lists of int per row.
    finite3 : list of bool per row, PLAIN with three finite numbers.
    """

    __slots__ = ("row", "values", "_rows", "count", "status", "finite3", "_status",
                 "_count", "_k")

    def __init__(self, ids, bodies, each, spans=None):
        if spans is None:
            buf = np.frombuffer("".join(bodies).encode("latin-1"), np.uint8)
            ends = np.cumsum(np.fromiter(map(len, bodies), np.int64, len(bodies)))
            starts = np.concatenate([np.zeros(1, np.int64), ends[:-1]])
        else:  # (the bodies where they lie in the file's bytes)
            buf, starts, ends = spans
        values, count, status, negative = read_coordinates(buf, starts, ends)
        if negative.any():
            values[negative] = -0.0
        for r in np.flatnonzero(status == BY_FLOAT).tolist():  # float's turn
            x = each(ids[r])
            if x is None:
                status[r] = OTHER
            elif len(x) <= 3:
                values[r, :len(x)] = x
                count[r], status[r] = len(x), PLAIN
        self.values, self._count, self._status = values, count, status
        plain = (status == PLAIN).all() and count.size and (count == count[0]).all()
        self._k = int(count[0]) if plain else None  # every row PLAIN with k numbers
        self.finite3 = ((status == PLAIN) & (count == 3)
                        & np.isfinite(values).all(axis=1)).tolist()
        self._rows = None  # (rows, made at the first numbers())
        self.count = count.tolist()
        self.status = status.tolist()
        self.row = dict(zip(ids, range(len(ids))))

    def numbers(self, r):
        """Row ``r``'s numbers (a tuple of floats), or the status OTHER / BY_FLOAT."""
        s = self.status[r]
        if s != PLAIN:
            return s
        return tuple(self.rows[r][:self.count[r]])

    @property
    def rows(self) -> list:
        """The rows' numbers as lists (:attr:`values`)."""
        if self._rows is None:
            self._rows = self.values.tolist()
        return self._rows

    def coordinates(self, rows, k: int, each):
        """The numbers (n, k) of ``rows``, or None when any is OTHER or has another
        count than ``k``; ``each(j)`` reads the ``j``-th of ``rows`` when it is left
        to ``float`` (its numbers or None)."""
        if k == self._k:
            return self.values[rows] if k == 3 else np.ascontiguousarray(self.values[rows, :k])
        st = self._status[rows]
        if (st == OTHER).any():
            return None
        plain = st == PLAIN
        if (self._count[rows][plain] != k).any():
            return None
        out = np.ascontiguousarray(self.values[rows, :k])
        if not plain.all():
            for j in np.flatnonzero(~plain).tolist():
                x = each(j)
                if x is None or len(x) != k:
                    return None
                out[j] = x
        return out
