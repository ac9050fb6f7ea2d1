"""The grid routes' measurement against both triangles of a cell, and the box route.

* ``cell_deviation(pair=True)``: a sample's surface point is measured against the
  nearer triangle of its cell's split (both in the mesh), so never more than the
  single-triangle measure, and the meshes stay within ``tol`` of the face both ways
  (checked independently by ``naive.sample_mesh_deviation``);
* ``cell_errors``' ``box``: the box edges' sags against the chord distances computed
  with numpy, folded into the estimates;
* a face whose only loop is a UV rectangle (``TrimPolylines.rectangle``) meshed as
  one grid over it, its in-plane boundary sag caught.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from geomkit._kernels.tess import cell_deviation, cell_errors
from geomkit.cad.step import read_step
from geomkit.mesh import quadtree as qt
from geomkit.mesh.tessellate import tessellate
from geomkit.mesh.trim_polylines import TrimPolylines
from geomkit.nurbs.evaluation import evaluate

from helpers import naive
from helpers.paths import DATA

def _part(name):
    S = read_step(DATA / "parts" / name, reader="geomkit").surfaces
    B = np.array([s.bounds for s in S])
    return S, 1e-3 * float(np.linalg.norm(B[:, 1].max(axis=0) - B[:, 0].min(axis=0)))


@pytest.fixture(scope="module")
def catia():
    return _part("catia_v5_ventilator_swept_faces.stp")


@pytest.fixture(scope="module")
def ctc01():
    return _part("nist_ctc_01_ap203.stp")


def _measure(s, cells, k, pair, exact_above, target):
    (u0, u1), (v0, v1) = s.domain
    E = np.empty((len(cells), 2))
    first = np.zeros(len(cells), dtype=np.int64)
    cell_deviation(s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                   np.ascontiguousarray(cells), first, k, u0, u1, v0, v1, exact_above,
                   target, E, pair)
    return E


def test_pair_measure_is_at_most_the_single_one_and_the_mesh_holds(ctc01):
    """On every untrimmed face of CTC-01 meshed by the uniform grid: the pair measure
    of the grid's cells is at most the single-triangle one (strictly less on the long
    cone cells), and the part's mesh is within tol of every such face both ways."""
    S, tol = ctc01
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mesh = tessellate(S, tol)
    faces = [i for i, st in enumerate(mesh.stats["surfaces"]) if st.get("uniform_grid")]
    assert len(faces) > 20
    less = 0
    k = 8
    for i in faces:
        s = S[i]
        fi = np.nonzero(mesh.face_surface == i)[0]
        uv = mesh.face_uv[fi]
        (u0, u1), (v0, v1) = s.domain
        u = np.unique(np.concatenate([uv[..., 0].ravel(), [u0, u1]]))
        v = np.unique(np.concatenate([uv[..., 1].ravel(), [v0, v1]]))
        cells = qt._tensor_cells(u, v)
        a = _measure(s, cells, k, True, 0.25 * tol, -1.0)   # both diagonals measured
        b = _measure(s, cells, k, False, 0.25 * tol, -1.0)
        assert (a <= b * (1 + 1e-12) + 1e-15).all(), i
        less += int((a < 0.99 * b).any())
    assert less > 0
    r = naive.sample_mesh_deviation(mesh, S, n_faces=4000, n_worst=500, exact_above=tol)
    assert r["to_surface"] <= tol and r["to_mesh"] <= tol, r


def test_box_edge_sags_match_numpy(catia):
    """The estimates with a box: the largest distance of the surface along a box edge
    from its chord, against the same samples evaluated and measured with numpy, folded
    into the chord error along the edge."""
    S, tol = catia
    s = S[0]
    (u0, u1), (v0, v1) = s.domain
    a0, a1 = u0 + 0.1 * (u1 - u0), u0 + 0.9 * (u1 - u0)
    b0, b1 = v0 + 0.2 * (v1 - v0), v0 + 0.7 * (v1 - v0)
    # cells refine the knot spans inside the box (as the grids' cells do)
    ku = np.unique(s.knots_u[(s.knots_u > a0) & (s.knots_u < a1)])
    kv = np.unique(s.knots_v[(s.knots_v > b0) & (s.knots_v < b1)])
    u = qt._lines(np.r_[a0, ku, a1], np.full(len(ku) + 1, 3))
    v = qt._lines(np.r_[b0, kv, b1], np.full(len(kv) + 1, 2))
    cells = qt._tensor_cells(u, v)
    m = 7
    args = (s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v, cells, m)
    plain = np.empty((len(cells), 5))
    cell_errors(*args, plain)
    out = np.empty((len(cells), 5))
    cell_errors(*args, out, box=(a0, a1, b0, b1))
    folded = 0
    for c, (c0, c1, d0, d1) in enumerate(cells):
        sag = [0.0, 0.0]
        edges = [(0, d0, (c0, c1)) for _ in [0] if d0 in (b0, b1)]
        edges += [(0, d1, (c0, c1)) for _ in [0] if d1 in (b0, b1)]
        edges += [(1, c0, (d0, d1)) for _ in [0] if c0 in (a0, a1)]
        edges += [(1, c1, (d0, d1)) for _ in [0] if c1 in (a0, a1)]
        for along, fixed, (t0, t1) in edges:
            t = t0 + (t1 - t0) * np.arange(m) / (m - 1)
            t[-1] = t1
            uv = np.c_[t, np.full(m, fixed)] if along == 0 else np.c_[np.full(m, fixed), t]
            X = evaluate(s, uv)
            A, B = X[0], X[-1]
            d = B - A
            w = np.clip((X[1:-1] - A) @ d / (d @ d), 0, 1)
            dist = np.linalg.norm(A + w[:, None] * d - X[1:-1], axis=1).max()
            sag[along] = max(sag[along], dist)
        want = plain[c].copy()
        want[2] = max(want[2], sag[0])
        want[3] = max(want[3], sag[1])
        folded += int(not np.array_equal(want, plain[c]))
        assert np.allclose(out[c], want, rtol=1e-9, atol=1e-12 * s.size), (c, out[c], want)
        if not edges:
            assert np.array_equal(out[c], plain[c])
    assert folded > 0


def test_rectangle_faces_meshed_as_one_box_grid(catia):
    """The CATIA part's swept faces are each their surface over a UV rectangle: the box
    route takes them, with far fewer triangles than the trimmed grid did (1,167 for the
    part before; BRepMesh 376), and the mesh is within tol both ways, the rim's
    in-plane sag included."""
    S, tol = catia
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mesh = tessellate(S, tol)
    box = [i for i, st in enumerate(mesh.stats["surfaces"]) if st.get("box_grid")]
    assert len(box) >= 3
    for i in box:
        assert TrimPolylines(S[i], 0.1 * tol).rectangle() is not None
    assert len(mesh.faces) <= 500
    assert mesh.max_deviation <= tol
    r = naive.sample_mesh_deviation(mesh, S, exact_above=tol)
    assert r["to_surface"] <= tol and r["to_mesh"] <= tol, r


@pytest.fixture(scope="module")
def euclid():
    return _part("euclid_screw_ap214.step")


def test_trimmed_grids_of_the_estimates_hold_tol_both_ways(euclid):
    """EUCLID's trimmed helical faces and cone are meshed on the grid of the estimates
    (the cone's rim sag folded in), their triangles measured only once clipped: the
    mesh is within tol of every such face both ways, checked independently."""
    S, tol = euclid
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mesh = tessellate(S, tol)
    faces = [i for i, st in enumerate(mesh.stats["surfaces"])
             if st.get("trimmed_grid") and st.get("grouped")]
    assert len(faces) >= 4
    assert mesh.max_deviation <= tol
    keep = np.isin(mesh.face_surface, faces)
    sub = type(mesh)(mesh.vertices, mesh.faces[keep], mesh.uv, mesh.vertex_surface,
                     mesh.face_surface[keep], mesh.face_deviation[keep], tol, mesh.stats,
                     mesh.face_uv[keep])
    r = naive.sample_mesh_deviation(sub, S, n_faces=4000, n_worst=500, exact_above=tol)
    assert r["to_surface"] <= tol and r["to_mesh"] <= tol, r


def test_line_rectangle_decides_as_the_polylines(catia, ctc01):
    """``line_rectangle`` (the box from a loop of straight UV pieces' control points)
    against ``TrimPolylines.rectangle`` (from the polylines) on every trimmed face of
    two parts at two chord tolerances: the same box, bit for bit, wherever it answers
    (CATIA's three swept faces); and None for a loop that cuts a corner of its box, a
    curved piece, and a loop on the domain rectangle."""
    from geomkit.mesh.trim_polylines import line_rectangle, packed_trims

    found = 0
    for S, tol in (catia, ctc01):
        for s in [s for s in S if s.trim]:
            for ct in (0.5 * tol, 0.05 * tol):
                got = line_rectangle(s, ct, packed_trims(s))
                if got is not None:
                    assert got == TrimPolylines(s, ct, cross_knots=True).rectangle()
                    found += 1
    assert found >= 6
    s = catia[0][0]
    (u0, u1), (v0, v1) = s.domain
    a0, a1 = u0 + 0.2 * (u1 - u0), u0 + 0.7 * (u1 - u0)
    b0, b1 = v0 + 0.3 * (v1 - v0), v0 + 0.6 * (v1 - v0)

    def loop(pts):
        pts = np.asarray(pts, dtype=float)
        CP = np.concatenate([pts[i:i + 2] for i in range(len(pts) - 1)])
        n = len(pts) - 1
        K = np.tile([0.0, 0.0, 1.0, 1.0], n)
        off = np.arange(0, 2 * n + 1, 2, dtype=np.int64)
        return (CP, np.ones(len(CP)), K, np.ones(n, dtype=np.int64), off, 2 * off,
                np.array([0, n], dtype=np.int64))

    box = [(a0, b0), (a1, b0), (a1, b1), (a0, b1), (a0, b0)]
    assert line_rectangle(s, 0.5 * catia[1], loop(box)) == (a0, a1, b0, b1)
    cut = [(a0, b0), (a1, b0), (a1, b1), (a0 + 0.1 * (a1 - a0), b1), (a0, b0 + 0.5 * (b1 - b0)),
           (a0, b0)]
    assert line_rectangle(s, 0.5 * catia[1], loop(cut)) is None
    dom = [(u0, v0), (u1, v0), (u1, v1), (u0, v1), (u0, v0)]
    assert line_rectangle(s, 0.5 * catia[1], loop(dom)) is None
    CP, W, K, deg, co, ko, lf = loop(box)
    assert line_rectangle(s, 0.5 * catia[1], (CP, W, K, deg + np.eye(len(deg), dtype=np.int64)[0],
                                               co, ko, lf)) is None


def test_a_model_no_one_here_wrote_holds_tol_both_ways(impeller):
    """pyiges' impeller (277 trimmed faces from another CAD system): meshed with the
    grids of the estimates on most faces, every face within tol both ways by
    independent two-sided sampling (exact projection onto the faces, the exact trim
    curves' points against the mesh)."""
    S = impeller.surfaces
    B = np.array([s.bounds for s in S])
    tol = 1e-2 * float(np.linalg.norm(B[:, 1].max(axis=0) - B[:, 0].min(axis=0)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mesh = tessellate(S, tol)
    routes = [st for st in mesh.stats["surfaces"]]
    assert sum(bool(st.get("trimmed_grid")) for st in routes) > 50
    assert sum(bool(st.get("uniform_grid")) for st in routes) > 5
    assert mesh.max_deviation <= tol
    r = naive.sample_mesh_deviation(mesh, S, n_faces=3000, n_worst=400, exact_above=tol)
    assert r["to_surface"] <= tol and r["to_mesh"] <= tol, r
