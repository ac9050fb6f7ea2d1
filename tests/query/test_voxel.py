"""VoxelGrid (Paper 1): exact binning, nearest-triangle searches against brute force,
and the case where Paper 1's first-hit rule is wrong."""

from __future__ import annotations

import numpy as np
import pytest

import geomkit
from geomkit._kernels.triangles import point_triangle_distance
from geomkit.errors import InvalidInputError
from geomkit.query.voxel import CROSSED, ENCLOSED, VoxelGrid

from helpers.naive import brute_tris


def random_mesh(rng, m, scale=10.0, size=1.0):
    c = rng.uniform(0, scale, (m, 1, 3))
    V = (c + rng.normal(0, size, (m, 3, 3))).reshape(-1, 3)
    return V, np.arange(3 * m).reshape(m, 3)


def brute_points(V, F, P):
    return np.array([min(point_triangle_distance(*p, V[f]) for f in F) for p in P])


def test_binning_lists_every_voxel_a_triangle_touches():
    rng = np.random.default_rng(1)
    V, F = random_mesh(rng, 60, size=1.5)
    g = VoxelGrid((V, F), voxel_size=0.7)
    # dense samples of each triangle fall in voxels that list the triangle
    b = rng.dirichlet([1, 1, 1], 400)
    for t, f in enumerate(F):
        X = b @ V[f]
        ijk = np.floor((X - g.origin) / g.voxel_size).astype(int)
        for key in {tuple(x) for x in ijk}:
            tris, flags = g.voxel_triangles(key)
            assert t in tris
    # a triangle is ENCLOSED only in a voxel that contains all its vertices
    for key in [(i, j, k) for i in range(g.shape[0]) for j in range(g.shape[1])
                for k in range(g.shape[2])][:2000]:
        tris, flags = g.voxel_triangles(key)
        lo = g.origin + np.array(key) * g.voxel_size
        for t, fl in zip(tris, flags):
            inside = np.all((V[F[t]] >= lo) & (V[F[t]] <= lo + g.voxel_size))
            assert (fl == ENCLOSED) == inside and fl in (CROSSED, ENCLOSED)


def test_point_nearest_equals_brute_force():
    rng = np.random.default_rng(2)
    V, F = random_mesh(rng, 200)
    g = VoxelGrid((V, F))
    P = rng.uniform(-15, 25, (300, 3))
    d, t, c = g.nearest(P)
    ref = brute_points(V, F, P)
    assert np.allclose(d, ref, rtol=0, atol=1e-12)
    assert np.allclose(np.linalg.norm(c - P, axis=1), d, atol=1e-12)


@pytest.mark.parametrize("method", ["best_first", "shells"])
def test_triangle_nearest_equals_brute_force(method):
    rng = np.random.default_rng(3)
    VB, FB = random_mesh(rng, 150)
    VA, FA = random_mesh(rng, 80, scale=16.0)
    VA -= 3.0
    res = geomkit.nearest_triangles((VA, FA), (VB, FB), method=method)
    ref = brute_tris(VA, FA, VB, FB)
    assert np.allclose(res.distance, ref, rtol=0, atol=1e-12)
    assert np.allclose(np.linalg.norm(res.point_a - res.point_b, axis=1), res.distance,
                       atol=1e-12)
    assert res.min_distance == pytest.approx(ref.min(), abs=1e-12)


def test_first_hit_rule_is_wrong_and_the_bound_rule_is_exact():
    """Paper 1 stops at the first shell that holds a triangle; a nearer triangle can sit
    in a later shell (box shells are not spheres).  Small sparse triangles make it
    common: count such cases and check the fixed rule on all of them."""
    rng = np.random.default_rng(4)
    wrong = 0
    for trial in range(20):
        VB, FB = random_mesh(rng, 40, scale=20.0, size=0.05)
        VA, FA = random_mesh(rng, 40, scale=20.0, size=0.05)
        g = VoxelGrid((VB, FB), voxel_size=1.0)
        first = g.nearest_triangles((VA, FA), method="shells", stop="first_hit")
        exact = g.nearest_triangles((VA, FA), method="shells")
        ref = brute_tris(VA, FA, VB, FB)
        assert np.allclose(exact.distance, ref, atol=1e-12)
        assert np.all(first.distance >= ref - 1e-12)
        wrong += int(np.count_nonzero(first.distance > ref + 1e-9))
    assert wrong > 0  # the paper's rule really does return farther triangles


def test_grid_on_a_tessellation_and_bad_input():
    mesh = geomkit.tessellate(geomkit.samples.load("torus"), 0.05)
    g = VoxelGrid(mesh)
    assert g.n_occupied > 0 and g.triangles.size >= mesh.faces.shape[0]
    assert "VoxelGrid" in repr(g)
    with pytest.raises(InvalidInputError, match="voxel_size"):
        VoxelGrid(mesh, voxel_size=-1)
    with pytest.raises(InvalidInputError, match="faces"):
        VoxelGrid((mesh.vertices, mesh.faces + 10**6))
    with pytest.raises(InvalidInputError, match="mesh"):
        VoxelGrid("torus")
    with pytest.raises(InvalidInputError, match="method"):
        g.nearest_triangles(mesh, method="bfs")
    with pytest.raises(InvalidInputError, match="stop"):
        g.nearest_triangles(mesh, stop="first_hit")
    with pytest.raises(InvalidInputError, match="outside"):
        g.voxel_triangles((10**6, 0, 0))


def test_candidate_search_grows_its_scratch_and_keeps_every_candidate():
    """The kernel search (geomkit._kernels.voxel.search) with a one-entry heap and
    one-candidate arrays: the heap grows privately and is resized for the caller, the
    candidates are searched again in larger arrays under a new query id, and the
    answer equals the one with ample scratch."""
    from geomkit._kernels.voxel import candidate_scratch, search

    rng = np.random.default_rng(7)
    V, F = random_mesh(rng, 300, scale=6.0, size=1.0)
    g = VoxelGrid((V, F), voxel_size=0.3)
    fdev = np.full(F.shape[0], 0.4)     # wide bounds: many candidates per point
    args = (g.vertices, g.faces, fdev, 0.4, *g._args())
    P = rng.uniform(-1, 7, (40, 3))
    big = candidate_scratch(F.shape[0], 4096)
    tiny = (np.full(F.shape[0], -1, dtype=np.int64), np.empty(1), np.empty(1, np.int64),
            np.empty(1, np.int64), np.empty(1), np.empty(1), np.empty(1))
    grew = 0
    for i, p in enumerate(P):
        kb, ubb, lbb, ovb, _, _, big = search(p[0], p[1], p[2], *args, big, i, np.inf)
        cap = tiny[3].shape[0]
        k, ub, lb, ov, _, _, tiny = search(p[0], p[1], p[2], *args, tiny, i, np.inf)
        assert not ovb
        assert ov == (kb > cap) and k == kb and (ub, lb) == (ubb, lbb)
        assert np.array_equal(tiny[3][:k], big[3][:kb])   # same triangles, same order
        assert np.array_equal(tiny[4][:k], big[4][:kb])
        grew += ov
    assert tiny[1].shape[0] > 1 and grew >= 1
