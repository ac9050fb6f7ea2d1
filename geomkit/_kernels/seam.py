"""Where a closed face's seam goes: the angle about a surface of revolution's axis at
which the reader cuts the loops that go around it (:mod:`geomkit.cad.stepseam`).

:func:`seam_margins` scores the candidate angles against every loop;
:func:`level_crossing` finds where an edge's sampled angles meet the chosen one and
:func:`seam_crossing` brackets that crossing on the edge to 1e-17 of its range.
"""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.policy import jit_exact, jit_plain as jit
from .pcurve_map import TWO_PI, local_at


@jit
def _crossings(lo, hi, c):
    """How many angles ``c + 2 pi k`` lie in ``[lo, hi]``."""
    return math.floor((hi - c) / TWO_PI) - math.ceil((lo - c) / TWO_PI) + 1


@jit
def seam_margins(paths, starts, spans, cand):
    """Margins of the candidate seam angles ``cand`` (:func:`geomkit.cad.stepseam.
    cut_at_seam`): -1 where a loop around the axis (``paths``, the unwrapped angles of
    all such loops one after another, loop ``k`` from ``starts[k]`` to
    ``starts[k + 1]``) is not crossed exactly once or the angle lies in a span
    ``spans[i] = (lo, hi)`` of another loop; else the distance to the nearest span
    (at most pi).

    Candidates evenly spaced around the turn (as the reader's are) are counted from
    each path step's few neighbours: a step shorter than the turn crosses only the
    candidates within its angles, found by their index (two more each side), each
    counted by the same formula as the others."""
    m = cand.shape[0]
    margin = np.full(m, math.pi)
    step = (cand[m - 1] - cand[0]) / (m - 1) if m > 1 else TWO_PI
    even = m > 1 and abs(m * step - TWO_PI) <= 1e-9
    for j in range(m):
        even = even and abs(cand[j] - (cand[0] + j * step)) <= 1e-3 * step
    counts = np.zeros(m)
    for k in range(starts.shape[0] - 1):
        counts[:] = 0.0
        for i in range(starts[k], starts[k + 1] - 1):
            lo = min(paths[i], paths[i + 1])
            hi = max(paths[i], paths[i + 1])
            if even and hi - lo < TWO_PI - 8 * step:
                j0 = math.floor((lo - cand[0]) / step) - 2
                for jj in range(j0, j0 + int((hi - lo) / step) + 6):
                    j = jj % m
                    n = _crossings(lo, hi, cand[j])
                    if n > 0:
                        counts[j] += n
            else:  # (a NaN angle or a long step: every candidate)
                for j in range(m):
                    n = _crossings(lo, hi, cand[j])
                    if n > 0:
                        counts[j] += n
        for j in range(m):
            if counts[j] != 1:
                margin[j] = -1.0
    for j in range(m):
        if margin[j] < 0:
            continue
        c = cand[j]
        for i in range(spans.shape[0]):
            w = spans[i, 1] - spans[i, 0]
            d = (c - spans[i, 0]) % TWO_PI
            if d <= w:
                margin[j] = -1.0
                break
            margin[j] = min(margin[j], min(d - w, TWO_PI - d))
    return margin


@jit_exact
def level_crossing(b, target):
    """Where the unwrapped angles ``b`` (n,) meet ``target`` (mod 2 pi): ``(1, j,
    0.0)`` when sample ``j`` (the first) is within 1e-12 x 2 pi of a level ``target +
    2 pi m``; else ``(2, j, level)`` for the first pair of samples ``j, j + 1`` with a
    level strictly between them; ``(0, -1, 0.0)`` when neither (a NaN angle meets
    nothing).  Each value as numpy computes it over the whole array (no contraction;
    ``m`` rounded half to even)."""
    n = b.shape[0]
    tiny = 1e-12 * TWO_PI
    for i in range(n):
        lev = target + TWO_PI * np.rint((b[i] - target) / TWO_PI)
        if abs(b[i] - lev) <= tiny:
            return 1, i, 0.0
    for j in range(n - 1):
        x, y = b[j], b[j + 1]
        if x != x or y != y:
            continue
        lo = min(x, y)
        hi = max(x, y)
        level = target + TWO_PI * np.floor((lo - target) / TWO_PI + 1)
        if lo < level and level < hi:
            return 2, j, level
    return 0, -1, 0.0


@jit
def seam_crossing(Pw, p, U, e0, e1, rev, kind, frame, R, r, tan_a, lo, hi, b_lo, level, up):
    """The loop parameter in ``[lo, hi]`` where the edge's angle about the axis crosses
    ``level``, bracketed to 1e-17 by 31 samples a round (each round narrows the bracket
    32 times, at most 12 rounds).  ``b_lo``: the (unwrapped) angle at ``lo``, the
    branch the samples are taken on; ``up``: whether the angle increases across the
    bracket.  Arguments as :func:`fit_edge_pcurve`'s."""
    N = np.empty(p + 1)
    left = np.empty(p + 1)
    right = np.empty(p + 1)
    for _ in range(12):
        if not hi - lo > 1e-17:
            break
        step = (hi - lo) / 32.0
        nlo, nhi = lo, hi
        for j in range(1, 32):
            sm = lo + j * step
            te = e0 + ((1.0 - sm) if rev else sm) * (e1 - e0)
            _, b = local_at(te, Pw, p, U, kind, frame, R, r, tan_a, N, left, right)
            b = b_lo + ((b - b_lo + math.pi) % TWO_PI - math.pi)
            if (b < level) != up:  # past the level: the bracket ends here
                nhi = sm
                break
            nlo = sm
        lo, hi = nlo, nhi
    return 0.5 * (lo + hi)
