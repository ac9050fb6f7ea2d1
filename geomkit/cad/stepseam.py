"""Seams of closed faces in geomkit's own STEP reader (:mod:`geomkit.cad.stepbrep`).

STEP writers bound a face on a closed surface in several ways; each becomes one trim
loop per boundary on a patch of exactly one turn:

* **A loop around the axis** (a full circle on a cylinder, a profile going once around
  a revolution): the turn's start angle ``theta`` is chosen where every such loop
  crosses once and no other loop passes (:func:`cut_at_seam`), and each such loop is
  cut there (:func:`_split_edge`: the crossing bracketed on the edge to 1e-17 of its
  range, in one compiled call), so its ends are the patch's two seam sides.
* **Two such loops** (a band, written without a seam edge) become one loop joined by
  two seam segments; **one** (a cap, a cone ending at its apex) is closed along the
  collapsed side of the domain (:func:`merge_winding`), the pole chosen by the face's
  orientation when no vertex loop gives it (:func:`cap_point`).
* An edge through the axis (a pole, an apex) has no defined angle there: its loop is
  not counted as going around.
"""

from __future__ import annotations

import math

import numpy as np

from geomkit.cad.analytic import unwrap
from geomkit.cad.faceedges import Edge
from geomkit.cad.iges.entities import restrict
from geomkit.cad.loops import Unsupported, reverse, shift
from geomkit.nurbs.surface import TrimCurve
from geomkit._kernels.seam import level_crossing, seam_crossing, seam_margins
from geomkit._kernels.ranges import col_range

__all__ = ["cut_at_seam", "cap_point", "merge_winding", "start_inside"]

TWO_PI = 2.0 * np.pi
_CANDIDATES = np.linspace(0.0, TWO_PI, 720, endpoint=False) + 1e-3
"""The seam angles tried (every quarter degree)."""
_CANDIDATES.setflags(write=False)


def start_inside(pieces, base):
    """The loop rotated to start with a piece that lies off the domain's sides (a seam
    edge's projection may fall on either side: chaining starts from a sure one)."""
    (u0, u1), (v0, v1) = base.domain
    e = 1e-9 * max(u1 - u0, v1 - v0)
    for k, c in enumerate(pieces):
        Q = np.asarray(c.control_points)
        if ((Q[:, 0] > u0 + e) & (Q[:, 0] < u1 - e) & (Q[:, 1] > v0 + e)
                & (Q[:, 1] < v1 - e)).all():
            return pieces[k:] + pieces[:k]
    return pieces


def _angles(srf, e, n=65, full=False):
    """Unwrapped angles about the axis along edge ``e``; None when it reaches the
    axis (a pole or an apex), unless ``full``: then the angle there is the
    neighbour's."""
    nearest, spread, W = e.turn(srf, n)  # (the samples, their inverse, unwrapped)
    if nearest > 1e-9 * max(1.0, spread):
        return W[:, 1]
    ab, rho = e.local(srf, n)
    X = e.points(n)
    b = ab[:, 1]
    on = rho <= 1e-9 * max(1.0, float(np.ptp(X, axis=0).max()))
    if not on.any():
        return e.unwrapped(srf, n, 1)
    if not full:  # through the pole or apex: no turn is defined
        return None
    if on.all():
        return None
    if on.any():
        good = np.flatnonzero(~on)
        b = np.interp(np.arange(n), good, b[good])
    return unwrap(b)


def _split_edge(srf, e, target):
    """Where edge ``e`` crosses the angle ``target`` (mod 2 pi) about the axis: None
    (it does not), ``0.0`` / ``1.0`` (at its start / end) or the two
    :class:`Edge` pieces in the loop's order."""
    n = 257
    b = _angles(srf, e, n, full=True)
    if b is None:
        return None
    # a sample on a level target + 2 pi m, else the first pair of consecutive
    # samples with a level strictly between them (their loop parameters j / (n - 1),
    # exact for n - 1 a power of two)
    code, j, level = level_crossing(b, float(target))
    if code == 1:
        return float(j) / (n - 1) if j in (0, n - 1) else _cut(srf, e, j / (n - 1))
    if code == 0:
        return None
    # the crossing bracketed on the loop's parameter s, 32 samples a round (each round
    # narrows it 32 times: as fine as bisection's 60 halvings in 12 rounds)
    # (srf.inverse: the kind's code, the frame O, X, Y, A, R, r and tan(alpha))
    p, U, Pw = e.curve
    sc = seam_crossing(np.ascontiguousarray(Pw, float), int(p), np.asarray(U, float),
                       e.t0, e.t1, bool(e.reverse), *srf.inverse, j / (n - 1),
                       (j + 1) / (n - 1), float(b[j]), level, bool(b[j + 1] > b[j]))
    return _cut(srf, e, sc)


def _cut(srf, e, sc):
    """Edge ``e`` cut at the loop parameter ``sc``: two :class:`Edge` in loop order."""
    t = e.t0 + ((1.0 - sc) if e.reverse else sc) * (e.t1 - e.t0)  # (Edge.ts's value)
    p, U, Pw = e.curve
    a1 = (p, *restrict(p, U, Pw, float(U[p]), t))
    a2 = (p, *restrict(p, U, Pw, t, float(U[-p - 1])))
    first, second = (a2, a1) if e.reverse else (a1, a2)
    return Edge(first, e.key, e.reverse), Edge(second, e.key, e.reverse)


def cut_at_seam(srf, loops, sweep=False):
    """Loops that go once around a cylinder, cone, sphere or torus (about its axis)
    start and end at one
    angle ``theta`` about the axis, chosen off the other loops, so that the patch
    spans exactly the turn ``[theta, theta + 2 pi]`` (each such loop is cut there:
    its ends are then the patch's two seam sides)."""
    if srf.kind not in ("cylinder", "cone", "sphere", "torus", "revolution"):
        return loops, []
    turns, spans, paths = [], [], []
    for lp in loops:
        bs = [_angles(srf, e) for e in lp]
        if any(b is None for b in bs):  # an edge on the axis: no turn
            turns.append(0)
            continue
        path = [bs[0]]
        for b in bs[1:]:  # one continuous angle along the loop
            k = (float(path[-1][-1]) - float(b[0])) / TWO_PI
            # (round half to even, as np.round, on a Python float: a tenth of its cost)
            path.append(b + TWO_PI * (round(k) if math.isfinite(k) else k))
        path = np.concatenate(path)
        turns.append(int(round(float(path[-1] - path[0]) / TWO_PI)))
        if turns[-1]:
            paths.append(path)
        else:
            lo, hi = col_range(path[:, None])
            spans.append((float(lo[0]), float(hi[0])))
    if not any(turns) and not sweep:
        return loops, turns
    # theta: crossed once by each loop around the axis, as far from the other loops'
    # angle ranges as can be
    starts = [0]
    for path in paths:
        starts.append(starts[-1] + len(path))
    starts = np.array(starts, dtype=np.int64)  # (np.cumsum's: a tenth of its cost)
    margin = seam_margins(np.concatenate(paths) if paths else np.zeros(0), starts,
                          np.array(spans, dtype=np.float64).reshape(-1, 2), _CANDIDATES)
    if not (margin > 0).any():
        raise Unsupported("no angle about the axis is crossed once by every loop "
                          "around it and by no other loop")
    theta = float(_CANDIDATES[int(np.argmax(margin))])
    if sweep:
        return _cut_loops(srf, loops, turns, theta), turns, theta
    return _cut_loops(srf, loops, turns, theta), turns


def _cut_loops(srf, loops, turns, theta):
    out = []
    for lp, t in zip(loops, turns):
        if not t:
            out.append(lp)
            continue
        for k, e in enumerate(lp):
            cut = _split_edge(srf, e, theta)
            if cut is None:
                continue
            if isinstance(cut, float):  # at a vertex: the loop starts there
                k += int(cut)
                out.append(lp[k:] + lp[:k])
            else:
                out.append([cut[1], *lp[k + 1:], *lp[:k], cut[0]])
            break
        else:
            raise Unsupported("a loop around the axis does not cross the seam angle")
    return out


def cap_point(srf, turn, same_sense):
    """The point that closes a face bounded by one loop around the axis: a cone's
    apex; a sphere's pole on the face's side (left of the loop seen along the face
    normal, the surface's outward normal unless ``same_sense`` is False)."""
    if srf.kind == "cone":
        return (srf.O + srf.A * (-srf.R / np.tan(srf.alpha)))[None]
    if srf.kind == "sphere":
        north = (turn > 0) == (same_sense is not False)
        return (srf.O + srf.A * (srf.R if north else -srf.R))[None]
    return np.empty((0, 3))


def _reversed_loop(pieces):
    return [reverse(c) for c in pieces[::-1]]


def _winding(pieces, periods, size):
    """Turns of a loop's pieces around each closed direction (0, or +-1: a loop
    that goes once around the surface, a full circle on a cylinder)."""
    e, s = pieces[-1].end.tolist(), pieces[0].start.tolist()
    d = [e[0] - s[0], e[1] - s[1]]  # (floats: numpy's values on 2-vectors)
    k = [int(round(d[c] / periods[c])) if periods[c] > 0 else 0 for c in (0, 1)]
    return k if all(abs(d[c] - k[c] * periods[c]) <= 1e-6 * size for c in (0, 1)) \
        else [0, 0]


def merge_winding(loops, base, periods, what):
    """Loops that go around a closed direction are not closed in UV: two of them (a
    band between two circles) become one loop joined by two seam segments; one (a
    cap or a cone ending at its apex) is closed along the collapsed side of the
    domain (the pole or apex: one model point)."""
    (u0, u1), (v0, v1) = dom = base.domain
    size = max(u1 - u0, v1 - v0)
    winds = [_winding(lp, periods, size) for lp in loops]
    idx = [i for i, k in enumerate(winds) if any(k)]
    if not idx:
        return loops
    rest = [lp for i, lp in enumerate(loops) if i not in idx]
    if len(idx) == 2:
        a, b = loops[idx[0]], loops[idx[1]]
        ka, kb = winds[idx[0]], winds[idx[1]]
        if ka == kb:  # both the same way round: run the second back
            b = _reversed_loop(b)
        c = 0 if ka[0] else 1
        d = np.zeros(2)
        d[c] = a[-1].end[c] - b[0].start[c]
        b = [shift(x, d) for x in b] if d[c] else b
        return [a + [TrimCurve.polyline([a[-1].end, b[0].start])] + b
                + [TrimCurve.polyline([b[-1].end, a[0].start])]] + rest
    if len(idx) == 1:
        a = loops[idx[0]]
        c = 0 if winds[idx[0]][0] else 1
        o = 1 - c
        sides = []
        for val in dom[o]:
            t = np.linspace(dom[c][0], dom[c][1], 9)
            uv = np.column_stack([t, np.full(9, val)] if c == 0 else [np.full(9, val), t])
            X = base.evaluate(uv)
            if float(np.ptp(X, axis=0).max()) <= 1e-9 * base.size:
                sides.append(val)
        if len(sides) == 1:
            e, s0 = a[-1].end.copy(), a[0].start.copy()
            e2, s2 = e.copy(), s0.copy()
            e2[o] = s2[o] = sides[0]
            return [a + [TrimCurve.polyline([e, e2, s2, s0])]] + rest
    raise Unsupported(f"{what}: {len(idx)} loop(s) go around the surface and no "
                      "collapsed side closes them")
