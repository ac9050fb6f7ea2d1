"""The trimmed planes' rings in one pass (:func:`geomkit.mesh.planes._rings`, kernels
``geomkit._kernels.tess_loops.plane_rings`` and ``loop_areas``), their triangles as
indexed meshes in one kernel (``tess_loops.polygon_meshes``, against the numpy route
it replaced, bit for bit: random triangles with repeated corners, zero areas and
signed zeros, and the parts' planes), the packing of every
loop of many surfaces at once (:func:`geomkit.nurbs.trims.packed_loops`) and the plane
test of many surfaces with few numpy calls (:func:`geomkit.mesh.trim_polylines.affine_flags`), each
against the route it replaced: the rings of ``TrimPolylines(...).rings()`` face by face
(:func:`geomkit.mesh.planes._rings_one_by_one`), bit for bit; each surface's
:func:`packed_trims` concatenated with its offsets moved, bit for bit; and
``affine_map(s, size) is not None``, the same answer.  On the trimmed faces of five
real parts (planes with arcs and several loops, cylinders, cones, tori, B-splines)
and on made-up cases: a loop that is the domain rectangle, two holes of one area,
loops of equal area, nets near the degeneracy threshold.  Also the planes' speed bounds
in one call (``tess_trim.speed_bounds``) against ``speed_bound`` face by face, the flat
nets' domains against ``Surface.domain``."""

from __future__ import annotations

import numpy as np
import pytest

from geomkit._kernels.tess_loops import loop_areas, polygon_meshes
from geomkit._kernels.tess_trim import speed_bounds
from geomkit.mesh.planes import _rings, _rings_one_by_one, _triangulate, planar_batch
from geomkit.mesh.trim_polylines import (affine_flags, affine_map, flat_surfaces,
                                         loop_points, speed_bound)
from geomkit.nurbs.surface import Surface
from geomkit.nurbs.trims import packed_loops, packed_trims

from helpers.parts import part_surfaces

PARTS = ["proe_as1_ap203.stp", "nist_ftc_07_ap242.stp", "nist_ctc_01_ap242.stp",
         "euclid_screw_ap214.step", "sw2013_featuretype_ap214.step"]


@pytest.fixture(scope="module", params=PARTS)
def part(request):
    S, size = part_surfaces(request.param)
    return S, 1e-3 * size


def _same_rings(P, chord_tol):
    got = _rings(P, chord_tol, True, flat_surfaces(P))
    faces, coords, ring_size, ring_face = _rings_one_by_one(P, range(len(P)), chord_tol, True)
    coords2, ring_size2, ring_face2, kept = got
    assert kept.tolist() == faces
    assert np.array_equal(coords2, coords)  # bit for bit (no signed-zero case here)
    assert np.array_equal(np.signbit(coords2), np.signbit(coords))
    assert ring_size2.tolist() == list(ring_size)
    assert ring_face2.tolist() == ring_face.tolist()


def _old_glue(packs):
    """The concatenation of per-surface packs as loop_polylines made it before."""
    starts = lambda c: np.concatenate([[0], np.cumsum(c)]).astype(np.int64)  # noqa: E731
    face_piece = starts([len(pk[3]) for pk in packs])
    cp_base = starts([len(pk[0]) for pk in packs])
    k_base = starts([len(pk[2]) for pk in packs])
    return (np.concatenate([pk[0] for pk in packs]), np.concatenate([pk[1] for pk in packs]),
            np.concatenate([pk[2] for pk in packs]), np.concatenate([pk[3] for pk in packs]),
            np.concatenate([pk[4][:-1] + b for pk, b in zip(packs, cp_base)] + [cp_base[-1:]]),
            np.concatenate([pk[5][:-1] + b for pk, b in zip(packs, k_base)] + [k_base[-1:]]),
            np.concatenate([pk[6][:-1] + b for pk, b in zip(packs, face_piece)]
                           + [face_piece[-1:]]),
            starts([len(pk[6]) - 1 for pk in packs]))


def test_packed_loops_match_the_surfaces_packs(part):
    S, _ = part
    T = [s for s in S if s.trim]
    for sel in (T, T[:1], T[1:4], T[::3]):
        got = packed_loops(sel)
        want = _old_glue([packed_trims(s) for s in sel])
        for a, b in zip(got, want):
            assert a.dtype == b.dtype and np.array_equal(a, b)


def test_affine_flags_match_affine_map_on_parts(part):
    S, _ = part
    assert affine_flags(S, [s.size for s in S]) == [affine_map(s, s.size) is not None
                                                    for s in S]


def _net(P, W=None):
    return Surface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], np.array(P, dtype=float), W)


def test_affine_flags_match_affine_map_on_made_up_nets():
    rng = np.random.default_rng(7)
    nets = []
    for _ in range(300):
        o, a, b = rng.standard_normal((3, 3)) * 10.0 ** rng.uniform(-3, 3)
        twist = rng.choice([0.0, 1e-13, 1e-9, 1e-3]) * rng.standard_normal(3)
        nets.append([[o, o + b], [o + a, o + a + b + twist]])
    for _ in range(300):  # nearly parallel edges: sin^2 around the 1e-24 threshold
        o, a = rng.standard_normal((2, 3))
        e = rng.standard_normal(3)
        b = 2.0 * a + 10.0 ** rng.uniform(-13.5, -11.5) * e
        nets.append([[o, o + b], [o + a, o + a + b]])
    o, a = rng.standard_normal((2, 3))
    nets += [[[o, o], [o + a, o + a]], [[o, o], [o, o]], [[o, o + a], [o + a, o + 2 * a]]]
    S = [_net(P, W) for P in nets
         for W in (None, [[2.0, 2.0], [2.0, 2.0]], [[1.0, 2.0], [1.0, 1.0]])]
    want = [affine_map(s, s.size) is not None for s in S]
    assert affine_flags(S, [s.size for s in S]) == want
    assert 0 < sum(want) < len(S)


def test_rings_match_trim_polylines_rings(part):
    S, tol = part
    P = [s for s in S if s.trim and affine_map(s, s.size) is not None]
    assert P
    _same_rings(P, 0.5 * tol)


def _square_face(loops):
    P = np.array([[[0, 0, 0], [0, 2, 0]], [[3, 0, 0], [3, 2, 1e-30]]], dtype=float)
    return Surface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], P, trim=[np.array(x, dtype=float)
                                                                  for x in loops])


def _box(a0, a1, b0, b1):
    return [[a0, b0], [a1, b0], [a1, b1], [a0, b1], [a0, b0]]


def test_rings_match_on_made_up_planes():
    faces = [
        _square_face([_box(0, 1, 0, 1), _box(0.2, 0.4, 0.2, 0.4)]),  # the domain loop, a hole
        _square_face([_box(0.2, 0.4, 0.2, 0.4), _box(0.6, 0.8, 0.6, 0.8)]),  # equal areas
        _square_face([_box(0.5, 0.7, 0.5, 0.7), _box(0.1, 0.9, 0.1, 0.9),
                      _box(0.2, 0.4, 0.2, 0.4)]),  # the shell second
        _square_face([_box(1e-9, 1, 0, 1)]),  # near the domain: speed_bound decides
        _square_face([_box(0.1, 0.9, 0.1, 0.9)]),
    ]
    _same_rings(faces, 1e-3)
    for s in faces:  # and the batch's triangles are those of the face's own region
        out = planar_batch([s, s], 1e-3, cross_knots=True)
        assert set(out) <= {0, 1}


def test_loop_areas_bound_their_rounding(part):
    S, tol = part
    P = [s for s in S if s.trim]
    pts, start, _, _ = loop_points(P, 0.5 * tol, False, True)
    area, err = loop_areas(pts, start)
    for lp in range(len(area)):
        p = pts[start[lp]:start[lp + 1]]
        exact = abs(np.dot(p[:-1, 0], p[1:, 1]) - np.dot(p[1:, 0], p[:-1, 1]))
        assert abs(area[lp] - exact) <= err[lp]


def _numpy_meshes(tri, idx, n):
    """The triangles' indexed meshes as planar_batch made them in numpy before."""
    tri = tri.copy()
    a = tri[:, 1] - tri[:, 0]
    b = tri[:, 2] - tri[:, 0]
    area2 = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    keep = area2 != 0
    tri, idx, area2 = tri[keep], idx[keep], area2[keep]
    flip = area2 < 0
    tri[flip] = tri[flip][:, ::-1]
    corners = tri.reshape(-1, 2)
    cown = np.repeat(idx, 3)
    order = np.lexsort((corners[:, 1], corners[:, 0], cown))
    c, o = corners[order], cown[order]
    new = np.ones(len(c), dtype=bool)
    new[1:] = (o[1:] != o[:-1]) | (c[1:, 0] != c[:-1, 0]) | (c[1:, 1] != c[:-1, 1])
    inv = np.empty(len(c), dtype=np.int64)
    inv[order] = np.cumsum(new) - 1
    uv, own = c[new], o[new]
    vstart = np.searchsorted(own, np.arange(n + 1))
    tstart = np.searchsorted(idx, np.arange(n + 1))
    return uv, inv.reshape(-1, 3) - vstart[idx][:, None], vstart, tstart


def _same_meshes(tri, idx, n):
    got = polygon_meshes(tri, idx, n)
    want = _numpy_meshes(tri, idx, n)
    for g, w in zip(got, want):
        assert g.shape == w.shape and np.array_equal(g, w)
    assert np.array_equal(np.signbit(got[0]), np.signbit(want[0]))


def test_polygon_meshes_match_numpy_on_made_up_triangles():
    rng = np.random.default_rng(3)
    for _ in range(200):
        n = int(rng.integers(1, 6))
        pts = rng.integers(-3, 4, size=(12, 2)).astype(float) * rng.choice([1.0, 0.1, 1e-9])
        pts[rng.random(12) < 0.2] *= -1.0  # signed zeros among the corners
        T = int(rng.integers(0, 40))
        tri = pts[rng.integers(0, 12, size=(T, 3))]  # shared, repeated and collinear corners
        idx = np.sort(rng.integers(0, n, size=T))
        _same_meshes(tri, idx, n)


def test_polygon_meshes_match_numpy_on_parts(part):
    import shapely

    S, tol = part
    P = [s for s in S if s.trim and affine_map(s, s.size) is not None]
    coords, ring_size, ring_face, kept = _rings(P, 0.5 * tol, True, flat_surfaces(P))
    rings = shapely.linearrings(coords, indices=np.repeat(np.arange(len(ring_size)),
                                                          ring_size))
    polys = shapely.polygons(rings, indices=ring_face)
    use = np.nonzero(shapely.is_valid(polys))[0]
    tri, idx, _ = _triangulate(polys, coords, ring_size, ring_face, use)
    _same_meshes(tri, idx, len(use))


def test_speed_bounds_and_flat_domains_match_the_face_by_face_values(part):
    S, _ = part
    flat = flat_surfaces(S)
    assert flat[7].tolist() == [list(s.domain[0] + s.domain[1]) for s in S]
    xyz = np.concatenate([s.control_points for s in S], axis=None).reshape(-1, 3)
    Pw, pw_off, nets, U, u_off, V, v_off, _ = flat
    got = speed_bounds(xyz, Pw, pw_off, nets, U, u_off, V, v_off, np.arange(len(S)))
    assert got.tolist() == [speed_bound(s) for s in S]  # bit for bit


def test_polygon_meshes_match_numpy_on_large_polygons():
    rng = np.random.default_rng(11)
    for T in (30, 200, 700):  # corners beyond one run of 8 and several merge passes
        pts = rng.integers(-20, 21, size=(3 * T // 2, 2)).astype(float)
        tri = pts[rng.integers(0, len(pts), size=(T, 3))]
        idx = np.sort(rng.integers(0, 3, size=T))
        _same_meshes(tri, idx, 3)
