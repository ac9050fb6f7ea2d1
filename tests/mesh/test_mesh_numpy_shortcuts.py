"""The mesh path's shortcuts around numpy's and shapely's wrappers against the calls
they replaced, bit for bit: the weld's :func:`geomkit._kernels.tess_weld.unique_uv`
against ``np.unique(z, return_inverse=True)`` of complex UV keys (repeats; of equal
signed zeros either may stand for both), and
:func:`geomkit.mesh.trim_polylines._polygon` against ``shapely.Polygon(shell,
holes)`` (WKB equal; a ring of fewer than 4 points as the class makes it, or
its error)."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from geomkit.mesh.trim_polylines import _polygon
from geomkit._kernels.tess_weld import unique_uv


def test_unique_uv_is_numpys_unique():
    rng = np.random.default_rng(7)
    for n in (0, 1, 2, 3, 17, 500, 4000):
        for k in range(10):
            uv = rng.integers(0, 9, (n, 2)) * 0.25
            if k % 2:
                uv[rng.random((n, 2)) < 0.1] = -0.0
            z = np.ascontiguousarray(uv).view(np.complex128).ravel()
            want, winv = np.unique(z, return_inverse=True)
            got, inv, _ = unique_uv(uv, False, 0.0, np.array([0.6, 0.8]))
            got = np.ascontiguousarray(got).view(np.complex128).ravel()
            assert np.array_equal(got, want)
            if not k % 2:
                assert got.tobytes() == want.tobytes()
            assert np.array_equal(inv, winv.ravel())


def _ring(rng, c, r, k):
    a = np.sort(rng.uniform(0, 2 * np.pi, k))
    p = np.c_[c[0] + r * np.cos(a), c[1] + r * np.sin(a)]
    return np.vstack([p, p[:1]])


def test_polygon_is_the_class_polygon():
    rng = np.random.default_rng(2)
    for holes in (0, 1, 3):
        for _ in range(5):
            rings = [_ring(rng, (0, 0), 10, 40)] + [_ring(rng, (4 * np.cos(h), 4 * np.sin(h)),
                                                            1, 12) for h in range(holes)]
            want = shapely.Polygon(rings[0], rings[1:])
            assert shapely.to_wkb(_polygon(rings)) == shapely.to_wkb(want)
    for short in ([[0.0, 0.0], [1.0, 0.0], [0.0, 0.0]], [[0.0, 0.0], [0.0, 0.0]]):
        rings = [np.array(short)]
        try:
            want = shapely.to_wkb(shapely.Polygon(rings[0]))
        except Exception as exc:  # noqa: BLE001 - the same error expected
            with pytest.raises(type(exc)):
                _polygon(rings)
        else:
            assert shapely.to_wkb(_polygon(rings)) == want


def _affine_numpy(P, gu, gv, size):
    """The bilinear branch of ``affine_map`` as numpy computed it before (the oracle)."""
    from geomkit.tolerances import AFFINE_REL

    du, dv = gu[1] - gu[0], gv[1] - gv[0]
    a = (P[1, 0] - P[0, 0]) / du
    b = (P[0, 1] - P[0, 0]) / dv
    o = P[0, 0] - gu[0] * a - gv[0] * b
    if np.abs(P[1, 1] - P[1, 0] - (P[0, 1] - P[0, 0])).max() > AFFINE_REL * size:
        return None
    n = (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
    if not n[0] ** 2 + n[1] ** 2 + n[2] ** 2 > 1e-24 * np.dot(a, a) * np.dot(b, b):
        return None
    return o, a, b


def test_bilinear_affine_is_the_numpy_test():
    from geomkit.mesh.trim_polylines import _bilinear_affine, _not_degenerate
    from geomkit.tolerances import AFFINE_REL

    rng = np.random.default_rng(9)
    for trial in range(400):
        o, a, b = rng.normal(size=(3, 3)) * rng.choice([1e-3, 1.0, 1e4])
        if trial % 5 == 0:
            b = a * 2.0  # degenerate: a line
        gu = np.sort(rng.uniform(-5, 5, 2))
        gv = np.sort(rng.uniform(-5, 5, 2))
        P = o + gu[:, None, None] * a + gv[None, :, None] * b
        size = float(np.linalg.norm(np.ptp(P.reshape(-1, 3), axis=0)))
        P[1, 1] += rng.normal(size=3) * AFFINE_REL * size * rng.choice([0.0, 0.5, 0.99, 2.0])
        want = _affine_numpy(P, gu, gv, size)
        # the knot lists hold the Greville abscissae at 1 and 2; then the degeneracy
        # test, as affine_map applies it
        got = _bilinear_affine(P.tolist(), [0.0, *gu.tolist(), 0.0], [0.0, *gv.tolist(), 0.0],
                               size)
        got = None if got is None else _not_degenerate(*(np.array(x) for x in got))
        assert (got is None) == (want is None), trial
        if want is not None:
            assert all(x.tobytes() == y.tobytes() for x, y in zip(got, want))


def test_max_gap_is_numpys_max_of_abs():
    from geomkit.mesh.cells import _max_gap

    rng = np.random.default_rng(12)
    for trial in range(300):
        a, b = rng.normal(size=(2, 3)) * rng.choice([1e-9, 1.0, 1e9])
        if trial % 4 == 0:
            b[trial % 3] = a[trial % 3]
        if trial % 7 == 0:
            a[rng.integers(3)] = np.nan
        want = float(np.abs(a - b).max())
        got = _max_gap(a.tolist(), b.tolist())
        assert (got == want) or (np.isnan(got) and np.isnan(want))
