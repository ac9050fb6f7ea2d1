"""Tessellation's per-call fast paths give the same meshes as the general code.

* meshes of small cases against a reference written by the code before the fast
  paths (tests/data/tess_fastpath_reference.npz: geomkit at 7ea6120): same faces,
  vertices, UVs and stated deviations;
* the uniform grid's weld from grid indices against the general weld (unique UVs,
  KD-tree of boundary vertices), poles and seams included;
* the boundary-pair and near-UV-pair pre-tests (oblique projection) against brute
  force;
* the knot breakpoints against ``np.unique``.
"""

from __future__ import annotations

import importlib

import numpy as np
import pytest
import shapely

from geomkit.mesh import quadtree as qt
from geomkit import samples
from geomkit import tolerances as tols
from geomkit.mesh.tessellate import tessellate
from geomkit._kernels.tess_weld import unique_uv

from helpers.paths import DATA

T = importlib.import_module("geomkit.mesh.tessellate")  # the module, not the function
C = importlib.import_module("geomkit.mesh.cells")
W = importlib.import_module("geomkit.mesh.weld")
REF = DATA / "tess_fastpath_reference.npz"
FIELDS = ("faces", "face_surface", "vertex_surface", "vertices", "uv", "face_uv",
          "face_deviation")


def _same(a, b):
    """Equal arrays: integers exactly, floats to a few rounding units of their scale
    (the reference was written on this project's machine; another CPU may round
    fused multiply-adds differently)."""
    assert a.shape == b.shape and a.dtype == b.dtype
    if a.dtype.kind in "iu":
        return np.array_equal(a, b)
    scale = max(1.0, float(np.abs(b).max())) if b.size else 1.0
    return bool(np.all(np.abs(a - b) <= 1e-12 * scale))


# (the reference's plate_with_hole_1e-02 is not compared: its hole's polyline started
# from 5 seeds a knot span, the trim polylines now start from the knots; the direct
# path for trimmed planes against the cell path: tests/mesh/test_tessellate_trims.py)
@pytest.mark.parametrize("key", ["cylinder_quarter_1e-02", "cylinder_quarter_1e-03",
                                 "offset_planes_1e-02",
                                 "sphere_1e-01", "torus_1e-01", "crease_3e-02"])
def test_meshes_match_the_reference_before_the_fast_paths(key):
    ref = np.load(REF)
    name, tol = key.rsplit("_", 1)
    mesh = tessellate(samples.load(name), float(tol))
    for f in FIELDS:
        assert _same(getattr(mesh, f), ref[f"{key}/{f}"]), f
    assert all(st.get("uniform_grid") or st.get("planar_trimmed") or st.get("affine_plane")
               for st in mesh.stats["surfaces"])  # the fast paths were taken


def _grid(name, tol):
    s = samples.load(name)[0]
    ub = C.breakpoints(s.knots_u, s.degree_u)
    vb = C.breakpoints(s.knots_v, s.degree_v)
    m = max(5, 2 * max(s.degree_u, s.degree_v) + 1)
    g = qt.uniform_grid(s, ub, vb, m, T.SAMPLES_PER_EDGE, tol, C.CELL_TARGET * tol,
                        C.EXACT_ABOVE * tol, T.GRID_CELLS)
    assert g is not None
    return s, g


@pytest.mark.parametrize("name,tol", [("sphere", 1e-1), ("torus", 1e-1),
                                      ("cylinder_quarter", 1e-2), ("crease", 3e-2),
                                      ("saddle", 1e-2), ("freeform_1", 1.2e-1),
                                      ("wave_seed003", 3e-1)])
def test_grid_weld_matches_the_general_weld(name, tol):
    """Poles (sphere: faces collapse), seams (sphere, torus) and open surfaces
    (freeform_1: a grid of 3,392 cells; at 0.1 its grid exceeds ``GRID_CELLS``)."""
    s, (tri_uv, dev, cells, (u, v, diag)) = _grid(name, tol)
    got = W.weld_grid(s, u, v, diag, s.size)
    want = W.weld(s, tri_uv, s.size, near_uv=False)
    assert got is not None
    for a, b in zip(got, want):
        assert a.dtype == b.dtype and np.array_equal(a, b)
    # the grid's triangles are the cells' two halves on the grid lines
    assert len(tri_uv) == 2 * len(cells) == 2 * (len(u) - 1) * (len(v) - 1)
    if name == "sphere":
        assert not got[3].all()  # faces collapsed at the poles were found


def test_boundary_pairs_match_brute_force():
    rng = np.random.default_rng(7)
    size, r = 1.0, tols.WELD_REL * 1.0
    for trial in range(40):
        n = int(rng.integers(2, 60))
        P = rng.random((n, 3))
        if trial % 4 == 0:  # points on an axis-aligned line and plane (equal coordinates)
            P[:, 1:] = 0.5
        elif trial % 4 == 1:
            P[:, 2] = 0.25
        if trial % 2:  # plant near and exact coincidences
            k = int(rng.integers(1, n // 2 + 1))
            i = rng.choice(n, size=k, replace=False)
            j = rng.choice(n, size=k, replace=False)
            P[j] = P[i] + rng.normal(size=(k, 3)) * r * rng.choice([0.0, 0.3, 3.0], size=(k, 1))
        bnd = np.sort(rng.choice(n + 5, size=n, replace=False))
        Q = np.zeros((n + 5, 3))
        Q[bnd] = P
        got = {tuple(sorted(p)) for p in W.boundary_pairs(Q, bnd, size).tolist()}
        d = np.linalg.norm(P[:, None] - P[None], axis=2)
        want = {(int(bnd[a]), int(bnd[b])) for a, b in zip(*np.nonzero(np.triu(d <= r, 1)))}
        assert got == want, trial


def test_near_uv_pairs_match_brute_force():
    """The weld's distinct UVs (numpy's unique of u + iv, with its inverse) and their
    near pairs (trim crossings computed in two cells) with the projection pre-test
    against all pairs within r."""
    rng = np.random.default_rng(11)
    for trial in range(40):
        n = int(rng.integers(2, 80))
        r = 1e-13 * float(rng.choice([1.0, 10.0, 1e3]))
        Q = rng.random((n, 2)) * float(rng.choice([1.0, 6.3, 1e3]))
        if trial % 3 == 0:  # points on grid lines (equal coordinates)
            Q[: n // 2, 0] = Q[0, 0]
        if trial % 2:  # plant near and exact coincidences
            k = int(rng.integers(1, n // 2 + 1))
            i = rng.choice(n, size=k, replace=False)
            j = rng.choice(n, size=k, replace=False)
            Q[j] = Q[i] + rng.normal(size=(k, 2)) * r * rng.choice([0.0, 0.3, 3.0], size=(k, 1))
        uniq, inv, pairs = unique_uv(Q, True, r, W.NEAR_DIRECTION)
        assert np.array_equal(uniq[inv], Q)
        # numpy's unique of u + iv: the same rows in the same order
        assert np.array_equal(uniq.copy().view(np.complex128).ravel(),
                              np.unique(Q.view(np.complex128).ravel()))
        got = {tuple(sorted(p)) for p in pairs.tolist()}
        d = np.linalg.norm(uniq[:, None] - uniq[None], axis=2)
        want = {(int(a), int(b)) for a, b in zip(*np.nonzero(np.triu(d <= r, 1)))}
        assert got == want, trial


def test_breakpoints_match_numpy():
    for name in samples.names():
        for s in samples.load(name):
            for U, p in ((s.knots_u, s.degree_u), (s.knots_v, s.degree_v)):
                assert np.array_equal(C.breakpoints(U, p), np.unique(U[p: len(U) - p]))


def test_boundary_pairs_far_from_the_origin():
    """Coordinates of 1e6 with pairs at 0.5 r: the projections' rounding (~1e-10)
    is the order of r itself; the pre-test must still leave them to the tree."""
    rng = np.random.default_rng(11)
    P = 1e6 + rng.random((30, 3))
    r = tols.WELD_REL * 1.0
    P[20:] = P[:10] + rng.normal(size=(10, 3)) * (0.5 * r / np.sqrt(3) / 3)
    got = {tuple(sorted(p)) for p in W.boundary_pairs(P, np.arange(30), 1.0).tolist()}
    d = np.linalg.norm(P[:, None] - P[None], axis=2)
    want = {(int(a), int(b)) for a, b in zip(*np.nonzero(np.triu(d <= r, 1)))}
    assert got == want and len(want) >= 5


# ------------------------------------------------------------------ whole-part batches
@pytest.fixture(scope="module")
def ctc01():
    from geomkit.cad.step import read_step

    S = read_step(DATA / "parts" / "nist_ctc_01_ap203.stp", reader="geomkit").surfaces
    B = np.array([s.bounds for s in S])
    return S, 1e-3 * float(np.linalg.norm(B[:, 1].max(axis=0) - B[:, 0].min(axis=0)))


def test_planes_batch_matches_face_by_face(ctc01):
    """The trimmed planes of NIST CTC-01 triangulated together: for each, the same
    vertices as the face-by-face triangulation of its region (their points S(uv) bit
    for bit), as many triangles,
    covering the region's area, every boundary edge kept; non-planes marked False."""
    from geomkit.mesh.planes import planar_batch
    from geomkit.mesh.trim_polylines import TrimPolylines, affine_map, planar_trimmed

    S, tol = ctc01
    out = planar_batch(S, 0.5 * tol)
    planes = [i for i, s in enumerate(S) if s.trim and affine_map(s, s.size) is not None]
    assert len(planes) > 50 and all(out[i] is False for i in range(len(S))
                                    if S[i].trim and i not in planes)
    for i in planes:
        trim = TrimPolylines(S[i], 0.5 * tol, affine=True)
        uv0, F0 = planar_trimmed(trim)
        uv, F, P, _ = out[i]
        used = np.unique(F0)
        assert np.array_equal(uv, uv0[used]) and len(F) == len(F0), i
        assert np.array_equal(P, W.points(S[i], uv)), i  # the batch's vertices S(uv)
        t = uv[F]
        a2 = (t[:, 1, 0] - t[:, 0, 0]) * (t[:, 2, 1] - t[:, 0, 1]) \
            - (t[:, 1, 1] - t[:, 0, 1]) * (t[:, 2, 0] - t[:, 0, 0])
        assert (a2 > 0).all()  # counter-clockwise
        assert abs(0.5 * a2.sum() - trim.region.area) <= 1e-12 * trim.region.area
        e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
        u, c = np.unique(e, axis=0, return_counts=True)
        outline = shapely.union_all(shapely.linestrings(uv[u[c == 1]]))
        assert shapely.equals(shapely.line_merge(outline), shapely.line_merge(
            shapely.union_all(trim.region.boundary))), i


def test_rectangle_clip_matches_the_overlay(ctc01, monkeypatch):
    """Cut cells of a trimmed cylinder's grid: the rectangle clip's pieces have the
    overlay's areas; a clip that returns a wrong piece is caught by the area sum and
    the overlay's pieces are used."""
    import geomkit.mesh.cells as C
    from geomkit.mesh.trim_polylines import TrimPolylines

    S, tol = ctc01
    s = S[19]
    trim = TrimPolylines(s, 0.5 * tol)
    (u0, u1), (v0, v1) = s.domain
    g = np.stack(np.meshgrid(np.linspace(u0, u1, 41)[:-1], np.linspace(v0, v1, 37)[:-1],
                             indexing="ij"), axis=-1).reshape(-1, 2)
    du, dv = (u1 - u0) / 40, (v1 - v0) / 36
    cells = np.c_[g[:, 0], g[:, 0] + du, g[:, 1], g[:, 1] + dv]
    state = trim.classify_uv(cells)
    cut, inside = cells[state == 2], cells[state == 1]
    ia = float(len(inside) * du * dv)
    want = shapely.area(shapely.intersection(shapely.box(cut[:, 0], cut[:, 2], cut[:, 1],
                                                         cut[:, 3]), trim.region))
    got = C.clip_rectangles(cut, trim, ia)
    np.testing.assert_allclose(shapely.area(got), want, rtol=0, atol=1e-12 * du * dv)
    real = shapely.lib.clip_by_rect

    def sliver(*a):
        out = real(*a)
        out[0] = shapely.box(a[1][0], a[2][0], a[1][0] + 1e-3 * du, a[2][0] + 1e-3 * dv)
        return out
    monkeypatch.setattr(shapely.lib, "clip_by_rect", sliver)
    got = C.clip_rectangles(cut, trim, ia)
    np.testing.assert_allclose(shapely.area(got), want, rtol=0, atol=1e-12 * du * dv)


def test_weld_components_match_scipy():
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    rng = np.random.default_rng(4)
    for trial in range(500):
        n = int(rng.integers(1, 60))
        if trial % 3 == 0 and n > 1:  # one long chain
            p = rng.permutation(n)
            pairs = np.stack([p[:-1], p[1:]], axis=1)
        else:
            pairs = rng.integers(0, n, size=(int(rng.integers(1, 3 * n + 1)), 2))
        _, label = connected_components(coo_matrix((np.ones(len(pairs)), (pairs[:, 0],
                                                   pairs[:, 1])), shape=(n, n)), directed=False)
        root = W.components(n, pairs)
        first = np.flatnonzero(root == np.arange(n))
        assert np.array_equal(np.searchsorted(first, root), label), trial



def test_triangle_coordinates_match_get_parts():
    """The triangles of GEOS's collections read in one get_coordinates call against
    the per-triangle route (get_parts, exterior rings), empty collections included; a
    part that is not a triangle (a square: 5 ring points) is not read as triangles."""
    rng = np.random.default_rng(7)
    polys = []
    for n in (5, 9, 23, 40):
        a = np.sort(rng.random(n)) * 2 * np.pi
        polys.append(shapely.Polygon(np.c_[np.cos(a), np.sin(a)]
                                     * (1 + 0.3 * rng.random(n))[:, None]))
    polys.insert(1, shapely.Polygon())
    polys.append(shapely.box(0, 0, 1, 1).difference(shapely.box(.4, .4, .6, .6)))
    tri = shapely.constrained_delaunay_triangles(np.array(polys, dtype=object))
    parts, idx = shapely.get_parts(tri, return_index=True)
    xy = shapely.get_coordinates(shapely.get_exterior_ring(parts))
    got = C.triangle_coordinates(tri)
    assert np.array_equal(got[0], xy.reshape(-1, 4, 2)[:, :3, :])
    assert np.array_equal(got[1], idx)
    assert set(idx.tolist()) == {0, 2, 3, 4, 5}
    square = np.array([shapely.GeometryCollection([shapely.box(0, 0, 1, 1)])], dtype=object)
    with pytest.raises(ValueError):  # 5 ring points: neither route reads it as triangles
        C.triangle_coordinates(square)


def _split_counts_numpy(e, eu, ev, target, max_parts=8):
    """quadtree.split_counts' numpy formulas before its kernel (the oracle)."""
    T = target
    twist = np.maximum(eu, ev) < 0.25 * e
    fu = np.sqrt(2.0 * eu / T)
    fv = np.sqrt(2.0 * ev / T)
    fu = np.where(fv < 1.0, np.sqrt(eu / np.maximum(T - ev, 0.5 * T)), fu)
    fv = np.where(fu < 1.0, np.sqrt(ev / np.maximum(T - eu, 0.5 * T)), fv)
    ft = np.sqrt(e / T)
    fu = np.where(twist, np.maximum(fu, ft), fu)
    fv = np.where(twist, np.maximum(fv, ft), fv)
    return (np.minimum(np.maximum(np.ceil(fu), 1), max_parts).astype(np.int64),
            np.minimum(np.maximum(np.ceil(fv), 1), max_parts).astype(np.int64))


def test_split_counts_kernel_matches_the_numpy_formulas():
    rng = np.random.default_rng(12)
    for trial in range(200):
        n = int(rng.integers(0, 50))
        E = 10.0 ** rng.uniform(-6, 3, (n, 3)) * (rng.random((n, 3)) > 0.1)
        if trial % 4 == 0:  # values exactly at the branch points
            E[: n // 2, 1] = 0.5
            E[: n // 3, 2] = 0.5
        target = 10.0 ** rng.uniform(-2, 1)
        for mp in (8, 4096):
            # strided columns as the callers pass them
            got = qt.split_counts(E[:, 0], E[:, 1], E[:, 2], target, max_parts=mp)
            want = _split_counts_numpy(E[:, 0], E[:, 1], E[:, 2], target, mp)
            assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])


def _weld_numpy(s, tri_uv, size, near_uv):
    """The weld in numpy steps and brute-force pairs (the route the compiled one
    replaced)."""
    (u0, u1), (v0, v1) = s.domain
    dom = max(u1 - u0, v1 - v0)
    z = np.ascontiguousarray(tri_uv.reshape(-1, 2)).view(np.complex128).ravel()
    uz, inv = np.unique(z, return_inverse=True)
    uniq = uz.view(np.float64).reshape(-1, 2)
    pairs = []
    if near_uv:
        d = np.linalg.norm(uniq[:, None] - uniq[None], axis=2)
        pairs.append(np.argwhere(np.triu(d <= 1e-13 * dom, 1)))
    P = W.points(s, uniq)
    eps = 1e-12 * dom
    bnd = np.nonzero((uniq[:, 0] <= u0 + eps) | (uniq[:, 0] >= u1 - eps)
                     | (uniq[:, 1] <= v0 + eps) | (uniq[:, 1] >= v1 - eps))[0]
    if len(bnd) >= 2:
        d = np.linalg.norm(P[bnd][:, None] - P[bnd][None], axis=2)
        pairs.append(bnd[np.argwhere(np.triu(d <= tols.WELD_REL * size, 1))])
    pairs = np.concatenate(pairs).reshape(-1, 2) if pairs else np.empty((0, 2), np.int64)
    return W.merge(P, uniq, inv.ravel(), pairs)


@pytest.mark.parametrize("name", ["sphere", "torus", "crease", "plate_with_hole"])
def test_weld_matches_numpy_steps(name):
    """The compiled weld against numpy's unique, brute-force pairs and the component
    merge, bit for bit: a grid over the domain (poles and seams weld in 3-D), with
    corners moved within rounding (near-UV pairs) and collapsed triangles."""
    rng = np.random.default_rng(3)
    for s in samples.load(name):
        (u0, u1), (v0, v1) = s.domain
        u = np.linspace(u0, u1, 9)
        v = np.linspace(v0, v1, 7)
        a = np.stack(np.meshgrid(u[:-1], v[:-1], indexing="ij"), -1).reshape(-1, 2)
        b = np.stack(np.meshgrid(u[1:], v[:-1], indexing="ij"), -1).reshape(-1, 2)
        c = np.stack(np.meshgrid(u[1:], v[1:], indexing="ij"), -1).reshape(-1, 2)
        d = np.stack(np.meshgrid(u[:-1], v[1:], indexing="ij"), -1).reshape(-1, 2)
        tri = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
        nudge = rng.random(tri.shape[:2]) < 0.1
        tri[nudge] += 1e-15 * max(u1 - u0, v1 - v0)
        tri[:3, 1] = tri[:3, 0]  # collapsed
        for near in (False, True):
            got = W.weld(s, tri, s.size, near_uv=near)
            want = _weld_numpy(s, tri, s.size, near)
            for g, w in zip(got, want):
                assert g.dtype == w.dtype or g.dtype.kind == w.dtype.kind
                assert np.array_equal(g, w), (name, near)
