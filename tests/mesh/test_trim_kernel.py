"""The trim polylines kernel (``geomkit._kernels.tess_trim.trim_polylines``: every piece
of a surface in one call, each from its knots, a curved piece's segments checked on
its knot span's 1/16 grid) against the exact boundary: for every segment of every
piece, the exact boundary curve ``S(C(t))`` and the image of the UV chord, sampled
at 48 points, lie within ``chord_tol`` of the 3-D chord.  On the curved trimmed faces
of real parts (NX9: quadratic pieces of 4 spans, FTC-07: lines on cylinders and
cones, the CATIA swept faces, Inventor's quintic of 100 spans), with and without
segments across smooth knots, and a freeform with a circle trim; the pieces' ends and
a polyline piece's vertices are kept exactly; smooth knots crossed, corners kept."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from geomkit import Surface
from geomkit._kernels.tess_trim import _curve_at, trim_polylines
from geomkit.cad.step import read_step
from geomkit.mesh.trim_polylines import SEED_SPANS, TrimPolylines, affine_map
from geomkit.nurbs.evaluation import evaluate

from helpers.paths import DATA
from helpers.tesshelp import circle_dict

M = 48
DENSE = SEED_SPANS  # the grid rule; -1 checks quarter points only (a failing control)


def _kernel(s, pieces, chord_tol, uv_chords=True, cross_knots=False, pair_tol=None):
    curve_tol, pair = (chord_tol, 2 * chord_tol) if pair_tol is None else (pair_tol, pair_tol)
    (u0, u1), (v0, v1) = s.domain
    CP = np.concatenate([c.control_points for c in pieces])
    W = np.concatenate([c.weights for c in pieces])
    K = np.concatenate([c.knots for c in pieces])
    deg = np.array([c.degree for c in pieces], dtype=np.int64)
    co = np.concatenate([[0], np.cumsum([len(c.weights) for c in pieces])]).astype(np.int64)
    ko = np.concatenate([[0], np.cumsum([len(c.knots) for c in pieces])]).astype(np.int64)
    counts = np.empty(len(pieces), dtype=np.int64)
    buf = np.empty((4, 3))
    n = trim_polylines(CP, W, K, deg, co, ko, DENSE, u0, v0, u1, v1, s.homogeneous,
                       s.degree_u, s.degree_v, s.knots_u, s.knots_v, curve_tol, chord_tol,
                       pair, uv_chords,
                       cross_knots, buf, counts, True)
    assert n == -1  # too small: asks for more
    buf = np.empty((200_000, 3))
    n = trim_polylines(CP, W, K, deg, co, ko, DENSE, u0, v0, u1, v1, s.homogeneous,
                       s.degree_u, s.degree_v, s.knots_u, s.knots_v, curve_tol, chord_tol,
                       pair, uv_chords,
                       cross_knots, buf, counts, True)
    assert n == counts.sum()
    return np.split(buf[:n], np.cumsum(counts)[:-1])


def _chord_gaps(s, A, B, X):
    """Distances of X (k, M-1, 3) from the chords A[i]-B[i]."""
    d = B - A
    ll = np.maximum((d * d).sum(axis=1), 1e-300)
    e = X - A[:, None]
    w = np.clip((e * d[:, None]).sum(axis=2) / ll[:, None], 0.0, 1.0)
    return np.linalg.norm(e - w[..., None] * d[:, None], axis=2).max(axis=1)


def _check_piece(s, c, rows, chord_tol, uv_chords=True, pair_tol=None):
    """Each segment's curve within ``chord_tol`` of its chord and (``uv_chords``) its UV
    chord's image too, or, with ``pair_tol``, the image within ``chord_tol`` and the
    curve within it too or the two distances adding up to at most ``pair_tol`` (a
    straight piece inside the domain, whose UV chords map onto the curve: the curve
    within ``pair_tol``) (48 samples a segment)."""
    (u0, u1), (v0, v1) = s.domain
    t, uv = rows[:, 0], rows[:, 1:]
    k = c.knots[c.degree: len(c.knots) - c.degree]
    assert t[0] == k[0] and t[-1] == k[-1] and np.all(np.diff(t) > 0)
    if c.is_polyline and len(np.unique(k)) == len(c.control_points):  # vertices kept
        P = np.clip(c.control_points, [u0, v0], [u1, v1])
        assert np.array_equal(uv[np.searchsorted(t, np.unique(k))], P)
    f = np.linspace(0.0, 1.0, M + 1)[1:-1]
    T = (t[:-1, None] * (1 - f) + t[1:, None] * f).ravel()
    N, lft, rgt = np.empty(c.degree + 1), np.empty(c.degree + 1), np.empty(c.degree + 1)
    Cuv = np.array([_curve_at(c.homogeneous, c.degree, c.knots, x, u0, v0, u1, v1, N, lft, rgt)
                    for x in T])
    A, B = evaluate(s, uv[:-1]), evaluate(s, uv[1:])
    g_curve = _chord_gaps(s, A, B, evaluate(s, Cuv).reshape(len(A), M - 1, 3))
    g_chord = np.zeros_like(g_curve)
    if uv_chords:
        L = (uv[:-1, None] * (1 - f)[:, None] + uv[1:, None] * f[:, None]).reshape(-1, 2)
        g_chord = _chord_gaps(s, A, B, evaluate(s, L).reshape(len(A), M - 1, 3))
    own = (uv_chords and c.is_polyline
           and np.all((c.control_points >= [u0, v0]) & (c.control_points <= [u1, v1])))
    if pair_tol is None:
        worst = max(g_curve.max(), g_chord.max())
        assert worst <= chord_tol, (worst / chord_tol, c.degree, len(k))
    elif own:  # a straight piece inside the domain is its own UV chord's image
        assert g_curve.max() <= pair_tol, (g_curve.max() / pair_tol, c.degree, len(k))
    else:
        assert g_chord.max() <= chord_tol, (g_chord.max() / chord_tol, c.degree, len(k))
        worst = np.where(g_curve <= chord_tol, 0.0, g_curve + g_chord).max()
        assert worst <= pair_tol, (worst / pair_tol, c.degree, len(k))
    return len(rows)


@pytest.mark.parametrize("cross_knots", [False, True])
@pytest.mark.parametrize("part", ["nx9_face_recognition_ap214.stp", "nist_ftc_07_ap242.stp",
                                  "catia_v5_ventilator_swept_faces.stp",
                                  "inventor2015_cylinder_block_face6.stp"])
@pytest.mark.parametrize("pair", [None, 1.8])
def test_trim_polylines_within_chord_tol_on_real_parts(part, cross_knots, pair):
    """Both rules: each distance within chord_tol, and (tessellate's, ``pair``) the UV
    chord's image within chord_tol and the curve within it or the sum of the two within
    ``pair * chord_tol``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        S = read_step(DATA / "parts" / part).surfaces
    B = np.array([s.bounds for s in S])
    chord_tol = 0.5e-3 * float(np.linalg.norm(B[:, 1].max(axis=0) - B[:, 0].min(axis=0)))
    checked = 0
    for s in S:
        if not s.trim:
            continue
        affine = affine_map(s, s.size) is not None
        pieces = [c for loop in s.trim for c in loop.pieces]
        pair_tol = None if pair is None else pair * chord_tol
        for c, rows in zip(pieces, _kernel(s, pieces, chord_tol, not affine, cross_knots,
                                           pair_tol)):
            checked += _check_piece(s, c, rows, chord_tol, not affine, pair_tol)
    assert checked > 100


def test_trim_polylines_on_a_freeform_circle_and_the_loops_they_make():
    rng = np.random.default_rng(5)
    gu, gv = np.meshgrid(np.linspace(0, 100, 5), np.linspace(0, 100, 5), indexing="ij")
    net = np.stack([gu, gv, 8.0 * rng.standard_normal((5, 5))], axis=-1)
    knots = [0, 0, 0, 0, 0.5, 1, 1, 1, 1]
    s = Surface(3, 3, knots, knots, net, trim=[circle_dict((0.45, 0.55), 0.3)])
    pieces = [c for loop in s.trim for c in loop.pieces]
    for chord_tol in (1e-1, 1e-2, 1e-3):
        rows = _kernel(s, pieces, chord_tol)
        for c, r in zip(pieces, rows):
            _check_piece(s, c, r, chord_tol)
        # TrimPolylines joins the pieces of a loop end to start and closes it exactly
        loop = TrimPolylines(s, chord_tol).loops[0]
        want = np.concatenate([r[:, 1:] if i == 0 else r[1:, 1:] for i, r in enumerate(rows)])
        want[-1] = want[0]
        assert np.array_equal(loop, want)


def test_a_wiggle_between_the_quarter_points_is_caught():
    """A quintic piece crossing its chord at 0, 1/4, 1/2, 3/4 and 1 (in UV, on a flat
    plane): the quarter points alone would accept the single chord, 0.0037 * A off;
    the knot span's 1/16 grid sees it and the polyline holds ``chord_tol``."""
    from math import comb

    from geomkit.nurbs.trims import TrimCurve

    t = np.linspace(0.0, 1.0, 6)
    y = 0.5 + 20.0 * t * (t - 0.25) * (t - 0.5) * (t - 0.75) * (t - 1.0)
    Bm = np.array([[comb(5, i) * x ** i * (1 - x) ** (5 - i) for i in range(6)] for x in t])
    P = np.c_[np.linalg.solve(Bm, 0.1 + 0.8 * t), np.linalg.solve(Bm, y)]
    wiggle = TrimCurve.create(5, [0] * 6 + [1] * 6, P)
    back = TrimCurve.create(1, [0, 0, 0.5, 1, 1], [P[-1], [0.5, 0.95], P[0]])
    gu, gv = np.meshgrid(np.linspace(0, 10, 2), np.linspace(0, 10, 2), indexing="ij")
    s = Surface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], np.stack([gu, gv, 0 * gu], axis=-1),
                trim=[[wiggle, back]])
    chord_tol = 1e-3
    rows = _kernel(s, [wiggle, back], chord_tol, uv_chords=False)
    assert len(rows[0]) > 10
    _check_piece(s, wiggle, rows[0], chord_tol, uv_chords=False)


def _domain_rectangle_only_numpy(surface, chord_tol):
    """The numpy version :func:`domain_rectangle_only` had before its kernel (the
    oracle)."""
    from geomkit.mesh.trim_polylines import speed_bound

    (u0, u1), (v0, v1) = surface.domain
    size_uv = max(u1 - u0, v1 - v0)
    lo, hi = 1e-12 * size_uv, 1e-6 * size_uv
    for loop in surface.trim:
        for c in loop.pieces:
            x, y = c.control_points[0].tolist()
            if min(abs(x - u0), abs(x - u1), abs(y - v0), abs(y - v1)) > hi:
                return False
    edges = np.array([u0, u1, v0, v1])
    full = (u1 - u0) * (v1 - v0)
    worst = 0.0
    for loop in surface.trim:
        pieces = loop.pieces
        P = np.concatenate([c.control_points for c in pieces])
        d = np.abs(P[:, [0, 0, 1, 1]] - edges)
        sizes = [len(c.control_points) for c in pieces]
        starts = np.cumsum([0] + sizes[:-1])
        seg = np.maximum(d[:-1], d[1:]).min(axis=1)
        inner = np.ones(len(seg), dtype=bool)
        inner[starts[1:] - 1] = False
        curved = np.array([c.degree > 1 for c in pieces])
        if curved.any():
            inner &= ~np.repeat(curved, sizes)[:-1]
            off = np.maximum.reduceat(d, starts, axis=0)[curved].min(axis=1).max()
            worst = max(worst, float(off))
        if inner.any():
            worst = max(worst, float(seg[inner].max()))
        x, y = P[:, 0], P[:, 1]
        area = 0.5 * abs(np.dot(x[:-1], y[1:]) - np.dot(x[1:], y[:-1])
                         + x[-1] * y[0] - x[0] * y[-1])
        worst = max(worst, abs(area - full) / (u1 - u0 + v1 - v0))
        if worst > hi:
            return False
    if worst <= lo:
        return True
    eps = min(hi, 1e-3 * chord_tol / max(speed_bound(surface), 1e-300))
    return worst <= max(eps, lo)


def test_domain_rectangle_only_matches_its_numpy_version():
    """The kernel's decision against the numpy code it replaces, on every trimmed face
    of four real parts (many are cylinders bounded by their own edges) and on domain
    rectangles moved by 1e-14 .. 1e-4 of the domain (the thresholds lie between)."""
    from geomkit.mesh.trim_polylines import domain_rectangle_only
    from geomkit.nurbs.trims import TrimCurve

    n_true = n = 0
    for part in ("nist_ftc_07_ap242.stp", "nist_ctc_05_ap203.stp", "proe_as1_ap203.stp",
                 "catia_v5_ventilator_swept_faces.stp"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            S = read_step(DATA / "parts" / part).surfaces
        for s in S:
            if s.trim:
                for ct in (1e-2, 1e-5):
                    want = _domain_rectangle_only_numpy(s, ct)
                    assert domain_rectangle_only(s, ct) == want
                    n_true += want
                    n += 1
    assert 0 < n_true < n
    rng = np.random.default_rng(2)
    arc = np.array([[2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    net = np.array([[[a[0], a[1], z] for a in arc] for z in (0.0, 3.0)])
    w = np.array([[1.0, np.sqrt(0.5), 1.0]] * 2)
    seen = set()
    for trial in range(300):
        jitter = 10.0 ** rng.uniform(-14, -4)
        corners = np.array([[0, 0], [3, 0], [3, 1], [0, 1], [0, 0]], dtype=float)
        k = int(rng.integers(0, 4))
        corners[k] += jitter * rng.standard_normal(2)
        if k == 0:
            corners[-1] = corners[0]
        if trial % 2:  # four pieces, the top one a quadratic along v = 1
            top = [corners[2], [1.3, 1.0 + jitter * rng.standard_normal()], corners[3]]
            loop = [TrimCurve.create(1, [0, 0, 1, 1], corners[0:2]),
                    TrimCurve.create(1, [0, 0, 1, 1], corners[1:3]),
                    TrimCurve.create(2, [0, 0, 0, 1, 1, 1], top, [1, 0.7, 1]),
                    TrimCurve.create(1, [0, 0, 1, 1], corners[3:5])]
        else:
            loop = corners
        try:
            s = Surface(1, 2, [0, 0, 3, 3], [0, 0, 0, 1, 1, 1], net, w, trim=[loop])
        except Exception:  # noqa: BLE001 - a jitter the validation refuses
            continue
        for ct in (1e-1, 1e-3, 1e-6):
            want = _domain_rectangle_only_numpy(s, ct)
            assert domain_rectangle_only(s, ct) == want, (trial, jitter, ct)
            seen.add(want)
    assert seen == {True, False}


def _is_domain_rectangle_numpy(pts, u0, u1, v0, v1, eps):
    """The numpy test :class:`TrimPolylines` made before ``loop_rectangle_gap``."""
    on = ((np.abs(pts[:, 0] - u0) <= eps) | (np.abs(pts[:, 0] - u1) <= eps)
          | (np.abs(pts[:, 1] - v0) <= eps) | (np.abs(pts[:, 1] - v1) <= eps))
    if not on.all():
        return False
    x, y = pts[:, 0], pts[:, 1]
    area = 0.5 * abs(np.sum(x[:-1] * y[1:] - x[1:] * y[:-1]))
    return bool(abs(area - (u1 - u0) * (v1 - v0)) <= eps * (u1 - u0 + v1 - v0))


def test_loop_rectangle_gap_decides_as_the_numpy_test():
    from geomkit._kernels.tess_trim import loop_rectangle_gap

    rng = np.random.default_rng(9)
    u0, u1, v0, v1 = -2.0, 5.0, 1.0, 1.5
    per = u1 - u0 + v1 - v0
    seen = set()
    for trial in range(400):
        # the rectangle walked with extra points on its edges, one point moved
        k = int(rng.integers(1, 6))
        t = np.sort(rng.random(k))
        pts = np.concatenate([np.c_[u0 + (u1 - u0) * t, np.full(k, v0)], [[u1, v0]],
                              np.c_[np.full(k, u1), v0 + (v1 - v0) * t], [[u1, v1]],
                              np.c_[u1 - (u1 - u0) * t, np.full(k, v1)], [[u0, v1]],
                              np.c_[np.full(k, u0), v1 - (v1 - v0) * t], [[u0, v0]]])
        pts = np.concatenate([[[u0, v0]], pts])
        i = int(rng.integers(0, len(pts)))
        pts[i] += 10.0 ** rng.uniform(-15, -3) * rng.standard_normal(2)
        if trial % 5 == 0:  # a loop well inside: not the rectangle
            pts = 0.5 * pts + [1.0, 0.6]
        gap, area_gap = loop_rectangle_gap(pts, u0, u1, v0, v1)
        for eps in (1e-12 * 7, 1e-9, 1e-6 * 7):
            want = _is_domain_rectangle_numpy(pts, u0, u1, v0, v1, eps)
            assert (gap <= eps and area_gap <= eps * per) == want, (trial, eps)
            seen.add(want)
    assert seen == {True, False}


def test_speed_bound_kernel_matches_its_numpy_formula():
    from geomkit.mesh.trim_polylines import speed_bound

    rng = np.random.default_rng(4)
    for trial in range(50):
        p, q = int(rng.integers(1, 4)), int(rng.integers(1, 4))
        nu, nv = p + 1 + int(rng.integers(0, 4)), q + 1 + int(rng.integers(0, 4))
        ku = np.r_[np.zeros(p), np.sort(rng.random(nu - p + 1)), np.ones(p)]
        kv = np.r_[np.zeros(q), np.sort(rng.random(nv - q + 1)), np.ones(q)]
        ku[p], ku[-p - 1], kv[q], kv[-q - 1] = 0.0, 1.0, 0.0, 1.0
        if trial % 3 == 0 and p > 1 and nu - p > 2:  # a double inner knot (a zero span)
            ku[p + 1] = ku[p + 2]
        P = rng.normal(size=(nu, nv, 3)) * 10.0 ** rng.uniform(-3, 3)
        W = np.exp(rng.uniform(-1, 1, (nu, nv))) if trial % 2 else None
        s = Surface(p, q, ku, kv, P, W)
        D = float(np.linalg.norm(np.ptp(P.reshape(-1, 3), axis=0)))
        ratio = 1.0 if W is None else float(W.max() / W.min())
        want = 0.0
        for deg, U in ((p, s.knots_u), (q, s.knots_v)):
            d = np.diff(U)
            want += 4.0 * deg * ratio * D / float(d[d > 0].min())
        assert abs(speed_bound(s) - want) <= 1e-14 * want


def _parabola_pieces(n, kink=None):
    """``y = 0.2 + 0.6 x^2`` (x in [0.1, 0.9]) as a quadratic B-spline of ``n`` spans,
    every interior knot of full multiplicity (each span the parabola's own Bezier
    piece: tangent-continuous at every knot); with ``kink = j`` the middle control
    points next to knot j are moved off so the curve has a corner there."""
    from geomkit.nurbs.trims import TrimCurve

    x = np.linspace(0.1, 0.9, n + 1)
    P = [[x[0], 0.2 + 0.6 * x[0] ** 2]]
    for i in range(n):
        m = [0.5 * (x[i] + x[i + 1]), 0.2 + 0.6 * x[i] * x[i + 1]]
        if kink is not None and i in (kink - 1, kink):
            m[1] += 1e-4  # a corner of 1e-3 in 3-D: a chord across it would pass
        P += [m, [x[i + 1], 0.2 + 0.6 * x[i + 1] ** 2]]
    t = np.linspace(0.0, 1.0, n + 1)
    knots = [0.0] * 3 + [v for v in t[1:-1] for _ in range(2)] + [1.0] * 3
    return TrimCurve.create(2, knots, np.array(P)), t


def test_smooth_knots_are_crossed_and_corners_kept():
    """A quadratic piece of 40 spans, every knot of full multiplicity: where the curve
    is tangent-continuous (all knots) its segments run across knots, far fewer
    vertices than knots, every segment within ``chord_tol``; with a corner at one
    knot (too small for the chord test to see), that knot is a vertex."""
    from geomkit.nurbs.trims import TrimCurve

    gu, gv = np.meshgrid(np.linspace(0, 10, 2), np.linspace(0, 10, 2), indexing="ij")
    flat = np.stack([gu, gv, 0 * gu], axis=-1)
    for kink in (None, 17):
        arc, t = _parabola_pieces(40, kink)
        P = arc.control_points
        back = TrimCurve.create(1, [0, 0, 1, 1], [P[-1], P[0]])
        s = Surface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], flat, trim=[[arc, back]])
        chord_tol = 1e-2
        rows = _kernel(s, [arc, back], chord_tol, uv_chords=False, cross_knots=True)
        _check_piece(s, arc, rows[0], chord_tol, uv_chords=False)
        assert len(rows[0]) < 20, len(rows[0])
        if kink is not None:
            assert t[kink] in rows[0][:, 0]
        # without cross_knots every knot is a vertex (the projector's polylines)
        held = _kernel(s, [arc, back], chord_tol, uv_chords=False)[0]
        _check_piece(s, arc, held, chord_tol, uv_chords=False)
        assert np.isin(t, held[:, 0]).all()


def test_classify_cells_matches_shapely():
    """``classify_cells`` (the cells of a trimmed grid or the adaptive lattice: cut by a
    loop, else in or out by the centre, even-odd over the rings) against shapely's
    segment/box intersection and point-in-polygon on random boxes: a wavy outer loop,
    a hole, and the domain rectangle as a last ring that is no cut (as
    ``TrimPolylines`` packs a loop that was the domain's)."""
    import shapely

    from geomkit._kernels.tess_lattice import classify_cells

    rng = np.random.default_rng(11)
    a = np.linspace(0.0, 2 * np.pi, 90)
    outer = np.c_[0.5 + (0.35 + 0.05 * np.sin(7 * a)) * np.cos(a),
                  0.5 + (0.35 + 0.05 * np.sin(7 * a)) * np.sin(a)]
    hole = np.c_[0.5 + 0.1 * np.cos(-a), 0.45 + 0.08 * np.sin(-a)]
    outer[-1], hole[-1] = outer[0], hole[0]
    rect = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], float)
    lo = rng.uniform(-0.05, 1.0, (4000, 2))
    wh = rng.uniform(0.0, 0.2, (4000, 2)) ** 2
    cells = np.ascontiguousarray(np.c_[lo[:, 0], lo[:, 0] + wh[:, 0], lo[:, 1],
                                       lo[:, 1] + wh[:, 1]])
    boxes = shapely.box(cells[:, 0], cells[:, 2], cells[:, 1], cells[:, 3])
    cu, cv = 0.5 * (cells[:, 0] + cells[:, 1]), 0.5 * (cells[:, 2] + cells[:, 3])
    for rings, n_cut, region in (
            ([outer, hole], 2, shapely.Polygon(outer, [hole])),
            ([hole, rect], 1, shapely.Polygon(rect, [hole]))):
        P = np.ascontiguousarray(np.concatenate(rings))
        starts = np.cumsum([0] + [len(r) for r in rings]).astype(np.int64)
        out = np.empty(len(cells), dtype=np.int8)
        classify_cells(P, starts, n_cut, cells, out)
        lines = shapely.multilinestrings([shapely.linestrings(r) for r in rings[:n_cut]])
        want = np.where(shapely.intersects(boxes, lines), 2,
                        shapely.contains_xy(region, cu, cv).astype(np.int8))
        assert np.array_equal(out, want), int((out != want).sum())
        assert set(np.unique(out)) == {0, 1, 2}
