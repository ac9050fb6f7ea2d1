"""Plain-Python reference evaluators, independent of geomkit's kernels.

* :func:`basis_all` — every B-spline basis function N_{i,p}(u) by the Cox–de Boor
  recursion (works for clamped *and* unclamped knot vectors; 0/0 := 0).
* :func:`surface_point` — S(u, v) = sum N_i(u) N_j(v) w_ij P_ij / sum N_i(u) N_j(v) w_ij
  straight from the definition (no span search tricks, no homogeneous kernels).
* :func:`bezier_point` — a rational tensor-product Bézier patch evaluated with
  explicit Bernstein polynomials on a sub-domain [u0, u1] x [v0, v1].

They are slow and only meant for tests.
"""

from __future__ import annotations

from math import comb

import numpy as np

__all__ = ["domain_span", "basis_all", "surface_point", "surface_points", "bernstein",
           "bezier_point"]


def domain_span(U, p, n, u):
    """The knot span index used for ``u`` on the domain [U[p], U[n]] (n = #control pts).

    The last ``i`` in ``[p, n-1]`` with ``U[i] <= u`` and ``U[i] < U[i+1]`` (so spans are
    half-open ``[U[i], U[i+1])`` and the right end of the domain belongs to the last
    non-empty span).
    """
    U = [float(x) for x in U]
    best = None
    for i in range(p, n):
        if U[i] < U[i + 1] and U[i] <= u:
            best = i
    if best is None:
        raise ValueError(f"u = {u!r} is left of the domain start {U[p]!r}")
    return best


def basis_all(U, p, n, u):
    """All n basis functions N_{i,p}(u), i = 0..n-1, by Cox–de Boor."""
    U = [float(x) for x in U]
    m = len(U) - 1
    s = domain_span(U, p, n, u)
    # degree 0: indicator of the chosen span (length m)
    N = [1.0 if i == s else 0.0 for i in range(m)]
    for k in range(1, p + 1):
        nxt = []
        for i in range(m - k):
            val = 0.0
            d1 = U[i + k] - U[i]
            if d1 != 0.0 and N[i] != 0.0:
                val += (u - U[i]) / d1 * N[i]
            d2 = U[i + k + 1] - U[i + 1]
            if d2 != 0.0 and N[i + 1] != 0.0:
                val += (U[i + k + 1] - u) / d2 * N[i + 1]
            nxt.append(val)
        N = nxt
    return N[:n]


def surface_point(degree_u, degree_v, knots_u, knots_v, control_points, weights, u, v):
    """S(u, v) from the definition; ``weights`` may be None (non-rational)."""
    P = np.asarray(control_points, float)
    nu, nv = P.shape[:2]
    W = np.ones((nu, nv)) if weights is None else np.asarray(weights, float)
    Nu = basis_all(knots_u, degree_u, nu, float(u))
    Nv = basis_all(knots_v, degree_v, nv, float(v))
    num = [0.0, 0.0, 0.0]
    den = 0.0
    for i in range(nu):
        if Nu[i] == 0.0:
            continue
        for j in range(nv):
            if Nv[j] == 0.0:
                continue
            b = Nu[i] * Nv[j] * W[i, j]
            den += b
            for c in range(3):
                num[c] += b * P[i, j, c]
    return np.array([x / den for x in num])


def surface_points(degree_u, degree_v, knots_u, knots_v, control_points, weights, uv):
    uv = np.asarray(uv, float).reshape(-1, 2)
    return np.array([surface_point(degree_u, degree_v, knots_u, knots_v, control_points,
                                   weights, u, v) for u, v in uv]).reshape(-1, 3)


def bernstein(p, t):
    """[B_{0,p}(t), ..., B_{p,p}(t)] = C(p, i) t^i (1 - t)^(p - i)."""
    return [comb(p, i) * t ** i * (1.0 - t) ** (p - i) for i in range(p + 1)]


def bezier_point(Hw, u, v, u0, u1, v0, v1):
    """Point of a rational Bézier patch with homogeneous net ``Hw`` (p+1, q+1, 4)
    (rows ``(w x, w y, w z, w)``) at (u, v) of its sub-domain [u0, u1] x [v0, v1]."""
    Hw = np.asarray(Hw, float)
    p, q = Hw.shape[0] - 1, Hw.shape[1] - 1
    s = (u - u0) / (u1 - u0)
    t = (v - v0) / (v1 - v0)
    Bu = bernstein(p, s)
    Bv = bernstein(q, t)
    acc = [0.0, 0.0, 0.0, 0.0]
    for i in range(p + 1):
        for j in range(q + 1):
            b = Bu[i] * Bv[j]
            for c in range(4):
                acc[c] += b * Hw[i, j, c]
    return np.array(acc[:3]) / acc[3]


# ====================================================================================
# Independent mesh-deviation sampler (tests only).  Nothing below calls geomkit's
# tessellation kernels: it uses only ``Surface.evaluate`` / ``derivatives`` /
# ``classify_uv``, trim-curve evaluation, numpy, scipy and trimesh's per-pair
# point-triangle routine.
# ====================================================================================

def surface_edges(surface, n=65, rel=1e-9):
    """Which domain edges are closed seams or collapsed poles, found by sampling.

    Returns ``{"closed_u": bool, "closed_v": bool, "poles": {"u0", "u1", "v0", "v1"}
    subset}``: ``closed_u`` when S(u0, v) == S(u1, v) for all sampled v (within ``rel *
    size``), a pole ``"v0"`` when S(u, v0) is one point for all sampled u, etc."""
    (u0, u1), (v0, v1) = surface.domain
    eps = rel * max(surface.size, 1e-300)
    t = np.linspace(0.0, 1.0, n)
    us = u0 + (u1 - u0) * t
    vs = v0 + (v1 - v0) * t
    rows = {"u0": surface.evaluate(np.c_[np.full(n, u0), vs]),
            "u1": surface.evaluate(np.c_[np.full(n, u1), vs]),
            "v0": surface.evaluate(np.c_[us, np.full(n, v0)]),
            "v1": surface.evaluate(np.c_[us, np.full(n, v1)])}
    poles = {k for k, P in rows.items() if np.ptp(P, axis=0).max() <= eps}
    return {"closed_u": bool(np.abs(rows["u0"] - rows["u1"]).max() <= eps),
            "closed_v": bool(np.abs(rows["v0"] - rows["v1"]).max() <= eps),
            "poles": poles}


def face_corner_uv(surface, corner_uv, edges=None):
    """Per-face UV triangles with seam and pole vertices made consistent.

    A mesh vertex welded across a closed seam or at a pole carries only one of its
    parameter values.  ``corner_uv`` (m, 3, 2) are the vertex UVs of each face; seam
    corners (on ``u0``/``u1`` of a surface closed in u, likewise v) are moved to the
    side of the face's other corners; a pole corner gets, along the collapsed edge,
    the mean parameter of the face's other corners.

    Returns ``(uv (m, 3, 2), clean (m,) bool)``; ``clean`` is False for faces with a
    pole corner or whose seam side could not be decided (their UV triangle is only a
    starting guess)."""
    edges = surface_edges(surface) if edges is None else edges
    (u0, u1), (v0, v1) = surface.domain
    uv = np.array(corner_uv, dtype=float, copy=True)
    clean = np.ones(uv.shape[0], dtype=bool)
    lo = np.array([u0, v0])
    hi = np.array([u1, v1])
    eps = 1e-9 * (hi - lo)
    for axis, closed in ((0, edges["closed_u"]), (1, edges["closed_v"])):
        if not closed:
            continue
        c = uv[:, :, axis]
        amb = (c <= lo[axis] + eps[axis]) | (c >= hi[axis] - eps[axis])
        mid = 0.5 * (lo[axis] + hi[axis])
        firm = ~amb
        nfirm = firm.sum(axis=1)
        upper = np.where(nfirm > 0, (np.where(firm, c, 0.0).sum(axis=1)
                                     / np.maximum(nfirm, 1)) > mid, False)
        target = np.where(upper, hi[axis], lo[axis])[:, None]
        c[:] = np.where(amb & (nfirm[:, None] > 0), target, c)
        clean &= nfirm > 0
    # poles: "v0" collapses the u direction at v = v0 (u free), "u0" the v direction
    for name in edges["poles"]:
        axis_fixed = 1 if name[0] == "v" else 0   # the coordinate that is constant
        free = 1 - axis_fixed
        val = (lo if name[1] == "0" else hi)[axis_fixed]
        on = np.abs(uv[:, :, axis_fixed] - val) <= eps[axis_fixed]
        n_off = (~on).sum(axis=1)
        mean_off = np.where(n_off > 0, np.where(~on, uv[:, :, free], 0.0).sum(axis=1)
                            / np.maximum(n_off, 1), uv[:, :, free].mean(axis=1))
        uv[:, :, free] = np.where(on, mean_off[:, None], uv[:, :, free])
        clean &= ~on.any(axis=1)
    return uv, clean


def random_barycentric(rng, n, k):
    """(n, k, 3) uniform random barycentric coordinates."""
    r = rng.random((n, k, 2))
    flip = r.sum(axis=-1) > 1.0
    r[flip] = 1.0 - r[flip]
    return np.concatenate([1.0 - r.sum(axis=-1, keepdims=True), r], axis=-1)


def project_to_surface(surface, X, uv0, iters=8):
    """Upper bound of dist(X, S) for points X (n, 3) started from uv0 (n, 2).

    Damped Newton on f(u, v) = |S(u, v) - X|^2 / 2 (full Hessian from second
    derivatives, Gauss–Newton where it is not positive definite), clamped to the
    domain, step halving; the smallest |S(uv) - X| over all iterates is returned, so the
    result is an upper bound whatever the convergence.  Returns (uv (n, 2), dist (n,))."""
    (u0, u1), (v0, v1) = surface.domain
    lo = np.array([u0, v0])
    hi = np.array([u1, v1])
    X = np.asarray(X, float)
    uv = np.clip(np.asarray(uv0, float), lo, hi)
    best_uv = uv.copy()
    best = np.linalg.norm(surface.evaluate(uv) - X, axis=1)
    for _ in range(iters):
        D = surface.derivatives(uv, 2)
        r = D[:, 0, 0] - X
        Su, Sv = D[:, 1, 0], D[:, 0, 1]
        Suu, Suv, Svv = D[:, 2, 0], D[:, 1, 1], D[:, 0, 2]
        g = np.stack([np.einsum("ij,ij->i", Su, r), np.einsum("ij,ij->i", Sv, r)], axis=1)
        a = np.einsum("ij,ij->i", Su, Su)
        b = np.einsum("ij,ij->i", Su, Sv)
        c = np.einsum("ij,ij->i", Sv, Sv)
        ha = a + np.einsum("ij,ij->i", Suu, r)
        hb = b + np.einsum("ij,ij->i", Suv, r)
        hc = c + np.einsum("ij,ij->i", Svv, r)
        pd = (ha > 0) & (ha * hc - hb * hb > 0)
        ha, hb, hc = np.where(pd, ha, a), np.where(pd, hb, b), np.where(pd, hc, c)
        lam = 1e-12 * (ha + hc) + 1e-300
        ha, hc = ha + lam, hc + lam
        det = ha * hc - hb * hb
        det = np.where(det > 0, det, 1e-300)
        step = -np.stack([hc * g[:, 0] - hb * g[:, 1], -hb * g[:, 0] + ha * g[:, 1]],
                         axis=1) / det[:, None]
        step = np.clip(step, -(hi - lo), hi - lo)
        new_uv = uv.copy()
        new_d = np.full(len(uv), np.inf)
        # deep backtracking: at a knot of a C0 parametrisation the one-sided derivative
        # can be 1000x off, and only a tiny step enters the span holding the foot
        for alpha in (1.0, 0.5) + tuple(8.0 ** -k for k in range(1, 9)):
            cand = np.clip(uv + alpha * step, lo, hi)
            d = np.linalg.norm(surface.evaluate(cand) - X, axis=1)
            take = d < new_d
            new_uv[take], new_d[take] = cand[take], d[take]
        gain = best - new_d
        better = gain > 0
        best_uv[better], best[better] = new_uv[better], new_d[better]
        uv = new_uv
        if not np.any(gain > 1e-3 * best):   # converged: no point still improves
            break
    return best_uv, best


def trim_boundary_polylines(surface, per_span=4000):
    """Dense 3-D polylines S(C(t)) of every trim loop, and a bound of their sag.

    Returns (list of (k, 3) arrays, sag); every polyline vertex lies on the trimmed
    surface's boundary, and the exact boundary curves are within ``sag`` of the
    polylines (estimated at the segment midpoints, doubled)."""
    from geomkit.nurbs.trimming import evaluate_trim_curve

    lines = []
    sag = 0.0
    for loop in surface.trim:
        for c in loop.pieces:
            p = c.degree
            brk = np.unique(c.knots[p: len(c.knots) - p])
            t = np.unique(np.concatenate([np.linspace(a, b, per_span + 1)
                                          for a, b in zip(brk[:-1], brk[1:])]))
            C = evaluate_trim_curve(c, t)[:, 0, :]
            Cm = evaluate_trim_curve(c, 0.5 * (t[:-1] + t[1:]))[:, 0, :]
            P = surface.evaluate(C)
            Pm = surface.evaluate(Cm)
            sag = max(sag, 2.0 * float(np.linalg.norm(Pm - 0.5 * (P[:-1] + P[1:]),
                                                       axis=1).max()))
            lines.append(P)
    return lines, sag


def point_polyline_distance(X, lines, k=4):
    """Distance of points X (n, 3) to a set of polylines (nearest ``k`` vertices' adjacent
    segments; exact when the nearest segment touches one of them)."""
    from scipy.spatial import cKDTree

    V = np.concatenate(lines)
    last = np.concatenate([np.r_[np.zeros(len(L) - 1, bool), True] for L in lines])
    first = np.concatenate([np.r_[True, np.zeros(len(L) - 1, bool)] for L in lines])
    tree = cKDTree(V)
    k = min(k, len(V))
    _, idx = tree.query(X, k=k)
    idx = idx.reshape(len(X), -1)
    best = np.full(len(X), np.inf)
    for j in range(idx.shape[1]):
        i = idx[:, j]
        for a_i, ok in ((i - 1, ~first[i]), (i, ~last[i])):
            a_i = np.where(ok, a_i, i)
            b_i = np.where(ok, a_i + 1, i)
            A, B = V[a_i], V[b_i]
            e = B - A
            ee = np.einsum("ij,ij->i", e, e)
            t = np.clip(np.einsum("ij,ij->i", X - A, e) / np.where(ee > 0, ee, 1.0), 0, 1)
            d = np.linalg.norm(X - A - t[:, None] * e, axis=1)
            best = np.minimum(best, d)
    return best


def mesh_distance_candidates(tri, centroids_tree, X, own=None, k=6, exact_above=None,
                             max_exact=5000):
    """Upper bound of the distance of X (n, 3) to the triangles ``tri`` (m, 3, 3): the
    smallest point–triangle distance (``trimesh.triangles.closest_point``) over the
    ``k`` triangles with the nearest centroids (and ``own`` (n,) when given).

    Points whose bound exceeds ``exact_above`` get the exact distance (largest bound
    first, at most ``max_exact`` points, stopping at the first one still above): every
    triangle that could be closer (``|X - centroid| - radius < bound``) is measured."""
    import trimesh

    def pair_dist(ti, Y):
        with np.errstate(divide="ignore", invalid="ignore"):   # degenerate triangles
            cp = trimesh.triangles.closest_point(tri[ti], Y)
        return np.linalg.norm(cp - Y, axis=1)

    kk = min(k, len(tri))
    _, idx = centroids_tree.query(X, k=kk)
    idx = idx.reshape(len(X), -1)
    if own is not None:
        idx = np.concatenate([np.asarray(own)[:, None], idx], axis=1)
    best = np.full(len(X), np.inf)
    for j in range(idx.shape[1]):
        best = np.minimum(best, pair_dist(idx[:, j], X))
    if exact_above is not None:
        centre = tri.mean(axis=1)
        radius = np.linalg.norm(tri - centre[:, None, :], axis=2).max(axis=1)
        over = np.nonzero(best > exact_above)[0]
        for i in over[np.argsort(-best[over])][:max_exact]:
            lower = np.linalg.norm(centre - X[i], axis=1) - radius
            cand = np.nonzero(lower < best[i])[0]
            if len(cand):
                d = pair_dist(cand, np.repeat(X[i:i + 1], len(cand), axis=0))
                best[i] = min(best[i], float(d.min()))
            if best[i] > exact_above:
                break   # a true violation: no need to tighten the others
    return best


def _span_grid(knots, m):
    """Parameters: ``m`` over the domain plus up to ``m`` in every non-empty knot span
    (capped at 4 m in all)."""
    k = np.unique(np.asarray(knots, float))
    per = max(3, min(m, (4 * m) // max(1, len(k) - 1)))
    parts = [np.linspace(k[0], k[-1], m)] + [np.linspace(a, b, per) for a, b in zip(k[:-1], k[1:])]
    return np.unique(np.concatenate(parts))


def bounded_distance_to_surface(surface, X, uv0, again_above=0.0, grid=129):
    """Upper bound of the distance of X (n, 3) to the (trimmed) surface.

    :func:`project_to_surface` from ``uv0``; points whose bound is still above
    ``again_above`` are projected again from the nearest samples of a ``grid`` x
    ``grid`` parameter grid (a global start: welded vertices can make ``uv0`` a poor
    guess).  A foot point outside the trim is not on the trimmed surface: its bound is
    replaced by the distance to the exact trim boundary (dense polylines plus their
    sag).  The smaller valid bound wins."""
    from scipy.spatial import cKDTree

    from geomkit import OUTSIDE

    cache = {}

    def checked(P, uv, d):
        """d, with feet outside the trim replaced by the distance to the trim."""
        if surface.trim:
            off = surface.classify_uv(uv) == OUTSIDE
            if off.any():
                if "lines" not in cache:
                    cache["lines"] = trim_boundary_polylines(surface)
                lines, sag = cache["lines"]
                d[off] = point_polyline_distance(P[off], lines) + sag
        return d

    uv, d = project_to_surface(surface, X, uv0)
    d = checked(X, uv, d)
    again = np.nonzero(d > again_above)[0]
    if len(again):
        # per knot span: a tiny span (knots 0, 0.001, 1) can hold half the surface
        gu = _span_grid(surface.knots_u, grid)
        gv = _span_grid(surface.knots_v, grid)
        g = np.stack(np.meshgrid(gu, gv, indexing="ij"), axis=-1).reshape(-1, 2)
        P = X[again]
        _, near = cKDTree(surface.evaluate(g)).query(P, k=3)
        for j in range(near.shape[1]):
            uv2, d2 = project_to_surface(surface, P, g[near[:, j]])
            d[again] = np.minimum(d[again], checked(P, uv2, d2))
    return d


def sample_mesh_deviation(mesh, surfaces, n_faces=30_000, n_worst=2_000, k_mesh=4,
                          k_surf=3, n_trim=4000, seed=0, exact_above=None):
    """Independent two-sided deviation of a :class:`geomkit.Mesh` from its surfaces.

    For each surface, on every face (or ``n_faces`` random faces plus the ``n_worst``
    with the largest reported ``face_deviation`` when there are more):

    * mesh -> surface: ``k_mesh`` random barycentric points X per face (plus the
      centroid), and 4 random points on each mesh boundary edge (at most ``n_faces``
      edges), projected onto the surface by :func:`project_to_surface` from their
      barycentric UV (an upper bound of dist(X, S)); where the projection's foot lies
      outside the trim, the distance to the exact trim boundary is used instead.
    * surface -> mesh: ``k_surf`` random UV points in each clean face's UV triangle
      (not the faces at poles; points outside the trim skipped) mapped by S, and
      ``n_trim`` points of each exact trim curve; distance to the surface's part of the
      mesh by :func:`mesh_distance_candidates` (an upper bound, made exact for points
      above ``exact_above``).

    Returns a dict: ``to_surface``/``to_mesh`` (largest one-sided distances),
    ``worst_to_surface``/``worst_to_mesh`` (face, point) for messages, ``faces`` (faces
    sampled), ``clean_fraction`` (sampled faces usable for the parametric side) and
    ``points`` (number of distances computed)."""
    from scipy.spatial import cKDTree

    rng = np.random.default_rng(seed)
    again_above = exact_above if exact_above is not None else 0.0
    out = {"to_surface": 0.0, "to_mesh": 0.0, "worst_to_surface": None,
           "worst_to_mesh": None, "faces": 0, "clean_fraction": 1.0, "points": 0}
    clean_total = 0
    for si, s in enumerate(surfaces):
        fidx = np.nonzero(mesh.face_surface == si)[0]
        if not len(fidx):
            continue
        F = mesh.faces[fidx]
        if len(fidx) > n_faces + n_worst:
            worst = np.argsort(mesh.face_deviation[fidx])[-n_worst:]
            pick = np.unique(np.concatenate([rng.choice(len(fidx), n_faces, replace=False),
                                             worst]))
        else:
            pick = np.arange(len(fidx))
        out["faces"] += len(pick)
        edges = surface_edges(s)
        UVall, clean_all = face_corner_uv(s, mesh.uv[F], edges)
        UVc, clean = UVall[pick], clean_all[pick]
        T = mesh.vertices[F[pick]]                       # (p, 3, 3)
        # ---- mesh -> surface
        bary = random_barycentric(rng, len(pick), k_mesh)
        bary = np.concatenate([bary, np.full((len(pick), 1, 3), 1.0 / 3.0)], axis=1)
        X = np.einsum("pkc,pcd->pkd", bary, T).reshape(-1, 3)
        UV0 = np.einsum("pkc,pcd->pkd", bary, UVc).reshape(-1, 2)
        owner = np.repeat(pick, k_mesh + 1)
        # plus random points on the mesh boundary edges (chords of trims and domain edges)
        ends = np.sort(np.stack([F, np.roll(F, -1, axis=1)], axis=-1).reshape(-1, 2), axis=1)
        key = ends[:, 0] * (int(F.max()) + 1) + ends[:, 1]                   # (3m,)
        _, inv, cnt = np.unique(key, return_inverse=True, return_counts=True)
        bnd = np.nonzero(cnt[inv] == 1)[0]
        if len(bnd) > n_faces:
            bnd = rng.choice(bnd, n_faces, replace=False)
        if len(bnd):
            fb, cb = bnd // 3, bnd % 3
            t = rng.random((len(bnd), 4, 1))
            A, B = mesh.vertices[F[fb, cb]], mesh.vertices[F[fb, (cb + 1) % 3]]
            a, b = UVall[fb, cb], UVall[fb, (cb + 1) % 3]
            X = np.concatenate([X, (A[:, None] + t * (B - A)[:, None]).reshape(-1, 3)])
            UV0 = np.concatenate([UV0, (a[:, None] + t * (b - a)[:, None]).reshape(-1, 2)])
            owner = np.concatenate([owner, np.repeat(fb, 4)])
        d = bounded_distance_to_surface(s, X, UV0, again_above)
        i = int(np.argmax(d))
        if d[i] > out["to_surface"]:
            out["to_surface"] = float(d[i])
            out["worst_to_surface"] = (int(fidx[owner[i]]), X[i].tolist())
        out["points"] += len(d)
        # ---- surface -> mesh
        allT = mesh.vertices[F]
        tree = cKDTree(allT.mean(axis=1))
        cp = pick[clean]
        clean_total += len(cp)
        bary = random_barycentric(rng, len(cp), k_surf)
        uv = np.einsum("pkc,pcd->pkd", bary, UVc[clean]).reshape(-1, 2)
        own = np.repeat(cp, k_surf)
        keep = np.ones(len(uv), dtype=bool)
        if s.trim:
            from geomkit import OUTSIDE
            keep = s.classify_uv(uv) != OUTSIDE
        groups = [(s.evaluate(uv[keep]), own[keep])]
        if s.trim:   # the exact trim curves: the mesh boundary must follow them
            lines, _ = trim_boundary_polylines(s, per_span=max(1, n_trim // 4))
            B = np.concatenate(lines)
            if len(B) > n_trim:
                B = B[rng.choice(len(B), n_trim, replace=False)]
            groups.append((B, None))
        for Y, own_y in groups:
            if not len(Y):
                continue
            dm = mesh_distance_candidates(allT, tree, Y, own_y, exact_above=exact_above)
            i = int(np.argmax(dm))
            if dm[i] > out["to_mesh"]:
                out["to_mesh"] = float(dm[i])
                out["worst_to_mesh"] = (None if own_y is None else int(fidx[own_y[i]]),
                                        Y[i].tolist())
            out["points"] += len(dm)
    out["clean_fraction"] = clean_total / max(out["faces"], 1)
    return out


def brute_tris(VA, FA, VB, FB):
    """For each triangle of the soup (VA, FA), the distance to the nearest triangle of
    (VB, FB): every pair, by geomkit's exact triangle-triangle distance."""
    from geomkit._kernels.triangles import triangle_triangle_distance

    qa, qb = np.empty(3), np.empty(3)
    return np.array([min(triangle_triangle_distance(VA[a], VB[b], qa, qb) for b in FB)
                     for a in FA])
