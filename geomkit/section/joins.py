"""Section curves put together: cut at poles, shared edges kept once, ends joined.

The pieces :func:`geomkit.plane_section` traces on each face are assembled here:

1. :func:`split_at_poles` cuts curves where they touch a pole of their surface (a
   section may turn there into any direction: a cone's two generators meet at the
   apex);
2. :func:`drop_shared_edges` keeps once a curve that two faces (or a closed face's two
   seam sides) give when the plane contains the edge between them;
3. :func:`join_ends` joins open curves whose ends coincide within the join distance,
   nearest pair first, and closes loops;
4. :func:`join_across_edges` joins the ends left where the plane crosses a shared edge
   obliquely, within :data:`EDGE_REACH` times the model's gap.

A curve is a dict with ``uv`` (k, 2), ``sid`` (k,) (surface of each point), ``X``
(k, 3), ``closed`` and ``chord`` (its largest chord error).
"""

from __future__ import annotations

import heapq
import math

import numpy as np

__all__ = ["split_at_poles", "drop_shared_edges", "join_ends", "merge_point_curves",
           "join_across_edges", "boundary_distance", "near_boundary", "EDGE_REACH"]


def _collapsed_sides(s) -> np.ndarray:
    """(4,) bool: which sides of the domain (u0, u1, v0, v1) map to one point (a pole,
    a cone's apex); kept on the surface (a part is sectioned at many planes)."""
    sides = s._cache.get("section_poles")
    if sides is None:
        P = s.control_points
        eps = 1e-10 * s.size
        sides = s._cache["section_poles"] = np.array(
            [np.ptp(row, axis=0).max() <= eps for row in (P[0], P[-1], P[:, 0], P[:, -1])])
    return sides


def split_at_poles(curves, surfs):
    """Curves cut at the points where they touch a pole of their surface.

    At a pole (a side of the domain that is one point) a section may turn into any
    direction: the plane through a cone's axis meets it in two generators joined at the
    apex, and the tracer walks them out and back (apex, base, apex, other base, apex).
    Cut there, and a piece from the pole back to it cut again where it turns, the
    pieces join again at the apex as the section really runs, and a piece walked twice
    is one curve (:func:`drop_shared_edges`)."""
    poles = {}
    out = []
    for c in curves:
        k = int(c["sid"][0])
        if k not in poles:
            s = surfs[k]
            (u0, u1), (v0, v1) = s.domain
            e = 1e-12 * max(u1 - u0, v1 - v0)
            poles[k] = (_collapsed_sides(s), (u0, u1, v0, v1), e)
        sides, (u0, u1, v0, v1), e = poles[k]
        if not sides.any() or np.any(c["sid"] != k):
            out.append(c)
            continue
        uv = c["uv"]
        at = np.zeros(len(uv), bool)
        for side, (col, val) in zip(sides, ((0, u0), (0, u1), (1, v0), (1, v1))):
            if side:
                at |= np.abs(uv[:, col] - val) <= e
        cut = np.flatnonzero(at)
        if c["closed"]:
            if not cut.size:
                out.append(c)
                continue
            r = int(cut[0])   # start at a pole, end there again
            idx = np.r_[r:len(uv), 0:r + 1]
            c = {**c, "closed": False, **{key: c[key][idx] for key in ("uv", "sid", "X")}}
            cut = np.flatnonzero(at[idx])
        cut = cut[(cut > 0) & (cut < len(c["uv"]) - 1)]
        if not cut.size:
            out.append(c)
            continue
        bounds = np.r_[0, cut, len(c["uv"]) - 1]
        for a, b in zip(bounds[:-1], bounds[1:]):
            if b <= a:
                continue
            X = c["X"][a:b + 1]
            if at[a] and at[b] and b - a >= 2:   # pole to pole: out and back, or a
                # loop through the pole; cut at the farthest point (the turn)
                m = a + int(np.argmax(np.linalg.norm(X - X[0], axis=1)))
                if 0 < m - a < b - a:
                    pieces = ((a, m), (m, b))
                else:
                    pieces = ((a, b),)
            else:
                pieces = ((a, b),)
            for i, j in pieces:
                out.append({**c, "closed": False,
                            **{key: c[key][i:j + 1] for key in ("uv", "sid", "X")}})
    return out


def _near_polyline(X, Y, tol) -> bool:
    """Every point of ``X`` (n, 3) within ``tol`` of the polyline ``Y`` (m, 3) (closed
    polylines are passed with their first point repeated)."""
    from scipy.spatial import cKDTree

    if len(Y) == 1:
        return bool((np.linalg.norm(X - Y[0], axis=1) <= tol).all())
    _, j = cKDTree(Y).query(X)
    best = np.full(len(X), np.inf)
    for a in (np.maximum(j - 1, 0), j):   # the two segments at the nearest vertex
        b = np.minimum(a + 1, len(Y) - 1)
        A, AB = Y[a], Y[b] - Y[a]
        L2 = np.einsum("ij,ij->i", AB, AB)
        t = np.clip(np.einsum("ij,ij->i", X - A, AB) / np.where(L2 > 0, L2, 1.0), 0, 1)
        best = np.minimum(best, np.linalg.norm(X - (A + t[:, None] * AB), axis=1))
    return bool((best <= tol).all())


def _longer_than(curves, X, starts, length):
    """(n,) bool: the polyline of each curve's points (not closed) is longer than
    ``length``, as ``np.linalg.norm(np.diff(X, axis=0), axis=1).sum()`` says: summed
    for all curves at once (``X`` their points one after the other, ``starts`` the
    first of each, every curve with a point), and per curve only where that sum is
    within 1e-9 of ``length`` (its summation order differs)."""
    seg = np.append(np.linalg.norm(np.diff(X, axis=0), axis=1), 0.0)
    seg[starts[1:] - 1] = 0.0   # the step from one curve's last point to the next's first
    total = np.add.reduceat(seg, starts)
    out = total > length
    for i in np.flatnonzero(np.abs(total - length) <= 1e-9 * (abs(length) + total)):
        out[i] = np.linalg.norm(np.diff(curves[i]["X"], axis=0), axis=1).sum() > length
    return out


def drop_shared_edges(curves, tol):
    """Where the plane contains an edge two faces share, both faces' sections run along
    it: the same curve twice (joined, a closed loop of zero area), or one face's piece
    of the edge inside the other's longer one; a closed face whose seam lies in the
    plane gives the seam twice (at both ends of its parameter range).  A curve longer
    than ``4 tol`` that lies within ``tol`` (the model gap and two chord errors) of
    another curve everywhere adds nothing to the section and is dropped (of two that
    contain each other, the earlier).  Shorter pieces are kept: a sliver face narrower than the gap
    is joined between its neighbours, not dropped."""
    def poly(c):
        X = c["X"]
        return np.vstack([X, X[:1]]) if c["closed"] else X

    if len(curves) < 2:
        return curves
    n = np.array([len(c["X"]) for c in curves])
    if not n.all():
        return curves   # a curve without points (never made): nothing to compare
    X = np.concatenate([c["X"] for c in curves])
    starts = np.cumsum(n) - n
    amin = np.minimum.reduceat(X, starts)
    amax = np.maximum.reduceat(X, starts)
    long_ = _longer_than(curves, X, starts, 4 * tol)
    drop = set()
    for i in np.flatnonzero(long_).tolist():
        a = curves[i]
        # the curves whose box (grown by tol) holds a's: a may lie along them
        inside = np.flatnonzero((amin[i] >= amin - tol).all(axis=1)
                                & (amax[i] <= amax + tol).all(axis=1))
        for j in inside.tolist():
            if j == i or j in drop:
                continue
            if _near_polyline(a["X"], poly(curves[j]), tol):
                drop.add(i)
                break
    return [c for k, c in enumerate(curves) if k not in drop]


def merge_point_curves(curves, exact):
    """Open curves that are points (all their points within ``exact`` of each
    other), one per spot: the first of those whose starts lie within ``exact`` of
    each other.  A plane through a cone's apex or a degenerate patch edge traces
    hundreds of such pieces at one model point (NIST CTC-01 AP242 at z = -25: 683 at
    one apex); joined, they would be that point again, or part of the curve they
    touch.

    The extents are measured over all curves at once and the distances to the spots
    over Python floats; one within a relative ``1e-9`` of ``exact`` is measured again
    as ``float(np.linalg.norm(d))`` of the one vector ``d``, so the decisions are those
    of that measure (:func:`_merge_point_curves_loop`, the loop this replaces)."""
    n = np.array([len(c["X"]) for c in curves], dtype=np.int64)
    if not len(curves) or not n.all():
        return _merge_point_curves_loop(curves, exact)
    X = np.concatenate([c["X"] for c in curves])
    starts = np.cumsum(n) - n
    ext = np.linalg.norm(np.maximum.reduceat(X, starts) - np.minimum.reduceat(X, starts),
                         axis=1)
    pt = ext <= exact
    for i in np.flatnonzero(np.abs(ext - exact) <= 1e-9 * exact).tolist():
        Y = curves[i]["X"]
        pt[i] = float(np.linalg.norm(Y.max(axis=0) - Y.min(axis=0))) <= exact
    pt &= ~np.array([bool(c["closed"]) for c in curves])
    idx = np.flatnonzero(pt)
    P = X[starts[idx]]
    sure, reach = exact * (1 - 1e-9), exact * (1 + 1e-9)
    spots = []     # (x, y, z, row of P)
    drop = np.zeros(len(curves), bool)
    for k, (x, y, z) in enumerate(P.tolist()):
        for a, b, c, j in spots:
            d = math.sqrt((x - a) ** 2 + (y - b) ** 2 + (z - c) ** 2)
            if d <= reach and (d <= sure or float(np.linalg.norm(P[k] - P[j])) <= exact):
                drop[idx[k]] = True
                break
        else:
            spots.append((x, y, z, k))
    return [c for c, d in zip(curves, drop.tolist()) if not d]


def _merge_point_curves_loop(curves, exact):
    """:func:`merge_point_curves` curve by curve."""
    keep, spots = [], []
    for c in curves:
        X = c["X"]
        if not c["closed"] and len(X) and \
                float(np.linalg.norm(X.max(axis=0) - X.min(axis=0))) <= exact:
            if any(float(np.linalg.norm(X[0] - q)) <= exact for q in spots):
                continue
            spots.append(X[0])
        keep.append(c)
    return keep


def _end_distances(curves, opens):
    """``(E, D)``: the ends of the curves ``opens`` (row 2 k the start, 2 k + 1 the end
    of ``curves[opens[k]]``) and their distances (inf on the diagonal)."""
    E = np.array([[curves[i]["X"][0], curves[i]["X"][-1]] for i in opens]).reshape(-1, 3)
    D = np.linalg.norm(E[:, None] - E[None], axis=2)
    np.fill_diagonal(D, np.inf)
    return E, D


def join_ends(curves, tol, bridged=None, exact=0.0):
    """Join open curves whose ends coincide within ``tol`` (seams, shared edges), the
    nearest pair of ends first (so a sliver face's short piece is joined between its
    neighbours rather than bridged over); close curves whose two ends meet.  An end
    point within ``exact`` of the end it is joined to is dropped as a duplicate;
    farther ones are kept (the curve then bridges the gap).  ``bridged[0]`` is raised
    to the largest distance joined.

    The pair joined next is the nearest of all open ends (a curve's own two ends
    count ``exact`` farther, and not at all with two points or fewer), ties going to
    the ends first in the list of open curves (each curve's start, then its end; a
    joined curve goes last).  The distances are measured once (a joined curve's ends
    are ends of the curves it joins) and only the pairs within ``tol + exact`` are
    kept, in a heap (any other pair is farther than ``tol``, and farther than every
    pair that can still join); above :data:`HEAP_PAIRS` of them, every pair is measured
    again at each join."""
    bridged = [0.0] if bridged is None else bridged
    curves = list(curves)
    opens = [i for i, c in enumerate(curves) if not c["closed"]]
    if not opens:
        return curves
    E, D = _end_distances(curves, opens)
    # end 2 k / 2 k + 1: start / end of opens[k]; a curve is known by its dict (a
    # joined curve is a new one); an end joined or closed has no owner any more
    owner = [curves[i] for i in opens for _ in (0, 1)]
    side = [0, 1] * len(opens)          # 0: the owner's start, 1: its end
    mate = [e ^ 1 for e in range(len(owner))]   # the other end of the same curve
    pa, pb = np.nonzero(np.triu(D <= tol + exact, 1))
    if len(pa) > HEAP_PAIRS:
        return _join_ends_each(curves, tol, bridged, exact)
    heap = [(float(D[x, y]), int(x), int(y)) for x, y in zip(pa, pb)]
    heapq.heapify(heap)

    def value(x, y):
        """The pair's distance now (None: an end is gone), with the own-curve rule."""
        cx, cy = owner[x], owner[y]
        if cx is None or cy is None:
            return None
        d = float(D[x, y])
        if cx is cy:
            return d + exact if len(cx["X"]) > 2 else np.inf
        return d

    while heap:
        # the nearest pairs (stored values only grow: a stale entry goes back)
        v, x, y = heapq.heappop(heap)
        cur = value(x, y)
        if cur is None or cur == np.inf:
            continue
        if cur != v:
            heapq.heappush(heap, (cur, x, y))
            continue
        group = [(x, y)]
        while heap and heap[0][0] == v:
            _, p, q = heapq.heappop(heap)
            cur = value(p, q)
            if cur == v:
                group.append((p, q))
            elif cur is not None and cur != np.inf:
                heapq.heappush(heap, (cur, p, q))
        if len(group) > 1:   # ties: the first in the list of open ends
            pos = {id(c): k for k, c in enumerate(c for c in curves if not c["closed"])}

            def at(e):
                return 2 * pos[id(owner[e])] + side[e]

            group.sort(key=lambda t: (min(at(t[0]), at(t[1])), max(at(t[0]), at(t[1]))))
            for t in group[1:]:
                heapq.heappush(heap, (v, *t))
            x, y = group[0]
            ea, eb = (x, y) if at(x) < at(y) else (y, x)
        else:
            ea, eb = group[0]
            if owner[ea] is owner[eb]:
                ea, eb = (ea, eb) if side[ea] == 0 else (eb, ea)
            elif not _first(curves, owner[ea], owner[eb]):
                ea, eb = eb, ea
        dist = float(np.linalg.norm(E[ea] - E[eb]))
        if not dist <= tol:
            return curves
        bridged[0] = max(bridged[0], dist)
        ci, cj = owner[ea], owner[eb]
        dup = dist <= exact
        if ci is cj:
            ci["closed"] = True
            if dup:
                for k in ("uv", "sid", "X"):
                    ci[k] = ci[k][:-1]
            owner[ea] = owner[eb] = None
            continue
        A = ci if side[ea] else _rev(ci)   # A ends at end ea
        B = _rev(cj) if side[eb] else cj   # B starts at end eb
        merged = {k: (np.concatenate([A[k], B[k][int(dup):]]) if k in ("uv", "sid", "X")
                      else A[k]) for k in A}
        merged["chord"] = max(A["chord"], B["chord"])
        # ci's other end starts the merged curve, cj's other end ends it (ea itself
        # where B was one duplicate point)
        first, last = mate[ea], (ea if len(B["X"]) <= int(dup) else mate[eb])
        for e in (ea, eb, mate[ea], mate[eb]):
            owner[e] = None
        owner[first], side[first], mate[first] = merged, 0, last
        owner[last], side[last], mate[last] = merged, 1, first
        curves = [c for c in curves if c is not ci and c is not cj] + [merged]
    return curves


HEAP_PAIRS = 20000
"""Above this many pairs of ends within reach, :func:`join_ends` measures all pairs
again at each join (:func:`_join_ends_each`; the tie groups of the heap grow
with the square of the ends stacked at one point)."""


def _join_ends_each(curves, tol, bridged, exact):
    """:func:`join_ends` measuring every pair of open ends at each join."""
    while True:
        opens = [i for i, c in enumerate(curves) if not c["closed"]]
        if not opens:
            return curves
        E, D = _end_distances(curves, opens)
        # a curve closes on itself only with > 2 points, and only where no other
        # curve's end is as near (to within ``exact``: duplicates join first)
        for k, i in enumerate(opens):
            D[2 * k, 2 * k + 1] = D[2 * k + 1, 2 * k] = (
                D[2 * k, 2 * k + 1] + exact if len(curves[i]["X"]) > 2 else np.inf)
        a, b = divmod(int(np.argmin(D)), len(E))
        dist = float(np.linalg.norm(E[a] - E[b]))
        if not (np.isfinite(D[a, b]) and dist <= tol):
            return curves
        bridged[0] = max(bridged[0], dist)
        i, j = opens[a // 2], opens[b // 2]
        dup = dist <= exact
        if i == j:
            c = curves[i]
            c["closed"] = True
            if dup:
                for k in ("uv", "sid", "X"):
                    c[k] = c[k][:-1]
            continue
        A = curves[i] if a % 2 else _rev(curves[i])   # A ends at end a
        B = _rev(curves[j]) if b % 2 else curves[j]   # B starts at end b
        merged = {k: (np.concatenate([A[k], B[k][int(dup):]]) if k in ("uv", "sid", "X")
                      else A[k]) for k in A}
        merged["chord"] = max(A["chord"], B["chord"])
        curves = [c for k, c in enumerate(curves) if k not in (i, j)] + [merged]


def _first(curves, ca, cb) -> bool:
    """Whether curve ``ca`` comes before ``cb`` in ``curves`` (both in it)."""
    for c in curves:
        if c is ca:
            return True
        if c is cb:
            return False
    raise ValueError("curves not in the list")


EDGE_REACH = 8.0
"""Open curve ends on two faces' boundaries are joined across their shared edge when
they are mutual nearest, each within ``gap`` of the other face's boundary and at most
``EDGE_REACH * gap`` apart (a plane crossing an edge whose sides are ``gap`` apart at
an angle a meets them up to ``gap / sin a`` apart: down to a = 7 degrees)."""


def join_across_edges(curves, surfs, gap, bridged):
    """Join the open ends :func:`join_ends` left where the plane crosses a shared edge obliquely
    (see EDGE_REACH); ``bridged[0]`` is raised to the largest distance joined."""
    while True:
        ends = [(i, e) for i, c in enumerate(curves) if not c["closed"] for e in (0, -1)]
        if len(ends) < 2:
            return curves
        P = np.array([curves[i]["X"][e] for i, e in ends])
        F = np.array([int(curves[i]["sid"][e]) for i, e in ends])
        D = np.linalg.norm(P[:, None] - P[None], axis=2)
        D[(F[:, None] == F[None]) | (D > EDGE_REACH * gap)] = np.inf
        np.fill_diagonal(D, np.inf)
        best = None
        for a, b in zip(*np.nonzero(np.isfinite(D))):
            if a < b and np.argmin(D[a]) == b and np.argmin(D[b]) == a \
                    and (best is None or D[a, b] < D[best]):
                if (_to_boundary(surfs[F[b]], P[a]) <= gap
                        and _to_boundary(surfs[F[a]], P[b]) <= gap):
                    best = (a, b)
        if best is None:
            return curves
        (i, ei), (j, ej) = ends[best[0]], ends[best[1]]
        bridged[0] = max(bridged[0], float(D[best]))
        if i == j:
            curves[i]["closed"] = True
            continue
        A = _rev(curves[i]) if ei == 0 else curves[i]
        B = curves[j] if ej == 0 else _rev(curves[j])
        merged = {k: (np.concatenate([A[k], B[k]]) if k in ("uv", "sid", "X") else A[k])
                  for k in A}
        merged["chord"] = max(A["chord"], B["chord"])
        curves = [c for k, c in enumerate(curves) if k not in (i, j)] + [merged]


def _to_boundary(s, p, per_piece=256):
    """Distance of the point ``p`` to the boundary of face ``s`` (see
    :func:`boundary_distance`)."""
    return float(boundary_distance(s, np.reshape(p, (1, 3)), per_piece=per_piece)[0])


def near_boundary(s, P, reach):
    """(n,) bool: ``boundary_distance(s, P, reach) <= reach``, a point settled as soon
    as a distance to some of the polyline's segments is within ``reach`` (the exact
    distance is at most that)."""
    return boundary_distance(s, P, reach, settle=True) <= reach


def boundary_distance(s, P, upto=np.inf, per_piece=256, k=8, settle=False):
    """(n,) distances of the points ``P`` (n, 3) to the boundary of face ``s``: its trim
    loops' 3-D polylines at ``per_piece`` samples per piece (within their sagitta of
    it; built once per face and kept).  Distances above ``upto`` may be reported as
    any value above it (a cheaper upper bound); with ``settle``, distances within
    ``upto`` may be reported as any value from the exact one up to ``upto`` (an upper
    bound from the nearest segments, not refined).

    Exact for the polyline: the ``k`` segments with the nearest midpoints give an upper
    bound ``d``; any other segment is at least ``r_k - h`` away (``r_k`` the k-th
    midpoint distance, ``h`` the longest half-segment), and every one at least
    ``r_1 - h``: points with ``d > r_k - h`` and ``r_1 - h <= upto`` are measured
    against all segments."""
    from scipy.spatial import cKDTree

    from geomkit.cad.gaps import boundary_samples

    key = ("boundary_polyline", per_piece)
    if key not in s._cache:
        X, _, pc = boundary_samples([s], per_piece)
        same = pc[:-1] == pc[1:]
        A, B = X[:-1][same], X[1:][same]
        s._cache[key] = (A, B, cKDTree(0.5 * (A + B)),
                         0.5 * float(np.linalg.norm(B - A, axis=1).max(initial=0.0)))
    A, B, tree, h = s._cache[key]
    P = np.asarray(P, dtype=float).reshape(-1, 3)
    if not len(P):
        return np.empty(0)
    k = min(k, len(A))
    r, j = tree.query(P, k)
    r, j = np.reshape(r, (len(P), k)), np.reshape(j, (len(P), k))
    out = _segment_distances(P[:, None, :], A[j], B[j]).min(axis=1)
    far = (out > r[:, -1] - h) & (r[:, 0] - h <= upto)
    if settle:
        far &= out > upto
    far = np.flatnonzero(far) if k < len(A) else []
    # the uncertain points against 8 times more nearest segments, until certified
    # (the same minimum as against all of them) or nearly all are needed
    while len(far) and 8 * k < len(A) // 2:
        k *= 8
        r, j = tree.query(P[far], k)
        d = _segment_distances(P[far, None, :], A[j], B[j]).min(axis=1)
        out[far] = d
        far = far[(d > r[:, -1] - h) & ((d > upto) if settle else True)]
    step = max(1, (1 << 20) // len(A))   # points per block: ~1e6 pairs
    for i in range(0, len(far), step):
        f = far[i:i + step]
        out[f] = _segment_distances(P[f, None, :], A[None], B[None]).min(axis=1)
    return out


def _segment_distances(P, A, B):
    """Distances of points ``P`` to segments ``A B`` (broadcast over leading axes)."""
    AB = B - A
    L2 = np.einsum("...j,...j->...", AB, AB)
    t = np.clip(np.einsum("...j,...j->...", P - A, AB) / np.where(L2 > 0, L2, 1.0), 0, 1)
    return np.linalg.norm(P - (A + t[..., None] * AB), axis=-1)


def _rev(c):
    return {k: (v[::-1].copy() if k in ("uv", "sid", "X") else v) for k, v in c.items()}
