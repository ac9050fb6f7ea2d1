"""IGES B-rep faces (186 / 514 / 510 / 508 / 504 / 502) and analytic surfaces
(108, 190 plane, 192 cylinder, 194 cone, 196 sphere, 198 torus) as exact NURBS.

The analytic surfaces are unbounded; each face's surface is built over the range of
its own boundary (:func:`face_surface`).  Boundaries are read from the *model-space*
edge curves (504 edges, 142 ``CPTR``), not from the file's pcurves (their
parametrisation conventions differ between writers: OCC writes angles in degrees):

* Each edge point is inverted in closed form to local coordinates ``(a, b)``: plane
  ``(x, y)`` in the plane's frame; cylinder / cone ``(height, angle)``; sphere
  ``(latitude, longitude)``; torus ``(minor angle, major angle)``.  Angles are unwrapped
  along each edge and chained from edge to edge; the second use of a seam edge in a
  loop is shifted by a full turn.
* On a plane the map is affine, so the pcurve is the edge's own NURBS with mapped
  control points (exact).  On the others an edge that is an iso-line (a circle or a
  generator line: all of OCC's primitives and fillets) is a straight UV segment,
  carried exactly through the angle reparametrisation; any other edge is a
  piecewise-quintic interpolant within ``PCURVE_TOL`` (:func:`geomkit.cad.uvmap.map_edge`:
  one compiled call per edge).
* Consecutive pieces that do not meet in UV (a pole, a degenerate edge) are joined by
  a straight UV segment, which maps to one point there.
* The surfaces are revolutions (:func:`geomkit.cad.analytic.revolve`) of a line or an
  arc, so they hold their closed forms to rounding.
"""

from __future__ import annotations

import math

import numpy as np

from geomkit.tolerances import ISO_TOL
from geomkit.nurbs.surface import TrimCurve
from geomkit.nurbs.trims import readonly
from geomkit.cad.analytic import (AngleMap, arc_curve, cross3, curve_eval, line_curve,
                                  norm3, plane_patch, revolve, unwrap)
from geomkit.cad.iges.entities import curve3d
from geomkit.cad.iges.file import integer as i_
from geomkit.cad.iges.file import real as f_
from geomkit.cad.loops import Unsupported
from geomkit.cad.uvmap import map_edge, map_pcurve
from geomkit._kernels.ranges import col_range, spread
from geomkit._kernels.pcurve_map import (CONE, CYLINDER, PLANE, SPHERE, TORUS, edge_local,
                                         curve_at, edge_turn, iso_ends, local_points,
                                         plane_piece, residuals)

__all__ = ["Analytic", "analytic", "edge_loop_508", "curve_loop_141", "curve_loop_142",
           "face_surface", "analytic_pieces"]

ANALYTIC = {108: "plane", 190: "plane surface", 192: "right circular cylindrical surface",
            194: "right circular conical surface", 196: "spherical surface",
            198: "toroidal surface"}
_NS = 65  # samples per edge for the inversion
KIND_CODE = {"cylinder": CYLINDER, "cone": CONE, "sphere": SPHERE, "torus": TORUS}
"""The compiled kernels' code of each kind of :class:`Analytic` surface of revolution."""
_LOCAL_CODE = {"plane": PLANE, **KIND_CODE}
"""The code of each kind for :func:`~geomkit._kernels.pcurve_map.local_points`."""
TWO_PI = 2 * math.pi


def _unit(v):
    v = np.asarray(v, float)
    n = norm3(v)
    if not n > 0:
        raise Unsupported("zero direction vector")
    return v / n


class Analytic:
    """An analytic surface: frame ``O, X, Y, A`` and its kind's parameters."""

    def __init__(self, kind, O, A, X, R=0.0, r=0.0, alpha=0.0):
        self.kind, self.O = kind, np.asarray(O, float)
        self.A = _unit(A)
        X = np.asarray(X, float) - np.dot(X, self.A) * self.A
        self.X = _unit(X)
        self.Y = cross3(self.A, self.X)
        self.R, self.r, self.alpha = R, r, alpha
        self.frame = np.concatenate([self.O, self.X, self.Y, self.A])
        self.inverse = (_LOCAL_CODE[kind], self.frame, float(R), float(r),
                        math.tan(alpha))
        """The arguments of the compiled inverse (:func:`local_points`)."""
        self.periodic = {"plane": (False, False), "cylinder": (False, True),
                         "cone": (False, True), "sphere": (False, True),
                         "torus": (True, True)}[kind]

    def local(self, P):
        """Closed-form inverse: model points (n, 3) to local ``(a, b)`` (n, 2) and the
        distance of each point from the axis (1 for planes); one compiled call
        (:func:`~geomkit._kernels.pcurve_map.local_points`, as the pcurve kernels
        invert)."""
        return local_points(np.ascontiguousarray(P, dtype=np.float64), *self.inverse)

    def worst_residual(self, P) -> float:
        """The largest distance of the points ``P`` (n >= 1, 3) from the surface (its
        closed form: a cone's two nappes, a spindle torus's inner part), NaN when one
        is: one compiled call (:func:`~geomkit._kernels.pcurve_map.residuals`)."""
        return float(residuals(np.ascontiguousarray(P, dtype=np.float64),
                               _LOCAL_CODE[self.kind], self.frame, float(self.R),
                               float(self.r), float(self.alpha)))

    def offset(self, d):
        """The surface offset by ``d`` along the radial / normal direction (exact: the
        offset of these surfaces is one of the same kind)."""
        if self.kind == "plane":
            return Analytic("plane", self.O + d * self.A, self.A, self.X)
        if self.kind == "torus":
            return Analytic("torus", self.O, self.A, self.X, self.R, self.r + d)
        R = self.R + (d / math.cos(self.alpha) if self.kind == "cone" else d)
        return Analytic(self.kind, self.O, self.A, self.X, R, self.r, self.alpha)

    def build(self, ra, rb):
        """Surface arguments over local ranges ``ra x rb`` and the maps ``fu, fv`` from
        local coordinates to the NURBS parameters."""
        (a0, a1), (b0, b1) = ra, rb
        O, X, A = self.O, self.X, self.A
        if self.kind == "plane":
            return plane_patch(O, X, self.Y, a0, a1, b0, b1), None, None
        fv = AngleMap(b0, b1)
        if self.kind in ("cylinder", "cone"):
            ta = math.tan(self.alpha)
            gen = line_curve(O + (self.R + a0 * ta) * X + a0 * A,
                             O + (self.R + a1 * ta) * X + a1 * A, a0, a1)
            fu = None
        elif self.kind == "sphere":
            gen = arc_curve(O, X, A, self.R, a0, a1)
            fu = AngleMap(a0, a1)
        else:
            gen = arc_curve(O + self.R * X, X, A, self.r, a0, a1)
            fu = AngleMap(a0, a1)
        return revolve(gen, O, A, b0, b1), fu, fv


def analytic(rd, de: int) -> Analytic:
    """Entity 108 / 190-198 as an :class:`Analytic` (its 124 transform applied)."""
    t = rd.type_of(de)
    r = rd.rec(de)

    def pt(k):
        return np.array([f_(x) for x in rd.rec(k)[1:4]])

    if t == 108:
        a, b, c, d = (f_(x) for x in r[1:5])
        n = np.array([a, b, c])
        nn = float(np.dot(n, n))
        if not nn > 0:
            raise Unsupported(f"plane 108 at DE {de} has a zero normal")
        O = n * d / nn
        ref = np.eye(3)[int(np.argmin(np.abs(n)))]
        s = Analytic("plane", O, n, ref)
    elif t == 190:
        O, N = pt(i_(r[1])), pt(i_(r[2]))
        ref = pt(i_(r[3])) if len(r) > 3 and i_(r[3]) else np.eye(3)[int(np.argmin(np.abs(N)))]
        s = Analytic("plane", O, N, ref)
    elif t in (192, 194, 196, 198):
        O = pt(i_(r[1]))
        A = pt(i_(r[2])) if t != 196 else None
        if t == 192:
            R, ref = f_(r[3]), i_(r[4]) if len(r) > 4 else 0
            kw = dict(R=R)
        elif t == 194:
            R, ang, ref = f_(r[3]), f_(r[4]), i_(r[5]) if len(r) > 5 else 0
            kw = dict(R=R, alpha=math.radians(ang))
        elif t == 196:  # 196: centre, radius, axis, refdir
            R = f_(r[2])
            A = pt(i_(r[3])) if len(r) > 3 and i_(r[3]) else np.array([0.0, 0.0, 1.0])
            ref = i_(r[4]) if len(r) > 4 else 0
            kw = dict(R=R)
        else:
            R, rr, ref = f_(r[3]), f_(r[4]), i_(r[5]) if len(r) > 5 else 0
            kw = dict(R=R, r=rr)
        refv = pt(ref) if ref else np.eye(3)[int(np.argmin(np.abs(A)))]
        kind = {192: "cylinder", 194: "cone", 196: "sphere", 198: "torus"}[t]
        s = Analytic(kind, O, A, refv, **kw)
    else:
        raise Unsupported(f"surface DE {de} is entity {t}, not an analytic surface")
    M = rd.transform(de)
    if M is not None:
        s = Analytic(s.kind, M[:3, :3] @ s.O + M[:3, 3], M[:3, :3] @ s.A,
                     M[:3, :3] @ s.X, s.R, s.r, s.alpha)
    return s


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


_S_NS = np.linspace(0.0, 1.0, _NS)
_S_NS.setflags(write=False)
_NO_X = np.empty((0, 3))
"""The samples :meth:`_Edge.turn` passes when the curve is evaluated in the call."""


# --------------------------------------------------------------------- edges
class _Edge:
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
            dense = self._cache.get((id(self.curve), _NS))
            if dense is not None and n >= 2 and (_NS - 1) % (n - 1) == 0:
                # every ((NS - 1) / (n - 1))th of the dense samples: the same
                # parameters bit for bit (the steps differ by a power of two), the
                # points as edge_local evaluates them (curve_eval's to rounding)
                X = dense[::(_NS - 1) // (n - 1)]
            else:  # (curve_eval's points, its per-call set-up left out)
                p, U, Pw = self.curve
                X = curve_at(np.ascontiguousarray(Pw, dtype=np.float64), int(p),
                             np.asarray(U, dtype=np.float64),
                             _linspace(self.t0, self.t1, n))
            self._cache[k] = X
        return X[::-1] if self.reverse else X

    def box(self) -> np.ndarray:
        """(2, 3): the least and largest x, y, z of the curve's control points
        (:func:`~geomkit._kernels.ranges.col_range`), computed once per curve."""
        k = ("box", id(self.curve))
        b = self._cache.get(k)
        if b is None:
            Pw = self.curve[2]
            b = self._cache[k] = np.array(col_range(Pw[:, :3] / Pw[:, 3:]))
        return b

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

    def turn(self, srf, n: int = _NS):
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


def edge_loop_508(rd, de: int):
    """The oriented model-space edges of a 508 loop (vertex entries are dropped)."""

    r = rd.rec(de)
    n = i_(r[1])
    a, out = 2, []
    for _ in range(n):
        typ, lst, ndx, of, k = (i_(x) for x in r[a: a + 5])
        a += 5 + 2 * k
        if typ == 1:
            continue
        e = rd.rec(lst)
        cde = i_(e[2 + 5 * (ndx - 1)])
        curve, _, _ = curve3d(rd, cde)
        out.append(_Edge(curve, (lst, ndx), of == 0))
    if not out:
        raise Unsupported(f"loop 508 at DE {de} has no edges")
    return out


def curve_loop_142(rd, de: int):
    """The model-space curve ``CPTR`` of a 142 as oriented edges (102 composites
    split)."""

    def walk(c):
        if rd.type_of(c) == 102:
            r = rd.rec(c)
            return [x for k in range(i_(r[1])) for x in walk(i_(r[2 + k]))]
        curve, _, _ = curve3d(rd, c)
        return [_Edge(curve, ("c", c), False)]

    cptr = i_(rd.rec(de)[4])
    if not cptr:
        raise Unsupported(f"boundary 142 at DE {de} has neither a parameter-space nor a "
                          "model-space curve")
    return walk(cptr)


def curve_loop_141(rd, de: int):
    """The model-space curves of a 141 boundary as oriented edges (``SENSE = 2``:
    reversed)."""

    if rd.type_of(de) != 141:
        raise Unsupported(f"boundary DE {de} is entity {rd.type_of(de)}, expected 141")
    r = rd.rec(de)
    n, a, out = i_(r[4]), 5, []
    for _ in range(n):
        crv, sense, k = i_(r[a]), i_(r[a + 1]), i_(r[a + 2])
        a += 3 + k
        parts = []

        def walk(c):
            if rd.type_of(c) == 102:
                rc = rd.rec(c)
                for j in range(i_(rc[1])):
                    walk(i_(rc[2 + j]))
            else:
                parts.append(_Edge(curve3d(rd, c)[0], ("c", c), False))

        walk(crv)
        if sense == 2:
            parts = [_Edge(e.curve, e.key, True) for e in parts[::-1]]
        out += parts
    if not out:
        raise Unsupported(f"boundary 141 at DE {de} has no curves")
    return out


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
            ab, rho = e.local(srf, _NS)
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
                ab[:, c] = unwrap(ab[:, c]) if polar else e.unwrapped(srf, _NS, c)
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


def face_surface(rd, srf_de: int, loops, tol_rel: float):
    """``(surface args, [loops of TrimCurve pieces], domain)`` of one face: the
    analytic surface ``srf_de`` over the range of its boundary ``loops`` (lists of
    :class:`_Edge`, outer first)."""
    if rd.type_of(srf_de) == 140:  # offset of an analytic surface: exact, the side
        # that holds the face's edges
        r = rd.rec(srf_de)
        if rd.transform(srf_de) is not None:
            raise Unsupported(f"offset surface DE {srf_de} with its own transformation")
        base = analytic(rd, i_(r[5]))
        P = _edge_points(loops)
        cands = [base.offset(f_(r[4])), base.offset(-f_(r[4]))]
        srf = min(cands, key=lambda c: c.worst_residual(P))
    else:
        srf = analytic(rd, srf_de)
    return analytic_pieces(srf, loops, tol_rel, f"surface DE {srf_de}")


def _edge_points(loops):
    return np.concatenate([e.points(9) for lp in loops for e in lp])


def analytic_pieces(srf: Analytic, loops, tol_rel: float, what: str, extra=None,
                    bridge: bool = True):
    """``(surface args, [loops of TrimCurve pieces], domain)`` of a face on the
    analytic surface ``srf`` over the range of its boundary ``loops`` (lists of
    :class:`_Edge`, outer first) and of the ``extra`` points (k, 3) (a cone's apex,
    a sphere's pole: their non-periodic coordinate); shared by the IGES and STEP
    readers.  ``bridge``: consecutive pieces more than 1e-3 of the range apart are
    joined by a UV segment (else left to the caller)."""
    P = _edge_points(loops)
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
    pad = 1e-9 * max(float(np.max(hi - lo)), 1.0)
    if srf.kind == "sphere":
        lo[0], hi[0] = max(lo[0], -math.pi / 2), min(hi[0], math.pi / 2)
    if np.any(hi - lo <= pad):
        raise Unsupported(f"{what}: its boundary spans no area")
    args, fu, fv = srf.build((lo[0], hi[0]), (lo[1], hi[1]))
    tol = tol_rel * float(np.max(hi - lo))
    uv_loops = [_pieces(srf, lp, ch, fu, fv, tol, float(np.max(hi - lo)), bridge)
                for lp, ch in zip(loops, chains)]
    dom = ((float(args[2][0]), float(args[2][-1])), (float(args[3][0]), float(args[3][-1])))
    return args, uv_loops, dom
