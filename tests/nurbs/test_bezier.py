"""Tests of geomkit.nurbs.bezier.bezier_patches (Bézier extraction, The NURBS Book A5.6).

Oracle: each patch is evaluated as a rational tensor-product Bézier patch with
explicit Bernstein polynomials (``tests/helpers/naive.py``) and compared with
``Surface.evaluate`` on the patch's sub-domain, to ``1e-12 * scale`` (``scale`` is
``surface.size`` for every bundled sample, see conftest).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, note
from hypothesis import strategies as st

import geomkit
from geomkit import BezierPatches

from helpers import naive
from helpers.surfaces import (all_surfaces, describe, distinct_knots, random_surfaces,
                              scale, surface_params)

SURFACES = surface_params()


def _patch_params(bp, i, j, n, rng):
    """Parameters in patch (i, j): its 4 corners, 2 points on each edge, n interior."""
    a, b = bp.u_breaks[i], bp.u_breaks[i + 1]
    c, d = bp.v_breaks[j], bp.v_breaks[j + 1]
    t = rng.random(2)
    pts = [[a, c], [a, d], [b, c], [b, d]]
    for x in t:
        pts += [[a + x * (b - a), c], [a + x * (b - a), d], [a, c + x * (d - c)],
                [b, c + x * (d - c)]]
    r = rng.random((n, 2))
    pts += np.column_stack([a + r[:, 0] * (b - a), c + r[:, 1] * (d - c)]).tolist()
    uv = np.array(pts)
    uv[:, 0] = np.clip(uv[:, 0], a, b)
    uv[:, 1] = np.clip(uv[:, 1], c, d)
    return uv


def _check_patches_evaluate_like_surface(s, n_per_patch, seed):
    bp = s.bezier_patches()
    rng = np.random.default_rng(seed)
    tol = 1e-12 * scale(s)
    worst = 0.0
    nsu, nsv = bp.shape
    for i in range(nsu):
        for j in range(nsv):
            uv = _patch_params(bp, i, j, n_per_patch, rng)
            want = s.evaluate(uv)
            a, b = bp.u_breaks[i], bp.u_breaks[i + 1]
            c, d = bp.v_breaks[j], bp.v_breaks[j + 1]
            got = np.array([naive.bezier_point(bp.homogeneous[i, j], u, v, a, b, c, d)
                            for u, v in uv])
            err = float(np.max(np.linalg.norm(got - want, axis=1)))
            worst = max(worst, err)
            assert err <= tol, ((i, j), err, tol)
    return worst


# ================================================================= structure
def _expected_breaks(knots, degree, count):
    """Distinct knot values of the domain [U[p], U[n]] (the patch boundaries)."""
    U = np.asarray(knots)
    dom = U[degree:count + 1]
    return np.unique(dom)


@pytest.mark.parametrize("name, index, s", SURFACES)
def test_structure_on_samples(name, index, s):
    bp = s.bezier_patches()
    assert isinstance(bp, BezierPatches)
    p, q = s.degree_u, s.degree_v
    nu, nv = s.shape
    ub = _expected_breaks(s.knots_u, p, nu)
    vb = _expected_breaks(s.knots_v, q, nv)
    # one patch per non-empty knot span
    nspans_u = int(np.count_nonzero(np.diff(s.knots_u[p:nu + 1]) > 0))
    nspans_v = int(np.count_nonzero(np.diff(s.knots_v[q:nv + 1]) > 0))
    assert bp.shape == (nspans_u, nspans_v) == (len(ub) - 1, len(vb) - 1)
    assert bp.homogeneous.shape == (nspans_u, nspans_v, p + 1, q + 1, 4)
    assert np.array_equal(bp.u_breaks, ub)
    assert np.array_equal(bp.v_breaks, vb)
    assert bp.control_points.shape == (nspans_u, nspans_v, p + 1, q + 1, 3)
    assert bp.weights.shape == (nspans_u, nspans_v, p + 1, q + 1)
    assert np.all(bp.weights > 0)
    assert np.all(np.isfinite(bp.homogeneous))


def test_expected_patch_counts():
    """Hand-counted: sphere 4 x 2, torus 4 x 4, freeform 5 x 5, crease 2 x 1, plane 1 x 1."""
    want = {"sphere": (4, 2), "torus": (4, 4), "freeform_1": (5, 5), "crease": (2, 1),
            "saddle": (1, 1), "heavy_weights": (3, 3), "wave_seed003": (1, 1)}
    got = {name: s.bezier_patches().shape for name, i, s in all_surfaces() if i == 0}
    for name, shape in want.items():
        assert got[name] == shape, name


def test_single_bezier_surface_is_its_own_patch():
    """A surface with no interior knots is one Bézier patch: its own control net."""
    for name, i, s in all_surfaces():
        nu, nv = s.shape
        if nu == s.degree_u + 1 and nv == s.degree_v + 1:
            bp = s.bezier_patches()
            assert bp.shape == (1, 1)
            assert np.array_equal(bp.homogeneous[0, 0], s.homogeneous), name


# ============================================================== evaluation
@pytest.mark.parametrize("name, index, s", SURFACES)
def test_patches_evaluate_like_surface_on_samples(name, index, s):
    _check_patches_evaluate_like_surface(s, n_per_patch=12, seed=index)


@given(s=random_surfaces(rational=True, unit_domain=False), seed=st.integers(0, 2 ** 16))
def test_patches_evaluate_like_surface_on_random_nurbs(s, seed):
    note(f"surface = {describe(s)}")
    _check_patches_evaluate_like_surface(s, n_per_patch=3, seed=seed)


@given(s=random_surfaces(rational=False), seed=st.integers(0, 2 ** 16))
def test_patches_evaluate_like_surface_on_random_bsplines(s, seed):
    note(f"surface = {describe(s)}")
    _check_patches_evaluate_like_surface(s, n_per_patch=3, seed=seed)


@given(s=random_surfaces(rational=True, unit_domain=False))
def test_patch_count_equals_nonempty_spans_random(s):
    note(f"surface = {describe(s)}")
    bp = s.bezier_patches()
    p, q = s.degree_u, s.degree_v
    nu, nv = s.shape
    ku, kv = distinct_knots(s)
    assert bp.shape == (len(ku) - 1, len(kv) - 1)
    assert bp.shape == (int(np.count_nonzero(np.diff(s.knots_u[p:nu + 1]) > 0)),
                        int(np.count_nonzero(np.diff(s.knots_v[q:nv + 1]) > 0)))
    assert np.array_equal(bp.u_breaks, ku) and np.array_equal(bp.v_breaks, kv)
    assert bp.homogeneous.shape == bp.shape + (p + 1, q + 1, 4)
    assert np.all(bp.weights > 0)


def test_patch_corners_are_surface_points():
    """Corner control points of each patch interpolate the surface at the cell corners."""
    for name, i, s in all_surfaces():
        bp = s.bezier_patches()
        U, V = np.meshgrid(bp.u_breaks, bp.v_breaks, indexing="ij")
        S = s.evaluate(np.stack([U, V], -1))
        C = bp.control_points
        tol = 1e-12 * s.size
        assert np.max(np.abs(C[:, :, 0, 0] - S[:-1, :-1])) <= tol, name
        assert np.max(np.abs(C[:, :, -1, 0] - S[1:, :-1])) <= tol, name
        assert np.max(np.abs(C[:, :, 0, -1] - S[:-1, 1:])) <= tol, name
        assert np.max(np.abs(C[:, :, -1, -1] - S[1:, 1:])) <= tol, name


def test_unclamped_surface_patches():
    """Extraction works on a surface given with unclamped knots (clamped on input)."""
    rng = np.random.default_rng(7)
    p, q, nu, nv = 3, 2, 7, 5
    U = np.arange(nu + p + 1, dtype=float)
    V = np.arange(nv + q + 1, dtype=float) / 2
    w = np.exp(rng.uniform(np.log(0.05), np.log(20), (nu, nv)))
    s = geomkit.Surface(p, q, U, V, rng.uniform(-100, 100, (nu, nv, 3)), w)
    bp = s.bezier_patches()
    assert bp.shape == (nu - p, nv - q)
    assert np.array_equal(bp.u_breaks, U[p:nu + 1])
    _check_patches_evaluate_like_surface(s, n_per_patch=6, seed=0)


# ===================================================== shared boundaries
def _check_shared_boundaries(bp):
    H = bp.homogeneous
    # u-neighbours share the control row at their common boundary, bit for bit
    for i in range(H.shape[0] - 1):
        assert np.array_equal(H[i, :, -1, :, :], H[i + 1, :, 0, :, :]), ("u", i)
    for j in range(H.shape[1] - 1):
        assert np.array_equal(H[:, j, :, -1, :], H[:, j + 1, :, 0, :]), ("v", j)


@pytest.mark.parametrize("name, index, s", SURFACES)
def test_patch_boundaries_shared_exactly_on_samples(name, index, s):
    _check_shared_boundaries(s.bezier_patches())


@given(s=random_surfaces(rational=True, unit_domain=False))
def test_patch_boundaries_shared_exactly_random(s):
    note(f"surface = {describe(s)}")
    bp = s.bezier_patches()
    _check_shared_boundaries(bp)
    # and the shared edges evaluate to the same curve from both sides
    rng = np.random.default_rng(0)
    t = rng.random(5)
    for i in range(bp.shape[0] - 1):
        j = int(rng.integers(bp.shape[1]))
        ub = bp.u_breaks[i + 1]
        c, d = bp.v_breaks[j], bp.v_breaks[j + 1]
        for x in t:
            v = c + x * (d - c)
            left = naive.bezier_point(bp.homogeneous[i, j], ub, v, bp.u_breaks[i], ub, c, d)
            right = naive.bezier_point(bp.homogeneous[i + 1, j], ub, v, ub,
                                       bp.u_breaks[i + 2], c, d)
            assert np.max(np.abs(left - right)) <= 1e-12 * scale(s)


def test_boundary_check_detects_a_gap():
    """The shared-boundary check is not vacuous: a perturbed net fails it."""
    s = next(s for name, i, s in all_surfaces() if name == "sphere")
    bp = s.bezier_patches()
    H = bp.homogeneous.copy()
    H[1, 0, 0, 1, 0] += 1e-15 * max(1.0, abs(H[1, 0, 0, 1, 0]))
    with pytest.raises(AssertionError):
        _check_shared_boundaries(BezierPatches(H, bp.u_breaks, bp.v_breaks))


# ================================================================= bounds
def _check_bounds_contain_samples(s, n):
    bp = s.bezier_patches()
    B = bp.bounds()
    nsu, nsv = bp.shape
    assert B.shape == (nsu, nsv, 2, 3)
    assert np.all(B[:, :, 0] <= B[:, :, 1])
    slack = 1e-12 * scale(s)
    g = np.linspace(0.0, 1.0, n)
    for i in range(nsu):
        for j in range(nsv):
            a, b = bp.u_breaks[i], bp.u_breaks[i + 1]
            c, d = bp.v_breaks[j], bp.v_breaks[j + 1]
            uu, vv = np.meshgrid(np.clip(a + g * (b - a), a, b),
                                 np.clip(c + g * (d - c), c, d), indexing="ij")
            P = s.evaluate(np.stack([uu, vv], -1)).reshape(-1, 3)
            assert np.all(P >= B[i, j, 0] - slack), (i, j)
            assert np.all(P <= B[i, j, 1] + slack), (i, j)
    # the union of the patch boxes is inside the control-net box of the surface
    assert np.all(B[:, :, 0].reshape(-1, 3).min(axis=0) >= s.bounds[0] - slack)
    assert np.all(B[:, :, 1].reshape(-1, 3).max(axis=0) <= s.bounds[1] + slack)


@pytest.mark.parametrize("name, index, s", SURFACES)
def test_bounds_contain_dense_samples(name, index, s):
    _check_bounds_contain_samples(s, n=33)


@given(s=random_surfaces(rational=True, unit_domain=False))
def test_bounds_contain_samples_random(s):
    note(f"surface = {describe(s)}")
    _check_bounds_contain_samples(s, n=9)


def test_bounds_are_tight_at_patch_corners():
    """Each box is the control-net box: the corners of the patch lie in it and the box
    of a flat patch is flat (z extent 0 on the plane z = 0)."""
    s = next(s for name, i, s in all_surfaces() if name == "plate_with_hole")
    B = s.bezier_patches().bounds()
    assert np.all(B[..., 2] == 0.0)
    s = next(s for name, i, s in all_surfaces() if name == "sphere")
    B = s.bezier_patches().bounds()
    # sphere patches: boxes within the sphere's box [-10, 10]^3 (weights < 1 pull the
    # control points outside the sphere, but never outside its bounding cube)
    assert np.all(B >= -10 - 1e-12) and np.all(B <= 10 + 1e-12)
    # 8 octant patches: each box spans exactly one octant-ish quarter
    assert B.shape == (4, 2, 2, 3)
    assert np.allclose(np.abs(B[..., 2]).max(axis=-1), 10.0)


def test_surface_keeps_its_patches():
    """``Surface.bezier_patches()`` extracts once (repeated distance queries against
    one part) and returns read-only arrays equal to a fresh extraction."""
    from geomkit.nurbs.bezier import bezier_patches
    from geomkit.samples import load

    s = load("freeform_1")[0]
    bp = s.bezier_patches()
    assert s.bezier_patches() is bp
    fresh = bezier_patches(s)
    np.testing.assert_array_equal(bp.homogeneous, fresh.homogeneous)
    np.testing.assert_array_equal(bp.u_breaks, fresh.u_breaks)
    assert not bp.homogeneous.flags.writeable
