"""Closing trim loops whose pieces meet within the file's tolerance, not exactly.

CAD files carry gaps of 1e-5 to 1e-3 of the parameter domain between consecutive
pcurves of a boundary.  Each gap is bridged by a straight UV segment; the exact pieces
are kept as they are.  A gap above :data:`GAP_TOL` x the domain size is not a rounding
gap: the face is refused (:class:`Unsupported`), never guessed.
"""

from __future__ import annotations

import numpy as np

from geomkit.tolerances import GAP_TOL, PCURVE_CLIP_TOL
from geomkit.nurbs.surface import TrimCurve
from geomkit.nurbs.trims import TrimLoop, evaluate_trim_curve, loop_pack, readonly
from geomkit.cad.uvmap import map_pcurve
from geomkit._kernels.trim_loops import (box_clip, loop_joins, segment_spread,
                                         shifted_points)

__all__ = ["close_gaps", "chain", "reverse", "Unsupported", "GAP_TOL", "clip_in_3d",
           "same_point_3d", "finish_loop"]


class Unsupported(Exception):
    """A face or entity that cannot be read exactly (the message says which and why)."""


_NO_BOX = np.array([-np.inf, np.inf, -np.inf, np.inf])


def _joins(pieces, domain=None):
    """``(gaps, inside)``: the UV distance from each piece's end to the next one's
    start (cyclic: the last piece's end to the first's start) and whether every
    control point lies in ``domain`` (closed), in one compiled call."""
    if not pieces:
        return np.zeros(0), True
    off = [0]
    for c in pieces:
        off.append(off[-1] + c.control_points.shape[0])
    Q = np.concatenate([c.control_points for c in pieces])
    box = _NO_BOX if domain is None else np.array([*domain[0], *domain[1]], dtype=float)
    return loop_joins(Q, np.array(off, dtype=np.int64), box)


def join_gaps(pieces) -> np.ndarray:
    """The UV distance from each piece's end to the next one's start (cyclic: the last
    piece's end to the first's start), all at once."""
    return _joins(pieces)[0]


def reverse(c: TrimCurve) -> TrimCurve:
    """The same trim curve traversed the other way."""
    U = np.asarray(c.knots)
    return TrimCurve.create(c.degree, U[0] + U[-1] - U[::-1], c.control_points[::-1],
                            None if np.all(c.weights == 1) else c.weights[::-1])


def shift(c: TrimCurve, d) -> TrimCurve:
    """The trim curve translated by ``d`` in UV (one period of a closed direction):
    ``TrimCurve.create`` of the moved points with ``c``'s knots and weights, which
    were checked when ``c`` was made (its points ``Q w / w`` when rational, as create
    stores them); a point that is not finite goes through create, which names it."""
    w = c.weights
    P = c.control_points
    d = np.asarray(d, dtype=np.float64)
    if (P.dtype == np.float64 and P.ndim == 2 and P.shape[1] == 2 and d.shape == (2,)
            and w.dtype == np.float64 and w.shape == (P.shape[0],)):
        Q, unit, finite = shifted_points(P, w, d)  # (one call: the same values)
        if finite:
            return TrimCurve(c.degree, c.knots, readonly(Q), w)
        return TrimCurve.create(c.degree, c.knots, P + d, None if unit else w)
    Q = np.asarray(P) + d
    unit = bool((w == 1).all())
    if not (Q.dtype == np.float64 and Q.shape == c.control_points.shape
            and np.isfinite(Q).all()):
        return TrimCurve.create(c.degree, c.knots, Q, None if unit else w)
    if not unit:
        Q = Q * w[:, None] / w[:, None]
    return TrimCurve(c.degree, c.knots, readonly(Q), w)


def chain(pieces, size, periods=(0.0, 0.0), domain=None):
    """Pieces reordered and reversed so that each starts nearest where the previous
    one ends (files that list a composite's pieces against its direction, e.g. OCC's
    pcurves on periodic surfaces).  Greedy from the first piece.  ``periods``: the
    UV periods of closed directions (0 for open); a piece may then also move by one
    period (a pcurve given on the other side of a seam), preferably to where it lies
    in ``domain`` ((u0, u1), (v0, v1))."""
    du, dv = periods
    moves = [np.zeros(2)] + [np.array(m, float) for m in
                             ([du, 0], [-du, 0]) * bool(du) + ([0, dv], [0, -dv]) * bool(dv)]
    rest = list(pieces[1:])
    out = [pieces[0]]
    while rest:
        prev = out[-1]
        best = None
        for k, c in enumerate(rest):
            for rev in (False, True):
                a, b = (c.end, c.start) if rev else (c.start, c.end)
                for m in moves:
                    d = float(np.hypot(*(a + m - prev.end)))
                    # prefer a join within the gap tolerance, then one that does not
                    # run back along the previous piece (a seam edge's other copy),
                    # then one without a period move, then the nearest
                    back = float(np.hypot(*(b + m - prev.start))) <= 1e-9 * size
                    out_of = domain is not None and not (_inside(a + m, domain, size) and
                                                         _inside(b + m, domain, size))
                    key = (d > GAP_TOL * size, out_of, back, bool(m.any()), d)
                    if best is None or key < best[0]:
                        best = (key, k, rev, m)
        _, k, rev, m = best
        c = rest.pop(k)
        c = reverse(c) if rev else c
        out.append(shift(c, m) if m.any() else c)
    return out


def _inside(p, domain, size) -> bool:
    (u0, u1), (v0, v1) = domain
    e = GAP_TOL * size
    return u0 - e <= p[0] <= u1 + e and v0 - e <= p[1] <= v1 + e


def close_gaps(pieces, domain, where: str, same_point=None, gaps=None):
    """``(pieces with bridging segments, [gap sizes in UV])``.

    With ``same_point(uv_a, uv_b) -> bool`` (the two UV points are one model point: a
    pole, a degenerate edge), a loop with a gap that is neither small nor one point is
    first re-chained (:func:`chain`), and a larger gap whose ends are one model point is
    bridged too (the segment maps to that point: a pole) — unless the same pieces, none
    reversed, close in another order without it (a loop listed out of order across a
    seam corner, whose UV images of one point are not joined by a degenerate edge):
    then the loop is re-chained instead.  ``gaps``: :func:`join_gaps` of ``pieces``
    when the caller has it."""
    (u0, u1), (v0, v1) = domain
    size = max(u1 - u0, v1 - v0)

    def far(a, b):
        return float(np.hypot(*(a.end - b.start))) > GAP_TOL * size

    def bad(a, b):
        return far(a, b) and not same_point(a.end, b.start)

    def joins(p):
        return [(a, p[(k + 1) % len(p)]) for k, a in enumerate(p)]

    g = join_gaps(pieces) if gaps is None else gaps
    if same_point is not None and len(pieces) > 1 and bool((g > GAP_TOL * size).any()):
        chained = chain(pieces, size)
        if any(bad(a, b) for a, b in joins(pieces)):
            pieces = chained
        elif not any(far(a, b) for a, b in joins(chained)) and \
                all(any(c is p for p in pieces) for c in chained):
            # the far gaps are one model point each, yet the same pieces, in another
            # order and none reversed, close without them: a loop listed out of order
            # across a seam corner (OCC writes a closed torus face so).  A straight UV
            # bridge would map to a curve across the face, not to one point.
            pieces = chained
        g = join_gaps(pieces)
    if not bool((g > 1e-9 * size).any()):  # closed to rounding: nothing to bridge
        return list(pieces), []
    out, gaps = [], []
    for k, a in enumerate(pieces):
        out.append(a)
        b = pieces[(k + 1) % len(pieces)]
        gap = float(g[k])
        if gap <= 1e-9 * size:
            continue
        if gap > GAP_TOL * size and not (same_point and same_point(a.end, b.start)):
            raise Unsupported(f"{where}: pieces {k} and {(k + 1) % len(pieces)} are "
                              f"{gap:.3g} apart in UV (more than {GAP_TOL:g} of the domain)")
        if gap <= GAP_TOL * size:  # a pole bridge is not a rounding gap
            gaps.append(gap)
        out.append(TrimCurve.polyline([a.end, b.start]))
    return out, gaps


def _points(c) -> np.ndarray:
    """A piece's control points as a float64 (n, 2) array (as stored, or a copy)."""
    P = c.control_points
    if P.dtype == np.float64 and P.ndim == 2 and P.shape[1] == 2:
        return P
    return np.array(P, dtype=np.float64).reshape(-1, 2)


def clip_to_domain(pieces, domain, rel: float, refit_rel: float = 0.0):
    """Move control points that lie at most ``rel`` x the domain size outside the
    parameter domain onto its edge (files round the domain ends: 0.011739075 vs
    0.0117390748871053; OCC's pcurves overshoot by up to ~1e-5); the curve moves by at
    most that much.  Points farther out are kept, and validation reports them.
    With ``refit_rel``, a piece whose *points* leave the domain by at most
    ``refit_rel`` x the domain size (OCC's re-approximated pcurves overshoot a
    surface's domain by up to ~0.3 %: outside the domain there is no surface, so the
    face ends at the domain edge) is re-fitted to its points clipped to the domain.
    Returns ``(pieces, [distances moved])``."""
    (u0, u1), (v0, v1) = domain
    eps = rel * max(u1 - u0, v1 - v0)
    box = float(u0), float(u1), float(v0), float(v1)
    out, moves = [], []
    for c in pieces:
        # inside, the points clipped and how far, in one call (numpy's values)
        inside, Q, moved = box_clip(_points(c), *box)
        if inside:
            out.append(c)  # inside: nothing to move
            continue
        if moved > eps and refit_rel > 0:  # the polygon leaves; does the curve itself?
            c, moved = _refit_clipped(c, (u0, u1, v0, v1),
                                      refit_rel * max(u1 - u0, v1 - v0), eps)
            P = np.array(c.control_points)
            Q = np.column_stack([np.clip(P[:, 0], u0, u1), np.clip(P[:, 1], v0, v1)])
            moved = max(moved, float(np.abs(Q - P).max()))
        if moved == 0 or moved > max(eps, refit_rel * max(u1 - u0, v1 - v0)):
            out.append(c)
            continue
        moves.append(moved)
        # the clipped points kept as they are (create's ``Q w / w`` would put a
        # rational piece's clipped point back outside by a unit in the last place);
        # the knots and weights are the valid piece's
        Q.setflags(write=False)
        out.append(TrimCurve(c.degree, c.knots, Q, c.weights))
    return out, moves


def _refit_clipped(c, box, eps, fit_tol):
    """A curve whose control polygon leaves the domain but whose points leave it by at
    most ``eps``: re-fitted (cubic, within ``fit_tol / 100``) to its
    points clipped to the domain.  Returns ``(curve, how far its points were out)``."""

    u0, u1, v0, v1 = box
    p = c.degree
    t = np.linspace(c.knots[p], c.knots[-p - 1], 257)
    X = evaluate_trim_curve(c, t)[:, 0, :]
    out = max(0.0, float(u0 - X[:, 0].min()), float(X[:, 0].max() - u1),
              float(v0 - X[:, 1].min()), float(X[:, 1].max() - v1))
    if out > eps:
        return c, np.inf
    if out == 0:
        return c, 0.0
    m, err = map_pcurve(c, lambda u: np.clip(u, u0, u1), lambda v: np.clip(v, v0, v1),
                        fit_tol / 100)
    return m, out + err


# ------------------------------------------------------- repairs measured in 3-D
def _extrapolation_error(base, uv, domain):
    """First-order 3-D distance between the surface continued to ``uv`` (m, 2) and its
    value at ``uv`` clamped to ``domain``: ``|S_u| du + |S_v| dv`` at the clamped point
    (0 at a pole, where a whole parameter line is one point).  Returns
    ``(clamped uv, distances)``."""
    (u0, u1), (v0, v1) = domain
    q = np.column_stack([np.clip(uv[:, 0], u0, u1), np.clip(uv[:, 1], v0, v1)])
    d = np.abs(uv - q)
    D = base.derivatives(q, 1)
    err = (np.linalg.norm(D[:, 1, 0], axis=1) * d[:, 0]
           + np.linalg.norm(D[:, 0, 1], axis=1) * d[:, 1])
    return q, err


def clip_in_3d(pieces, base, tol3d: float, samples: int = 257):
    """Pieces whose points leave the domain of ``base`` (the untrimmed surface) by an
    amount the model cannot see: each point outside is moved onto the domain edge, and
    the move is measured in 3-D (:func:`_extrapolation_error`: the surface's speed
    across the edge times the overshoot, 0 at a pole).  A piece whose largest move is
    at most ``tol3d`` (the file's own tolerance) is re-fitted to its clipped points;
    others are kept, for validation to report.  Returns ``(pieces, [3-D moves])``."""
    (u0, u1), (v0, v1) = domain = base.domain
    size = max(u1 - u0, v1 - v0)
    box = float(u0), float(u1), float(v0), float(v1)
    out, moves = [], []
    for c in pieces:
        if box_clip(_points(c), *box)[0]:  # every point in the domain
            out.append(c)
            continue
        p = c.degree
        t = np.linspace(c.knots[p], c.knots[-p - 1], samples)
        X = evaluate_trim_curve(c, t)[:, 0, :]
        _, err = _extrapolation_error(base, X, domain)
        worst = float(err.max())
        if worst > tol3d:
            out.append(c)
            continue
        m, _ = map_pcurve(c, lambda u: np.clip(u, u0, u1), lambda v: np.clip(v, v0, v1),
                          1e-9 * size)
        # the re-fit against its target, in 3-D: S(m(t)) against S(clip(c(t)))
        q = m.degree
        s = m.knots[q] + (t - t[0]) / (t[-1] - t[0]) * (m.knots[-q - 1] - m.knots[q])
        Z = evaluate_trim_curve(m, s)[:, 0, :]
        Z = np.column_stack([np.clip(Z[:, 0], u0, u1), np.clip(Z[:, 1], v0, v1)])
        Y = np.column_stack([np.clip(X[:, 0], u0, u1), np.clip(X[:, 1], v0, v1)])
        fit = float(np.linalg.norm(base.evaluate(Z) - base.evaluate(Y), axis=1).max())
        out.append(m)
        moves.append(worst + fit)
    return out, moves


def same_point_3d(base, tol3d: float, samples: int = 17):
    """``same(a, b)`` for :func:`close_gaps`: the straight UV segment from ``a`` to
    ``b`` (clamped to the domain) maps within ``tol3d`` of one model point (a pole or
    a degenerate edge, or a gap the file's tolerance covers).  The largest distance
    found is kept in ``same.errors``."""
    (u0, u1), (v0, v1) = base.domain
    net = (base.homogeneous, base.degree_u, base.degree_v, base.knots_u, base.knots_v)

    def same(a, b) -> bool:
        d = segment_spread(*net, float(a[0]), float(a[1]), float(b[0]), float(b[1]),
                           u0, u1, v0, v1, samples)
        if d <= tol3d:
            same.errors.append(d)
            return True
        return False

    same.errors = []
    return same


def finish_loop(pieces, base, periods, ftol: float, what: str):
    """``(loop, gaps, repairs)``: one trim loop's pieces made a closed
    :class:`~geomkit.nurbs.trims.TrimLoop` on ``base`` (no pieces: an empty list):
    chained (edge order, seam sides: ``periods`` of the closed directions) when
    consecutive pieces do not meet, control points just outside the domain
    snapped onto it, what is left outside or open repaired when the face's own
    tolerance ``ftol`` covers it, measured in 3-D (:func:`clip_in_3d`,
    :func:`same_point_3d`), rounding gaps bridged (:func:`close_gaps`).  ``gaps``: the
    UV sizes of the moves and bridges; ``repairs``: the 3-D sizes of the repairs (the
    face's ``approx_error`` holds them)."""
    (u0, u1), (v0, v1) = domain = base.domain
    size = max(u1 - u0, v1 - v0)
    if pieces:  # packed once: the surface's check of the loop reads the same arrays
        loop = TrimLoop(tuple(pieces))
        pk = loop_pack(loop)
        gaps, inside = loop_joins(pk[0], pk[2], np.array([u0, u1, v0, v1]))
        if inside and not bool((gaps > 1e-9 * size).any()):  # closed, in the domain
            return loop, [], []
    else:
        return [], [], []
    probe = same_point_3d(base, ftol)  # a gap at a pole is not out of order
    far = np.flatnonzero(gaps > GAP_TOL * size).tolist()
    nxt = pieces[1:] + pieces[:1]
    if any(not probe(pieces[k].end, nxt[k].start) for k in far):
        pieces, gaps = chain(pieces, size, periods, domain), None
        inside = _joins(pieces, domain)[1]
    if inside:  # nothing to clip
        moved, moved3 = [], []
    else:
        pieces, moved = clip_to_domain(pieces, domain, PCURVE_CLIP_TOL, GAP_TOL)
        pieces, moved3 = clip_in_3d(pieces, base, ftol)
        gaps = None
    same = same_point_3d(base, ftol)
    pieces, g = close_gaps(pieces, domain, what, same, gaps)
    return TrimLoop(tuple(pieces)), moved + g, moved3 + same.errors
