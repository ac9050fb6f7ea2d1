"""Nearest-triangle searches against brute force on awkward soups.

Soups long in one axis (aspect up to 1e3), skewed (slivers), sparse and clustered,
1 to 1e4 triangles, voxel sizes from far below to far above the triangle size, and
query points on, near, far from and outside the grid.  Every answer must equal the
brute-force minimum to rounding: :meth:`VoxelGrid.nearest` against libigl's
``point_mesh_squared_distance``; :meth:`VoxelGrid.nearest_triangles` (both methods)
and :func:`geomkit.min_distance` against the minimum over all triangle pairs; the
candidate search of :func:`geomkit.project_points` (a :class:`Projector` with each
voxel size) against the analytic distance to planar rectangles.

Grids with more than 2**8 voxels along an axis have 9 or more pyramid levels: the
heap values' encoding (:mod:`geomkit._kernels.voxel`) must hold every level.
"""

from __future__ import annotations

import zlib

import numpy as np
import pytest

import geomkit
from geomkit.errors import InvalidInputError
from geomkit.query.projection import Projector
from geomkit.query.results import BEYOND
from geomkit.query.voxel import VoxelGrid

from helpers.naive import brute_tris

igl = pytest.importorskip("igl")

KINDS = ("long", "skewed", "sparse", "clustered")


def soup(rng, kind, m):
    """(V, F) of ``m`` independent triangles of one kind."""
    if kind == "long":
        ext = np.array([rng.choice([10.0, 200.0, 1000.0]), rng.choice([0.5, 1.0, 5.0]),
                        rng.choice([0.5, 1.0, 5.0])])
        C = rng.uniform(0, 1, (m, 3)) * ext
        V = C[:, None, :] + rng.normal(0, 0.5, (m, 3, 3))
    elif kind == "skewed":          # slivers: one long edge, a tiny width
        C = rng.uniform(0, 20, (m, 3))
        d = rng.normal(size=(m, 3))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        w = rng.normal(size=(m, 3)) * 1e-3
        V = np.stack([C - 3 * d, C + 3 * d, C + w], axis=1)
    elif kind == "sparse":          # few triangles, far apart
        C = rng.uniform(0, 500, (m, 3))
        V = C[:, None, :] + rng.normal(0, 0.3, (m, 3, 3))
    else:                           # clusters of small triangles and a few outliers
        centres = rng.uniform(0, 100, (3, 3))
        C = centres[rng.integers(0, 3, m)] + rng.normal(0, 1.0, (m, 3))
        C[: max(1, m // 20)] = rng.uniform(-50, 150, (max(1, m // 20), 3))
        V = C[:, None, :] + rng.normal(0, 0.2, (m, 3, 3))
    return V.reshape(-1, 3), np.arange(3 * m).reshape(m, 3)


def queries(rng, V, F, n):
    """Points on, near, far from and outside the soup's box."""
    lo, hi = V.min(axis=0), V.max(axis=0)
    ext = np.maximum(hi - lo, 1e-3)
    t = rng.integers(0, len(F), n)
    b = rng.dirichlet([1, 1, 1], n)
    on = np.einsum("nk,nkd->nd", b, V[F[t]])
    near = on + rng.normal(0, 0.05, (n, 3))
    far = rng.uniform(lo - ext, hi + ext, (n, 3))
    out = hi + ext * rng.uniform(5, 50, (n, 3)) * rng.choice([-1, 1], (n, 3))
    return np.concatenate([on, near, far, out])


def median_edge(V, F):
    E = V[F]
    return float(np.median(np.linalg.norm(E - np.roll(E, 1, axis=1), axis=2)))


def grid_or_none(V, F, h):
    """The grid, or None when the voxel size asks for too many voxels (that refusal
    must be the clear one)."""
    try:
        return VoxelGrid((V, F), voxel_size=h)
    except InvalidInputError as e:
        assert "voxel_size" in str(e)
        return None


ROUND = 1e-9
"""Rounding slack of distances relative to the coordinates."""
ROUND2 = 1e-13
"""Rounding slack of squared distances relative to the squared coordinates: libigl
returns squared distances, whose rounding (~1e-16 of the squared scale) is ~1e-8 of
the scale once the root is taken, for points on a triangle."""


def scale(V):
    """Coordinate scale of a soup (for rounding slack)."""
    return 1.0 + float(np.abs(V).max())


SIZES = (0.02, 0.2, 1.0, 8.0, 100.0)   # voxel size / median edge


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("m", [1, 7, 38, 400])
def test_point_nearest_equals_brute_force(kind, m):
    rng = np.random.default_rng(zlib.crc32(f"{kind} {m}".encode()))
    for trial in range(3):
        V, F = soup(rng, kind, m)
        P = queries(rng, V, F, 25)
        ref2 = igl.point_mesh_squared_distance(P, V, F)[0]
        grids = [VoxelGrid((V, F))] + [grid_or_none(V, F, f * median_edge(V, F))
                                        for f in SIZES]
        for g in grids:
            if g is None:
                continue
            d, t, c = g.nearest(P)
            what = f"{kind} m={m} trial {trial} grid {tuple(g.shape)} h={g.voxel_size:.4g}"
            assert np.all((t >= 0) & (t < m)), what
            assert np.allclose(d ** 2, ref2, rtol=1e-12, atol=ROUND2 * scale(V) ** 2), what
            assert np.allclose(np.linalg.norm(c - P, axis=1), d,
                               rtol=1e-9, atol=1e-9), what


def test_point_nearest_ten_thousand_triangles_long_grid():
    rng = np.random.default_rng(11)
    V, F = soup(rng, "long", 10_000)
    V[:, 0] *= 1000.0 / max(1.0, np.ptp(V[:, 0]))         # aspect ~1e3
    P = queries(rng, V, F, 250)
    ref2 = igl.point_mesh_squared_distance(P, V, F)[0]
    for h in (None, 0.2, 1.0, 5.0):
        g = VoxelGrid((V, F), voxel_size=h)
        d, t, _ = g.nearest(P)
        assert np.allclose(d ** 2, ref2, rtol=1e-12, atol=ROUND2 * scale(V) ** 2), (
            h, tuple(g.shape))


def test_two_triangles_far_apart_on_a_long_grid():
    """The reproducer: two triangles 175 apart along x; levels with 3 cells in y, z."""
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 1], [175, 0, 0], [176, 0, 0], [175, 1, 1.]])
    F = np.array([[0, 1, 2], [3, 4, 5]])
    Q = np.array([[0.2, 0.2, 0.5], [175.2, 0.2, 0.5]])
    for h in (0.05, 0.2188, 0.5, 1.0, 3.0):
        g = VoxelGrid((V, F), voxel_size=h)
        d, t, _ = g.nearest(Q)
        assert t.tolist() == [0, 1], (h, g.lvl_dims.tolist())
        assert np.allclose(d, np.sqrt(0.045), atol=1e-12)


@pytest.mark.parametrize("kind", KINDS)
def test_triangle_nearest_equals_brute_force(kind):
    rng = np.random.default_rng(zlib.crc32(kind.encode()))
    VB, FB = soup(rng, kind, 60)
    VA, FA = soup(rng, kind, 12)
    VA = VA + rng.normal(0, 2.0, 3)
    ref = brute_tris(VA, FA, VB, FB)
    for f in (None,) + SIZES[1:4]:
        g = VoxelGrid((VB, FB)) if f is None else grid_or_none(VB, FB, f * median_edge(VB, FB))
        if g is None:
            continue
        for method in ("best_first", "shells"):
            r = g.nearest_triangles((VA, FA), method=method)
            assert np.allclose(r.distance, ref, rtol=1e-12, atol=ROUND * scale(VB)), (
                kind, f, method)


@pytest.mark.parametrize("kind", KINDS)
def test_min_distance_equals_brute_force(kind):
    rng = np.random.default_rng(zlib.crc32(f"md {kind}".encode()))
    VA, FA = soup(rng, kind, 30)
    VB, FB = soup(rng, kind, 30)
    pose_a = np.eye(4)
    pose_b = np.eye(4)
    pose_b[:3, 3] = rng.normal(0, 3.0, 3)
    VB_w = VB + pose_b[:3, 3]
    ref = brute_tris(VA, FA, VB_w, FB).min()
    r = geomkit.min_distance(geomkit.Body((VA, FA)), pose_a, geomkit.Body((VB, FB)), pose_b)
    assert r.distance == pytest.approx(ref, rel=1e-12, abs=ROUND * scale(VB_w))


def rectangle(origin, du, dv):
    """A flat bilinear patch origin + s du + t dv, (s, t) in [0, 1]^2."""
    P = np.array([[origin, origin + dv], [origin + du, origin + du + dv]], float)
    return geomkit.Surface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], P)


def rectangle_distance(P, origin, du, dv):
    """Exact distance from points to the rectangle (orthogonal du, dv)."""
    X = P - origin
    s = np.clip(X @ du / (du @ du), 0, 1)
    t = np.clip(X @ dv / (dv @ dv), 0, 1)
    return np.linalg.norm(X - s[:, None] * du - t[:, None] * dv, axis=1)


def test_projection_candidates_on_a_long_scene():
    """Small rectangles strung along 1000 units of x: every projected distance equals
    the analytic one, whatever the voxel size (none answered "beyond")."""
    rng = np.random.default_rng(5)
    rects = []
    for i in range(12):
        o = np.array([i * 1000.0 / 11, rng.uniform(0, 3), rng.uniform(0, 3)])
        a = rng.normal(size=3)
        a /= np.linalg.norm(a)
        b = np.cross(a, rng.normal(size=3))
        b /= np.linalg.norm(b)
        rects.append((o, a * rng.uniform(0.5, 2), b * rng.uniform(0.5, 2)))
    surfaces = [rectangle(*r) for r in rects]
    lo = np.min([r[0] for r in rects], axis=0) - 2
    hi = np.max([r[0] for r in rects], axis=0) + 4
    P = np.concatenate([rng.uniform(lo, hi, (150, 3)),
                        np.array([r[0] + 0.3 * r[1] + 0.2 * r[2] for r in rects])
                        + rng.normal(0, 0.1, (12, 3))])
    ref = np.min([rectangle_distance(P, *r) for r in rects], axis=0)
    with pytest.raises(InvalidInputError, match="voxel_size"):
        Projector(surfaces, voxel_size=0.01)       # 1e8 voxels: refused, clearly
    for h in (None, 0.2, 2.0, 80.0):
        proj = Projector(surfaces, voxel_size=h)
        res = proj.project(P)
        assert not np.any(res.status == BEYOND), h     # no max_distance: all answered
        assert np.all(np.isfinite(res.distance)), h
        assert np.allclose(np.abs(res.distance), ref, rtol=1e-9, atol=1e-9), h


def test_surface_distance_on_a_long_scene():
    """A strip 1000 long and 1 wide, and small squares above points along it: the
    certified interval holds the analytic distance (the candidate pairs come from
    the Bezier branch and bound, not a grid: the long axis must not hide a pair)."""
    strip = rectangle(np.zeros(3), np.array([1000.0, 0, 0]), np.array([0, 1.0, 0]))
    for x, h in ((0.0, 2.0), (500.0, 0.5), (999.5, 3.0), (1200.0, 1.0)):
        sq = rectangle(np.array([x, 0.25, h]), np.array([0.5, 0, 0]), np.array([0, 0.5, 0]))
        exact = h if x <= 1000.0 else float(np.hypot(x - 1000.0, h))
        r = geomkit.surface_distance(strip, sq, tol=1e-9)
        assert r.lower - 1e-12 <= exact <= r.upper + 1e-12, (x, h, r)
        assert r.upper - r.lower <= 1e-6
