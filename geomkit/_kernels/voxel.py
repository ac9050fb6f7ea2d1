"""Voxel grid kernels (Paper 1, steps 2–5): binning, best-first and shell searches.

Layout shared by every kernel:

* level 0 is the voxel grid: ``origin`` (3,), voxel size ``h``, ``dims`` (3,); voxel
  ``(i, j, k)`` has linear index ``(i * ny + j) * nz + k`` and covers
  ``origin + h * [i, i+1] x [j, j+1] x [k, k+1]``;
* CSR bins: ``start`` (nvox + 1,) int64 into ``tris`` (int32 triangle ids) and
  ``flags`` (int8, :data:`CROSSED` or :data:`ENCLOSED`);
* a pyramid of occupancy for the best-first search: level ``L`` has cells of
  ``2**L`` voxels per side, dims ``lvl_dims[L]``, occupancy bytes at
  ``occ[lvl_off[L]:]``; a cell is occupied when any voxel below it holds a triangle.

Every search returns exact nearest distances: a cell is discarded only when the
distance from the query to its box (a guaranteed lower bound for every triangle that
touches the cell) exceeds the best distance found so far.
"""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit, jit_inline, prun
from .triangles import point_triangle_closest

CROSSED = 1
"""The triangle crosses the voxel (it also reaches outside it)."""
ENCLOSED = 2
"""The triangle lies entirely inside the voxel."""

CHUNK = 256
# non-literal flags: bin_counts and bin_fill share one compiled _bin_triangle
_COUNT = np.bool_(False)
_WRITE = np.bool_(True)
_ZERO = np.int64(0)


# ---------------------------------------------------------------- triangle / box test
@jit
def _axis_test(ax, ay, az, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, hx, hy, hz):
    """True when the axis separates the triangle (relative to the box centre) and box."""
    p0 = ax * v0x + ay * v0y + az * v0z
    p1 = ax * v1x + ay * v1y + az * v1z
    p2 = ax * v2x + ay * v2y + az * v2z
    r = hx * abs(ax) + hy * abs(ay) + hz * abs(az)
    lo = min(p0, min(p1, p2))
    hi = max(p0, max(p1, p2))
    return lo > r or hi < -r


@jit
def tri_box_overlap(cx, cy, cz, hx, hy, hz, V, a, b, c):
    """Exact triangle/box overlap by the 13 separating axes (Akenine-Möller 2001).

    Box centre ``(cx, cy, cz)``, half sides ``(hx, hy, hz)``; triangle ``V[a], V[b],
    V[c]``.  Touching counts as overlap.
    """
    v0x = V[a, 0] - cx
    v0y = V[a, 1] - cy
    v0z = V[a, 2] - cz
    v1x = V[b, 0] - cx
    v1y = V[b, 1] - cy
    v1z = V[b, 2] - cz
    v2x = V[c, 0] - cx
    v2y = V[c, 1] - cy
    v2z = V[c, 2] - cz
    # the box's face normals: the triangle's bounding box against the box
    if min(v0x, min(v1x, v2x)) > hx or max(v0x, max(v1x, v2x)) < -hx:
        return False
    if min(v0y, min(v1y, v2y)) > hy or max(v0y, max(v1y, v2y)) < -hy:
        return False
    if min(v0z, min(v1z, v2z)) > hz or max(v0z, max(v1z, v2z)) < -hz:
        return False
    e0x, e0y, e0z = v1x - v0x, v1y - v0y, v1z - v0z
    e1x, e1y, e1z = v2x - v1x, v2y - v1y, v2z - v1z
    e2x, e2y, e2z = v0x - v2x, v0y - v2y, v0z - v2z
    # the triangle's plane
    nx = e0y * e1z - e0z * e1y
    ny = e0z * e1x - e0x * e1z
    nz = e0x * e1y - e0y * e1x
    if _axis_test(nx, ny, nz, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, hx, hy, hz):
        return False
    # the nine edge x box-axis crosses (zero axes separate nothing and pass)
    for ex, ey, ez in ((e0x, e0y, e0z), (e1x, e1y, e1z), (e2x, e2y, e2z)):
        if _axis_test(0.0, -ez, ey, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, hx, hy, hz):
            return False
        if _axis_test(ez, 0.0, -ex, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, hx, hy, hz):
            return False
        if _axis_test(-ey, ex, 0.0, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, hx, hy, hz):
            return False
    return True


@jit_inline
def _tri_voxel_range(V, a, b, c, origin, h, dims, pad, out):
    for d in range(3):
        lo = min(V[a, d], min(V[b, d], V[c, d]))
        hi = max(V[a, d], max(V[b, d], V[c, d]))
        i0 = int(math.floor((lo - pad - origin[d]) / h))
        i1 = int(math.floor((hi + pad - origin[d]) / h))
        out[d, 0] = max(0, min(dims[d] - 1, i0))
        out[d, 1] = max(0, min(dims[d] - 1, i1))


@jit
def _bin_triangle(V, F, t, origin, h, dims, rng, write, pos, cell, tri, flag):
    """Count (write=False) or write the voxels of triangle t; returns the count.

    Filters as in Paper 1: the box around the circumscribed sphere (here the tighter
    box of the triangle itself), the sphere/voxel distance (a correct version of the
    paper's corner test), then the exact separating-axis test.  Boxes are inflated by
    a relative 1e-12 so that a triangle on a voxel face is binned on both sides.
    """
    a = F[t, 0]
    b = F[t, 1]
    c = F[t, 2]
    pad = 1e-12 * h
    _tri_voxel_range(V, a, b, c, origin, h, dims, pad, rng)
    # circumsphere (centre, radius) of the triangle
    ax, ay, az = V[a, 0], V[a, 1], V[a, 2]
    ux, uy, uz = V[b, 0] - ax, V[b, 1] - ay, V[b, 2] - az
    wx, wy, wz = V[c, 0] - ax, V[c, 1] - ay, V[c, 2] - az
    nx = uy * wz - uz * wy
    ny = uz * wx - ux * wz
    nz = ux * wy - uy * wx
    nn = nx * nx + ny * ny + nz * nz
    uu = ux * ux + uy * uy + uz * uz
    ww = wx * wx + wy * wy + wz * wz
    if nn > 0.0:
        # centre = a + (|u|^2 (w x n) + |w|^2 (n x u)) / (2 |n|^2)
        sx = (uu * (wy * nz - wz * ny) + ww * (ny * uz - nz * uy)) / (2.0 * nn)
        sy = (uu * (wz * nx - wx * nz) + ww * (nz * ux - nx * uz)) / (2.0 * nn)
        sz = (uu * (wx * ny - wy * nx) + ww * (nx * uy - ny * ux)) / (2.0 * nn)
        R = math.sqrt(sx * sx + sy * sy + sz * sz)
        sx += ax
        sy += ay
        sz += az
    else:  # degenerate: any enclosing sphere does (the triangle's box centre)
        sx = 0.5 * (min(ax, min(V[b, 0], V[c, 0])) + max(ax, max(V[b, 0], V[c, 0])))
        sy = 0.5 * (min(ay, min(V[b, 1], V[c, 1])) + max(ay, max(V[b, 1], V[c, 1])))
        sz = 0.5 * (min(az, min(V[b, 2], V[c, 2])) + max(az, max(V[b, 2], V[c, 2])))
        R = 0.0
        for k in (a, b, c):
            R = max(R, math.sqrt((V[k, 0] - sx) ** 2 + (V[k, 1] - sy) ** 2
                                 + (V[k, 2] - sz) ** 2))
    R = R * (1.0 + 1e-12) + pad
    hh = 0.5 * h + pad
    ny_ = dims[1]
    nz_ = dims[2]
    n = 0
    for i in range(rng[0, 0], rng[0, 1] + 1):
        cx = origin[0] + (i + 0.5) * h
        for j in range(rng[1, 0], rng[1, 1] + 1):
            cy = origin[1] + (j + 0.5) * h
            for k in range(rng[2, 0], rng[2, 1] + 1):
                cz = origin[2] + (k + 0.5) * h
                # sphere / voxel distance
                dx = max(0.0, abs(sx - cx) - hh)
                dy = max(0.0, abs(sy - cy) - hh)
                dz = max(0.0, abs(sz - cz) - hh)
                if dx * dx + dy * dy + dz * dz > R * R:
                    continue
                if not tri_box_overlap(cx, cy, cz, hh, hh, hh, V, a, b, c):
                    continue
                if write:
                    cell[pos + n] = (i * ny_ + j) * nz_ + k
                    tri[pos + n] = t
                    inside = True
                    for v in (a, b, c):
                        if (abs(V[v, 0] - cx) > 0.5 * h or abs(V[v, 1] - cy) > 0.5 * h
                                or abs(V[v, 2] - cz) > 0.5 * h):
                            inside = False
                    flag[pos + n] = ENCLOSED if inside else CROSSED
                n += 1
    return n


@jit
def _bin_counts_range(i0, i1, V, F, origin, h, dims, counts):
    rng = np.empty((3, 2), dtype=np.int64)
    dummy_i = np.empty(0, dtype=np.int64)
    dummy_t = np.empty(0, dtype=np.int32)
    dummy_f = np.empty(0, dtype=np.int8)
    for t in range(i0, i1):
        counts[t] = _bin_triangle(V, F, t, origin, h, dims, rng, _COUNT, _ZERO,
                                  dummy_i, dummy_t, dummy_f)


def bin_counts(V, F, origin, h, dims, counts):
    """Pass 1: number of voxels each triangle touches."""
    prun(_bin_counts_range, F.shape[0], CHUNK, V, F, origin, h, dims, counts)


@jit
def _bin_fill_range(i0, i1, V, F, origin, h, dims, offsets, cell, tri, flag):
    rng = np.empty((3, 2), dtype=np.int64)
    for t in range(i0, i1):
        _bin_triangle(V, F, t, origin, h, dims, rng, _WRITE, offsets[t], cell, tri, flag)


def bin_fill(V, F, origin, h, dims, offsets, cell, tri, flag):
    """Pass 2: write (voxel, triangle, flag) entries at each triangle's offset."""
    prun(_bin_fill_range, F.shape[0], CHUNK, V, F, origin, h, dims, offsets, cell, tri, flag)


# ---------------------------------------------------------------- a small binary heap
@jit_inline
def _heap_push(hk, hv, n, key, val):
    """Push (key, val), growing the arrays when full; returns ``(hk, hv, n + 1)``
    (loops that push often use :func:`_heap_grow` and :func:`_heap_add` instead: see
    the first)."""
    if n == hk.shape[0]:
        hk, hv = _heap_grow(hk, hv, n, n + 1)
    return hk, hv, _heap_add(hk, hv, n, key, val)


@jit_inline
def _heap_pop(hk, hv, n):
    """Remove the root; returns the new size (the caller read hk[0], hv[0] first)."""
    n -= 1
    key = hk[n]
    val = hv[n]
    i = 0
    while True:
        c = 2 * i + 1
        if c >= n:
            break
        if c + 1 < n and hk[c + 1] < hk[c]:
            c += 1
        if hk[c] >= key:
            break
        hk[i] = hk[c]
        hv[i] = hv[c]
        i = c
    if n > 0:
        hk[i] = key
        hv[i] = val
    return n


AXIS_BITS = 19
"""Bits per cell index in a heap value: ``((i << 19 | j) << 19 | k) << 5 | level``.
The level sits in the low :data:`LEVEL_BITS` bits, so every value is a non-negative
int64 (62 bits used) whatever the number of levels."""
LEVEL_BITS = 5
LEVEL_MASK = (1 << LEVEL_BITS) - 1
AXIS_MASK = (1 << AXIS_BITS) - 1
MAX_AXIS = 1 << AXIS_BITS
"""Largest number of voxels along one axis (a pyramid over it has at most 20 levels,
well within :data:`LEVEL_BITS`)."""


@jit_inline
def _encode(lev, i, j, k):
    return (((((i << AXIS_BITS) | j) << AXIS_BITS) | k) << LEVEL_BITS) | lev


@jit_inline
def _level(val):
    return val & LEVEL_MASK


@jit_inline
def _decode(val):
    c = val >> LEVEL_BITS
    return (val & LEVEL_MASK, (c >> (2 * AXIS_BITS)) & AXIS_MASK, (c >> AXIS_BITS) & AXIS_MASK,
            c & AXIS_MASK)


@jit_inline
def _gap2(lev, i, j, k, origin, h, lx, ly, lz, ux, uy, uz):
    """Squared distance between cell (lev, i, j, k) and the box [l, u]."""
    s = h * (1 << lev)
    g = 0.0
    lo = origin[0] + i * s
    d = max(0.0, max(lo - ux, lx - (lo + s)))
    g += d * d
    lo = origin[1] + j * s
    d = max(0.0, max(lo - uy, ly - (lo + s)))
    g += d * d
    lo = origin[2] + k * s
    d = max(0.0, max(lo - uz, lz - (lo + s)))
    return g + d * d


@jit
def _heap_grow(hk, hv, n, need):
    """The heap's arrays with room for at least ``need`` entries (the first ``n``
    copied).  Called only when they are full: the callers' loops reassign their heap
    arrays in that rare branch only (an array variable rebound on every push costs
    two atomic reference-count updates per array)."""
    m = max(need, 2 * hk.shape[0], 16)
    nk = np.empty(m, dtype=hk.dtype)
    nv = np.empty(m, dtype=hv.dtype)
    for r in range(n):
        nk[r] = hk[r]
        nv[r] = hv[r]
    return nk, nv


@jit_inline
def _heap_add(hk, hv, n, key, val):
    """:func:`_heap_push` into arrays with room (``n < hk.shape[0]``); returns the new
    size."""
    i = n
    while i > 0:
        parent = (i - 1) // 2
        if hk[parent] <= key:
            break
        hk[i] = hk[parent]
        hv[i] = hv[parent]
        i = parent
    hk[i] = key
    hv[i] = val
    return n + 1


@jit_inline
def _push_children(val, lvl_dims, lvl_off, occ, origin, h, lx, ly, lz, ux, uy, uz, hk, hv,
                   n, bound2):
    """Push the occupied children of a cell whose squared gap to the box [l, u] is <=
    bound2 (the
    heap needs room for 8 more: :func:`_heap_grow`); returns the new size."""
    lev, i, j, k = _decode(val)
    c = lev - 1
    nx = lvl_dims[c, 0]
    ny = lvl_dims[c, 1]
    nz = lvl_dims[c, 2]
    off = lvl_off[c]
    for a in range(2):
        ci = 2 * i + a
        if ci >= nx:
            continue
        for b in range(2):
            cj = 2 * j + b
            if cj >= ny:
                continue
            for e in range(2):
                ck = 2 * k + e
                if ck >= nz:
                    continue
                if occ[off + (ci * ny + cj) * nz + ck] == 0:
                    continue
                key = _gap2(c, ci, cj, ck, origin, h, lx, ly, lz, ux, uy, uz)
                if key > bound2:
                    continue
                n = _heap_add(hk, hv, n, key, _encode(c, ci, cj, ck))
    return n


@jit_inline
def _top_cells(lvl_dims):
    top = lvl_dims.shape[0] - 1
    return lvl_dims[top, 0] * lvl_dims[top, 1] * lvl_dims[top, 2]


@jit_inline
def _seed_heap(lvl_dims, lvl_off, occ, origin, h, lx, ly, lz, ux, uy, uz, hk, hv):
    """Push the occupied top-level cells with their squared gaps to the box [l, u] (the heap needs room for
    :func:`_top_cells`); returns the size."""
    top = lvl_dims.shape[0] - 1
    n = 0
    off = lvl_off[top]
    for i in range(lvl_dims[top, 0]):
        for j in range(lvl_dims[top, 1]):
            for k in range(lvl_dims[top, 2]):
                if occ[off + (i * lvl_dims[top, 1] + j) * lvl_dims[top, 2] + k]:
                    key = _gap2(top, i, j, k, origin, h, lx, ly, lz, ux, uy, uz)
                    n = _heap_add(hk, hv, n, key, _encode(top, i, j, k))
    return n


# ---------------------------------------------------------------- point queries
@jit
def point_candidates(px, py, pz, V, F, fdev, dmax, origin, h, lvl_dims, lvl_off, occ,
                     start, tris, stamp, qid, hk, hv, cand_t, cand_d, cand_s, cand_w,
                     max_dist):
    """Best-first search for the triangles that can hold the point's nearest surface
    point.

    ``fdev[t]`` bounds the distance between triangle t and the surface piece it
    stands for (both ways), so with d_t the point–triangle distance the surface piece
    lies in ``[d_t - fdev[t], d_t + fdev[t]]``.  Collects every triangle with
    ``d_t - fdev[t] <= UB`` (UB = min over triangles of ``d_t + fdev[t]``), nearest
    first, into ``cand_*``.  Returns ``(count, UB, LB, pops, tested, heap)``
    (``pops`` cells opened, ``tested`` point–triangle distances) with LB a guaranteed
    lower bound of the point's distance to the surfaces.  With ``max_dist`` finite,
    the search stops once every remaining triangle is farther than ``max_dist`` (then
    count may be 0 and LB > max_dist).

    The arrays are not grown for the caller (it borrows them, see
    :mod:`geomkit._kernels.numba_ext.borrow`): ``heap`` > 0 is the heap size the search
    needed beyond ``hk`` (it grew a private copy), and a count above
    ``cand_t.shape[0]`` says the candidates did not fit: none is kept, the caller
    grows the arrays to at least ``count`` and searches again with a new ``qid``
    (:func:`search`).  ``stamp[t] == qid`` marks triangles tested for this query.
    """
    (V, F, fdev, origin, lvl_dims, lvl_off, occ, start, tris, stamp, hk, hv, cand_t,
     cand_d, cand_s, cand_w) = borrow_all((V, F, fdev, origin, lvl_dims, lvl_off, occ,
                                           start, tris, stamp, hk, hv, cand_t, cand_d,
                                           cand_s, cand_w))
    top = _top_cells(lvl_dims) + 8
    grown = 0
    if hk.shape[0] < top:
        hk, hv = _heap_grow(hk, hv, 0, top)
        grown = hk.shape[0]
    n = _seed_heap(lvl_dims, lvl_off, occ, origin, h, px, py, pz, px, py, pz, hk, hv)
    ny0 = lvl_dims[0, 1]
    nz0 = lvl_dims[0, 2]
    UB = np.inf
    count = 0
    cap = cand_t.shape[0]
    LB = np.inf
    pops = 0
    tested = 0
    while n > 0:
        key = math.sqrt(hk[0])
        val = hv[0]
        if key - dmax > UB or key - dmax > max_dist:
            LB = key - dmax
            break
        n = _heap_pop(hk, hv, n)
        pops += 1
        if _level(val) > 0:
            bound = min(UB, max_dist) + dmax
            if n + 8 > hk.shape[0]:
                hk, hv = _heap_grow(hk, hv, n, n + 8)
                grown = hk.shape[0]
            n = _push_children(val, lvl_dims, lvl_off, occ, origin, h, px, py, pz, px, py,
                               pz, hk, hv, n, bound * bound)
            continue
        lev, i0, j0, k0 = _decode(val)
        lin = (i0 * ny0 + j0) * nz0 + k0
        for e in range(start[lin], start[lin + 1]):
            t = tris[e]
            if stamp[t] == qid:
                continue
            stamp[t] = qid
            tested += 1
            d, s, w = point_triangle_closest(px, py, pz, V, F[t, 0], F[t, 1], F[t, 2])
            if d + fdev[t] < UB:
                UB = d + fdev[t]
            lbt = d - fdev[t]
            if lbt <= UB and lbt <= max_dist:
                if count < cap:
                    cand_t[count] = t
                    cand_d[count] = d
                    cand_s[count] = s
                    cand_w[count] = w
                count += 1  # beyond cap: only counted (the caller searches again)
    if count > cap:
        return count, UB, LB, pops, tested, grown
    # keep the candidates that can still win, nearest first (insertion sort: few)
    k = 0
    for i in range(count):
        if cand_d[i] - fdev[cand_t[i]] <= UB:
            cand_t[k] = cand_t[i]
            cand_d[k] = cand_d[i]
            cand_s[k] = cand_s[i]
            cand_w[k] = cand_w[i]
            k += 1
    for i in range(1, k):
        tt, dd, ss, ww = cand_t[i], cand_d[i], cand_s[i], cand_w[i]
        j = i - 1
        while j >= 0 and cand_d[j] > dd:
            cand_t[j + 1] = cand_t[j]
            cand_d[j + 1] = cand_d[j]
            cand_s[j + 1] = cand_s[j]
            cand_w[j + 1] = cand_w[j]
            j -= 1
        cand_t[j + 1] = tt
        cand_d[j + 1] = dd
        cand_s[j + 1] = ss
        cand_w[j + 1] = ww
    for i in range(k):
        LB = min(LB, cand_d[i] - fdev[cand_t[i]])
    return k, UB, max(0.0, LB), pops, tested, grown


@jit
def search(px, py, pz, V, F, fdev, dmax, origin, h, lvl_dims, lvl_off, occ, start, tris,
           sc, qid, max_dist):
    """:func:`point_candidates` with the scratch ``sc`` = (stamp, hk, hv, ct, cd, cs,
    cw) of :func:`candidate_scratch`, grown and searched again as it asks.  Returns
    ``(count, UB, LB, overflow, pops, tested, sc)``: ``sc`` is the same tuple unless
    it grew (then new owned arrays; ``overflow``: more candidates than fitted)."""
    stamp, hk, hv, ct, cd, cs, cw = sc
    k, UB, LB, pops, tested, heap = point_candidates(
        px, py, pz, V, F, fdev, dmax, origin, h, lvl_dims, lvl_off, occ, start, tris,
        stamp, qid, hk, hv, ct, cd, cs, cw, max_dist)
    ovf = False
    need = heap
    while k > ct.shape[0]:
        ovf = True
        m = max(k, 2 * ct.shape[0])
        ct = np.empty(m, dtype=ct.dtype)
        cd = np.empty(m)
        cs = np.empty(m)
        cw = np.empty(m)
        if need > hk.shape[0]:
            hk = np.empty(need)
            hv = np.empty(need, dtype=np.int64)
        qid = -2 - qid  # the first search's stamps are this query's: a new id
        k, UB, LB, pops2, tested2, heap = point_candidates(
            px, py, pz, V, F, fdev, dmax, origin, h, lvl_dims, lvl_off, occ, start, tris,
            stamp, qid, hk, hv, ct, cd, cs, cw, max_dist)
        pops += pops2
        tested += tested2
        need = max(need, heap)
    if need > hk.shape[0]:
        hk = np.empty(need)
        hv = np.empty(need, dtype=np.int64)
    return k, UB, LB, ovf, pops, tested, (stamp, hk, hv, ct, cd, cs, cw)


@jit
def candidate_scratch(m, cap):
    """Working arrays of :func:`point_candidates` for a mesh of ``m`` triangles and
    ``cap`` candidates (grown by it as needed): ``(stamp, hk, hv, ct, cd, cs, cw)``."""
    return (np.full(m, -1, dtype=np.int64), np.empty(256), np.empty(256, dtype=np.int64),
            np.empty(cap, dtype=np.int64), np.empty(cap), np.empty(cap), np.empty(cap))


@jit
def _nearest_points_range(i0, i1, P, V, F, origin, h, lvl_dims, lvl_off, occ, start, tris,
                          out_d, out_t, out_p, work):
    _nearest_points_loop(i0, i1, P, V, F, origin, h, lvl_dims, lvl_off, occ, start, tris,
                         out_d, out_t, out_p, work, np.zeros(F.shape[0]),
                         candidate_scratch(F.shape[0], 1))


@jit
def _nearest_points_loop(i0, i1, P, V, F, origin, h, lvl_dims, lvl_off, occ, start, tris,
                         out_d, out_t, out_p, work, zero, sc):
    """The loop of :func:`_nearest_points_range` over borrowed views."""
    (P, V, F, origin, lvl_dims, lvl_off, occ, start, tris, out_d, out_t, out_p, work, zero,
     sc) = borrow_all((P, V, F, origin, lvl_dims, lvl_off, occ, start, tris, out_d, out_t,
                       out_p, work, zero, sc))
    for i in range(i0, i1):
        k, UB, LB, ovf, pops, tested, sc = search(
            P[i, 0], P[i, 1], P[i, 2], V, F, zero, 0.0, origin, h, lvl_dims, lvl_off,
            occ, start, tris, sc, i, np.inf)
        ct, cd, cs, cw = sc[3], sc[4], sc[5], sc[6]
        work[i, 0] = pops
        work[i, 1] = tested
        t = ct[0]
        out_d[i] = cd[0]
        out_t[i] = t
        a, b, c = F[t, 0], F[t, 1], F[t, 2]
        s, w = cs[0], cw[0]
        for d in range(3):
            out_p[i, d] = V[a, d] + s * (V[b, d] - V[a, d]) + w * (V[c, d] - V[a, d])


def nearest_points(P, V, F, origin, h, lvl_dims, lvl_off, occ, start, tris,
                   out_d, out_t, out_p, work):
    """Exact nearest triangle of each point (best-first over the voxel pyramid)."""
    prun(_nearest_points_range, P.shape[0], CHUNK, P, V, F, origin, h, lvl_dims, lvl_off,
         occ, start, tris, out_d, out_t, out_p, work)


# ---------------------------------------------------------------- triangle queries
@jit
def _tri_aabb(V, F, t, lo, hi):
    for d in range(3):
        lo[d] = min(V[F[t, 0], d], min(V[F[t, 1], d], V[F[t, 2], d]))
        hi[d] = max(V[F[t, 0], d], max(V[F[t, 1], d], V[F[t, 2], d]))


CANDIDATES_CHUNK = 64
"""Points per parallel work item of :func:`candidates_batch`."""


@jit
def _candidates_chunk(i0, i1, P, V, F, fdev, dmax, origin, h, lvl_dims, lvl_off, occ,
                      start, tris, max_dist, out_k, out_lb):
    """The candidate search of :func:`geomkit._kernels.project._project_chunk` alone (for profiling)."""
    _candidates_range(i0, i1, P, V, F, fdev, dmax, origin, h, lvl_dims, lvl_off, occ,
                      start, tris, max_dist, out_k, out_lb, candidate_scratch(F.shape[0], 64))


@jit
def _candidates_range(i0, i1, P, V, F, fdev, dmax, origin, h, lvl_dims, lvl_off, occ,
                      start, tris, max_dist, out_k, out_lb, sc):
    (P, V, F, fdev, origin, lvl_dims, lvl_off, occ, start, tris, out_k, out_lb, sc) = \
        borrow_all((P, V, F, fdev, origin, lvl_dims, lvl_off, occ, start, tris, out_k,
                    out_lb, sc))
    for i in range(i0, i1):
        k, UB, LB, ovf, pops, tested, sc = search(
            P[i, 0], P[i, 1], P[i, 2], V, F, fdev, dmax, origin, h, lvl_dims, lvl_off,
            occ, start, tris, sc, i, max_dist)
        out_k[i] = k
        out_lb[i] = LB


def candidates_batch(P, V, F, fdev, dmax, origin, h, lvl_dims, lvl_off, occ, start, tris,
                     max_dist, out_k, out_lb):
    """Number of candidate triangles and the lower bound of each point: the first
    stage of :func:`geomkit._kernels.project.project_batch` on its own (the benchmark's stage profile)."""
    prun(_candidates_chunk, P.shape[0], CANDIDATES_CHUNK, P, V, F, fdev, dmax, origin, h,
         lvl_dims, lvl_off, occ, start, tris, max_dist, out_k, out_lb)
