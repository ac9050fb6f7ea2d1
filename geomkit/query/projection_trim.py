"""Trim data of the projector: trim-boundary triangles of the candidate mesh, the
parameter boxes of the candidates' pieces of their faces (the certificate's: trim
slivers included) and samples on the trim curves' images that seed the
trim-boundary Newton."""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from geomkit._kernels import trim_feet as _tf
from geomkit.nurbs.evaluation import evaluate
from geomkit.nurbs.trimming import INSIDE
from geomkit.nurbs.surface import Surface

TRIM_SAMPLES = 32
"""Samples per trim segment that seed the trim-boundary Newton."""
TRIM_STARTS = 3
"""Trim-boundary Newton starts per point: from its nearest boundary samples."""


def _boundary_edges(mesh, trimmed) -> np.ndarray:
    """(m, 3) bool: edge k (corners k, k+1) of a triangle of a trimmed face is on the
    mesh boundary (no other triangle has it)."""
    F = mesh.faces
    on = trimmed[mesh.face_surface] != 0
    out = np.zeros(F.shape, bool)
    if not on.any():
        return out
    idx = np.flatnonzero(on)
    E = np.sort(np.stack([F[idx][:, [0, 1]], F[idx][:, [1, 2]], F[idx][:, [2, 0]]],
                         axis=1), axis=2).reshape(-1, 2)  # (3k, 2), vertex ids
    _, inv, cnt = np.unique(E, axis=0, return_inverse=True, return_counts=True)
    out[idx] = (cnt[inv.ravel()] == 1).reshape(-1, 3)
    return out


def _trim_boundary_triangles(mesh, trimmed) -> np.ndarray:
    """(m,) bool: triangles of trimmed faces with an edge on the mesh boundary.

    Their deviation bound must also carry the trim polyline's 3-D chord error
    (:data:`geomkit.query.projection.PROJ_TRIM_TARGET` times the mesh tolerance): along a trim
    curve the face runs past the mesh (outer loops) or the mesh past the face (over a
    hole), so ``d(x, t) + e_t`` measured on the parametric gap alone is no upper bound
    of the distance to the trimmed face there — it pruned the nearest face of a real
    part (a disk above a plate's hole)."""
    return _boundary_edges(mesh, trimmed).any(axis=1)


class _TrimData:
    """Trim segments of one surface and dense samples on their images."""

    def __init__(self, s: Surface):
        seg, deg, _, _ = s.trim_segments()
        self.seg = np.ascontiguousarray(seg)
        self.deg = deg
        M = seg.shape[0] * TRIM_SAMPLES
        uv = np.empty((M, 2))
        self.samp_seg = np.empty(M, dtype=np.int64)
        self.samp_t = np.empty(M)
        _tf.trim_samples(self.seg, deg, TRIM_SAMPLES, uv, self.samp_seg, self.samp_t)
        (u0, u1), (v0, v1) = s.domain
        uv[:, 0] = np.clip(uv[:, 0], u0, u1)
        uv[:, 1] = np.clip(uv[:, 1], v0, v1)
        self.samp_xyz = np.ascontiguousarray(evaluate(s, uv))
        self.tree = cKDTree(self.samp_xyz)

    def nearest_samples(self, P):
        """Indices (n, 3) of the :data:`TRIM_STARTS` boundary samples nearest to each
        point (-1 where there are fewer samples)."""
        k = min(TRIM_STARTS, self.samp_xyz.shape[0])
        _, idx = self.tree.query(P, k=k)
        near = np.full((P.shape[0], TRIM_STARTS), -1, dtype=np.int64)
        near[:, :k] = np.asarray(idx, dtype=np.int64).reshape(P.shape[0], k)
        return near


CERT_SAMPLES = 64
"""Samples per trim segment that seed the parameters of the boundary vertices."""
CERT_NEAREST = 6
"""Trim samples (hence segments) tried per boundary vertex."""


def _bernstein(p, t):
    """(n, p + 1) Bernstein basis of degree ``p`` at the parameters ``t`` (n,)."""
    n = t.shape[0]
    a = np.ones((n, p + 1))
    b = np.ones((n, p + 1))
    for k in range(1, p + 1):
        a[:, k] = a[:, k - 1] * t  # t^k
        b[:, k] = b[:, k - 1] * (1.0 - t)  # (1 - t)^k
    c = np.array([math.comb(p, k) for k in range(p + 1)], dtype=np.float64)
    return c * a * b[:, ::-1]


def _curve(Q, p, t):
    """Point (n, 2) and derivative (n, 2) of the rational Bézier segments ``Q`` (n,
    p + 1, 3) (homogeneous: u w, v w, w) of degree ``p`` at ``t`` (n,)."""
    H = np.einsum("ni,nic->nc", _bernstein(p, t), Q)
    D = np.einsum("ni,nic->nc", _bernstein(p - 1, t), p * np.diff(Q, axis=1))
    C = H[:, :2] / H[:, 2:]
    return C, (D[:, :2] - C * D[:, 2:]) / H[:, 2:]


def _split_rows(P, t):
    """de Casteljau of every row of ``P`` (n, k, 3) at its own ``t`` (n,): (left,
    right)."""
    L, R, Q = [P[:, 0]], [P[:, -1]], P
    tt = t[:, None, None]
    for _ in range(P.shape[1] - 1):
        Q = (1.0 - tt) * Q[:, :-1] + tt * Q[:, 1:]
        L.append(Q[:, 0])
        R.append(Q[:, -1])
    return np.stack(L, axis=1), np.stack(R[::-1], axis=1)


def _seeds(seg, deg, uv):
    """For each parameter point ``uv`` (n, 2): the segments and parameters of its
    :data:`CERT_NEAREST` nearest samples on the trim curves (n, k)."""
    M = seg.shape[0] * CERT_SAMPLES
    suv = np.empty((M, 2))
    sseg = np.empty(M, dtype=np.int64)
    st = np.empty(M)
    _tf.trim_samples(seg, deg, CERT_SAMPLES, suv, sseg, st)
    k = min(CERT_NEAREST, M)
    _, idx = cKDTree(suv).query(uv, k=k)
    idx = np.asarray(idx).reshape(uv.shape[0], k)
    S = np.full((uv.shape[0], CERT_NEAREST), -1, dtype=np.int64)
    T = np.zeros((uv.shape[0], CERT_NEAREST))
    S[:, :k] = sseg[idx]
    T[:, :k] = st[idx]
    return S, T


def _refine(seg, deg, S, T, X, tol):
    """Gauss-Newton on ``|C_S(t) - X|`` from ``T`` (all flat, S the segment indices
    into ``seg``, -1 none): the parameters and whether each lands within ``tol`` (per
    row) of its point."""
    T = T.copy()
    ok = np.zeros(S.shape, bool)
    live = S >= 0
    for p in np.unique(deg[S[live]]):
        sel = np.flatnonzero(live & (deg[np.maximum(S, 0)] == p))
        Q = seg[S[sel], :p + 1]
        t = T[sel]
        for _ in range(10):
            C, dC = _curve(Q, p, t)
            g = np.einsum("nc,nc->n", C - X[sel], dC)
            h = np.einsum("nc,nc->n", dC, dC)
            t = np.clip(t - np.where(h > 0, g / np.where(h > 0, h, 1.0), 0.0), 0.0, 1.0)
        C, _ = _curve(Q, p, t)
        T[sel] = t
        ok[sel] = np.linalg.norm(C - X[sel], axis=1) <= tol[sel]
    return T, ok


def cert_boxes(mesh, surfaces, trimmed, ttol) -> np.ndarray:
    """(m, 5): parameter boxes ``(umin, umax, vmin, vmax)`` holding every point of each
    candidate triangle's piece of its face, for the projection's certificate
    (:func:`geomkit._kernels.project_cert.cert_settle`; NaN rows are never settled),
    and a *deep* flag (column 4, 1.0 or 0.0): the whole box of a triangle of a trimmed
    face lies inside the face, farther than the classification band ``ttol[s]`` from
    its trim curves and domain sides, so a foot in that box is INSIDE without
    classifying it (:func:`_deep`).

    Inside a face the piece is the parameter triangle.  A triangle with an edge on a
    trim polyline also stands for the sliver between that chord and the exact trim
    curve (the face runs past the mesh where the curve bulges away from the
    triangle): the arc between the edge's two vertices lies in the convex hull of its
    rational Bézier sub-segment (positive weights), so the box also holds that hull.
    The arc is found by locating both vertices on one trim segment (within ``1e-9`` of
    the parameter domain's size).  An edge within that of a side of the domain has no
    sliver (the face ends there: the box reaches the side), nor has an edge found
    twice in parameters (the mesh split along a line inside the face: the other
    triangle goes on); any other edge (a vertex off the exact trim curve, no common
    segment, a non-positive weight) gives NaN: no certificate."""
    fuv = mesh.face_uv
    box = np.stack([fuv[..., 0].min(1), fuv[..., 0].max(1), fuv[..., 1].min(1),
                    fuv[..., 1].max(1)], axis=1)
    bedge = _boundary_edges(mesh, trimmed)
    segs, degs, E_tri, E_a, E_b, E_tol, SA, TA, SB, TB = ([] for _ in range(10))
    seg_of = {}  # surface -> (first global segment, count)
    so = 0
    for si in np.flatnonzero(trimmed):
        tri, k = np.nonzero(bedge & (mesh.face_surface == si)[:, None])
        if tri.size == 0:
            continue
        s = surfaces[si]
        (u0, u1), (v0, v1) = s.domain
        tol = 1e-9 * max(u1 - u0, v1 - v0)
        a = fuv[tri, k]
        b = fuv[tri, (k + 1) % 3]
        lo = np.array([u0, v0])
        hi = np.array([u1, v1])
        side = ((np.abs(a - lo) <= tol) & (np.abs(b - lo) <= tol)) \
            | ((np.abs(a - hi) <= tol) & (np.abs(b - hi) <= tol))
        # an edge twice in parameters (the mesh split along a seam or a knot line,
        # vertices not shared): the face goes on in the other triangle
        key = np.concatenate([np.minimum(a, b), np.maximum(a, b)], axis=1)
        _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        free = ~side.any(axis=1) & (cnt[inv.ravel()] == 1)
        # an edge within tol of a domain side: the box reaches that side
        st = tri[side[:, 0]]
        box[st[np.abs(a[side[:, 0], 0] - u0) <= tol], 0] = u0
        box[st[np.abs(a[side[:, 0], 0] - u1) <= tol], 1] = u1
        st = tri[side[:, 1]]
        box[st[np.abs(a[side[:, 1], 1] - v0) <= tol], 2] = v0
        box[st[np.abs(a[side[:, 1], 1] - v1) <= tol], 3] = v1
        if not free.any():
            continue
        tri, a, b = tri[free], a[free], b[free]
        seg, deg, _, _ = s.trim_segments()
        seg = np.ascontiguousarray(seg)
        Sa, Ta = _seeds(seg, deg, a)
        Sb, Tb = _seeds(seg, deg, b)
        segs.append(seg)
        degs.append(deg)
        SA.append(np.where(Sa >= 0, Sa + so, -1))
        SB.append(np.where(Sb >= 0, Sb + so, -1))
        TA.append(Ta)
        TB.append(Tb)
        seg_of[si] = (so, seg.shape[0])
        so += seg.shape[0]
        E_tri.append(tri)
        E_a.append(a)
        E_b.append(b)
        E_tol.append(np.full(tri.size, tol))
    if not E_tri:
        return _deep(mesh, surfaces, trimmed, ttol, box, bedge, None)
    pmax = max(sg.shape[1] for sg in segs)
    seg = np.ones((so, pmax, 3))
    o = 0
    for sg in segs:
        seg[o:o + sg.shape[0], :sg.shape[1]] = sg
        o += sg.shape[0]
    deg = np.concatenate(degs)
    tri, a, b, tol = (np.concatenate(E) for E in (E_tri, E_a, E_b, E_tol))
    Sa, Sb, Ta, Tb = (np.concatenate(E) for E in (SA, SB, TA, TB))
    kk = Sa.shape[1]
    Ta, oka = _refine(seg, deg, Sa.ravel(), Ta.ravel(), np.repeat(a, kk, axis=0),
                      np.repeat(tol, kk))
    Tb, okb = _refine(seg, deg, Sb.ravel(), Tb.ravel(), np.repeat(b, kk, axis=0),
                      np.repeat(tol, kk))
    Ta, oka, Tb, okb = (x.reshape(-1, kk) for x in (Ta, oka, Tb, okb))
    # both vertices on one segment: the pair with the shortest arc
    same = (Sa[:, :, None] == Sb[:, None, :]) & oka[:, :, None] & okb[:, None, :]
    gap = np.where(same, np.abs(Ta[:, :, None] - Tb[:, None, :]), np.inf).reshape(
        tri.size, -1)
    flat = gap.argmin(axis=1)
    ia, ib = np.divmod(flat, kk)
    rows = np.arange(tri.size)
    found = np.isfinite(gap[rows, flat])
    sg = Sa[rows, ia]
    t0 = np.clip(np.minimum(Ta[rows, ia], Tb[rows, ib]) - 1e-9, 0.0, 1.0)
    t1 = np.clip(np.maximum(Ta[rows, ia], Tb[rows, ib]) + 1e-9, 0.0, 1.0)
    hull = np.full((tri.size, 4), np.nan)
    for p in np.unique(deg[sg[found]]):
        sel = np.flatnonzero(found & (deg[sg] == p))
        left, _ = _split_rows(seg[sg[sel], :p + 1], t1[sel])
        _, sub = _split_rows(left, t0[sel] / t1[sel])
        w = sub[..., 2]
        pos = (w > 0).all(axis=1)
        X = sub[..., :2] / np.where(w > 0, w, 1.0)[..., None]
        h = np.stack([X[..., 0].min(1), X[..., 0].max(1), X[..., 1].min(1),
                      X[..., 1].max(1)], axis=1)
        h[:, ::2] -= tol[sel, None]
        h[:, 1::2] += tol[sel, None]
        h[~pos] = np.nan
        hull[sel] = h
    # a triangle's box grows by the hull of each of its boundary arcs (NaN spreads)
    with np.errstate(invalid="ignore"):
        np.minimum.at(box[:, 0], tri, hull[:, 0])
        np.maximum.at(box[:, 1], tri, hull[:, 1])
        np.minimum.at(box[:, 2], tri, hull[:, 2])
        np.maximum.at(box[:, 3], tri, hull[:, 3])
    return _deep(mesh, surfaces, trimmed, ttol, box, bedge,
                 (tri, hull, found, sg, t0, t1, seg, deg, seg_of))


def _deep(mesh, surfaces, trimmed, ttol, box, bedge, arcs):
    """Clip ``box`` to the domains and append the deep flag (:func:`cert_boxes`).

    The boundary of a trimmed face lies in the union of its *obstacles*: the hull box
    of every located trim arc (``arcs``), the whole hull box of every trim segment not
    covered by located arcs (a loop the mesh dropped, a bridge), and the domain's
    sides.  A triangle not on the mesh boundary lies in the trim polylines' region,
    which differs from the face only in slivers inside arc hulls; so when its box,
    grown by ``ttol[s]`` (and rounding), meets no obstacle and stays that far inside
    the domain, the box holds no point of the face's boundary, contains points of the
    face, and is connected: all of it is inside the face, beyond the band.  A surface
    with a refused (NaN) arc gets no deep triangle."""
    fs = mesh.face_surface
    dm = np.array([[*s.domain[0], *s.domain[1]] for s in surfaces])[fs]
    box[:, 0] = np.maximum(box[:, 0], dm[:, 0])  # the face lies in the domain
    box[:, 1] = np.minimum(box[:, 1], dm[:, 1])
    box[:, 2] = np.maximum(box[:, 2], dm[:, 2])
    box[:, 3] = np.minimum(box[:, 3], dm[:, 3])
    deep = np.zeros(box.shape[0])
    inner = ~bedge.any(axis=1)
    gdeep, goff, o = [], np.zeros((len(surfaces), 2), dtype=np.int64), 0
    for si in np.flatnonzero(trimmed):
        s = surfaces[si]
        (u0, u1), (v0, v1) = s.domain
        seg, deg, _, _ = s.trim_segments()
        O = _segment_hulls(seg, deg, np.ones(seg.shape[0], bool))
        if arcs is not None and si in arcs[8]:
            tri, hull, found, sg, t0, t1, gseg, gdeg, seg_of = arcs
            o_s, n = seg_of[si]
            mine = fs[tri] == si
            h = hull[mine]
            if not np.isnan(h).any():  # else: the whole segments' hulls
                cov = np.zeros(n, bool)
                g, a, b = sg[mine] - o_s, t0[mine], t1[mine]
                order = np.lexsort((a, g))
                g, a, b = g[order], a[order], b[order]
                for j in range(n):
                    lo, hi = np.searchsorted(g, [j, j + 1])
                    reach = 0.0
                    for k in range(lo, hi):  # the arcs cover [0, 1] without a gap
                        if a[k] > reach:
                            break
                        reach = max(reach, b[k])
                    cov[j] = reach >= 1.0
                O = np.concatenate([h, _segment_hulls(seg, deg, ~cov)])
        if np.isnan(O).any():
            continue
        g = ttol[si] + 1e-9 * max(u1 - u0, v1 - v0)
        G = _deep_grid(int(np.count_nonzero(trimmed)))
        cells = _deep_cells(s, O, g, G)
        goff[si] = (o, G)
        gdeep.append(cells.ravel())
        o += cells.size
        cand = np.flatnonzero(inner & (fs == si))
        B = box[cand]
        ok = ((B[:, 0] - u0 > g) & (u1 - B[:, 1] > g) & (B[:, 2] - v0 > g)
              & (v1 - B[:, 3] > g))
        for i in range(0, cand.size, 256):  # no obstacle meets the grown box
            b = B[i:i + 256, None, :]
            hit = ((O[None, :, 0] <= b[..., 1] + g) & (O[None, :, 1] >= b[..., 0] - g)
                   & (O[None, :, 2] <= b[..., 3] + g) & (O[None, :, 3] >= b[..., 2] - g))
            ok[i:i + 256] &= ~hit.any(axis=1)
        deep[cand[ok]] = 1.0
    gdeep = np.concatenate(gdeep) if gdeep else np.zeros(1, dtype=np.int8)
    return (np.ascontiguousarray(np.concatenate([box, deep[:, None]], axis=1)),
            np.ascontiguousarray(gdeep, dtype=np.int8), goff)


DEEP_GRID = 32
"""Cells per direction of a trimmed surface's grid of deep parameter cells (at
least; see :data:`DEEP_CELLS`)."""
DEEP_CELLS = 1 << 18
"""Cells of all deep grids together: models with few trimmed faces get finer grids
(up to :data:`DEEP_GRID_MAX` per direction), so fewer feet near the domain sides and
the trim curves need a classification (the plate with a hole: 37 % of its scan points'
feet at 32 x 32, the two cells along each domain side never being deep)."""
DEEP_GRID_MAX = 256


def _deep_grid(n_trimmed):
    """Cells per direction of each deep grid for ``n_trimmed`` trimmed surfaces."""
    G = int(math.sqrt(DEEP_CELLS / max(1, n_trimmed)))
    return max(DEEP_GRID, min(DEEP_GRID_MAX, G))


def _deep_cells(s, O, g, G=DEEP_GRID):
    """(G, G) int8: cell (i, j) of the surface's domain split ``G`` times each way is
    *deep* (1) when, grown by ``g`` and rounding, it meets no obstacle box of ``O``
    (k, 4) and no domain side, and its centre is INSIDE the face: then the cell holds
    no boundary point and is connected, so all of it is inside the face beyond ``g``
    (the argument of :func:`_deep`).  The same holds for each 4-connected run of such
    cells, so one centre per run is classified."""
    (u0, u1), (v0, v1) = s.domain
    du, dv = (u1 - u0) / G, (v1 - v0) / G
    eu, ev = g + 1e-12 * (u1 - u0), g + 1e-12 * (v1 - v0)
    free = np.ones((G, G), bool)
    free[0, :] = free[-1, :] = free[:, 0] = free[:, -1] = False  # the domain sides
    if not (du > 2 * eu and dv > 2 * ev):
        return np.zeros((G, G), dtype=np.int8)
    ia = np.clip(np.floor((O[:, 0] - eu - u0) / du).astype(np.int64) - 1, 0, G - 1)
    ib = np.clip(np.floor((O[:, 1] + eu - u0) / du).astype(np.int64) + 1, 0, G - 1)
    ja = np.clip(np.floor((O[:, 2] - ev - v0) / dv).astype(np.int64) - 1, 0, G - 1)
    jb = np.clip(np.floor((O[:, 3] + ev - v0) / dv).astype(np.int64) + 1, 0, G - 1)
    for a, b, c, d in zip(ia, ib, ja, jb):  # one cell of slack each way (rounding)
        free[a:b + 1, c:d + 1] = False
    # a 4-connected run of free cells holds no boundary point either, so all of it is
    # inside or all outside: one centre per run is classified
    lab, n = ndimage.label(free)
    if n == 0:
        return np.zeros((G, G), dtype=np.int8)
    labels, first = np.unique(lab.ravel(), return_index=True)
    first = first[labels > 0]
    i, j = np.unravel_index(first, free.shape)
    uv = np.c_[u0 + (i + 0.5) * du, v0 + (j + 0.5) * dv]
    val = np.zeros(n + 1, dtype=np.int8)
    val[labels[labels > 0]] = s.classify_uv(uv) == INSIDE
    return val[lab]


def _segment_hulls(seg, deg, sel):
    """(k, 4) boxes of the control points of the selected trim segments (NaN for a
    non-positive weight)."""
    out = []
    for j in np.flatnonzero(sel):
        Q = seg[j, :deg[j] + 1]
        if not (Q[:, 2] > 0).all():
            out.append([np.nan] * 4)
            continue
        X = Q[:, :2] / Q[:, 2:]
        out.append([X[:, 0].min(), X[:, 0].max(), X[:, 1].min(), X[:, 1].max()])
    return np.array(out, dtype=np.float64).reshape(-1, 4)
