"""The records of a STEP file's DATA section from its bytes (ISO 10303-21): each
``#id = NAME(...)``'s id, where its body and its entity name lie, and a code per
distinct name, for :meth:`geomkit.cad.p21.P21._cut` (which finds where the records
end: at each ``;`` after an even number of quotes).

Whitespace is `` \t\n\v\f\r``; a record that is not ``#digits = ...``, or that
holds where it is stripped a byte Python's ``str.strip`` also takes for whitespace in
Latin-1 (``\x1c``-``\x1f``, ``\x85``, ``\xa0``), is left to the caller's
record-by-record route (status 1), which reads the file the same way or names the
fault.
"""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit

# columns of the records' table
ID, BODY0, BODY1, NAME0, NAME1, CODE, LOWER = range(7)


@jit
def _is_space(c):
    return c == 32 or 9 <= c <= 13


@jit
def _is_odd(c):
    """Whether Python's ``str.strip`` takes byte ``c`` for whitespace in Latin-1 when
    :func:`_is_space` does not."""
    return 28 <= c <= 31 or c == 133 or c == 160


@jit
def _code(b, a, e, table, firsts, rec, recs, nfirst):
    """The code of the name ``b[a:e]`` in the open-addressing ``table`` (slots hold a
    code + 1; ``firsts[code]`` the first record of that name, whose span is in
    ``recs``), added as a new code when absent."""
    h = np.uint64(14695981039346656037)
    for j in range(a, e):
        h = (h ^ np.uint64(b[j])) * np.uint64(1099511628211)
    mask = table.size - 1
    s = np.int64(h & np.uint64(mask))
    while True:
        c = table[s] - 1
        if c < 0:
            table[s] = nfirst + 1
            firsts[nfirst] = rec
            return nfirst
        r = firsts[c]
        a2, e2 = recs[r, NAME0], recs[r, NAME1]
        if e2 - a2 == e - a:
            same = True
            for j in range(e - a):
                if b[a + j] != b[a2 + j]:
                    same = False
                    break
            if same:
                return c
        s = (s + 1) & mask


@jit
def find_upper(b, pat, start):
    """The first position from ``start`` where ``b`` upper-cased (ASCII letters only)
    reads ``pat`` (upper-case ASCII), or -1."""
    m = pat.size
    p0 = pat[0]
    l0 = p0 + 32 if 65 <= p0 <= 90 else p0
    for i in range(start, b.size - m + 1):
        c = b[i]
        if c != p0 and c != l0:
            continue
        same = True
        for t in range(1, m):
            c = b[i + t]
            q = pat[t]
            if c != q and not (65 <= q <= 90 and c == q + 32):
                same = False
                break
        if same:
            return i
    return -1


@jit
def cut_records(b, ends):
    """``(status, recs, firsts, n, m)`` of the records ``b[ends[k] + 1:ends[k + 1]]``
    (``b`` uint8; ``ends``: the section's start - 1, each record's ``;`` and the
    section's end): ``recs[:n]`` (n, 7) int64 per record its id, its body's span
    (stripped), its name's span (stripped, empty for a complex record), the name's
    code and whether the name has bytes other than ``A-Z 0-9 _ -`` (1: upper-case it),
    spans in ``b``; ``firsts`` the first record of each of the ``m`` codes.  Status 0,
    else 1 (see the module: nothing is returned)."""
    n = ends.size
    recs = np.empty((n, 7), np.int64)
    firsts = np.empty(n, np.int64)
    size = 64
    while size < 2 * n:
        size *= 2
    table = np.zeros(size, np.int64)
    k = 0
    nfirst = 0
    for r in range(1, n):
        a, e = ends[r - 1] + 1, ends[r]
        while a < e and _is_space(b[a]):
            a += 1
        while e > a and _is_space(b[e - 1]):
            e -= 1
        if a == e:
            continue
        if _is_odd(b[a]) or _is_odd(b[e - 1]):
            return 1, recs, firsts, 0, 0
        if b[a] != 35:  # '#'
            return 1, recs, firsts, 0, 0
        q = a + 1
        while q < e and b[q] != 61:  # '='
            q += 1
        if q == e:
            return 1, recs, firsts, 0, 0
        d0, d1 = a + 1, q
        while d0 < d1 and _is_space(b[d0]):
            d0 += 1
        while d1 > d0 and _is_space(b[d1 - 1]):
            d1 -= 1
        if d1 == d0 or d1 - d0 > 18:
            return 1, recs, firsts, 0, 0
        ident = 0
        for t in range(d0, d1):
            c = b[t]
            if c < 48 or c > 57:
                return 1, recs, firsts, 0, 0
            ident = ident * 10 + (c - 48)
        s0 = q + 1
        while s0 < e and _is_space(b[s0]):
            s0 += 1
        if s0 < e and _is_odd(b[s0]):
            return 1, recs, firsts, 0, 0
        p = s0
        while p < e and b[p] != 40:  # '('
            p += 1
        n0 = n1 = s0
        if s0 < p < e:
            n1 = p
            while _is_space(b[n1 - 1]):
                n1 -= 1
            if _is_odd(b[n1 - 1]):
                return 1, recs, firsts, 0, 0
        lower = 0
        for t in range(n0, n1):
            c = b[t]
            if not (65 <= c <= 90 or 48 <= c <= 57 or c == 95 or c == 45):
                lower = 1
        recs[k, ID] = ident
        recs[k, BODY0] = s0
        recs[k, BODY1] = e
        recs[k, NAME0] = n0
        recs[k, NAME1] = n1
        recs[k, LOWER] = lower
        recs[k, CODE] = _code(b, n0, n1, table, firsts, k, recs, nfirst)
        if recs[k, CODE] == nfirst:
            nfirst += 1
        k += 1
    return 0, recs, firsts, k, nfirst
