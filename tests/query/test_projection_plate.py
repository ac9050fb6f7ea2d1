"""The plate with a hole (one bilinear trimmed face meshed into 108 long fan
triangles): the projector's sliver voxel size and the finer deep-cell grid of a model
with few trimmed faces change the work, never the answer."""

from __future__ import annotations

import numpy as np
import pytest

import geomkit
import geomkit.query.projection_trim as gpt
from geomkit import samples
from geomkit.bench.projection_mesh import case_points
from geomkit.query.voxel import sliver_voxel_size


def _median_edge(mesh):
    E = mesh.vertices[mesh.faces]
    return float(np.median(np.linalg.norm(E - np.roll(E, 1, axis=1), axis=2)))


@pytest.mark.parametrize("name", ["freeform_1", "sphere", "torus"])
def test_sliver_voxel_size_leaves_regular_meshes(name):
    pr = geomkit.Projector(samples.load(name))
    assert sliver_voxel_size(pr.mesh) is None
    assert pr.grid.voxel_size == pytest.approx(_median_edge(pr.mesh))


def test_plate_sliver_grid_and_deep_cells_same_answers():
    """The plate's grid (voxels of the triangles' width, not of their length) tests
    far fewer triangles; with main's grid and 32 x 32 deep cells the answers are the
    same (surface, status, distance, foot); every deep cell of the 256 x 256 grid is
    INSIDE the face at sampled points (corners included)."""
    S = samples.load("plate_with_hole")
    new = geomkit.Projector(S)
    h = _median_edge(new.mesh)
    assert new.grid.voxel_size < 0.3 * h
    saved = gpt.DEEP_CELLS
    try:
        gpt.DEEP_CELLS = 0
        old = geomkit.Projector(S, voxel_size=h)
    finally:
        gpt.DEEP_CELLS = saved
    G = int(new.cert_pack[2][0, 1])
    assert G == gpt.DEEP_GRID_MAX and old.cert_pack[2][0, 1] == gpt.DEEP_GRID
    scan, box = case_points(S, 4000, np.random.default_rng(2))
    for P in (scan, box):
        a = old.project(P)
        b = new.project(P)
        assert np.array_equal(a.surface, b.surface)
        assert np.array_equal(a.status, b.status)
        assert np.abs(a.distance - b.distance).max() <= 1e-12 * new.size
        assert np.abs(a.point - b.point).max() <= 1e-9 * new.size
        assert np.all(b.lower_bound <= b.distance + 1e-12 * new.size)
        assert b.stats["triangles_tested"] < 0.5 * a.stats["triangles_tested"]
    cells = new.cert_pack[1][:G * G].reshape(G, G)
    i, j = np.nonzero(cells)
    assert i.size > 0.5 * G * G
    (u0, u1), (v0, v1) = S[0].domain
    rng = np.random.default_rng(3)
    r = rng.random((i.size, 4, 2))
    r[:, :2] = [[0, 0], [1 - 1e-15, 1 - 1e-15]]
    uv = np.stack([u0 + (i[:, None] + r[..., 0]) * (u1 - u0) / G,
                   v0 + (j[:, None] + r[..., 1]) * (v1 - v0) / G], axis=-1)
    assert np.all(S[0].classify_uv(uv.reshape(-1, 2)) == geomkit.INSIDE)
