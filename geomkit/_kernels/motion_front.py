"""Frame-coherence kernels of the continuous collision queries: a collision traversal
restarted from a cached front of node pairs, and the front moved up where siblings
separate (split out of :mod:`geomkit._kernels.motion`)."""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit_plain as jit
from .bvh_query import STACK, _move, _node_sep, split_a
from .triangles import _intersect_point


# ------------------------------------------------------------------ frame coherence
@jit
def collide_front(kind, childA, rngA, CA, RA, EA, KA, TA, orderA,
                  childB, rngB, CB, RB, EB, KB, TB, orderB,
                  Rr, tr, MA, mA, MB, mB, order, front, nfront, out_front, out_sep,
                  out_pairs):
    """:func:`collide_trees` restarted from a cached traversal front (Paper 4).

    ``front[:nfront]`` are node pairs that together cover every leaf pair (the
    root alone at the first frame).  Each is tested; a separated one stays in the
    front, an overlapping one is descended as usual and the pairs where that
    descent stops (separated pairs and leaf pairs) join the new front.  Writes the
    new front to ``out_front`` with ``out_sep`` (separated this frame) and
    intersecting triangle pairs to ``out_pairs``.  Returns ``(n_pairs, n_front,
    bv_tests)``; a count above its buffer means "call again with more room".
    """
    st = np.empty((STACK, 2), dtype=np.int64)
    Rab = np.empty((3, 3))
    T = np.empty(3)
    scr = np.empty((2, 3, 3))
    hit = np.empty(3)
    ta = np.empty((3, 3))
    tb = np.empty((3, 3))
    capf = out_front.shape[0]
    capp = out_pairs.shape[0]
    npairs = 0
    nf = 0
    tests = 0
    for f in range(nfront):
        st[0, 0] = front[f, 0]
        st[0, 1] = front[f, 1]
        top = 1
        while top > 0:
            top -= 1
            i = st[top, 0]
            j = st[top, 1]
            tests += 1
            if _node_sep(kind, i, j, CA, RA, EA, KA, CB, RB, EB, KB, Rr, tr, order, True,
                         Rab, T, scr) > 0.0:
                if nf < capf:
                    out_front[nf, 0] = i
                    out_front[nf, 1] = j
                    out_sep[nf] = True
                nf += 1
                continue
            la = childA[i, 0] < 0
            lb = childB[j, 0] < 0
            if la and lb:
                if nf < capf:
                    out_front[nf, 0] = i
                    out_front[nf, 1] = j
                    out_sep[nf] = False
                nf += 1
                for ra in range(rngA[i, 0], rngA[i, 1]):
                    _move(TA, ra, MA, mA, ta)
                    for rb in range(rngB[j, 0], rngB[j, 1]):
                        _move(TB, rb, MB, mB, tb)
                        if _intersect_point(ta, tb, hit):
                            if npairs < capp:
                                out_pairs[npairs, 0] = orderA[ra]
                                out_pairs[npairs, 1] = orderB[rb]
                            npairs += 1
                continue
            if split_a(kind, childA, childB, EA, KA, EB, KB, i, j):
                st[top, 0] = childA[i, 1]
                st[top, 1] = j
                st[top + 1, 0] = childA[i, 0]
                st[top + 1, 1] = j
            else:
                st[top, 0] = i
                st[top, 1] = childB[j, 1]
                st[top + 1, 0] = i
                st[top + 1, 1] = childB[j, 0]
            top += 2
    return npairs, nf, tests


@jit
def collapse_front(kind, childA, parentA, EA, KA, childB, parentB, EB, KB, front, sep, n,
                   out):
    """Move the front up where siblings separate (Paper 4): two separated entries
    that are exactly the two children of a node pair under the traversal's split
    rule, and that both choose that pair, are replaced by it.  Returns the new
    front size (written to ``out``); the leaf pairs covered are unchanged (the
    front stays a partition of all leaf pairs)."""
    nB = childB.shape[0]
    keys = np.empty(n, dtype=np.int64)
    for k in range(n):
        keys[k] = front[k, 0] * nB + front[k, 1] if sep[k] else -1
    perm = np.argsort(keys)
    skeys = keys[perm]
    # candidate parent of each separated entry: (parent key, sibling index)
    cand = np.full(n, -1, dtype=np.int64)
    sib = np.full(n, -1, dtype=np.int64)
    for k in range(n):
        if not sep[k]:
            continue
        i = front[k, 0]
        j = front[k, 1]
        p = parentA[i]
        if p >= 0 and split_a(kind, childA, childB, EA, KA, EB, KB, p, j):
            s = childA[p, 1] if childA[p, 0] == i else childA[p, 0]
            key = s * nB + j
            q = np.searchsorted(skeys, key)
            if q < n and skeys[q] == key:
                cand[k] = p * nB + j
                sib[k] = perm[q]
                continue
        p = parentB[j]
        if p >= 0 and not split_a(kind, childA, childB, EA, KA, EB, KB, i, p):
            s = childB[p, 1] if childB[p, 0] == j else childB[p, 0]
            key = i * nB + s
            q = np.searchsorted(skeys, key)
            if q < n and skeys[q] == key:
                cand[k] = i * nB + p
                sib[k] = perm[q]
    no = 0
    for k in range(n):
        o = sib[k]
        if o >= 0 and cand[o] == cand[k]:
            if k < o:
                out[no, 0] = cand[k] // nB
                out[no, 1] = cand[k] % nB
                no += 1
            continue
        out[no, 0] = front[k, 0]
        out[no, 1] = front[k, 1]
        no += 1
    return no
