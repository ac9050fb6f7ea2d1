"""The compiled closed-form inverse of the analytic surfaces (``Analytic.local``)
against the numpy formulas it replaced, on points all around each kind of surface:
beyond a cone's apex, on a spindle torus's inner part, on the axis."""

import math

import numpy as np
import pytest

from geomkit.cad.brep import Analytic


def _numpy_local(s, P):
    """The numpy reference: the formulas of the closed-form inverse."""
    d = np.asarray(P, float) - s.O
    x, y, z = d @ s.X, d @ s.Y, d @ s.A
    if s.kind == "plane":
        return np.column_stack([x, y]), np.ones(len(d))
    rho = np.hypot(x, y)
    th = np.arctan2(y, x)
    if s.kind in ("cylinder", "cone"):
        a = z
        if s.kind == "cone":
            th = np.where(s.R + z * math.tan(s.alpha) < 0, th + np.pi, th)
    elif s.kind == "sphere":
        a = np.arctan2(z, rho)
    else:
        a = np.arctan2(z, rho - s.R)
        if s.r > s.R:
            lemon = np.abs(np.hypot(rho + s.R, z) - s.r) < np.abs(np.hypot(rho - s.R, z) - s.r)
            a = np.where(lemon, np.arctan2(z, -rho - s.R), a)
            th = np.where(lemon, th + np.pi, th)
    return np.column_stack([a, th]), rho


SURFACES = {
    "plane": Analytic("plane", [1.0, -2.0, 0.5], [0.2, 0.3, 1.0], [1.0, 0.0, 0.0]),
    "cylinder": Analytic("cylinder", [0.0, 1.0, 2.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], R=3.0),
    "cone": Analytic("cone", [0.0, 0.0, 0.0], [0.3, -0.2, 1.0], [1.0, 0.0, 0.0], R=2.0,
                     alpha=0.4),
    "sphere": Analytic("sphere", [1.0, 1.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], R=5.0),
    "torus": Analytic("torus", [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], R=4.0,
                      r=1.0),
    "spindle torus": Analytic("torus", [0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0],
                              R=1.0, r=2.5),
}


@pytest.mark.parametrize("name", SURFACES)
def test_local_matches_the_numpy_formulas(name):
    s = SURFACES[name]
    rng = np.random.default_rng(7)
    P = rng.normal(size=(4000, 3)) * 6.0
    P[:50] = s.O + rng.normal(size=(50, 1)) * s.A  # on the axis
    if s.kind == "cone":  # beyond the apex: the other nappe
        apex = s.O - s.R / math.tan(s.alpha) * s.A
        P[50:100] = apex - rng.uniform(1.0, 3.0, (50, 1)) * s.A + 0.2 * rng.normal(size=(50, 3))
    ab, rho = s.local(P)
    ref, rref = _numpy_local(s, P)
    assert ab.shape == (4000, 2) and rho.shape == (4000,)
    np.testing.assert_allclose(rho, rref, rtol=4e-15, atol=1e-14)
    # angles agree to rounding, on the same branch (an angle at +-pi may take either
    # sign of pi: the sign of a zero y)
    d = np.abs(ab - ref)
    d[:, 1] = np.minimum(d[:, 1], np.abs(d[:, 1] - 2 * np.pi))
    assert d.max() <= 1e-13
    if s.kind == "cone":  # the other nappe's points are at the angle + pi
        beyond = s.R + (P - s.O) @ s.A * math.tan(s.alpha) < 0
        assert beyond[50:100].all()
    if s.kind == "torus" and s.r > s.R:
        assert (np.abs(ab[:, 1] - np.arctan2((P - s.O) @ s.Y, (P - s.O) @ s.X)) > 3).any()


def test_local_accepts_lists_and_strided_arrays():
    s = SURFACES["cylinder"]
    P = np.arange(30, dtype=float).reshape(10, 3)
    ab, _ = s.local(P[::2])
    np.testing.assert_array_equal(ab, s.local(P[::2].copy())[0])
    np.testing.assert_array_equal(s.local(P.tolist())[0], s.local(P)[0])


@pytest.mark.parametrize("name", ["cylinder", "cone", "torus", "plane"])
def test_edge_samples_and_their_inverse_in_one_call(name):
    """edge_local: the curve's samples as curve_eval gives them at the reader's
    linspace (to rounding) and local() of them, on a rational arc and a cubic."""
    from geomkit.cad.analytic import arc_curve, curve_eval
    from geomkit.cad.faceedges import _linspace
    from geomkit._kernels.pcurve_map import edge_local

    s = SURFACES[name]
    arc = arc_curve(np.array([0.5, 0.2, 1.0]), np.array([3.0, 0.0, 0.0]),
                    np.array([0.0, 3.0, 0.0]), 1.0, 0.3, 4.0)
    rng = np.random.default_rng(3)
    P = rng.normal(size=(7, 3)) * 4
    cubic = (3, np.array([0, 0, 0, 0, 0.3, 0.5, 0.9, 1, 1, 1, 1.0]),
             np.column_stack([P, np.ones(7)]))
    for (p, U, Pw), (t0, t1) in ((arc, (0.3, 4.0)), (cubic, (0.1, 0.95))):
        for n in (2, 9, 65):
            X, ab, rho = edge_local(np.ascontiguousarray(Pw, float), p, U, t0, t1, n,
                                    *s.inverse)
            ref = curve_eval((p, U, Pw), _linspace(t0, t1, n))
            np.testing.assert_allclose(X, ref, rtol=0, atol=1e-14 * np.abs(ref).max())
            ab2, rho2 = s.local(X)
            np.testing.assert_array_equal(ab, ab2)
            np.testing.assert_array_equal(rho, rho2)


def test_curve_at_is_curve_eval_bit_for_bit():
    """curve_at (an edge's samples in one call) gives curve_eval's points exactly on
    random rational curves of degrees 1 to 5, at the reader's parameters and at the
    knots and ends."""
    from geomkit.cad.analytic import curve_eval
    from geomkit.cad.faceedges import _linspace
    from geomkit._kernels.pcurve_map import curve_at

    rng = np.random.default_rng(9)
    for _ in range(200):
        p = int(rng.integers(1, 6))
        n = p + 1 + int(rng.integers(0, 6))
        inner = np.sort(rng.uniform(0.0, 1.0, n - p - 1))
        U = np.concatenate([[0.0] * (p + 1), inner, [1.0] * (p + 1)]) * 3.0 - 1.0
        w = rng.uniform(0.2, 3.0, n)
        Pw = np.column_stack([rng.normal(size=(n, 3)) * w[:, None], w])
        for t in (_linspace(-1.0, 2.0, int(rng.integers(2, 70))), U.copy()):
            np.testing.assert_array_equal(curve_at(Pw, p, U, t), curve_eval((p, U, Pw), t))


@pytest.mark.parametrize("name", ["cylinder", "cone", "torus", "spindle torus"])
def test_edge_turn_against_the_methods_it_replaces(name):
    """Edge.turn (one edge_turn call): the same nearest distance to the axis, spread
    and unwrapped loop-order coordinates as the per-method route (local, np.ptp,
    np.unwrap), bit for bit, both ways along the edge, from the curve or from samples
    already taken; a NaN sample gives -inf and NaN as the methods do."""
    from geomkit.cad.analytic import arc_curve
    from geomkit.cad.faceedges import NS as _NS, Edge

    s = SURFACES[name]
    # an arc around the axis (crossing the angle branch cut) and a wild cubic
    arc = arc_curve(s.O + 0.3 * s.A, 3.5 * s.X, 3.5 * s.Y, 1.0, 0.3, 6.0)
    rng = np.random.default_rng(5)
    P = rng.normal(size=(7, 3)) * 4
    cubic = (3, np.array([0, 0, 0, 0, 0.3, 0.5, 0.9, 1, 1, 1, 1.0]),
             np.column_stack([P, np.ones(7)]))
    for curve in (arc, cubic):
        for rev in (False, True):
            for pre in (False, True):
                e, ref = Edge(curve, 1, rev), Edge(curve, 1, rev)
                if pre:  # samples already taken (curve_eval's): turn inverts those
                    e.points(_NS)
                    ref.points(_NS)
                nearest, spread, W = e.turn(s)
                ab, rho = ref.local(s, _NS)
                assert nearest == float(rho.min())
                assert spread == float(np.ptp(ref.points(_NS), axis=0).max())
                for c in (0, 1):
                    want = np.unwrap(ab[:, c]) if s.periodic[c] else ab[:, c]
                    np.testing.assert_array_equal(W[:, c], want)
                assert not W.flags.writeable
                # the other methods read the cache turn filled: the same values
                np.testing.assert_array_equal(e.local(s, _NS)[0], ab)
                assert e.nearest_axis(s, _NS) == nearest and e.spread(_NS) == spread
    bad = (cubic[0], cubic[1], cubic[2].copy())
    bad[2][3, 0] = np.nan
    nearest, spread, _ = Edge(bad, 2, False).turn(s)
    assert nearest == -np.inf and np.isnan(spread)


def test_iso_ends_against_the_numpy_iso_test_and_angle_maps():
    """iso_ends: the iso flags of the numpy test, the mapped ends of AngleMap (to
    rounding), NaN samples never iso, non-finite ends refused."""
    from geomkit.cad.analytic import AngleMap
    from geomkit._kernels.pcurve_map import iso_ends

    rng = np.random.default_rng(11)
    for _ in range(500):
        ab = rng.normal(size=(65, 2))
        flat = rng.integers(0, 3)  # 0: coordinate 0 iso, 1: coordinate 1, 2: none
        if flat < 2:
            ab[:, flat] = ab[0, flat] + rng.uniform(-1, 1, 65) * 1e-12
        t0 = rng.uniform(-4, 0)
        fmap = AngleMap(t0 - 3.0, t0 + 6.0)
        maps = np.array([[0.0, 0.0, 0.0], [1.0, fmap.theta0, fmap.theta1]])
        iso0, iso1, q = iso_ends(ab, 1e-10, maps)
        dev = np.abs(ab - ab[0]).max(axis=0)
        assert (iso0, iso1) == (dev[0] <= 1e-10, dev[1] <= 1e-10)
        want = np.array([ab[0], ab[-1]])
        for k, iso in enumerate((iso0, iso1)):
            if iso:
                want[:, k] = ab[0, k]
        want[:, 1] = fmap(want[:, 1])
        np.testing.assert_allclose(q, want, rtol=0, atol=1e-14)
    ab = np.zeros((9, 2))
    ab[4, 0] = np.nan
    iso0, iso1, _ = iso_ends(ab, 1e-10, np.zeros((2, 3)))
    assert not iso0 and iso1
    ab[-1, 1] = np.inf
    assert iso_ends(ab, 1e-10, np.zeros((2, 3))) is None


def _numpy_margins(paths, spans, cand):
    """The numpy reference of the seam angle's margins (the formulas it replaced)."""
    two_pi = 2 * np.pi
    ok = np.ones(cand.size, bool)
    for path in paths:
        lo = np.minimum(path[:-1], path[1:])[:, None]
        hi = np.maximum(path[:-1], path[1:])[:, None]
        first = np.ceil((lo - cand[None]) / two_pi)
        last = np.floor((hi - cand[None]) / two_pi)
        ok &= np.maximum(last - first + 1, 0).sum(axis=0) == 1
    margin = np.full(cand.size, np.pi)
    for lo, hi in spans:
        c = (cand - lo) % two_pi
        inside = c <= hi - lo
        margin = np.where(inside, -1.0, np.minimum(margin, np.minimum(c - (hi - lo),
                                                                      two_pi - c)))
    margin[~ok] = -1.0
    return margin


def test_seam_margins_against_numpy():
    """Loops going once (or twice, or back) around the axis, other loops' spans: the
    compiled margins are numpy's bit for bit."""
    from geomkit.cad.stepseam import _CANDIDATES
    from geomkit._kernels.seam import seam_margins

    rng = np.random.default_rng(5)
    for _ in range(300):
        paths = []
        for _ in range(rng.integers(0, 3)):
            turns = rng.choice([1, -1, 2])
            n = rng.integers(5, 200)
            a0 = rng.uniform(-7, 7)
            steps = rng.uniform(0, 1, n - 1)
            steps *= turns * 2 * np.pi / steps.sum()
            steps += rng.normal(0, 0.05, n - 1)  # wiggles back and forth
            paths.append(np.concatenate([[a0], a0 + np.cumsum(steps)]))
        spans = [tuple(sorted(rng.uniform(-7, 7, 2))) for _ in range(rng.integers(0, 4))]
        starts = np.cumsum([0] + [len(p) for p in paths])
        got = seam_margins(np.concatenate(paths) if paths else np.zeros(0), starts,
                           np.array(spans, dtype=np.float64).reshape(-1, 2), _CANDIDATES)
        np.testing.assert_array_equal(got, _numpy_margins(paths, spans, _CANDIDATES))


def test_seam_margins_at_candidates_long_steps_and_uneven_candidates():
    """The windowed count (evenly spaced candidates) against numpy where it is
    tightest: path samples exactly on candidate angles (a turn away too), steps
    longer than a turn, NaN angles, and candidates that are not evenly spaced (every
    candidate counted)."""
    from geomkit.cad.stepseam import _CANDIDATES
    from geomkit._kernels.seam import seam_margins

    rng = np.random.default_rng(8)
    uneven = np.sort(rng.uniform(0, 2 * np.pi, 300))
    for trial in range(200):
        cand = uneven if trial % 4 == 3 else _CANDIDATES
        paths = []
        for _ in range(rng.integers(1, 3)):
            n = rng.integers(3, 60)
            pts = rng.choice(cand, n) + 2 * np.pi * rng.integers(-2, 3, n)
            if trial % 5 == 0:  # long steps
                pts[1:] += np.cumsum(rng.uniform(0, 9, n - 1))
            pts.sort() if trial % 2 else None
            paths.append(pts)
        if trial == 7:
            paths[0][1] = np.nan
        spans = [tuple(sorted(rng.uniform(-7, 7, 2))) for _ in range(rng.integers(0, 3))]
        starts = np.cumsum([0] + [len(p) for p in paths])
        got = seam_margins(np.concatenate(paths), starts,
                           np.array(spans, dtype=np.float64).reshape(-1, 2), cand)
        np.testing.assert_array_equal(got, _numpy_margins(paths, spans, cand))


def _numpy_plane_piece(curve, reverse, s):
    """The numpy reference of a plane face's piece: the edge's NURBS with its
    control points mapped into the plane's frame, run in loop order."""
    from geomkit.nurbs.surface import TrimCurve
    p, U, Pw = curve
    w = Pw[:, 3]
    d = Pw[:, :3] / w[:, None] - s.O
    Q = np.column_stack([d @ s.X, d @ s.Y])
    if reverse:
        U = (U[0] + U[-1]) - np.asarray(U)[::-1]
        Q, w = Q[::-1], w[::-1]
    return TrimCurve.create(p, U, Q, None if np.all(w == w[0]) else w)


@pytest.mark.parametrize("seed", range(3))
def test_plane_piece_against_numpy(seed):
    """``_plane_piece`` (one compiled call) against the numpy route on random
    rational and polynomial edges with repeated knots, both ways round; a curve
    with a bad knot vector or a zero weight is refused as ``TrimCurve.create``
    refuses it."""
    from geomkit.cad.faceedges import _plane_piece
    from geomkit.errors import InvalidTrimError
    rng = np.random.default_rng(seed)
    s = SURFACES["plane"]
    worst = 0.0
    for _ in range(300):
        p = int(rng.integers(1, 5))
        n = p + 1 + int(rng.integers(0, 4))
        inner = np.sort(rng.choice([0.25, 0.5, 0.75], n - p - 1))
        if n - p - 1 and np.unique(inner, return_counts=True)[1].max() > p:
            inner = np.linspace(0, 1, n - p + 1)[1:-1]
        U = np.concatenate([np.zeros(p + 1), inner, np.ones(p + 1)]) * 3.0 - 1.0
        w = np.full(n, rng.choice([1.0, 2.0])) if rng.random() < 0.4 else \
            rng.uniform(0.3, 3.0, n)
        P = rng.normal(0, 5, (n, 3))
        curve = (p, U, np.column_stack([P * w[:, None], w]))
        for rev in (False, True):
            a, b = _plane_piece(curve, rev, s), _numpy_plane_piece(curve, rev, s)
            assert a.degree == b.degree
            assert np.array_equal(a.knots, b.knots) and np.array_equal(a.weights, b.weights)
            worst = max(worst, float(np.abs(a.control_points - b.control_points).max()))
    assert worst <= 1e-14 * 5.0 * 8
    p, U, Pw = curve
    for bad in ((p, U[::-1].copy(), Pw), (p, U[:-1].copy(), Pw)):
        with pytest.raises(InvalidTrimError, match="knots"):
            _plane_piece(bad, False, s)
    Pw0 = Pw.copy()
    Pw0[0, 3] = 0.0
    with pytest.raises(InvalidTrimError):
        _plane_piece((p, U, Pw0), False, s)


def test_plane_piece_that_is_no_trim_curve_is_named():
    """A plane face's piece with a non-finite control point or a weight <= 0 is not
    kept as it stands: TrimCurve.create names the fault."""
    from geomkit.cad.faceedges import _plane_piece
    from geomkit.errors import InvalidTrimError

    s = SURFACES["plane"]
    U = np.array([0.0, 0.0, 0.0, 1.0, 1.0, 1.0])
    Pw = np.array([[1.0, 0, 0, 1], [0.5, 0.5, 0, 0.5], [0, 1.0, 0, 1]])
    c = _plane_piece((2, U, Pw), False, s)
    assert np.isfinite(c.control_points).all() and (c.weights > 0).all()
    bad = Pw.copy()
    bad[1, 0] = np.inf
    with pytest.raises(InvalidTrimError):
        _plane_piece((2, U, bad), True, s)
    bad = Pw.copy()
    bad[1] *= -1.0  # weight -0.5
    with pytest.raises(InvalidTrimError, match="weight"):
        _plane_piece((2, U, bad), False, s)


def _numpy_residual(s, P):
    """The numpy reference of the distance from an analytic surface (closed forms)."""
    d = np.asarray(P, float) - s.O
    h = d @ s.A
    rho = np.linalg.norm(d - h[:, None] * s.A, axis=1)
    if s.kind == "plane":
        return np.abs(h)
    if s.kind == "cylinder":
        return np.abs(rho - s.R)
    if s.kind == "cone":  # both nappes
        return np.abs(rho - np.abs(s.R + h * math.tan(s.alpha))) * math.cos(s.alpha)
    if s.kind == "sphere":
        return np.abs(np.hypot(rho, h) - s.R)
    out = np.abs(np.hypot(rho - s.R, h) - s.r)
    if s.r > s.R:  # a spindle torus's inner part
        out = np.minimum(out, np.abs(np.hypot(rho + s.R, h) - s.r))
    return out


@pytest.mark.parametrize("name", SURFACES)
def test_worst_residual_is_the_largest_numpy_residual(name):
    """Analytic.worst_residual (one compiled call) against the numpy closed forms'
    largest value (the reader's former route), to rounding, on random points all around (a cone's other nappe, a
    spindle torus's inner part), jittered at several scales; NaN when a point is."""
    s = SURFACES[name]
    rng = np.random.default_rng(2)
    for scale in (1e-9, 1e-3, 1.0, 10.0):
        P = rng.normal(size=(60, 3)) * 6.0 + scale * rng.normal(size=(60, 3))
        ref = float(_numpy_residual(s, P).max())
        assert s.worst_residual(P) == pytest.approx(ref, rel=1e-12, abs=1e-13)
    P[7, 1] = np.nan
    assert np.isnan(s.worst_residual(P))


def test_spans_net_matches_numpy_route():
    """uvmap.spans_curve's kernel against its former numpy assembly."""
    from geomkit._kernels.pcurve_map import spans_net

    rng = np.random.default_rng(5)
    for trial in range(500):
        k = int(rng.integers(1, 40))
        starts = np.sort(rng.uniform(0.0, 1.0, k))
        if trial % 7 == 0 and k > 1:
            starts[1] = starts[0]  # a repeated start: not ok
        bez = rng.normal(size=(k, 6, 2))
        if trial % 11 == 0:
            bez[rng.integers(k), rng.integers(6), 0] = np.nan
        end = 1.0 if trial % 13 else float(starts[-1])
        perm = rng.permutation(k)
        S, B = starts[perm], bez[perm]
        order = np.argsort(S, kind="stable")
        A, Bo = S[order], B[order]
        pts = np.concatenate([Bo[:1, 0], Bo[:, 1:].reshape(-1, 2)])
        knots = np.concatenate([np.full(6, A[0]), np.repeat(A[1:], 5), np.full(6, end)])
        ok = bool(np.isfinite(pts).all() and A[0] < end and (A[1:] > A[:-1]).all()
                  and A[-1] < end)
        got = spans_net(S, B, end)
        assert got[0] == ok
        if ok:
            assert np.array_equal(got[1], knots) and np.array_equal(got[2], pts)


def test_curve_at_even_is_curve_at_of_the_linspace():
    """Edge.points' one call (curve_at_even: the linspace parameters made in the
    kernel, each i * step + t0 rounded twice) against curve_at of the reader's
    linspace, bit for bit, on random rational curves of degrees 1 to 5 with knots
    of several scales and offsets, at the counts the readers take and others."""
    from geomkit.cad.faceedges import _linspace
    from geomkit._kernels.pcurve_map import curve_at, curve_at_even

    rng = np.random.default_rng(9)
    for _ in range(1000):
        p = int(rng.integers(1, 6))
        n = p + 1 + int(rng.integers(0, 6))
        inner = np.sort(rng.uniform(0.0, 1.0, n - p - 1))
        U = (np.concatenate([[0.0] * (p + 1), inner, [1.0] * (p + 1)])
             * 10.0 ** rng.integers(-3, 4) + rng.normal() * 10.0 ** rng.integers(-2, 3))
        w = rng.uniform(0.2, 3.0, n)
        Pw = np.column_stack([rng.normal(size=(n, 3)) * w[:, None], w])
        m = int(rng.choice([2, 3, 9, 17, 33, 65, 257, int(rng.integers(2, 100))]))
        t0, t1 = float(U[p]), float(U[-p - 1])
        np.testing.assert_array_equal(curve_at_even(Pw, p, U, t0, t1, m),
                                      curve_at(Pw, p, U, _linspace(t0, t1, m)))
