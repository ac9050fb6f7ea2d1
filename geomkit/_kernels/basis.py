"""B-spline basis functions (The NURBS Book, Algorithms A2.1, A2.2, A2.3)."""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit, jit_inline


@jit
def find_span(n, p, u, U):
    """Knot span index of ``u`` (A2.1).

    ``n`` is the index of the last control point (count - 1), ``p`` the degree, ``U``
    the clamped knot vector.  Returns ``i`` with ``U[i] <= u < U[i+1]`` and
    ``p <= i <= n``; the right end of the domain belongs to the last non-empty span.
    """
    if u >= U[n + 1]:
        return n
    if u <= U[p]:
        return p
    low = p
    high = n + 1
    mid = (low + high) // 2
    while u < U[mid] or u >= U[mid + 1]:
        if u < U[mid]:
            high = mid
        else:
            low = mid
        mid = (low + high) // 2
    return mid


@jit
def basis_funs(i, u, p, U, N, left, right):
    """Non-zero basis functions ``N[0..p]`` at ``u`` in span ``i`` (A2.2).

    ``N``, ``left`` and ``right`` are caller-provided scratch arrays of length p+1.
    """
    N[0] = 1.0
    for j in range(1, p + 1):
        left[j] = u - U[i + 1 - j]
        right[j] = U[i + j] - u
        saved = 0.0
        for r in range(j):
            temp = N[r] / (right[r + 1] + left[j - r])
            N[r] = saved + right[r + 1] * temp
            saved = left[j - r] * temp
        N[j] = saved


@jit
def basis_d1(i, u, p, U, D, left, right):
    """Non-zero basis functions ``D[0, 0..p]`` at ``u`` in span ``i`` and their first
    derivatives ``D[1, 0..p]`` (``p >= 1``): A2.2, whose last round divides the degree
    ``p - 1`` functions by the knot differences that A2.3's first derivatives take
    (``N'_r = p (T_{r-1} - T_r)``, ``T_r`` that quotient, ``T_{-1} = T_p = 0``), at the
    cost of A2.2 alone.  ``left``, ``right``: scratch of length ``p + 1``."""
    D[0, 0] = 1.0
    prev = 0.0
    for j in range(1, p + 1):
        left[j] = u - U[i + 1 - j]
        right[j] = U[i + j] - u
        saved = 0.0
        for r in range(j):
            temp = D[0, r] / (right[r + 1] + left[j - r])
            if j == p:
                D[1, r] = p * (prev - temp)
                prev = temp
            D[0, r] = saved + right[r + 1] * temp
            saved = left[j - r] * temp
        D[0, j] = saved
    D[1, p] = p * prev


@jit
def ders_scratch(p):
    """Scratch arrays for :func:`ders_basis_funs`: (ndu, left, right, a)."""
    return (np.empty((p + 1, p + 1)), np.empty(p + 1), np.empty(p + 1),
            np.empty((2, p + 1)))


@jit
def ders_basis_funs(i, u, p, n, U, ders, ndu, left, right, a):
    """Basis functions and their derivatives up to order ``n`` (A2.3).

    Fills ``ders[k, j]`` = k-th derivative of N_{i-p+j, p} at ``u`` for
    ``k = 0..n`` (rows above ``p`` are zero).  ``ders`` has shape (n+1, p+1);
    ``ndu`` (p+1, p+1), ``left``/``right`` (p+1,), ``a`` (2, p+1) are scratch
    (see :func:`ders_scratch`).
    """
    ndu[0, 0] = 1.0
    for j in range(1, p + 1):
        left[j] = u - U[i + 1 - j]
        right[j] = U[i + j] - u
        saved = 0.0
        for r in range(j):
            ndu[j, r] = right[r + 1] + left[j - r]
            temp = ndu[r, j - 1] / ndu[j, r]
            ndu[r, j] = saved + right[r + 1] * temp
            saved = left[j - r] * temp
        ndu[j, j] = saved
    for j in range(p + 1):
        ders[0, j] = ndu[j, p]
    for k in range(1, n + 1):
        for j in range(p + 1):
            ders[k, j] = 0.0
    top = n if n < p else p
    for r in range(p + 1):
        s1 = 0
        s2 = 1
        a[0, 0] = 1.0
        for k in range(1, top + 1):
            d = 0.0
            rk = r - k
            pk = p - k
            if r >= k:
                a[s2, 0] = a[s1, 0] / ndu[pk + 1, rk]
                d = a[s2, 0] * ndu[rk, pk]
            j1 = 1 if rk >= -1 else -rk
            j2 = k - 1 if r - 1 <= pk else p - r
            for j in range(j1, j2 + 1):
                a[s2, j] = (a[s1, j] - a[s1, j - 1]) / ndu[pk + 1, rk + j]
                d += a[s2, j] * ndu[rk + j, pk]
            if r <= pk:
                a[s2, k] = -a[s1, k - 1] / ndu[pk + 1, r]
                d += a[s2, k] * ndu[r, pk]
            ders[k, r] = d
            s1, s2 = s2, s1
    r = p
    for k in range(1, top + 1):
        for j in range(p + 1):
            ders[k, j] *= r
        r *= p - k


# The same functions inlined at numba's IR level into the kernel that calls them: a
# call with array arguments pays their reference counting (~20 ns), as much as the
# basis itself at low degree; for kernels that evaluate one point at a time in long
# loops (the readers' edge samples).
find_span_inline = jit_inline(find_span.py_func)
basis_funs_inline = jit_inline(basis_funs.py_func)
ders_basis_funs_inline = jit_inline(ders_basis_funs.py_func)
basis_d1_inline = jit_inline(basis_d1.py_func)
