"""Chebyshev fits (minimum zone, circumscribed, inscribed) against constructed
contact configurations, brute force, linprog on linearised problems, and errors."""

from __future__ import annotations

import itertools
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.optimize import linprog

sys.path.insert(0, str(Path(__file__).parent))
import fitcases as C  # noqa: E402

from geomkit.errors import DegenerateGeometryError, InvalidInputError  # noqa: E402
from geomkit.fitting import fit  # noqa: E402

WORST = {}
H = 0.01


def _check(key, res, want, size, width):
    err = max(C.geometry_error(res, want, size), abs(res.form_error - width) / size)
    WORST[key] = max(WORST.get(key, 0.0), err)
    assert err < 1e-9, (key, err)
    assert res.optimality["met"], res.optimality
    assert res.optimality["kkt_residual"] < 1e-8


def _fill(rng, m, lo, hi):
    return rng.uniform(lo, hi, m)


@pytest.mark.parametrize("config", ["3-1", "2-2"])
@pytest.mark.parametrize("n", [10, 20000])
def test_flatness_constructed(config, n):
    rng = np.random.default_rng(n)
    R, t = C.pose(n + len(config))
    if config == "3-1":
        xy = np.array([[10, 0], [-5, 8.66], [-5, -8.66], [1, 1.5]])
        z = [H, H, H, -H]
    else:
        xy = np.array([[10, 0], [-10, 0], [0, 9], [0, -9]])
        z = [H, H, -H, -H]
    xy = np.vstack([xy, rng.uniform(-4, 4, (n - 4, 2))])
    z = np.concatenate([z, _fill(rng, n - 4, -0.9 * H, 0.9 * H)])
    res = fit(C.place(np.column_stack([xy, z]), R, t), "plane", "minzone")
    _check(f"minzone plane {config}", res, C.truth("plane", R, t), 10.0, 2 * H)
    assert set(res.contacts.tolist()) == {0, 1, 2, 3}


def _brute_flatness(P):
    """Exact minimum-zone flatness: every optimum normal is that of 3 points or the
    common normal of two point pairs."""
    best = np.inf
    cands = []
    for i, j, k in itertools.combinations(range(len(P)), 3):
        cands.append(np.cross(P[j] - P[i], P[k] - P[i]))
    for (i, j), (k, m) in itertools.combinations(itertools.combinations(range(len(P)), 2), 2):
        cands.append(np.cross(P[j] - P[i], P[m] - P[k]))
    for nrm in cands:
        ln = np.linalg.norm(nrm)
        if ln > 1e-12:
            d = P @ (nrm / ln)
            best = min(best, d.max() - d.min())
    return best


@settings(deadline=None, max_examples=15)
@given(seed=st.integers(0, 10_000))
def test_flatness_brute_force(seed):
    rng = np.random.default_rng(seed)
    P = np.column_stack([rng.uniform(-5, 5, (12, 2)), rng.uniform(-0.5, 0.5, 12)])
    R, t = C.pose(seed, offset=100.0)
    res = fit(C.place(P, R, t), "plane", "minzone")
    want = _brute_flatness(P)
    assert res.form_error == pytest.approx(want, abs=1e-9 * 5)
    assert res.form_error <= fit(P, "plane").form_error + 1e-12
    WORST["minzone plane brute"] = max(WORST.get("minzone plane brute", 0),
                                        abs(res.form_error - want) / 5)


def _lp_chebyshev(A, b):
    """min_x max_i |A_i x - b_i| by linprog (oracle for linearised problems)."""
    m, k = A.shape
    Aub = np.vstack([np.column_stack([A, -np.ones(m)]), np.column_stack([-A, -np.ones(m)])])
    s = np.abs(b).max()             # HiGHS tolerances are absolute: scale b to 1
    bub = np.concatenate([b, -b]) / s
    c = np.zeros(k + 1)
    c[-1] = 1
    r = linprog(c, A_ub=Aub, b_ub=bub, bounds=[(None, None)] * (k + 1), method="highs",
                options={"primal_feasibility_tolerance": 1e-10,
                         "dual_feasibility_tolerance": 1e-10})
    return 2 * s * np.abs(A @ r.x[:-1] - b / s).max()


@pytest.mark.parametrize("kind", ["plane", "circle", "sphere", "cylinder"])
def test_small_form_deviation_matches_linprog(kind):
    """Form deviations of 1e-7 x size: the linearised Chebyshev problem (an LP)
    equals the exact one to O(1e-14 x size)."""
    rng = np.random.default_rng(len(kind))
    n = 400
    P, N = C.BUILDERS[kind](n, rng)
    size = {"plane": 10.0, "circle": 5.0, "sphere": 7.0, "cylinder": 20.0}[kind]
    e = rng.uniform(-1e-7, 1e-7, n) * size
    Q = P + e[:, None] * N
    if kind == "plane":
        A = np.column_stack([P[:, 0], P[:, 1], np.ones(n)])
    elif kind in ("circle", "sphere"):
        d = 2 if kind == "circle" else 3
        A = np.column_stack([N[:, :d], np.ones(n)])
    else:
        z = P[:, 2]
        A = np.column_stack([N[:, 0], N[:, 1], z * N[:, 0], z * N[:, 1], np.ones(n)])
    want = _lp_chebyshev(A, e)
    R, t = C.pose(3, offset=1e3)
    res = fit(C.place(Q, R, t), kind, "minzone")
    assert res.form_error == pytest.approx(want, abs=1e-10 * size)
    assert res.optimality["met"]


def test_roundness_constructed():
    rng = np.random.default_rng(2)
    R, t = C.pose(4)
    ang = np.array([0.3, 1.9, 3.0, 4.4])
    rad = 5 + H * np.array([1, -1, 1, -1])
    a2 = rng.uniform(0, 2 * np.pi, 300)
    r2 = 5 + rng.uniform(-0.9 * H, 0.9 * H, 300)
    A, Rr = np.concatenate([ang, a2]), np.concatenate([rad, r2])
    P = C.place(np.column_stack([Rr * np.cos(A), Rr * np.sin(A), 0 * A]), R, t)
    res = fit(P, "circle", "minzone")
    _check("minzone circle", res, C.truth("circle", R, t), 5.0, 2 * H)
    assert res.contacts.tolist() == [0, 1, 2, 3]


def _brute_min_circle(Y):
    best = np.inf
    for i, j in itertools.combinations(range(len(Y)), 2):
        c = 0.5 * (Y[i] + Y[j])
        r = np.linalg.norm(Y[i] - c)
        if np.linalg.norm(Y - c, axis=1).max() <= r * (1 + 1e-12):
            best = min(best, r)
    for i, j, k in itertools.combinations(range(len(Y)), 3):
        a, b = Y[j] - Y[i], Y[k] - Y[i]
        d = 2 * (a[0] * b[1] - a[1] * b[0])
        if abs(d) < 1e-12:
            continue
        c = Y[i] + np.array([b[1] * (a @ a) - a[1] * (b @ b),
                             a[0] * (b @ b) - b[0] * (a @ a)]) / d
        r = np.linalg.norm(Y[i] - c)
        if np.linalg.norm(Y - c, axis=1).max() <= r * (1 + 1e-12):
            best = min(best, r)
    return best


@settings(deadline=None, max_examples=20)
@given(seed=st.integers(0, 10_000))
def test_min_circumscribed_circle_brute_force(seed):
    rng = np.random.default_rng(seed)
    m = 12
    th = rng.uniform(0, 2 * np.pi, m)
    rr = 5 + rng.uniform(-0.5, 0.5, m)
    Y = np.column_stack([rr * np.cos(th), rr * np.sin(th)])
    R, t = C.pose(seed)
    res = fit(C.place(np.column_stack([Y, np.zeros(m)]), R, t), "circle",
              "mincircumscribed")
    want = _brute_min_circle(Y)
    WORST["mincircumscribed circle brute"] = max(
        WORST.get("mincircumscribed circle brute", 0), abs(res.radius - want) / 5)
    assert res.radius == pytest.approx(want, abs=1e-9 * 5)
    assert res.optimality["met"]


@pytest.mark.parametrize("method", ["mincircumscribed", "maxinscribed"])
def test_circle_sphere_extreme_constructed(method):
    """Three (circle) / four (sphere) contacts at radius R surrounding the centre,
    the other points strictly inside (circumscribed) or outside (inscribed)."""
    rng = np.random.default_rng(8)
    R, t = C.pose(12)
    sgn = -1 if method == "mincircumscribed" else 1
    th = np.concatenate([[0.1, 2.3, 4.2], rng.uniform(0, 2 * np.pi, 200)])
    rr = np.concatenate([[5.0] * 3, 5 + sgn * rng.uniform(0.001, 0.02, 200)])
    P = C.place(np.column_stack([rr * np.cos(th), rr * np.sin(th), 0 * th]), R, t)
    res = fit(P, "circle", method)
    _check(f"{method} circle", res, {"center": t, "radius": 5.0}, 5.0, res.form_error)
    assert res.contacts.tolist() == [0, 1, 2]
    tet = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]) / np.sqrt(3)
    U = np.vstack([tet, C.sphere(300, rng)[1]])
    rr = np.concatenate([[7.0] * 4, 7 + sgn * rng.uniform(0.001, 0.02, 300)])
    res = fit(C.place(rr[:, None] * U, R, t), "sphere", method)
    _check(f"{method} sphere", res, {"center": t, "radius": 7.0}, 7.0, res.form_error)


def test_sphere_minzone_constructed():
    rng = np.random.default_rng(9)
    R, t = C.pose(13)
    ang = np.array([0.0, 2.1, 4.0])
    outer = np.column_stack([np.cos(ang), np.sin(ang), np.zeros(3)])
    inner = np.array([[0.0, 0, 1], [0, 0, -1]])
    U = np.vstack([outer, inner, C.sphere(400, rng)[1]])
    rr = np.concatenate([[7 + H] * 3, [7 - H] * 2, 7 + rng.uniform(-0.9 * H, 0.9 * H, 400)])
    res = fit(C.place(rr[:, None] * U, R, t), "sphere", "minzone")
    _check("minzone sphere", res, {"center": t, "radius": 7.0}, 7.0, 2 * H)


def _two_ring(rng, base, signs, n, kind="cylinder", phi=0.0):
    """Cylinder / cone with alternating contacts (+, -, +, -) at two heights."""
    ang = np.array([0, np.pi / 2, np.pi, 1.5 * np.pi] * 2) + 0.2
    z = np.array([40.0] * 4 + [10.0] * 4)
    a2 = rng.uniform(0, 2 * np.pi, n)
    z2 = rng.uniform(10, 40, n)
    A = np.concatenate([ang, a2])
    Z = np.concatenate([z, z2])
    dev = np.concatenate([signs * H, rng.uniform(-0.9 * H, 0.9 * H, n)])
    r = base + Z * np.tan(phi)
    N = np.column_stack([np.cos(phi) * np.cos(A), np.cos(phi) * np.sin(A),
                         -np.sin(phi) * np.ones_like(A)])
    P = np.column_stack([r * np.cos(A), r * np.sin(A), Z]) + dev[:, None] * N
    return P


@pytest.mark.parametrize("n", [10, 5000])
def test_cylinder_and_cone_minzone_constructed(n):
    rng = np.random.default_rng(n)
    R, t = C.pose(n)
    s = np.array([1, -1, 1, -1] * 2, dtype=float)
    P = _two_ring(rng, 20.0, s, n)
    P[:, 2] -= 25.0
    res = fit(C.place(P, R, t), "cylinder", "minzone")
    _check("minzone cylinder", res, C.truth("cylinder", R, t), 50.0, 2 * H)
    P = _two_ring(rng, 0.0, s, n, phi=0.3)
    res = fit(C.place(P, R, t), "cone", "minzone")
    _check("minzone cone", res, C.truth("cone", R, t), 40.0, 2 * H)


def test_cylinder_extremes_and_line_constructed():
    rng = np.random.default_rng(5)
    R, t = C.pose(6)
    # circumscribed / straightness: 4 contacts at radius 20 (two diameters at the
    # two ends), the rest inside; inscribed: the same outside.
    for method, sgn in (("mincircumscribed", -1), ("maxinscribed", 1)):
        ang = np.array([0.2, 0.2 + np.pi, 0.2 + 2.1, 0.2 + 4.2])
        if method == "maxinscribed":   # 3 per end, surrounding the axis
            ang = np.array([0.2, 2.3, 4.3, 1.0, 3.1, 5.2])
            z = np.array([30.0] * 3 + [-30.0] * 3)
        else:
            ang = np.array([0.2, 0.2 + np.pi, 1.2, 1.2 + np.pi])
            z = np.array([30.0, 30.0, -30.0, -30.0])
        k = ang.shape[0]
        A = np.concatenate([ang, rng.uniform(0, 2 * np.pi, 300)])
        Z = np.concatenate([z, rng.uniform(-30, 30, 300)])
        rr = np.concatenate([[20.0] * k, 20 + sgn * rng.uniform(0.001, 0.05, 300)])
        P = C.place(np.column_stack([rr * np.cos(A), rr * np.sin(A), Z]), R, t)
        res = fit(P, "cylinder", method)
        _check(f"{method} cylinder", res, C.truth("cylinder", R, t), 50.0, res.form_error)
        assert sorted(res.contacts.tolist()) == list(range(k))
        if method == "mincircumscribed":
            # Diametral contacts: the objective rises only as (offset)^2 / 2R, so
            # the data fix the axis to ~sqrt(eps R L) ~ 1e-7 (any solver); the
            # zone width is exact.
            ln = fit(P, "line", "minzone")
            assert ln.form_error == pytest.approx(40.0, abs=1e-12 * 50)
            assert ln.optimality["met"] and sorted(ln.contacts.tolist()) == [0, 1, 2, 3]
            err = C.geometry_error(ln, {"point": t, "direction": R[:, 2]}, 50.0)
            WORST["minzone line (flat optimum) geometry"] = err
            assert err < 1e-7


@settings(deadline=None, max_examples=30)
@given(seed=st.integers(0, 10_000),
       kind=st.sampled_from(["plane", "circle", "sphere", "cylinder", "cone", "line"]))
def test_minzone_invariance_and_bounds(seed, kind):
    """Rigid motion and point order change nothing; minzone <= lsq form error."""
    rng = np.random.default_rng(seed)
    n = 40
    P, N = C.BUILDERS[kind](n, rng)
    if N is None:
        P = P + rng.normal(0, 0.05, P.shape) * [1, 1, 0]
    else:
        P = P + rng.normal(0, 0.02, (n, 1)) * N
    a = fit(P, kind, "minzone")
    R, t = C.pose(seed, offset=rng.uniform(0, 1e3))
    perm = rng.permutation(n)
    b = fit(C.place(P, R, t)[perm], kind, "minzone")
    assert b.form_error == pytest.approx(a.form_error, abs=1e-9 * 40)
    assert a.optimality["met"] and b.optimality["met"]
    assert sorted(perm[b.contacts].tolist()) == sorted(a.contacts.tolist())
    lsq = fit(P, kind)
    assert a.form_error <= lsq.form_error + 1e-12


@pytest.mark.parametrize("args, cls, text", [
    (([[0, 0, 0], [1, 0, 0]], "plane"), InvalidInputError, "at least 3"),
    (([[0, 0, 0]], "line"), InvalidInputError, "at least 2"),
    ((np.zeros((5, 3)), "cone"), InvalidInputError, "at least 6"),
    ((np.zeros((4, 3)), "cylinder"), InvalidInputError, "at least 5"),
    ((np.zeros((3, 3)), "sphere"), InvalidInputError, "at least 4"),
    (([[0, 0, 0], [1, 0, np.nan], [0, 1, 0]], "plane"), InvalidInputError, "non-finite"),
    ((np.zeros((5, 2)), "plane"), InvalidInputError, "shape"),
    ((np.zeros((5, 3)), "torus"), InvalidInputError, "unknown kind"),
    ((np.zeros((5, 3)), "plane", "l1"), InvalidInputError, "unknown method"),
    ((np.zeros((5, 3)), "plane", "mincircumscribed"), InvalidInputError, "not defined"),
    ((np.zeros((9, 3)), "cone", "maxinscribed"), InvalidInputError, "not defined"),
    ((np.outer(np.arange(5.0), [1, 2, 3]), "plane"), DegenerateGeometryError, "collinear"),
    ((np.outer(np.arange(5.0), [1, 2, 3]), "circle"), DegenerateGeometryError, "collinear"),
    ((np.outer(np.arange(6.0), [1, 2, 3]), "cylinder"), DegenerateGeometryError, "line"),
    ((C.circle(9, np.random.default_rng(0))[0], "sphere"), DegenerateGeometryError,
     "coplanar"),
    ((np.ones((6, 3)), "line"), DegenerateGeometryError, "coincide"),
])
def test_errors(args, cls, text):
    with pytest.raises(cls, match=text) as info:
        fit(*args)
    assert "\n" not in str(info.value)


def test_zz_report(capsys):
    with capsys.disabled():
        for k, v in sorted(WORST.items()):
            print(f"\n  worst {k}: {v:.2e}", end="")
        print()
