"""Surface.placed: a rigid or affine placement of a trimmed rational surface equals the
surface built from the mapped control points, point for point, and shares its trims."""

import numpy as np
import pytest

import geomkit
from geomkit.errors import InvalidSurfaceError
from geomkit.nurbs.surface import Surface


def _rational_trimmed():
    s = geomkit.samples.load("plate_with_hole")[0]
    w = np.linspace(0.5, 3.0, s.control_points[..., 0].size).reshape(s.shape)
    return Surface(s.degree_u, s.degree_v, s.knots_u, s.knots_v, s.control_points, w,
                   s.trim, name="a")


def _matrix(rng, affine):
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    A = Q @ np.diag([1.0, 2.0, 0.5]) if affine else Q
    M = np.eye(4)
    M[:3, :3], M[:3, 3] = A, rng.normal(size=3) * 10
    return M


@pytest.mark.parametrize("affine", [False, True])
def test_placed_equals_the_surface_of_mapped_points(affine):
    rng = np.random.default_rng(1)
    s = _rational_trimmed()
    M = _matrix(rng, affine)
    t = s.placed(M, name="b")
    ref = Surface(s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                  s.control_points @ M[:3, :3].T + M[:3, 3], s.weights, s.trim, name="b")
    assert t.name == "b" and t.trim is s.trim and t.weights is s.weights
    np.testing.assert_array_equal(t.control_points, ref.control_points)
    np.testing.assert_array_equal(t.homogeneous, ref.homogeneous)
    (u0, u1), (v0, v1) = s.domain
    uv = rng.uniform([u0, v0], [u1, v1], size=(300, 2))
    np.testing.assert_allclose(t.evaluate(uv), s.evaluate(uv) @ M[:3, :3].T + M[:3, 3],
                               atol=1e-12 * s.size)
    np.testing.assert_array_equal(t.classify_uv(uv), s.classify_uv(uv))
    assert not t.control_points.flags.writeable and not t.homogeneous.flags.writeable
    assert s.name == "a"   # the original is untouched


def test_placed_without_a_matrix_renames_only():
    s = _rational_trimmed()
    t = s.placed(name="c")
    assert t.name == "c" and t.control_points is s.control_points


@pytest.mark.parametrize("M", [np.eye(3), np.full((4, 4), np.nan), "x"])
def test_placed_refuses_a_bad_matrix(M):
    with pytest.raises(InvalidSurfaceError, match="matrix"):
        _rational_trimmed().placed(M)
