"""The compiled clip and constrained triangulation of a trimmed grid's cut cells
(geomkit._kernels.tess_clip) against GEOS: the same pieces (area per cell, triangle
count), triangles counter-clockwise inside the region and the cell, every diagonal
locally Delaunay; degenerate rings (on the cells' edges, along them, through their
corners) either taken exactly or left to GEOS; and on real parts, every cut cell of
every trimmed grid against GEOS's clip and triangulation."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import shapely

from geomkit._kernels import tess_clip as K
from geomkit._kernels.tess_clip import CLIP_DONE, clip_cells
from geomkit._kernels.tess_rings import clean_rings, ring_directions
from geomkit.mesh import cells as cells_mod
from geomkit.mesh import tessellate as tess_mod
from geomkit.mesh.cells import triangulate_pieces

from helpers.parts import part_surfaces


def _pack(rings):
    rings = [np.asarray(r, dtype=np.float64) for r in rings]
    rings = [r if (r[0] == r[-1]).all() else np.vstack([r, r[:1]]) for r in rings]
    starts = np.zeros(len(rings) + 1, dtype=np.int64)
    np.add.accumulate([len(r) for r in rings], out=starts[1:])
    return np.ascontiguousarray(np.concatenate(rings)), starts


def _grid(u0, u1, v0, v1, nu, nv):
    us = np.linspace(u0, u1, nu + 1)
    vs = np.linspace(v0, v1, nv + 1)
    return np.array([[us[i], us[i + 1], vs[j], vs[j + 1]] for i in range(nu)
                     for j in range(nv)])


def _area2(t):
    a = t[:, 1] - t[:, 0]
    b = t[:, 2] - t[:, 0]
    return a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]


def _check_against_geos(rings, cells):
    """Cells the kernel takes: area and triangle count of GEOS's piece, triangles
    counter-clockwise inside the piece.  Returns the statuses."""
    P, starts = _pack(rings)
    dirs = ring_directions(P, starts)
    tri, own, status, area = clip_cells(cells, P, starts, dirs)
    region = shapely.Polygon(rings[0], rings[1:])
    assert region.is_valid
    assert (_area2(tri) > 0).all()
    for c in np.nonzero(status == CLIP_DONE)[0]:
        piece = shapely.clip_by_rect(region, cells[c, 0], cells[c, 2], cells[c, 1],
                                     cells[c, 3])
        mine = tri[own == c]
        assert area[c] == pytest.approx(piece.area, rel=1e-9, abs=1e-12)
        assert 0.5 * _area2(mine).sum() == pytest.approx(piece.area, rel=1e-9, abs=1e-12)
        geos = triangulate_pieces(np.array([piece]))[0]
        assert len(mine) == len(geos)
        cent = shapely.points(mine.mean(axis=1))
        assert shapely.contains(piece.buffer(1e-9), cent).all()
    return status, tri, own


def _star(n, r0, r1, seed, centre=(0.0, 0.0)):
    rng = np.random.default_rng(seed)
    a = np.sort(rng.uniform(0, 2 * np.pi, n))
    r = rng.uniform(r0, r1, n)
    return np.c_[centre[0] + r * np.cos(a), centre[1] + r * np.sin(a)]


@pytest.mark.parametrize("seed", range(8))
def test_random_regions_match_geos(seed):
    outer = _star(40, 0.6, 1.0, seed)
    hole = _star(12, 0.05, 0.15, seed + 100, centre=(0.1, -0.1))[::-1]
    for rings in ([outer], [outer, hole], [outer[::-1], hole[::-1]]):
        cells = _grid(-1.1, 1.1, -1.05, 1.05, 9, 7)
        status, _, _ = _check_against_geos(rings, cells)
        assert (status == CLIP_DONE).sum() >= 20


def _circle(cx, cy, r, n, cw):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    p = np.c_[cx + r * np.cos(t), cy + r * np.sin(t)]
    return p[::-1] if cw else p


def test_holes_and_islands_inside_cells():
    """Holes wholly inside cells (one, two in one cell, one holding an island) against
    GEOS's clip and triangulation of the even-odd region, cell by cell."""
    outer = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0]])
    holes = [_circle(0.5, 0.5, 0.3, 17, True), _circle(1.3, 1.5, 0.2, 11, True),
             _circle(1.7, 1.5, 0.15, 9, True), _circle(2.5, 2.5, 0.4, 23, True),
             _circle(2.5, 2.5, 0.2, 13, False), _circle(3.5, 0.6, 0.3, 19, True)]
    cells = np.array([[0.0, 1.0, 0.0, 1.0], [1.0, 2.0, 1.0, 2.0], [2.0, 3.0, 2.0, 3.0],
                      [3.0, 4.0, 0.0, 1.0], [0.0, 1.0, 1.0, 2.0]])
    P, starts = _pack([outer] + holes)
    dirs = ring_directions(P, starts)
    assert dirs.tolist() == [1, 1, 1, 1, 1, 1, 1]
    tri, own, status, area = clip_cells(cells, P, starts, dirs)
    assert (status == CLIP_DONE).all()
    region = shapely.Polygon(outer, holes[:4] + holes[5:]).union(shapely.Polygon(holes[4]))
    for c in range(len(cells)):
        piece = shapely.clip_by_rect(region, *cells[c, [0, 2, 1, 3]])
        mine = tri[own == c]
        assert area[c] == pytest.approx(piece.area, rel=1e-12)
        assert 0.5 * _area2(mine).sum() == pytest.approx(piece.area, rel=1e-12)
        assert (_area2(mine) > 0).all()
        cent = shapely.points(mine.mean(axis=1))
        assert shapely.contains(piece, cent).all()
        geos = triangulate_pieces(np.array([piece]))[0]
        assert len(mine) == len(geos)


def test_ring_directions_follow_nesting():
    sq = lambda a, b: np.array([[a, a], [b, a], [b, b], [a, b]])  # noqa: E731
    # outer stored clockwise, a hole stored counter-clockwise, an island in the hole
    rings = [sq(0, 10)[::-1], sq(2, 8), sq(4, 6)]
    P, starts = _pack(rings)
    assert ring_directions(P, starts).tolist() == [-1, -1, 1]


def test_rings_on_the_cell_edges():
    # a staircase along the grid lines with one slanted cut: vertices on cell edges,
    # segments along them, a corner of the region at a cell corner
    ring = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 0.5], [1.5, 1.0], [1.5, 1.5], [1.0, 1.5],
                     [1.0, 2.0], [0.0, 2.0]])
    cells = _grid(0.0, 2.0, 0.0, 2.0, 4, 4)
    status, tri, own = _check_against_geos([ring], cells)
    # every cell the region covers is taken; the ones it misses have no chain
    region = shapely.Polygon(ring)
    for c in range(len(cells)):
        a = shapely.clip_by_rect(region, cells[c, 0], cells[c, 2], cells[c, 1],
                                 cells[c, 3]).area
        if status[c] == CLIP_DONE:
            assert 0.5 * _area2(tri[own == c]).sum() == pytest.approx(a, rel=1e-12)
    assert (status == CLIP_DONE).sum() >= 8


def test_a_point_on_the_edge_between_runs_is_dropped():
    # the ring runs along the cell's left edge through (0, 0.5): the piece is the
    # cell's rectangle cut by the diagonal, not a pentagon with a point on its side
    ring = np.array([[0.0, -1.0], [2.0, -1.0], [0.0, 1.0], [0.0, 0.5]])
    tri, own, status, area = clip_cells(np.array([[0.0, 1.0, 0.0, 1.0]]),
                                        *_pack([ring]), np.array([1]))
    assert status[0] == CLIP_DONE and len(tri) == 1
    assert area[0] == pytest.approx(0.5)


def test_left_cases():
    sq = np.array([[0.2, 0.2], [0.8, 0.2], [0.8, 0.8], [0.2, 0.8]])
    cell = np.array([[0.0, 1.0, 0.0, 1.0]])
    # a hole without a vertex outside the cell that touches its edge; as an island
    # (counter-clockwise) it is the piece
    touch = np.array([[0.0, 0.2], [0.8, 0.2], [0.8, 0.8], [0.2, 0.8]])
    assert clip_cells(cell, *_pack([touch]), np.array([-1]))[2][0] == K.CLIP_RING_INSIDE
    tri, own, status, area = clip_cells(cell, *_pack([touch]), np.array([1]))
    assert status[0] == CLIP_DONE and area[0] == pytest.approx(shapely.Polygon(touch).area)
    # a ring wholly inside the cell is an island
    tri, own, status, area = clip_cells(cell, *_pack([sq]), np.array([1]))
    assert status[0] == CLIP_DONE and len(tri) == 2 and area[0] == pytest.approx(0.36)
    # two rings touching at one point of the cell's edge
    a = np.array([[-1.0, -1.0], [0.5, -1.0], [0.5, 0.0], [-1.0, 0.5]])
    b = np.array([[0.5, 0.0], [2.0, -1.0], [2.0, 0.5]])
    P, starts = _pack([a, b])
    assert clip_cells(cell, P, starts, ring_directions(P, starts))[2][0] == K.CLIP_WALK
    # crossing rings: the walk meets a chain twice, or the pieces' edges meet
    c1 = np.array([[-1.0, 0.3], [2.0, 0.3], [2.0, 2.0], [-1.0, 2.0]])
    c2 = np.array([[0.3, -1.0], [0.6, -1.0], [0.6, 2.5], [0.3, 2.5]])
    P, starts = _pack([c1, c2])
    assert clip_cells(cell, P, starts, np.array([1, 1]))[2][0] in (K.CLIP_WALK, K.CLIP_TOUCH)


def test_the_triangulation_is_constrained_delaunay():
    # a fan of points on an arc inside one cell: ear clipping alone gives slivers
    t = np.linspace(0.1, np.pi - 0.1, 15)
    arc = np.c_[0.5 + 0.45 * np.cos(t), 0.05 + 0.9 * np.sin(t)]
    ring = np.vstack([[[-0.5, -0.5], [1.5, -0.5]], arc])
    cells = np.array([[0.0, 1.0, 0.0, 1.0]])
    P, starts = _pack([ring])
    tri, own, status, _ = clip_cells(cells, P, starts, ring_directions(P, starts))
    assert status[0] == CLIP_DONE
    # every edge shared by two triangles: the opposite corner outside the circle
    edges = {}
    for k, t3 in enumerate(tri):
        for e in range(3):
            a, b = tuple(t3[e]), tuple(t3[(e + 1) % 3])
            edges[(a, b)] = (k, tuple(t3[(e + 2) % 3]))
    checked = 0
    for (a, b), (k, c) in edges.items():
        if (b, a) not in edges:
            continue
        d = edges[(b, a)][1]
        m = np.array([[p[0] - d[0], p[1] - d[1], (p[0] - d[0]) ** 2 + (p[1] - d[1]) ** 2]
                      for p in (a, b, c)])
        assert np.linalg.det(m) <= 1e-12
        checked += 1
    assert checked >= 10


PARTS = ["inventor2015_cylinder_block_face6.stp", "nist_ctc_05_ap203.stp",
         "euclid_screw_ap214.step", "catia_v5_ventilator_swept_faces.stp"]


def _packed_clean(trim):
    rings = trim.rings()
    starts = np.zeros(len(rings) + 1, dtype=np.int64)
    np.add.accumulate([len(r) for r in rings], out=starts[1:])
    (u0, u1), (v0, v1) = trim.surface.domain
    tiny = cells_mod.LOOP_AREA_REL * (u1 - u0) * (v1 - v0)
    return clean_rings(np.ascontiguousarray(np.concatenate(rings)), starts, tiny), tiny


@pytest.mark.parametrize("name", PARTS)
def test_parts_cut_cells_match_geos(name, monkeypatch):
    """Every cut cell of every trimmed grid against GEOS's clip of the cleaned rings'
    region and its triangulation: the same triangle count and area (only the area
    where the cleaned rings still touch: against GEOS's valid form of the rings); the
    cleaned region's area within the loops cut off of GEOS's valid form."""
    S, size = part_surfaces(name)
    tol = 1e-3 * size
    seen = []
    real = cells_mod.clip_grid_cells

    def spy(c, trim, inside_area):
        out = real(c, trim, inside_area)
        seen.append((c, trim, out))
        return out

    monkeypatch.setattr(tess_mod, "clip_grid_cells", spy)
    monkeypatch.setattr(tess_mod, "FIRST_CELLS", 0)  # the steps: their cut cells seen
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tess_mod.tessellate(S, tol)
    assert seen
    for c, trim, (t1, o1) in seen:
        (P, starts), tiny = _packed_clean(trim)
        rings = [P[a:b] for a, b in zip(starts[:-1], starts[1:])]
        region = shapely.Polygon(rings[0], rings[1:])
        valid = region.is_valid  # else rings that still touch: GEOS's valid form
        if not valid:
            region = trim.region
        assert abs(region.area - trim.region.area) <= 4 * tiny
        pieces = shapely.lib.clip_by_rect(region, c[:, 0], c[:, 2], c[:, 1], c[:, 3])
        t2, o2 = triangulate_pieces(pieces)
        assert (np.diff(o1) >= 0).all()
        if valid:
            assert np.array_equal(np.bincount(o1, minlength=len(c)),
                                  np.bincount(o2, minlength=len(c)))
        a1 = np.bincount(o1, 0.5 * _area2(t1), minlength=len(c))
        a2 = np.bincount(o2, 0.5 * np.abs(_area2(t2)), minlength=len(c))
        np.testing.assert_allclose(a1, a2, rtol=1e-9, atol=1e-14 * a2.max() + 4 * tiny)


def test_clean_rings_spurs_and_small_loops():
    # a square whose bottom edge overshoots the corner by 1e-9 and comes back (a spur),
    # whose right edge crosses itself in a loop of 5e-17 area, and a repeated vertex
    def square(e):
        return np.array([[0.0, 0.0], [1.0 + 1e-9, 0.0], [1.0, 0.0], [1.0, 0.5],
                         [1.0, 0.5 + 2 * e], [1.0 + e, 0.5 + e], [1.0 - e, 0.5 + e],
                         [1.0, 1.0], [1.0, 1.0], [0.0, 1.0]])
    P, starts = _pack([square(1e-8)])
    assert not shapely.Polygon(P).is_valid
    Q, qs = clean_rings(P, starts, 1e-12)
    assert qs.tolist() == [0, 8]
    assert shapely.Polygon(Q).is_valid
    assert abs(shapely.Polygon(Q).area - shapely.make_valid(shapely.Polygon(P)).area) < 1e-15
    assert [1.0 + 1e-9, 0.0] not in Q.tolist() and [1.0, 0.5 + 1e-8] in Q.tolist()
    # a loop above the bound stays (only the spur and the repeat go)
    assert clean_rings(*_pack([square(1e-3)]), 1e-12)[1].tolist() == [0, 9]
    # a ring of spurs only goes
    spur = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [1.0, 0.0]])
    sq = np.array([[5.0, 5.0], [6.0, 5.0], [6.0, 6.0], [5.0, 6.0]])
    Q, qs = clean_rings(*_pack([spur, sq]), 1e-12)
    assert qs.tolist() == [0, 5] and np.array_equal(Q[:4], sq)
