"""Sweep and prune on world AABBs with incremental re-sorting (Papers 4 and 5).

State per axis ``a`` (3 axes): ``ep_id[a]`` (2n,) int64 endpoint codes
``2 * body + is_max`` in sorted order, ``ep_val[a]`` (2n,) their coordinates.
Between frames the boxes move little, so the previous order is nearly sorted and
an insertion sort (keys ``(value, is_max)``: at equal values a box's start comes
before another's end, so touching boxes overlap, as closed intervals should) costs
O(n + swaps).  All three axes are kept sorted; the sweep runs along the axis with
the largest spread of box centres and tests the other two axes for each pair of
boxes active together (Paper 5's "crude stage").

Pair filter (Paper 4's assembly awareness): bodies of one group are never paired,
and a pair of two static bodies is skipped.
"""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit


@jit
def world_aabbs(C, H, R, t, lo, hi):
    """World AABBs of local boxes (centre ``C`` (n, 3), half sizes ``H`` (n, 3)) under
    rotations ``R`` (n, 3, 3) and translations ``t`` (n, 3): centre ``R C + t``,
    half sizes ``|R| H`` (Paper 4's cheap box update).  Writes ``lo``, ``hi``."""
    for i in range(C.shape[0]):
        for r in range(3):
            c = R[i, r, 0] * C[i, 0] + R[i, r, 1] * C[i, 1] + R[i, r, 2] * C[i, 2] + t[i, r]
            h = abs(R[i, r, 0]) * H[i, 0] + abs(R[i, r, 1]) * H[i, 1] + \
                abs(R[i, r, 2]) * H[i, 2]
            h = h * (1.0 + 1e-12)
            lo[i, r] = c - h
            hi[i, r] = c + h


@jit
def init_endpoints(lo, hi, ep_id, ep_val):
    """Fresh endpoint arrays (3, 2n), sorted."""
    n = lo.shape[0]
    for a in range(3):
        for i in range(n):
            ep_id[a, 2 * i] = 2 * i
            ep_id[a, 2 * i + 1] = 2 * i + 1
        refresh_values(lo, hi, ep_id[a], ep_val[a], a)
    return resort(lo, hi, ep_id, ep_val)


@jit
def refresh_values(lo, hi, ids, vals, a):
    for k in range(ids.shape[0]):
        e = ids[k]
        vals[k] = hi[e >> 1, a] if e & 1 else lo[e >> 1, a]


@jit
def resort(lo, hi, ep_id, ep_val):
    """Refresh the endpoint values from the boxes and insertion-sort each axis from
    the previous order.  Returns the number of swaps (the work of coherence)."""
    swaps = 0
    for a in range(3):
        ids = ep_id[a]
        vals = ep_val[a]
        refresh_values(lo, hi, ids, vals, a)
        for k in range(1, ids.shape[0]):
            e = ids[k]
            v = vals[k]
            m = e & 1
            j = k - 1
            while j >= 0 and (vals[j] > v or (vals[j] == v and (ids[j] & 1) > m)):
                ids[j + 1] = ids[j]
                vals[j + 1] = vals[j]
                j -= 1
                swaps += 1
            ids[j + 1] = e
            vals[j + 1] = v
    return swaps


@jit
def sweep_pairs(lo, hi, ep_id, axis, group, static, margin, out):
    """Candidate pairs: boxes (grown by ``margin``) overlapping on all 3 axes, of
    different groups, not both static.  Sweeps ``ep_id[axis]``; writes up to
    ``len(out)`` pairs ``(i, j)``, i < j, and returns the total count (call again
    with a larger buffer if it exceeds it).  With ``margin > 0`` the sweep order
    is still valid: every box grows by the same amount on both sides, so it is
    done on the unchanged order with grown values compared explicitly."""
    n = lo.shape[0]
    active = np.empty(n, dtype=np.int64)
    pos = np.empty(n, dtype=np.int64)
    nact = 0
    cap = out.shape[0]
    cnt = 0
    a1 = (axis + 1) % 3
    a2 = (axis + 2) % 3
    ids = ep_id[axis]
    if margin > 0.0:
        # grown boxes change the interleaving on the sweep axis: sweep by
        # starts sorted as they are (lo - margin keeps the order of lo) and expire
        # ends lazily by value.
        order = np.empty(n, dtype=np.int64)
        k = 0
        for q in range(ids.shape[0]):
            if ids[q] & 1 == 0:
                order[k] = ids[q] >> 1
                k += 1
        for q in range(n):
            i = order[q]
            start = lo[i, axis] - margin
            # drop active boxes ending before this start
            r = 0
            while r < nact:
                j = active[r]
                if hi[j, axis] + margin < start:
                    nact -= 1
                    active[r] = active[nact]
                else:
                    r += 1
            for r in range(nact):
                j = active[r]
                if group[i] == group[j] or (static[i] and static[j]):
                    continue
                if lo[i, a1] - margin > hi[j, a1] + margin or \
                        lo[j, a1] - margin > hi[i, a1] + margin:
                    continue
                if lo[i, a2] - margin > hi[j, a2] + margin or \
                        lo[j, a2] - margin > hi[i, a2] + margin:
                    continue
                if cnt < cap:
                    out[cnt, 0] = min(i, j)
                    out[cnt, 1] = max(i, j)
                cnt += 1
            active[nact] = i
            nact += 1
        return cnt
    # active boxes with their other-axis bounds in contiguous rows (cache friendly)
    box = np.empty((n, 4))
    for q in range(ids.shape[0]):
        e = ids[q]
        i = e >> 1
        if e & 1:
            r = pos[i]
            nact -= 1
            last = active[nact]
            active[r] = last
            box[r] = box[nact]
            pos[last] = r
            continue
        l1, h1, l2, h2 = lo[i, a1], hi[i, a1], lo[i, a2], hi[i, a2]
        gi = group[i]
        si = static[i]
        for r in range(nact):
            if l1 > box[r, 1] or box[r, 0] > h1 or l2 > box[r, 3] or box[r, 2] > h2:
                continue
            j = active[r]
            if gi == group[j] or (si and static[j]):
                continue
            if cnt < cap:
                out[cnt, 0] = min(i, j)
                out[cnt, 1] = max(i, j)
            cnt += 1
        active[nact] = i
        box[nact, 0] = l1
        box[nact, 1] = h1
        box[nact, 2] = l2
        box[nact, 3] = h2
        pos[i] = nact
        nact += 1
    return cnt
