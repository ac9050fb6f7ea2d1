"""Trim curves: the 2-D NURBS pieces of a trim loop in a surface's parameter plane.

:class:`TrimCurve` and :class:`TrimLoop` hold validated, read-only arrays;
:func:`parse_loop` builds a loop from any of the accepted input forms and
:func:`check_loop` validates it against a surface domain; :func:`pack_segments` packs
loops as rational Bézier segments for the classification and distance kernels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from geomkit._kernels.bezier import curve_points, de_casteljau_split, decompose, insert_knot
from geomkit._kernels.trim_loops import loop_check, loop_points, polyline_knots
from geomkit.validate import as_float_array, as_int, check_knots
from geomkit.errors import InvalidInputError, InvalidTrimError

__all__ = ["TrimCurve", "TrimLoop", "parse_loop", "check_loop", "pack_segments", "concat_segments",
           "evaluate_trim_curve", "readonly", "clamp_knots", "is_clamped", "packed_trims",
           "packed_loops", "starts"]


def readonly(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=np.float64)
    a.setflags(write=False)
    return a


def is_clamped(U: np.ndarray, p: int) -> bool:
    """Whether the non-decreasing knot vector ``U`` of degree ``p`` is clamped: its
    first and last ``p + 1`` knots equal (so its ends ``p`` apart are equal)."""
    return bool(U[0] == U[p] and U[-1] == U[-p - 1])


def clamp_knots(Pw: np.ndarray, p: int, U: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Clamp an unclamped knot vector by knot insertion; the curve is unchanged.

    ``Pw`` (n, dim) homogeneous rows.  Inserts the domain ends ``U[p]`` and ``U[n]``
    until they have multiplicity ``p`` and drops the parts outside the domain.
    """
    n = Pw.shape[0]
    a, b = U[p], U[n]
    if is_clamped(U, p):
        return Pw, U
    for end in (a, b):
        s = int(np.count_nonzero(U == end))
        if s < p:
            Pw, U = insert_knot(np.ascontiguousarray(Pw), p, U, end, p - s)
    first_a = int(np.nonzero(U == a)[0][0])
    start = first_a + int(np.count_nonzero(U == a)) - 1 - p  # span of a, minus p
    first_b = int(np.nonzero(U == b)[0][0])
    newU = U[start: first_b + p + 1].copy()
    newU[: p + 1] = a
    newU[-(p + 1):] = b
    return np.ascontiguousarray(Pw[start: first_b]), newU


SEGMENT_KNOTS = np.array([0.0, 0.0, 1.0, 1.0])
"""The knots of a straight segment as a trim curve (read-only)."""
SEGMENT_KNOTS.setflags(write=False)
_TWO_ONES = np.ones(2)
_TWO_ONES.setflags(write=False)


@dataclass(frozen=True, eq=False)
class TrimCurve:
    """A 2-D NURBS curve in a surface's parameter plane (one piece of a trim loop).

    Attributes
    ----------
    degree : int
    knots : (n + degree + 1,) float, clamped.
    control_points : (n, 2) float, in (u, v).
    weights : (n,) float, all 1 for a polyline or plain B-spline.
    """

    degree: int
    knots: np.ndarray
    control_points: np.ndarray
    weights: np.ndarray

    @classmethod
    def create(cls, degree, knots, control_points, weights=None, field="trim") -> "TrimCurve":
        """Validate and build a trim curve (unclamped knot vectors are clamped)."""
        p = as_int(degree, f"{field}.degree", minimum=1, error=InvalidTrimError)
        P = as_float_array(control_points, f"{field}.control_points", shape=(None, 2),
                           error=InvalidTrimError)
        n = P.shape[0]
        if n < p + 1:
            raise InvalidTrimError(f"{n} control points but degree {p} needs at least {p + 1}",
                                   f"{field}.control_points")
        U = check_knots(knots, p, n, f"{field}.knots", InvalidTrimError)
        if weights is None:
            w = np.ones(n)
        else:
            w = as_float_array(weights, f"{field}.weights", shape=(n,), error=InvalidTrimError)
            if np.any(w <= 0):
                i = int(np.argmin(w))
                raise InvalidTrimError(f"weights must be > 0, weight[{i}] = {float(w[i])!r}",
                                       f"{field}.weights")
        Pw = np.empty((n, 3))
        Pw[:, :2] = P * w[:, None]
        Pw[:, 2] = w
        Pw, U = clamp_knots(Pw, p, U)
        w = Pw[:, 2].copy()
        return cls(p, readonly(U), readonly(Pw[:, :2] / w[:, None]), readonly(w))

    @classmethod
    def polyline(cls, points, field="trim") -> "TrimCurve":
        """A polyline (k, 2) as a degree-1 curve with one knot per vertex (chord length)."""
        if type(points) in (list, tuple, np.ndarray) and len(points) == 2:
            # a segment (most polylines: bridges, seams): its knots are [0, 0, 1, 1]
            P = np.array(points, dtype=np.float64)
            if P.shape == (2, 2):  # (the tests on four floats: numpy's per-call cost
                a, b, c, d = P.ravel().tolist()  # is most of it on so few)
                if (math.isfinite(a) and math.isfinite(b) and math.isfinite(c)
                        and math.isfinite(d) and (a != c or b != d)):
                    P.setflags(write=False)
                    return cls(1, SEGMENT_KNOTS, P, _TWO_ONES)
        P = points if type(points) is np.ndarray and points.dtype == np.float64 else None
        if P is None or P.ndim != 2 or P.shape[1] != 2:  # the checks with their messages
            P = as_float_array(points, field, shape=(None, 2), error=InvalidTrimError)
        if P.shape[0] < 2:
            raise InvalidTrimError(f"a polyline needs at least 2 points, got {P.shape[0]}", field)
        status, P, U = polyline_knots(P)
        if status == 1:
            as_float_array(points, field, error=InvalidTrimError)  # names the value
        if status:
            raise InvalidTrimError("degenerate polyline: all points coincide", field)
        return cls(1, readonly(U), readonly(P), readonly(np.ones(P.shape[0])))

    @property
    def is_polyline(self) -> bool:
        return self.degree == 1 and bool(np.all(self.weights == 1.0))

    @property
    def start(self) -> np.ndarray:
        return self.control_points[0]

    @property
    def end(self) -> np.ndarray:
        return self.control_points[-1]

    @property
    def homogeneous(self) -> np.ndarray:
        """(n, 3) homogeneous control points ``(w u, w v, w)``."""
        Pw = np.empty((self.control_points.shape[0], 3))
        Pw[:, :2] = self.control_points * self.weights[:, None]
        Pw[:, 2] = self.weights
        return Pw

    def to_dict(self) -> dict:
        """The ``geomkit-case/1`` form of this piece."""
        if self.is_polyline:
            return {"degree": 1, "knots": self.knots.tolist(),
                    "control_points": self.control_points.tolist()}
        return {"degree": self.degree, "knots": self.knots.tolist(),
                "control_points": self.control_points.tolist(),
                "weights": self.weights.tolist()}


@dataclass(frozen=True, eq=False)
class TrimLoop:
    """A closed chain of trim curves, in order; the end of each piece meets the next."""

    pieces: tuple

    @property
    def is_polyline(self) -> bool:
        return all(c.is_polyline for c in self.pieces)

    def to_case(self):
        """The ``geomkit-case/1`` form: a point list for a single polyline piece,
        a curve dict for a single NURBS piece, else a list of curve dicts."""
        if len(self.pieces) == 1:
            c = self.pieces[0]
            return c.control_points.tolist() if c.is_polyline else c.to_dict()
        return [c.to_dict() for c in self.pieces]


def parse_loop(loop, field) -> TrimLoop:
    if isinstance(loop, TrimLoop):
        return loop
    if isinstance(loop, (TrimCurve, dict)):
        raw = [loop]
    elif isinstance(loop, (list, tuple)) and loop and isinstance(loop[0], (TrimCurve, dict)):
        raw = list(loop)
    else:
        raw = [("polyline", loop)]
    pieces = []
    for k, item in enumerate(raw):
        f = field if len(raw) == 1 else f"{field}[{k}]"
        if isinstance(item, TrimCurve):
            pieces.append(item)
        elif isinstance(item, tuple) and item[0] == "polyline":
            pieces.append(TrimCurve.polyline(item[1], f))
        elif isinstance(item, dict):
            missing = [key for key in ("degree", "knots", "control_points") if key not in item]
            if missing:
                raise InvalidTrimError(f"trim curve is missing {', '.join(missing)}", f)
            pieces.append(TrimCurve.create(item["degree"], item["knots"], item["control_points"],
                                           item.get("weights"), f))
        else:
            raise InvalidTrimError(f"expected a polyline or a NURBS curve dict, got "
                                   f"{type(item).__name__}", f)
    return TrimLoop(tuple(pieces))


def first_point_outside(curve: TrimCurve, box: np.ndarray, tol: float):
    """A point of ``curve`` outside ``box`` (u0, u1, v0, v1), or None if it stays in.

    Exact up to ``tol``: Bézier pieces whose control points lie in the box are inside
    (convex hull property); others are split until a piece end point is found
    outside or the piece is smaller than ``tol``.
    """
    xy = curve.control_points  # the curve lies in their convex hull (weights > 0)
    if ((xy[:, 0] >= box[0]) & (xy[:, 0] <= box[1]) & (xy[:, 1] >= box[2])
            & (xy[:, 1] <= box[3])).all():
        return None
    Q, _ = decompose(curve.homogeneous, curve.degree, curve.knots)
    stack = list(Q)
    while stack:
        piece = stack.pop()
        xy = piece[:, :2] / piece[:, 2:3]
        if ((xy[:, 0] >= box[0]) & (xy[:, 0] <= box[1]) & (xy[:, 1] >= box[2])
                & (xy[:, 1] <= box[3])).all():
            continue
        for end in (xy[0], xy[-1]):
            if not (box[0] <= end[0] <= box[1] and box[2] <= end[1] <= box[3]):
                return end
        if np.ptp(xy, axis=0).max() <= tol:
            continue
        left = np.empty_like(piece)
        right = np.empty_like(piece)
        de_casteljau_split(piece, 0.5, left, right)
        stack += [left, right]
    return None


def _packed(pcs):
    """A loop's pieces as :func:`~geomkit._kernels.trim_loops.loop_points` takes them."""
    n, u = [0], [0]
    for c in pcs:
        n.append(n[-1] + c.control_points.shape[0])
        u.append(u[-1] + c.knots.shape[0])
    return (np.concatenate([c.control_points for c in pcs]),
            np.concatenate([c.weights for c in pcs]), np.array(n, dtype=np.int64),
            np.array([c.degree for c in pcs], dtype=np.int64),
            np.concatenate([c.knots for c in pcs]), np.array(u, dtype=np.int64))


def loop_pack(loop: TrimLoop) -> tuple:
    """:func:`_packed` of a loop's pieces, kept with the loop (it is immutable): a
    reader that tests its loops before building the surface packs each once."""
    pk = loop.__dict__.get("_pack")
    if pk is None:
        pk = _packed(loop.pieces)
        object.__setattr__(loop, "_pack", pk)
    return pk


def packed_trims(surface):
    """The trim pieces of ``surface``, every loop's in order, as flat arrays for the
    kernels: ``(CP (n, 2), W (n,), K (k,), deg (m,), cp_off (m+1,), k_off (m+1,),
    loop_first (loops+1,))``, piece ``c``'s control points ``CP[cp_off[c]:cp_off[c+1]]``
    (weights ``W``), its knots ``K[k_off[c]:k_off[c+1]]``, loop ``i``'s pieces
    ``loop_first[i]:loop_first[i+1]``.  Built from each loop's pack, kept with the
    loop (:func:`loop_pack`: the reader has made it when it
    checked the loop); a single loop's arrays are its pack's own (read only here)."""
    packs = [loop_pack(loop) for loop in surface.trim]
    if len(packs) == 1:
        CP, W, cp_off, deg, K, k_off = packs[0]
        return CP, W, K, deg, cp_off, k_off, np.array([0, len(deg)], dtype=np.int64)
    cp_off = [packs[0][2]]
    k_off = [packs[0][5]]
    first = [0]
    for pk in packs:
        first.append(first[-1] + len(pk[3]))
    for pk in packs[1:]:
        cp_off.append(pk[2][1:] + cp_off[-1][-1])
        k_off.append(pk[5][1:] + k_off[-1][-1])
    return (np.concatenate([pk[0] for pk in packs]), np.concatenate([pk[1] for pk in packs]),
            np.concatenate([pk[4] for pk in packs]), np.concatenate([pk[3] for pk in packs]),
            np.concatenate(cp_off), np.concatenate(k_off), np.array(first, dtype=np.int64))


def packed_loops(surfaces) -> tuple:
    """The trim pieces of every loop of ``surfaces`` as :func:`packed_trims` packs
    one surface's, all surfaces' in one set of flat arrays: ``(CP, W, K, deg, cp_off,
    k_off, loop_first, face_loop (len(surfaces)+1,))``, surface ``f``'s loops
    ``face_loop[f]:face_loop[f+1]`` (the same values as the surfaces' packs
    concatenated, offsets moved to their places), each loop's arrays once (its kept
    pack, :func:`loop_pack`) and a dozen numpy calls in all, not a dozen a surface."""
    packs = [loop_pack(loop) for s in surfaces for loop in s.trim]
    CPs, Ws, cps, degs, Ks, kos = zip(*packs)
    pieces = np.fromiter(map(len, degs), dtype=np.int64, count=len(packs))
    loop_first = starts(pieces)
    face_loop = starts(np.fromiter((len(s.trim) for s in surfaces), dtype=np.int64,
                                    count=len(surfaces)))
    # each loop's offsets (m+1 from 0) moved by its base; a loop's first (0 + base)
    # is the loop before's last (its count + its base): dropped after the first loop
    size = pieces + 1
    first = starts(size)[:-1]
    keep = np.ones(int(first[-1] + size[-1]), dtype=bool)
    keep[first[1:]] = False
    cp_off = np.concatenate(cps)
    k_off = np.concatenate(kos)
    cp_off += np.repeat(starts(cp_off[first + pieces])[:-1], size)
    k_off += np.repeat(starts(k_off[first + pieces])[:-1], size)
    return (np.concatenate(CPs), np.concatenate(Ws), np.concatenate(Ks), np.concatenate(degs),
            cp_off[keep], k_off[keep], loop_first, face_loop)


def starts(counts: np.ndarray) -> np.ndarray:
    """``[0, c0, c0 + c1, ...]`` (len(counts) + 1,) int64."""
    out = np.zeros(len(counts) + 1, dtype=np.int64)
    np.add.accumulate(counts, out=out[1:])
    return out


def loop_samples(loop: TrimLoop, per_segment: int = 24) -> np.ndarray:
    """Points along a loop (for validation only: area, domain containment): a
    polyline piece's points, a curved piece at ``per_segment`` parameters a span
    (fewer on a piece of many spans: at least ``2 per_segment`` over it and 2 a span)
    and its end; every piece in one compiled call."""
    return loop_points(*loop_pack(loop), int(per_segment))


def check_loop(loop: TrimLoop, domain, close: float, field: str) -> None:
    """Validate a loop against the domain ``((u0, u1), (v0, v1))``: the pieces join
    within ``close``, the loop stays in the domain (to ``close``) and encloses area.
    Raises :class:`InvalidTrimError` naming ``field``.  The tests are one compiled
    call (:func:`~geomkit._kernels.trim_loops.loop_check`)."""
    (u0, u1), (v0, v1) = domain
    pcs = loop.pieces
    if not pcs:
        raise InvalidTrimError("a loop of no pieces", field)
    close = float(close)
    box = np.array([u0 - close, u1 + close, v0 - close, v1 + close])
    i, gap, inside, area, spread = loop_check(*loop_pack(loop), 24, close, box)
    if i >= 0:   # the first gap too wide
        c, nxt = pcs[i], pcs[(i + 1) % len(pcs)]
        if len(pcs) == 1:
            what = (f"loop is open: it ends at {c.end.tolist()}, {gap:.3g} away "
                    f"from its start {nxt.start.tolist()}")
        else:
            j = (i + 1) % len(pcs)
            what = (f"pieces do not join: piece {i} ends at {c.end.tolist()} but "
                    f"piece {j} starts at {nxt.start.tolist()}, {gap:.3g} away")
        raise InvalidTrimError(f"{what} (closure tolerance {close:.3g})", field)
    for c in () if inside else pcs:  # (inside: every curve is, by its convex hull)
        bad = first_point_outside(c, box, close)
        if bad is not None:
            raise InvalidTrimError(
                f"loop leaves the parameter domain [{u0}, {u1}] x [{v0}, {v1}] at "
                f"({bad[0]:.6g}, {bad[1]:.6g})", field)
    if abs(area) <= (close * close) or not spread:
        raise InvalidTrimError(f"degenerate loop: enclosed area {area:.3g} in UV", field)


def pack_segments(loops) -> tuple:
    """All trim loops as homogeneous rational Bézier segments.

    Returns ``seg`` (S, pmax+1, 3), ``deg`` (S,), ``loop`` (S,) and the loop count.
    Gaps between consecutive pieces (within the closure tolerance) are bridged by
    straight segments so that every loop is exactly closed.
    """
    pieces = []  # (deg, Q (p+1, 3), loop)
    for k, loop in enumerate(loops):
        n = len(loop.pieces)
        for i, c in enumerate(loop.pieces):
            Q, _ = decompose(c.homogeneous, c.degree, c.knots)
            for s in range(Q.shape[0]):
                pieces.append((c.degree, Q[s], k))
            nxt = loop.pieces[(i + 1) % n]
            if np.any(c.end != nxt.start):
                bridge = np.array([[*c.end, 1.0], [*nxt.start, 1.0]])
                pieces.append((1, bridge, k))
    pmax = max((d for d, _, _ in pieces), default=1)
    seg = np.ones((len(pieces), pmax + 1, 3))
    deg = np.empty(len(pieces), dtype=np.int64)
    lp = np.empty(len(pieces), dtype=np.int64)
    for s, (d, Q, k) in enumerate(pieces):
        seg[s, : d + 1] = Q
        deg[s] = d
        lp[s] = k
    return seg, deg, lp, len(loops)


def concat_segments(surfaces, min_rows: int = 0) -> tuple:
    """The trim segments of several surfaces in one padded array for the kernels.

    Returns ``seg`` (S, pmax+1, 3) (rows beyond a segment's degree hold ones), ``deg``
    and ``loop`` (S,) int64 and ``off`` (n, 3) int64: surface i's segments are rows
    ``off[i, 0]`` to ``off[i, 0] + off[i, 1]`` and it has ``off[i, 2]`` loops (zeros for
    an untrimmed surface).  At least ``min_rows`` rows (padding: degree 1, loop 0) and
    ``pmax >= 1``."""
    parts = [s.trim_segments() if s.is_trimmed else None for s in surfaces]
    p1 = max([2] + [q[0].shape[1] for q in parts if q is not None])
    total = sum(q[0].shape[0] for q in parts if q is not None)
    rows = max(total, min_rows)
    seg = np.ones((rows, p1, 3))
    deg = np.ones(rows, dtype=np.int64)
    lp = np.zeros(rows, dtype=np.int64)
    off = np.zeros((len(surfaces), 3), dtype=np.int64)
    o = 0
    for i, q in enumerate(parts):
        if q is None:
            continue
        S = q[0].shape[0]
        seg[o:o + S, :q[0].shape[1]] = q[0]
        deg[o:o + S] = q[1]
        lp[o:o + S] = q[2]
        off[i] = (o, S, q[3])
        o += S
    return seg, deg, lp, off


def evaluate_trim_curve(curve: TrimCurve, t, order: int = 0) -> np.ndarray:
    """Points (and derivatives) of a 2-D trim curve.

    Parameters
    ----------
    curve : TrimCurve
    t : (m,) float in ``[knots[p], knots[-p-1]]``
    order : int, number of derivatives

    Returns
    -------
    (m, order+1, 2) float: C(t), C'(t), ... (The NURBS Book A3.2 + A4.2).
    """
    t = as_float_array(t, "t", shape=(None,))
    a, b = curve.knots[curve.degree], curve.knots[-curve.degree - 1]
    if t.size and (t.min() < a or t.max() > b):
        raise InvalidInputError(f"parameters must lie in [{a}, {b}]", "t")
    out = np.empty((t.shape[0], order + 1, 2))
    if t.shape[0]:
        curve_points(curve.homogeneous, curve.degree, curve.knots, t, order, out)
    return out
