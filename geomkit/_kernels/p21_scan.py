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


# Python's str.isspace over Latin-1 (what float() and the regex \s skip)
_WS = np.zeros(256, np.bool_)
_WS[[9, 10, 11, 12, 13, 28, 29, 30, 31, 32, 133, 160]] = True
_FWS = _WS.copy()
_FWS[28:32] = False
"""What float() strips around a number (not the ASCII separators 0x1c-0x1f)."""
_P10 = np.array([10.0 ** e for e in range(23)])
"""The powers of ten a double holds exactly."""
_W_MAX = 2 ** 53


@jit
def _number(b, a, e):
    """``(status, value)`` of the text ``b[a:e]`` as ``float`` reads it: 0 when read
    exactly here (a sign, a significand of at most 2**53 once its trailing zeros are
    taken into the exponent, a power of ten up to 22: one correctly rounded product or
    quotient, Clinger's fast path), 3 for ``-0`` (the value 0.0, the caller sets the
    sign), 2 otherwise (for ``float`` to read or reject)."""
    while a < e and _FWS[b[a]]:
        a += 1
    while e > a and _FWS[b[e - 1]]:
        e -= 1
    neg = False
    if a < e and (b[a] == 43 or b[a] == 45):
        neg = b[a] == 45
        a += 1
    w = 0
    zeros = 0  # zeros read but not yet taken into w (trailing ones stay out)
    digits = 0
    frac = 0
    point = False
    while a < e:
        c = b[a]
        if 48 <= c <= 57:
            digits += 1
            if point:
                frac += 1
            if c == 48:
                zeros += 1
            else:
                for _ in range(zeros + 1):
                    if w > (_W_MAX - 9) // 10:
                        return 2, 0.0
                    w *= 10
                w += c - 48
                zeros = 0
        elif c == 46 and not point:
            point = True
        else:
            break
        a += 1
    if digits == 0:
        return 2, 0.0
    ex = 0
    if a < e and (b[a] == 69 or b[a] == 101):
        a += 1
        eneg = False
        if a < e and (b[a] == 43 or b[a] == 45):
            eneg = b[a] == 45
            a += 1
        if a == e:
            return 2, 0.0
        while a < e:
            c = b[a]
            if not 48 <= c <= 57 or ex > 1000:
                return 2, 0.0
            ex = ex * 10 + (c - 48)
            a += 1
        if eneg:
            ex = -ex
    if a != e:
        return 2, 0.0
    if w == 0:
        return (3 if neg else 0), 0.0
    p = ex - frac + zeros
    if p > 22 or p < -22:
        return 2, 0.0
    v = float(w) * _P10[p] if p >= 0 else float(w) / _P10[-p]
    return 0, -v if neg else v


@jit
def read_coordinates(b, starts, ends):
    """``(values, counts, status, negative)`` of the records ``b[starts[r]:ends[r]]``
    (in a file's bytes, or one after another), each matched as
    ``NAME('label', (numbers))`` (the
    readers' plain points and directions, :data:`geomkit.cad.p21._COORDS`): status 0
    with ``counts[r]`` (at most 3) values read exactly (:func:`_number`), 1 when the
    record is not of that form, 2 when ``float`` is to read its numbers (or
    another count); ``negative`` marks the values that are ``-0.0`` (stored as 0.0)."""
    n = ends.size
    values = np.zeros((n, 3))
    counts = np.zeros(n, np.int64)
    status = np.zeros(n, np.int8)
    negative = np.zeros((n, 3), np.bool_)
    for r in range(n):
        a = starts[r]
        e = ends[r]
        i = a
        while i < e and (65 <= b[i] <= 90 or 97 <= b[i] <= 122 or b[i] == 95):
            i += 1
        ok = i > a
        while ok and i < e and _WS[b[i]]:
            i += 1
        ok = ok and i < e and b[i] == 40  # '('
        i += 1
        while ok and i < e and _WS[b[i]]:
            i += 1
        ok = ok and i < e and b[i] == 39  # the label's quote
        i += 1
        while ok and i < e and b[i] != 39:
            i += 1
        ok = ok and i < e
        i += 1
        while ok and i < e and _WS[b[i]]:
            i += 1
        ok = ok and i < e and b[i] == 44  # ','
        i += 1
        while ok and i < e and _WS[b[i]]:
            i += 1
        ok = ok and i < e and b[i] == 40
        i += 1
        g0 = i
        while ok and i < e:
            c = b[i]
            if not (48 <= c <= 57 or c == 43 or c == 45 or c == 46 or c == 44
                    or c == 69 or c == 101 or c == 68 or c == 100 or _WS[c]):
                break
            i += 1
        g1 = i
        ok = ok and i < e and b[i] == 41  # ')'
        i += 1
        while ok and i < e and _WS[b[i]]:
            i += 1
        ok = ok and i < e and b[i] == 41
        i += 1
        while ok and i < e and _WS[b[i]]:
            i += 1
        if not ok or i != e:
            status[r] = 1
            continue
        k = 0
        s = g0
        for j in range(g0, g1 + 1):
            if j < g1 and b[j] != 44:
                continue
            if k == 3:
                status[r] = 2
                break
            st, v = _number(b, s, j)
            if st == 3:
                negative[r, k] = True
            elif st != 0:
                status[r] = 2
                break
            values[r, k] = v
            k += 1
            s = j + 1
        counts[r] = k
    return values, counts, status, negative
