"""Tests of geomkit.nurbs.evaluation: points, partial derivatives and unit normals.

Oracles: geomdl (same algorithms, independent pure-Python code), a Cox–de Boor
reference in ``tests/helpers/naive.py``, the analytic truths of the bundled cases and
finite differences of ``evaluate``.

Tolerances (``scale(s)`` is ``s.size`` for every bundled sample, see conftest):

* points vs geomdl / naive / analytic formula: ``1e-12 * scale``;
* derivatives vs geomdl: ``|D - G| <= 1e-9 * max(1, |G|)`` per (k, l) vector (on
  random surfaces plus a rounding floor, see ``_deriv_floor``);
* derivatives vs central differences of ``evaluate`` with step ``h = 1e-5 * width``,
  at points at least ``1e-3 * width`` from every knot (so the stencil never crosses a
  knot of reduced continuity), error measured relative to
  ``max(|D|, scale / width^k)`` for a k-th derivative: first derivatives ``1e-6``
  (truncation ~h^2 |S'''| plus rounding ~eps |S| / h, observed <= 4e-8), second
  derivatives ``1e-4`` (rounding ~4 eps |S| / h^2 dominates, observed <= 5e-6); second
  derivatives are also checked against central differences of the first derivatives
  (step ``1e-6 * width``) to ``1e-7``.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, note
from hypothesis import strategies as st

import geomkit
from geomkit import InvalidInputError, samples
from geomkit.nurbs.evaluation import NORMAL_LIMIT, NORMAL_REGULAR, NORMAL_UNDEFINED

from helpers import naive
from helpers.surfaces import (all_surfaces, distinct_knots, geomdl_derivs, geomdl_eval,
                              random_surfaces, sample_surface, describe, scale,
                              surface_params, uv_samples)

SURFACES = surface_params()


def _max_err(a, b):
    return float(np.max(np.linalg.norm(np.asarray(a) - np.asarray(b), axis=-1), initial=0.0))


def _away_from_knots(surface, n, seed, margin=1e-3):
    """n random parameters at least ``margin * width`` from every knot and the edges."""
    rng = np.random.default_rng(seed)
    (u0, u1), (v0, v1) = surface.domain
    ku, kv = distinct_knots(surface)
    out = []
    while len(out) < n:
        u = rng.uniform(u0, u1)
        v = rng.uniform(v0, v1)
        if (np.abs(ku - u).min() > margin * (u1 - u0)
                and np.abs(kv - v).min() > margin * (v1 - v0)):
            out.append((u, v))
    return np.array(out)


# ======================================================================== points
@pytest.mark.parametrize("name, index, s", SURFACES)
def test_evaluate_matches_geomdl_on_samples(name, index, s):
    uv = uv_samples(s, n_random=60, seed=index)
    got = s.evaluate(uv)
    ref = geomdl_eval(s, uv)
    assert got.shape == ref.shape == (uv.shape[0], 3)
    assert _max_err(got, ref) <= 1e-12 * s.size


@pytest.mark.parametrize("name, index, s", SURFACES)
def test_evaluate_matches_cox_de_boor_on_samples(name, index, s):
    uv = uv_samples(s, n_random=30, seed=10 + index)
    ref = naive.surface_points(s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                               s.control_points, s.weights, uv)
    assert _max_err(s.evaluate(uv), ref) <= 1e-12 * s.size


@given(s=random_surfaces(rational=True), seed=st.integers(0, 2 ** 16))
def test_evaluate_matches_geomdl_on_random_nurbs(s, seed):
    note(f"surface = {describe(s)}")
    g = s.to_geomdl()
    # the generated knots survive geomdl's knot normalisation exactly
    assert list(g.knotvector_u) == s.knots_u.tolist()
    assert list(g.knotvector_v) == s.knots_v.tolist()
    uv = uv_samples(s, n_random=20, seed=seed)
    assert _max_err(s.evaluate(uv), geomdl_eval(s, uv, g)) <= 1e-12 * scale(s)


@given(s=random_surfaces(rational=False, unit_domain=False), seed=st.integers(0, 2 ** 16))
def test_evaluate_matches_cox_de_boor_on_random_bsplines(s, seed):
    note(f"surface = {describe(s)}")
    uv = uv_samples(s, n_random=10, seed=seed)
    ref = naive.surface_points(s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                               s.control_points, s.weights, uv)
    assert _max_err(s.evaluate(uv), ref) <= 1e-12 * scale(s)


def test_evaluate_interpolates_corner_control_points():
    """Clamped surfaces pass through their four corner control points."""
    for name, i, s in all_surfaces():
        (u0, u1), (v0, v1) = s.domain
        P = s.control_points
        got = s.evaluate([[u0, v0], [u0, v1], [u1, v0], [u1, v1]])
        want = [P[0, 0], P[0, -1], P[-1, 0], P[-1, -1]]
        assert _max_err(got, want) <= 1e-12 * s.size, (name, i)


# ====================================================================== analytic
ANALYTIC = [(name, i, s) for name, i, s in all_surfaces()
            if "analytic" in samples.load_case(name).truth]


def test_analytic_cases_present():
    names = {name for name, _, _ in ANALYTIC}
    assert {"sphere", "torus", "cylinder_quarter"} <= names


@pytest.mark.parametrize("name, index, s",
                         [pytest.param(*t, id=f"{t[0]}[{t[1]}]") for t in ANALYTIC])
def test_points_satisfy_analytic_formula(name, index, s):
    truth = samples.load_case(name).truth["analytic"]
    (u0, u1), (v0, v1) = s.domain
    g = np.linspace(0.0, 1.0, 41)
    grid = np.stack(np.meshgrid(u0 + g * (u1 - u0), v0 + g * (v1 - v0), indexing="ij"), -1)
    uv = np.concatenate([grid.reshape(-1, 2), uv_samples(s, n_random=300)])
    res = samples.analytic_residual(truth, s.evaluate(uv))
    assert np.max(np.abs(res)) <= 1e-12 * s.size


def test_analytic_residual_is_not_vacuous():
    """The residual oracle does detect points off the sphere (guards the test above)."""
    s = sample_surface("sphere")
    truth = samples.load_case("sphere").truth["analytic"]
    P = s.evaluate(uv_samples(s)) * (1 + 1e-9)
    assert np.max(np.abs(samples.analytic_residual(truth, P))) > 1e-12 * s.size


def test_saddle_is_z_equals_xy_over_10():
    s = sample_surface("saddle")
    uv = uv_samples(s, n_random=400)
    P = s.evaluate(uv)
    assert np.max(np.abs(P[:, 2] - P[:, 0] * P[:, 1] / 10.0)) <= 1e-12 * s.size
    # and it covers the square [-10, 10]^2
    assert np.allclose(P[:4, :2], [[-10, -10], [-10, 10], [10, -10], [10, 10]], atol=0)


def test_wave_points_on_surface_truth():
    case = samples.load_case("wave_seed003")
    s = case.surfaces[0]
    for key, want in case.truth["points_on_surface"].items():
        uv = [float(t) for t in key.split(",")]
        # the truth is given to 4 decimals
        assert np.max(np.abs(s.evaluate(uv) - want)) <= 5e-5 + 1e-12 * s.size, key


# =================================================================== derivatives
def _basis_abs_sums(degree, knots, count, params, order):
    """T[n, k] = sum_i |N_i^(k)(param_n)| (geomdl's A2.1 / A2.3 helpers)."""
    from geomdl import helpers
    kv = [float(x) for x in knots]
    T = np.zeros((len(params), order + 1))
    for n, x in enumerate(params):
        span = helpers.find_span_linear(degree, kv, count, float(x))
        ders = helpers.basis_function_ders(degree, kv, span, float(x), min(order, degree))
        for k, row in enumerate(ders):
            T[n, k] = np.sum(np.abs(row))
    return T


def _deriv_floor(s, uv, order):
    """Rounding floor for derivative comparisons, (n, order+1, order+1).

    A relative bound cannot hold where a derivative cancels to ~0 (e.g. a surface
    collapsed to a point on tiny knot spans: the exact derivatives are 0, both codes
    return rounding noise).  Forward error analysis of A3.6 + A4.4 bounds that noise by
    ``~eps * |P| * (1 + rho)^(k+l+1) * Lu^k * Lv^l`` with ``rho = w_max / w_min`` and
    ``L = max_k (sum_i |N_i^(k)|)^(1/k)`` the basis functions' rate of change at the
    point; the floor is that bound with ``1e-13`` (~450 eps) for eps.  Wherever the
    derivative itself is of the size the bound allows, the floor is ~1e-13 |G|, far
    below the 1e-9 relative term."""
    uv = np.asarray(uv, float).reshape(-1, 2)
    nu, nv = s.shape
    rho = 1.0 if s.weights is None else float(s.weights.max() / s.weights.min())

    def rate(degree, knots, count, params):
        T = _basis_abs_sums(degree, knots, count, params, order)
        k = np.arange(1, order + 1)
        return np.max(T[:, 1:] ** (1.0 / k), axis=1, initial=1.0)

    Lu = rate(s.degree_u, s.knots_u, nu, uv[:, 0])
    Lv = rate(s.degree_v, s.knots_v, nv, uv[:, 1])
    k = np.arange(order + 1)
    return (1e-13 * scale(s) * (1 + rho) ** (1 + k[:, None] + k[None, :])
            * Lu[:, None, None] ** k[None, :, None] * Lv[:, None, None] ** k[None, None, :])


def _check_vs_geomdl(D, G, order, floor=None):
    """``|D - G| <= 1e-9 * max(1, |G|) (+ floor)`` for every k + l <= order."""
    for k in range(order + 1):
        for l in range(order + 1 - k):
            err = np.linalg.norm(D[..., k, l, :] - G[..., k, l, :], axis=-1)
            lim = 1e-9 * np.maximum(1.0, np.linalg.norm(G[..., k, l, :], axis=-1))
            if floor is not None:
                lim = lim + floor[..., k, l]
            assert np.all(err <= lim), (k, l, float(np.max(err / lim)))


@pytest.mark.parametrize("name, index, s", SURFACES)
def test_derivatives_match_geomdl_on_samples(name, index, s):
    uv = uv_samples(s, n_random=40, seed=20 + index)
    D = s.derivatives(uv, order=2)
    G = geomdl_derivs(s, uv[:, 0], uv[:, 1], 2)
    _check_vs_geomdl(D, G, 2)


@given(s=random_surfaces(rational=True), seed=st.integers(0, 2 ** 16))
def test_derivatives_match_geomdl_on_random_nurbs(s, seed):
    note(f"surface = {describe(s)}")
    uv = uv_samples(s, n_random=8, seed=seed)
    D = s.derivatives(uv, order=2)
    G = geomdl_derivs(s, uv[:, 0], uv[:, 1], 2, s.to_geomdl())
    _check_vs_geomdl(D, G, 2, _deriv_floor(s, uv, 2))


@pytest.mark.parametrize("name, index, s", SURFACES)
def test_derivatives_match_central_differences(name, index, s):
    (u0, u1), (v0, v1) = s.domain
    wu, wv = u1 - u0, v1 - v0
    uv = _away_from_knots(s, 30, seed=index)
    D = s.derivatives(uv, order=2)
    hu, hv = 1e-5 * wu, 1e-5 * wv

    def E(du, dv):
        return s.evaluate(uv + [du, dv])

    S0 = E(0, 0)
    fd = {
        (1, 0): (E(hu, 0) - E(-hu, 0)) / (2 * hu),
        (0, 1): (E(0, hv) - E(0, -hv)) / (2 * hv),
        (2, 0): (E(hu, 0) - 2 * S0 + E(-hu, 0)) / hu ** 2,
        (0, 2): (E(0, hv) - 2 * S0 + E(0, -hv)) / hv ** 2,
        (1, 1): (E(hu, hv) - E(hu, -hv) - E(-hu, hv) + E(-hu, -hv)) / (4 * hu * hv),
    }
    w = max(wu, wv)
    for (k, l), approx in fd.items():
        exact = D[:, k, l]
        ref = np.maximum(np.linalg.norm(exact, axis=1), s.size / w ** (k + l))
        err = np.linalg.norm(approx - exact, axis=1) / ref
        tol = 1e-6 if k + l == 1 else 1e-4
        assert err.max() <= tol, ((k, l), float(err.max()))
    # second derivatives against differences of the first derivatives (tighter)
    h2u, h2v = 1e-6 * wu, 1e-6 * wv
    Dp = s.derivatives(uv + [h2u, 0], 1)
    Dm = s.derivatives(uv - [h2u, 0], 1)
    Ep = s.derivatives(uv + [0, h2v], 1)
    Em = s.derivatives(uv - [0, h2v], 1)
    pairs = {(2, 0): (Dp[:, 1, 0] - Dm[:, 1, 0]) / (2 * h2u),
             (1, 1): (Dp[:, 0, 1] - Dm[:, 0, 1]) / (2 * h2u),
             (0, 2): (Ep[:, 0, 1] - Em[:, 0, 1]) / (2 * h2v)}
    for (k, l), approx in pairs.items():
        exact = D[:, k, l]
        ref = np.maximum(np.linalg.norm(exact, axis=1), s.size / w ** 2)
        err = np.linalg.norm(approx - exact, axis=1) / ref
        assert err.max() <= 1e-7, ((k, l), float(err.max()))


@pytest.mark.parametrize("order", [0, 1, 2, 3])
@pytest.mark.parametrize("lead", [(), (1,), (7,), (2, 3)])
def test_derivatives_shape_and_point(order, lead):
    rng = np.random.default_rng(order)
    for name, i, s in all_surfaces():
        uv = rng.random(lead + (2,))
        D = s.derivatives(uv, order=order)
        assert D.shape == lead + (order + 1, order + 1, 3)
        assert np.all(np.isfinite(D))
        P = s.evaluate(uv)
        assert np.max(np.abs(D[..., 0, 0, :] - P), initial=0.0) <= 1e-13 * s.size, name


def test_derivatives_full_tensor_beyond_total_order():
    """Entries with k + l > order are documented as filled too: on the bilinear saddle
    (x = -10 + 20u, y = -10 + 20v, z = x y / 10) they are known exactly."""
    s = sample_surface("saddle")
    uv = np.array([[0.3, 0.7], [0.0, 1.0], [0.25, 0.5]])
    D = s.derivatives(uv, order=2)
    for (u, v), d in zip(uv, D):
        x, y = -10 + 20 * u, -10 + 20 * v
        assert np.allclose(d[1, 0], [20, 0, 20 * y / 10], atol=1e-12)
        assert np.allclose(d[0, 1], [0, 20, 20 * x / 10], atol=1e-12)
        assert np.allclose(d[1, 1], [0, 0, 400 / 10], atol=1e-12)
        assert np.allclose(d[2, 0], 0, atol=1e-12) and np.allclose(d[0, 2], 0, atol=1e-12)
        assert np.allclose(d[2, 1], 0, atol=1e-12) and np.allclose(d[1, 2], 0, atol=1e-12)
        assert np.allclose(d[2, 2], 0, atol=1e-12)


@pytest.mark.parametrize("name", ["sphere", "heavy_weights", "freeform_1"])
def test_derivatives_order3_match_geomdl(name):
    s = sample_surface(name)
    uv = _away_from_knots(s, 10, seed=3)
    _check_vs_geomdl(s.derivatives(uv, 3), geomdl_derivs(s, uv[:, 0], uv[:, 1], 3), 3)


@pytest.mark.parametrize("order", [-1, 9, 1.5, "2"])
def test_derivatives_bad_order(order):
    s = sample_surface("saddle")
    with pytest.raises(InvalidInputError):
        s.derivatives([0.5, 0.5], order=order)


# ======================================================================= normals
def _regular_mask(s, uv):
    D = s.derivatives(uv, 1)
    c = np.cross(D[:, 1, 0], D[:, 0, 1])
    big = np.maximum(np.linalg.norm(D[:, 1, 0], axis=1), np.linalg.norm(D[:, 0, 1], axis=1))
    return np.linalg.norm(c, axis=1) > 1e-6 * big ** 2, c


@pytest.mark.parametrize("name, index, s", SURFACES)
def test_normals_unit_and_parallel_to_cross_product(name, index, s):
    uv = uv_samples(s, n_random=80, seed=index)
    N, status = s.normals(uv, return_status=True)
    assert N.shape == uv.shape[:-1] + (3,) and status.shape == uv.shape[:-1]
    assert status.dtype == np.int8
    assert np.all(status != NORMAL_UNDEFINED)
    assert np.max(np.abs(np.linalg.norm(N, axis=1) - 1.0)) <= 1e-12
    reg, c = _regular_mask(s, uv)
    assert reg.sum() >= 60
    assert np.all(status[reg] == NORMAL_REGULAR)
    want = c[reg] / np.linalg.norm(c[reg], axis=1)[:, None]
    assert _max_err(N[reg], want) <= 1e-12
    # without return_status: the same normals
    assert np.array_equal(s.normals(uv), N)


@given(s=random_surfaces(rational=True), seed=st.integers(0, 2 ** 16))
def test_normals_unit_on_random_nurbs(s, seed):
    note(f"surface = {describe(s)}")
    uv = uv_samples(s, n_random=20, seed=seed)
    N, status = s.normals(uv, return_status=True)
    n = np.linalg.norm(N, axis=1)
    undefined = status == NORMAL_UNDEFINED
    assert np.all(N[undefined] == 0.0)
    assert np.max(np.abs(n[~undefined] - 1.0), initial=0.0) <= 1e-12
    reg, c = _regular_mask(s, uv)
    want = c[reg] / np.linalg.norm(c[reg], axis=1)[:, None]
    assert np.all(status[reg] == NORMAL_REGULAR)
    assert _max_err(N[reg], want) <= 1e-12


def test_sphere_normals_outward():
    s = sample_surface("sphere")
    c = np.array(samples.load_case("sphere").truth["analytic"]["center"], float)
    R = samples.load_case("sphere").truth["analytic"]["radius"]
    uv = uv_samples(s, n_random=500)
    N = s.normals(uv)
    P = s.evaluate(uv)
    assert np.all(np.einsum("ij,ij->i", N, P - c) > 0)
    assert _max_err(N, (P - c) / R) <= 1e-9


def test_torus_normals_outward():
    s = sample_surface("torus")
    t = samples.load_case("torus").truth["analytic"]
    uv = uv_samples(s, n_random=500)
    N = s.normals(uv)
    P = s.evaluate(uv)
    rho = np.hypot(P[:, 0], P[:, 1])
    C = np.column_stack([t["R"] * P[:, 0] / rho, t["R"] * P[:, 1] / rho, np.zeros(len(P))])
    assert np.all(np.einsum("ij,ij->i", N, P - C) > 0)
    assert _max_err(N, (P - C) / t["r"]) <= 1e-9


def test_cylinder_and_plane_normals():
    s = sample_surface("cylinder_quarter")
    uv = uv_samples(s, n_random=200)
    N, P = s.normals(uv), s.evaluate(uv)
    radial = P * [1, 1, 0]
    radial /= np.linalg.norm(radial, axis=1)[:, None]
    assert np.max(np.abs(np.abs(np.einsum("ij,ij->i", N, radial)) - 1)) <= 1e-12
    # one consistent orientation over the whole patch
    assert len(set(np.sign(np.einsum("ij,ij->i", N, radial)))) == 1
    s = sample_surface("plate_with_hole")
    N = s.normals(uv_samples(s))
    assert np.max(np.abs(np.abs(N[:, 2]) - 1)) <= 1e-12


def _collapsed_edges(s, n=9):
    """Edges of the domain whose image is a single point, found by evaluation:
    {("u"|"v", value): point}."""
    (u0, u1), (v0, v1) = s.domain
    t = np.linspace(0, 1, n)
    out = {}
    for axis, val in (("u", u0), ("u", u1), ("v", v0), ("v", v1)):
        if axis == "u":
            uv = np.column_stack([np.full(n, val), v0 + t * (v1 - v0)])
        else:
            uv = np.column_stack([u0 + t * (u1 - u0), np.full(n, val)])
        P = s.evaluate(uv)
        if np.max(np.ptp(P, axis=0)) <= 1e-12 * s.size:
            out[(axis, val)] = (uv, P[0])
    return out


def _inward(s, uv, axis, val, h):
    """``uv`` on a collapsed edge moved ``h`` (relative) into the domain."""
    (u0, u1), (v0, v1) = s.domain
    uv = uv.copy()
    if axis == "u":
        uv[:, 0] = val + (h if val == u0 else -h) * (u1 - u0)
    else:
        uv[:, 1] = val + (h if val == v0 else -h) * (v1 - v0)
    return uv


def test_sphere_poles_are_v_edges():
    s = sample_surface("sphere")
    edges = _collapsed_edges(s)
    assert set(edges) == {("v", 0.0), ("v", 1.0)}
    assert np.allclose(edges[("v", 0.0)][1], [0, 0, -10], atol=1e-12 * s.size)
    assert np.allclose(edges[("v", 1.0)][1], [0, 0, 10], atol=1e-12 * s.size)


def test_sphere_pole_normals():
    s = sample_surface("sphere")
    edges = _collapsed_edges(s, n=17)
    assert len(edges) == 2
    for (axis, val), (uv, pole) in edges.items():
        N, status = s.normals(uv, return_status=True)
        assert np.all(np.isfinite(N))
        assert np.max(np.abs(np.linalg.norm(N, axis=1) - 1)) <= 1e-12
        outward = np.array([0.0, 0.0, np.sign(pole[2])])
        assert _max_err(N, outward) <= 1e-12, (axis, val)
        assert np.all(status == NORMAL_LIMIT), (axis, val, status)
        # near the pole (1e-9 inside) the ordinary normal agrees with the pole normal;
        # the true angle there is ~3e-9 rad, the rest is rounding in S_u ~ 1e-8.
        near, st_near = s.normals(_inward(s, uv, axis, val, 1e-9), return_status=True)
        assert _max_err(near, N) <= 1e-6
        assert np.max(np.abs(np.linalg.norm(near, axis=1) - 1)) <= 1e-12


def _transposed(s):
    return geomkit.Surface(s.degree_v, s.degree_u, s.knots_v, s.knots_u,
                           s.control_points.transpose(1, 0, 2), s.weights.T)


def _reversed_v(s):
    (v0, v1) = s.domain[1]
    return geomkit.Surface(s.degree_u, s.degree_v, s.knots_u, (v0 + v1) - s.knots_v[::-1],
                           s.control_points[:, ::-1], s.weights[:, ::-1])


@pytest.mark.parametrize("variant", ["transposed", "reversed_v"])
def test_pole_normals_other_orientations(variant):
    """Collapsed u-edges (transposed sphere) and reversed parametrisations use the
    other branches of the limit normal; the normal at the pole must equal the limit of
    the regular normals next to it (and, both variants being inward-facing, -position)."""
    base = sample_surface("sphere")
    s = _transposed(base) if variant == "transposed" else _reversed_v(base)
    edges = _collapsed_edges(s, n=17)
    assert len(edges) == 2
    for (axis, val), (uv, pole) in edges.items():
        N, status = s.normals(uv, return_status=True)
        assert np.all(status == NORMAL_LIMIT)
        near = s.normals(_inward(s, uv, axis, val, 1e-6))
        assert _max_err(N, near) <= 1e-5, (axis, val)
        assert _max_err(N, -pole / np.linalg.norm(pole)) <= 1e-12
    # regular points are inward too
    uv = uv_samples(s, n_random=100)
    assert np.all(np.einsum("ij,ij->i", s.normals(uv), s.evaluate(uv)) < 0)


def test_sphere_normals_accurate_approaching_pole():
    """At distance h = 10^-k (k = 3..16) from the south pole the normal must be within
    1e-6 rad of the exact sphere normal at the evaluated point.  An implementation
    that switches to the limit normal where S_u is tiny achieves ~3h + rounding."""
    s = sample_surface("sphere")
    u = np.random.default_rng(0).random(200)
    worst = {}
    for k in range(3, 17):
        uv = np.column_stack([u, np.full_like(u, 10.0 ** -k)])
        N = s.normals(uv)
        P = s.evaluate(uv)
        worst[k] = _max_err(N, P / np.linalg.norm(P, axis=1)[:, None])
    assert max(worst.values()) <= 1e-6, worst


def test_heavy_weights_normals_match_finite_differences():
    s = sample_surface("heavy_weights")
    assert s.weights.max() == 200 and s.weights.min() == 0.005
    rng = np.random.default_rng(5)
    uv = rng.uniform(1e-3, 1 - 1e-3, (300, 2))
    # include the neighbourhood of the extreme weights' Greville points
    uv = np.concatenate([uv, [[2 / 3, 1 / 3 + 0.01], [1 / 3 + 0.01, 0.1]]])
    N, status = s.normals(uv, return_status=True)
    assert np.all(status == NORMAL_REGULAR)
    assert np.max(np.abs(np.linalg.norm(N, axis=1) - 1)) <= 1e-12
    h = 1e-6
    Su = (s.evaluate(uv + [h, 0]) - s.evaluate(uv - [h, 0])) / (2 * h)
    Sv = (s.evaluate(uv + [0, h]) - s.evaluate(uv - [0, h])) / (2 * h)
    C = np.cross(Su, Sv)
    C /= np.linalg.norm(C, axis=1)[:, None]
    assert _max_err(N, C) <= 1e-7   # observed ~5e-9


@pytest.mark.parametrize("knots_u", [[0, 0, 0, 0, 0, 1, 1, 1, 1, 1],
                                     [0, 0, 0, 0, 0, 0.995, 1, 1, 1, 1, 1],
                                     [0, 0, 0, 0.3, 0.3, 1, 1, 1]])
@pytest.mark.parametrize("kind", ["point", "segment"])
def test_normals_undefined_on_collapsed_surface(knots_u, kind):
    """A surface that collapses to a point or a line segment has no normal anywhere:
    status 3 and a zero vector (documented), never an exception or NaN."""
    U = np.array(knots_u, float)
    p = int(np.count_nonzero(U == 0)) - 1
    nu = len(U) - p - 1
    V = [0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0]
    P = np.zeros((nu, 4, 3))
    if kind == "segment":   # all control points on the x axis
        P[..., 0] = np.random.default_rng(0).uniform(-100, 100, (nu, 4))
    s = geomkit.Surface(p, 3, U, V, P)
    uv = uv_samples(s, n_random=10)
    N, status = s.normals(uv, return_status=True)
    assert np.all(status == NORMAL_UNDEFINED)
    assert np.all(N == 0.0)


# ======================================================================== crease
def test_crease_evaluation_continuous_across_knot():
    s = sample_surface("crease")
    assert np.count_nonzero(s.knots_u == 0.5) == s.degree_u   # C0 at u = 0.5
    v = np.linspace(0, 1, 21)
    at = s.evaluate(np.column_stack([np.full_like(v, 0.5), v]))
    D = s.derivatives(np.column_stack([np.full_like(v, 0.5), v]), 1)
    lip = 2 * np.max(np.linalg.norm(D[:, 1, 0], axis=1))
    for d in (1e-6, 1e-9, 1e-12):
        left = s.evaluate(np.column_stack([np.full_like(v, 0.5 - d), v]))
        right = s.evaluate(np.column_stack([np.full_like(v, 0.5 + d), v]))
        assert _max_err(left, at) <= lip * d + 1e-13 * s.size
        assert _max_err(right, at) <= lip * d + 1e-13 * s.size
    # the crease line is the image of the middle control row
    ref = naive.surface_points(s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                               s.control_points, None, np.column_stack([np.full_like(v, .5), v]))
    assert _max_err(at, ref) <= 1e-12 * s.size


def test_crease_one_sided_derivatives_differ():
    """Left S_u = p/(0.5) (P2 - P1), right S_u = p/(0.5) (P3 - P2) = (40, +-60, 0) here."""
    s = sample_surface("crease")
    P = s.control_points
    v = np.linspace(0, 1, 11)
    col = lambda u: np.column_stack([np.full_like(v, u), v])  # noqa: E731
    left_exact = 4 * (P[2, 0] - P[1, 0])
    right_exact = 4 * (P[3, 0] - P[2, 0])
    assert np.allclose(P[2] - P[1], P[2, 0] - P[1, 0]) and np.allclose(P[3] - P[2], P[3, 0] - P[2, 0])
    assert np.linalg.norm(left_exact - right_exact) > 100   # (40, 60, 0) vs (40, -60, 0)
    tol = 1e-9 * np.linalg.norm(left_exact)
    # one-sided limits of the derivative
    dl = s.derivatives(col(0.5 - 1e-12), 1)[:, 1, 0]
    dr = s.derivatives(col(0.5 + 1e-12), 1)[:, 1, 0]
    assert _max_err(dl, left_exact) <= tol
    assert _max_err(dr, right_exact) <= tol
    # exactly on the knot: the derivative from the right (documented)
    assert _max_err(s.derivatives(col(0.5), 1)[:, 1, 0], right_exact) <= tol
    # one-sided differences of evaluate show the same kink
    h = 1e-6
    S0 = s.evaluate(col(0.5))
    fl = (S0 - s.evaluate(col(0.5 - h))) / h
    fr = (s.evaluate(col(0.5 + h)) - S0) / h
    assert _max_err(fl, left_exact) <= 1e-5 * np.linalg.norm(left_exact)
    assert _max_err(fr, right_exact) <= 1e-5 * np.linalg.norm(right_exact)
    angle = np.degrees(np.arccos(left_exact @ right_exact
                                 / np.linalg.norm(left_exact) / np.linalg.norm(right_exact)))
    assert angle > 100   # a real crease: ~112.6 degrees between the tangents
    # v-derivatives are continuous across the crease
    dvl = s.derivatives(col(0.5 - 1e-12), 1)[:, 0, 1]
    dvr = s.derivatives(col(0.5), 1)[:, 0, 1]
    assert _max_err(dvl, dvr) <= 1e-9 * s.size


# ================================================================ input handling
@pytest.fixture(scope="module")
def sphere():
    return sample_surface("sphere")


def test_single_pair_returns_single_point(sphere):
    P = sphere.evaluate([0.3, 0.6])
    assert P.shape == (3,)
    assert np.array_equal(P, sphere.evaluate([[0.3, 0.6]])[0])
    assert sphere.derivatives((0.3, 0.6), 2).shape == (3, 3, 3)
    N, st_ = sphere.normals(np.array([0.3, 0.6]), return_status=True)
    assert N.shape == (3,) and st_.shape == ()


def test_grid_shape_preserved(sphere):
    uv = np.random.default_rng(1).random((4, 5, 2))
    P = sphere.evaluate(uv)
    assert P.shape == (4, 5, 3)
    assert np.array_equal(P.reshape(-1, 3), sphere.evaluate(uv.reshape(-1, 2)))
    assert sphere.derivatives(uv, 1).shape == (4, 5, 2, 2, 3)
    N, st_ = sphere.normals(uv, return_status=True)
    assert N.shape == (4, 5, 3) and st_.shape == (4, 5)
    assert np.array_equal(N.reshape(-1, 3), sphere.normals(uv.reshape(-1, 2)))


def test_empty_input(sphere):
    empty = np.zeros((0, 2))
    assert sphere.evaluate(empty).shape == (0, 3)
    assert sphere.derivatives(empty, 2).shape == (0, 3, 3, 3)
    N, st_ = sphere.normals(empty, return_status=True)
    assert N.shape == (0, 3) and st_.shape == (0,)


def test_list_input_and_module_functions(sphere):
    uv = [[0.1, 0.2], [0.9, 0.4]]
    assert np.array_equal(geomkit.evaluate(sphere, uv), sphere.evaluate(np.array(uv)))
    assert np.array_equal(geomkit.normals(sphere, uv), sphere.normals(uv))
    assert np.array_equal(geomkit.derivatives(sphere, uv, 2), sphere.derivatives(uv, 2))


@pytest.mark.parametrize("bad, row", [([[0.5, 0.5], [0.2, 0.3], [1.5, 0.5]], 2),
                                      ([[-0.1, 0.5]], 0),
                                      ([[0.5, 0.5], [0.5, 1.0 + 1e-6]], 1)])
@pytest.mark.parametrize("func", ["evaluate", "derivatives", "normals"])
def test_outside_domain_raises_naming_row(sphere, bad, row, func):
    with pytest.raises(InvalidInputError) as exc:
        getattr(sphere, func)(bad)
    assert f"row {row}" in str(exc.value)
    assert exc.value.field == "uv"


def test_domain_tolerance_clamps(sphere):
    """Within DOMAIN_TOL * width outside the domain: clamped onto the boundary."""
    eps = 0.5 * geomkit.tolerances.DOMAIN_TOL
    P = sphere.evaluate([[1 + eps, 0.5], [-eps, 0.25]])
    assert np.array_equal(P, sphere.evaluate([[1.0, 0.5], [0.0, 0.25]]))
    with pytest.raises(InvalidInputError):
        sphere.evaluate([[1 + 4 * geomkit.tolerances.DOMAIN_TOL, 0.5]])


@pytest.mark.parametrize("bad", [[np.nan, 0.5], [[0.5, 0.5], [0.5, np.nan]],
                                 [np.inf, 0.5], [[0.2, -np.inf]]])
@pytest.mark.parametrize("func", ["evaluate", "derivatives", "normals"])
def test_nonfinite_raises(sphere, bad, func):
    with pytest.raises(InvalidInputError):
        getattr(sphere, func)(bad)


@pytest.mark.parametrize("bad", [[0.5], [[0.1, 0.2, 0.3]], 0.5, "ab", [[0.1, "x"]]])
def test_bad_shape_or_type_raises(sphere, bad):
    with pytest.raises(InvalidInputError):
        sphere.evaluate(bad)


def test_not_a_surface_raises():
    with pytest.raises(InvalidInputError):
        geomkit.evaluate("sphere", [0.5, 0.5])


# ========================================================= unclamped knot vectors
def _geomdl_unclamped(p, q, U, V, P, w):
    """A geomdl surface from the raw (unclamped) data, knots not normalised."""
    from geomdl import BSpline, NURBS
    nu, nv = P.shape[:2]
    g = (NURBS.Surface(normalize_kv=False) if w is not None
         else BSpline.Surface(normalize_kv=False))
    g.degree_u, g.degree_v = p, q
    g.ctrlpts_size_u, g.ctrlpts_size_v = nu, nv
    g.ctrlpts = P.reshape(-1, 3).tolist()
    if w is not None:
        g.weights = w.reshape(-1).tolist()
    g.knotvector_u = list(map(float, U))
    g.knotvector_v = list(map(float, V))
    return g


def _domain_grid(U, V, p, q, nu, nv, n=9):
    a, b = U[p], U[nu]
    c, d = V[q], V[nv]
    t = np.linspace(0, 1, n)
    us = np.unique(np.concatenate([a + t * (b - a), U[(U >= a) & (U <= b)]]))
    vs = np.unique(np.concatenate([c + t * (d - c), V[(V >= c) & (V <= d)]]))
    us, vs = np.clip(us, a, b), np.clip(vs, c, d)
    return np.stack(np.meshgrid(us, vs, indexing="ij"), -1).reshape(-1, 2)


@pytest.mark.parametrize("p, q", [(1, 1), (2, 2), (3, 2), (2, 4), (4, 3)])
@pytest.mark.parametrize("rational", [False, True])
def test_unclamped_uniform_matches_geomdl_and_cox_de_boor(p, q, rational):
    rng = np.random.default_rng(p * 10 + q + rational)
    nu, nv = p + 4, q + 3
    U = np.arange(nu + p + 1, dtype=float)           # uniform, unclamped
    V = 0.5 * np.arange(nv + q + 1, dtype=float) - 1.0
    P = rng.uniform(-100, 100, (nu, nv, 3))
    w = np.exp(rng.uniform(np.log(0.05), np.log(20), (nu, nv))) if rational else None
    uv = _domain_grid(U, V, p, q, nu, nv)
    size = np.linalg.norm(np.ptp(P.reshape(-1, 3), axis=0))
    # the two oracles agree on the unclamped input
    ref_naive = naive.surface_points(p, q, U, V, P, w, uv)
    g = _geomdl_unclamped(p, q, U, V, P, w)
    ref_geomdl = np.array([g.evaluate_single([float(a), float(b)]) for a, b in uv])
    assert _max_err(ref_geomdl, ref_naive) <= 1e-12 * size
    s = geomkit.Surface(p, q, U, V, P, w)
    assert s.domain == ((U[p], U[nu]), (V[q], V[nv]))
    got = s.evaluate(uv)
    assert _max_err(got, ref_naive) <= 1e-12 * size
    assert _max_err(got, ref_geomdl) <= 1e-12 * size
    # derivatives too (geomdl differentiates the unclamped data directly)
    inner = uv[(uv[:, 0] > U[p]) & (uv[:, 0] < U[nu]) & (uv[:, 1] > V[q]) & (uv[:, 1] < V[nv])]
    inner = inner[:: max(1, len(inner) // 12)]
    D = s.derivatives(inner, 2)
    G = np.array([g.derivatives(float(a), float(b), order=2) for a, b in inner])
    _check_vs_geomdl(D, G, 2)


@pytest.mark.parametrize("end", ["start", "end"])
@pytest.mark.parametrize("p", [2, 3])
def test_unclamped_at_one_end_only(p, end):
    """A curve-like surface (degree 1 in v) unclamped at just one end of u."""
    rng = np.random.default_rng(p)
    n = p + 4
    U = np.arange(n + p + 1, dtype=float)
    if end == "start":
        U[n:] = U[n]          # clamped at the end, unclamped at the start
    else:
        U[:p + 1] = U[p]      # clamped at the start, unclamped at the end
    V = [0.0, 0.0, 1.0, 1.0]
    P = rng.uniform(-100, 100, (n, 2, 3))
    s = geomkit.Surface(p, 1, U, V, P)
    uv = _domain_grid(U, np.array(V), p, 1, n, 2, n=17)
    ref = naive.surface_points(p, 1, U, V, P, None, uv)
    size = np.linalg.norm(np.ptp(P.reshape(-1, 3), axis=0))
    assert _max_err(s.evaluate(uv), ref) <= 1e-12 * size


@given(data=st.data())
def test_unclamped_random_knots_match_cox_de_boor(data):
    p = data.draw(st.integers(1, 4), "p")
    q = data.draw(st.integers(1, 3), "q")
    nu = data.draw(st.integers(p + 1, p + 4), "nu")
    nv = data.draw(st.integers(q + 1, q + 4), "nv")

    def knots(deg, n):
        # strictly increasing at the ends, interior repeats <= deg
        steps = data.draw(st.lists(st.integers(0, 4), min_size=n + deg, max_size=n + deg))
        steps = [max(1, x) if (i < deg or i >= n - 1) else x for i, x in enumerate(steps)]
        K = np.concatenate([[0.0], np.cumsum(steps)]) / 4.0
        vals, counts = np.unique(K, return_counts=True)
        if counts.max() > deg:
            K = np.arange(n + deg + 1, dtype=float)
        return K

    U, V = knots(p, nu), knots(q, nv)
    P = np.random.default_rng(data.draw(st.integers(0, 999))).uniform(-100, 100, (nu, nv, 3))
    w = np.exp(np.random.default_rng(1).uniform(np.log(0.05), np.log(20), (nu, nv)))
    s = geomkit.Surface(p, q, U, V, P, w)
    uv = _domain_grid(U, V, p, q, nu, nv, n=5)
    size = np.linalg.norm(np.ptp(P.reshape(-1, 3), axis=0))
    ref = naive.surface_points(p, q, U, V, P, w, uv)
    assert _max_err(s.evaluate(uv), ref) <= 1e-12 * size
