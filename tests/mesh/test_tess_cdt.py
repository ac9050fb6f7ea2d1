"""The compiled constrained Delaunay triangulation of polygons with holes
(geomkit._kernels.tess_cdt) against GEOS's: the same triangle count, the polygon's
area, triangles counter-clockwise inside it, every diagonal locally Delaunay; on the
planar faces of real parts, every polygon the planes' batch triangulates."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import shapely

from geomkit._kernels.tess_cdt import triangulate_polygons
from geomkit.mesh import planes as planes_mod
from geomkit.mesh.tessellate import tessellate

from helpers.parts import part_surfaces


def _area2(t):
    a = t[:, 1] - t[:, 0]
    b = t[:, 2] - t[:, 0]
    return a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]


def _check(poly, tri):
    """GEOS's count and area, counter-clockwise triangles inside, locally Delaunay."""
    geos = shapely.get_parts(shapely.constrained_delaunay_triangles(poly))
    assert len(tri) == len(geos)
    assert (_area2(tri) > 0).all()
    assert 0.5 * _area2(tri).sum() == pytest.approx(poly.area, rel=1e-9)
    assert shapely.contains(poly.buffer(1e-12 * np.sqrt(poly.area)),
                            shapely.points(tri.mean(axis=1))).all()
    ring_edges = set()
    for ring in [poly.exterior, *poly.interiors]:
        c = [tuple(p) for p in np.asarray(ring.coords)]
        ring_edges |= {frozenset(e) for e in zip(c[:-1], c[1:])}
    edges = {}
    for t3 in tri:
        for e in range(3):
            a, b = tuple(t3[e]), tuple(t3[(e + 1) % 3])
            edges[(a, b)] = tuple(t3[(e + 2) % 3])
    for (a, b), c in edges.items():
        if (b, a) not in edges or frozenset((a, b)) in ring_edges:
            continue
        d = np.array(edges[(b, a)])
        m = np.array([[p[0] - d[0], p[1] - d[1], (p[0] - d[0]) ** 2 + (p[1] - d[1]) ** 2]
                      for p in (a, b, c)])
        scale = np.abs(m).max() ** 2
        assert np.linalg.det(m) <= 1e-9 * scale


def _star(n, r0, r1, rng, centre=(0.0, 0.0)):
    a = np.sort(rng.uniform(0, 2 * np.pi, n))
    r = rng.uniform(r0, r1, n)
    return np.c_[centre[0] + r * np.cos(a), centre[1] + r * np.sin(a)]


def _batch(polys):
    """The polygons' rings packed for triangulate_polygons (shell first, closed)."""
    rings, first, last = [], [], []
    for g in polys:
        first.append(len(rings))
        rings += [np.asarray(g.exterior.coords)] + [np.asarray(r.coords) for r in g.interiors]
        last.append(len(rings))
    rstart = np.zeros(len(rings) + 1, dtype=np.int64)
    np.add.accumulate([len(r) for r in rings], out=rstart[1:])
    return (np.ascontiguousarray(np.concatenate(rings)), rstart, np.array(first),
            np.array(last))


def test_random_polygons_with_holes_match_geos():
    rng = np.random.default_rng(5)
    polys = []
    for trial in range(60):
        shell = _star(int(rng.integers(3, 30)), 0.7, 1.0, rng)
        holes = []
        for h in range(int(rng.integers(0, 4))):
            c = (0.4 * np.cos(2.1 * h + trial), 0.4 * np.sin(2.1 * h + trial))
            holes.append(_star(int(rng.integers(3, 9)), 0.05, 0.12, rng, c))
        g = shapely.Polygon(shell if trial % 2 else shell[::-1], holes)
        if g.is_valid:
            polys.append(g)
    tri, idx, taken = triangulate_polygons(*_batch(polys), 64)
    # every simple one; of those with holes, ear clipping may stop on a bridged ring
    # (then GEOS takes it)
    simple = np.array([len(g.interiors) == 0 for g in polys])
    assert taken[simple].all() and taken.mean() > 0.7
    assert (np.diff(idx) >= 0).all()
    for j in np.nonzero(taken)[0]:
        _check(polys[j], tri[idx == j])


def test_large_polygons_are_left():
    g = shapely.Polygon(_star(80, 0.7, 1.0, np.random.default_rng(1)))
    tri, idx, taken = triangulate_polygons(*_batch([g]), 64)
    assert not taken[0] and len(tri) == 0


@pytest.mark.parametrize("name", ["proe_as1_ap203.stp", "nist_ctc_05_ap203.stp"])
def test_parts_planes_match_geos(name, monkeypatch):
    S, size = part_surfaces(name)
    tol = 1e-3 * size
    seen = []
    real = planes_mod._triangulate

    def spy(polys, *rest):
        seen.append(polys[rest[-1]])
        return real(polys, *rest)

    monkeypatch.setattr(planes_mod, "_triangulate", spy)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tessellate(S, tol)
    polys = seen[0]
    tri, idx, taken = triangulate_polygons(*_batch(polys), planes_mod.CDT_SMALL)
    assert taken.mean() > 0.9
    for j in np.nonzero(taken)[0]:
        _check(polys[j], tri[idx == j])
