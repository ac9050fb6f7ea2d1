"""A face's boundary edges as trim pieces on an analytic surface, for the IGES and
STEP readers (:mod:`geomkit.cad.brep`, :mod:`geomkit.cad.stepbrep`).

Each oriented model-space edge (:class:`Edge`) is sampled once per curve and
inverted in closed form to the surface's local coordinates, unwrapped along the
edge and chained from edge to edge (:func:`analytic_pieces`, whose method the
:mod:`geomkit.cad.brep` docstring describes): a plane's pieces are the edges' own
NURBS mapped, an iso-line on a surface of revolution is a straight UV segment, any
other edge a piecewise-quintic interpolant (:func:`geomkit.cad.uvmap.map_edge`).
"""

from __future__ import annotations

import math

import numpy as np

from geomkit.tolerances import ISO_TOL
from geomkit.nurbs.surface import TrimCurve
from geomkit.nurbs.trims import readonly
from geomkit.cad.analytic import AngleMap, curve_eval, unwrap
from geomkit.cad.loops import Unsupported
from geomkit.cad.uvmap import map_edge, map_pcurve
from geomkit._kernels.ranges import col_range, spread
from geomkit._kernels.pcurve_map import (CONE, CYLINDER, SPHERE, TORUS, curve_at,
                                         curve_at_even, edge_local, edge_turn, iso_ends,
                                         plane_piece)

__all__ = ["Edge", "analytic_pieces", "edge_points", "KIND_CODE", "NS"]

NS = 65
"""Samples per edge for the inversion."""
KIND_CODE = {"cylinder": CYLINDER, "cone": CONE, "sphere": SPHERE, "torus": TORUS}
"""The compiled kernels' code of each kind of analytic surface of revolution."""
TWO_PI = 2 * math.pi
_AR: dict = {}


def _linspace(a: float, b: float, n: int) -> np.ndarray:
    """``np.linspace(a, b, n)`` (n >= 2, a != b), the same values without its generic
    argument handling: a reader samples thousands of edges."""
    ar = _AR.get(n)
    if ar is None:
        ar = _AR[n] = np.arange(n, dtype=np.float64)
    y = ar * ((b - a) / (n - 1)) + a
    y[-1] = b
    return y


_S_NS = np.linspace(0.0, 1.0, NS)
_S_NS.setflags(write=False)
_NO_X = np.empty((0, 3))
"""The samples :meth:`Edge.turn` passes when the curve is evaluated in the call."""


# --------------------------------------------------------------------- edges
class Edge:
    """One oriented model-space edge: its NURBS curve and parameter direction."""

    def __init__(self, curve, key, reverse, cache=None):
        self.curve, self.key, self.reverse = curve, key, reverse
        p, U, _ = curve
        self.t0, self.t1 = float(U[p]), float(U[-p - 1])
        # samples shared by every use of the curve (a reader passes one dict per file,
        # keeping its curves alive)
        self._cache = {} if cache is None else cache

    def points(self, n: int) -> np.ndarray:
        """The curve at ``n`` parameters evenly spaced along the edge, in loop order
        (``curve_eval(curve, ts(linspace(0, 1, n)))``), computed once per curve."""
        k = (id(self.curve), n)
        X = self._cache.get(k)
        if X is None:
            dense = self._cache.get((id(self.curve), NS))
            if dense is not None and n >= 2 and (NS - 1) % (n - 1) == 0:
                # every ((NS - 1) / (n - 1))th of the dense samples: the same
                # parameters bit for bit (the steps differ by a power of two), the
                # points as edge_local evaluates them (curve_eval's to rounding)
                X = dense[::(NS - 1) // (n - 1)]
            elif n >= 2:  # (curve_eval's points at linspace, in one call)
                p, U, Pw = self.curve
                X = curve_at_even(np.ascontiguousarray(Pw, dtype=np.float64), int(p),
                                  np.asarray(U, dtype=np.float64), self.t0, self.t1, n)
            else:  # (curve_eval's points, its per-call set-up left out)
                p, U, Pw = self.curve
                X = curve_at(np.ascontiguousarray(Pw, dtype=np.float64), int(p),
                             np.asarray(U, dtype=np.float64),
                             _linspace(self.t0, self.t1, n))
            self._cache[k] = X
        return X[::-1] if self.reverse else X

    def local(self, srf, n: int):
        """``srf.local`` of :meth:`points` (copies: callers unwrap them in place),
        computed once per surface and curve (a seam cut and the face's chain read
        the same samples)."""
        key = (srf, id(self.curve), n)
        v = self._cache.get(key)
        if v is None:
            pk = (id(self.curve), n)
            if pk in self._cache or n < 2:
                self.points(n)
                v = srf.local(self._cache[pk])
            else:  # the samples and their inverse in one compiled call
                p, U, Pw = self.curve
                X, ab, rho = edge_local(np.ascontiguousarray(Pw, dtype=np.float64), p,
                                        np.asarray(U, dtype=np.float64), self.t0,
                                        self.t1, n, *srf.inverse)
                self._cache[pk] = X
                v = ab, rho
            self._cache[key] = v
        ab, rho = v[0], v[1]
        if self.reverse:
            return ab[::-1].copy(), rho[::-1]
        return ab.copy(), rho

    def turn(self, srf, n: int = NS):
        """``(nearest, spread, W)`` of the ``n`` samples on the surface of
        revolution ``srf``: :meth:`nearest_axis`, :meth:`spread` and the local
        coordinates in loop order with the periodic ones unwrapped (read-only; a
        seam cut and the face's chain read them), in one compiled call
        (:func:`~geomkit._kernels.pcurve_map.edge_turn`); the other methods' caches
        are filled with the same values."""
        key = (srf, id(self.curve), "turn", self.reverse, n)
        v = self._cache.get(key)
        if v is not None:
            return v
        pk = (id(self.curve), n)
        X = self._cache.get(pk)
        p, U, Pw = self.curve
        wrap = getattr(srf, "periodic", (False, True))
        X, ab, rho, nearest, spread, W = edge_turn(
            _NO_X if X is None else X, X is not None,
            np.ascontiguousarray(Pw, dtype=np.float64), p,
            np.asarray(U, dtype=np.float64), self.t0, self.t1, n, bool(self.reverse),
            bool(wrap[0]), bool(wrap[1]), *srf.inverse)
        W.setflags(write=False)
        c = self._cache
        c.setdefault(pk, X)
        c[(srf, id(self.curve), n)] = (ab, rho, nearest)
        c[("spread", id(self.curve), n)] = spread
        for k in (0, 1):
            if wrap[k]:
                c[(srf, id(self.curve), n, self.reverse, k)] = W[:, k]
        v = c[key] = (nearest, spread, W)
        return v

    def spread(self, n: int) -> float:
        """The largest extent along x, y or z of :meth:`points` (kept)."""
        key = ("spread", id(self.curve), n)
        v = self._cache.get(key)
        if v is None:
            v = self._cache[key] = float(np.ptp(self.points(n), axis=0).max())
        return v

    def nearest_axis(self, srf, n: int) -> float:
        """The least distance of :meth:`local`'s samples from the surface's axis
        (``-inf`` when one is NaN), kept with them."""
        key = (srf, id(self.curve), n)
        v = self._cache.get(key)
        if v is None or len(v) == 2:
            self.local(srf, n)
            ab, rho = self._cache[key]
            lo = float(rho.min())
            v = self._cache[key] = (ab, rho, -math.inf if lo != lo else lo)
        return v[2]

    def unwrapped(self, srf, n: int, c: int) -> np.ndarray:
        """``unwrap`` of coordinate ``c`` of :meth:`local` (read-only), computed once
        per surface, curve and direction (a seam cut and the face's chain unwrap the
        same angles)."""
        key = (srf, id(self.curve), n, self.reverse, c)
        v = self._cache.get(key)
        if v is None:
            v = self._cache[key] = unwrap(self.local(srf, n)[0][:, c])
            v.setflags(write=False)
        return v

    def ts(self, s):
        s = np.asarray(s, float)
        if self.reverse:
            s = 1.0 - s
        return self.t0 + s * (self.t1 - self.t0)


def _chain(srf, loop, size):
    """Local coordinates of every edge's samples, unwrapped and chained."""
    s = _S_NS
    out, first, prev, prev_pole = [], {}, None, False
    apex = None  # the last edge that starts at a pole from another edge's end
    for e in loop:
        nearest, _, W = e.turn(srf)
        if nearest > 1e-9 * size:  # no sample on the axis: W as it is
            ab, pole, polar = W, None, False
        else:  # (the pole flags only when a sample may lie on the axis)
            ab, rho = e.local(srf, NS)
            pole = rho <= 1e-9 * size
            if pole.all():
                raise Unsupported("an edge lies on the surface's axis")
            polar = bool(pole.any())
        if polar:  # angle undefined on the axis: take the neighbour's
            good = np.nonzero(~pole)[0]
            idx = good[np.clip(np.searchsorted(good, np.arange(len(s))), 0, len(good) - 1)]
            ab[pole, 1] = ab[idx[pole], 1]
        shift = np.zeros(2)
        for c in (0, 1):
            if not srf.periodic[c]:
                continue
            if ab is not W:
                ab[:, c] = unwrap(ab[:, c]) if polar else e.unwrapped(srf, NS, c)
            if prev is None:
                continue
            if c == 1 and prev_pole and e.key in first:
                cand = first[e.key][0, 1] + np.array([TWO_PI, -TWO_PI])
                shift[c] = cand[0] - ab[0, c]
            else:
                shift[c] = TWO_PI * round((prev[c] - ab[0, c]) / TWO_PI)
                if c == 1 and prev_pole:
                    apex = len(out)
        ab = ab + shift
        first.setdefault(e.key, ab)
        out.append(ab)
        prev, prev_pole = ab[-1], pole is not None and bool(pole[-1])
    if apex is not None and srf.periodic[1]:
        # at a pole the angle jumps by any amount (a sector of a cone from its apex
        # jumps by its opening, a half cone by exactly pi, either way round): the
        # edges after the pole take the turn that closes the loop, which therefore
        # does not go around the axis (as :func:`~geomkit.cad.stepseam.cut_at_seam`
        # counts a loop through the axis)
        k = round((out[-1][-1, 1] - out[0][0, 1]) / TWO_PI)
        if k:
            for j in range(apex, len(out)):
                out[j] = out[j] - np.array([0.0, TWO_PI * k])
    return out


def _plane_piece(curve, reverse, srf):
    """An edge's own NURBS ``curve`` mapped onto the plane ``srf`` as a trim piece in
    loop order (one compiled call,
    :func:`~geomkit._kernels.pcurve_map.plane_piece`): thousands per part.  A curve
    that is not as the readers build it (finite, clamped, weights > 0) goes through
    ``TrimCurve.create`` (an error naming the fault)."""
    p, U, Pw = curve
    U2, Q, w, plain, ok = plane_piece(np.ascontiguousarray(Pw, dtype=np.float64), int(p),
                                      np.asarray(U, dtype=np.float64), bool(reverse),
                                      srf.O, srf.X, srf.Y)
    if not ok:
        return TrimCurve.create(p, U2, Q, None if plain else w)
    return TrimCurve(p, readonly(U2), readonly(Q), readonly(w))


def _pieces(srf, loop, chains, fu, fv, tol, size, bridge=True):
    pieces = []
    maps = None  # the angle maps as iso_ends takes them (None: mapped in Python)
    if srf.kind != "plane" and all(f is None or isinstance(f, AngleMap) for f in (fu, fv)):
        maps = np.zeros((2, 3))
        for c, f in enumerate((fu, fv)):
            if f is not None:
                maps[c] = 1.0, f.theta0, f.theta1
    for e, ab in zip(loop, chains):
        if srf.kind == "plane":
            c = _plane_piece(e.curve, e.reverse, srf)
        elif maps is not None and (got := iso_ends(ab, ISO_TOL * max(size, 1.0), maps)):
            # an iso-line's mapped ends (as below) in one compiled call
            iso0, iso1, q = got
            c = TrimCurve.polyline(q) if iso0 or iso1 else _fit(srf, e, ab, fu, fv, tol)
        else:
            dev = np.abs(ab - ab[0])
            iso = [float(dev[:, k].max()) <= ISO_TOL * max(size, 1.0) for k in (0, 1)]
            if iso[0] or iso[1]:
                q = np.array([ab[0], ab[-1]])
                for k in (0, 1):
                    if iso[k]:
                        q[:, k] = ab[0, k]
                # an axis-parallel segment maps onto one (each coordinate by its
                # own monotone map): its mapped ends are exact
                if fu is not None:
                    q[:, 0] = fu(q[:, 0])
                if fv is not None:
                    q[:, 1] = fv(q[:, 1])
                c = TrimCurve.polyline(q)
            else:
                c = _fit(srf, e, ab, fu, fv, tol)
        pieces.append(c)
    if not bridge:
        return pieces
    out = []
    for k, c in enumerate(pieces):
        out.append(c)
        nxt = pieces[(k + 1) % len(pieces)]
        if float(np.hypot(*(c.end - nxt.start))) > 1e-3 * size:
            out.append(TrimCurve.polyline([c.end, nxt.start]))
    return out


def _distinct(x):
    """``np.unique`` of a non-decreasing array (its values, without the sort)."""
    keep = np.empty(len(x), dtype=bool)
    keep[:1] = True
    np.not_equal(x[1:], x[:-1], out=keep[1:])
    return x[keep]


def _fit(srf, e, ab, fu, fv, tol):
    """A non-iso edge: piecewise-quintic interpolant of its mapped local coordinates
    (angles on the branch of the chained samples); compiled on the surfaces of
    revolution, :func:`~geomkit.cad.uvmap.map_pcurve` of the closed-form inversion
    otherwise."""
    last = [None, None]  # the parameters of the last call and their local coordinates

    def loc(s, k):
        s = np.clip(s, 0.0, 1.0)
        if last[0] is not None and last[0].shape == s.shape and np.array_equal(last[0], s):
            v = last[1]  # both coordinates come from one evaluation
        else:
            v, _ = srf.local(curve_eval(e.curve, e.ts(s)))
            last[:] = s, v
        x = v[:, k]
        if srf.periodic[k]:
            ref = np.interp(s, np.linspace(0.0, 1.0, len(ab)), ab[:, k])
            x = ref + (x - ref + math.pi) % TWO_PI - math.pi
        f = fu if k == 0 else fv
        return x if f is None else f(x)

    # the edge's own knots start the spans (a quintic across a knot of the edge
    # converges slowly)
    p, U, _ = e.curve
    sk = (_distinct(np.asarray(U, float)[p:len(U) - p]) - e.t0) / (e.t1 - e.t0)
    sk = np.clip(sk, 0.0, 1.0) if not e.reverse else np.clip(1.0 - sk, 0.0, 1.0)[::-1]
    sk = _distinct(sk) if np.isfinite(sk).all() else np.unique(sk)
    if sk.size < 2:
        sk = np.array([0.0, 1.0])
    diag = TrimCurve.polyline(np.column_stack([sk, sk]))  # (chord length: knots sk)
    code = KIND_CODE.get(srf.kind)
    if code is not None and all(f is None or isinstance(f, AngleMap) for f in (fu, fv)):
        frame = srf.frame
        maps = [None if f is None else (f.theta0, f.theta1) for f in (fu, fv)]
        c, _ = map_edge(e.curve, e.reverse, code, frame,
                        (srf.R, srf.r, math.tan(srf.alpha)), srf.periodic, ab, maps, diag,
                        tol)
        return c
    c, _ = map_pcurve(diag, lambda s: loc(s, 0), lambda s: loc(s, 1), tol)
    return c


def edge_points(loops):
    return np.concatenate([e.points(9) for lp in loops for e in lp])


def _extent(lo, hi) -> float:
    """``float(np.max(hi - lo))`` of two 2-vectors (NaN when a difference is), in
    Python floats."""
    a, b = float(hi[0] - lo[0]), float(hi[1] - lo[1])
    return math.nan if a != a or b != b else max(a, b)


def analytic_pieces(srf, loops, tol_rel: float, what: str, extra=None,
                    bridge: bool = True):
    """``(surface args, [loops of TrimCurve pieces], domain)`` of a face on the
    analytic surface ``srf`` over the range of its boundary ``loops`` (lists of
    :class:`Edge`, outer first) and of the ``extra`` points (k, 3) (a cone's apex,
    a sphere's pole: their non-periodic coordinate); shared by the IGES and STEP
    readers.  ``bridge``: consecutive pieces more than 1e-3 of the range apart are
    joined by a UV segment (else left to the caller)."""
    P = edge_points(loops)
    size = float(spread(P)) or 1.0
    if srf.kind == "plane":  # the pieces are the edges' own NURBS mapped: the range
        # is their control points' (a rational arc's middle control point lies beyond
        # the arc, and trims must stay in the domain; the hull holds every sample)
        chains = [[None] * len(lp) for lp in loops]
        Q = np.concatenate([e.curve[2][:, :3] / e.curve[2][:, 3:] for lp in loops
                            for e in lp])
        q, _ = srf.local(Q)
        lo, hi = col_range(q)
    else:
        chains = [_chain(srf, lp, size) for lp in loops]
        outer = np.concatenate(chains[0])
        for ch in chains[1:]:  # inner loops: same turn as the outer one
            for c in (0, 1):
                if srf.periodic[c]:
                    m = np.concatenate(ch)[:, c].mean()
                    k = round((outer[:, c].mean() - m) / TWO_PI)
                    for ab in ch:
                        ab[:, c] += k * TWO_PI
        lo, hi = col_range(np.concatenate([np.concatenate(ch) for ch in chains]))
    if extra is not None and len(extra):
        ab, _ = srf.local(np.asarray(extra, float).reshape(-1, 3))
        for c in (0, 1):
            if not srf.periodic[c]:
                lo[c], hi[c] = min(lo[c], ab[:, c].min()), max(hi[c], ab[:, c].max())
    if srf.kind == "cone":  # never across the apex; an end near it is the apex
        apex = -srf.R / math.tan(srf.alpha)
        near = 1e-6 * max(size, abs(apex))
        if abs(lo[0] - apex) <= near or lo[0] < apex < hi[0] and hi[0] - apex > apex - lo[0]:
            lo[0] = apex
        elif abs(hi[0] - apex) <= near or lo[0] < apex < hi[0]:
            hi[0] = apex
    pad = 1e-9 * max(_extent(lo, hi), 1.0)
    if srf.kind == "sphere":
        lo[0], hi[0] = max(lo[0], -math.pi / 2), min(hi[0], math.pi / 2)
    if float(hi[0] - lo[0]) <= pad or float(hi[1] - lo[1]) <= pad:
        raise Unsupported(f"{what}: its boundary spans no area")
    args, fu, fv = srf.build((lo[0], hi[0]), (lo[1], hi[1]))
    ext = _extent(lo, hi)
    tol = tol_rel * ext
    uv_loops = [_pieces(srf, lp, ch, fu, fv, tol, ext, bridge)
                for lp, ch in zip(loops, chains)]
    dom = ((float(args[2][0]), float(args[2][-1])), (float(args[3][0]), float(args[3][-1])))
    return args, uv_loops, dom
