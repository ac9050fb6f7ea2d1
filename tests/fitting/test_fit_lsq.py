"""Least-squares fits against known solutions, scipy's least_squares and invariances."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.optimize import least_squares

sys.path.insert(0, str(Path(__file__).parent))
import fitcases as C  # noqa: E402

from geomkit.fitting import FitResult, fit  # noqa: E402

KINDS = ["plane", "line", "circle", "sphere", "cylinder", "cone"]
SIZE = {"plane": 10.0, "line": 30.0, "circle": 5.0, "sphere": 7.0, "cylinder": 50.0,
        "cone": 40.0}
WORST = {}   # kind -> worst error seen (printed by test_zz_report)


def _record(key, err):
    WORST[key] = max(WORST.get(key, 0.0), err)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("n", [10, 1000])
def test_noise_free_far_from_origin(kind, n):
    rng = np.random.default_rng(n)
    R, t = C.pose(n + len(kind))
    P, _ = C.BUILDERS[kind](n, rng)
    res = fit(C.place(P, R, t), kind)
    err = C.geometry_error(res, C.truth(kind, R, t), SIZE[kind])
    _record(f"lsq {kind} noise-free", err)
    assert err < 1e-9
    assert res.form_error < 1e-9 * SIZE[kind]
    assert np.abs(res.residuals).max() < 1e-9 * SIZE[kind]


@pytest.mark.parametrize("kind", ["plane", "circle", "sphere", "cylinder", "cone"])
@pytest.mark.parametrize("n", [10, 2000])
def test_symmetric_deviations_give_the_nominal(kind, n):
    rng = np.random.default_rng(7 * n)
    R, t = C.pose(3 * n + len(kind))
    P, N = C.BUILDERS[kind](n, rng)
    h = 0.02
    Q = C.symmetric(P, N, h, rng)
    res = fit(C.place(Q, R, t), kind)
    err = C.geometry_error(res, C.truth(kind, R, t), SIZE[kind])
    _record(f"lsq {kind} symmetric", err)
    assert err < 1e-9
    # residuals are the displacements themselves (outward / along the normal)
    half = Q.shape[0] // 2
    d = np.linalg.norm(Q[:half] - P, axis=1)
    sign = 1.0 if kind != "plane" else float(np.sign(res.normal @ R[:, 2]))
    assert np.allclose(res.residuals[:half], sign * d, atol=1e-9 * SIZE[kind])
    assert res.form_error == pytest.approx(2 * d.max(), abs=1e-9 * SIZE[kind])
    assert res.optimality.get("converged", True)


@pytest.mark.parametrize("kind", ["plane", "circle", "sphere", "cylinder"])
def test_million_points(kind):
    rng = np.random.default_rng(11)
    R, t = C.pose(5)
    P, N = C.BUILDERS[kind](500_000, rng)
    res = fit(C.place(C.symmetric(P, N, 0.01, rng), R, t), kind)
    err = C.geometry_error(res, C.truth(kind, R, t), SIZE[kind])
    _record(f"lsq {kind} 1e6 symmetric", err)
    assert err < 1e-9


def _scipy_ls(kind, P, res):
    """Independent least squares (scipy, global parametrisation) from a perturbed
    start; returns its sum of squares and parameters comparable to ``res``."""
    if kind == "sphere":
        def f(x):
            return np.linalg.norm(P - x[:3], axis=1) - x[3]
        x0 = np.concatenate([res.center + 1e-3, [res.radius * 1.001]])
    else:  # cylinder: point + axis by two angles
        a = res.axis

        def axis_of(x):
            th, ph = x[3], x[4]
            return np.array([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)])

        def f(x):
            q = P - x[:3]
            w = axis_of(x)
            return np.linalg.norm(q - np.outer(q @ w, w), axis=1) - x[5]
        x0 = np.concatenate([res.point + 1e-3, [np.arccos(a[2]) + 1e-4,
                                                np.arctan2(a[1], a[0]), res.radius]])
    sol = least_squares(f, x0, xtol=1e-15, ftol=1e-15, gtol=1e-15, method="lm")
    return float(sol.fun @ sol.fun), sol.x


@pytest.mark.parametrize("kind", ["sphere", "cylinder"])
def test_noisy_matches_scipy_least_squares(kind):
    rng = np.random.default_rng(3)
    R, t = C.pose(9, offset=50.0)
    P, N = C.BUILDERS[kind](300, rng)
    Q = C.place(P + rng.normal(0, 0.05, (300, 1)) * N, R, t)
    res = fit(Q, kind)
    S = float(res.residuals @ res.residuals)
    S_ref, x = _scipy_ls(kind, Q, res)
    assert S <= S_ref * (1 + 1e-10)
    if kind == "sphere":
        assert np.linalg.norm(x[:3] - res.center) < 1e-8 * SIZE[kind]
        assert abs(x[3] - res.radius) < 1e-8 * SIZE[kind]


def test_partial_arc_cylinder_and_wide_cone():
    rng = np.random.default_rng(4)
    R, t = C.pose(21)
    th = rng.uniform(0, np.pi / 2, 400)
    z = rng.uniform(-30, 30, 400)
    P = np.column_stack([20 * np.cos(th), 20 * np.sin(th), z])
    res = fit(C.place(P, R, t), "cylinder")
    assert C.geometry_error(res, C.truth("cylinder", R, t), 50.0) < 1e-9
    P, _ = C.cone(400, rng, phi=1.1, h0=2.0, h1=6.0)
    res = fit(C.place(P, R, t), "cone")
    assert C.geometry_error(res, C.truth("cone", R, t, phi=1.1), 40.0) < 1e-9


@settings(deadline=None, max_examples=30)
@given(seed=st.integers(0, 10_000), kind=st.sampled_from(KINDS),
       n=st.integers(12, 80))
def test_rigid_motion_and_order_invariance(seed, kind, n):
    rng = np.random.default_rng(seed)
    P, N = C.BUILDERS[kind](n, rng)
    if N is None:
        P = P + rng.normal(0, 0.01, P.shape) * [1, 1, 0]
    else:
        P = P + rng.normal(0, 0.01, (n, 1)) * N
    a = fit(P, kind)
    R, t = C.pose(seed, offset=rng.uniform(0, 1e3))
    perm = rng.permutation(n)
    b = fit(C.place(P, R, t)[perm], kind)
    assert b.form_error == pytest.approx(a.form_error, rel=1e-7, abs=1e-10)
    ra = a.residuals[perm]
    if kind == "plane" and np.dot(R @ a.normal, b.normal) < 0:
        ra = -ra
    assert np.allclose(b.residuals, ra, atol=1e-8)
    for k, v in a.geometry.items():
        w = getattr(b, k)
        if k in ("normal", "direction", "axis"):
            assert 1 - abs(np.dot(R @ v, w)) < 1e-12
        elif k in ("center", "apex"):
            assert np.linalg.norm(R @ v + t - w) < 1e-7
        elif k in ("radius", "half_angle"):
            assert w == pytest.approx(v, rel=1e-9)


def test_result_conventions_and_json():
    import json

    rng = np.random.default_rng(5)
    P, _ = C.cone(50, rng)
    r = fit(P[:, ::-1] * [-1, 1, 1], "cone")      # axis along -x after the flip
    assert r.axis[0] < 0 and abs(np.linalg.norm(r.axis) - 1) < 1e-15
    assert 0 < r.half_angle < np.pi / 2
    p = fit(C.plane(20, rng)[0] * [1, 1, 0] + [0, 0, 3], "plane")
    assert np.allclose(p.normal, [0, 0, 1]) and p.point[2] == pytest.approx(3)
    d = json.loads(json.dumps(r.to_dict()))
    assert d["kind"] == "cone" and len(d["residuals"]) == 50
    assert "residuals" not in r.to_dict(residuals=False)
    assert isinstance(r, FitResult)
    with pytest.raises(Exception):
        r.radius = 1.0


def test_zz_report(capsys):
    with capsys.disabled():
        for k, v in sorted(WORST.items()):
            print(f"\n  worst {k}: {v:.2e}", end="")
        print()
