"""IGES curve and surface entities as exact NURBS (used by :mod:`geomkit.cad.iges.reader`).

Each converter takes the reader (``rec``, ``type_of``, ``transform``) and a directory
pointer.  Curves come back as ``(curve, fmap, (t0, t1))``: the NURBS ``(p, U, Pw)`` in
model space (124 transform applied), the map from the entity's own parameter to the
NURBS parameter (``None``: the same) and the entity's parameter range.  Surfaces come
back as ``(args, fu, fv)``: :class:`~geomkit.Surface` arguments and the maps that carry
the file's ``(u, v)`` (what its pcurves are written in) to the NURBS ``(u, v)``.
"""

from __future__ import annotations

import math

import numpy as np

from geomkit.tolerances import JOIN_TOL, RULED_ARC_TOL
from geomkit._kernels.bezier import insert_knot, restrict_curve
from geomkit.cad.analytic import (angle_to_param, arc_curve, curve_derivs, extrude, line_curve,
                                  revolve, ruled, transform_curve, turn_angle, turn_into)
from geomkit.cad.conic import conic_arc
from geomkit.cad.iges.file import integer as i_
from geomkit.cad.iges.file import real as f_
from geomkit.cad.iges.file import units
from geomkit.cad.loops import Unsupported
from geomkit.cad.offset import offset_args
from geomkit.errors import FileFormatError
from geomkit.nurbs.surface import Surface

READ_SURFACES = {128: "rational B-spline surface", 114: "parametric spline surface",
                 120: "surface of revolution",
                 122: "tabulated cylinder", 118: "ruled surface",
                 140: "offset surface (approximated)"}
READ_CURVES = {110: "line", 100: "circular arc", 104: "conic arc",
               126: "rational B-spline curve", 112: "parametric spline curve"}


def numbers(rd, de: int, first: int, n: int) -> list:
    """``n`` real parameters of entity ``de`` from index ``first``; a missing or
    non-numeric one is a :class:`~geomkit.errors.FileFormatError` naming the entity."""
    r = rd.rec(de)
    t = rd.type_of(de)
    if len(r) < first + n:
        raise FileFormatError(f"{rd.path}: entity {t} at DE {de}: {len(r) - first} "
                              f"parameters, expected {n}")
    try:
        return [f_(x) for x in r[first: first + n]]
    except ValueError:
        raise FileFormatError(f"{rd.path}: entity {t} at DE {de}: non-numeric parameter "
                              f"in {r[first: first + n]}") from None


def restrict(p, U, Pw, t0, t1):
    """A NURBS curve (any dimension, homogeneous ``Pw``) restricted to ``[t0, t1]``
    exactly, by knot insertion (The NURBS Book A5.1)."""
    U = np.asarray(U, float)
    n = Pw.shape[0]
    lo, hi = U[p], U[n]
    if t0 <= lo and t1 >= hi:  # the whole curve (most edges)
        return U, Pw
    t0 = max(t0, lo)
    t1 = min(t1, hi) if t1 > t0 else hi
    # an end within rounding of a knot is that knot (no sliver span of ~1e-17)
    whole, newU, newPw = restrict_curve(p, U, np.ascontiguousarray(Pw, float), t0, t1,
                                        1e-12 * (hi - lo))
    return (U, Pw) if whole else (newU, newPw)


def bspline126(r) -> tuple:
    """The fields of a 126 (rational B-spline curve) parameter record ``r``:
    ``(degree, knots, weights, control points (K+1, 3), (t0, t1))``; the weights are all 1
    when the file marks the curve polynomial (PROP3 = 1)."""
    K, M = i_(r[1]), i_(r[2])
    prop3 = i_(r[5])
    A = K + M + 1
    a = 7
    knots = np.array([f_(x) for x in r[a: a + A + 1]])
    a += A + 1
    W = np.array([f_(x) for x in r[a: a + K + 1]])
    a += K + 1
    P = np.array([f_(x) for x in r[a: a + 3 * (K + 1)]]).reshape(K + 1, 3)
    a += 3 * (K + 1)
    t0, t1 = f_(r[a]), f_(r[a + 1])
    if prop3 == 1:
        W = np.ones(K + 1)
    return M, knots, W, P, (t0, t1)


def curve3d(rd, de: int):
    """A model-space curve entity as ``(curve, fmap, (t0, t1))``."""
    t = rd.type_of(de)
    r = rd.rec(de)
    if t == 110:
        v = [f_(x) for x in r[1:7]]
        c, fmap, rng = line_curve(v[:3], v[3:]), None, (0.0, 1.0)
    elif t == 100:
        zt, x1, y1, x2, y2, x3, y3 = (f_(x) for x in r[1:8])
        rad = math.hypot(x2 - x1, y2 - y1)
        a0 = turn_angle(y2 - y1, x2 - x1)
        a1 = turn_angle(y3 - y1, x3 - x1)
        if a1 <= a0 + 1e-12:
            a1 += 2 * math.pi
        c = arc_curve([x1, y1, zt], [1, 0, 0], [0, 1, 0], rad, a0, a1)
        # the file's angles may be written in another turn ([-pi/2, 0] for [3pi/2, 2pi])
        fmap, rng = (lambda x, a0=a0, a1=a1: angle_to_param(turn_into(x, a0, a1), a0,
                                                            a1)), \
            (a0, a1)
    elif t == 104:
        v = numbers(rd, de, 1, 11)
        form = int(rd.dir[de].d.get("form_number") or 0)
        c, fmap, rng = conic_arc(v[:6], v[6], v[7:9], v[9:11], form,
                                 f"{rd.path}: entity 104 at DE {de}")
    elif t == 126:
        M, knots, W, P, (t0, t1) = bspline126(r)
        U, Pw = restrict(M, knots, np.column_stack([P * W[:, None], W]), t0, t1)
        c, fmap, rng = (M, U, Pw), None, (float(U[M]), float(U[-M - 1]))
    elif t == 112:
        c, fmap, rng = _spline112(r), None, None
        rng = (float(c[1][0]), float(c[1][-1]))
    else:
        raise Unsupported(f"curve DE {de} is entity {t} (read: "
                          + ", ".join(f"{k} {v}" for k, v in READ_CURVES.items()) + ")")
    return transform_curve(c, rd.transform(de)), fmap, rng


def _bezier3(c, h):
    """Bezier control points of the cubic ``c[0] + c[1] s + c[2] s^2 + c[3] s^3`` on
    ``s`` in ``[0, h]`` (``c`` (4, ...): coefficients along the first axis)."""
    c = np.asarray(c, float)
    A, B, C, D = c[0], c[1] * h, c[2] * h * h, c[3] * h ** 3
    return np.stack([A, A + B / 3, A + 2 * B / 3 + C / 3, A + B + C + D])


def _spline112(r):
    """Entity 112 (piecewise cubic polynomial) as an exact cubic B-spline: each
    segment's power form becomes its Bezier form; breakpoints become triple knots."""
    N = i_(r[4])
    T = [f_(x) for x in r[5: 5 + N + 1]]
    a = 5 + N + 1
    pts, knots = [], [T[0]] * 4
    for k in range(N):
        c = np.array([f_(x) for x in r[a: a + 12]]).reshape(3, 4)  # rows x, y, z: A B C D
        a += 12
        bez = _bezier3(c.T, T[k + 1] - T[k])
        if not pts:
            pts.append(bez[0])
        pts += list(bez[1:])
        knots += [T[k + 1]] * 3
    knots.append(T[-1])
    P = np.array(pts)
    return 3, np.array(knots), np.column_stack([P, np.ones(len(P))])




def _spline114(rd, de: int):
    """Entity 114 (parametric spline surface: bicubic polynomial patches) as an exact
    bicubic B-spline.  Patch ``(i, j)`` is ``sum X[a + 4 b] s^a t^b`` with ``s = u -
    TU(i)``, ``t = v - TV(j)`` (IGES 5.3: coefficients ``AX, BX, ..., SX``); its
    power form becomes its Bezier form (:func:`_bezier3` in ``u`` then ``v``) and the
    breakpoints become triple knots, so the surface is the file's, to rounding."""
    what = f"{rd.path}: entity 114 at DE {de}"
    r = rd.rec(de)
    try:
        M, N = i_(r[3]), i_(r[4])
    except (IndexError, ValueError):
        raise FileFormatError(f"{what}: missing or non-integer segment counts") from None
    if M < 1 or N < 1:
        raise FileFormatError(f"{what}: {M} x {N} segments, expected at least 1 x 1")
    nb = M + 1 + N + 1 + M * (N + 1) * 48  # the trailing arbitrary values are not needed
    v = numbers(rd, de, 5, min(nb, len(r) - 5))
    if len(v) < nb - 48:
        raise FileFormatError(f"{what}: {len(v)} parameters after the segment counts, "
                              f"{M} x {N} patches need {nb - 48}")
    TU, TV = np.array(v[: M + 1]), np.array(v[M + 1: M + N + 2])
    if np.any(np.diff(TU) <= 0) or np.any(np.diff(TV) <= 0):
        raise FileFormatError(f"{what}: breakpoints not increasing (u {TU.tolist()}, "
                              f"v {TV.tolist()})")
    base = M + N + 2
    res = units(rd.glob)[1] or 0.0
    worst = 0.0
    P = np.full((3 * M + 1, 3 * N + 1, 3), np.nan)
    for i in range(M):
        for j in range(N):
            a = base + i * (N + 1) * 48 + j * 48
            c = np.array(v[a: a + 48]).reshape(3, 4, 4)  # [xyz, b (t), a (s)]
            c = c.transpose(2, 1, 0)  # [a, b, xyz]
            bz = _bezier3(c, TU[i + 1] - TU[i])  # [k (u), b, xyz]
            bz = _bezier3(bz.transpose(1, 0, 2), TV[j + 1] - TV[j]).transpose(1, 0, 2)
            blk = P[3 * i: 3 * i + 4, 3 * j: 3 * j + 4]
            have = ~np.isnan(blk[..., 0])
            if have.any():
                size = float(np.ptp(bz.reshape(-1, 3), axis=0).max()) or 1.0
                gap = float(np.linalg.norm(blk[have] - bz[have], axis=-1).max())
                if gap > max(JOIN_TOL * max(size, float(np.abs(bz).max())), res):
                    raise FileFormatError(f"{what}: patch ({i}, {j}) does not meet its "
                                          f"neighbours (gap {gap:.3g}, resolution "
                                          f"{res:g})")
                worst = max(worst, gap)
            blk[~have] = bz[~have]
    if worst > 1e-12 * float(np.nanmax(np.abs(P))):  # beyond rounding: the neighbours'
        rd.approx[de] = max(rd.approx.get(de, 0.0), worst)  # own boundary is this far
    U = np.concatenate([[TU[0]] * 4, np.repeat(TU[1:-1], 3), [TU[-1]] * 4])
    V = np.concatenate([[TV[0]] * 4, np.repeat(TV[1:-1], 3), [TV[-1]] * 4])
    return 3, 3, U, V, P, None


def _normalised(c, rng, fmap):
    """Reparametrise a curve linearly to [0, 1]; map from the entity's normalised
    parameter to the NURBS parameter."""
    p, U, Pw = c
    a, b = float(U[0]), float(U[-1])
    U2 = (np.asarray(U) - a) / (b - a)
    if fmap is None:
        return (p, U2, Pw), None
    t0, t1 = rng
    return (p, U2, Pw), (lambda s: (fmap(t0 + s * (t1 - t0)) - a) / (b - a))


def surface(rd, de: int):
    """A surface entity as ``(args, fu, fv)`` (see the module docstring)."""
    t = rd.type_of(de)
    r = rd.rec(de)
    if t == 128:
        return rd.surface128_args(de), None, None
    if t == 114:
        args, fu, fv = _spline114(rd, de), None, None
    elif t == 120:
        axis, _, _ = curve3d(rd, i_(r[1]))
        if rd.type_of(i_(r[1])) != 110:
            raise Unsupported(f"axis of surface of revolution DE {de} is not a line")
        A = axis[2][:, :3] / axis[2][:, 3:]
        gen, fu, _ = curve3d(rd, i_(r[2]))
        sa, ta = f_(r[3]), f_(r[4])
        args = revolve(gen, A[0], A[1] - A[0], sa, ta)
        fv = lambda x, sa=sa, ta=ta: angle_to_param(x, sa, ta)  # noqa: E731
    elif t == 122:
        gen, fmap, rng = curve3d(rd, i_(r[1]))
        gen, fu = _normalised(gen, rng, fmap)
        L = np.array([f_(x) for x in r[2:5]])
        p, U, Pw = gen
        args, fv = extrude(gen, L - Pw[0, :3] / Pw[0, 3]), None
    elif t == 118:
        c1, m1, r1 = curve3d(rd, i_(r[1]))
        c2, m2, r2 = curve3d(rd, i_(r[2]))
        c1, g1 = _normalised(c1, r1, m1)
        c2, g2 = _normalised(c2, r2, m2)
        if i_(r[3]) == 1:
            p, U, Pw = c2
            c2 = (p, 1.0 - np.asarray(U)[::-1], Pw[::-1].copy())
            g2 = None if g2 is None else (lambda s, g=g2: 1.0 - g(1.0 - np.asarray(s)))
        if rd.dir[de].d.get("form_number", 0) == 0:
            _equal_arc_length(rd, de, (c1, g1), (c2, g2))
        if g1 is not None or g2 is not None:
            # rulings join equal entity parameters: exact only where both curves
            # carry them to equal NURBS parameters (arcs / ellipses of equal sweep)
            s = np.linspace(0.0, 1.0, 33)
            h1 = s if g1 is None else g1(s)
            h2 = s if g2 is None else g2(s)
            if float(np.abs(h1 - h2).max()) > 1e-12:
                raise Unsupported(f"ruled surface DE {de}: its curves' parameters map "
                                  "differently to their NURBS parameters (e.g. an arc and "
                                  "a line, or arcs of different sweeps); no exact NURBS")
        c1, c2 = _compatible(c1, c2, de)
        args, fu, fv = ruled(c1, c2), g1, None
    elif t == 140:

        base_de = i_(r[5])
        bargs, fu, fv = surface(rd, base_de)
        if rd.transform(de) is not None:
            raise Unsupported(f"offset surface DE {de} with its own transformation")
        args, err = offset_args(Surface(*bargs), f_(r[4]))
        rd.approx[de] = err
        return args, fu, fv
    else:
        raise Unsupported(f"surface DE {de} is entity {t} (read: "
                          + ", ".join(f"{k} {v}" for k, v in READ_SURFACES.items()) + ")")
    Mt = rd.transform(de)
    if Mt is not None:
        P = args[4] @ Mt[:3, :3].T + Mt[:3, 3]
        args = args[:4] + (P,) + args[5:]
    return args, fu, fv




def _arc_fraction(c, g, n: int = 256):
    """Relative arc length of the normalised curve ``c`` at the entity parameters
    ``e = 0, 1/n, ..., 1`` (``g`` maps them to the NURBS parameter), and its length.
    Gauss-Legendre (10 points) on 8 pieces between consecutive samples and knots."""
    p, U, Pw = c
    e = np.linspace(0.0, 1.0, n + 1)
    t = e if g is None else np.asarray(g(e), float)
    U = np.asarray(U, float)
    br = np.unique(np.concatenate([t, U[(U > t.min()) & (U < t.max())]]))
    x, w = np.polynomial.legendre.leggauss(10)
    cuts = br[:-1, None] + np.diff(br)[:, None] * np.linspace(0.0, 1.0, 9)[None, :]
    lo, hi = cuts[:, :-1].ravel(), cuts[:, 1:].ravel()
    q = 0.5 * (lo + hi)[:, None] + 0.5 * (hi - lo)[:, None] * x[None, :]
    speed = np.linalg.norm(curve_derivs(c, q.ravel(), 1)[:, 1], axis=1).reshape(q.shape)
    piece = 0.5 * (hi - lo) * (speed @ w)
    cum = np.concatenate([[0.0], np.cumsum(piece.reshape(len(br) - 1, 8).sum(axis=1))])
    at = cum[np.searchsorted(br, t)]
    total = float(at[-1] - at[0])
    return e, np.abs(at - at[0]) / total, total


def _equal_arc_length(rd, de, *curves):
    """Form 0 of entity 118 joins points at equal relative arc length.  geomkit's ruled
    surface joins equal relative entity parameters (form 1): the same surface where
    both curves run at constant speed in their parameters (lines, circular arcs).
    Otherwise there is no exact NURBS: Unsupported, never a silently different surface.
    The achieved error (how far a ruling's end moves along its curve) is stated."""
    size = max(float(np.ptp(np.asarray(c[2])[:, :3] / np.asarray(c[2])[:, 3:], axis=0).max())
               for c, _ in curves) or 1.0
    tol = max(RULED_ARC_TOL * size, units(rd.glob)[1] or 0.0)
    err = 0.0
    for c, g in curves:
        e, lam, length = _arc_fraction(c, g)
        err = max(err, float(np.abs(lam - e).max()) * length)
    if err > tol:
        raise Unsupported(f"ruled surface DE {de} is form 0 (rulings at equal arc length) "
                          "between curves that do not run at constant speed in their "
                          f"parameters (a ruling end would move by up to {err:.3g}, "
                          f"tolerance {tol:.3g}); no exact NURBS")
    if err > 1e-12 * size:
        rd.approx[de] = max(rd.approx.get(de, 0.0), err)


def _compatible(c1, c2, de):
    """Two curves of equal degree brought to one knot vector (knot insertion)."""
    (p, U1, P1), (q, U2, P2) = c1, c2
    if p != q:
        raise Unsupported(f"ruled surface DE {de} between curves of degree {p} and {q} "
                          "(degree elevation is not implemented)")
    U1, U2 = np.asarray(U1, float), np.asarray(U2, float)
    P1, P2 = np.ascontiguousarray(P1), np.ascontiguousarray(P2)
    for k in np.unique(np.concatenate([U1, U2])):
        need = max(np.count_nonzero(np.isclose(U1, k, rtol=0, atol=1e-13)),
                   np.count_nonzero(np.isclose(U2, k, rtol=0, atol=1e-13)))
        s1 = int(np.count_nonzero(np.isclose(U1, k, rtol=0, atol=1e-13)))
        s2 = int(np.count_nonzero(np.isclose(U2, k, rtol=0, atol=1e-13)))
        if s1 < need:
            P1, U1 = insert_knot(P1, p, U1, float(k), need - s1)
        if s2 < need:
            P2, U2 = insert_knot(P2, p, U2, float(k), need - s2)
    return (p, U1, P1), (p, U1, P2)
